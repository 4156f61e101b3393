//! End conditions of an open curve, Kersey §3.6: clamped Df(t_1) = v_1, Df(t_N) = v_n, or
//! near-clamped |Df(t_1) − v_1| ≤ ε, |Df(t_N) − v_n| ≤ ε, on the derivative stencils at the two
//! end vertices (natural ends: none).
//!
//! Rows: a point (an equality, zero cone) or a ball on each end's stencil (full-vertex backend
//! only). Certificate through the cone duals ([`super::derivative_terms`]); origin indices 0 =
//! start, 1 = end. No common point. Translation moves nothing.

use divdiff::Topology;

use super::{At, Boundary, Kind, Rows, Tangent, Terms};
use crate::conic_problem::{set_distance, ConvexSet};
use crate::problem::Problem;
use crate::solve::times_power_of_two;
use crate::stage::FixedProblem;
use crate::Error;

/// The end conditions (never [`Boundary::Natural`]).
pub(crate) struct Ends<'a>(pub &'a Boundary);

impl Ends<'_> {
    /// The vertices the two sets constrain the derivative at, of `count` vertices: the first
    /// and the last (the one place rows, certificate and [`Kind::derivative_vertices`] read).
    fn vertices(count: usize) -> [usize; 2] {
        [0, count - 1]
    }

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
        let far = super::far_derivative_threshold(stage.q, stage.knots, stage.data_vertex);
        let ends = Self::vertices(stage.knots.vertex_count());
        for (k, (v, set)) in ends.into_iter().zip(self.sets()).enumerate() {
            super::derivative_rows(stage, rows, ("boundary", k), v, set, far)?;
        }
        Ok(())
    }

    fn derivative_vertices(&self, _: &[usize], vertices: usize) -> Vec<usize> {
        Self::vertices(vertices).to_vec()
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        let far = super::far_derivative_threshold(at.q, at.knots, at.data_vertex);
        let ends = Self::vertices(at.knots.vertex_count());
        for (v, set) in ends.into_iter().zip(self.sets()) {
            super::certify_derivative(at, terms, v, set, far);
        }
    }

    /// The end derivatives (and a near-clamped end's radius) by 2^(points − knots).
    fn rescale(&self, points: i32, knots: i32, into: &mut Problem) -> Result<(), Error> {
        let k = points - knots;
        let up = |v: &[f64]| v.iter().map(|&x| times_power_of_two(x, k)).collect();
        into.boundary = match self.0 {
            Boundary::Natural => Boundary::Natural,
            Boundary::Clamped { start, end } => Boundary::Clamped {
                start: up(start),
                end: up(end),
            },
            Boundary::NearClamped { start, end, radius } => Boundary::NearClamped {
                start: up(start),
                end: up(end),
                radius: times_power_of_two(*radius, k),
            },
        };
        Ok(())
    }
}

/// An end condition and a tangent set at the same end of an open curve both constrain Df at
/// that vertex (the same derivative stencil, [`divdiff::derivative_stencil`]): the end's set —
/// the point v (clamped) or the ball |Df − v| ≤ ε (near-clamped) — must meet the tangent set of
/// the end's data point. A proof that they do not, found before any solve: the end (0 = start,
/// 1 = end), its data point, and the distance between the two sets, which exceeds
/// [`CONFLICT_MARGIN`] times their size. Without it such problems ran the interior-point method to
/// its iteration limit and were refused as not converged, naming nothing (ROBUSTNESS.md §4, 22).
pub(crate) fn conflict(problem: &Problem) -> Option<(usize, usize, f64)> {
    let (starts, radius) = match &problem.boundary {
        Boundary::Natural => return None,
        Boundary::Clamped { start, end } => ([start, end], 0.0),
        Boundary::NearClamped { start, end, radius } => ([start, end], *radius),
    };
    let tangents = problem.tangents.as_ref()?;
    let n = problem.points.len();
    if problem.topology != Topology::Open || tangents.len() != n {
        return None;
    }
    [0, n - 1]
        .into_iter()
        .zip(starts)
        .enumerate()
        .find_map(|(end, (point, center))| {
            let tangent = tangents[point].as_ref()?;
            let (gap, size) = gap(center, radius, tangent)?;
            (gap > CONFLICT_MARGIN * size).then_some((end, point, gap))
        })
}

/// Sets closer than this fraction of their size are left to the solver (whose feasibility is
/// judged at rounding); only a clear separation is refused up front.
const CONFLICT_MARGIN: f64 = 1e-6;

/// A lower bound on the distance between the ball |x − c| ≤ r and a tangent set — the distance
/// from c to the set ([`set_distance`]: exact for balls, the tension ball and wedges; for
/// half-spaces the largest distance to one of them) less r — and the two sets' size (the largest
/// of |c|, r and the tangent set's own scale). `None` for non-finite values (validation reports
/// those).
fn gap(c: &[f64], r: f64, tangent: &Tangent) -> Option<(f64, f64)> {
    let (to_set, scale) = set_distance(&super::tangents::set(tangent, c.len()), c);
    let gap = to_set - r;
    let size = banded::vector::norm(c).max(r).max(scale);
    (gap.is_finite() && size.is_finite()).then_some((gap, size))
}
