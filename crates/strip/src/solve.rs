//! The entry point: validate, normalize, solve the outer problem, map back, check.

use crate::assemble::{assemble, assemble_spline, to_caller};
use crate::check::worst_violation;
use crate::error::{Error, Infeasibility};
use crate::frame::{scaled, Frame};
use crate::outer;
use crate::piece::cubic3;
use crate::strategy::{self, CellsOut, Staged};
use crate::types::{Options, Problem, Solution, RESULT_FEASIBILITY_TOL, ROUNDING_TOL};
use crate::validate::validate;
use crate::Progress;

/// Solves the strip problem.
///
/// The solver works on the normalized problem (sites over a unit-order range starting at 0, the
/// line through the first and last data point subtracted, values divided by the value scale V;
/// see the crate documentation), so the answer is equivariant under t ↦ t₀ + λt, values ↦ c·v
/// and adding a line, and every tolerance is relative to V or the site range. The answer is
/// solved again in the caller's frame through its points (the data, and touching points: every
/// contact of the exchange, Newton on Φ's tangencies and pairs), on its bound over each subarc,
/// with Newton's tangencies and subarc ends placed again on their conditions (`resolve`: the
/// frame's rounding of the values moves f'' on short spans). The returned
/// pieces are checked against the strip in the caller's frame (exact extrema of every cubic
/// piece): a violation above [`RESULT_FEASIBILITY_TOL`]·V plus the rounding allowance
/// [`ROUNDING_TOL`]·M (M the magnitude of the values, see [`Solution::violation`]) is an
/// [`Error::StripViolated`], never an answer.
///
/// # Errors
/// Invalid input (lengths, non-finite numbers, non-increasing sites or polylines, data outside
/// the bounds, an empty strip) and an interval without a feasible candidate give an [`Error`]
/// naming the field and index; numbers too badly scaled for double precision give
/// [`Error::InvalidValue`]; running out of iterations gives [`Error::NotConverged`].
pub fn solve(problem: &Problem, opts: &Options) -> Result<Solution, Error> {
    solve_observed(problem, opts, &|_| {})
}

/// [`solve`], telling `progress` how a long solve goes ([`Progress`]: each iteration of Newton
/// on Φ, each sweep of the exchange), on the calling thread. Keep it cheap: it runs once an
/// iteration or sweep.
///
/// # Errors
/// As [`solve`].
pub fn solve_observed(
    problem: &Problem,
    opts: &Options,
    progress: &dyn Fn(&Progress),
) -> Result<Solution, Error> {
    validate(problem)?;
    let frame = Frame::of(problem)?;
    let normalized = frame.forward(problem)?;
    let (sol, exchange) =
        solve_normalized(problem, &normalized, &frame, opts, progress).map_err(|e| match e {
            // distances and places in the caller's units
            Error::Infeasible {
                field,
                index,
                reason,
            } => Error::Infeasible {
                field,
                index,
                reason: match reason {
                    Infeasibility::OutsideBound { side, by } => Infeasibility::OutsideBound {
                        side,
                        by: by * frame.c,
                    },
                    Infeasibility::Closed { at } => Infeasibility::Closed { at: frame.time(at) },
                    other => other,
                },
            },
            other => other,
        })?;
    let finite = sol.energy.is_finite()
        && sol.slopes.iter().all(|z| z.is_finite())
        && sol.coefficients.iter().flatten().all(|c| c.is_finite())
        && sol.breaks.iter().all(|b| b.is_finite());
    if !finite {
        return Err(scaled("y", 0));
    }
    let mut sol = sol;
    let tolerance = RESULT_FEASIBILITY_TOL * frame.scale + ROUNDING_TOL * frame.magnitude;
    // (a re-solved answer has passed the strip's test below already)
    let mut checked = false;
    if let Some(exact) = crate::resolve::in_callers_frame(problem, &sol, exchange, tolerance) {
        (sol, checked) = (exact, true);
    }
    // the pieces must join (each starts at its exact value): coefficients c·v/λ^k that
    // underflow (values tiny against the site scale) break this, and the answer would not
    // interpolate
    let last = sol.coefficients.len() - 1;
    for j in 0..=last {
        let (k, h) = (&sol.coefficients[j], sol.breaks[j + 1] - sol.breaks[j]);
        let (end, slope, _) = cubic3(k, h);
        // the end value carries the rounding of its terms c_k h^k and of the abscissa (steep
        // next to short spans: slope × ulp(t))
        let terms = k[0].abs()
            + h * (k[1].abs() + h * (k[2].abs() + h * k[3].abs()))
            + slope.abs() * sol.breaks[j + 1].abs();
        let next = if j < last {
            Some(sol.coefficients[j + 1][0])
        } else {
            let n = problem.y.len();
            (!sol.shifted_data.contains(&(n - 1))).then_some(problem.y[n - 1])
        };
        if let Some(next) = next {
            let by = (end - next).abs();
            let tolerance = tolerance + ROUNDING_TOL * terms;
            if by.is_nan() || by > tolerance {
                return Err(Error::Discontinuous {
                    at: sol.breaks[j + 1],
                    by,
                    tolerance,
                });
            }
        }
    }
    let worst = if checked {
        None
    } else {
        worst_violation(problem, &sol)
    };
    if let Some((by, interval, side)) = worst {
        sol.violation = by;
        if by.is_nan() || by > tolerance {
            return Err(Error::StripViolated {
                interval,
                side,
                by,
                tolerance,
                sites_rounding: sites_rounding(problem, &sol, interval),
            });
        }
    }
    Ok(sol)
}

/// How far the values of the pieces over data interval `interval` move when their abscissae move
/// by one rounding: max |f'| · ε · max |t| there (ε = 2⁻⁵², so ε·|t| is one to two ulps of t).
/// A bound evaluated at a rounded abscissa is uncertain by as much; see
/// [`Error::StripViolated`].
fn sites_rounding(problem: &Problem, sol: &Solution, interval: usize) -> f64 {
    let (a, b) = (problem.t[interval], problem.t[interval + 1]);
    let mut worst = 0.0f64;
    for (j, k) in sol.coefficients.iter().enumerate() {
        let (x0, x1) = (sol.breaks[j], sol.breaks[j + 1]);
        if x1 < a || x0 > b {
            continue;
        }
        let h = x1 - x0;
        let slope = k[1].abs() + h * (2.0 * k[2].abs() + 3.0 * h * k[3].abs());
        worst = worst.max(slope * f64::EPSILON * x0.abs().max(x1.abs()));
    }
    worst
}

/// Solves `q`, the normalized form of `problem` in `frame`, and returns the solution in the
/// caller's frame, and whether the exchange produced it.
fn solve_normalized(
    problem: &Problem,
    q: &Problem,
    frame: &Frame,
    opts: &Options,
    progress: &dyn Fn(&Progress),
) -> Result<(Solution, bool), Error> {
    let ef = frame.energy_factor();
    let (staged, shifted) = strategy::run(
        q,
        opts,
        frame.scale / frame.c,
        ef * frame.lam / frame.c,
        progress,
    )?;
    let exchange = matches!(staged, Staged::Spline { .. });
    let sol = match staged {
        Staged::Spline { q: qs, ex } => assemble_spline(problem, &qs, frame, &ex, shifted),
        Staged::Cells(CellsOut {
            setup: st,
            out,
            stats,
            cell_solves,
        }) => {
            let outer = &st.outer;
            // the decrement ½gᵀH⁻¹g estimates Φ − min Φ (BFGS does not compute it: one Hessian
            // here)
            let decrement = if out.decrement.is_nan() {
                outer::decrement_at(outer, &out.x, &out.grad)
            } else {
                out.decrement
            };
            // abscissae in the caller's frame, placed from their data site (a break or knot
            // inside a short interval keeps its offset exactly; t₀ + λu would round it to
            // ulp(u))
            let place = |j: usize, offset: f64| problem.t[j] + frame.lam * offset;
            // how far the rounded abscissa lies from the exact one, in normalized units: pieces
            // are re-expanded about the abscissa actually returned (a bound of slope 1e12 moves
            // by 2.6e-4 over the 2e-16 rounding of a break near t = 2.5)
            let error = |j: usize, offset: f64| {
                ((place(j, offset) - problem.t[j]) - frame.lam * offset) / frame.lam
            };
            let mut sol = assemble(&place, &error, outer, &out, cell_solves, stats, shifted);
            sol.newton_decrement = decrement;
            sol.gap = if out.phi > 0.0 {
                (decrement / out.phi).max(0.0)
            } else {
                0.0
            };
            sol.gradient_norm = out
                .grad
                .iter()
                .zip(&outer.unit)
                .map(|(g, u)| (g * u) * (g * u))
                .sum::<f64>()
                .sqrt();
            sol
        }
    };
    Ok((to_caller(problem, frame, sol), exchange))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell::CellStats;
    use crate::outer::{setup, Hints};
    use crate::types::Bound;

    /// Sixteen oscillating data values in a strip of half-width w about their polygon.
    fn polygon_strip(w: f64) -> Problem {
        let y = [
            0.0, 2.0, 1.0, 3.0, 2.0, 2.5, 1.0, 2.0, 1.5, 2.5, 3.0, 0.5, 0.5, 3.0, 1.5, 2.0,
        ];
        let n = y.len();
        let side = |c: f64| -> Bound {
            Bound::Pieces(
                (0..n - 1)
                    .map(|i| [y[i] + c, y[i + 1] - y[i], 0.0, 0.0])
                    .collect(),
            )
        };
        Problem {
            t: (0..n).map(|i| i as f64).collect(),
            y: y.to_vec(),
            lower: side(-w),
            upper: side(w),
            end_slopes: [None, None],
        }
    }

    /// Φ and ∇Φ at the unknowns `x` (slopes at the data sites without prescribed end slopes, in
    /// order), and the starting point (natural/clamped spline). For tests of the analytic
    /// gradient.
    fn objective(problem: &Problem, x: Option<&[f64]>) -> Result<(f64, Vec<f64>, Vec<f64>), Error> {
        let vscale = 1.0 + problem.y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let st = setup(problem, &Options::default(), vscale)?;
        let x = x.map_or_else(|| st.x0.clone(), <[f64]>::to_vec);
        if x.len() != st.outer.nvar {
            return Err(Error::WrongLength {
                field: "x",
                expected: st.outer.nvar,
                got: x.len(),
            });
        }
        let mut hints: Hints = vec![None; problem.t.len() - 1];
        let e = st
            .outer
            .eval(&x, &mut hints, None, &mut CellStats::default(), &mut 0)
            .map_err(|j| st.outer.no_candidate(j))?;
        Ok((e.phi, e.grad, st.x0))
    }

    #[test]
    fn outer_gradient_matches_finite_differences() {
        // ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)) against central differences of Φ, at the starting
        // point and at a perturbed point, for strips with every contact kind, natural and
        // clamped ends.
        let mut clamped = polygon_strip(0.15);
        clamped.end_slopes = [Some(3.0), None];
        let cases = [polygon_strip(0.1), clamped];
        for p in &cases {
            let (_, _, x0) = objective(p, None).unwrap();
            let xs = [
                x0.clone(),
                x0.iter()
                    .enumerate()
                    .map(|(k, v)| v + 0.01 * ((k * 7 % 5) as f64 - 2.0))
                    .collect::<Vec<_>>(),
            ];
            for x in &xs {
                let (_, g, _) = objective(p, Some(x)).unwrap();
                for k in 0..x.len() {
                    let d = 1e-6;
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[k] += d;
                    xm[k] -= d;
                    let fd = (objective(p, Some(&xp)).unwrap().0
                        - objective(p, Some(&xm)).unwrap().0)
                        / (2.0 * d);
                    assert!(
                        (fd - g[k]).abs() <= 1e-5 * (1.0 + g[k].abs()),
                        "∂Φ/∂x{k}: {} vs fd {fd}",
                        g[k]
                    );
                }
            }
        }
    }
}
