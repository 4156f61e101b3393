//! Exact checks of the returned pieces in the caller's frame: the strip (extrema of the cubic
//! minus the bound on every sub-interval between consecutive breaks and bound vertices).

use crate::piece::{cubic_min, shift};
use crate::types::{polyline_at, Bound, Problem, Side, Solution};

/// The largest violation of the strip by the pieces of `s` (exact extrema of the cubic
/// difference on every piece, split at polyline vertices), with its data interval and side;
/// `None` without bounds.
pub(crate) fn worst_violation(p: &Problem, s: &Solution) -> Option<(f64, usize, Side)> {
    let n = p.t.len();
    let mut worst: Option<(f64, usize, Side)> = None;
    for j in 0..s.coefficients.len() {
        let (x0, x1) = (s.breaks[j], s.breaks[j + 1]);
        if x1 <= x0 {
            continue;
        }
        let i = p.t.partition_point(|t| *t <= x0).clamp(1, n - 1) - 1;
        for (side, b) in [(Side::Lower, &p.lower), (Side::Upper, &p.upper)] {
            let mut cuts = vec![x0];
            if let Bound::Polyline(v) = b {
                cuts.extend(v.iter().map(|q| q[0]).filter(|x| *x > x0 && *x < x1));
            }
            cuts.push(x1);
            for w in cuts.windows(2) {
                let g = match b {
                    Bound::None => continue,
                    Bound::Pieces(pc) => shift(&pc[i], w[0] - p.t[i]),
                    Bound::Polyline(v) => {
                        let (ga, gb) = (polyline_at(v, w[0]), polyline_at(v, w[1]));
                        [ga, (gb - ga) / (w[1] - w[0]), 0.0, 0.0]
                    }
                };
                let f = shift(&s.coefficients[j], w[0] - x0);
                let d: [f64; 4] = std::array::from_fn(|k| match side {
                    Side::Lower => f[k] - g[k],
                    Side::Upper => g[k] - f[k],
                });
                let by = -cubic_min(&d, w[1] - w[0]);
                if worst.is_none_or(|(m, _, _)| by > m || by.is_nan()) {
                    worst = Some((by, i, side));
                }
            }
        }
    }
    worst
}
