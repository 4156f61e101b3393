//! `curvefit strip PROBLEM` — best interpolation in a strip (Dontchev–Kolmanovsky; the `strip`
//! crate).
//!
//! Problem: `t`, `y`, `lower`, `upper`, optional `end_slopes` \[s_start or null, s_end or null\].
//! A bound is null (or absent), `{"pieces": [[c0, c1, c2, c3], …]}` — one cubic per interval
//! \[t_i, t_{i+1}\] in s = t − t_i, so bounds may jump at data sites — or
//! `{"polyline": [[t, v], …]}` (continuous, its own breakpoints, handled by §4's grid).
//! Result: `breaks`, `coefficients` (\[c0, c1, c2, c3\] of the cubic on \[breaks_j, breaks_{j+1}\]
//! in s = t − breaks_j), `slopes` (f' at the data sites), `extra_knots` \[{"t", "kind"}\] with kind
//! one of `touch_lower`, `touch_upper`, `subarc_start_lower`, `subarc_end_lower`,
//! `subarc_start_upper`, `subarc_end_upper`, `energy` (∫f''²), `norm` (its square root),
//! `iterations`, `gradient_norm`.

use serde::{Deserialize, Serialize};

use super::{Command, InputError};
use crate::plot::{palette, Figure, Marker, Style};

/// Largest number of data points accepted (the solver is O(n) per iteration; this guards
/// against absurd inputs).
pub const MAX_POINTS: usize = 2_000_000;

/// A bound in the JSON problem.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum BoundSpec {
    /// One cubic per data interval, coefficients in s = t − t_i.
    Pieces(Vec<[f64; 4]>),
    /// A continuous polyline of (t, value) vertices covering \[t_1, t_n\].
    Polyline(Vec<[f64; 2]>),
}

/// The JSON problem of `curvefit strip`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Problem {
    /// Data sites, strictly increasing.
    pub t: Vec<f64>,
    /// Data values.
    pub y: Vec<f64>,
    /// Lower bound (default: none).
    #[serde(default)]
    pub lower: Option<BoundSpec>,
    /// Upper bound (default: none).
    #[serde(default)]
    pub upper: Option<BoundSpec>,
    /// Prescribed end slopes \[f'(t_1), f'(t_n)\], each optional (default: natural ends).
    #[serde(default)]
    pub end_slopes: Option<[Option<f64>; 2]>,
}

/// One extra knot in the JSON result.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ExtraKnot {
    /// Where.
    pub t: f64,
    /// `touch_lower`, `subarc_start_upper`, ….
    pub kind: String,
}

/// The JSON result of `curvefit strip`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Solution {
    /// Breakpoints of the piecewise cubic.
    pub breaks: Vec<f64>,
    /// \[c0, c1, c2, c3\] on \[breaks_j, breaks_{j+1}\] in s = t − breaks_j.
    pub coefficients: Vec<[f64; 4]>,
    /// f'(t_i) at the data sites.
    pub slopes: Vec<f64>,
    /// Extra knots with their kinds.
    pub extra_knots: Vec<ExtraKnot>,
    /// ∫ f''².
    pub energy: f64,
    /// ‖f''‖ = √energy.
    pub norm: f64,
    /// Outer iterations.
    pub iterations: usize,
    /// Final gradient norm of Φ.
    pub gradient_norm: f64,
}

/// The `strip` subcommand.
pub enum Strip {}

fn bound(b: &Option<BoundSpec>) -> strip::Bound {
    match b {
        None => strip::Bound::None,
        Some(BoundSpec::Pieces(p)) => strip::Bound::Pieces(p.clone()),
        Some(BoundSpec::Polyline(p)) => strip::Bound::Polyline(p.clone()),
    }
}

fn side_name(s: strip::Side) -> &'static str {
    match s {
        strip::Side::Lower => "lower",
        strip::Side::Upper => "upper",
    }
}

fn kind_name(k: strip::KnotKind) -> String {
    match k {
        strip::KnotKind::Touch(s) => format!("touch_{}", side_name(s)),
        strip::KnotKind::SubarcStart(s) => format!("subarc_start_{}", side_name(s)),
        strip::KnotKind::SubarcEnd(s) => format!("subarc_end_{}", side_name(s)),
    }
}

/// Maps the library's typed error to a field path (the library names the user's field and
/// index in every input error).
fn input_error(e: &strip::Error) -> InputError {
    use strip::Error as E;
    match e {
        E::TooFew { field, .. } | E::WrongLength { field, .. } => InputError::new(*field, e),
        E::NonFinite { field, index }
        | E::TooLarge { field, index, .. }
        | E::NonIncreasing { field, index }
        | E::InvalidValue { field, index, .. }
        | E::Infeasible { field, index, .. }
        | E::Unsupported { field, index, .. } => InputError::new(format!("{field}[{index}]"), e),
        E::StripViolated { side, .. } => InputError::new(side_name(*side), e),
        E::Discontinuous { .. } => InputError::new("t", e),
        _ => InputError::new("", e),
    }
}

impl Command for Strip {
    type Problem = Problem;
    type Solution = Solution;

    fn solve(p: &Problem) -> Result<Solution, InputError> {
        if p.t.len() > MAX_POINTS {
            return Err(InputError::new(
                "t",
                format!("{} data points exceed the limit of {MAX_POINTS}", p.t.len()),
            ));
        }
        let problem = strip::Problem {
            t: p.t.clone(),
            y: p.y.clone(),
            lower: bound(&p.lower),
            upper: bound(&p.upper),
            end_slopes: p.end_slopes.unwrap_or([None, None]),
        };
        let s = strip::solve(&problem, &strip::Options::default()).map_err(|e| input_error(&e))?;
        Ok(Solution {
            breaks: s.breaks,
            coefficients: s.coefficients,
            slopes: s.slopes,
            extra_knots: s
                .extra_knots
                .iter()
                .map(|k| ExtraKnot {
                    t: k.t,
                    kind: kind_name(k.kind),
                })
                .collect(),
            energy: s.energy,
            norm: s.norm,
            iterations: s.iterations,
            gradient_norm: s.gradient_norm,
        })
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
    let data: Vec<[f64; 2]> = p.t.iter().zip(&p.y).map(|(a, b)| [*a, *b]).collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Problem {
        serde_json::from_str(s).unwrap()
    }

    #[test]
    fn solves_a_small_strip_problem() {
        let p = parse(
            r#"{"t": [0, 1, 2, 3, 4], "y": [0, 1, 0, 0, 1],
                "lower": {"pieces": [[-0.05,0,0,0],[-0.05,0,0,0],[-0.05,0,0,0],[-0.05,0,0,0]]},
                "upper": null}"#,
        );
        let s = Strip::solve(&p).unwrap();
        assert!(!s.extra_knots.is_empty());
        assert!(s.extra_knots.iter().all(|k| k.kind.ends_with("lower")));
        assert!((s.norm * s.norm - s.energy).abs() <= 1e-12 * s.energy);
        assert_eq!(s.breaks.len(), s.coefficients.len() + 1);
        assert!(Strip::svg(&p, &s).unwrap().starts_with("<svg"));
    }

    #[test]
    fn errors_name_the_field() {
        let p = parse(r#"{"t": [0, 1, 2], "y": [0, 1, 0], "lower": {"pieces": [[0,0,0,0]]}}"#);
        assert_eq!(Strip::solve(&p).unwrap_err().field, "lower.pieces");
        let p = parse(r#"{"t": [0, 1, 1], "y": [0, 1, 0]}"#);
        assert_eq!(Strip::solve(&p).unwrap_err().field, "t[2]");
        let p = parse(
            r#"{"t": [0, 1, 2], "y": [0, 2, 0], "upper": {"pieces": [[1,0,0,0],[1,0,0,0]]}}"#,
        );
        assert_eq!(Strip::solve(&p).unwrap_err().field, "y[1]");
        let p = parse(
            r#"{"t": [0, 1, 2], "y": [0, 0.5, 0], "lower": {"pieces": [[-1,0,0,0],[2,0,0,0]]}, "upper": {"pieces": [[1,0,0,0],[1,0,0,0]]}}"#,
        );
        assert_eq!(Strip::solve(&p).unwrap_err().field, "lower.pieces[1]");
        assert!(
            serde_json::from_str::<Problem>(r#"{"t": [0, 1], "y": [0, 1], "extra": 1}"#).is_err()
        );
    }
}
