/// Errors of the `refine` crate. Variants name the offending field and index.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Invalid knots or points (from `divdiff`).
    #[error(transparent)]
    Divdiff(#[from] divdiff::Error),
    /// A linear-algebra failure (from `energy`).
    #[error(transparent)]
    Energy(#[from] energy::Error),
    /// A vertex index is out of range (conic problems).
    #[error("{field} vertex {index} is out of range (N = {len})")]
    VertexOutOfRange {
        /// The field.
        field: &'static str,
        /// The index given.
        index: usize,
        /// The number of vertices.
        len: usize,
    },
    /// A vector has the wrong number of coordinates (conic problems).
    #[error("{field}[{index}] has {got} coordinates, expected {expected}")]
    WrongDimension {
        /// The field.
        field: &'static str,
        /// The vertex or constraint index.
        index: usize,
        /// The expected size.
        expected: usize,
        /// The given size.
        got: usize,
    },
    /// A value is NaN or infinite (conic problems).
    #[error("{field}[{index}] is not finite")]
    NonFiniteInput {
        /// The field.
        field: &'static str,
        /// The vertex or constraint index.
        index: usize,
    },
    /// A constraint is malformed (negative radius, zero normal, non-unit axis, bad stencil …).
    #[error("constraint {constraint}: {reason}")]
    InvalidConstraint {
        /// The constraint index.
        constraint: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// The constraints cannot be met: an empty polytope, a constraint contradicting fixed
    /// vertices, or (when the interior-point method finds no feasible point) the most violated
    /// constraint.
    #[error("constraint {constraint} cannot be satisfied")]
    Infeasible {
        /// The constraint index.
        constraint: usize,
    },
    /// The exact solver did not reach the accepted KKT residual within its iteration limit.
    #[error("not converged after {iterations} iterations (best relative KKT residual {best_residual:e})")]
    NotConverged {
        /// Iterations performed.
        iterations: usize,
        /// The best relative KKT residual reached.
        best_residual: f64,
    },
}
