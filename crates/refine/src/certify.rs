//! Certificates of a fixed-knot solution: energy, KKT residual, active set, Corollary 3.3.
//!
//! Everything here is recomputed from the points, the knots and the multipliers with the
//! matrix-free operator of [`crate::operator`], independently of the solver that produced them.

use divdiff::Points;

use crate::operator::Stencil;
use crate::problem::Constraint;

/// A data vertex counts as active when |p_{i_k} − q_i| ≥ (1 − ACTIVE_REL_TOL) ε_i (balls) or
/// when n·p ≥ c − ACTIVE_REL_TOL · |n| · scale (half-spaces).
/// (Used for the exact solver.)
pub const ACTIVE_REL_TOL: f64 = 1e-7;
/// The same test for the paper's iteration, which approaches the sphere only to within its
/// iteration's accuracy (oscillating about it as the weights settle).
pub const PAPER_ACTIVE_REL_TOL: f64 = 1e-3;

/// A derivative-constraint force: the stencil L_c and the force z_c (Σ_c L_cᵀ z_c enters
/// the stationarity condition).
pub(crate) type StencilForce = (Vec<(usize, f64)>, Vec<f64>);

/// What one fixed-knot stage certifies.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Certificate {
    pub energy: f64,
    pub kkt_residual: f64,
    pub active: Vec<bool>,
    /// max |jmp_{i_k}| over inactive data vertices, relative; `None` when none is inactive.
    pub jmp_inactive: Option<f64>,
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Certifies points `p` for data `q` attached at the data vertices `data_vertex` (multiples of
/// one stride), with the constraint's multipliers in the conventions of
/// [`crate::Refinement::multipliers`]; `None` means "the reactions −(Hp)_{i_k}", the
/// multipliers of interpolation, computed here from the same Hp. Returns the certificate and the
/// multipliers.
///
/// The relative KKT residual is the largest of: the stationarity residual
/// ‖Hp + Σ (constraint gradient × multiplier)‖_∞, complementarity |w (slack)| and negative
/// multipliers, all divided by the force scale ‖H‖_∞ · δ (δ the largest coordinate step between
/// consecutive vertices: Hp is computed from such differences); the constraint violation divided by
/// the length scale L, the largest coordinate distance of a vertex or data point from the data's
/// centroid; and the duality gap Σ_i ½ w_i(ε_i² − |p_{i_k} − q_i|²) (Σ w_ij·slack_ij for
/// half-spaces) divided by E, which bounds the relative energy excess over the optimum.
// Eight inputs, each a distinct part of the claim being certified.
#[allow(clippy::too_many_arguments)]
pub(crate) fn certify(
    stencil: &Stencil,
    p: &Points,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
    multipliers: Option<Vec<Vec<f64>>>,
    active_tol: f64,
    extra: &[StencilForce],
) -> (Certificate, Vec<Vec<f64>>) {
    let d = p.dim();
    let n = q.len();
    let mut centroid = vec![0.0; d];
    for x in q.iter() {
        for (c, v) in centroid.iter_mut().zip(x) {
            *c += v / n as f64;
        }
    }
    let stride = if n > 1 {
        data_vertex[1]
    } else {
        p.len().max(1)
    };
    let pass = stencil.pass(p, stride, &centroid);
    let q_extent = q
        .iter()
        .map(|x| {
            x.iter()
                .zip(&centroid)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let length = pass.extent.max(q_extent).max(f64::MIN_POSITIVE);
    // Forces: Hp is a combination of differences of neighbouring vertices, computed to
    // rounding level ‖H‖_∞ · (largest step between vertices); the reactions and multiplier
    // terms present set the other scale.
    let force = (pass.h_norm * pass.step).max(f64::MIN_POSITIVE);
    let hp = &pass.data_gradient;
    let multipliers = multipliers.unwrap_or_else(|| {
        (0..n)
            .map(|i| hp[i * d..(i + 1) * d].iter().map(|x| -x).collect())
            .collect()
    });
    // Derivative constraints add Σ_c L_cᵀ z_c on their stencils (data and free vertices):
    // then stationarity needs the full Hp rather than the pass's summary.
    let extra_at: Option<(Vec<f64>, Vec<f64>)> = (!extra.is_empty()).then(|| {
        let mut e = vec![0.0; p.len() * d];
        for (st, z) in extra {
            for &(v, c) in st {
                for (k, zk) in z.iter().enumerate() {
                    e[v * d + k] += c * zk;
                }
            }
        }
        (stencil.apply_h(p).0, e)
    });
    // Stationarity at the data vertices: r = (Hp)_v + Σ (constraint gradient × multiplier).
    let mut stat = match &extra_at {
        None => pass.free_gradient,
        Some((full, e)) => {
            let mut m: f64 = 0.0;
            for j in 0..p.len() {
                if j % stride != 0 {
                    for k in 0..d {
                        m = m.max((full[j * d + k] + e[j * d + k]).abs());
                    }
                }
            }
            m
        }
    };
    let mut comp: f64 = 0.0; // complementarity, forces
    let mut primal: f64 = 0.0; // feasibility violation, lengths
    let mut dual: f64 = 0.0; // negative multipliers, forces
    let mut gap_sum: f64 = 0.0; // duality gap Σ (multiplier × slack), energies
    let mut active = vec![false; n];
    let mut r = vec![0.0; d];
    for i in 0..n {
        let v = data_vertex[i];
        let (pv, qi) = (p.point(v), q.point(i));
        let m = &multipliers[i];
        r.copy_from_slice(&hp[i * d..(i + 1) * d]);
        if let Some((_, e)) = &extra_at {
            for (rk, ek) in r.iter_mut().zip(&e[v * d..(v + 1) * d]) {
                *rk += ek;
            }
        }
        match constraint {
            Constraint::Interpolate => {
                // The multiplier of p_v = q_i is the reaction λ_i = −(Hp)_v.
                for (rc, mc) in r.iter_mut().zip(m) {
                    *rc += mc;
                }
                primal = primal.max(dist(pv, qi));
                active[i] = true;
            }
            Constraint::Balls(radii) if radii[i] == 0.0 => {
                for (rc, mc) in r.iter_mut().zip(m) {
                    *rc += mc;
                }
                primal = primal.max(dist(pv, qi));
                active[i] = true;
            }
            Constraint::Balls(radii) => {
                let (eps, gap) = (radii[i], dist(pv, qi));
                // Multipliers projected onto complementarity: a clearly inactive ball carries no
                // force, so an interior-point method's leftover multiplier there is charged to
                // stationarity (where a wrong active set still shows) rather than to a duality
                // gap that, relative to E, blows up when the optimum has E* = 0.
                // "Clearly inactive": the slack exceeds the tolerance in length units, so tiny
                // radii (ε ≲ tol·length) always keep their multiplier.
                let w = if eps - gap <= active_tol * length {
                    m[0]
                } else {
                    0.0
                };
                for c in 0..d {
                    r[c] += w * (pv[c] - qi[c]);
                }
                primal = primal.max(gap - eps);
                dual = dual.max(-w * eps.max(gap));
                comp = comp.max((w * (eps - gap)).abs());
                gap_sum += (0.5 * w * (eps * eps - gap * gap)).abs();
                active[i] = gap >= (1.0 - active_tol) * eps;
            }
            Constraint::Smoothing(weights) => {
                let w = weights[i];
                for c in 0..d {
                    r[c] += w * (pv[c] - qi[c]);
                }
            }
            Constraint::HalfSpaces(sets) => {
                let mut any = false;
                for (j, h) in sets[i].iter().enumerate() {
                    let norm = h.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                    let g = (h.normal.iter().zip(pv).map(|(a, b)| a * b).sum::<f64>() - h.offset)
                        / norm;
                    // Projected onto complementarity, as for balls.
                    let w = if g >= -active_tol * length { m[j] } else { 0.0 };
                    for (rc, nc) in r.iter_mut().zip(&h.normal) {
                        *rc += w * nc;
                    }
                    primal = primal.max(g);
                    dual = dual.max(-w * norm * length);
                    comp = comp.max((w * norm * g).abs());
                    gap_sum += (w * norm * g).abs();
                    if g >= -active_tol * length {
                        any = true;
                    }
                }
                active[i] = any;
            }
        }
        stat = r.iter().fold(stat, |a, x| a.max(x.abs()));
    }
    // The duality gap bounds E(p) − E* for a feasible p; relative to E (or, for E ≈ 0, to the
    // rounding level of the force scale times the length scale).
    let gap_rel = gap_sum / pass.energy.max(f64::EPSILON * force * length);
    let kkt = (stat / force)
        .max(comp / force)
        .max(dual / force)
        .max(primal.max(0.0) / length)
        .max(gap_rel);
    // Corollary 3.3 / 3.6: jmp = ½Hp vanishes at inactive data vertices.
    let jmp_inactive = (0..n)
        .filter(|&i| !active[i] && !matches!(constraint, Constraint::Smoothing(_)))
        .map(|i| (0..d).fold(0.0f64, |a, c| a.max((0.5 * hp[i * d + c]).abs())) / force)
        .reduce(f64::max);
    (
        Certificate {
            energy: pass.energy,
            kkt_residual: kkt,
            active,
            jmp_inactive,
        },
        multipliers,
    )
}
