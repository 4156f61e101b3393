//! The energy (2.1) and its derivatives with respect to the points and the knots.

use divdiff::{Knots, Points};

use crate::Error;

/// Checks that `points` has one point per vertex of `knots`.
pub(crate) fn check_sizes(knots: &Knots, points: &Points) -> Result<(), Error> {
    if points.len() != knots.vertex_count() {
        return Err(Error::SizeMismatch {
            field: "points",
            expected: knots.vertex_count(),
            got: points.len(),
        });
    }
    Ok(())
}

/// Kersey's energy (2.1), summed directly from the slopes:
///
/// E(f) = Σ_i |s_i − s_{i−1}|² / (h_{i−1} + h_i) = Σ_i |Δ_{i−1,2} f|² h_{i−1,2},
///
/// over every vertex i of a closed curve (indices wrapping) and the interior vertices of an open
/// one (§3.6). Here s_i = (p_{i+1} − p_i)/h_i is the slope of span i. It discretizes ½∫|f''|².
///
/// # Errors
/// [`Error::SizeMismatch`] if `points` does not have one point per vertex.
///
/// ```
/// use divdiff::{Knots, Points};
/// // f(t) = t² at t = 0, 1, 3: slopes 1 and 4, so E = (4 − 1)² / (1 + 2) = 3.
/// let knots = Knots::open(vec![0.0, 1.0, 3.0]).unwrap();
/// let p = Points::from_rows(&[[0.0], [1.0], [9.0]]).unwrap();
/// assert!((energy::energy(&knots, &p).unwrap() - 3.0).abs() < 1e-12);
/// ```
pub fn energy(knots: &Knots, points: &Points) -> Result<f64, Error> {
    check_sizes(knots, points)?;
    let mut e = 0.0;
    for i in crate::hessian::interior_rows(knots) {
        let (hl, hr) = (knots.h(i as isize - 1), knots.h(i as isize));
        let (l, c, r) = neighbours(knots, i);
        let d2: f64 = (0..points.dim())
            .map(|k| {
                let sl = (points.point(c)[k] - points.point(l)[k]) / hl;
                let sr = (points.point(r)[k] - points.point(c)[k]) / hr;
                (sr - sl).powi(2)
            })
            .sum();
        e += d2 / (hl + hr);
    }
    Ok(e)
}

/// The vertices (i − 1, i, i + 1), wrapping for closed curves; `i` must be interior for open ones.
pub(crate) fn neighbours(knots: &Knots, i: usize) -> (usize, usize, usize) {
    let n = knots.vertex_count();
    if knots.is_closed() {
        ((i + n - 1) % n, i, (i + 1) % n)
    } else {
        (i - 1, i, i + 1)
    }
}
