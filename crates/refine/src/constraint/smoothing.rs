//! Smoothing, Kersey (3.6): minimize E + ½ Σ w_i |p_{i_k} − q_i|², one weight w_i ≥ 0 per data
//! point (a penalty, not a constraint: the problem is the linear system (H + W)p = W q̃).
//!
//! Rows: a smoothing term per positive weight. Multiplier of point i: its weight `[w_i]`.
//! Certificate: the force w_i(p_{i_k} − q_i) enters the stationarity exactly; nothing is ever
//! active, and Corollary 3.3's jumps do not apply. Validation: enough positive weights to pin
//! down the kernel of H (constants closed, linear polynomials open). No common point. Translation
//! moves nothing but the data.

use divdiff::Topology;

use super::{At, Kind, Rows, Terms};
use crate::conic_problem::ConicSolution;
use crate::problem::Problem;
use crate::solve::times_power_of_two;
use crate::stage::FixedProblem;
use crate::Error;

/// The weights.
pub(crate) struct Smoothing<'a>(pub &'a [f64]);

impl Kind for Smoothing<'_> {
    fn validate(&self, problem: &Problem) -> Result<(), Error> {
        let w = self.0;
        super::check_len("weights", w.len(), problem.points.len())?;
        super::check_nonneg("weights", w)?;
        let positive = w.iter().filter(|&&x| x > 0.0).count();
        let needed = match problem.topology {
            Topology::Open => 2,
            Topology::Closed => 1,
        };
        if positive < needed {
            return Err(Error::TooFewWeights {
                needed,
                got: positive,
            });
        }
        Ok(())
    }

    fn linear(&self) -> bool {
        true
    }

    fn multiplier_overflow(&self) -> (&'static str, &'static str) {
        ("weights", "this point's weight overflows against the curve's stiffness (weights act against ~1/h^3 of the parameter spans h); use a smaller weight, or interpolate the point")
    }

    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error> {
        for (i, &v) in stage.data_vertex.iter().enumerate() {
            if self.0[i] > 0.0 {
                rows.problem.add_smoothing(v, self.0[i], stage.q.point(i))?;
            }
        }
        Ok(())
    }

    fn multipliers(
        &self,
        _: &FixedProblem<'_>,
        _: &ConicSolution,
        _: &Rows,
        _: &[f64],
    ) -> Vec<Vec<f64>> {
        self.0.iter().map(|&w| vec![w]).collect()
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        let d = at.q.dim();
        for (i, &v) in at.data_vertex.iter().enumerate() {
            let w = self.0[i];
            let (pv, qi) = (at.p.point(v), at.q.point(i));
            for c in 0..d {
                terms.force_data[i * d + c] += w * (pv[c] - qi[c]);
                terms.penalty += 0.5 * w * (pv[c] - qi[c]).powi(2);
            }
            // p_{i_k} is known to half an ulp of the larger of its coordinates and the length
            // scale (the solve runs on centred data and translates back): a weight w turns that
            // into a force w·u·|p|, which the stationarity cannot resolve below. For w ≫ ‖H‖
            // the optimum sits within rounding of q_i (the interpolation limit) and this is
            // what remains of w(p − q).
            let size = pv.iter().chain(qi).fold(at.length, |a, x| a.max(x.abs()));
            terms.rounding_data[i] = w * f64::EPSILON * size;
            terms.no_jump[i] = true;
            terms.stiffness = terms.stiffness.max(w.abs());
        }
    }

    /// A weight whose scaled value overflows — w·h³ beyond the doubles for spans h, which no
    /// solve can tell from an interpolated point (1e300 on spans of 1e100) — is refused naming
    /// it. Solved unscaled, such a problem came back with the interpolant's points but E = 0 (its
    /// divided differences underflowed) and a certificate of 0 (ROBUSTNESS.md item 39). (Weights
    /// that scale to 0 are left to the solve, which refuses H + W singular naming them.)
    fn penalty_weights(&self) -> Option<&[f64]> {
        Some(self.0)
    }

    fn rescale(&self, _: i32, knots: i32, into: &mut Problem) -> Result<(), Error> {
        let weights: Vec<f64> = self
            .0
            .iter()
            .map(|&w| times_power_of_two(w, -3 * knots))
            .collect();
        if let Some(index) = weights.iter().position(|w| !w.is_finite()) {
            return Err(Error::InvalidValue {
                field: "weights",
                index,
                value: self.0[index],
                reason: "this weight is beyond the doubles against the curve's stiffness (w·h^3 for the parameter spans h exceeds 1e308): no solve can tell it from an interpolated point; interpolate the point (constraint interpolate, or a ball of radius 0) or use a smaller weight",
            });
        }
        into.constraint = crate::Constraint::Smoothing(weights);
        Ok(())
    }

    /// The given weights (scaled as [`Kind::rescale`] scales them).
    fn multiplier_power(&self, _: usize, _: i32, knots: i32) -> i32 {
        -3 * knots
    }
}
