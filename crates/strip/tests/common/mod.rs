//! Shared test helpers on top of `strip-testkit`: the independent lower bound from Clarabel and
//! the exact strip check.
#![allow(dead_code)]

use strip::{Problem, Solution};

/// The Clarabel lower bound (tight tolerances) on the data sites plus `extra` points; panics
/// unless Clarabel reports `Solved` or `AlmostSolved` (at 1e-12 tolerances these small QPs end
/// `AlmostSolved` now and then; the callers compare at 1e-6).
pub fn qp_lower_bound(problem: &Problem, extra: &[f64]) -> f64 {
    let lb = strip_testkit::lower_bound(problem, extra, true).expect("clarabel setup");
    assert!(
        lb.solved || lb.status == "AlmostSolved",
        "clarabel: {}",
        lb.status
    );
    lb.value
}

/// A grid for the QP (see `strip_testkit::fine_grid`).
pub fn qp_grid(problem: &Problem, per_interval: usize, near: Option<&Solution>) -> Vec<f64> {
    strip_testkit::fine_grid(problem, per_interval, near)
}

/// The largest violation of the strip by `s`, exact on every piece (no sampling; the former
/// `samples` argument is kept for the call sites and ignored).
pub fn max_violation(problem: &Problem, s: &Solution, _samples: usize) -> f64 {
    strip_testkit::strip_violation(problem, s).by
}

pub fn bound_at(b: &strip::Bound, i: usize, ti: f64, x: f64) -> Option<f64> {
    match b {
        strip::Bound::None => None,
        strip::Bound::Pieces(p) => {
            let c = p[i];
            let s = x - ti;
            Some(c[0] + s * (c[1] + s * (c[2] + s * c[3])))
        }
        strip::Bound::Polyline(p) => {
            let k = p.partition_point(|v| v[0] <= x).clamp(1, p.len() - 1);
            let (a, b) = (p[k - 1], p[k]);
            Some(a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]))
        }
    }
}

/// The independent checks of an answer that every strip test asks for: it keeps to the strip
/// (exactly, to 1e-9 of the largest |y| or 1) and interpolates the data it was given, the values
/// Remark 4.2 moved included (to 1e-12 of the same scale).
pub fn assert_keeps_strip_and_data(p: &Problem, s: &Solution) {
    let v = p.y.iter().fold(1.0f64, |m, y| m.max(y.abs()));
    if let Err(e) = strip_testkit::strip_violation(p, s).at_most(1e-9 * v) {
        panic!("{e}");
    }
    let interp = strip_testkit::interpolation_error(&strip_testkit::moved_data(p, s), s);
    assert!(interp <= 1e-12 * v, "interpolation {interp:e}");
}
