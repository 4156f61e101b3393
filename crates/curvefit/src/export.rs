//! A refinement's limit curve ([`refine::CubicSpline`]) in formats other programs read: CSV
//! samples, an SVG path of exact cubic Béziers, a DXF SPLINE entity and a B-spline/Bézier JSON.
//! Every function returns the file's text; writing it is the caller's business (the binary's
//! `--export FILE`).
//!
//! # The exact forms
//!
//! The spline has P cubic pieces on breaks t_0 < … < t_P, piece i with Bézier control points
//! b_{i,0..3} (b_{i,3} = b_{i+1,0}). As a B-spline of degree 3 it has the 3P + 1 control points
//! b_{0,0}, then b_{i,1}, b_{i,2}, b_{i,3} for every piece, and the clamped knot vector with every
//! interior break of multiplicity 3:
//! (t_0, t_0, t_0, t_0, t_1, t_1, t_1, …, t_{P−1}, t_{P−1}, t_{P−1}, t_P, t_P, t_P, t_P)
//! (3P + 5 knots). On [t_i, t_{i+1}] only the four B-splines of that piece are non-zero and they are
//! the Bernstein polynomials of the local parameter, so this B-spline is the spline exactly
//! (Farin, *Curves and Surfaces for CAGD*, 5th ed., §8.3 and §10.7: knot insertion to full
//! multiplicity gives the Bézier form). A closed curve is written the same way: its first and last
//! control points coincide, so it closes; no periodic flag is set (the knot vector is clamped).
//! Numbers are written in Rust's shortest round-trip form, so reading them back is exact.

use std::fmt::Write;

use refine::CubicSpline;

use crate::spec::refine::MAX_REFINED_COORDS;
use crate::spec::InputError;

/// Samples per piece of [`csv`] when no count is given: every break and 15 points between two.
pub const DEFAULT_SAMPLES_PER_PIECE: usize = 16;

/// The export formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    /// Samples `u,x,y[,z]` ([`csv`]).
    Csv,
    /// An SVG `<path>` of cubic Béziers, d = 2 ([`svg()`]).
    Svg,
    /// A DXF SPLINE entity ([`dxf`]).
    Dxf,
    /// B-spline and Bézier JSON ([`json`]).
    Json,
}

impl ExportFormat {
    /// Every format, by name.
    pub const ALL: [(&'static str, ExportFormat); 4] = [
        ("csv", ExportFormat::Csv),
        ("svg", ExportFormat::Svg),
        ("dxf", ExportFormat::Dxf),
        ("json", ExportFormat::Json),
    ];

    /// The format named `name` (case-insensitive), as in a file's extension.
    pub fn from_name(name: &str) -> Option<ExportFormat> {
        Self::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|&(_, f)| f)
    }
}

/// The curve in `format` (`samples` is [`csv`]'s count; `None` for its default).
///
/// # Errors
/// Those of [`svg()`] and [`csv()`].
pub fn export(
    spline: &CubicSpline,
    format: ExportFormat,
    samples: Option<usize>,
) -> Result<String, InputError> {
    match format {
        ExportFormat::Csv => csv(spline, samples),
        ExportFormat::Svg => svg(spline),
        ExportFormat::Dxf => Ok(dxf(spline)),
        ExportFormat::Json => Ok(json(spline)),
    }
}

fn coordinate_names(d: usize) -> Vec<String> {
    match d {
        1..=3 => ["x", "y", "z"][..d].iter().map(|s| s.to_string()).collect(),
        _ => (1..=d).map(|i| format!("x{i}")).collect(),
    }
}

/// Samples of the curve as CSV: a header `u,x,y[,z]` (`x1,…,xd` for d > 3), then one line per
/// sample. With `samples` = `None`: [`DEFAULT_SAMPLES_PER_PIECE`] samples per piece, evenly in each
/// piece's parameter, every break included (so the polyline through them passes through the
/// constrained vertices); with `Some(n)`: n ≥ 2 samples evenly in the whole parameter interval,
/// both ends included. A closed curve's last sample is its first point again, at t_P.
///
/// # Errors
/// `--samples` below 2, or samples × (d + 1) beyond the refined curve's own limit
/// ([`MAX_REFINED_COORDS`], about a gigabyte of text; `--samples 10^12` was killed for its memory).
pub fn csv(spline: &CubicSpline, samples: Option<usize>) -> Result<String, InputError> {
    if let Some(n) = samples.filter(|n| n.saturating_mul(spline.dim() + 1) > MAX_REFINED_COORDS) {
        return Err(InputError::new(
            "--samples",
            format!(
                "{n} samples of u and {} coordinates are more than {MAX_REFINED_COORDS} numbers, the limit",
                spline.dim()
            ),
        ));
    }
    let t = spline.breaks();
    let params: Vec<f64> = match samples {
        None => {
            let m = DEFAULT_SAMPLES_PER_PIECE;
            let mut u: Vec<f64> = t
                .windows(2)
                .flat_map(|w| (0..m).map(move |j| w[0] + (w[1] - w[0]) * j as f64 / m as f64))
                .collect();
            u.push(t[t.len() - 1]);
            u
        }
        Some(n) if n >= 2 => {
            let (a, b) = spline.domain();
            (0..n)
                .map(|j| a + (b - a) * j as f64 / (n - 1) as f64)
                .collect()
        }
        Some(n) => {
            return Err(InputError::new(
                "--samples",
                format!("needs at least 2 samples, got {n}"),
            ))
        }
    };
    let mut out = String::from("u,");
    out.push_str(&coordinate_names(spline.dim()).join(","));
    out.push('\n');
    for u in params {
        write!(out, "{u}").expect("writing to a String");
        for x in spline.eval(u) {
            write!(out, ",{x}").expect("writing to a String");
        }
        out.push('\n');
    }
    Ok(out)
}

/// A standalone SVG document with one `<path>` whose `d` is `M b_{0,0} C b_{0,1} b_{0,2} b_{0,3}
/// C …` (`Z` appended for a closed curve): the spline exactly, in the curve's own coordinates.
/// The path sits in a group with `transform="scale(1 -1)"` so that y points up as in the data,
/// and the viewBox is the control points' bounding box (which contains the curve) plus 5 %.
///
/// # Errors
/// A curve that is not planar (d ≠ 2): SVG has two coordinates.
pub fn svg(spline: &CubicSpline) -> Result<String, InputError> {
    let d = spline.dim();
    if d != 2 {
        return Err(InputError::new(
            "--export",
            format!(
                "an SVG path needs a plane curve (2 coordinates), this one has {d}: export dxf or json instead"
            ),
        ));
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut path = String::new();
    for i in 0..spline.pieces() {
        let b = spline.bezier(i).expect("a piece");
        for r in 0..4 {
            for c in 0..2 {
                lo[c] = lo[c].min(b[2 * r + c]);
                hi[c] = hi[c].max(b[2 * r + c]);
            }
        }
        if i == 0 {
            write!(path, "M {} {}", b[0], b[1]).expect("writing to a String");
        }
        write!(
            path,
            " C {} {} {} {} {} {}",
            b[2], b[3], b[4], b[5], b[6], b[7]
        )
        .expect("writing to a String");
    }
    if spline.is_closed() {
        path.push_str(" Z");
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let pad = 0.05 * size;
    let (x, w) = (lo[0] - pad, hi[0] - lo[0] + 2.0 * pad);
    // The group flips y, so the box's top in SVG coordinates is −(hi_y + pad).
    let (y, h) = (-(hi[1] + pad), hi[1] - lo[1] + 2.0 * pad);
    let stroke = size / 400.0;
    Ok(format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{x} {y} {w} {h}\">\n\
         <g transform=\"scale(1 -1)\">\n\
         <path fill=\"none\" stroke=\"black\" stroke-width=\"{stroke}\" d=\"{path}\"/>\n\
         </g>\n</svg>\n"
    ))
}

/// The B-spline form (see the module docs): the clamped knot vector and the 3P + 1 control
/// points.
pub fn bspline(spline: &CubicSpline) -> (Vec<f64>, Vec<Vec<f64>>) {
    let t = spline.breaks();
    let p = spline.pieces();
    let d = spline.dim();
    let mut knots = vec![t[0]; 4];
    for &x in &t[1..p] {
        knots.extend([x; 3]);
    }
    knots.extend([t[p]; 4]);
    let mut control = Vec::with_capacity(3 * p + 1);
    for i in 0..p {
        let b = spline.bezier(i).expect("a piece");
        let first = if i == 0 { 0 } else { 1 };
        for r in first..4 {
            control.push(b[r * d..(r + 1) * d].to_vec());
        }
    }
    (knots, control)
}

/// A DXF file (AutoCAD R2000 group codes) whose ENTITIES section holds one SPLINE of degree 3:
/// the B-spline form of the module docs, knots (code 40) then control points (codes 10/20/30),
/// flag 70 = 8 (planar) for d ≤ 2, else 0. Coordinates past the third are dropped (DXF is 3-D);
/// d = 1 curves get y = z = 0. A minimal file (HEADER with `$ACADVER` and ENTITIES only), the
/// form ezdxf, LibreCAD and FreeCAD import.
pub fn dxf(spline: &CubicSpline) -> String {
    let (knots, control) = bspline(spline);
    let d = spline.dim();
    let mut out = String::new();
    let mut pair = |code: u32, value: &dyn std::fmt::Display| {
        writeln!(out, "{code}\n{value}").expect("writing to a String");
    };
    pair(0, &"SECTION");
    pair(2, &"HEADER");
    pair(9, &"$ACADVER");
    pair(1, &"AC1015");
    pair(0, &"ENDSEC");
    pair(0, &"SECTION");
    pair(2, &"ENTITIES");
    pair(0, &"SPLINE");
    pair(8, &"0");
    pair(100, &"AcDbEntity");
    pair(100, &"AcDbSpline");
    if d <= 2 {
        pair(210, &0.0);
        pair(220, &0.0);
        pair(230, &1.0);
    }
    pair(70, &if d <= 2 { 8 } else { 0 });
    pair(71, &3);
    pair(72, &knots.len());
    pair(73, &control.len());
    pair(74, &0);
    pair(42, &"0.0000001");
    pair(43, &"0.0000001");
    for k in &knots {
        pair(40, k);
    }
    for c in &control {
        for (axis, code) in [10, 20, 30].into_iter().enumerate() {
            pair(code, &c.get(axis).copied().unwrap_or(0.0));
        }
    }
    pair(0, &"ENDSEC");
    pair(0, &"EOF");
    out
}

/// One JSON object: `{"degree": 3, "dimension": d, "closed": bool, "knots": […],
/// "control_points": [[…], …], "breaks": […], "bezier": [[b0, b1, b2, b3], …]}` — the B-spline
/// form (module docs) and the same curve piece by piece.
pub fn json(spline: &CubicSpline) -> String {
    let (knots, control) = bspline(spline);
    let d = spline.dim();
    let bezier: Vec<Vec<&[f64]>> = (0..spline.pieces())
        .map(|i| {
            let b = spline.bezier(i).expect("a piece");
            (0..4).map(|r| &b[r * d..(r + 1) * d]).collect()
        })
        .collect();
    let value = serde_json::json!({
        "degree": 3,
        "dimension": d,
        "closed": spline.is_closed(),
        "knots": knots,
        "control_points": control,
        "breaks": spline.breaks(),
        "bezier": bezier,
    });
    let mut s = value.to_string();
    s.push('\n');
    s
}

/// The limit curve of a `curvefit refine` result ([`refine::limit_curve_of`] on the JSON types).
///
/// # Errors
/// The problem's validation errors, and an error naming `result` when the result does not
/// belong to the problem.
pub fn refine_limit(
    problem: &crate::spec::refine::RefineProblem,
    result: &crate::spec::refine::RefineResult,
) -> Result<CubicSpline, InputError> {
    let library = crate::spec::refine::to_library(problem)?;
    let topology = if problem.closed {
        divdiff::Topology::Closed
    } else {
        divdiff::Topology::Open
    };
    let knots = divdiff::Knots::new(topology, result.knots.clone())
        .map_err(|e| InputError::new("result.knots", e))?;
    refine::limit_curve_of(&library, &result.points, &knots, &result.data_vertex)
        .map_err(|e| InputError::new("result", e))
}
