//! The tests' independent judge of a linear objective over cones: Clarabel on min qᵀx subject
//! to A x + s = b, s in `cones`, asserted solved (or almost), its x returned.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// x of min qᵀx subject to A x + s = b, s in `cones`; `gap` tightens Clarabel's absolute and
/// relative gap tolerances (its defaults when `None`).
pub fn minimize_linear(
    q: &[f64],
    a: &CscMatrix<f64>,
    b: &[f64],
    cones: &[SupportedConeT<f64>],
    gap: Option<f64>,
) -> Vec<f64> {
    let mut builder = DefaultSettingsBuilder::default();
    builder.verbose(false);
    if let Some(tol) = gap {
        builder.tol_gap_abs(tol).tol_gap_rel(tol);
    }
    let settings = builder.build().unwrap();
    let p = CscMatrix::zeros((q.len(), q.len()));
    let mut solver = DefaultSolver::new(&p, q, a, b, cones, settings).unwrap();
    solver.solve();
    assert!(
        matches!(
            solver.solution.status,
            SolverStatus::Solved | SolverStatus::AlmostSolved
        ),
        "{:?}",
        solver.solution.status
    );
    solver.solution.x.clone()
}
