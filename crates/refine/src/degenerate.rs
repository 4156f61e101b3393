//! Degenerate input handled deliberately: constraint sets with a common point.
//!
//! If every data constraint set contains one point x (balls that overlap in a common region,
//! half-space sets with a common point), the constant curve p ≡ x is feasible with E = 0, the
//! smallest possible energy — so it is an optimum (not the unique one: any feasible curve with
//! zero second differences is). The solvers would meet a singular or ill-conditioned system
//! there (all multipliers vanish and ker H is not pinned down), so the constant curve is
//! returned directly. Each kind gives its sets as projections
//! ([`crate::constraint::Kind::common_point`]); a kind without sets (interpolation, smoothing,
//! derivative constraints) rules the shortcut out. The point is found by alternating projections
//! ([`crate::options::CommonPointOptions`]).
//!
//! With derivative constraints the shortcut is not taken, but the solver may still find the
//! constant curve (the sets have a common point and every derivative set admits Df = 0); the
//! knot updates of Algorithm 4.1 then stop at it ([`is_constant`]), since it is optimal on any
//! knots and has no spans to parametrize.

use divdiff::Points;

use crate::constraint::{dist, CommonPoint};
use crate::problem::Problem;

/// A point common to every set, with the (zero) multipliers of the constant curve.
pub(crate) struct Common {
    pub point: Vec<f64>,
    pub multipliers: Vec<Vec<f64>>,
}

/// A point common to all data constraint sets, if every kind of the problem is a set and such a
/// point is found; `None` otherwise.
pub(crate) fn common_point(problem: &Problem) -> Option<Common> {
    let kinds = problem.kinds();
    let q = &problem.points;
    if kinds.len() != 1 {
        // Derivative constraints: a constant curve has Df = 0, which they need not admit.
        return None;
    }
    let CommonPoint::Sets(sets) = kinds[0].common_point(q) else {
        return None;
    };
    if !sets.possible() {
        return None;
    }
    let opts = &problem.options.common_point;
    let n = q.len();
    let d = q.dim();
    let mut centroid = vec![0.0; d];
    for x in q.iter() {
        for (c, v) in centroid.iter_mut().zip(x) {
            *c += v / n as f64;
        }
    }
    let extent = q
        .iter()
        .map(|x| dist(x, &centroid))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let tol = opts.tolerance * extent;
    let mut x = centroid;
    let mut last = f64::INFINITY;
    for _ in 0..opts.sweeps {
        sets.sweep(&mut x);
        let v = sets.violation(&x);
        // (A NaN coordinate is no common point, whatever `violation` reads.)
        if v <= tol && x.iter().all(|c| c.is_finite()) {
            return Some(Common {
                point: x,
                multipliers: sets.zero_multipliers(d),
            });
        }
        if v > (1.0 - opts.stagnation) * last {
            return None;
        }
        last = v;
    }
    None
}

/// Whether every vertex of `p` equals the first, coordinate by coordinate: the constant curve.
pub(crate) fn is_constant(p: &Points) -> bool {
    let c = p.coords();
    let first = &c[..p.dim()];
    c.chunks_exact(p.dim()).all(|x| x == first)
}
