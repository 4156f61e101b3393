//! The error type of `banded`.

use std::fmt;

/// Errors of the `banded` crate: one enum, variants named as across the workspace.
///
/// Indices are the caller's: a row of a scalar matrix, a block row of a block matrix, in the
/// original (not the factored) order.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The factorization met a pivot that is not finite or not above the relative pivot
    /// tolerance times the diagonal entry of its row (see [`crate::PIVOT_RTOL`]): the matrix is
    /// singular, indefinite or too ill-conditioned for the tolerance.
    Singular {
        /// The (block) row of the failing pivot.
        index: usize,
    },
    /// A slice does not have the length the matrix needs.
    WrongLength {
        /// The argument (`"x"`, `"diag"`, `"block"`, `"eliminated"`, …).
        field: &'static str,
        /// The length it must have.
        expected: usize,
        /// The length it has.
        got: usize,
    },
    /// A (block) row or column index is not below the matrix size.
    IndexOutOfRange {
        /// `"row"` or `"col"`.
        field: &'static str,
        /// The index given.
        index: usize,
        /// The matrix size (number of rows, or block rows).
        len: usize,
    },
    /// An entry lies outside the band: rows `row` and `col` are more than the half-bandwidth
    /// apart (cyclically, for cyclic matrices).
    OutsideBand {
        /// The row of the entry.
        row: usize,
        /// The column of the entry.
        col: usize,
        /// The half-bandwidth of the matrix.
        half_bandwidth: usize,
    },
    /// A size is below its minimum (a block size of 0).
    TooFew {
        /// The argument (`"dim"`).
        field: &'static str,
        /// The minimum.
        minimum: usize,
        /// What was given.
        got: usize,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Singular { index } => write!(
                f,
                "singular matrix: the pivot of row {index} is not positive relative to its diagonal"
            ),
            Error::WrongLength {
                field,
                expected,
                got,
            } => write!(f, "{field} has length {got}, expected {expected}"),
            Error::IndexOutOfRange { field, index, len } => {
                write!(f, "{field} index {index} is out of range (size {len})")
            }
            Error::OutsideBand {
                row,
                col,
                half_bandwidth,
            } => write!(
                f,
                "entry ({row}, {col}) lies outside the band of half-bandwidth {half_bandwidth}"
            ),
            Error::TooFew {
                field,
                minimum,
                got,
            } => write!(f, "{field} must be at least {minimum}, got {got}"),
        }
    }
}

impl std::error::Error for Error {}
