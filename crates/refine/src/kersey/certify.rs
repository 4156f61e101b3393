//! Certificates of a fixed-knot solution: energy, KKT residual, active set, Corollary 3.3.
//!
//! Everything here is recomputed from the points, the knots and the multipliers with the
//! matrix-free operator of [`super::operator`], independently of the solver that produced them.

use divdiff::{Knots, Points};

use super::operator;
use super::problem::Constraint;

/// A data vertex counts as active when |p_{i_k} − q_i| ≥ (1 − ACTIVE_REL_TOL) ε_i (balls) or
/// when n·p ≥ c − ACTIVE_REL_TOL · |n| · scale (half-spaces).
pub const ACTIVE_REL_TOL: f64 = 1e-7;

/// What one fixed-knot stage certifies.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Certificate {
    pub energy: f64,
    pub kkt_residual: f64,
    pub active: Vec<bool>,
    /// max |jmp_{i_k}| over inactive data vertices, relative; `None` when none is inactive.
    pub jmp_inactive: Option<f64>,
}

/// The scales of the relative residuals: `force` = ‖H‖_∞ · `length`, where `length` is the
/// largest distance of a vertex or a data point from the data's centroid. Hp, the multiplier
/// terms and the complementarity products are forces; feasibility violations are lengths.
pub(crate) struct Scale {
    pub length: f64,
    pub force: f64,
}

pub(crate) fn scale(knots: &Knots, p: &Points, q: &Points) -> Scale {
    let d = q.dim();
    let n = q.len() as f64;
    let mut c = vec![0.0; d];
    for x in q.iter() {
        for (ci, xi) in c.iter_mut().zip(x) {
            *ci += xi / n;
        }
    }
    let far = |pts: &Points| {
        pts.iter()
            .map(|x| x.iter().zip(&c).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max)
    };
    let length = far(p).max(far(q)).max(f64::MIN_POSITIVE);
    Scale {
        length,
        force: operator::h_norm_inf(knots) * length,
    }
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Certifies points `p` on `knots` for data `q` attached at `data_vertex`, with the
/// constraint's multipliers in the conventions of [`crate::Refinement::multipliers`].
pub(crate) fn certify(
    knots: &Knots,
    p: &Points,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
    multipliers: &[Vec<f64>],
) -> Certificate {
    let d = p.dim();
    let sc = scale(knots, p, q);
    let hp = operator::apply_h(knots, p);
    // Stationarity residual r = Hp + Σ (constraint gradient × multiplier), per vertex.
    let mut r = hp.clone();
    let mut comp: f64 = 0.0; // complementarity, forces
    let mut primal: f64 = 0.0; // feasibility violation, lengths
    let mut dual: f64 = 0.0; // negative multipliers, forces
    let n = q.len();
    let mut active = vec![false; n];
    for i in 0..n {
        let v = data_vertex[i];
        let (pv, qi) = (p.point(v), q.point(i));
        let m = &multipliers[i];
        match constraint {
            Constraint::Interpolate => {
                // The multiplier of p_v = q_i is the reaction λ_i = −(Hp)_v.
                for c in 0..d {
                    r[v * d + c] += m[c];
                }
                primal = primal.max(dist(pv, qi));
                active[i] = true;
            }
            Constraint::Balls(radii) if radii[i] == 0.0 => {
                for c in 0..d {
                    r[v * d + c] += m[c];
                }
                primal = primal.max(dist(pv, qi));
                active[i] = true;
            }
            Constraint::Balls(radii) => {
                let (eps, w, gap) = (radii[i], m[0], dist(pv, qi));
                for c in 0..d {
                    r[v * d + c] += w * (pv[c] - qi[c]);
                }
                primal = primal.max(gap - eps);
                dual = dual.max(-w * eps.max(gap));
                comp = comp.max((w * (eps - gap)).abs());
                active[i] = gap >= (1.0 - ACTIVE_REL_TOL) * eps;
            }
            Constraint::Smoothing(weights) => {
                let w = weights[i];
                for c in 0..d {
                    r[v * d + c] += w * (pv[c] - qi[c]);
                }
            }
            Constraint::HalfSpaces(sets) => {
                let mut any = false;
                for (j, h) in sets[i].iter().enumerate() {
                    let w = m[j];
                    let norm = h.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                    let g = (h.normal.iter().zip(pv).map(|(a, b)| a * b).sum::<f64>()
                        - h.offset)
                        / norm;
                    for c in 0..d {
                        r[v * d + c] += w * h.normal[c];
                    }
                    primal = primal.max(g);
                    dual = dual.max(-w * norm * sc.length);
                    comp = comp.max((w * norm * g).abs());
                    if g >= -ACTIVE_REL_TOL * sc.length {
                        any = true;
                    }
                }
                active[i] = any;
            }
        }
    }
    let stat = r.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let kkt = (stat / sc.force)
        .max(comp / sc.force)
        .max(dual / sc.force)
        .max(primal.max(0.0) / sc.length);
    // Corollary 3.3 / 3.6: jmp = ½Hp vanishes at inactive data vertices.
    let jmp_inactive = (0..n)
        .filter(|&i| !active[i] && !matches!(constraint, Constraint::Smoothing(_)))
        .map(|i| {
            let v = data_vertex[i];
            (0..d).fold(0.0f64, |a, c| a.max((0.5 * hp[v * d + c]).abs())) / sc.force
        })
        .reduce(f64::max);
    Certificate {
        energy: operator::energy(knots, p),
        kkt_residual: kkt,
        active,
        jmp_inactive,
    }
}
