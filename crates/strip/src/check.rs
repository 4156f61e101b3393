//! Exact strip checks of a piecewise cubic: on every sub-interval between consecutive breaks of
//! the cubic and breakpoints of the bound (polyline vertices; the data sites for cubic pieces),
//! f − e (or d − f) is one cubic, whose minimum is taken at an end or at a real root of its
//! derivative. Breaks and bound breakpoints are merged in one pass: O(pieces + M).
//!
//! Used twice: by the sweeps of the exchange ([`crate::exchange`]) to find where the current
//! spline leaves the strip (normalized frame), and by [`crate::solve()`] on the returned pieces in
//! the caller's frame (a violation beyond the documented tolerance is refused).

use crate::piece::{cubic_argmin, shift};
use crate::types::{Bound, Problem, Side, Solution};

/// Calls `visit(segment, a, excursion, at, start)` for every sub-interval \[a, b\] of the
/// piecewise cubic (`breaks`, `coeffs`) and the bound `b` of `side`, where `excursion` is the
/// largest amount by which f leaves the bound there (NaN propagates), `at` where, `start` the
/// amount at a (negative inside), and `segment` the polyline segment (or the data interval, for
/// cubic pieces) holding \[a, b\]. Where f is clearly inside (its distance to the bound at the
/// ends exceeds its largest possible bend, |d''|·(b − a)²/8), a negative upper bound of the
/// excursion is reported instead of the exact value, which spares the roots on most
/// sub-intervals.
pub(crate) fn excursions(
    b: &Bound,
    t: &[f64],
    side: Side,
    breaks: &[f64],
    coeffs: &[[f64; 4]],
    visit: &mut dyn FnMut(usize, f64, f64, f64, f64),
) {
    let cuts: &[[f64; 2]] = match b {
        Bound::None => return,
        Bound::Polyline(v) => v,
        Bound::Pieces(_) => &[],
    };
    let n = t.len();
    let count = match b {
        Bound::Polyline(v) => v.len(),
        _ => n,
    };
    let at = |k: usize| match b {
        Bound::Polyline(_) => cuts[k][0],
        _ => t[k],
    };
    // the bound's breakpoint index (polyline vertex or data site) at or before the current a,
    // found by bisection so that a stretch of the curve costs its own length only
    let Some(&first) = breaks.first() else {
        return;
    };
    let (mut lo, mut hi) = (0, count);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if at(mid) <= first {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut k = lo;
    for j in 0..coeffs.len() {
        let (x0, x1) = (breaks[j], breaks[j + 1]);
        if x1 <= x0 {
            continue;
        }
        let mut a = x0;
        loop {
            // the segment holding [a, b): last breakpoint ≤ a (clamped to a valid segment)
            while k + 1 < count && at(k + 1) <= a {
                k += 1;
            }
            let seg = k.min(count - 2);
            let next = at(seg + 1);
            let end = if next > a && next < x1 { next } else { x1 };
            let g = match b {
                Bound::Polyline(v) => {
                    let (p, q) = (v[seg], v[seg + 1]);
                    let slope = (q[1] - p[1]) / (q[0] - p[0]);
                    [p[1] + slope * (a - p[0]), slope, 0.0, 0.0]
                }
                Bound::Pieces(pc) => shift(&pc[seg], a - t[seg]),
                Bound::None => unreachable!("returned above"),
            };
            let f = shift(&coeffs[j], a - x0);
            let d: [f64; 4] = std::array::from_fn(|i| match side {
                Side::Lower => f[i] - g[i],
                Side::Upper => g[i] - f[i],
            });
            let l = end - a;
            // clearly inside: min(d(0), d(l)) less the largest bend of d over [0, l] (|d''| l²/8)
            // is positive; that bound (negated) is reported instead of the exact excursion
            let dl = d[0] + l * (d[1] + l * (d[2] + l * d[3]));
            let bend = (2.0 * d[2].abs() + 6.0 * d[3].abs() * l) * l * l / 8.0;
            let lower = d[0].min(dl) - bend;
            if lower > 0.0 {
                visit(seg, a, -lower, a, -d[0]);
            } else {
                let (min, u) = cubic_argmin(&d, l);
                visit(seg, a, -min, a + u, -d[0]);
            }
            if end >= x1 {
                break;
            }
            a = end;
        }
    }
}

/// The largest violation of the strip by the pieces of `s`, with its data interval and side;
/// `None` without bounds.
pub(crate) fn worst_violation(p: &Problem, s: &Solution) -> Option<(f64, usize, Side)> {
    let mut worst: Option<(f64, f64, Side)> = None;
    for (side, b) in [(Side::Lower, &p.lower), (Side::Upper, &p.upper)] {
        excursions(
            b,
            &p.t,
            side,
            &s.breaks,
            &s.coefficients,
            &mut |_, a, by, _, _| {
                if worst.is_none_or(|(m, _, _)| by > m || by.is_nan()) {
                    worst = Some((by, a, side));
                }
            },
        );
    }
    let n = p.t.len();
    worst.map(|(by, a, side)| {
        (
            by,
            p.t.partition_point(|x| *x <= a).clamp(1, n - 1) - 1,
            side,
        )
    })
}
