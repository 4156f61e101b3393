//! `curvefit refine`: the subcommand (the JSON contract is
//! [`spec::refine`](mod@crate::spec::refine)) and its picture.

use super::super::format::{bytes_piece, json_array_pieces, write_pieces, Table};
use crate::spec::refine::*;
use crate::spec::InputError;

/// The `refine` subcommand.
pub enum RefineCmd {}

impl super::super::Command for RefineCmd {
    type Problem = RefineProblem;
    type Solution = RefineResult;

    /// `--points FILE.csv`: the problem's `points`.
    fn set_points(p: &mut RefineProblem, csv: super::super::input::Csv) -> Result<(), InputError> {
        super::set_points(&mut p.points, csv)
    }

    /// The result as serde_json writes it, with `points` and `knots` (8·10⁵ vertices and more)
    /// and the other fields formatted on every core ([`write_pieces`]); the destructuring is
    /// exhaustive, so a new result field does not compile until it is written here too.
    fn write_json(r: &RefineResult, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        #[derive(serde::Serialize)]
        struct Rest<'a> {
            data_vertex: &'a [usize],
            energy: f64,
            multipliers: MultiplierRows<'a>,
            active: &'a [bool],
            kkt_residual: f64,
            iterations: &'a RefineIterations,
        }
        let RefineResult {
            points,
            knots,
            data_vertex,
            energy,
            multipliers,
            active,
            kkt_residual,
            iterations,
        } = r;
        let rest = Rest {
            data_vertex,
            energy: *energy,
            multipliers: MultiplierRows(multipliers),
            active,
            kkt_residual: *kkt_residual,
            iterations,
        };
        let mut pieces = vec![bytes_piece(b"{\"points\":")];
        pieces.extend(json_array_pieces(points.coords(), points.dim().max(1)));
        pieces.push(bytes_piece(b",\"knots\":"));
        pieces.extend(json_array_pieces(knots, 0));
        pieces.push(Box::new(move |out: &mut Vec<u8>| {
            let start = out.len();
            serde_json::to_writer(&mut *out, &rest).map_err(std::io::Error::other)?;
            // `rest` is an object: its fields follow the others', without its opening brace.
            out[start] = b',';
            out.push(b'\n');
            Ok(())
        }));
        write_pieces(pieces, w)
    }

    /// The refined points, one row per vertex.
    fn table(r: &RefineResult) -> Option<Table<'_>> {
        Some(Table {
            columns: Table::point_columns(r.points.dim()),
            data: r.points.coords().into(),
        })
    }

    fn solve(problem: &RefineProblem) -> Result<RefineResult, InputError> {
        crate::spec::refine(problem)
    }

    fn solve_observed(
        problem: &RefineProblem,
        line: &std::sync::Arc<crate::cli::progress::Line>,
    ) -> Result<RefineResult, InputError> {
        crate::spec::refine::solve_observed(problem, Some(line.observer()))
    }

    fn svg(problem: &RefineProblem, solution: &RefineResult) -> Option<String> {
        Some(picture(problem, solution))
    }

    /// The limit curve (docs/limit.md) in `format`.
    fn export(
        problem: &RefineProblem,
        solution: &RefineResult,
        format: crate::export::ExportFormat,
        samples: Option<usize>,
    ) -> Option<Result<String, InputError>> {
        Some(
            crate::export::refine_limit(problem, solution)
                .and_then(|s| crate::export::export(&s, format, samples)),
        )
    }
}

/// Draws each tangent constraint at its data vertex: the derivative of the refined curve there
/// (central difference of the neighbours) as a solid arrow, the wedge's bounding rays dashed and
/// the ball of a ball/tension constraint around the vertex, all scaled to a common length.
fn draw_tangents(
    fig: &mut crate::plot::Figure,
    tangents: &[Option<TangentSpec>],
    r: &RefineResult,
) {
    use crate::plot::{palette, Style};
    let n = r.points.len();
    if n < 3 {
        return;
    }
    let closed_len = r.knots.len() > n;
    let span: f64 =
        r.knots.last().copied().unwrap_or(1.0) - r.knots.first().copied().unwrap_or(0.0);
    let extent = r
        .points
        .iter()
        .flat_map(|v| v.iter().take(2))
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(1e-300);
    let len = 0.12 * extent;
    let mut wedges = false;
    for (i, t) in tangents.iter().enumerate() {
        let (Some(t), Some(&j)) = (t, r.data_vertex.get(i)) else {
            continue;
        };
        let (a, b) = if closed_len {
            ((j + n - 1) % n, (j + 1) % n)
        } else {
            (j.saturating_sub(1), (j + 1).min(n - 1))
        };
        let dt = if b > a {
            r.knots[b] - r.knots[a]
        } else {
            r.knots[b] + span - r.knots[a]
        };
        // Knots are strictly increasing, so dt > 0; guard anyway (a picture never fails).
        let dt = if dt > 0.0 { dt } else { 1.0 };
        let df = [
            (r.points.point(b)[0] - r.points.point(a)[0]) / dt,
            (r.points.point(b)[1] - r.points.point(a)[1]) / dt,
        ];
        let p0 = [r.points.point(j)[0], r.points.point(j)[1]];
        let norm = (df[0] * df[0] + df[1] * df[1]).sqrt().max(1e-300);
        let arrow = [p0[0] + len * df[0] / norm, p0[1] + len * df[1] / norm];
        fig.segment(p0, arrow, Style::stroke(palette::SECOND, 2.0));
        if let TangentSpec::Wedge {
            direction,
            half_angle,
        } = t
        {
            wedges = true;
            let u = (direction[0].hypot(direction[1])).max(1e-300);
            for s in [-1.0, 1.0] {
                let (c, sn) = ((s * half_angle).cos(), (s * half_angle).sin());
                let v = [
                    (c * direction[0] - sn * direction[1]) / u,
                    (sn * direction[0] + c * direction[1]) / u,
                ];
                fig.segment(
                    p0,
                    [p0[0] + 1.4 * len * v[0], p0[1] + 1.4 * len * v[1]],
                    Style::stroke(palette::THIRD, 1.0).dashed("3 2"),
                );
            }
        }
    }
    fig.legend("curve's derivative Df", Style::stroke(palette::SECOND, 2.0));
    if wedges {
        fig.legend(
            "wedge bounds (allowed Df)",
            Style::stroke(palette::THIRD, 1.0).dashed("3 2"),
        );
    }
}

/// The 2-D polygon of a JSON half-space set, clipped to a square (see
/// [`refine::halfplane_polygon`]).
pub fn halfplane_polygon(
    halfspaces: &[HalfSpaceSpec],
    around: [f64; 2],
    extent: f64,
) -> Vec<[f64; 2]> {
    let set: Vec<refine::HalfSpace> = halfspaces
        .iter()
        .map(|h| refine::HalfSpace {
            normal: h.normal.clone(),
            offset: h.offset,
        })
        .collect();
    refine::halfplane_polygon(&set, around, extent)
}

/// The picture of a refinement: data points, their tolerance regions (active ones highlighted),
/// the refined curve and the attached data vertices; curves in R^d show the first two coordinates,
/// curves in R^1 are drawn as graphs over their knots.
pub fn picture(p: &RefineProblem, r: &RefineResult) -> String {
    use crate::plot::{palette, Figure, Marker, Style};
    let d = p.points.dim();
    let xy = |v: &[f64], t: f64| -> [f64; 2] {
        if d >= 2 {
            [v[0], v[1]]
        } else {
            [t, v.first().copied().unwrap_or(0.0)]
        }
    };
    let kind = match &p.constraint {
        ConstraintSpec::Interpolate => "interpolation",
        ConstraintSpec::Balls { .. } => "balls",
        ConstraintSpec::Smoothing { .. } => "smoothing",
        ConstraintSpec::Halfspaces { .. } => "convex polygons",
    };
    let extras = match (&p.tangents, &p.boundary) {
        (Some(_), BoundarySpec::Natural) => " + tangents",
        (Some(_), _) => " + tangents + ends",
        (None, BoundarySpec::Clamped { .. }) => ", clamped ends",
        (None, BoundarySpec::NearClamped { .. }) => ", near-clamped ends",
        (None, BoundarySpec::Natural) => "",
    };
    let mut fig = Figure::new(&format!(
        "Refinement: {kind}{extras} ({}, {} → {} vertices)",
        if p.closed { "closed" } else { "open" },
        p.points.len(),
        r.points.len()
    ));
    fig.equal_aspect(d >= 2);
    if d >= 2 {
        fig.axis_labels("x", "y");
    } else {
        fig.axis_labels("t (the returned knots' parameter)", "f(t)");
    }
    let data_t: Vec<f64> = r
        .data_vertex
        .iter()
        .map(|&j| r.knots.get(j).copied().unwrap_or(0.0))
        .collect();
    let active_style = Style::stroke(palette::ACTIVE, 1.3).with_fill(palette::ACTIVE, 0.08);
    let inactive_style = Style::stroke(palette::REGION, 1.0).with_fill(palette::REGION, 0.08);
    match &p.constraint {
        ConstraintSpec::Balls { radii } if d >= 2 => {
            for (i, q) in p.points.iter().enumerate() {
                let st = if r.active.get(i).copied().unwrap_or(false) {
                    &active_style
                } else {
                    &inactive_style
                };
                fig.circle(xy(q, 0.0), radii[i], st.clone());
            }
        }
        ConstraintSpec::Halfspaces { sets } if d == 2 => {
            // Unbounded sets are clipped to a box around the data (a quarter of its size beyond it).
            let (lo, hi) = p.points.iter().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), q| {
                    (
                        [lo[0].min(q[0]), lo[1].min(q[1])],
                        [hi[0].max(q[0]), hi[1].max(q[1])],
                    )
                },
            );
            let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
            let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
            for (i, (_q, set)) in p.points.iter().zip(sets).enumerate() {
                let poly = halfplane_polygon(set, centre, 0.75 * size);
                let st = if r.active.get(i).copied().unwrap_or(false) {
                    &active_style
                } else {
                    &inactive_style
                };
                if poly.len() >= 3 {
                    fig.polygon(&poly, st.clone());
                }
            }
        }
        _ => {}
    }
    let curve: Vec<[f64; 2]> = r
        .points
        .iter()
        .zip(&r.knots)
        .map(|(v, &t)| xy(v, t))
        .collect();
    if p.closed && d >= 2 {
        fig.polygon(&curve, Style::stroke(palette::CURVE, 1.6));
    } else {
        fig.polyline(&curve, Style::stroke(palette::CURVE, 1.6));
    }
    if let (Some(tangents), true) = (&p.tangents, d >= 2) {
        draw_tangents(&mut fig, tangents, r);
    }
    let attached: Vec<[f64; 2]> = r
        .data_vertex
        .iter()
        .zip(&data_t)
        .filter(|&(&j, _)| j < r.points.len())
        .map(|(&j, &t)| xy(r.points.point(j), t))
        .collect();
    fig.points_sized(
        &attached,
        Marker::Ring,
        6.0,
        Style::stroke(palette::CURVE, 1.0),
    );
    let data: Vec<[f64; 2]> = p
        .points
        .iter()
        .zip(&data_t)
        .map(|(q, &t)| xy(q, t))
        .collect();
    fig.points(&data, Marker::Dot, Style::fill(palette::DATA));
    fig.legend("refined polygon", Style::stroke(palette::CURVE, 1.6));
    fig.legend_marker(
        "data point q_i",
        Marker::Dot,
        5.0,
        Style::fill(palette::DATA),
    );
    fig.legend_marker(
        "its refined vertex p_{i_k}",
        Marker::Ring,
        6.0,
        Style::stroke(palette::CURVE, 1.0),
    );
    // Only balls and half-space sets can be inactive (interpolation always binds, smoothing is
    // a penalty, not a constraint).
    let can_be_inactive = matches!(
        p.constraint,
        ConstraintSpec::Balls { .. } | ConstraintSpec::Halfspaces { .. }
    );
    let drawn_regions = match &p.constraint {
        ConstraintSpec::Balls { .. } => d >= 2,
        ConstraintSpec::Halfspaces { .. } => d == 2,
        _ => false,
    };
    if drawn_regions {
        if r.active.iter().any(|&a| a) {
            fig.legend_region("active tolerance region", active_style.clone());
        }
        if r.active.iter().any(|&a| !a) {
            fig.legend_region("inactive tolerance region", inactive_style.clone());
        }
    }
    let mut fields = vec![
        ("E (Kersey (2.1))", format!("{:.6}", r.energy)),
        ("KKT residual", format!("{:.1e}", r.kkt_residual)),
    ];
    if can_be_inactive {
        let n_active = r.active.iter().filter(|&&a| a).count();
        fields.push(("active", format!("{n_active} of {}", r.active.len())));
    }
    fig.caption_fields(&fields);
    fig.to_svg()
}

#[cfg(test)]
mod tests {
    use super::super::super::Command;
    use super::*;

    /// The fast writer is serde_json's output byte for byte, on every refine test problem.
    #[test]
    fn fast_json_is_serde_json() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/problems");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if !name.starts_with("refine-") {
                continue;
            }
            let p: RefineProblem =
                crate::spec::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap();
            let r = RefineCmd::solve(&p).unwrap();
            let mut fast = Vec::new();
            RefineCmd::write_json(&r, &mut fast).unwrap();
            let mut want = serde_json::to_vec(&r).unwrap();
            want.push(b'\n');
            assert_eq!(
                String::from_utf8(fast).unwrap(),
                String::from_utf8(want).unwrap(),
                "{name}"
            );
            n += 1;
        }
        assert!(n >= 5);
    }
}
