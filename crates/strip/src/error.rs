//! The typed errors of `strip`, in the workspace's shared vocabulary: every variant that concerns
//! the input names the user's field (`t`, `y`, `end_slopes`, `lower.pieces`, `upper.polyline`,
//! `options.boundary_margin`, …) and the index into it.

use crate::types::Side;

/// Why a problem has no solution.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Infeasibility {
    /// The data value lies outside a bound at its site (condition (4) of the seed fails), by
    /// `by` in the caller's units.
    OutsideBound {
        /// Which bound.
        side: Side,
        /// By how much.
        by: f64,
    },
    /// The strip closes: e(t) ≥ d(t) at `at`, so no function fits between the bounds there.
    Closed {
        /// Where.
        at: f64,
    },
    /// The data value lies on a bound at a kink that no C¹ function through it can follow
    /// (a lower bound bending up, or an upper bound bending down, at the site: the slopes
    /// allowed on the left and on the right do not overlap).
    Kink {
        /// Which bound.
        side: Side,
    },
}

impl std::fmt::Display for Infeasibility {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Infeasibility::OutsideBound { side, by } => {
                let dir = if *side == Side::Lower {
                    "below"
                } else {
                    "above"
                };
                write!(f, "the data value lies {by:e} {dir} the {side} bound")
            }
            Infeasibility::Closed { at } => write!(
                f,
                "the strip closes at t = {at}: the lower bound is not below the upper bound"
            ),
            Infeasibility::Kink { side } => write!(
                f,
                "the data value lies on a kink of the {side} bound that no smooth curve can pass"
            ),
        }
    }
}

/// Everything that can go wrong when setting up or solving a strip problem.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Too few entries: fewer than two data points, or a polyline with fewer than two vertices.
    #[error("{field} needs at least {minimum} entries, got {got}")]
    TooFew {
        /// The field (`t`, `lower.polyline`, …).
        field: &'static str,
        /// The minimum.
        minimum: usize,
        /// What was given.
        got: usize,
    },
    /// An array has the wrong length.
    #[error("{field} has length {got}, expected {expected}")]
    WrongLength {
        /// The field (`y`, `lower.pieces`, …).
        field: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
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
    #[error("{field}[{index}] = {got:e} exceeds {limit:e} in magnitude")]
    TooLarge {
        /// The field.
        field: &'static str,
        /// Index of the entry.
        index: usize,
        /// The limit.
        limit: f64,
        /// The value.
        got: f64,
    },
    /// Abscissae not strictly increasing: `field[index]` ≤ `field[index − 1]` (for data sites
    /// that are distinct, also: so close that t − t_1 rounds them to the same number at the
    /// scale of the whole range t_n − t_1).
    #[error("{field}[{index}] is not greater than {field}[{}]", index - 1)]
    NonIncreasing {
        /// The field (`t`, `lower.polyline`, …).
        field: &'static str,
        /// Index of the offending entry.
        index: usize,
    },
    /// A value outside its domain: an option out of range, a polyline that does not cover
    /// \[t_1, t_n\], or numbers too badly scaled for double precision (index 0 for scalars).
    #[error("{field}[{index}]: {reason}")]
    InvalidValue {
        /// The field.
        field: &'static str,
        /// Index of the entry.
        index: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// The problem has no solution: `field[index]` is where it fails.
    #[error("{field}[{index}]: {reason}")]
    Infeasible {
        /// The field (`y` for a data point, the lower bound's field for a closed strip).
        field: &'static str,
        /// Index of the data point, or of the bound's piece or vertex.
        index: usize,
        /// Why.
        reason: Infeasibility,
    },
    /// A cubic bound whose solution needs a contact structure outside Theorem 2.1's list (more
    /// than two contacts in one interval, Remark 3.2): no enumerated candidate is feasible.
    #[error("{field}[{index}]: {reason}")]
    Unsupported {
        /// The bound's field.
        field: &'static str,
        /// The data interval.
        index: usize,
        /// What is not supported.
        reason: &'static str,
    },
    /// An iterative method stopped without the accuracy asked for. `residual` is the best
    /// iterate's relative optimality gap estimate (Newton on Φ, BFGS), or for the dual
    /// active-set exchange the excursion outside the strip it left, relative to the value
    /// scale (it stopped with no candidate it could add: the excursion lies within 1e-12 of the
    /// range from a knot, or its sweep or step limit).
    #[error("{solver} did not converge in {iterations} iterations (residual {residual:e})")]
    NotConverged {
        /// Which method.
        solver: &'static str,
        /// Iterations performed.
        iterations: usize,
        /// The residual reached.
        residual: f64,
    },
    /// The method converged (the curve leaves the strip by no more than its tolerance), but its
    /// first-order optimality gap stays above what an answer must meet (1e-9, `required`):
    /// the contacts' f''' jumps are so large, against the energy, that the rounding of the
    /// excursion alone is worth more than 1e-9 of it. Hair-thin strips and data whose slopes
    /// are steep against the strip's width end here; the answer is refused, with its gap.
    #[error("{solver} converged after {iterations} sweeps, but its optimality gap {gap:e} stays above the {required:e} an answer must meet")]
    Uncertified {
        /// Which method.
        solver: &'static str,
        /// Sweeps performed.
        iterations: usize,
        /// The relative optimality gap estimate of the converged curve.
        gap: f64,
        /// The largest gap an answer is returned with.
        required: f64,
    },
    /// The returned pieces leave the strip by more than the documented tolerance
    /// ([`crate::RESULT_FEASIBILITY_TOL`] times the value scale plus the rounding allowance
    /// [`crate::ROUNDING_TOL`] times the magnitude of the values): the answer is refused. When
    /// the excess is within [`SITES_ROUNDING_COUNTS`] times `sites_rounding`, the rounding of the
    /// sites themselves is the cause (a strip narrower than slope × ulp(t), sites far from 0
    /// against their spacing), and the message says so.
    #[error("the solution leaves the {side} bound by {by:e} in interval {interval} (tolerance {tolerance:e}){}", sites_rounding_hint(*by, *sites_rounding))]
    StripViolated {
        /// The data interval (0-based).
        interval: usize,
        /// Which bound.
        side: Side,
        /// By how much (caller's units).
        by: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
        /// How far the values there move when the abscissae move by one rounding
        /// (max |f'| · ε · max |t| over the interval).
        sites_rounding: f64,
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
}

/// The field name of a bound of the given side and kind.
pub(crate) fn bound_field(b: &crate::types::Bound, side: Side) -> &'static str {
    use crate::types::Bound;
    match (b, side) {
        (Bound::Polyline(_), Side::Lower) => "lower.polyline",
        (Bound::Polyline(_), Side::Upper) => "upper.polyline",
        (Bound::Pieces(_), Side::Lower) => "lower.pieces",
        (Bound::Pieces(_), Side::Upper) => "upper.pieces",
        (Bound::None, Side::Lower) => "lower",
        (Bound::None, Side::Upper) => "upper",
    }
}

/// The reason given for numbers too badly scaled for double precision.
pub(crate) const BADLY_SCALED: &str =
    "too badly scaled for double precision (a normalized number overflows; rescale t and the values)";

/// A violation within this many times the sites' rounding (max |f'| · ε · |t|) is put down to
/// it ([`Error::StripViolated`]): the bounds and the pieces are evaluated at abscissae that carry
/// that much (ε·|t| is one to two ulps of t).
pub const SITES_ROUNDING_COUNTS: f64 = 100.0;

/// The end of [`Error::StripViolated`]'s message: why, when the sites' rounding explains it.
pub fn sites_rounding_hint(by: f64, sites_rounding: f64) -> &'static str {
    if by <= SITES_ROUNDING_COUNTS * sites_rounding {
        ": the sites' own rounding moves the curve there by as much (slope × ulp(t)); shift t to start near 0"
    } else {
        ""
    }
}
