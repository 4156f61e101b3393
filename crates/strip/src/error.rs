//! The typed errors of `strip`.

use crate::types::Side;

/// Everything that can go wrong when setting up or solving a strip problem.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Fewer than two data points.
    #[error("at least two data points are needed, got {len}")]
    TooFewPoints {
        /// Number of data points given.
        len: usize,
    },
    /// An array has the wrong length.
    #[error("{field} has length {found}, expected {expected}")]
    LengthMismatch {
        /// The field (`y`, `lower.pieces`, …).
        field: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A NaN or infinite number.
    #[error("{field}[{index}] is not finite")]
    NonFinite {
        /// The field.
        field: &'static str,
        /// Index of the entry.
        index: usize,
    },
    /// A number whose magnitude exceeds [`crate::MAX_MAGNITUDE`] (its squares and products
    /// would overflow double precision).
    #[error("{field}[{index}] exceeds {max:e} in magnitude")]
    TooLarge {
        /// The field.
        field: &'static str,
        /// Index of the entry.
        index: usize,
        /// The limit.
        max: f64,
    },
    /// The computation overflowed (an intermediate or final value is not finite): the data are
    /// too badly scaled for double precision. Rescale t and y.
    #[error("numerical overflow: the data are too badly scaled (rescale t and y)")]
    Overflow,
    /// Newton's method ran out of iterations ([`crate::Options::max_iterations`]) without
    /// converging; `gradient_norm` is the projected gradient norm of the best iterate.
    #[error("not converged in {iterations} iterations (gradient norm {gradient_norm:e})")]
    NotConverged {
        /// Iterations performed.
        iterations: usize,
        /// Projected gradient norm at the last iterate.
        gradient_norm: f64,
    },
    /// The returned pieces leave the strip by more than the documented tolerance
    /// ([`crate::RESULT_FEASIBILITY_TOL`] times the value scale plus the rounding allowance
    /// [`crate::ROUNDING_TOL`] times the magnitude of the values): the answer is refused.
    #[error("the solution leaves the {side} bound by {by:e} in interval {interval} (tolerance {tolerance:e})")]
    StripViolated {
        /// The data interval (0-based).
        interval: usize,
        /// Which bound.
        side: Side,
        /// By how much (caller's units).
        by: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
    },
    /// The returned pieces do not join at `at` to the tolerance of [`Error::StripViolated`]: the
    /// cubic coefficients c·v/λ^k underflow or lose their precision (values tiny against the
    /// site scale). Rescale t and y.
    #[error("the solution's pieces do not join at t = {at} (by {by:e}, tolerance {tolerance:e}): rescale t and y")]
    Discontinuous {
        /// Where (a break).
        at: f64,
        /// By how much (caller's units).
        by: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
    },
    /// Data sites not strictly increasing: t\[index\] ≤ t\[index − 1\] (or, for sites that
    /// are distinct, so close that t − t_1 rounds them to the same number at the scale of the
    /// whole range t_n − t_1).
    #[error("t[{index}] is not greater than t[{}]", index - 1)]
    NonIncreasingSites {
        /// Index of the offending site.
        index: usize,
    },
    /// Polyline abscissae not strictly increasing.
    #[error("{side} polyline vertex {index} does not increase in t")]
    NonIncreasingPolyline {
        /// Which bound.
        side: Side,
        /// Index of the offending vertex.
        index: usize,
    },
    /// A polyline bound does not cover [t_1, t_n].
    #[error("{side} polyline does not cover [t_1, t_n]")]
    PolylineDoesNotCover {
        /// Which bound.
        side: Side,
    },
    /// Data point `index` lies outside its bound (condition (4) fails).
    #[error(
        "y[{index}] lies outside the {side} bound (by {by:e}) at an end of interval {interval}"
    )]
    DataOutsideBounds {
        /// Index of the data point.
        index: usize,
        /// The interval whose bound it violates (0-based).
        interval: usize,
        /// Which bound.
        side: Side,
        /// By how much.
        by: f64,
    },
    /// The strip is empty or has zero width somewhere: e(t) ≥ d(t) at `t` in `interval`.
    #[error("lower bound is not below the upper bound in interval {interval} (at t = {t})")]
    EmptyStrip {
        /// The interval (0-based).
        interval: usize,
        /// Where.
        t: f64,
    },
    /// No enumerated candidate is feasible in an interval: a structure outside Theorem 2.1's list
    /// (possible only for cubic bounds, Remark 3.2).
    #[error("no feasible candidate in interval {interval} (cubic bound with an unsupported contact structure)")]
    NoFeasibleCandidate {
        /// The interval (0-based, of the solver's grid).
        interval: usize,
    },
    /// An option is out of range.
    #[error("option {name} is out of range")]
    BadOption {
        /// The option.
        name: &'static str,
    },
    /// The quasi-Newton solver (argmin) reported an error.
    #[error("BFGS failed: {message}")]
    Bfgs {
        /// argmin's message.
        message: String,
    },
}
