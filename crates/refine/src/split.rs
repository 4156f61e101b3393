//! The k-level split (3.1).

use divdiff::{Knots, Points};

use crate::Error;

/// Index of the data vertex of q_i after a k-level split: i_k = (k + 1) i (0-based; the seed's
/// 1-based i_k = (k + 1)(i − 1) + 1).
pub fn data_vertex(i: usize, k: usize) -> usize {
    (k + 1) * i
}

/// The k-level split (3.1): every span [q_i, q_{i+1}] (including the closing span of a closed
/// curve) is divided into k + 1 equal sub-spans, in both the points and the knots. Returns the
/// (k + 1)n (closed) or (k + 1)(n − 1) + 1 (open) refined vertices and their knots.
///
/// # Errors
/// [`Error::InvalidParameter`] for k = 0, [`Error::WrongLength`] when `knots` does not have one
/// vertex per point, [`Error::Divdiff`] if a sub-span falls below floating-point resolution.
pub fn split(points: &Points, knots: &Knots, k: usize) -> Result<(Points, Knots), Error> {
    if k == 0 {
        return Err(Error::InvalidParameter {
            field: "k",
            value: 0.0,
            reason: "at least one intermediate point per span (k >= 1)",
        });
    }
    let n = points.len();
    if knots.vertex_count() != n {
        return Err(Error::WrongLength {
            field: "knots",
            expected: n + usize::from(knots.is_closed()),
            got: knots.values().len(),
        });
    }
    let d = points.dim();
    let m = k + 1;
    let spans = knots.span_count();
    let total = m * spans + usize::from(!knots.is_closed());
    let u = knots.values();
    let mut coords = Vec::with_capacity(total * d);
    let mut t = Vec::with_capacity(m * spans + 1);
    for i in 0..spans {
        let (a, b) = (points.point(i), points.point((i + 1) % n));
        for j in 0..m {
            let s = j as f64 / m as f64;
            coords.extend(a.iter().zip(b).map(|(x, y)| (1.0 - s) * x + s * y));
            t.push((1.0 - s) * u[i] + s * u[i + 1]);
        }
    }
    t.push(u[spans]);
    if !knots.is_closed() {
        coords.extend_from_slice(points.point(n - 1));
    }
    // Every sub-span is 1/(k+1) of a positive span, so the knots stay increasing unless the
    // span is below the floating-point resolution of its endpoints; the constructors check.
    Ok((Points::new(d, coords)?, Knots::new(knots.topology(), t)?))
}
