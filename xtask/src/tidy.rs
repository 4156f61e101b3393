//! `cargo xtask tidy`: mechanical checks of the invariants stated in ARCHITECTURE.md.
//!
//! 1. Layering: each workspace crate depends only on the crates it is allowed to (from
//!    `cargo metadata`, normal dependencies).
//! 2. No library crate does I/O: the sources of `divdiff`, `energy`, `refine` and `strip` never
//!    name `std::fs`, `std::io`, `std::net`, `File`, or print.
//! 3. The solve path never forms a dense N×N matrix: outside files named `dense.rs` and
//!    `#[cfg(test)]` code, `energy` and `refine` sources never name `DMatrix`.

use std::collections::BTreeMap;
use std::path::Path;

/// Allowed internal dependencies of each workspace crate.
const LAYERS: &[(&str, &[&str])] = &[
    ("divdiff", &[]),
    ("energy", &["divdiff"]),
    ("conic", &[]),
    ("refine", &["divdiff", "energy", "conic"]),
    ("strip", &[]),
    ("curvefit", &["divdiff", "energy", "refine", "strip"]),
];

const LIBRARIES: &[&str] = &["divdiff", "energy", "conic", "refine", "strip"];
const IO_PATTERNS: &[&str] = &[
    "std::fs",
    "std::io",
    "std::net",
    "File::",
    "println!",
    "eprintln!",
    "print!(",
    "eprint!(",
    "dbg!(",
];

pub fn run(_args: &[String]) -> anyhow::Result<bool> {
    let mut problems = Vec::new();
    check_layers(&mut problems)?;
    for lib in LIBRARIES {
        scan(
            &Path::new("crates").join(lib).join("src"),
            &mut |path, text| {
                for (lineno, line) in non_test_lines(text) {
                    let code = line.split("//").next().unwrap_or("");
                    for pat in IO_PATTERNS {
                        if code.contains(pat) {
                            problems.push(format!(
                                "{}:{lineno}: library crate does I/O ({pat})",
                                path.display()
                            ));
                        }
                    }
                    if (*lib == "energy" || *lib == "refine")
                        && code.contains("DMatrix")
                        && path.file_name().is_some_and(|f| f != "dense.rs")
                    {
                        problems.push(format!(
                        "{}:{lineno}: dense matrix outside dense.rs/test code (the solve path must stay banded)",
                        path.display()
                    ));
                    }
                }
            },
        )?;
    }
    for p in &problems {
        println!("tidy: {p}");
    }
    println!("tidy: {} problem(s)", problems.len());
    Ok(problems.is_empty())
}

fn check_layers(problems: &mut Vec<String>) -> anyhow::Result<()> {
    let out = std::process::Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()?;
    anyhow::ensure!(out.status.success(), "cargo metadata failed");
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let internal: Vec<&str> = LAYERS.iter().map(|(n, _)| *n).collect();
    let allowed: BTreeMap<&str, &[&str]> = LAYERS.iter().copied().collect();
    for pkg in meta["packages"].as_array().into_iter().flatten() {
        let name = pkg["name"].as_str().unwrap_or("");
        let Some(ok) = allowed.get(name) else {
            continue;
        };
        for dep in pkg["dependencies"].as_array().into_iter().flatten() {
            let dname = dep["name"].as_str().unwrap_or("");
            let kind = dep["kind"].as_str();
            if kind.is_none() && internal.contains(&dname) && !ok.contains(&dname) {
                problems.push(format!("layering: {name} must not depend on {dname}"));
            }
        }
    }
    Ok(())
}

/// Lines outside `#[cfg(test)]` modules (a module starting at the attribute is skipped to the
/// end of its brace block).
fn non_test_lines(text: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut depth_skip: Option<i64> = None;
    let mut depth = 0i64;
    let mut pending = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("#[cfg(test)]") {
            pending = true;
        }
        let opens = line.matches('{').count() as i64;
        let closes = line.matches('}').count() as i64;
        if pending && opens > 0 && depth_skip.is_none() {
            depth_skip = Some(depth);
            pending = false;
        }
        if depth_skip.is_none() && !pending {
            out.push((i + 1, line));
        }
        depth += opens - closes;
        if let Some(d) = depth_skip {
            if depth <= d {
                depth_skip = None;
            }
        }
    }
    out
}

fn scan(dir: &Path, f: &mut dyn FnMut(&Path, &str)) -> anyhow::Result<()> {
    if !dir.exists() {
        return Ok(());
    }
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            scan(&path, f)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path)?;
            f(&path, &text);
        }
    }
    Ok(())
}
