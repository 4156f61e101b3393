/// Errors of the `subdivision` crate. Variants name the user's field (`points`, `arity`,
/// `levels`, `rows`, …) and, where there is one, the offending index.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A coordinate is NaN or infinite: in the input, or in a result whose affine combinations
    /// (weights of magnitude above 1) overflowed the `f64` range. `index` is the point.
    #[error("{field}[{index}] is not finite")]
    NonFinite {
        /// The field, `"points"`.
        field: &'static str,
        /// The point (of the input, or of the result for an overflow).
        index: usize,
    },
    /// A field that must have a given number of entries has another.
    #[error("{field} has length {got}, expected {expected}")]
    WrongLength {
        /// The field, e.g. `"points"` of a quad grid (`rows × cols` entries).
        field: &'static str,
        /// The expected length.
        expected: usize,
        /// The given length.
        got: usize,
    },
    /// Too few entries (points of a polygon, rows of a grid) or too small a parameter
    /// (the arity, the interval length L).
    #[error("{field} must be at least {minimum}, got {got}")]
    TooFew {
        /// The field, e.g. `"points"`, `"arity"`, `"rows"`, `"intervals"`.
        field: &'static str,
        /// The smallest valid value.
        minimum: usize,
        /// The value given.
        got: usize,
    },
    /// A parameter, or the result it asks for, exceeds a documented limit (or `usize`).
    /// For `"levels"` and `"level"`, `limit` and `got` count what the limit is stated in
    /// (output coordinates, grid intervals); `got` saturates at `usize::MAX` on overflow.
    #[error("{field}: {got} exceeds the limit of {limit}")]
    TooLarge {
        /// The field, e.g. `"points"`, `"arity"`, `"levels"`.
        field: &'static str,
        /// The limit.
        limit: usize,
        /// The value (or the size of the result) asked for.
        got: usize,
    },
    /// A parameter is not of a valid form (e.g. an odd number of stencil points). `index` is
    /// 0 for a scalar parameter.
    #[error("{field} is invalid: {reason}")]
    InvalidValue {
        /// The field, e.g. `"points"`.
        field: &'static str,
        /// The entry (0 for a scalar parameter).
        index: usize,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// An exact linear system of a rule derivation, or the tridiagonal system of
    /// interpolation, turned out singular at pivot (row) `index`. Does not occur for the
    /// natural cubic scheme; reported rather than panicking.
    #[error("singular system at pivot {index}")]
    Singular {
        /// The pivot (row) at which elimination failed.
        index: usize,
    },
    /// The request is valid but not supported (e.g. OBJ output of points outside R² and R³).
    #[error("{field}: {reason}")]
    Unsupported {
        /// The field, e.g. `"points"`.
        field: &'static str,
        /// What is not supported.
        reason: &'static str,
    },
}

impl Error {
    /// The output of a level as `Points`: the only failure left after the callers' checks is a
    /// non-finite coordinate (an overflow of the affine combinations), reported at its point.
    pub(crate) fn from_output(e: divdiff::Error) -> Self {
        match e {
            divdiff::Error::NonFinite { index, .. } => Error::NonFinite {
                field: "points",
                index,
            },
            // `Points::new` with the input's dimension and a multiple of it coordinates: the
            // other variants cannot occur; report the shape honestly if they ever did.
            _ => Error::Unsupported {
                field: "points",
                reason: "the refined coordinates do not form points of the input's dimension",
            },
        }
    }
}
