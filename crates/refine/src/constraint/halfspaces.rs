//! Half-space sets, Kersey (3.7): p_{i_k} ∈ K_i = ∩_j {x : n_ij · x ≤ c_ij}, one (possibly empty)
//! set per data point.
//!
//! Rows: the polytope at the data vertex (one orthant row per face, unit normals); on the
//! condensed backend [`PointSet::Faces`]. Multipliers of point i: one per face, w_ij ≥ 0 with
//! (Hp)_{i_k} + Σ_j w_ij n_ij = 0 (3.8) for the original normals (the unit normal's dual
//! divided by |n_ij|).
//!
//! Certificate, per face (signed distance g = (n·p − c)/|n|): force w n (projected onto
//! complementarity as for balls); violation g; complementarity and gap |w |n| g|.
//! Common point: projection onto each half-space in turn. Translation by a: c ↦ c + n·a.
//! Offsets beyond [`super::FAR_BOUND`] times the data's extent from a data point inside its set
//! are capped there for the solvers (an open side of a box); the certificate keeps them as
//! given. (A set its data point is outside of is left as given: capping could empty it.)

use banded::vector::{dot, norm};
use divdiff::Points;

use super::{At, CommonPoint, HalfSpace, Kind, Projections, Rows, Terms};
use crate::backend::condensed::{Face, PointSet};
use crate::conic_problem::ConicSolution;
use crate::problem::Problem;
use crate::stage::FixedProblem;
use crate::{Constraint, Error};

/// One set per data point.
pub(crate) struct HalfSpaces<'a>(pub &'a [Vec<HalfSpace>]);

impl HalfSpaces<'_> {
    /// The sets the solvers see for data `q`: a set that contains its data point q_i with each
    /// offset capped at n·q_i + [`super::far_cap`]·|n| (module docs), the others as given.
    fn solved_sets(&self, q: &Points) -> Vec<Vec<HalfSpace>> {
        let cap = super::far_cap(q);
        self.0
            .iter()
            .enumerate()
            .map(|(i, set)| {
                let qi = q.point(i);
                let inside = set.iter().all(|h| dot(&h.normal, qi) <= h.offset);
                set.iter()
                    .map(|h| HalfSpace {
                        normal: h.normal.clone(),
                        offset: if inside {
                            h.offset.min(dot(&h.normal, qi) + cap * norm(&h.normal))
                        } else {
                            h.offset
                        },
                    })
                    .collect()
            })
            .collect()
    }
}

impl Kind for HalfSpaces<'_> {
    fn multiplier_overflow(&self) -> (&'static str, &'static str) {
        ("sets", "the multiplier of this point's half-spaces overflows (the force that holds the point in them is beyond the doubles against the data's scale); loosen them")
    }

    fn validate(&self, problem: &Problem) -> Result<(), Error> {
        super::check_len("sets", self.0.len(), problem.points.len())?;
        let mut budget = super::farkas::PROBLEM_CANDIDATES;
        for (i, set) in self.0.iter().enumerate() {
            let q = problem.points.point(i);
            super::check_halfspaces("sets", i, set, problem.points.dim(), Some(q), &mut budget)?;
        }
        Ok(())
    }

    /// (The condensed method needs the first point's set nonempty, which half-space sets need
    /// not be.)
    fn may_need_full_vertex(&self) -> bool {
        true
    }

    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error> {
        let sets = self.solved_sets(stage.q);
        for (i, &v) in stage.data_vertex.iter().enumerate() {
            if !sets[i].is_empty() {
                rows.data("sets", i, v, super::polytope(&sets[i]))?;
            }
        }
        Ok(())
    }

    fn point_sets(&self, stage: &FixedProblem<'_>) -> Option<Vec<Option<PointSet>>> {
        Some(
            self.solved_sets(stage.q)
                .iter()
                .map(|set| {
                    (!set.is_empty()).then(|| {
                        PointSet::Faces(
                            set.iter()
                                .map(|h| {
                                    let l = norm(&h.normal);
                                    Face {
                                        normal: h.normal.iter().map(|x| x / l).collect(),
                                        offset: h.offset / l,
                                        norm: l,
                                    }
                                })
                                .collect(),
                        )
                    })
                })
                .collect(),
        )
    }

    fn multipliers(
        &self,
        _: &FixedProblem<'_>,
        sol: &ConicSolution,
        rows: &Rows,
        _: &[f64],
    ) -> Vec<Vec<f64>> {
        self.0
            .iter()
            .enumerate()
            .map(|(i, set)| match rows.data[i] {
                Some(c) => set
                    .iter()
                    .zip(&sol.cone_duals[c])
                    .map(|(h, z)| z / norm(&h.normal))
                    .collect(),
                None => Vec::new(),
            })
            .collect()
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        let d = at.q.dim();
        for (i, &v) in at.data_vertex.iter().enumerate() {
            let pv = at.p.point(v);
            let m = &at.multipliers[i];
            let mut any = false;
            for (j, h) in self.0[i].iter().enumerate() {
                let l = norm(&h.normal);
                let g = (dot(&h.normal, pv) - h.offset) / l;
                // Projected onto complementarity, as for balls.
                let w = if g >= -at.active_tol * at.length {
                    m[j]
                } else {
                    0.0
                };
                for c in 0..d {
                    terms.force_data[i * d + c] += w * h.normal[c];
                }
                terms.primal = terms.primal.max(g);
                terms.dual = terms.dual.max(-w * l * at.length);
                terms.comp = terms.comp.max((w * l * g).abs());
                terms.gap += (w * l * g).abs();
                any |= g >= -at.active_tol * at.length;
            }
            terms.active[i] = any;
        }
    }

    fn common_point<'s>(&'s self, _: &'s Points) -> CommonPoint<'s> {
        CommonPoint::Sets(Box::new(Sets(self.0)))
    }

    fn translate(&self, offset: &[f64], into: &mut Problem) {
        let moved = self
            .0
            .iter()
            .map(|set| {
                set.iter()
                    .map(|h| HalfSpace {
                        normal: h.normal.clone(),
                        offset: h.offset + dot(&h.normal, offset),
                    })
                    .collect()
            })
            .collect();
        into.constraint = Constraint::HalfSpaces(moved);
    }

    fn rescale(&self, points: i32, _: i32, into: &mut Problem) -> Result<(), Error> {
        let scaled = self
            .0
            .iter()
            .map(|set| super::scaled_halfspaces(set, points))
            .collect();
        into.constraint = Constraint::HalfSpaces(scaled);
        Ok(())
    }
}

/// The polytopes as sets of the common-point test.
struct Sets<'a>(&'a [Vec<HalfSpace>]);

impl Projections for Sets<'_> {
    fn sweep(&self, x: &mut [f64]) {
        for h in self.0.iter().flatten() {
            let nn = dot(&h.normal, &h.normal);
            let g = dot(&h.normal, x) - h.offset;
            if g > 0.0 {
                for (xj, nj) in x.iter_mut().zip(&h.normal) {
                    *xj -= g / nn * nj;
                }
            }
        }
    }

    fn violation(&self, x: &[f64]) -> f64 {
        self.0
            .iter()
            .flatten()
            .map(|h| (dot(&h.normal, x) - h.offset) / norm(&h.normal))
            .fold(0.0, f64::max)
    }

    fn zero_multipliers(&self, _: usize) -> Vec<Vec<f64>> {
        self.0.iter().map(|s| vec![0.0; s.len()]).collect()
    }
}
