//! `strip` — best interpolation in a strip (Dontchev–Kolmanovsky; the `strip`
//! crate).
//!
//! Problem: `t`, `y`, `lower`, `upper`, optional `end_slopes` \[s_start or null, s_end or null\].
//! A bound is null (or absent), `{"pieces": [[c0, c1, c2, c3], …]}` — one cubic per interval
//! \[t_i, t_{i+1}\] in s = t − t_i, so bounds may jump at data sites — or
//! `{"polyline": [[t, v], …]}` (continuous, its own breakpoints, solved exactly between them).
//! Result: `breaks`, `coefficients` (\[c0, c1, c2, c3\] of the cubic on \[breaks_j, breaks_{j+1}\]
//! in s = t − breaks_j), `slopes` (f' at the data sites), `extra_knots` \[{"t", "kind"}\] with kind
//! one of `touch_lower`, `touch_upper`, `subarc_start_lower`, `subarc_end_lower`,
//! `subarc_start_upper`, `subarc_end_upper`, `energy` (∫f''²), `norm` (its square root),
//! `iterations`, `gradient_norm`.

use serde::{Deserialize, Serialize};

use super::messages::num;
use super::{InputError, Numbers};

/// Largest number of data points accepted (the solver is O(n) per iteration; this guards
/// against absurd inputs).
pub const MAX_POINTS: usize = 2_000_000;

/// A bound in the JSON problem.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum BoundSpec {
    /// One cubic per data interval, coefficients in s = t − t_i.
    Pieces(Vec<[f64; 4]>),
    /// A continuous polyline of (t, value) vertices covering \[t_1, t_n\].
    Polyline(Vec<[f64; 2]>),
}

/// The JSON problem of `curvefit strip`.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Problem {
    /// Data sites, strictly increasing (required; the command line may read `t` and `y` from
    /// the two columns of `--points FILE.csv`).
    #[serde(default)]
    pub t: Numbers,
    /// Data values (required, like `t`).
    #[serde(default)]
    pub y: Numbers,
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
    /// Indices of data values that lay on a bound and were moved inside by ε = 1e-7 of the strip
    /// width there before solving (Dontchev–Kolmanovsky Remark 4.2; cubic-piece bounds only —
    /// polyline bounds keep such data exactly): the curve passes through the moved values, not
    /// the given ones. Empty when every data value is interpolated exactly.
    pub shifted_data: Vec<usize>,
}

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

/// Maps the library's typed error to a field path (the library names the user's field and index
/// in every input error) and a message in the user's words (numbers as written, see
/// [`num`]; the field is not repeated: [`InputError`] prints it).
fn input_error(t: &[f64], e: &strip::Error) -> InputError {
    use strip::Error as E;
    use strip::Infeasibility as I;
    let at = |field: &str, index: usize| format!("{field}[{index}]");
    // where a data point is (the data-point errors name y[i])
    let site = |index: usize| {
        t.get(index)
            .map_or(String::new(), |t| format!(" at t = {}", num(*t)))
    };
    match e {
        E::TooFew {
            field,
            minimum,
            got,
        } => InputError::new(
            *field,
            format!("needs at least {minimum} entries, got {got}"),
        ),
        E::WrongLength {
            field,
            expected,
            got,
        } => InputError::new(*field, format!("has length {got}, expected {expected}")),
        E::NonFinite { field, index } => InputError::new(at(field, *index), "is not finite"),
        E::TooLarge {
            field,
            index,
            limit,
            ..
        } => InputError::new(
            at(field, *index),
            format!("exceeds {} in magnitude", num(*limit)),
        ),
        E::NonIncreasing { field, index } => InputError::new(
            at(field, *index),
            format!("is not greater than {field}[{}]", index - 1),
        ),
        E::InvalidValue {
            field,
            index,
            reason,
        }
        | E::Unsupported {
            field,
            index,
            reason,
        } => InputError::new(at(field, *index), reason),
        E::Infeasible {
            field,
            index,
            reason,
        } => InputError::new(
            at(field, *index),
            match reason {
                I::OutsideBound { side, by } => {
                    format!("lies outside the {side} bound by {}{}", num(*by), site(*index))
                }
                I::Closed { at } => format!(
                    "the lower bound is not below the upper bound at t = {}",
                    num(*at)
                ),
                I::Kink { side } => format!(
                    "lies on a kink of the {side} bound{} that no smooth curve can pass",
                    site(*index)
                ),
                other => other.to_string(),
            },
        ),
        E::StripViolated {
            side,
            interval,
            by,
            tolerance,
            sites_rounding,
        } => {
            let hint = strip::sites_rounding_hint(*by, *sites_rounding);
            // (the sites' rounding is the cause, not the bound: name `t`)
            InputError::new(
                if hint.is_empty() { side_name(*side) } else { "t" },
                format!(
                    "the solution leaves the {side} bound by {} in interval {interval} (tolerance {}){hint}",
                    num(*by),
                    num(*tolerance)
                ),
            )
        }
        E::Discontinuous { at, by, tolerance } => InputError::new(
            "t",
            format!(
                "the solution's pieces do not join at t = {} (by {}, tolerance {}): rescale t and y",
                num(*at),
                num(*by),
                num(*tolerance)
            ),
        ),
        E::Uncertified { gap, required, .. } => InputError::new(
            "",
            format!(
                "no certified answer: the best curve keeps to the strip within its tolerance, but its optimality gap is {} (an answer must be within {}); the strip is too narrow against the data's slopes for double precision: widen the bounds where the curve must turn sharply",
                num(*gap),
                num(*required)
            ),
        ),
        E::NotConverged {
            solver,
            iterations,
            residual,
        } if *solver == strip::EXCHANGE => InputError::new(
            "",
            format!(
                "{solver} stopped after {iterations} sweeps with the curve still outside the strip by {} of the value scale (beside a knot where the data are too steep to place another contact in double precision, or at its sweep limit): widen the bounds where the curve must turn sharply",
                num(*residual)
            ),
        ),
        E::NotConverged {
            solver,
            iterations,
            residual,
        } => InputError::new(
            "",
            format!(
                "{solver} did not converge in {iterations} iterations (optimality gap {})",
                num(*residual)
            ),
        ),
        _ => InputError::new("", e),
    }
}

/// `curvefit strip`: validates and solves the problem with [`strip::solve`].
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn solve(p: &Problem) -> Result<Solution, InputError> {
    solve_observed(p, &|_| {})
}

/// [`solve`], telling `progress` of each iteration of Newton on Φ and each sweep of the exchange
/// ([`strip::solve_observed`]).
///
/// # Errors
/// As [`solve`].
pub fn solve_observed(
    p: &Problem,
    progress: &dyn Fn(&strip::Progress),
) -> Result<Solution, InputError> {
    solve_data(p.t.0.clone(), p.y.0.clone(), p, progress)
}

/// [`solve`] for a problem that is not needed afterwards: its data `t` and `y` move into the
/// solve instead of being copied (the Python package's calls).
///
/// # Errors
/// As [`solve`].
pub fn solve_owned(mut p: Problem) -> Result<Solution, InputError> {
    let (t, y) = (std::mem::take(&mut p.t.0), std::mem::take(&mut p.y.0));
    solve_data(t, y, &p, &|_| {})
}

/// The strip of data `t`, `y` (the problem's, moved or copied) with `p`'s bounds and ends.
fn solve_data(
    t: Vec<f64>,
    y: Vec<f64>,
    p: &Problem,
    progress: &dyn Fn(&strip::Progress),
) -> Result<Solution, InputError> {
    if t.len() > MAX_POINTS {
        return Err(InputError::new(
            "t",
            format!("{} data points exceed the limit of {MAX_POINTS}", t.len()),
        ));
    }
    let problem = strip::Problem {
        t,
        y,
        lower: bound(&p.lower),
        upper: bound(&p.upper),
        end_slopes: p.end_slopes.unwrap_or([None, None]),
    };
    let s = strip::solve_observed(&problem, &strip::Options::default(), progress)
        .map_err(|e| input_error(&problem.t, &e))?;
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
        shifted_data: s.shifted_data,
    })
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
        let s = solve(&p).unwrap();
        assert!(!s.extra_knots.is_empty());
        assert!(s.extra_knots.iter().all(|k| k.kind.ends_with("lower")));
        assert!((s.norm * s.norm - s.energy).abs() <= 1e-12 * s.energy);
        assert_eq!(s.breaks.len(), s.coefficients.len() + 1);
    }

    /// A problem solved by value (its data moved) gives the result and the errors of the same
    /// problem solved by reference.
    #[test]
    fn solving_a_moved_problem_equals_solving_a_borrowed_one() {
        for text in [
            r#"{"t": [0, 1, 2, 3, 4], "y": [0, 1, 0, 0, 1], "lower": {"pieces": [[-0.05,0,0,0],[-0.05,0,0,0],[-0.05,0,0,0],[-0.05,0,0,0]]}}"#,
            r#"{"t": [0, 1, 2], "y": [0, 2, 0], "upper": {"pieces": [[1,0,0,0],[1,0,0,0]]}}"#,
            r#"{"t": [0, 1, 1], "y": [0, 1, 0]}"#,
        ] {
            let json = |r: Result<Solution, InputError>| match r {
                Ok(s) => serde_json::to_string(&s).unwrap(),
                Err(e) => format!("{e}"),
            };
            let p = parse(text);
            let borrowed = json(solve(&p));
            assert_eq!(json(solve_owned(p)), borrowed, "{text}");
        }
    }

    #[test]
    fn errors_name_the_field() {
        let p = parse(r#"{"t": [0, 1, 2], "y": [0, 1, 0], "lower": {"pieces": [[0,0,0,0]]}}"#);
        assert_eq!(solve(&p).unwrap_err().field, "lower.pieces");
        let p = parse(r#"{"t": [0, 1, 1], "y": [0, 1, 0]}"#);
        assert_eq!(solve(&p).unwrap_err().field, "t[2]");
        let p = parse(
            r#"{"t": [0, 1, 2], "y": [0, 2, 0], "upper": {"pieces": [[1,0,0,0],[1,0,0,0]]}}"#,
        );
        assert_eq!(solve(&p).unwrap_err().field, "y[1]");
        let p = parse(
            r#"{"t": [0, 1, 2], "y": [0, 0.5, 0], "lower": {"pieces": [[-1,0,0,0],[2,0,0,0]]}, "upper": {"pieces": [[1,0,0,0],[1,0,0,0]]}}"#,
        );
        assert_eq!(solve(&p).unwrap_err().field, "lower.pieces[1]");
        assert!(
            serde_json::from_str::<Problem>(r#"{"t": [0, 1], "y": [0, 1], "extra": 1}"#).is_err()
        );
    }
}
