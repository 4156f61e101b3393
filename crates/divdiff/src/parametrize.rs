//! Knots from points: the parametrizations of Kersey's Algorithm 4.1, step (iv).

use crate::{Error, Knots, Points, Topology};

/// A parametrization u_{i+1} = u_i + |q_{i+1} − q_i|^e (Kersey, Algorithm 4.1 step (iv)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Parametrization {
    /// e = 0: unit spans.
    Uniform,
    /// e = ½ (the paper's choice).
    Centripetal,
    /// e = 1: spans as long as the chords.
    Chordal,
    /// Any exponent e, finite and ≥ 0.
    Exponent(f64),
}

impl Parametrization {
    /// The exponent e.
    pub fn exponent(self) -> f64 {
        match self {
            Parametrization::Uniform => 0.0,
            Parametrization::Centripetal => 0.5,
            Parametrization::Chordal => 1.0,
            Parametrization::Exponent(e) => e,
        }
    }
}

/// Knots for `points` by Algorithm 4.1 step (iv): u_0 = 0, u_{i+1} = u_i + |q_{i+1} − q_i|^e
/// (Euclidean norm, computed without overflow or underflow of the squares), **not** normalized. A closed curve gets the closing span |q_0 − q_{N−1}|^e as
/// its knot N + 1, so N points give N knots (open) or N + 1 knots (closed).
///
/// # Errors
/// - [`Error::OutOfRange`] (`field: "exponent"`) if e is NaN, infinite or negative;
/// - [`Error::TooFew`] for fewer than 2 points (open) or 3 points (closed);
/// - [`Error::ZeroLengthSpan`] `{ index, next }` if two consecutive points coincide (for a closed
///   curve also the closing pair, `next = 0`) — for every exponent, uniform included, since such
///   a polygon has a degenerate span;
/// - [`Error::NonFinite`] / [`Error::NonIncreasingKnots`] if a span length |q_{i+1} − q_i|^e
///   overflows to infinity or underflows to zero.
///
/// ```
/// use divdiff::{parametrize, Parametrization, Points, Topology};
/// let q = Points::from_rows(&[[0.0, 0.0], [3.0, 4.0], [3.0, 0.0]]).unwrap();
/// let u = parametrize(&q, Topology::Closed, Parametrization::Chordal).unwrap();
/// assert_eq!(u.vertex_count(), 3);
/// let want = [0.0, 5.0, 9.0, 12.0];
/// assert!(u.values().iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
/// ```
pub fn parametrize(
    points: &Points,
    topology: Topology,
    parametrization: Parametrization,
) -> Result<Knots, Error> {
    checked_exponent(parametrization)?;
    let spans = span_count(points, topology)?;
    let mut t = vec![0.0; spans + 1];
    span_powers(points, parametrization, 0, &mut t[1..])?;
    accumulate(&mut t);
    Knots::new(topology, t)
}

/// The number of spans of [`parametrize`]'s polygon: n − 1 open, n closed.
///
/// # Errors
/// [`Error::TooFew`] for fewer than 2 points (open) or 3 points (closed).
pub fn span_count(points: &Points, topology: Topology) -> Result<usize, Error> {
    let n = points.len();
    let needed = match topology {
        Topology::Open => 2,
        Topology::Closed => 3,
    };
    if n < needed {
        return Err(Error::TooFew {
            field: "points",
            needed,
            got: n,
        });
    }
    Ok(match topology {
        Topology::Open => n - 1,
        Topology::Closed => n,
    })
}

/// The increments |q_{j+1} − q_j|^e of [`parametrize`] for the spans `first .. first +
/// out.len()` into `out` (span j runs from point j to point j + 1, the last span of a closed
/// curve from point n − 1 back to point 0): the knots are their running sums from 0. For callers
/// that compute them in pieces (refine's knot updates, over 10⁶ vertices, in parallel chunks);
/// the same values as `parametrize` computes.
///
/// # Errors
/// - [`Error::OutOfRange`] (`field: "exponent"`) if e is NaN, infinite or negative;
/// - [`Error::ZeroLengthSpan`] `{ index, next }` for the first span in the range whose points
///   coincide.
#[inline(always)] // (so a caller's wider vector instructions reach the distances' loop)
pub fn span_powers(
    points: &Points,
    parametrization: Parametrization,
    first: usize,
    out: &mut [f64],
) -> Result<(), Error> {
    let e = checked_exponent(parametrization)?;
    let (n, d) = (points.len(), points.dim());
    // Scaled (Blue's algorithm, `banded::vector`): squares of coordinates at 1e±300 would
    // overflow to ∞ or underflow to 0 where the distance itself is representable. The spans
    // from point i to i + 1 in one pass; a closed curve's closing span (n − 1 to 0) apart.
    let straight = out.len().min((n - 1).saturating_sub(first));
    if straight > 0 {
        let rows = &points.coords()[first * d..(first + straight + 1) * d];
        banded::vector::consecutive_dists(rows, d, &mut out[..straight]);
    }
    if let Some(o) = out.get_mut(straight) {
        *o = banded::vector::dist(points.point(0), points.point(n - 1));
    }
    // (A branch-free scan first: the position is wanted only on failure.)
    if out.iter().fold(false, |b, &x| b | (x <= 0.0)) {
        let i = first + out.iter().position(|&x| x <= 0.0).expect("found above");
        let next = if i + 1 == n { 0 } else { i + 1 };
        return Err(Error::ZeroLengthSpan { index: i, next });
    }
    // The common exponents without a general power (both correctly rounded, so the same values).
    match parametrization {
        Parametrization::Centripetal => out.iter_mut().for_each(|x| *x = x.sqrt()),
        Parametrization::Chordal => {}
        _ => out.iter_mut().for_each(|x| *x = x.powf(e)),
    }
    Ok(())
}

/// The exponent e, finite and non-negative.
fn checked_exponent(parametrization: Parametrization) -> Result<f64, Error> {
    let e = parametrization.exponent();
    if !e.is_finite() || e < 0.0 {
        return Err(Error::OutOfRange {
            field: "exponent",
            value: e,
            reason: "the exponent must be finite and non-negative",
        });
    }
    Ok(e)
}

/// Running sums in place: t_j ← t_{j−1} + t_j from t_0 (the knots of [`parametrize`] from 0 and
/// the [`span_powers`] after it).
pub fn accumulate(t: &mut [f64]) {
    for j in 1..t.len() {
        t[j] += t[j - 1];
    }
}
