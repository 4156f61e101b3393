//! The exact solver for polyline bounds: a dual active-set (Goldfarb–Idnani) method on point
//! constraints, driven by an exact sweep of the strip (an exchange method for the
//! semi-infinite QP).
//!
//! **The point problem.** For a finite set of points P with sides, minimize ∫f''² subject to
//! f(t_i) = y_i and f(p) ≥ e(p) (lower points), f(p) ≤ d(p) (upper points). Its solution is the
//! cubic spline through the data and the *active* points held on their bound (Holladay), with
//! natural (or the prescribed clamped) ends; the multiplier of an active point is the jump of
//! f''' there (∂∫f''²/∂f(p) = 2·jump), which must be ≥ 0 at a lower point and ≤ 0 at an upper
//! one. It is a relaxation of the strip problem, so its optimum is a **lower bound** on the strip
//! optimum, and when its spline satisfies the strip everywhere (to the tolerance), it **is** the
//! strip optimum: a function is optimal for the strip exactly when it is C² (every spline is),
//! interpolates, stays in the strip, and f''' jumps only at contacts, up at lower and down at
//! upper ones (for any feasible g, ∫g''² − ∫f''² ≥ 2 Σ jump·(g − f)(τ) ≥ 0).
//!
//! **Dual active set** (Goldfarb & Idnani, *A numerically stable dual method for solving strictly
//! convex quadratic programs*, Math. Programming 27, 1983). The iterate is always dual feasible
//! (every multiplier has the right sign); a violated point q is added by moving its value from
//! f(q) to its bound. Along that move everything is linear in the value (the spline is linear in
//! its data), so the multipliers of the active points move linearly: when one reaches zero
//! first, the move stops there and that point leaves the active set (its jump is zero, so the
//! spline does not change), and the move continues; otherwise q joins. Each step is one or two
//! tridiagonal solves (diagonally dominant: well conditioned however uneven the spacing). The
//! dual objective increases strictly, so the method cannot cycle.
//!
//! **Exchange.** An O(M) sweep ([`crate::check::excursions`]) finds, on every sub-interval
//! between consecutive knots and bound breakpoints, where f leaves the strip most (the real roots
//! of the derivative of the cubic minus the bound). In every run of consecutive violated
//! sub-intervals the worst point is a candidate (one per run: adding every violated point
//! activates nearly every vertex of a narrow channel at once, far from the answer); candidates
//! still violated when their turn comes are added. Points at vertices fix contacts at kinks of
//! the polyline; points inside segments converge to the tangent contacts (the added point lands
//! where f dips deepest, and the previous one leaves the active set as its multiplier falls to
//! zero), quadratically in the measured runs. The sweeps stop when f leaves the strip nowhere
//! by more than the tolerance.
//!
//! Measured on the issue-15 channels (M = 10³ … 10⁴, 16 and 200 sites): 16–34 sweeps, 500–2600
//! spline solves; the energies agree with the Φ-based exact stage where that one converged
//! (6.5·10⁻⁹ relative, from below, as they must) and showed it 1.1·10⁻⁵ too high where it
//! stopped at a vertex contact with f'' jumping (see [`crate::stages`]).

use crate::check::excursions;
use crate::spline::{Curve, Spline};
use crate::types::{Bound, Problem, Side};

/// The sweeps stop when f leaves the strip nowhere by more than this fraction of the value scale
/// (normalized frame). Its first-order effect on the energy (holding every contact up by this
/// much, [`crate::Solution::gap`]) was ≤ 2·10⁻¹⁰ relative on the generator's channels; the
/// rounding of the spline's values there is ~10⁻¹³.
pub(crate) const EXCHANGE_TOL: f64 = 1e-12;
/// The sweeps go on with a tolerance 100 times smaller while the first-order gap estimate
/// ([`Exchanged::gap`]) exceeds this (a hair-thin strip turns sharply, so its multipliers are
/// large and a tolerance relative to the value scale alone is too coarse) …
pub(crate) const GAP_TARGET: f64 = 1e-11;
/// … down to this fraction of the value scale (the rounding of the spline's values).
const TOL_FLOOR: f64 = 1e-15;
/// Sweeps before giving up.
pub(crate) const MAX_SWEEPS: usize = 400;
/// Dual steps (additions and removals) before giving up.
const MAX_STEPS: usize = 2_000_000;

/// An active point: abscissa, side, and its bound value there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Contact {
    pub x: f64,
    pub side: Side,
    pub value: f64,
}

/// The exchange's answer.
pub(crate) struct Exchanged {
    /// The spline through the data and the active points.
    pub spline: Spline,
    /// The active points.
    pub active: Vec<Contact>,
    /// The largest excursion of the spline outside the strip (normalized frame).
    pub violation: f64,
    /// Whether the sweeps ended with no excursion above the tolerance.
    pub converged: bool,
    /// First-order estimate of how far the energy lies below the strip optimum, relative: what
    /// holding every contact up by the remaining excursion would cost (∂∫f''²/∂f(τ) = 2·jump),
    /// over the energy.
    pub gap: f64,
    /// Sweeps, dual steps, spline solves.
    pub sweeps: usize,
    pub steps: usize,
    pub solves: usize,
}

/// The bound of `side` at x.
fn bound_at(q: &Problem, side: Side, x: f64) -> f64 {
    let b = if side == Side::Lower {
        &q.lower
    } else {
        &q.upper
    };
    match b {
        Bound::None => {
            if side == Side::Lower {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            }
        }
        Bound::Pieces(p) => {
            let n = q.t.len();
            let i = q.t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
            crate::piece::cubic3(&p[i], x - q.t[i]).0
        }
        Bound::Polyline(v) => crate::types::polyline_at(v, x),
    }
}

/// The spline through the data and `active` (sorted), with `extra` (abscissa, value) inserted;
/// and for every active point its index among the knots.
fn spline_through(
    q: &Problem,
    active: &[Contact],
    extra: Option<(f64, f64)>,
) -> (Spline, Vec<usize>) {
    let t = &q.t;
    let k = t.len() + active.len() + usize::from(extra.is_some());
    let mut x = Vec::with_capacity(k);
    let mut v = Vec::with_capacity(k);
    let mut at = Vec::with_capacity(active.len());
    let (mut i, mut a) = (0, 0);
    let mut e = extra;
    loop {
        let next_t = t.get(i).copied().unwrap_or(f64::INFINITY);
        let next_a = active.get(a).map_or(f64::INFINITY, |c| c.x);
        let next_e = e.map_or(f64::INFINITY, |e| e.0);
        if next_t.is_infinite() && next_a.is_infinite() && next_e.is_infinite() {
            break;
        }
        if next_t <= next_a && next_t <= next_e {
            x.push(next_t);
            v.push(q.y[i]);
            i += 1;
        } else if next_a <= next_e {
            at.push(x.len());
            x.push(next_a);
            v.push(active[a].value);
            a += 1;
        } else {
            let (ex, ev) = e.take().expect("checked above");
            x.push(ex);
            v.push(ev);
        }
    }
    (Spline::through(x, v, q.end_slopes), at)
}

/// The multipliers of the active points (f''' jump, positive when of the right sign).
fn multipliers(s: &Spline, active: &[Contact], at: &[usize]) -> Vec<f64> {
    active
        .iter()
        .zip(at)
        .map(|(c, &k)| {
            let j = s.jump(k).0;
            if c.side == Side::Lower {
                j
            } else {
                -j
            }
        })
        .collect()
}

/// Value of the spline at x.
fn value_at(s: &Spline, x: f64) -> f64 {
    let mut out = Vec::with_capacity(1);
    s.eval_sorted(&[x], &mut out);
    out[0]
}

/// The state of the method.
struct State<'a> {
    q: &'a Problem,
    active: Vec<Contact>,
    steps: usize,
    solves: usize,
}

impl State<'_> {
    /// Adds the point x on `side` (violated by the current spline): the dual step.
    fn add(&mut self, x: f64, side: Side) {
        let target = bound_at(self.q, side, x);
        let (s0, _) = spline_through(self.q, &self.active, None);
        self.solves += 1;
        let mut value = value_at(&s0, x);
        loop {
            self.steps += 1;
            let (f0, at0) = spline_through(self.q, &self.active, Some((x, value)));
            let (f1, at1) = spline_through(self.q, &self.active, Some((x, target)));
            self.solves += 2;
            let (m0, m1) = (
                multipliers(&f0, &self.active, &at0),
                multipliers(&f1, &self.active, &at1),
            );
            // the first active multiplier to reach zero along value → target
            let mut block: Option<(f64, usize)> = None;
            for (i, (&a, &b)) in m0.iter().zip(&m1).enumerate() {
                if b < 0.0 && b < a {
                    let theta = if a > 0.0 { a / (a - b) } else { 0.0 };
                    if theta < 1.0 && block.is_none_or(|(t, _)| theta < t) {
                        block = Some((theta, i));
                    }
                }
            }
            match block {
                None => {
                    let at = self.active.partition_point(|c| c.x < x);
                    self.active.insert(
                        at,
                        Contact {
                            x,
                            side,
                            value: target,
                        },
                    );
                    return;
                }
                Some((theta, i)) => {
                    value += theta * (target - value);
                    self.active.remove(i);
                }
            }
            if self.steps >= MAX_STEPS {
                return;
            }
        }
    }
}

/// The largest excursion of `curve` outside the strip of `q`, and one candidate (where, side,
/// excursion) per run of sub-intervals where it exceeds `tol`.
fn sweep(q: &Problem, curve: &Curve, tol: f64) -> (f64, Vec<(f64, Side, f64)>) {
    // per side, the excursions in order of the sub-intervals; runs are merged across sides by
    // position (a run on the lower bound and one on the upper bound are separate candidates)
    let mut worst = f64::NEG_INFINITY;
    let mut out = Vec::new();
    for side in [Side::Lower, Side::Upper] {
        let b = if side == Side::Lower {
            &q.lower
        } else {
            &q.upper
        };
        let mut run: Option<(f64, f64)> = None;
        excursions(
            b,
            &q.t,
            side,
            &curve.breaks,
            &curve.coeffs,
            &mut |_, _, by, at| {
                if by > worst || by.is_nan() {
                    worst = by;
                }
                if by > tol || by.is_nan() {
                    if run.is_none_or(|(w, _)| by > w) {
                        run = Some((by, at));
                    }
                } else if let Some((w, at)) = run.take() {
                    out.push((at, side, w));
                }
            },
        );
        if let Some((w, at)) = run {
            out.push((at, side, w));
        }
    }
    out.sort_by(|a, b| b.2.total_cmp(&a.2));
    (worst, out)
}

/// The first-order gap estimate of a spline with its active points and excursion.
fn gap_of(s: &Spline, active: &[Contact], violation: f64) -> f64 {
    let mut a = 0;
    let mut jumps = 0.0;
    for (k, &u) in s.x.iter().enumerate() {
        if a < active.len() && active[a].x.to_bits() == u.to_bits() {
            jumps += s.jump(k).0.abs();
            a += 1;
        }
    }
    let e = s.energy();
    if e > 0.0 {
        2.0 * jumps * violation.max(0.0) / e
    } else {
        0.0
    }
}

/// Solves the strip problem `q` (normalized, data strictly inside) to the excursion tolerance
/// `tol` (`vscale` the value scale), tightened while the gap estimate exceeds [`GAP_TARGET`].
pub(crate) fn exchange(q: &Problem, tol: f64, vscale: f64) -> Exchanged {
    let mut tol = tol;
    let t = &q.t;
    let n = t.len();
    let range = t[n - 1] - t[0];
    let mut st = State {
        q,
        active: Vec::new(),
        steps: 0,
        solves: 0,
    };
    let mut sweeps = 0;
    let mut violation;
    let mut converged = false;
    loop {
        let (spline, _) = spline_through(q, &st.active, None);
        st.solves += 1;
        let (worst, candidates) = sweep(q, &spline.to_curve(), tol);
        sweeps += 1;
        violation = worst.max(0.0);
        if candidates.is_empty() {
            converged = !worst.is_nan();
            let (s, _) = spline_through(q, &st.active, None);
            if converged
                && gap_of(&s, &st.active, violation) > GAP_TARGET
                && tol > TOL_FLOOR * vscale
            {
                tol = (tol * 1e-2).max(TOL_FLOOR * vscale);
                continue;
            }
            break;
        }
        if sweeps >= MAX_SWEEPS || st.steps >= MAX_STEPS {
            break;
        }
        let mut added = false;
        for (x, side, _) in candidates {
            // not on a data site or an active point (there the excursion is rounding)
            let near = |u: f64| (u - x).abs() <= 1e-12 * range;
            let k = t.partition_point(|v| *v < x);
            if (k < n && near(t[k])) || (k > 0 && near(t[k - 1])) {
                continue;
            }
            let a = st.active.partition_point(|c| c.x < x);
            if (a < st.active.len() && near(st.active[a].x)) || (a > 0 && near(st.active[a - 1].x))
            {
                continue;
            }
            let (s, _) = spline_through(q, &st.active, None);
            st.solves += 1;
            let f = value_at(&s, x);
            let by = match side {
                Side::Lower => bound_at(q, side, x) - f,
                Side::Upper => f - bound_at(q, side, x),
            };
            if by > tol {
                st.add(x, side);
                added = true;
            }
        }
        if !added {
            // every candidate sits on a knot, or no longer leaves the strip by more than the
            // tolerance when its turn comes: the excursions are rounding
            converged = violation <= 1e2 * tol;
            break;
        }
    }
    let (spline, _) = spline_through(q, &st.active, None);
    Exchanged {
        gap: gap_of(&spline, &st.active, violation),
        spline,
        active: st.active,
        violation,
        converged,
        sweeps,
        steps: st.steps,
        solves: st.solves + 1,
    }
}
