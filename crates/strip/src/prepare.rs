//! Feasibility of a problem, decided before any solve (O(M + n)), and Remark 4.2.
//!
//! A strip problem with e < d on every interval and every data value strictly inside its bounds
//! has a solution (the open channel holds a C² function, so Lemma 1.1 applies). It has none when
//! * the strip closes: e(t) ≥ d(t) somewhere — checked exactly on every sub-interval between
//!   consecutive breakpoints of the two bounds (polyline vertices, data sites), where d − e is
//!   one cubic, so a pinch between two breakpoints of cubic pieces is found too;
//! * a data value lies outside its bounds (condition (4));
//! * a data value lies on a bound at a kink that no C¹ curve through it can follow (a lower bound
//!   whose slope jumps up at the site: f' would have to be ≥ e'(t+) and ≤ e'(t−)), or at an end
//!   whose prescribed slope points out of the strip.
//!
//! A data value on a bound otherwise (Remark 4.2) is moved inside by the margin ε of
//! [`crate::Options::boundary_margin`] times the strip width there, and reported in
//! [`crate::Solution::shifted_data`] — for Newton on Φ, whose cells need their ends inside the
//! strip. The exchange needs no margin (a data value on the bound is a knot like any other; the
//! strip next to it is held by points), so polyline problems keep such data exactly.

use crate::error::{bound_field, Error, Infeasibility};
use crate::piece::{cubic3, cubic_min, shift};
use crate::types::{Bound, Options, Problem, Side};

/// The bound of `b` as a cubic in s = x − a on a sub-interval starting at `a` in data interval
/// `i` and polyline segment `k` (`None` without a bound).
fn local(b: &Bound, t: &[f64], i: usize, k: usize, a: f64) -> Option<[f64; 4]> {
    match b {
        Bound::None => None,
        Bound::Pieces(p) => Some(shift(&p[i], a - t[i])),
        Bound::Polyline(v) => {
            let (p, q) = (v[k], v[k + 1]);
            let slope = (q[1] - p[1]) / (q[0] - p[0]);
            Some([p[1] + slope * (a - p[0]), slope, 0.0, 0.0])
        }
    }
}

/// The breakpoints of a bound inside (t_1, t_n).
fn cuts(b: &Bound, t: &[f64]) -> Vec<f64> {
    let n = t.len();
    match b {
        Bound::Polyline(v) => v
            .iter()
            .map(|p| p[0])
            .filter(|x| *x > t[0] && *x < t[n - 1])
            .collect(),
        _ => Vec::new(),
    }
}

/// Segment of polyline `b` holding abscissa `x` from the right (0 for other bounds).
fn segment(b: &Bound, x: f64) -> usize {
    match b {
        Bound::Polyline(v) => v.partition_point(|p| p[0] <= x).clamp(1, v.len() - 1) - 1,
        _ => 0,
    }
}

/// Checks that the strip never closes (see the module docs).
fn strip_open(q: &Problem) -> Result<(), Error> {
    if matches!(q.lower, Bound::None) || matches!(q.upper, Bound::None) {
        return Ok(());
    }
    let t = &q.t;
    let n = t.len();
    // every breakpoint of either bound and every data site, merged
    let (a, b) = (cuts(&q.lower, t), cuts(&q.upper, t));
    let mut xs = Vec::with_capacity(a.len() + b.len() + n);
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        if j >= b.len() || (i < a.len() && a[i] <= b[j]) {
            xs.push(a[i]);
            i += 1;
        } else {
            xs.push(b[j]);
            j += 1;
        }
    }
    let mut all = Vec::with_capacity(xs.len() + n);
    let (mut i, mut j) = (0, 0);
    while i < xs.len() || j < n {
        if j >= n || (i < xs.len() && xs[i] <= t[j]) {
            all.push(xs[i]);
            i += 1;
        } else {
            all.push(t[j]);
            j += 1;
        }
    }
    all.dedup_by(|x, y| x.total_cmp(y).is_eq());
    let (mut i, mut kl, mut ku) = (0, 0, 0);
    for w in all.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        while i + 2 < n && t[i + 1] <= x0 {
            i += 1;
        }
        if let Bound::Polyline(v) = &q.lower {
            while kl + 2 < v.len() && v[kl + 1][0] <= x0 {
                kl += 1;
            }
        }
        if let Bound::Polyline(v) = &q.upper {
            while ku + 2 < v.len() && v[ku + 1][0] <= x0 {
                ku += 1;
            }
        }
        let (Some(lo), Some(up)) = (local(&q.lower, t, i, kl, x0), local(&q.upper, t, i, ku, x0))
        else {
            continue;
        };
        let d: [f64; 4] = std::array::from_fn(|c| up[c] - lo[c]);
        let l = x1 - x0;
        let min = cubic_min(&d, l);
        if min.is_nan() || min <= 0.0 {
            // where: the end or interior point of least width
            let mut at = if d[0] <= cubic3(&d, l).0 { x0 } else { x1 };
            for s in roots::find_roots_quadratic(3.0 * d[3], 2.0 * d[2], d[1]).as_ref() {
                if *s > 0.0 && *s < l && cubic3(&d, *s).0 <= min {
                    at = x0 + s;
                }
            }
            let index = match &q.lower {
                Bound::Polyline(v) => v.partition_point(|p| p[0] <= at).clamp(1, v.len()) - 1,
                _ => i,
            };
            return Err(Error::Infeasible {
                field: bound_field(&q.lower, Side::Lower),
                index,
                reason: Infeasibility::Closed { at },
            });
        }
    }
    Ok(())
}

/// The bound at site i from the left and from the right: (value, slope) on each side that has
/// one.
fn at_site(b: &Bound, t: &[f64], i: usize) -> [Option<(f64, f64)>; 2] {
    let n = t.len();
    match b {
        Bound::None => [None, None],
        Bound::Pieces(p) => {
            let left = (i > 0).then(|| {
                let (v, d, _) = cubic3(&p[i - 1], t[i] - t[i - 1]);
                (v, d)
            });
            let right = (i + 1 < n).then(|| (p[i][0], p[i][1]));
            [left, right]
        }
        Bound::Polyline(v) => {
            let x = t[i];
            let k = segment(b, x);
            let slope = |k: usize| (v[k + 1][1] - v[k][1]) / (v[k + 1][0] - v[k][0]);
            let value = v[k][1] + slope(k) * (x - v[k][0]);
            // at a vertex the slopes on the two sides differ
            let left_slope = if v[k][0].total_cmp(&x).is_eq() && k > 0 {
                slope(k - 1)
            } else {
                slope(k)
            };
            [
                (i > 0).then_some((value, left_slope)),
                (i + 1 < n).then_some((value, slope(k))),
            ]
        }
    }
}

/// Checks that the problem has a solution and, when `shift`, applies Remark 4.2: returns the
/// problem with data values on a bound moved inside, and their indices. `vscale` is the value
/// scale (normalized frame: tolerances relative to it).
pub(crate) fn prepare(
    q: &Problem,
    opts: &Options,
    vscale: f64,
    shift: bool,
) -> Result<(Problem, Vec<usize>), Error> {
    strip_open(q)?;
    // a value within this distance of a bound counts as on it (Remark 4.2); it is exactly on it
    // (for the kink test) within the rounding of the values
    let near = 1e-12 * vscale;
    let n = q.t.len();
    let mut out = q.clone();
    let mut shifted = Vec::new();
    for i in 0..n {
        let y = q.y[i];
        let lower = at_site(&q.lower, &q.t, i);
        let upper = at_site(&q.upper, &q.t, i);
        let lo = lower
            .iter()
            .flatten()
            .fold(f64::NEG_INFINITY, |m, g| m.max(g.0));
        let hi = upper
            .iter()
            .flatten()
            .fold(f64::INFINITY, |m, g| m.min(g.0));
        for (side, by) in [(Side::Lower, lo - y), (Side::Upper, y - hi)] {
            if by > near || by.is_nan() {
                return Err(Error::Infeasible {
                    field: "y",
                    index: i,
                    reason: Infeasibility::OutsideBound { side, by },
                });
            }
        }
        for (side, sides, bound) in [(Side::Lower, lower, lo), (Side::Upper, upper, hi)] {
            let gap = (y - bound).abs();
            if gap > near {
                continue;
            }
            let exact = gap <= 8.0 * f64::EPSILON * (y.abs() + bound.abs() + vscale);
            // exactly on the bound: the slopes allowed on the left (f' ≤ e'(t−) for the lower
            // bound) and on the right (f' ≥ e'(t+)) where the bound passes through y, and a
            // prescribed slope, must be compatible
            let sign = if side == Side::Lower { 1.0 } else { -1.0 };
            let touch = |g: &Option<(f64, f64)>| g.filter(|g| (g.0 - bound).abs() <= near);
            let (left, right) = (touch(&sides[0]), touch(&sides[1]));
            let lo_slope = right.map_or(f64::NEG_INFINITY, |g| sign * g.1);
            let hi_slope = left.map_or(f64::INFINITY, |g| sign * g.1);
            let end = if i == 0 {
                q.end_slopes[0]
            } else if i == n - 1 {
                q.end_slopes[1]
            } else {
                None
            };
            let (field, index) = match end {
                Some(_) => ("end_slopes", usize::from(i != 0)),
                None => ("y", i),
            };
            let kink = match end {
                Some(s) => !(sign * s >= lo_slope && sign * s <= hi_slope),
                None => lo_slope > hi_slope,
            };
            if exact && kink {
                return Err(Error::Infeasible {
                    field,
                    index,
                    reason: Infeasibility::Kink { side },
                });
            }
            // Remark 4.2: ε times the strip width inside (never closer to the bound)
            let width = hi - lo;
            let margin = if width.is_finite() {
                opts.boundary_margin * width
            } else {
                opts.boundary_margin * vscale
            };
            let moved = bound + sign * margin;
            if shift && sign * (moved - y) > 0.0 {
                out.y[i] = moved;
                shifted.push(i);
            }
            break;
        }
    }
    Ok((out, shifted))
}
