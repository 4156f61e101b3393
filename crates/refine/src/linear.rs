//! The linear fixed-knot problems: interpolation (3.3) and smoothing (3.6) — one banded solve,
//! exact to rounding — and the banded system H ⊗ I_d they share with the paper's iteration.

use divdiff::Points;
use energy::{Hessian, System};

use crate::stage::{FixedProblem, FixedSolution};
use crate::Error;

/// The system H ⊗ I_d of the Hessian `h` (its bands moved in).
pub(crate) fn hessian_system(h: Hessian, dim: usize) -> Result<System, Error> {
    let topology = h.topology();
    let (d0, d1, d2) = h.into_bands();
    Ok(System::from_bands(topology, d0, d1, d2, dim)?)
}

/// The weight from which smoothing is interpolation to rounding: w ≥ ‖H‖_∞/ε. At the optimum
/// w(p_{i_k} − q_i) = −(Hp)_{i_k}, and |Hp| ≤ ‖H‖_∞ L (H annihilates constants; L the extent
/// about the centroid), so |p_{i_k} − q_i| ≤ ε L: the vertex is q_i to rounding, and fixing it
/// there is exact to the certificate's stationarity allowance w·ε·L (`constraint/smoothing.rs`)
/// while it keeps w·q (1e300 × 1e10) from overflowing and the factorization well scaled.
pub(crate) fn stiff_weight(h: &Hessian) -> f64 {
    let (d0, d1, d2) = h.bands();
    let m = |b: &[f64]| b.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    (m(d0) + 2.0 * m(d1) + 2.0 * m(d2)) / f64::EPSILON
}

/// Interpolation at the data vertices whose `fixed` flag is set, plus weights `w` (0 = none) at
/// the others: (H + W)p = W q̃ with p_v = q_i at fixed data vertices (3.3), (3.5), (3.6).
pub(crate) fn linear(fp: &FixedProblem<'_>, fixed: &[bool], w: &[f64]) -> Result<Points, Error> {
    let n_vert = fp.knots.vertex_count();
    let d = fp.q.dim();
    let h = Hessian::new(fp.knots);
    let stiff = stiff_weight(&h);
    let mut sys = hessian_system(h, d)?;
    let mut rhs = vec![0.0; n_vert * d];
    for (i, &v) in fp.data_vertex.iter().enumerate() {
        let qi = fp.q.point(i);
        if fixed[i] || w[i] >= stiff {
            sys.fix(v)?;
            rhs[v * d..(v + 1) * d].copy_from_slice(qi);
        } else if w[i] > 0.0 {
            sys.add_weight(v, w[i])?;
            for c in 0..d {
                rhs[v * d + c] = w[i] * qi[c];
            }
        }
    }
    let f = sys.factor()?;
    f.solve_flat(&mut rhs)?;
    Ok(Points::new(d, rhs)?)
}

/// Interpolation (3.3) at every data vertex: the closed forms of [`crate::uniform`] on the knots
/// of the split, else the fused banded solver of [`crate::fast`].
pub(crate) fn interpolate(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    if fp.uniform_spans {
        return Ok(FixedSolution::new(
            crate::uniform::interpolate(fp.knots, fp.q, fp.stride)?,
            None,
            1,
        ));
    }
    let p = crate::fast::interpolate(fp.knots, fp.q, fp.stride)?;
    Ok(FixedSolution::new(p, None, 1))
}

/// The linear problems of [`crate::strategy`]: interpolation (also balls of radius 0 at every
/// point) and smoothing, without derivative constraints.
pub(crate) fn solve(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    use crate::constraint::Constraint;
    let n = fp.q.len();
    match fp.constraint {
        Constraint::Smoothing(w) => Ok(FixedSolution::new(
            linear(fp, &vec![false; n], w)?,
            Some(w.iter().map(|&x| vec![x]).collect()),
            1,
        )),
        _ => interpolate(fp),
    }
}
