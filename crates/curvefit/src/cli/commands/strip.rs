//! `curvefit strip`: the subcommand (the JSON contract is [`spec::strip`](mod@crate::spec::strip))
//! and its picture.

use super::super::format::Table;
use crate::plot::{palette, Figure, Marker, Style};
use crate::spec::strip::*;
use crate::spec::{InputError, Numbers};

/// The `strip` subcommand.
pub enum Strip {}

impl super::super::Command for Strip {
    type Problem = Problem;
    type Solution = Solution;

    /// One row per piece: its interval and its coefficients in s = t − start.
    fn table(s: &Solution) -> Option<Table<'_>> {
        let mut data = Vec::with_capacity(6 * s.coefficients.len());
        for (j, c) in s.coefficients.iter().enumerate() {
            data.extend_from_slice(&[s.breaks[j], s.breaks[j + 1]]);
            data.extend_from_slice(c);
        }
        Some(Table {
            columns: ["start", "end", "c0", "c1", "c2", "c3"]
                .iter()
                .map(|s| s.to_string())
                .collect(),
            data: data.into(),
        })
    }

    fn solve(p: &Problem) -> Result<Solution, InputError> {
        crate::spec::strip(p)
    }

    fn solve_observed(
        p: &Problem,
        line: &std::sync::Arc<crate::cli::progress::Line>,
    ) -> Result<Solution, InputError> {
        crate::spec::strip::solve_observed(p, &|e| line.strip_event(e))
    }

    /// `--points FILE.csv` with two columns: the sites `t` and the values `y`.
    fn set_points(p: &mut Problem, csv: super::super::input::Csv) -> Result<(), InputError> {
        if !p.t.is_empty() || !p.y.is_empty() {
            return Err(InputError::new(
                "t",
                "given both in the problem and by --points (give t and y in one place)",
            ));
        }
        let points = csv.points;
        if !points.is_empty() && points.dim() != 2 {
            return Err(InputError::new(
                "--points",
                format!(
                    "a strip's CSV has two columns, t and y; this one has {}",
                    points.dim()
                ),
            ));
        }
        p.t = Numbers(points.iter().map(|r| r[0]).collect());
        p.y = Numbers(points.iter().map(|r| r[1]).collect());
        Ok(())
    }

    fn svg(p: &Problem, s: &Solution) -> Option<String> {
        Some(figure(p, s, "best interpolation in a strip").to_svg())
    }
}

fn eval_piece(c: &[f64; 4], s: f64) -> f64 {
    c[0] + s * (c[1] + s * (c[2] + s * c[3]))
}

/// Samples of f on every piece (16 per piece).
pub fn curve_points(s: &Solution) -> Vec<[f64; 2]> {
    let mut pts = Vec::new();
    for (j, c) in s.coefficients.iter().enumerate() {
        let (a, b) = (s.breaks[j], s.breaks[j + 1]);
        for k in 0..16 {
            let x = a + (b - a) * k as f64 / 16.0;
            pts.push([x, eval_piece(c, x - a)]);
        }
    }
    if let (Some(c), Some(&b), Some(&a)) = (
        s.coefficients.last(),
        s.breaks.last(),
        s.breaks.get(s.breaks.len().wrapping_sub(2)),
    ) {
        pts.push([b, eval_piece(c, b - a)]);
    }
    pts
}

/// The bound drawn as polylines (one per data interval for pieces, so jumps show).
fn bound_lines(t: &[f64], b: &Option<BoundSpec>) -> Vec<Vec<[f64; 2]>> {
    match b {
        None => vec![],
        Some(BoundSpec::Polyline(p)) => vec![p.clone()],
        Some(BoundSpec::Pieces(pc)) => pc
            .iter()
            .enumerate()
            .filter(|(i, _)| i + 1 < t.len())
            .map(|(i, c)| {
                (0..=24)
                    .map(|k| {
                        let s = (t[i + 1] - t[i]) * k as f64 / 24.0;
                        [t[i] + s, eval_piece(c, s)]
                    })
                    .collect()
            })
            .collect(),
    }
}

/// The figure: bounds (dashed), the solution, the data, and the contacts with the bounds by
/// kind (Dontchev–Kolmanovsky Theorem 2.1): a touching point of the upper bound (▼) or the lower
/// one (▲), a subarc along a bound (drawn thick between its two knots, ■ at its ends), and a
/// touching pair — an upper and a lower touch in the same data interval (◆).
pub fn figure(p: &Problem, s: &Solution, title: &str) -> Figure {
    let mut fig = Figure::new(title);
    fig.equal_aspect(false);
    fig.axis_labels("t", "f(t)");
    let bstyle = Style::stroke(palette::BOUND, 1.2).dashed("5 3");
    for line in bound_lines(&p.t, &p.lower)
        .into_iter()
        .chain(bound_lines(&p.t, &p.upper))
    {
        fig.polyline(&line, bstyle.clone());
    }
    let curve = curve_points(s);
    fig.polyline(&curve, Style::stroke(palette::CURVE, 2.0));
    let at = |t: f64| -> [f64; 2] {
        let j = s
            .breaks
            .partition_point(|b| *b <= t)
            .clamp(1, s.coefficients.len())
            - 1;
        [t, eval_piece(&s.coefficients[j], t - s.breaks[j])]
    };
    // The interval of a knot between consecutive data sites and polyline-bound vertices (the
    // cells of Theorem 2.1 and §4), to find touching pairs.
    let mut cells: Vec<f64> = p.t.to_vec();
    for b in [&p.lower, &p.upper] {
        if let Some(BoundSpec::Polyline(v)) = b {
            cells.extend(v.iter().map(|q| q[0]));
        }
    }
    cells.sort_by(f64::total_cmp);
    let interval = |t: f64| cells.partition_point(|x| *x <= t);
    let (mut upper, mut lower, mut ends, mut pair) = (vec![], vec![], vec![], vec![]);
    let mut subarcs = 0;
    let mut open_subarc: Option<f64> = None;
    for k in &s.extra_knots {
        let kind = k.kind.as_str();
        if kind.starts_with("subarc_start") {
            open_subarc = Some(k.t);
            ends.push(at(k.t));
        } else if kind.starts_with("subarc_end") {
            ends.push(at(k.t));
            if let Some(a) = open_subarc.take() {
                subarcs += 1;
                let arc: Vec<[f64; 2]> = curve
                    .iter()
                    .copied()
                    .filter(|q| q[0] >= a && q[0] <= k.t)
                    .collect();
                fig.polyline(&arc, Style::stroke(palette::ACTIVE, 4.0));
            }
        } else {
            let partner = if kind == "touch_upper" {
                "touch_lower"
            } else {
                "touch_upper"
            };
            let paired = s
                .extra_knots
                .iter()
                .any(|o| o.kind == partner && interval(o.t) == interval(k.t));
            match (paired, kind) {
                (true, _) => pair.push(at(k.t)),
                (false, "touch_upper") => upper.push(at(k.t)),
                _ => lower.push(at(k.t)),
            }
        }
    }
    let data: Vec<[f64; 2]> = p.t.iter().zip(p.y.iter()).map(|(a, b)| [*a, *b]).collect();
    fig.points(&data, Marker::Ring, Style::stroke(palette::DATA, 1.5));
    let knot = Style::fill(palette::KNOT);
    fig.points_sized(&upper, Marker::TriangleDown, 8.0, knot.clone());
    fig.points_sized(&lower, Marker::TriangleUp, 8.0, knot.clone());
    fig.points_sized(&ends, Marker::Square, 6.0, Style::fill(palette::ACTIVE));
    fig.points_sized(&pair, Marker::Diamond, 8.0, Style::fill(palette::THIRD));
    fig.legend("bounds e ≤ f ≤ d", bstyle);
    fig.legend("solution f", Style::stroke(palette::CURVE, 2.0));
    fig.legend_marker(
        "data (t_i, y_i)",
        Marker::Ring,
        5.0,
        Style::stroke(palette::DATA, 1.5),
    );
    if !upper.is_empty() {
        fig.legend_marker(
            "touches upper bound",
            Marker::TriangleDown,
            8.0,
            knot.clone(),
        );
    }
    if !lower.is_empty() {
        fig.legend_marker("touches lower bound", Marker::TriangleUp, 8.0, knot.clone());
    }
    if subarcs > 0 {
        fig.legend("subarc on a bound", Style::stroke(palette::ACTIVE, 4.0));
        fig.legend_marker(
            "subarc ends",
            Marker::Square,
            6.0,
            Style::fill(palette::ACTIVE),
        );
    }
    if !pair.is_empty() {
        fig.legend_marker(
            "touching pair (upper + lower)",
            Marker::Diamond,
            8.0,
            Style::fill(palette::THIRD),
        );
    }
    fig.caption_fields(&[
        ("‖f''‖", format!("{:.4}", s.norm)),
        ("∫f''²", format!("{:.4}", s.energy)),
        ("extra knots", s.extra_knots.len().to_string()),
        ("iterations", s.iterations.to_string()),
    ]);
    fig.caption_fields(&[
        ("touch upper", upper.len().to_string()),
        ("touch lower", lower.len().to_string()),
        ("subarcs", subarcs.to_string()),
        ("pairs", (pair.len() / 2).to_string()),
    ]);
    fig
}
