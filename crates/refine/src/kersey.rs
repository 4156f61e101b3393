//! Kersey's variational refinement: split, interpolation, balls, smoothing, Algorithm 4.1.

mod algorithm;
mod certify;
mod degenerate;
mod exact;
mod fast;
mod fixed;
mod operator;
mod problem;
mod split;

pub use algorithm::{Iterations, Refinement, Stage};
pub use certify::{ACTIVE_REL_TOL, PAPER_ACTIVE_REL_TOL};
pub use degenerate::{COMMON_POINT_STAGNATION, COMMON_POINT_SWEEPS, COMMON_POINT_TOL};
pub use divdiff::{DerivativeRule, Parametrization};
pub use exact::{EXACT_CONIC_TOLERANCE, EXACT_KKT_TARGET};
pub use fixed::{
    BALL_POLISH_ACTIVE_RTOL, BALL_POLISH_NEWTON_STEPS, BALL_POLISH_ROUNDS, BALL_POLISH_STIFFNESS,
    PAPER_WEIGHT_FLOOR,
};
pub use problem::{
    Boundary, Constraint, HalfSpace, Problem, Solver, Tangent, DEFAULT_K, DEFAULT_KNOT_ITERATIONS,
    DEFAULT_PAPER_ITERATIONS,
};
pub use split::{data_vertex, split};

impl Problem {
    /// Validates the problem and runs Algorithm 4.1 (see the crate docs).
    ///
    /// # Errors
    /// Any validation error of [`Problem::validate`]; [`crate::Error::DegenerateRefinedSpan`]
    /// when a knot update meets coincident refined vertices; [`crate::Error::Energy`] if a
    /// linear system is numerically singular; [`crate::Error::Unsupported`] for combinations a
    /// solver does not handle.
    pub fn solve(&self) -> Result<Refinement, crate::Error> {
        algorithm::run(self)
    }
}
