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
pub const EXAMPLES: &[Example] = &[
    Example {
        name: "refine-interpolate-closed",
        command: "refine",
        title: "interpolatory refinement, centripetal knots, one 3-level step then two further levels (Kersey Figs. 1.1, 3.1)",
        problem: include_str!("../../examples/data/refine-interpolate-closed.json"),
    },
    Example {
        name: "refine-balls-closed",
        command: "refine",
        title: "near-interpolation to balls of random radii; active balls in red (Kersey Fig. 3.2)",
        problem: include_str!("../../examples/data/refine-balls-closed.json"),
    },
    Example {
        name: "refine-star-balls",
        command: "refine",
        title: "the star with tolerance 0.35 at every point (Kersey Fig. 3.3)",
        problem: include_str!("../../examples/data/refine-star-balls.json"),
    },
    Example {
        name: "refine-balls-open",
        command: "refine",
        title: "open curve, interpolated ends, two loosened tolerances (Kersey Fig. 3.9)",
        problem: include_str!("../../examples/data/refine-balls-open.json"),
    },
    Example {
        name: "refine-halfspaces-closed",
        command: "refine",
        title: "each point confined to a square or triangle: corner, edge and interior contacts (Kersey Fig. 3.4)",
        problem: include_str!("../../examples/data/refine-halfspaces-closed.json"),
    },
    Example {
        name: "refine-tangent-wedges",
        command: "refine",
        title: "direction-only tangent wedges tilted by 0.6 rad, half-angle 0.1 (Kersey Figs. 3.5b, 3.7)",
        problem: include_str!("../../examples/data/refine-tangent-wedges.json"),
    },
    Example {
        name: "refine-clamped-open",
        command: "refine",
        title: "open curve with clamped end derivatives (Bessel end quadratics; Kersey §3.6, Fig. 3.9)",
        problem: include_str!("../../examples/data/refine-clamped-open.json"),
    },
    Example {
        name: "refine-smoothing-open",
        command: "refine",
        title: "smoothing of noisy samples, open curve with natural ends (Kersey (3.6), §3.6)",
        problem: include_str!("../../examples/data/refine-smoothing-open.json"),
    },
    Example {
        name: "strip-example-5-1",
        command: "strip",
        title: "16 points in a strip: touching points, a subarc and a touching pair (Dontchev–Kolmanovsky Fig. 2)",
        problem: include_str!("../../examples/data/strip-example-5-1.json"),
    },
    Example {
        name: "strip-example-5-2",
        command: "strip",
        title: "bounds jumping at data sites, a cubic lower piece, end slopes −2, −2 (Fig. 4)",
        problem: include_str!("../../examples/data/strip-example-5-2.json"),
    },
    Example {
        name: "strip-example-5-3",
        command: "strip",
        title: "two points, end slopes −2 and 2, a winding polyline channel (§4, Remark 4.2, Fig. 5)",
        problem: include_str!("../../examples/data/strip-example-5-3.json"),
    },
    Example {
        name: "natural-example",
        command: "natural",
        title: "natural cubic subdivision: energies decrease to the exact limit energy (Warren–Weimer §6.2)",
        problem: include_str!("../../examples/data/natural-example.json"),
    },
    Example {
        name: "surface-torus",
        command: "surface",
        title: "4-point binary tensor-product scheme on a closed 8 × 5 grid, two levels (Khan et al. §4)",
        problem: include_str!("../../examples/data/surface-torus.json"),
    },
];

/// The introduction of `index.html`: what the figures show, how to read their marks, and which
/// seed each reproduces.
const INTRO: &str = "<p>Each figure below is one built-in example, solved by the same code as the \
command line (<code>curvefit SUBCOMMAND examples/data/NAME.json --svg NAME.svg</code>); the caption \
names the figure of the paper it reproduces and the numbers the solver certified.</p>\n\
<ul>\n\
<li><b>refine-*</b>: S. N. Kersey, <i>Near-interpolatory variational refinement of piecewise-linear \
curves</i> (J. Comput. Appl. Math. 223, 2009), §3–4. Black dots are the data points q<sub>i</sub>; \
the blue polygon is the refined curve (N vertices, minimal discrete energy E of (2.1)); hollow rings \
are the refined vertices attached to the data points; shaded discs and polygons are the tolerance \
regions each attached vertex must stay in, red where the constraint is active (the vertex is on its \
boundary), grey where it is not; orange arrows are the curve's derivative at a tangent-constrained \
vertex, dashed green rays the wedge it must lie in. The footer gives E, the independent KKT \
residual of the certificate and, where constraints can be inactive, how many are active.</li>\n\
<li><b>strip-*</b>: A. L. Dontchev, I. Kolmanovsky, <i>Best interpolation in a strip</i>, the \
examples of §5: the C² cubic spline of least ∫f''² through the data (rings) between the dashed \
bounds; its contacts with the bounds are marked by kind (▼ touches the upper bound, ▲ the lower, a \
thick red stretch is a subarc along a bound, ◆ a touching pair), as Theorem 2.1 classifies them.</li>\n\
<li><b>natural-example</b>: J. Warren, H. Weimer, <i>Subdivision Methods for Geometric Design</i>, \
§6.2–6.3: natural cubic subdivision is <i>approximating</i> — the rings are control points, and the \
curve passes through the two end ones only; its limit is a natural cubic spline whose exact energy the footer \
compares with the last level's.</li>\n\
<li><b>surface-torus</b>: F. Khan, I. Mukhtar, N. Batool, <i>A unified (2m+2)-point n-ary interpolating subdivision scheme</i> (Open J. Appl. Sci. 3, 2013), §4: the \
tensor-product surface rule on a closed grid, drawn as an isometric wireframe over the dashed \
control net it interpolates.</li>\n\
</ul>\n";

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
    let p: C::Problem = crate::spec::from_json(problem)?;
    let s = C::solve(&p)?;
    let json = serde_json::to_string_pretty(&s).map_err(|e| InputError::new("", e))?;
    Ok(Summary {
        line: describe(&s),
        svg: C::svg(&p, &s),
        json,
    })
}

/// Runs all examples into `out`, printing the summary table to `stdout`. All files and the
/// summary are committed together ([`super::Outputs`]): a failure leaves no file behind (and
/// removes `out` if this run created it).
///
/// # Errors
/// When an example fails (a bug: the built-in data are valid) or an output cannot be written.
pub fn run(
    out: &Path,
    stdout: &mut dyn Write,
    solve: impl Fn(&Example) -> Result<Summary, InputError>,
) -> Result<(), InputError> {
    let mut html = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>curvefit demo</title>\
         <style>body{font-family:sans-serif;max-width:1400px;margin:auto}figure{display:inline-block;margin:8px;\
         vertical-align:top;width:870px}figcaption{font-size:14px}</style></head><body>\n<h1>curvefit demo</h1>\n",
    );
    html.push_str(INTRO);
    let mut files = Vec::new();
    let mut summary = format!("{:<28} {:<8} result\n", "example", "command");
    for ex in EXAMPLES {
        let s = solve(ex).map_err(|e| InputError::new(format!("example {}", ex.name), e))?;
        summary.push_str(&format!("{:<28} {:<8} {}\n", ex.name, ex.command, s.line));
        files.push((out.join(format!("{}.json", ex.name)), s.json.into_bytes()));
        if let Some(svg) = s.svg {
            files.push((out.join(format!("{}.svg", ex.name)), svg.into_bytes()));
            html.push_str(&format!(
                "<figure><img src=\"{0}.svg\" width=\"858\"><figcaption><b>{0}</b> ({1}): {2}<br><code>{3}</code></figcaption></figure>\n",
                ex.name,
                ex.command,
                ex.title,
                html_escape(&s.line)
            ));
        }
    }
    html.push_str("</body></html>\n");
    files.push((out.join("index.html"), html.into_bytes()));
    summary.push_str(&format!(
        "wrote {} files to {}\n",
        files.len(),
        out.display()
    ));
    let created = !out.exists();
    std::fs::create_dir_all(out)
        .map_err(|e| InputError::new("--out", format!("cannot create {}: {e}", out.display())))?;
    let mut outputs = super::Outputs::new();
    for (path, bytes) in files {
        outputs.add("--out", Some(&path), super::bytes_writer(bytes))?;
    }
    outputs.add(
        "standard output",
        None,
        super::bytes_writer(summary.into_bytes()),
    )?;
    outputs.commit(stdout).inspect_err(|_| {
        if created {
            // Only an empty directory is removed: nothing else was put there.
            let _ = std::fs::remove_dir(out);
        }
    })
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
