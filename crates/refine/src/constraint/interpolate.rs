//! Interpolation, Kersey (3.2): p_{i_k} = q_i at every data vertex.
//!
//! Rows: every data vertex fixed at its data point. Multiplier of point i: the reaction
//! λ_i = −(Hp)_{i_k} (less any derivative force at that vertex), so (Hp)_{i_k} + λ_i = 0.
//! Certificate: the reaction absorbs the force at the vertex exactly; the violation is
//! |p_{i_k} − q_i|. No common point (the data are distinct). Translation moves nothing but the
//! data.

use super::{At, Kind, Rows, Terms};
use crate::conic_problem::ConicSolution;
use crate::problem::Problem;
use crate::stage::FixedProblem;
use crate::Error;

/// The kind (no data of its own).
pub(crate) struct Interpolate;

impl Kind for Interpolate {
    fn validate(&self, _: &Problem) -> Result<(), Error> {
        Ok(())
    }

    fn linear(&self) -> bool {
        true
    }

    fn multiplier_overflow(&self) -> (&'static str, &'static str) {
        ("points", "the reaction at this point overflows (the data's slopes against their parameter spans are beyond the doubles); rescale the data or use another parametrization")
    }

    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error> {
        for (i, &v) in stage.data_vertex.iter().enumerate() {
            rows.problem.fix(v, stage.q.point(i))?;
        }
        Ok(())
    }

    fn multipliers(
        &self,
        stage: &FixedProblem<'_>,
        sol: &ConicSolution,
        rows: &Rows,
        hp: &[f64],
    ) -> Vec<Vec<f64>> {
        let forces = derivative_forces(stage, sol, rows);
        (0..stage.q.len())
            .map(|i| reaction(stage, &forces, hp, i))
            .collect()
    }

    fn certify(&self, at: &At<'_>, terms: &mut Terms) {
        fixed_points(at, terms, |_| true);
    }
}

/// The forces of the derivative constraints at every vertex, Σ_c L_cᵀ z_c (N × d; empty
/// without derivative constraints): gathered once, so that each data point's reaction reads its
/// vertex instead of scanning every constraint (which made the multipliers of n/8 tangents
/// O(n²): 62 % of a 10⁵-point solve).
pub(crate) fn derivative_forces(
    stage: &FixedProblem<'_>,
    sol: &ConicSolution,
    rows: &Rows,
) -> Vec<f64> {
    if rows.derivative.is_empty() {
        return Vec::new();
    }
    let d = stage.q.dim();
    let mut out = vec![0.0; stage.knots.vertex_count() * d];
    for (c, stencil) in &rows.derivative {
        for &(u, coef) in stencil {
            for (o, z) in out[u * d..(u + 1) * d].iter_mut().zip(&sol.forces[*c]) {
                *o += coef * z;
            }
        }
    }
    out
}

/// The reaction at data point i's (fixed) vertex: −(Hp)_v less the derivative forces there
/// (`forces`, of [`derivative_forces`]).
pub(crate) fn reaction(stage: &FixedProblem<'_>, forces: &[f64], hp: &[f64], i: usize) -> Vec<f64> {
    let d = stage.q.dim();
    let v = stage.data_vertex[i];
    let mut f = super::reaction(hp, v, d);
    if !forces.is_empty() {
        for (fc, z) in f.iter_mut().zip(&forces[v * d..(v + 1) * d]) {
            *fc -= z;
        }
    }
    f
}

/// Certificate terms of the fixed data points (those `fixed(i)` selects): the multiplier is
/// the reaction, the violation |p_{i_k} − q_i|; always active.
pub(crate) fn fixed_points(at: &At<'_>, terms: &mut Terms, fixed: impl Fn(usize) -> bool) {
    let d = at.q.dim();
    let n = at.data_vertex.len();
    // Every point fixed (interpolation) with reactions of d components each: flat passes over
    // the n × d arrays (a row at a time was ~20 ns per point of a 10⁵-point certificate).
    if at.multipliers.width() == Some(d) && (0..n).all(&fixed) {
        for (f, m) in terms.force_data.iter_mut().zip(at.multipliers.values()) {
            *f += m;
        }
        let violation = banded::vector::max_dist(at.data_points, at.q.coords(), d);
        terms.primal = terms.primal.max(violation);
        terms.active.fill(true);
        return;
    }
    for i in 0..n {
        if !fixed(i) {
            continue;
        }
        let m = &at.multipliers[i];
        for (f, mc) in terms.force_data[i * d..(i + 1) * d].iter_mut().zip(m) {
            *f += mc;
        }
        terms.primal = terms
            .primal
            .max(super::dist(at.data_point(i), at.q.point(i)));
        terms.active[i] = true;
    }
}
