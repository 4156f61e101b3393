/// Errors of the `divdiff` crate. Every variant names the offending field and index.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A value is NaN or infinite.
    #[error("{field}[{index}] is not finite")]
    NonFinite {
        /// The field (e.g. `"knots"`, `"points"`).
        field: &'static str,
        /// The index of the offending entry.
        index: usize,
    },
    /// Knots must be strictly increasing: `knots[index] <= knots[index - 1]`.
    #[error("knots[{index}] is not greater than knots[{}]", index - 1)]
    NonIncreasingKnots {
        /// The index of the first knot that fails to increase.
        index: usize,
    },
    /// Too few entries for the requested object.
    #[error("{field} needs at least {needed} entries, got {got}")]
    TooFew {
        /// The field.
        field: &'static str,
        /// The minimum number of entries.
        needed: usize,
        /// What was given.
        got: usize,
    },
    /// A point has the wrong number of coordinates.
    #[error("points[{index}] has {got} coordinates, expected {expected}")]
    DimensionMismatch {
        /// The index of the offending point.
        index: usize,
        /// The dimension of the first point.
        expected: usize,
        /// The dimension of this point.
        got: usize,
    },
    /// Two consecutive points coincide, so the span between them has zero length.
    #[error("points[{index}] and points[{next}] coincide (zero-length span)")]
    ZeroLengthSpan {
        /// The index of the first point of the span.
        index: usize,
        /// The index of the second point (wraps to 0 for the closing span).
        next: usize,
    },
    /// Two objects that must have the same length do not.
    #[error("{field} has length {got}, expected {expected}")]
    LengthMismatch {
        /// The field.
        field: &'static str,
        /// The expected length.
        expected: usize,
        /// The given length.
        got: usize,
    },
    /// A parameter is out of its valid range.
    #[error("{field} = {value} is out of range: {reason}")]
    OutOfRange {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// An index is out of range (e.g. a vertex index ≥ N).
    #[error("{field} index {index} is out of range (size {len})")]
    IndexOutOfRange {
        /// The field (e.g. `"vertex"`).
        field: &'static str,
        /// The index given.
        index: usize,
        /// The valid size.
        len: usize,
    },
    /// The divided difference \[t_index, …, t_{index+order}\] f of an open curve needs knots that
    /// do not exist (index < 0 or index + order ≥ N).
    #[error("divided difference of order {order} at index {index} needs knots outside 0..{len}")]
    DifferenceOutOfRange {
        /// The first knot index.
        index: isize,
        /// The order of the difference.
        order: usize,
        /// The number of knots.
        len: usize,
    },
}
