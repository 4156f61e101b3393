//! `curvefit demo [--out DIR]`: the main job on built-in data. Runs every built-in example problem
//! through the same pipeline as the subcommands, writes each picture as SVG, an `index.html`
//! showing them all, and prints a summary table.

use std::io::Write;
use std::path::Path;

use super::{Command, InputError};

/// One built-in example: a subcommand and its JSON problem.
pub struct Example {
    /// File stem for the outputs.
    pub name: &'static str,
    /// Which subcommand solves it.
    pub command: &'static str,
    /// What it shows.
    pub title: &'static str,
    /// The JSON problem.
    pub problem: &'static str,
}

/// The built-in examples (the JSON files are in `crates/curvefit/examples/data/`).
pub const EXAMPLES: &[Example] = &[];

/// The summary of one solved example.
pub struct Summary {
    /// One-line description of the result (energy, residual, counts).
    pub line: String,
    /// The picture.
    pub svg: Option<String>,
    /// The JSON result.
    pub json: String,
}

/// Solves one example with command `C`.
pub fn solve_with<C: Command>(
    problem: &str,
    describe: impl Fn(&C::Solution) -> String,
) -> Result<Summary, InputError> {
    let value: serde_json::Value = serde_json::from_str(problem)
        .map_err(|e| InputError::new("problem", format!("malformed JSON: {e}")))?;
    let p: C::Problem = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        InputError::new(path, e.into_inner())
    })?;
    let s = C::solve(&p)?;
    let json = serde_json::to_string_pretty(&s).map_err(|e| InputError::new("", e))?;
    Ok(Summary {
        line: describe(&s),
        svg: C::svg(&p, &s),
        json,
    })
}

/// Runs all examples into `out`, printing the summary table to `stdout`.
///
/// # Errors
/// When an example fails (a bug: the built-in data are valid) or the directory cannot be written.
pub fn run(
    out: &Path,
    stdout: &mut dyn Write,
    solve: impl Fn(&Example) -> Result<Summary, InputError>,
) -> Result<(), InputError> {
    std::fs::create_dir_all(out)
        .map_err(|e| InputError::new("--out", format!("cannot create {}: {e}", out.display())))?;
    let mut html = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>curvefit demo</title>\
         <style>body{font-family:sans-serif;max-width:1400px;margin:auto}figure{display:inline-block;margin:8px;\
         vertical-align:top;width:660px}figcaption{font-size:14px}</style></head><body>\n<h1>curvefit demo</h1>\n",
    );
    let mut files = Vec::new();
    let _ = writeln!(stdout, "{:<28} {:<8} result", "example", "command");
    for ex in EXAMPLES {
        let s = solve(ex).map_err(|e| InputError::new(format!("example {}", ex.name), e))?;
        let _ = writeln!(stdout, "{:<28} {:<8} {}", ex.name, ex.command, s.line);
        files.push((out.join(format!("{}.json", ex.name)), s.json.into_bytes()));
        if let Some(svg) = s.svg {
            files.push((out.join(format!("{}.svg", ex.name)), svg.into_bytes()));
            html.push_str(&format!(
                "<figure><img src=\"{0}.svg\" width=\"640\"><figcaption><b>{0}</b> ({1}): {2}<br><code>{3}</code></figcaption></figure>\n",
                ex.name,
                ex.command,
                ex.title,
                html_escape(&s.line)
            ));
        }
    }
    html.push_str("</body></html>\n");
    files.push((out.join("index.html"), html.into_bytes()));
    super::write_files(&files)?;
    let _ = writeln!(stdout, "wrote {} files to {}", files.len(), out.display());
    Ok(())
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
