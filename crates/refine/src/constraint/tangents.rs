//! Derivative constraints, Kersey §3.5, (3.9)–(3.10): one optional constraint per data point on
//! the approximate derivative Df(t_{i_k}) = Σ_k c_k p_{v_k} (a stencil of three vertices, the
//! problem's [`divdiff::DerivativeRule`] on the current knots).
//!
//! Rows, on the derivative stencil at the data vertex (full-vertex backend only): a ball
//! |Df − v| ≤ ε (Fig. 3.5a, a second-order cone), a direction wedge Df·a ≥ |Df| cos θ (Fig.
//! 3.5b, a second-order cone in the rotated frame (Df·a / cos θ, Df)), tension |Df| ≤ ε (Fig.
//! 3.5c) or a polytope. Multipliers: none in [`crate::Refinement::multipliers`]; the forces
//! enter the certificate through the cone duals ([`super::derivative_terms`]). No common point:
//! a constant curve has Df = 0, which need not satisfy them. Translation moves nothing (Df is
//! translation invariant).

use super::{At, Kind, Rows, Tangent, Terms};
use crate::conic_problem::ConvexSet;
use crate::problem::Problem;
use crate::solve::times_power_of_two;
use crate::stage::FixedProblem;
use crate::Error;

/// The tangent constraints, one entry (or none) per data point.
pub(crate) struct Tangents<'a>(pub &'a [Option<Tangent>]);

fn unit(v: &[f64]) -> Vec<f64> {
    // Scaled norm: a direction like [1e-200, 0] has a representable length whose square
    // underflows to 0 (it gave a non-finite axis).
    let n = banded::vector::norm(v);
    v.iter().map(|x| x / n).collect()
}

impl Tangents<'_> {
    /// Each constraint's data point and tangent (the one place rows, certificate and
    /// [`Kind::derivative_vertices`] read which data points carry one).
    fn constrained(&self) -> impl Iterator<Item = (usize, &Tangent)> + '_ {
        self.0
            .iter()
            .enumerate()
            .filter_map(|(i, t)| Some((i, t.as_ref()?)))
    }

    /// Each constraint's data point and set (on the stencil at its data vertex).
    fn sets(&self, d: usize) -> impl Iterator<Item = (usize, ConvexSet)> + '_ {
        self.constrained().map(move |(i, t)| (i, set(t, d)))
    }
}

/// A tangent constraint's set of Df in R^d.
pub(crate) fn set(tangent: &Tangent, d: usize) -> ConvexSet {
    match tangent {
        Tangent::Ball { center, radius } => ConvexSet::Ball {
            center: center.clone(),
            radius: *radius,
        },
        Tangent::Wedge {
            direction,
            half_angle,
        } => ConvexSet::Cone {
            axis: unit(direction),
            half_angle: *half_angle,
        },
        Tangent::Tension { radius } => ConvexSet::Ball {
            center: vec![0.0; d],
            radius: *radius,
        },
        Tangent::HalfSpaces(h) => super::polytope(h),
    }
}

impl Kind for Tangents<'_> {
    fn validate(&self, problem: &Problem) -> Result<(), Error> {
        let d = problem.points.dim();
        super::check_len("tangents", self.0.len(), problem.points.len())?;
        let mut budget = super::farkas::PROBLEM_CANDIDATES;
        for (i, tan) in self.0.iter().enumerate() {
            match tan {
                None => {}
                Some(Tangent::Ball { center, radius }) => {
                    super::check_dim("tangents.center", i, center, d)?;
                    super::check_nonneg_one("tangents.radius", i, *radius)?;
                }
                Some(Tangent::Wedge {
                    direction,
                    half_angle,
                }) => {
                    super::check_dim("tangents.direction", i, direction, d)?;
                    if direction.iter().all(|&x| x == 0.0) {
                        return Err(Error::InvalidValue {
                            field: "tangents.direction",
                            index: i,
                            value: 0.0,
                            reason: "the direction must be non-zero",
                        });
                    }
                    let a = *half_angle;
                    if !(a.is_finite() && (0.0..std::f64::consts::FRAC_PI_2).contains(&a)) {
                        return Err(Error::InvalidValue {
                            field: "tangents.half_angle",
                            index: i,
                            value: a,
                            reason: "must be in [0, pi/2)",
                        });
                    }
                }
                Some(Tangent::Tension { radius }) => {
                    super::check_nonneg_one("tangents.radius", i, *radius)?;
                }
                Some(Tangent::HalfSpaces(h)) => {
                    super::check_halfspaces("tangents.halfspaces", i, h, d, None, &mut budget)?;
                }
            }
        }
        Ok(())
    }

    fn on_derivatives(&self) -> bool {
        true
    }

    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error> {
        let far = super::far_derivative_threshold(stage.q, stage.knots, stage.data_vertex);
        for (i, set) in self.sets(stage.q.dim()) {
            let v = stage.data_vertex[i];
            super::derivative_rows(stage, rows, ("tangents", i), v, set, far)?;
        }
        Ok(())
    }

    fn derivative_vertices(&self, data_vertex: &[usize], _: usize) -> Vec<usize> {
        self.constrained().map(|(i, _)| data_vertex[i]).collect()
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        let far = super::far_derivative_threshold(at.q, at.knots, at.data_vertex);
        for (i, set) in self.sets(at.q.dim()) {
            super::certify_derivative(at, terms, at.data_vertex[i], set, far);
        }
    }

    fn rescale(&self, points: i32, knots: i32, into: &mut Problem) -> Result<(), Error> {
        let slope = points - knots;
        let scaled = self.0.iter().map(|t| t.as_ref().map(|t| scaled(t, slope)));
        into.tangents = Some(scaled.collect());
        Ok(())
    }
}

/// A tangent constraint on derivatives scaled by 2^k (a wedge's direction and angle as given).
fn scaled(tangent: &Tangent, k: i32) -> Tangent {
    let up = |x: &f64| times_power_of_two(*x, k);
    match tangent {
        Tangent::Ball { center, radius } => Tangent::Ball {
            center: center.iter().map(up).collect(),
            radius: up(radius),
        },
        Tangent::Wedge { .. } => tangent.clone(),
        Tangent::Tension { radius } => Tangent::Tension { radius: up(radius) },
        Tangent::HalfSpaces(set) => Tangent::HalfSpaces(super::scaled_halfspaces(set, k)),
    }
}
