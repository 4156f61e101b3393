//! Bookkeeping of the border of a cyclic factorization (shared by the scalar and block kinds).
//!
//! A cyclic band matrix is factored in its natural order with its last t = min(W, n) (block)
//! rows as a dense *border*: rows 0..m (m = n − t) form an ordinary band, and the factor's
//! border rows L[m + r][j], j < m, fill in. Those entries start at the wrap-around couplings
//! (j < W), decay geometrically along j for the matrices met here (diagonally dominant after
//! elimination, or positive definite with a short correlation length) and pick up again at the
//! direct couplings (j ≥ m − W). Entries whose magnitude — in the Cholesky scaling, |L̂| with
//! L̂ = L D^{1/2} — falls below [`BORDER_FLUSH_RTOL`] times the largest one met so far in the
//! same border row are set to zero; once W consecutive rows are zero the head of the border
//! has ended, and since the recurrence of the border is homogeneous between the head and the
//! direct couplings, every later entry up to m − W is exactly zero and is neither computed nor
//! stored. So the border is stored and visited on rows [0, head) ∪ [tail, m) only, head ≤ tail.
//!
//! A flushed entry changes the factored matrix by at most BORDER_FLUSH_RTOL · (largest border
//! entry) · |L̂ column|, some 40 orders of magnitude below the backward error ε|L̂||L̂ᵀ| the
//! factorization already has, even when the diagonal of the matrix spans 30 orders of magnitude
//! (interior-point Newton systems).

/// Relative magnitude below which a border entry of a cyclic factor is flushed to zero (see the
/// module docs).
pub(crate) const BORDER_FLUSH_RTOL: f64 = 1e-60;

/// The stored rows of a border: [0, head) ∪ [tail, m), head ≤ tail ≤ m.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Border {
    pub(crate) head: usize,
    pub(crate) tail: usize,
}

impl Border {
    /// No border (open matrices): every one of the m band rows is plain.
    pub(crate) fn none(m: usize) -> Border {
        Border { head: 0, tail: m }
    }

    /// The slot of the first row of the tail segment (= number of head rows).
    #[inline]
    pub(crate) fn tail_slot(&self) -> usize {
        self.head
    }
}
