//! The exact fixed-knot optimum through the conic solver (balls, half-spaces, derivative
//! constraints).

use super::algorithm::{FixedProblem, FixedSolution};
use crate::Error;

/// Solves the fixed-knot problem exactly with [`crate::conic`].
pub(crate) fn solve(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    let _ = fp;
    Err(Error::Unsupported {
        field: "solver",
        reason: "the exact conic solver is not available yet",
    })
}
