//! Worked examples in the spirit of the seed's §5. The paper does not print its data: these are
//! invented to show the same phenomena (Example 5.1's data and strip were tuned until the
//! solution had the contact structure of its Figure 2), used by the figures, the verification
//! cases, the benchmarks and the tests.

use strip::{Bound, Problem};

/// The 16 data values of [`example_5_1`].
pub const Y16: [f64; 16] = [
    0.0, 2.0, 1.0, 3.0, 2.0, 2.5, 1.0, 2.0, 1.5, 2.5, 3.0, 0.5, 0.5, 3.0, 1.5, 2.0,
];

/// Data at t = 0, 1, …, n − 1 in a strip of half-width `w` about the data polygon (bounds
/// linear in every interval, continuous).
pub fn polygon_strip(y: &[f64], w: f64) -> Problem {
    let t: Vec<f64> = (0..y.len()).map(|i| i as f64).collect();
    polygon_band(&t, y, w)
}

/// Data (`t`, `y`) in a strip of half-width `w` about the data polygon: one linear piece per
/// interval on each side, y_i ∓ w with the polygon's slope.
pub fn polygon_band(t: &[f64], y: &[f64], w: f64) -> Problem {
    let slope = |i: usize| (y[i + 1] - y[i]) / (t[i + 1] - t[i]);
    let side = |off: f64| {
        Bound::Pieces(
            (0..y.len().saturating_sub(1))
                .map(|i| [y[i] + off, slope(i), 0.0, 0.0])
                .collect(),
        )
    };
    Problem {
        t: t.to_vec(),
        y: y.to_vec(),
        lower: side(-w),
        upper: side(w),
        end_slopes: [None, None],
    }
}

/// Example 5.1-like: 16 points, continuous piecewise-linear bounds; the unconstrained spline
/// leaves the strip, the solution has touching points, subarcs and touching pairs. The strip is
/// ±0.2 about the data polygon, narrowed to ±0.1 in the 14th interval (which makes a touching
/// pair there, as in the paper).
pub fn example_5_1() -> Problem {
    let mut p = polygon_strip(&Y16, 0.2);
    if let (Bound::Pieces(lo), Bound::Pieces(up)) = (&mut p.lower, &mut p.upper) {
        for (i, w) in [(12, 0.1), (13, 0.1), (14, 0.1)] {
            let (a, b) = (Y16[i], Y16[i + 1]);
            // keep the bounds continuous: interpolate the half-width across intervals 12..14
            let (w0, w1) = if i == 12 {
                (0.2, w)
            } else if i == 14 {
                (w, 0.2)
            } else {
                (w, w)
            };
            lo[i] = [a - w0, (b - w1) - (a - w0), 0.0, 0.0];
            up[i] = [a + w0, (b + w1) - (a + w0), 0.0, 0.0];
        }
    }
    p
}

/// Example 5.2-like: bounds that jump at data sites, a cubic lower bound in the fourth interval,
/// end slopes −2 and −2 on \[0, 16\].
pub fn example_5_2() -> Problem {
    let t: Vec<f64> = (0..9).map(|i| 2.0 * i as f64).collect();
    let y = vec![1.0, 1.6, 0.8, 1.4, 1.0, 1.5, 0.7, 1.2, 0.9];
    let n = t.len();
    let mut lo: Vec<[f64; 4]> = (0..n - 1)
        .map(|i| [0.65 - 0.05 * (i % 2) as f64, 0.0, 0.0, 0.0])
        .collect();
    lo[3] = [1.35, -0.05, 0.0, -0.05];
    let up = (0..n - 1)
        .map(|i| [1.72 - 0.1 * (i % 3) as f64, 0.0, 0.0, 0.0])
        .collect();
    Problem {
        t,
        y,
        lower: Bound::Pieces(lo),
        upper: Bound::Pieces(up),
        end_slopes: [Some(-2.0), Some(-2.0)],
    }
}

/// Example 5.3-like (Remark 4.2): two data points f(0) = 0 (on the upper bound) and
/// f(25) = −1, end slopes −2 and 2, and a winding polyline channel of width 1.2 with 15 vertices
/// that forces many extra knots.
pub fn example_5_3() -> Problem {
    let m = 14;
    let centre = |t: f64| -0.6 + 2.5 * (2.0 * std::f64::consts::PI * t / 12.5).sin();
    let vert: Vec<f64> = (0..=m).map(|k| 25.0 * k as f64 / m as f64).collect();
    Problem {
        t: vec![0.0, 25.0],
        y: vec![0.0, -1.0],
        lower: Bound::Polyline(vert.iter().map(|&t| [t, centre(t) - 0.6]).collect()),
        upper: Bound::Polyline(vert.iter().map(|&t| [t, centre(t) + 0.6]).collect()),
        end_slopes: [Some(-2.0), Some(2.0)],
    }
}

/// A large problem for benchmarks: n points of a deterministic oscillating sequence in a strip
/// of half-width 0.1 about the data polygon (most intervals end up with active constraints).
pub fn large(n: usize) -> Problem {
    let y: Vec<f64> = (0..n)
        .map(|i| {
            let x = i as f64;
            (0.7 * x).sin() + 0.5 * (2.3 * x).sin() + 0.25 * (5.1 * x).cos()
        })
        .collect();
    polygon_strip(&y, 0.1)
}
