//! Balls, Kersey (3.4): |p_{i_k} − q_i| ≤ ε_i, one radius per data point (0 interpolates).
//!
//! Rows: a ball of radius ε_i about q_i at the data vertex (a second-order cone), or the vertex
//! fixed for ε_i = 0; on the condensed backend [`PointSet::Ball`] / [`PointSet::Fixed`].
//! Multiplier of a ball: Kersey's weight w_i ≥ 0 of (3.5), (Hp)_{i_k} + w_i(p_{i_k} − q_i) = 0,
//! read from the cone's dual as w = z₀/ε; of a fixed point, the reaction.
//!
//! Certificate: force w(p − q) (the multiplier projected onto complementarity: a clearly inactive
//! ball carries none, so a leftover interior-point multiplier is charged to stationarity, where a
//! wrong active set shows, rather than to a duality gap that blows up relative to E* = 0);
//! violation |p − q| − ε; complementarity |w(ε − |p − q|)|; duality gap ½ w(ε² − |p − q|²).
//! Common point: projection onto each ball, with the necessary test that consecutive balls meet.
//! Translation: the balls move with their centres, the data.
//! Radii beyond [`super::FAR_BOUND`] times the data's extent are capped there for the solvers
//! (a point left free); the certificate keeps them as given.

use divdiff::Points;

use super::{dist, At, CommonPoint, Kind, Projections, Rows, Terms};
use crate::backend::condensed::PointSet;
use crate::conic_problem::{ConicSolution, ConvexSet};
use crate::problem::Problem;
use crate::solve::times_power_of_two;
use crate::stage::FixedProblem;
use crate::Error;

/// The radii.
pub(crate) struct Balls<'a>(pub &'a [f64]);

impl Balls<'_> {
    /// The radii the solvers see for data `q`: the given ones capped at [`super::far_cap`].
    fn solved_radii(&self, q: &Points) -> Vec<f64> {
        let cap = super::far_cap(q);
        self.0.iter().map(|&e| e.min(cap)).collect()
    }
}

impl Kind for Balls<'_> {
    fn validate(&self, problem: &Problem) -> Result<(), Error> {
        super::check_len("radii", self.0.len(), problem.points.len())?;
        super::check_nonneg("radii", self.0)
    }

    fn linear(&self) -> bool {
        self.0.iter().all(|&e| e == 0.0)
    }

    fn multiplier_overflow(&self) -> (&'static str, &'static str) {
        ("radii", "the multiplier of this point's constraint overflows (a ball's force over a radius too small to tell from 0 against the data: give that point radius 0 to interpolate it exactly, or a larger radius)")
    }

    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error> {
        let radii = self.solved_radii(stage.q);
        for (i, &v) in stage.data_vertex.iter().enumerate() {
            let qi = stage.q.point(i);
            if radii[i] == 0.0 {
                rows.problem.fix(v, qi)?;
            } else {
                rows.data(
                    "radii",
                    i,
                    v,
                    ConvexSet::Ball {
                        center: qi.to_vec(),
                        radius: radii[i],
                    },
                )?;
            }
        }
        Ok(())
    }

    fn point_sets(&self, stage: &FixedProblem<'_>) -> Option<Vec<Option<PointSet>>> {
        Some(
            self.solved_radii(stage.q)
                .into_iter()
                .map(|e| {
                    Some(if e == 0.0 {
                        PointSet::Fixed
                    } else {
                        PointSet::Ball(e)
                    })
                })
                .collect(),
        )
    }

    fn multipliers(
        &self,
        stage: &FixedProblem<'_>,
        sol: &ConicSolution,
        rows: &Rows,
        hp: &[f64],
    ) -> Vec<Vec<f64>> {
        let forces = super::interpolate::derivative_forces(stage, sol, rows);
        (0..stage.q.len())
            .map(|i| match rows.data[i] {
                Some(c) => vec![sol.ball_weights[c].unwrap_or(0.0)],
                None => super::interpolate::reaction(stage, &forces, hp, i),
            })
            .collect()
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        let radii = self.0;
        super::interpolate::fixed_points(at, terms, |i| radii[i] == 0.0);
        let d = at.q.dim();
        for (i, &v) in at.data_vertex.iter().enumerate() {
            let eps = radii[i];
            if eps == 0.0 {
                continue;
            }
            let (pv, qi) = (at.p.point(v), at.q.point(i));
            let gap = dist(pv, qi);
            // "Clearly inactive": the slack exceeds the tolerance in length units, so tiny radii
            // (ε ≲ tol·length) always keep their multiplier.
            let w = if eps - gap <= at.active_tol * at.length {
                at.multipliers[i][0]
            } else {
                0.0
            };
            for c in 0..d {
                terms.force_data[i * d + c] += w * (pv[c] - qi[c]);
            }
            terms.primal = terms.primal.max(gap - eps);
            terms.dual = terms.dual.max(-w * eps.max(gap));
            // (A ball without a multiplier adds no gap: for radii near the top of the range,
            // ε² overflows and 0·∞ would be NaN.)
            if w != 0.0 {
                terms.comp = terms.comp.max((w * (eps - gap)).abs());
                terms.gap += (0.5 * w * (eps * eps - gap * gap)).abs();
            }
            terms.stiffness = terms.stiffness.max(w.abs());
            terms.active[i] = gap >= (1.0 - at.active_tol) * eps;
        }
    }

    fn common_point<'s>(&'s self, q: &'s Points) -> CommonPoint<'s> {
        CommonPoint::Sets(Box::new(BallSets { radii: self.0, q }))
    }

    fn rescale(&self, points: i32, _: i32, into: &mut Problem) -> Result<(), Error> {
        let radii = self.0.iter().map(|&r| times_power_of_two(r, points));
        into.constraint = crate::Constraint::Balls(radii.collect());
        Ok(())
    }

    /// A ball's weight is its force over its radius; radius 0 reports the reaction.
    fn multiplier_power(&self, i: usize, points: i32, knots: i32) -> i32 {
        if self.0[i] == 0.0 {
            points - 3 * knots
        } else {
            -3 * knots
        }
    }
}

/// The balls as sets of the common-point test.
struct BallSets<'a> {
    radii: &'a [f64],
    q: &'a Points,
}

impl Projections for BallSets<'_> {
    /// Consecutive balls must meet (cheap; rejects almost all real data).
    fn possible(&self) -> bool {
        let n = self.q.len();
        let r = self.radii;
        (0..n).all(|i| dist(self.q.point(i), self.q.point((i + 1) % n)) <= r[i] + r[(i + 1) % n])
    }

    fn sweep(&self, x: &mut [f64]) {
        for (i, &ri) in self.radii.iter().enumerate() {
            let c = self.q.point(i);
            let g = dist(x, c);
            if g > ri {
                let s = ri / g;
                for (xj, cj) in x.iter_mut().zip(c) {
                    *xj = cj + s * (*xj - cj);
                }
            }
        }
    }

    fn violation(&self, x: &[f64]) -> f64 {
        (0..self.q.len())
            .map(|i| dist(x, self.q.point(i)) - self.radii[i])
            .fold(0.0, f64::max)
    }

    fn zero_multipliers(&self, d: usize) -> Vec<Vec<f64>> {
        self.radii
            .iter()
            .map(|&e| if e == 0.0 { vec![0.0; d] } else { vec![0.0] })
            .collect()
    }
}
