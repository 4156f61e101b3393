//! The relative KKT residual: the method's progress measure and the certificate of what it
//! returns.
//!
//! A point (x, s, z) is optimal for minimize ½xᵀPx + qᵀx s.t. s = b − Ax ∈ K iff
//! P x + q + Aᵀz = 0, A x + s = b, s ∈ K, z ∈ K*, sᵀz = 0. With g = Px + q, the force scale
//! F = max(‖g‖∞, ‖Aᵀz‖∞, F₀) and the length scale L = max(‖b‖∞, ‖Ax‖∞, L₀) ([`crate::Scales`]):
//!
//! - **stationarity** ‖g + Aᵀz‖∞ / F;
//! - **primal** ‖Ax + s − b‖∞ / L for an iterate; for a returned point, whose slack is
//!   s = b − Ax, the distance of s to K (largest over blocks, Euclidean) / L;
//! - **dual cone** (returned points only) the distance of z to K* / F;
//! - **gap** |sᵀz| / max(|f(x)|, ε F L), f the objective: for a feasible point this bounds
//!   the relative excess f(x) − f* over the optimum (weak duality), down to the rounding level
//!   ε F L of an optimum with f* = 0;
//! - **total** the largest of these.
//!
//! This is the measure of Vandenberghe (2010, §7.2) with the norms taken in ∞ and the gap
//! relative to the objective rather than to the dual objective.

use crate::cone::{distance_to_cone, project_dual, Cones};
use crate::vector::inf_norm;

/// The relative residuals of a point (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Residuals {
    /// ‖Px + q + Aᵀz‖∞ / F.
    pub stationarity: f64,
    /// The primal infeasibility / L.
    pub primal: f64,
    /// The distance of z to the dual cone / F.
    pub dual_cone: f64,
    /// |sᵀz| / max(|f|, ε F L).
    pub gap: f64,
    /// The largest of the four (NaN if any is NaN).
    pub total: f64,
    /// F.
    pub force: f64,
    /// max(‖g‖∞, ‖Aᵀz‖∞): F without its floor F₀, the largest force the point actually carries
    /// (the polish stops relative to it, [`crate::polish`]).
    pub reaction: f64,
    /// L.
    pub length: f64,
}

impl Residuals {
    /// Folds the parts into `total`, keeping NaN.
    pub(crate) fn fold(mut self) -> Self {
        let parts = [self.stationarity, self.primal, self.dual_cone, self.gap];
        self.total = if parts.iter().any(|v| v.is_nan()) {
            f64::NAN
        } else {
            parts.iter().fold(0.0, |a, &v| a.max(v))
        };
        self
    }
}

/// The inputs of a residual evaluation, computed once by the caller.
pub(crate) struct Parts<'a> {
    pub g: &'a [f64],
    pub atz: &'a [f64],
    pub ax: &'a [f64],
    pub b: &'a [f64],
    pub s: &'a [f64],
    pub z: &'a [f64],
    pub objective: f64,
    pub floors: crate::Scales,
}

/// The residuals of an interior iterate (s, z in the interior; primal = ‖Ax + s − b‖∞ / L).
pub(crate) fn iterate(p: &Parts<'_>, cones: &Cones) -> Residuals {
    let (force, length, reaction) = scales(p);
    let mut stat: f64 = 0.0;
    for (a, b) in p.g.iter().zip(p.atz) {
        stat = stat.max((a + b).abs());
    }
    let mut primal: f64 = 0.0;
    for ((a, s), b) in p.ax.iter().zip(p.s).zip(p.b) {
        primal = primal.max((a + s - b).abs());
    }
    Residuals {
        stationarity: stat / force,
        primal: primal / length,
        dual_cone: 0.0,
        gap: gap(p, cones, force, length),
        total: 0.0,
        force,
        length,
        reaction,
    }
    .fold()
}

/// The certificate of a returned point: s = b − Ax (its distance to K is the primal part), z
/// as given (its distance to K* is the dual-cone part).
pub(crate) fn certificate(p: &Parts<'_>, cones: &Cones) -> Residuals {
    let (force, length, reaction) = scales(p);
    let mut stat: f64 = 0.0;
    for (a, b) in p.g.iter().zip(p.atz) {
        stat = stat.max((a + b).abs());
    }
    let (mut primal, mut dual): (f64, f64) = (0.0, 0.0);
    let mut buf = Vec::new();
    if let Some(m) = cones.uniform_soc() {
        // Every block Q^m: the same per block, without the per-block offsets and buffer.
        for (s, z) in p.s.chunks_exact(m).zip(p.z.chunks_exact(m)) {
            primal = primal.max(distance_to_cone(crate::Kind::SecondOrder, s));
            dual = dual.max(soc_dual_distance(z));
        }
    } else {
        for (bi, cone) in cones.blocks().iter().enumerate() {
            let r = cones.range(bi);
            primal = primal.max(distance_to_cone(cone.kind(), &p.s[r.clone()]));
            buf.clear();
            buf.extend_from_slice(&p.z[r.clone()]);
            project_dual(cone.kind(), &mut buf);
            let moved = buf
                .iter()
                .zip(&p.z[r])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            dual = dual.max(moved);
        }
    }
    Residuals {
        stationarity: stat / force,
        primal: primal / length,
        dual_cone: dual / force,
        gap: gap(p, cones, force, length),
        total: 0.0,
        force,
        length,
        reaction,
    }
    .fold()
}

/// The distance [`project_dual`] moves a block of Q^m (m ≤ 16) by, on the stack.
fn soc_dual_distance(z: &[f64]) -> f64 {
    let mut buf = [0.0; 16];
    let b = &mut buf[..z.len()];
    b.copy_from_slice(z);
    project_dual(crate::Kind::SecondOrder, b);
    b.iter()
        .zip(z)
        .map(|(a, c)| (a - c) * (a - c))
        .sum::<f64>()
        .sqrt()
}

/// (F, L, max(‖g‖∞, ‖Aᵀz‖∞)).
fn scales(p: &Parts<'_>) -> (f64, f64, f64) {
    let reaction = inf_norm(p.g).max(inf_norm(p.atz));
    let force = reaction.max(p.floors.force).max(f64::MIN_POSITIVE);
    let length = inf_norm(p.b)
        .max(inf_norm(p.ax))
        .max(p.floors.length)
        .max(f64::MIN_POSITIVE);
    (force, length, reaction)
}

fn gap(p: &Parts<'_>, cones: &Cones, force: f64, length: f64) -> f64 {
    let mut sz = 0.0;
    for (bi, cone) in cones.blocks().iter().enumerate() {
        if cone.kind() != crate::Kind::Zero {
            let r = cones.range(bi);
            sz += p.s[r.clone()]
                .iter()
                .zip(&p.z[r])
                .map(|(a, b)| a * b)
                .sum::<f64>();
        }
    }
    sz.abs()
        / p.objective
            .abs()
            .max(f64::EPSILON * force * length)
            .max(f64::MIN_POSITIVE)
}
