//! Approximate vertex derivatives Df(t_i) (Kersey (2.2), (2.3) corrected, §3.6 end rules).

use crate::differences::check_sizes;
use crate::{Error, Knots, Points};

/// How the derivative Df(t_i) at a vertex is approximated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DerivativeRule {
    /// Kersey (2.2): the average of the adjacent slopes, ½(s_{i−1} + s_i). At the ends of an open
    /// curve, the one-sided difference s_0 (resp. s_{N−2}) (Kersey §3.6, "clamped").
    Average,
    /// Bessel: the derivative at t_i of the quadratic through p_{i−1}, p_i, p_{i+1}
    /// (what Kersey (2.3) intends; the printed coefficients give the derivative at t_{i−1}).
    /// At the ends of an open curve, the derivative at t_0 (resp. t_{N−1}) of the quadratic
    /// through the first (resp. last) three points (Kersey §3.6, printed correctly).
    Bessel,
}

/// The derivative Df(t_i) as a linear stencil: `[(v_0, c_0), (v_1, c_1), (v_2, c_2)]` with
/// Df(t_i) = Σ_k c_k p_{v_k}. The coefficients depend only on the knots.
///
/// Interior vertices (and every vertex of a closed curve, indices wrapping), with a = h_{i−1},
/// b = h_i:
/// - [`DerivativeRule::Average`]: (−1/(2a), 1/(2a) − 1/(2b), 1/(2b)) on (i − 1, i, i + 1);
/// - [`DerivativeRule::Bessel`]: (−b/(a(a+b)), (b − a)/(ab), a/(b(a+b))) on (i − 1, i, i + 1),
///   exact for quadratics.
///
/// Ends of an open curve (Kersey §3.6), with a = h_0, b = h_1 at the left end and a = h_{N−3},
/// b = h_{N−2} at the right end:
/// - `Average`: the one-sided difference (−1/h, 1/h) on (0, 1) resp. (N − 2, N − 1), and a zero
///   third coefficient (on the vertex 2 resp. N − 3);
/// - `Bessel`: (−(2a+b)/(a(a+b)), (a+b)/(ab), −a/(b(a+b))) on (0, 1, 2), and
///   (b/(a(a+b)), −(a+b)/(ab), (a+2b)/(b(a+b))) on (N − 3, N − 2, N − 1).
///   An open curve with only two vertices has no quadratic: both rules give the secant there.
///
/// # Errors
/// [`Error::IndexOutOfRange`] if `i >= N`.
///
/// ```
/// use divdiff::{derivative_stencil, DerivativeRule, Knots};
/// // f(t) = t² at t = 0, 1, 3: the Bessel derivative at t = 1 is exactly 2.
/// let knots = Knots::open(vec![0.0, 1.0, 3.0]).unwrap();
/// let f = [0.0, 1.0, 9.0];
/// let s = derivative_stencil(&knots, 1, DerivativeRule::Bessel).unwrap();
/// let df: f64 = s.iter().map(|&(v, c)| c * f[v]).sum();
/// assert!((df - 2.0).abs() < 1e-12);
/// ```
pub fn derivative_stencil(
    knots: &Knots,
    i: usize,
    rule: DerivativeRule,
) -> Result<[(usize, f64); 3], Error> {
    let n = knots.vertex_count();
    if i >= n {
        return Err(Error::IndexOutOfRange {
            field: "vertex",
            index: i,
            len: n,
        });
    }
    let closed = knots.is_closed();
    if closed || (i > 0 && i + 1 < n) {
        let (l, r) = ((i + n - 1) % n, (i + 1) % n);
        let a = knots.h(i as isize - 1);
        let b = knots.h(i as isize);
        return Ok(match rule {
            DerivativeRule::Average => [(l, -0.5 / a), (i, 0.5 / a - 0.5 / b), (r, 0.5 / b)],
            DerivativeRule::Bessel => [
                (l, -b / (a * (a + b))),
                (i, (b - a) / (a * b)),
                (r, a / (b * (a + b))),
            ],
        });
    }
    if n == 2 {
        // Two points: the secant is the derivative of the only interpolating polynomial.
        let h = knots.h(0);
        return Ok([(0, -1.0 / h), (1, 1.0 / h), (1, 0.0)]);
    }
    Ok(if i == 0 {
        let (a, b) = (knots.h(0), knots.h(1));
        match rule {
            DerivativeRule::Average => [(0, -1.0 / a), (1, 1.0 / a), (2, 0.0)],
            DerivativeRule::Bessel => [
                (0, -(2.0 * a + b) / (a * (a + b))),
                (1, (a + b) / (a * b)),
                (2, -a / (b * (a + b))),
            ],
        }
    } else {
        let (a, b) = (knots.h(n as isize - 3), knots.h(n as isize - 2));
        match rule {
            DerivativeRule::Average => [(n - 3, 0.0), (n - 2, -1.0 / b), (n - 1, 1.0 / b)],
            DerivativeRule::Bessel => [
                (n - 3, b / (a * (a + b))),
                (n - 2, -(a + b) / (a * b)),
                (n - 1, (a + 2.0 * b) / (b * (a + b))),
            ],
        }
    })
}

/// The derivative Df(t_i) ∈ R^d at vertex `i` by `rule` (see [`derivative_stencil`]).
///
/// # Errors
/// [`Error::LengthMismatch`] if `points` does not have one point per vertex;
/// [`Error::IndexOutOfRange`] if `i >= N`.
pub fn vertex_derivative(
    knots: &Knots,
    points: &Points,
    i: usize,
    rule: DerivativeRule,
) -> Result<Vec<f64>, Error> {
    check_sizes(knots, points)?;
    let s = derivative_stencil(knots, i, rule)?;
    let mut out = vec![0.0; points.dim()];
    for (v, c) in s {
        for (o, x) in out.iter_mut().zip(points.point(v)) {
            *o += c * x;
        }
    }
    Ok(out)
}

/// The derivatives Df(t_i) at every vertex, one row per vertex (see [`derivative_stencil`]).
///
/// # Errors
/// [`Error::LengthMismatch`] if `points` does not have one point per vertex.
pub fn vertex_derivatives(
    knots: &Knots,
    points: &Points,
    rule: DerivativeRule,
) -> Result<Points, Error> {
    check_sizes(knots, points)?;
    let mut coords = Vec::with_capacity(points.coords().len());
    for i in 0..knots.vertex_count() {
        coords.extend(vertex_derivative(knots, points, i, rule)?);
    }
    Points::new(points.dim(), coords)
}
