//! End conditions of an open curve, Kersey §3.6: clamped Df(t_1) = v_1, Df(t_N) = v_n, or
//! near-clamped |Df(t_1) − v_1| ≤ ε, |Df(t_N) − v_n| ≤ ε, on the derivative stencils at the two
//! end vertices (natural ends: none).
//!
//! Rows: a point (an equality, zero cone) or a ball on each end's stencil (full-vertex backend
//! only). Certificate through the cone duals ([`super::derivative_terms`]); origin indices 0 =
//! start, 1 = end. No common point. Translation moves nothing.

use divdiff::Topology;

use super::{At, Boundary, Kind, Rows, Terms};
use crate::conic_problem::ConvexSet;
use crate::problem::Problem;
use crate::stage::FixedProblem;
use crate::Error;

/// The end conditions (never [`Boundary::Natural`]).
pub(crate) struct Ends<'a>(pub &'a Boundary);

impl Ends<'_> {
    /// The set at each end (0 = start, 1 = end).
    fn sets(&self) -> [ConvexSet; 2] {
        match self.0 {
            Boundary::Clamped { start, end } => [
                ConvexSet::Point(start.clone()),
                ConvexSet::Point(end.clone()),
            ],
            Boundary::NearClamped { start, end, radius } => [
                ConvexSet::Ball {
                    center: start.clone(),
                    radius: *radius,
                },
                ConvexSet::Ball {
                    center: end.clone(),
                    radius: *radius,
                },
            ],
            // (Never built for natural ends.)
            Boundary::Natural => [ConvexSet::Point(Vec::new()), ConvexSet::Point(Vec::new())],
        }
    }
}

impl Kind for Ends<'_> {
    fn validate(&self, problem: &Problem) -> Result<(), Error> {
        let d = problem.points.dim();
        match (self.0, problem.topology) {
            (Boundary::Natural, _) => {}
            (_, Topology::Closed) => {
                return Err(Error::Unsupported {
                    field: "boundary",
                    reason: "end conditions apply to open curves only",
                })
            }
            (Boundary::Clamped { start, end }, Topology::Open) => {
                super::check_dim("boundary.start", 0, start, d)?;
                super::check_dim("boundary.end", 0, end, d)?;
            }
            (Boundary::NearClamped { start, end, radius }, Topology::Open) => {
                super::check_dim("boundary.start", 0, start, d)?;
                super::check_dim("boundary.end", 0, end, d)?;
                super::check_nonneg_one("boundary.radius", 0, *radius)?;
            }
        }
        Ok(())
    }

    fn on_derivatives(&self) -> bool {
        true
    }

    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error> {
        let rule = stage.problem.derivative;
        let last = stage.knots.vertex_count() - 1;
        for (k, (v, set)) in [0, last].into_iter().zip(self.sets()).enumerate() {
            let stencil = divdiff::derivative_stencil(stage.knots, v, rule)?.to_vec();
            rows.derivative("boundary", k, stencil, set)?;
        }
        Ok(())
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        let last = at.knots.vertex_count() - 1;
        for (v, set) in [0, last].into_iter().zip(self.sets()) {
            super::derivative_terms(at, terms, v, &set);
        }
    }
}
