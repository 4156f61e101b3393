//! The answer solved again in the caller's frame, from the caller's own numbers.
//!
//! The solver works in the normalized frame ([`crate::frame`]), whose values (y − a) − b(t − t₀)
//! each round by ~ε|y|; over a span h that moves a slope by ε|y|/h, and on very short spans f''
//! with it. Measured on `xtask/sweeps/strip.py`'s seed 719, case 69 (5000 sites near t = 5·10⁵
//! with spans from 7.5e-9 to 28, values in [−1, 1]): the natural spline came back with f'' 54 %
//! of its size off at a span of 1e-7 and ∫f''² 6.7e-7 above its value in 60-digit arithmetic
//! (which scipy's `CubicSpline` on the same doubles matches to 12 digits), and the same sites in
//! a polyline band of 0.3 % of the range (10 contacts) 6.0e-7 above the spline through the same
//! points (ROBUSTNESS.md §4, item 46). Perturbing those values by one ulp moves the exact ∫f''² by
//! 1e-7 … 5e-6 of itself, so no frame that rounds the values can give these answers.
//!
//! Where the answer is a spline through points — the data, and its touching points (f equal to
//! its bound there: the exchange's contacts, and Newton on Φ's tangencies and touching pairs,
//! where f' meets the bound's slope too) — it is solved again through the same abscissae
//! with the caller's values: the data as given, a contact's value its bound's at that abscissa,
//! computed in the caller's frame with the error of its rounding ([`crate::compensated`]). The
//! slopes of the moment system are formed with the roundings of their differences, of their
//! quotient and of the contacts' values ([`Spline::through_exactly`]), so its right-hand sides
//! keep the accuracy of their own size even where the slopes nearly cancel, and the system is
//! diagonally dominant (condition ≤ 3): the moments are those of the caller's doubles and its
//! bounds' exact values, to rounding. (Without the compensation, on `strip.py` seed 1, sites near
//! 10⁶ with values 1e7 and slopes 3e4 lost four digits of their moments, ∫f''² 4.7e-13 of
//! itself off; a contact's value rounded to ε|g| moved f'' by 1.1e-9 of its size at a break 1e-8
//! from the next, `tests/offset.rs`.) Where that spline fails a test below, the spline through
//! the contacts' values rounded to doubles is tried next: a contact whose multiplier is at
//! rounding can change sign between the two (on `strip.py` seeds 3 and 727, by 4e-7 and 1.7e-7
//! of the largest |f'''|, on data where one ulp of the contacts' values moves f'' by 1e-7 of its
//! size). Either replaces the solver's answer only when
//! - its slopes join to their rounding ([`SLOPE_ROUNDING`]) and every number is finite (moments
//!   that underflow, values 1e-268 on spans of 1e34, leave a polygon that is no spline; on spans
//!   of 1e-79 f''² overflows);
//! - every contact's f''' jump, its multiplier, has the sign of its side (up at a lower contact,
//!   down at an upper one; [`SIGN_TOLERANCE`] of the largest |f'''|): then it is optimal among
//!   the curves that keep to its contact points, a relaxation of the strip (with no contact, the
//!   natural or clamped spline: Holladay);
//! - it keeps to the strip by the test every answer passes ([`crate::solve()`]), and its gap — the
//!   exchange's estimate 2 Σ |jump| × excursion over ∫f''² — is at most the exchange's acceptance.
//!
//! At a tangency the spline through the touching point need not meet the bound's slope there:
//! it does when the solver's abscissa is the optimum's (the optimum is the spline through its
//! contacts, Holladay), and where rounding moves the abscissa the energy moves to second order
//! only (f' = g' makes it stationary in the abscissa); the strip's test then judges the answer.
//! Measured on `tests/offset.rs`'s clustered sites in bands of constant pieces (one and two
//! tangencies): Newton's answers were 1.3e-11 and 1.5e-11 of ∫f''² above the spline through the
//! same points, f'' 1.6e-8 and 8.4e-9 of its size off; formed again, ∫f''² to the last bit and
//! f'' to 2.2e-16 of its size.
//!
//! A subarc (f on its bound over an interval) is no point; answers with one stay as solved.

use crate::check::worst_violation;
use crate::piece::cubic3;
use crate::spline::Spline;
use crate::strategy::ACCEPT_GAP;
use crate::types::{KnotKind, Problem, Side, Solution};

/// A spline's slopes join to this many ε times the size of the terms they are formed from.
const SLOPE_ROUNDING: f64 = 64.0;

/// A contact's f''' jump may have the wrong sign by this fraction of the largest |f'''|.
const SIGN_TOLERANCE: f64 = 1e-9;

/// `sol` solved again in the caller's frame (module docs), or `None` where it is not a spline
/// through points (a subarc), or the new spline fails a test. `exchange`: whether the exchange
/// produced `sol` (it reports no gradient); `tolerance`: the strip's, as [`crate::solve()`]
/// applies it. The answer carries its [`Solution::violation`], from the same exact test.
pub(crate) fn in_callers_frame(
    problem: &Problem,
    sol: &Solution,
    exchange: bool,
    tolerance: f64,
) -> Option<Solution> {
    if !sol.shifted_data.is_empty() || !sol.uncertified.is_empty() {
        return None;
    }
    let (t, n) = (&problem.t, problem.t.len());
    // The values at the breaks; where each data site is among them; the contacts' breaks.
    let mut values = Vec::with_capacity(sol.breaks.len());
    let mut low = vec![0.0; sol.breaks.len()];
    let mut at_site = Vec::with_capacity(n);
    let mut contacts = Vec::with_capacity(sol.extra_knots.len());
    let mut extra = sol.extra_knots.iter().peekable();
    for (j, &b) in sol.breaks.iter().enumerate() {
        let site = at_site.len();
        if site < n && t[site].to_bits() == b.to_bits() {
            values.push(problem.y[site]);
            at_site.push(j);
        } else if let Some(k) = extra.next_if(|k| k.t.to_bits() == b.to_bits()) {
            let KnotKind::Touch(side) = k.kind else {
                return None;
            };
            let (value, error) = problem.bound_at_compensated(side, b);
            values.push(value);
            low[j] = error;
            contacts.push((j, side));
        } else {
            return None;
        }
    }
    if at_site.len() != n || extra.next().is_some() {
        return None;
    }
    let points = Points {
        values,
        at_site,
        contacts,
    };
    let through = |low: &[f64]| formed(problem, sol, exchange, tolerance, &points, low);
    // Through the bounds' exact values first; where that fails a test, through their doubles
    // (the module docs: a contact whose multiplier is at rounding can change sign between them).
    through(&low).or_else(|| {
        let rounded = vec![0.0; low.len()];
        low.iter()
            .any(|&l| l != 0.0)
            .then(|| through(&rounded))
            .flatten()
    })
}

/// The points an answer is formed through: the values at its breaks (the data at a site, a
/// contact's bound value rounded to a double), where each data site is among them, and the
/// contacts' breaks with their sides.
struct Points {
    values: Vec<f64>,
    at_site: Vec<usize>,
    contacts: Vec<(usize, Side)>,
}

/// The spline through `points` (their values plus the low parts `low`) as an answer in place of
/// `sol`, or `None` where it fails a test ([`in_callers_frame`]).
fn formed(
    problem: &Problem,
    sol: &Solution,
    exchange: bool,
    tolerance: f64,
    points: &Points,
    low: &[f64],
) -> Option<Solution> {
    let (t, n) = (&problem.t, problem.t.len());
    let (at_site, contacts) = (&points.at_site, &points.contacts);
    let spline = Spline::through_exactly(
        sol.breaks.clone(),
        points.values.clone(),
        low,
        problem.end_slopes,
    );
    let energy = spline.energy();
    let coefficients = spline.to_curve().coeffs;
    if !energy.is_finite() || !coefficients.iter().flatten().all(|c| c.is_finite()) {
        return None;
    }
    let (x, m, v) = (&spline.x, &spline.m, &spline.v);
    let k = x.len();
    // the slopes join (and meet the given end slopes) to their rounding
    let slope_size = |i: usize| {
        let h = x[i + 1] - x[i];
        ((v[i + 1] - v[i]) / h).abs() + h * (m[i].abs() + m[i + 1].abs())
    };
    for i in 0..k {
        let left = match i {
            0 => problem.end_slopes[0],
            _ => Some(cubic3(&coefficients[i - 1], x[i] - x[i - 1]).1),
        };
        let right = if i + 1 == k {
            problem.end_slopes[1]
        } else {
            Some(coefficients[i][1])
        };
        let size = if i > 0 { slope_size(i - 1) } else { 0.0 }
            + if i + 1 < k { slope_size(i) } else { 0.0 };
        if let (Some(l), Some(r)) = (left, right) {
            let by = (l - r).abs();
            if by.is_nan() || by > SLOPE_ROUNDING * f64::EPSILON * size {
                return None;
            }
        }
    }
    // each contact's multiplier, the f''' jump, on its side's sign
    let f3max = (0..k - 1).fold(0.0f64, |a, j| a.max(spline.third(j).abs()));
    let mut jumps = 0.0;
    for &(j, side) in contacts {
        let jump = spline.jump(j).0;
        let wrong = match side {
            Side::Lower => -jump,
            Side::Upper => jump,
        };
        if wrong > SIGN_TOLERANCE * f3max {
            return None;
        }
        jumps += jump.abs();
    }
    let last = coefficients[k - 2];
    let mut slopes: Vec<f64> = at_site
        .iter()
        .map(|&j| match coefficients.get(j) {
            Some(c) => c[1],
            None => cubic3(&last, x[k - 1] - x[k - 2]).1,
        })
        .collect();
    for (side, end) in [0, n - 1].into_iter().enumerate() {
        if let Some(s) = problem.end_slopes[side] {
            slopes[end] = s;
        }
    }
    // ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)) at the sites whose slope is free: the moments' rounding
    // (0 for the exchange's answers, as it reports them)
    let second = |j: usize, s: f64| cubic3(&coefficients[j], s).2;
    let gradient_norm = if exchange {
        0.0
    } else {
        (0..n)
            .filter(|&i| !(i == 0 && problem.end_slopes[0].is_some()))
            .filter(|&i| !(i == n - 1 && problem.end_slopes[1].is_some()))
            .map(|i| {
                let j = at_site[i];
                let left = if j > 0 {
                    second(j - 1, x[j] - x[j - 1])
                } else {
                    0.0
                };
                let right = if j + 1 < k { second(j, 0.0) } else { 0.0 };
                let g = 2.0 * (left - right);
                g * g
            })
            .sum::<f64>()
            .sqrt()
    };
    let mut out = Solution {
        coefficients,
        slopes,
        grid: t.clone(),
        grid_values: problem.y.clone(),
        energy,
        norm: energy.sqrt(),
        gradient_norm,
        newton_decrement: 0.0,
        gap: 0.0,
        ..sol.clone()
    };
    // (the strip's test, made here once: the caller takes `violation` from it)
    out.violation = match worst_violation(problem, &out) {
        Some((by, _, _)) if by.is_nan() || by > tolerance => return None,
        Some((by, _, _)) => by,
        None => 0.0,
    };
    out.newton_decrement = 2.0 * jumps * out.violation.max(0.0);
    out.gap = if energy > 0.0 {
        out.newton_decrement / energy
    } else {
        0.0
    };
    (out.gap <= ACCEPT_GAP).then_some(out)
}
