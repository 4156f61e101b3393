//! Degenerate input handled deliberately: constraint sets with a common point.
//!
//! If every data constraint set contains one point x (balls that overlap in a common region,
//! half-space sets with a common point), the constant curve p ≡ x is feasible with E = 0, the
//! smallest possible energy — so it is an optimum (not the unique one: any feasible curve with
//! zero second differences is). The solvers would meet a singular or ill-conditioned system
//! there (all multipliers vanish and ker H is not pinned down), so the constant curve is
//! returned directly.

use crate::problem::{Constraint, Problem};

/// Sweeps of alternating projections onto the constraint sets before giving up on finding a
/// common point (a cheap necessary test runs first, so this only runs when it can succeed).
pub const COMMON_POINT_SWEEPS: usize = 2000;
/// A point counts as common when it violates no set by more than this times the data extent.
pub const COMMON_POINT_TOL: f64 = 1e-13;
/// The projections stop (no common point) when a sweep reduces the largest violation by less
/// than this fraction: they stall on an empty intersection.
pub const COMMON_POINT_STAGNATION: f64 = 1e-4;

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// A point common to all data constraint sets, if the problem has no derivative constraints
/// and such a point is found; `None` otherwise.
pub(crate) fn common_point(problem: &Problem) -> Option<Vec<f64>> {
    if problem.has_derivative_constraints() {
        return None;
    }
    let q = &problem.points;
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
    let tol = COMMON_POINT_TOL * extent;
    match &problem.constraint {
        Constraint::Balls(r) => {
            // Necessary: consecutive balls intersect (cheap; rejects almost all real data).
            if (0..n).any(|i| dist(q.point(i), q.point((i + 1) % n)) > r[i] + r[(i + 1) % n]) {
                return None;
            }
            let violation = |x: &[f64]| {
                (0..n)
                    .map(|i| dist(x, q.point(i)) - r[i])
                    .fold(0.0, f64::max)
            };
            let mut x = centroid;
            let mut last = f64::INFINITY;
            for _ in 0..COMMON_POINT_SWEEPS {
                for (i, &ri) in r.iter().enumerate() {
                    let c = q.point(i);
                    let g = dist(&x, c);
                    if g > ri {
                        let s = ri / g;
                        for (xj, cj) in x.iter_mut().zip(c) {
                            *xj = cj + s * (*xj - cj);
                        }
                    }
                }
                let v = violation(&x);
                // (A NaN coordinate is no common point, whatever `violation` reads.)
                if v <= tol && x.iter().all(|c| c.is_finite()) {
                    return Some(x);
                }
                if v > (1.0 - COMMON_POINT_STAGNATION) * last {
                    return None;
                }
                last = v;
            }
            None
        }
        Constraint::HalfSpaces(sets) => {
            let project = |x: &mut Vec<f64>| {
                for set in sets {
                    for h in set {
                        let nn: f64 = h.normal.iter().map(|a| a * a).sum();
                        let g: f64 = h
                            .normal
                            .iter()
                            .zip(x.iter())
                            .map(|(a, b)| a * b)
                            .sum::<f64>()
                            - h.offset;
                        if g > 0.0 {
                            for (xj, nj) in x.iter_mut().zip(&h.normal) {
                                *xj -= g / nn * nj;
                            }
                        }
                    }
                }
            };
            let violation = |x: &[f64]| {
                sets.iter()
                    .flatten()
                    .map(|h| {
                        let nn = h.normal.iter().map(|a| a * a).sum::<f64>().sqrt();
                        (h.normal.iter().zip(x).map(|(a, b)| a * b).sum::<f64>() - h.offset) / nn
                    })
                    .fold(0.0, f64::max)
            };
            let mut x = centroid;
            let mut last = f64::INFINITY;
            for _ in 0..COMMON_POINT_SWEEPS {
                project(&mut x);
                let v = violation(&x);
                // (A NaN coordinate is no common point, whatever `violation` reads.)
                if v <= tol && x.iter().all(|c| c.is_finite()) {
                    return Some(x);
                }
                if v > (1.0 - COMMON_POINT_STAGNATION) * last {
                    return None;
                }
                last = v;
            }
            None
        }
        Constraint::Interpolate | Constraint::Smoothing(_) => None,
    }
}

/// Zero multipliers in the shape [`crate::Refinement::multipliers`] documents.
pub(crate) fn zero_multipliers(problem: &Problem) -> Vec<Vec<f64>> {
    let d = problem.points.dim();
    let n = problem.points.len();
    match &problem.constraint {
        Constraint::Interpolate => vec![vec![0.0; d]; n],
        Constraint::Balls(r) => r
            .iter()
            .map(|&e| if e == 0.0 { vec![0.0; d] } else { vec![0.0] })
            .collect(),
        Constraint::Smoothing(w) => w.iter().map(|&x| vec![x]).collect(),
        Constraint::HalfSpaces(sets) => sets.iter().map(|s| vec![0.0; s.len()]).collect(),
    }
}
