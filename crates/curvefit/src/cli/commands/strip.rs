//! `curvefit strip`: the subcommand (the JSON contract is [`crate::spec::strip`]) and its picture.

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

/// The figure: bounds (dashed), the solution, the data, and the extra knots as stars.
pub fn figure(p: &Problem, s: &Solution, title: &str) -> Figure {
    let mut fig = Figure::new(title);
    fig.equal_aspect(false);
    let bstyle = Style::stroke(palette::BOUND, 1.2).dashed("5 3");
    for line in bound_lines(&p.t, &p.lower)
        .into_iter()
        .chain(bound_lines(&p.t, &p.upper))
    {
        fig.polyline(&line, bstyle.clone());
    }
    fig.polyline(&curve_points(s), Style::stroke(palette::CURVE, 2.0));
    let data: Vec<[f64; 2]> = p.t.iter().zip(p.y.iter()).map(|(a, b)| [*a, *b]).collect();
    fig.points(&data, Marker::Ring, Style::stroke(palette::DATA, 1.5));
    let knots: Vec<[f64; 2]> = s
        .extra_knots
        .iter()
        .map(|k| {
            let j = s
                .breaks
                .partition_point(|b| *b <= k.t)
                .clamp(1, s.coefficients.len())
                - 1;
            [k.t, eval_piece(&s.coefficients[j], k.t - s.breaks[j])]
        })
        .collect();
    fig.points(&knots, Marker::Star, Style::fill(palette::KNOT));
    fig.legend("bounds", bstyle);
    fig.legend("solution", Style::stroke(palette::CURVE, 2.0));
    fig.legend("extra knots", Style::fill(palette::KNOT));
    fig.caption(&format!(
        "‖f''‖ = {:.4}   ∫f''² = {:.4}   {} extra knots   {} iterations",
        s.norm,
        s.energy,
        s.extra_knots.len(),
        s.iterations
    ));
    fig
}
