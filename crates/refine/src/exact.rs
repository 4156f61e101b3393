//! The exact optimum of the fixed-knot constrained problems through [`crate::conic`]: balls
//! (3.4), half-space sets (3.7), derivative constraints (3.9)/(3.10) and clamped or
//! near-clamped ends (§3.6), translated into constraints L p ∈ K on stencils of at most three
//! vertices.

use divdiff::{derivative_stencil, Points};
use energy::Hessian;

use crate::algorithm::{FixedProblem, FixedSolution};
use crate::conic_problem::{ConicOptions, ConicProblem, ConvexSet};
use crate::problem::{Boundary, Constraint, Tangent};
use crate::Error;

/// The stricter target of the second conic solve. The conic solver measures complementarity
/// against the force scale of H (its module docs), which for many small balls is far larger
/// than the energy: at its default 1e-12 a closed curve with n = 1000 balls stopped 1.8e-7
/// (relative) above Clarabel's optimum, which this crate's duality-gap certificate flagged
/// (1.2e-6). At 1e-16 it reached the optimum (1.4e-12 from Clarabel). On small problems the
/// default is already exact and the stricter target can stall at a worse iterate, so the
/// exact path solves at the default first and again at this target only when the certificate
/// is above [`EXACT_KKT_TARGET`], keeping the better of the two.
pub const EXACT_CONIC_TOLERANCE: f64 = 1e-16;
/// The target of the first conic solve.
pub const CONIC_TOLERANCE: f64 = 1e-12;
/// The certificate level below which the first conic solve is accepted.
pub const EXACT_KKT_TARGET: f64 = 1e-10;

/// What a conic constraint index stands for, to map multipliers and errors back.
#[derive(Clone, Copy)]
enum Origin {
    /// The data constraint of point i.
    Data(usize),
    /// The derivative constraint of point i.
    Tangent(usize),
    /// An end condition (0 = start, 1 = end).
    End(usize),
}

/// Derivative-constraint forces: (stencil, force z_c) with Σ_c L_cᵀ z_c in the stationarity.
pub(crate) type StencilForces = Vec<crate::certify::StencilForce>;

fn halfspaces(set: &[crate::problem::HalfSpace]) -> ConvexSet {
    ConvexSet::HalfSpaces(set.iter().map(|h| (h.normal.clone(), h.offset)).collect())
}

fn unit(v: &[f64]) -> Vec<f64> {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter().map(|x| x / n).collect()
}

/// Solves the fixed-knot problem exactly with the conic interior-point solver. Returns the
/// solution with multipliers in the conventions of [`crate::Refinement::multipliers`], the
/// derivative-constraint forces (for the certificate), and the conic solver's own relative KKT
/// residual (which covers the primal and complementarity parts of derivative constraints).
pub(crate) fn solve(
    fp: &FixedProblem<'_>,
    tolerance: f64,
) -> Result<(FixedSolution, StencilForces, f64), Error> {
    let q = fp.q;
    let d = q.dim();
    let n = q.len();
    let hess = Hessian::new(fp.knots);
    let mut cp = ConicProblem::new(fp.knots, d)?;
    let mut origin = Vec::new();
    let mut data_constraint = vec![None; n];
    for i in 0..n {
        let v = fp.data_vertex[i];
        let qi = q.point(i);
        match fp.constraint {
            Constraint::Interpolate => cp.fix(v, qi)?,
            Constraint::Balls(r) if r[i] == 0.0 => cp.fix(v, qi)?,
            Constraint::Balls(r) => {
                let c = cp.add_constraint(
                    &[(v, 1.0)],
                    ConvexSet::Ball {
                        center: qi.to_vec(),
                        radius: r[i],
                    },
                )?;
                origin.push(Origin::Data(i));
                data_constraint[i] = Some(c);
            }
            Constraint::Smoothing(w) => cp.add_smoothing(v, w[i], qi)?,
            Constraint::HalfSpaces(sets) => {
                if !sets[i].is_empty() {
                    let c = cp.add_constraint(&[(v, 1.0)], halfspaces(&sets[i]))?;
                    origin.push(Origin::Data(i));
                    data_constraint[i] = Some(c);
                }
            }
        }
    }
    let rule = fp.problem.derivative;
    let mut derivative = Vec::new();
    if let Some(tangents) = &fp.problem.tangents {
        for (i, t) in tangents.iter().enumerate() {
            let Some(t) = t else { continue };
            let v = fp.data_vertex[i];
            let stencil = derivative_stencil(fp.knots, v, rule)?.to_vec();
            let set = match t {
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
                Tangent::HalfSpaces(h) => halfspaces(h),
            };
            let c = cp.add_constraint(&stencil, set)?;
            origin.push(Origin::Tangent(i));
            derivative.push((c, stencil));
        }
    }
    let last = fp.knots.vertex_count() - 1;
    let ends = match &fp.problem.boundary {
        Boundary::Natural => Vec::new(),
        Boundary::Clamped { start, end } => vec![
            (0, ConvexSet::Point(start.clone())),
            (last, ConvexSet::Point(end.clone())),
        ],
        Boundary::NearClamped { start, end, radius } => vec![
            (
                0,
                ConvexSet::Ball {
                    center: start.clone(),
                    radius: *radius,
                },
            ),
            (
                last,
                ConvexSet::Ball {
                    center: end.clone(),
                    radius: *radius,
                },
            ),
        ],
    };
    for (k, (v, set)) in ends.into_iter().enumerate() {
        let stencil = derivative_stencil(fp.knots, v, rule)?.to_vec();
        let c = cp.add_constraint(&stencil, set)?;
        origin.push(Origin::End(k));
        derivative.push((c, stencil));
    }
    let opts = ConicOptions::default().with_tolerance(tolerance);
    let sol = cp.solve(&opts).map_err(|e| match e {
        Error::Infeasible { constraint } => match origin.get(constraint) {
            Some(Origin::Data(i)) => Error::InfeasibleConstraint {
                field: "sets",
                point: *i,
            },
            Some(Origin::Tangent(i)) => Error::InfeasibleConstraint {
                field: "tangents",
                point: *i,
            },
            Some(Origin::End(k)) => Error::InfeasibleConstraint {
                field: "boundary",
                point: *k,
            },
            None => e,
        },
        e => e,
    })?;
    let hp = hess.apply(&sol.points);
    let multipliers = (0..n)
        .map(|i| {
            let v = fp.data_vertex[i];
            match (fp.constraint, data_constraint[i]) {
                (Constraint::Smoothing(w), _) => vec![w[i]],
                (Constraint::Balls(_), Some(c)) => vec![sol.ball_weights[c].unwrap_or(0.0)],
                (Constraint::HalfSpaces(sets), Some(c)) => sets[i]
                    .iter()
                    .zip(&sol.cone_duals[c])
                    .map(|(h, z)| z / h.normal.iter().map(|x| x * x).sum::<f64>().sqrt())
                    .collect(),
                (Constraint::HalfSpaces(_), None) => Vec::new(),
                // Fixed vertices: the reaction −(Hp)_v less any derivative forces there.
                _ => {
                    let mut f: Vec<f64> = hp.point(v).iter().map(|x| -x).collect();
                    for (c, stencil) in &derivative {
                        for &(u, coef) in stencil {
                            if u == v {
                                for (fc, z) in f.iter_mut().zip(&sol.forces[*c]) {
                                    *fc -= coef * z;
                                }
                            }
                        }
                    }
                    f
                }
            }
        })
        .collect();
    let forces = derivative
        .iter()
        .map(|(c, stencil)| (stencil.clone(), sol.forces[*c].clone()))
        .collect();
    let points: Points = sol.points;
    Ok((
        FixedSolution {
            points,
            multipliers: Some(multipliers),
            iterations: sol.iterations,
            stencil: None,
            extra: Vec::new(),
            solver_kkt: None,
            certificate: None,
        },
        forces,
        sol.kkt.total,
    ))
}
