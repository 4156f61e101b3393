//! Small dense vector helpers of the method (one home in this crate; see `banded::vector` for
//! the workspace's).

/// Σ a_i b_i over the shorter of the two.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The Euclidean norm.
#[inline]
pub(crate) fn norm(v: &[f64]) -> f64 {
    dot(v, v).sqrt()
}

/// The largest absolute entry (0 for an empty slice; NaN entries are skipped by `max`, so
/// callers test finiteness separately where it matters).
#[inline]
pub(crate) fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}
