//! The errors of `conic`, in the workspace's shared vocabulary.

/// Errors of the `conic` crate. `field` names the input the caller gave (`"b"`, `"cones"`,
/// `"x"`, …); `index` the offending entry.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A value is NaN or infinite.
    #[error("{field}[{index}] is not finite")]
    NonFinite {
        /// The input.
        field: &'static str,
        /// The offending entry.
        index: usize,
    },
    /// An input has the wrong number of entries.
    #[error("{field} has length {got}, expected {expected}")]
    WrongLength {
        /// The input.
        field: &'static str,
        /// The expected length.
        expected: usize,
        /// The given length.
        got: usize,
    },
    /// An entry is out of its valid range (an empty cone, a second-order cone of dimension 1,
    /// a start point outside its cone, …).
    #[error("{field}[{index}] is invalid: {reason}")]
    InvalidValue {
        /// The input.
        field: &'static str,
        /// The offending entry.
        index: usize,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// The Newton matrix P + AᵀΘA did not factor (a non-positive pivot at `index`, in the
    /// backend's numbering), even with the regularizations of [`crate::Options`].
    #[error("singular Newton system: non-positive pivot at {index}")]
    Singular {
        /// The pivot (variable or block) at which the factorization failed.
        index: usize,
    },
    /// The method did not reach its tolerance; `residual` is the best relative KKT residual
    /// ([`crate::Residuals::total`]) it reached.
    #[error("{solver} did not converge in {iterations} iterations (best residual {residual:e})")]
    NotConverged {
        /// The solver.
        solver: &'static str,
        /// Iterations taken.
        iterations: usize,
        /// The best residual reached.
        residual: f64,
    },
    /// The requested combination is not supported (e.g. the Clarabel backend on a problem that
    /// cannot export its matrices).
    #[error("{field}: {reason}")]
    Unsupported {
        /// The input or option.
        field: &'static str,
        /// What is not supported.
        reason: &'static str,
    },
}
