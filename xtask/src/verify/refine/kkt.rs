//! The KKT conditions of Kersey's fixed-knot problems, recomputed by the case from the returned
//! points and multipliers with `divdiff` only — never the solver's self-reported residual.
//!
//! For a refinement p on knots t with data vertices i_k and multipliers w as documented on
//! [`refine::Refinement::multipliers`], with Hp = 2·jmp (Corollary 2.2, jmp from
//! `divdiff::jumps`, verified against the definition in `kersey/cor2.2/…`):
//! - **stationarity**: (Hp)_j = 0 at every vertex that carries no data constraint, and at
//!   i_k: (Hp)_{i_k} + w_i(p_{i_k} − q_i) = 0 (balls (3.5), smoothing (3.6)),
//!   (Hp)_{i_k} + Σ_j w_ij n_ij = 0 (half-spaces (3.8)); relative to the force scale
//!   F = max(max_j |(Hp)_j|, R / 1e-9): the largest reaction, but no smaller than the scale at
//!   which the rounding level R = 16 ε (‖H‖_∞ + w_max) max_j |p_j| is 1e-9 of it. R bounds what
//!   rounding alone leaves: evaluating 2·jmp from points of size |p| errs by up to ε‖H‖_∞|p|
//!   (the slopes err by 2ε|p|/h, and Hp = 2·jmp divides three differences of them by h², as the
//!   row (1, −4, 6, −4, 1)/h³ of H does), and a backward-stable banded solve of the system
//!   (H + W)p = Wq̃ leaves a residual of a few (bandwidth + 1) ε‖H + W‖|p| more in any of its
//!   rows, free vertices' included. W holds the constraints' stiffness: a ball's multiplier or
//!   a smoothing weight w_i at its data vertex (its force w_i(p_{i_k} − q_i) is linear in p with
//!   that slope; half-spaces add none), so w_max, the largest, joins ‖H‖_∞. A residual below R
//!   cannot be told from 0. Where the reactions are far above rounding the scale is the largest
//!   reaction — much stricter than the solver's own certificate, which divides by
//!   ‖H‖_∞ · max step. (Without w_max, `hard.rs`'s draws asked stiff constraints for less than
//!   rounding leaves: ball multipliers of 10⁸ against ‖H‖_∞ = 1.8·10⁷ left a free vertex at
//!   3·10⁻⁹ of the force scale, and weights of 10¹⁰ ‖H‖_∞ a data vertex at 8·10⁻²). The floor
//!   is as wide as each vertex's own row: past 16 ε (r_j + w_max) max_j |p_j| at vertex j (r_j
//!   row j's sum of |H|) the residual also counts against the largest reaction with no floor
//!   (as in the certificate; a floor set by the stiffest row once passed a curve 1.6e7 times
//!   above the optimal energy, `tests/tests/optimality.rs`);
//! - **primal feasibility**: |p_{i_k} − q_i| ≤ ε_i, n_ij·p_{i_k} ≤ c_ij, p_{i_k} = q_i
//!   (violation relative to L, the largest coordinate distance of a data point from the data's
//!   centroid);
//! - **dual feasibility**: w ≥ 0 (a negative multiplier times ε_i resp. |n_ij|, over F);
//! - **complementarity** as the Lagrangian duality gap Σ ½w_i(ε_i² − |p_{i_k} − q_i|²) resp.
//!   Σ w_ij (c_ij − n_ij·p_{i_k}), relative to E: with stationarity exact it bounds the relative
//!   energy excess E(p) − E* (weak duality of the convex problem).

use divdiff::{jumps, Points};
use refine::{Constraint, Problem, Refinement};

use super::super::worst;
use crate::verify::kersey_defs::{dot, norm2, sub};

/// The four parts of the recomputed certificate (all relative, see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct Kkt {
    pub stationarity: f64,
    pub feasibility: f64,
    pub dual: f64,
    pub gap: f64,
}

impl Kkt {
    /// The largest part (NaN if any is NaN).
    pub fn worst(&self) -> f64 {
        worst([self.stationarity, self.feasibility, self.dual, self.gap])
    }

    /// Part-wise worst of two certificates.
    pub fn max(self, o: Kkt) -> Kkt {
        Kkt {
            stationarity: worst([self.stationarity, o.stationarity]),
            feasibility: worst([self.feasibility, o.feasibility]),
            dual: worst([self.dual, o.dual]),
            gap: worst([self.gap, o.gap]),
        }
    }

    pub fn show(&self) -> String {
        format!(
            "stationarity {:.1e}, feasibility {:.1e}, dual {:.1e}, gap {:.1e}",
            self.stationarity, self.feasibility, self.dual, self.gap
        )
    }
}

/// L: the largest coordinate distance of a data point from the data's centroid.
pub fn extent(q: &Points) -> f64 {
    let n = q.len() as f64;
    let d = q.dim();
    let centroid: Vec<f64> = (0..d)
        .map(|c| q.iter().map(|x| x[c]).sum::<f64>() / n)
        .collect();
    worst(
        q.iter()
            .flat_map(|x| x.iter().zip(&centroid).map(|(a, b)| (a - b).abs())),
    )
}

/// The relative level at which the rounding allowance R sets the force scale (the KKT
/// tolerance of the cases).
const KKT_SCALE: f64 = super::KKT_TOL;

/// 16 ε ‖H‖_∞ max_j |p_j|: the level of a residual of Hp that rounding alone leaves without
/// constraint stiffness (see the module docs).
pub fn rounding_level(knots: &divdiff::Knots, points: &Points) -> f64 {
    16.0 * f64::EPSILON * h_norm(knots) * magnitude(points)
}

/// max_j |p_j|_∞.
fn magnitude(points: &Points) -> f64 {
    worst(points.coords().iter().map(|x| x.abs()))
}

/// w_max of the module docs: the largest ball multiplier (as returned) or smoothing weight (as
/// given); 0 for interpolation and half-spaces.
fn stiffness(problem: &Problem, r: &Refinement) -> f64 {
    match &problem.constraint {
        Constraint::Balls(_) => worst(r.multipliers.iter().flatten().map(|w| w.max(0.0))),
        Constraint::Smoothing(w) => worst(w.iter().copied()),
        Constraint::Interpolate | Constraint::HalfSpaces(_) => 0.0,
    }
}

/// ‖H‖_∞, the largest absolute row sum of H.
fn h_norm(knots: &divdiff::Knots) -> f64 {
    worst(row_sums(knots))
}

/// The absolute row sums of H, from its bands.
fn row_sums(knots: &divdiff::Knots) -> Vec<f64> {
    let h = energy::Hessian::new(knots);
    let (d0, d1, d2) = h.bands();
    let n = d0.len();
    let closed = knots.is_closed();
    let mut rows = vec![0.0; n];
    for j in 0..n {
        rows[j] += d0[j].abs();
        for (band, step) in [(d1, 1), (d2, 2)] {
            if !closed && j + step >= n {
                continue;
            }
            let k = (j + step) % n;
            rows[j] += band[j].abs();
            rows[k] += band[j].abs();
        }
    }
    rows
}

/// Recomputes the KKT conditions of stage 0 of `r` (no further levels, no derivative
/// constraints: their multipliers are not reported).
pub fn recompute(problem: &Problem, r: &Refinement) -> anyhow::Result<Kkt> {
    anyhow::ensure!(
        problem.levels == 0,
        "the multipliers belong to stage 0; recompute on a problem without further levels"
    );
    anyhow::ensure!(
        problem.tangents.is_none() && problem.boundary == refine::Boundary::Natural,
        "derivative-constraint multipliers are not reported; compare with Clarabel instead"
    );
    let q = &problem.points;
    let d = q.dim();
    let hp: Vec<Vec<f64>> = jumps(&r.knots, &r.points)?
        .iter()
        .map(|j| j.iter().map(|x| 2.0 * x).collect())
        .collect();
    // R = 16 ε (‖H‖_∞ + w_max) max|p|, and each row's own level 16 ε (r_j + w_max) max|p|
    // (r_j row j's sum of |H|; ‖H‖_∞ the largest).
    let rows = row_sums(&r.knots);
    let (w_max, size) = (stiffness(problem, r), magnitude(&r.points));
    let level = |row: f64| 16.0 * f64::EPSILON * (row + w_max) * size;
    let rounding = level(worst(rows.iter().copied()));
    let hp_max = worst(hp.iter().flat_map(|v| v.iter().map(|x| x.abs())));
    let force = hp_max.max(rounding / KKT_SCALE).max(f64::MIN_POSITIVE);
    // The stationarity of vertex j's residual: over the force scale, and past its own row's
    // level over the largest reaction with no floor (module docs).
    let stationarity = |j: usize, residual: &[f64]| {
        let largest = worst(residual.iter().map(|x| x.abs()));
        worst([
            largest / force,
            (largest - level(rows[j])).max(0.0) / hp_max.max(f64::MIN_POSITIVE),
        ])
    };
    let l = extent(q).max(f64::MIN_POSITIVE);
    let e = r.energy.max(f64::MIN_POSITIVE);
    let mut data = vec![false; r.points.len()];
    for &v in &r.data_vertex {
        data[v] = true;
    }
    let mut k = Kkt {
        stationarity: worst(
            hp.iter()
                .enumerate()
                .filter(|&(j, _)| !data[j])
                .map(|(j, v)| stationarity(j, v)),
        ),
        ..Kkt::default()
    };
    let mut gap = 0.0;
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let (p, qi) = (r.points.point(v), q.point(i));
        let diff = sub(p, qi);
        let mut residual = hp[v].clone();
        match &problem.constraint {
            Constraint::Interpolate => {
                k.feasibility = worst([k.feasibility, worst(diff.iter().map(|x| x.abs())) / l]);
                residual = vec![0.0; d];
            }
            Constraint::Balls(eps) if eps[i] == 0.0 => {
                k.feasibility = worst([k.feasibility, worst(diff.iter().map(|x| x.abs())) / l]);
                residual = vec![0.0; d];
            }
            Constraint::Balls(eps) => {
                let w = r.multipliers[i][0];
                let dist = norm2(&diff).sqrt();
                for (x, y) in residual.iter_mut().zip(&diff) {
                    *x += w * y;
                }
                k.feasibility = worst([k.feasibility, (dist - eps[i]) / l]);
                k.dual = worst([k.dual, -w * eps[i] / force]);
                gap += 0.5 * w * (eps[i] * eps[i] - dist * dist);
            }
            Constraint::Smoothing(w) => {
                for (x, y) in residual.iter_mut().zip(&diff) {
                    *x += w[i] * y;
                }
            }
            Constraint::HalfSpaces(sets) => {
                anyhow::ensure!(
                    r.multipliers[i].len() == sets[i].len(),
                    "point {i}: {} multipliers for {} half-spaces",
                    r.multipliers[i].len(),
                    sets[i].len()
                );
                for (h, &w) in sets[i].iter().zip(&r.multipliers[i]) {
                    let nn = norm2(&h.normal).sqrt();
                    for (x, nc) in residual.iter_mut().zip(&h.normal) {
                        *x += w * nc;
                    }
                    let g = dot(&h.normal, p) - h.offset;
                    k.feasibility = worst([k.feasibility, g / nn / l]);
                    k.dual = worst([k.dual, -w * nn / force]);
                    gap += w * -g;
                }
            }
        }
        k.stationarity = worst([k.stationarity, stationarity(v, &residual)]);
    }
    k.gap = gap.abs() / e;
    Ok(k)
}
