//! The condensed backend: only data vertices carry constraints, so the free vertices are
//! eliminated exactly and the variables are the constrained data vertices alone.
//!
//! # The conic program
//!
//! With the data vertices of a set W at y ([`Condensation`], taken onto W's vertices; the other
//! data vertices are free vertices of longer spans), the energy minimized over the free
//! vertices is E(y) = ½ Σ_coords (Ky)ᵀ T⁻¹ (Ky), T symmetric positive definite tridiagonal and K
//! tridiagonal (both cyclic for a closed curve). The program is
//!
//!   minimize ½ yᵀ Q y,  Q = Kᵀ T⁻¹ K ⊗ I_d,  s.t. each point's rows s_j = b_j − A_j y_j ∈ K_j,
//!
//! over the points of W that are not interpolated (an interpolated point, radius 0, keeps
//! y_j = q_j and folds into the linear term): a ball |y − q| ≤ ε is (ε, q − y) ∈ Q^{d+1}
//! (A_j = (0; −I)… with b = (ε, q): s = (ε, q − y)); a polytope ∩{n̂_k·y ≤ ĉ_k} (unit normals) is
//! ĉ − N̂ y ≥ 0. Q is dense but applied in O(|W| d) (one tridiagonal solve).
//!
//! # The Newton systems
//!
//! P + AᵀΘA = Q + D with D block diagonal, D_j = A_jᵀΘ_jA_j (d × d per point), is solved
//! through the augmented form [[D, Kᵀ], [K, −T]]: (T + K D⁻¹ Kᵀ) w = K D⁻¹ r, then
//! Δy = D⁻¹(r − Kᵀ w) — a block pentadiagonal (cyclic) positive definite system of |W| blocks of
//! size d (`banded::BlockBand<2>`, bordered for a closed curve). D vanishes along inactive constraints, where D⁻¹ would make
//! T + K D⁻¹ Kᵀ as ill-conditioned as D⁻¹ is large (K annihilates constants), so D + ρI is
//! inverted (ρ = [`REGULARIZATION`] × max Q_jj, grown by [`REGULARIZATION_GROWTH`] while the
//! matrix does not factor) and the method's iterative refinement against Q + D removes ρ
//! ([`conic::KktSystem::factor_is_exact`] is false). D + ρI is inverted without cancellation
//! from its structure: for a ball's Nesterov–Todd weight D = η⁻²(I + 2 w̄₁w̄₁ᵀ) per eigenspace;
//! for a polytope D = Σ θ_k n̂_k n̂_kᵀ in an orthonormal basis built from the normals in order of
//! decreasing θ (each large θ_k then enters one new diagonal entry and no Schur complement
//! subtracts it from a small one).
//!
//! The active-set polish's weights ([`conic::polish`]: an active ball's c I + p ūūᵀ, c its
//! curvature and p the stiff penalty on its normal; a polytope's penalties on its active faces; 0
//! on an inactive point) take the condensed route too, c floored at [`POLISH_FLOOR`] × Q_jj in
//! the inverse (refined away). When they are indefinite (a multiplier turned negative), or when a
//! solve was too inexact ([`conic::KktSystem::escalate`]: with balls the repeated step after the
//! first time, every system after the second; with polytopes every system after the first), the
//! systems take the full-vertex elimination instead: H ⊗ I_d + D at W's data vertices, whose
//! Schur complement on them is Q + D, factored by [`energy::System`] in O(N) with no D⁻¹.

// The per-point kernels index several small arrays by the same row/column.
#![allow(clippy::needless_range_loop)]

use banded::vector::dot;
use conic::{BlockWeight, Cone, Cones, KktSystem, Scales, Weights};
use divdiff::{Knots, Points};
use energy::{Factor, System};

use super::inverse::{ball_inverse, faces_inverse, faces_inverse_fixed};
use crate::fast::Condensation;
use crate::operator::Stencil;
use crate::Error;
use banded::{BlockBand, BlockFactor, FactorOptions, SymBand, SymBandFactor, Topology};

/// ρ of the module docs, relative to the largest diagonal entry of Q.
pub(crate) const REGULARIZATION: f64 = 1e-13;
/// Factor by which ρ grows when T + K (D + ρI)⁻¹ Kᵀ does not factor (a pivot lost to the
/// cancellation).
pub(crate) const REGULARIZATION_GROWTH: f64 = 100.0;
/// Largest ρ tried, relative to the largest diagonal entry of Q.
pub(crate) const MAX_REGULARIZATION: f64 = 1e-7;
/// The polish's weight on a ball (its curvature across the normal, 0 on an inactive ball) is
/// inverted as at least this times the point's Q_jj: at a point the polish leaves free, D⁻¹ of
/// 1/ρ made T + K D⁻¹ Kᵀ lose its T entirely, and the cancellation in D⁻¹(r − Kᵀw) of the
/// penalty's large right-hand side at its active neighbours grows as 1/(this): first solves off
/// by 10⁴ relative at 1e-8 (the noisy star at n = 10⁵, a step after 22 constraints left the set),
/// 10¹ at 1e-5, each followed by a full-vertex escalation at 1e-8 only. The refinement against
/// the exact Q + D removes the floor at a rate of about this where the free points are isolated
/// among active ones.
pub(crate) const POLISH_FLOOR: f64 = 1e-5;

/// The balls' start ([`Condensed::ball_start`]) keeps each multiplier at least this times the
/// largest force: a huge ball (a bound far beyond the data) would otherwise start with a
/// multiplier at the rounding level of the others.
const START_FORCE_RANGE: f64 = 1e-6;

/// The median of `v` (the upper one of an even count; `None` when empty or a NaN is present).
fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() || v.iter().any(|x| x.is_nan()) {
        return None;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// One face n̂·y ≤ ĉ of a polytope, with unit normal and the original normal's length (the
/// multipliers of (3.8) are for the original normals).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Face {
    /// n̂ = n / |n|.
    pub normal: Vec<f64>,
    /// ĉ = c / |n|.
    pub offset: f64,
    /// |n|.
    pub norm: f64,
}

/// The set a data point must lie in.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PointSet {
    /// p = q (interpolation, a ball of radius 0).
    Fixed,
    /// |p − q| ≤ radius, radius > 0.
    Ball(f64),
    /// Every face (a nonempty list).
    Faces(Vec<Face>),
}

/// How the last factorization eliminated the free vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    /// T + K (D + ρI)⁻¹ Kᵀ.
    Condensed,
    /// H ⊗ I + D on all vertices.
    Full,
}

/// The condensed backend (module docs) for the points of one working set.
pub(crate) struct Condensed<'a> {
    cond: &'a Condensation,
    knots: &'a Knots,
    d: usize,
    /// The sets of the condensed points (index j = position in `cond.vertices`).
    sets: Vec<PointSet>,
    /// The data of the condensed points (cond.n × d).
    q: Vec<f64>,
    /// The condensed point of each variable.
    var_point: Vec<usize>,
    /// The row offset of each variable's block (one block per variable).
    cones: Cones,
    b: Vec<f64>,
    row_start: Vec<usize>,
    /// Q's machinery: T's factor and buffers.
    t: SymBandFactor<1>,
    u: Vec<f64>,
    s: Vec<f64>,
    y: Vec<f64>,
    g: Vec<f64>,
    /// The Newton system T + K D⁻¹ Kᵀ (S = T ⊗ I_d plus d × d blocks, cyclic for a closed
    /// curve), its factor, and the rows of K touching each point.
    sm: BlockBand<2>,
    sm_factor: BlockFactor<2>,
    touching: Vec<[(usize, f64); 3]>,
    ntouch: Vec<usize>,
    /// (D + ρI)⁻¹ per condensed point (d × d; 0 at an interpolated point, which does not move)
    /// and D per variable (d × d).
    dinv: Vec<f64>,
    dmat: Vec<f64>,
    /// Every variable is a ball (apply_a / apply_at take their fixed-size kernels).
    balls: bool,
    /// Work space: the face weights θ of one point.
    theta: Vec<f64>,
    /// Every condensed point is a variable, in order (x is the condensed y itself).
    identity: bool,
    /// What the interpolated points of `y` hold: their data (`Some(true)`), zero
    /// (`Some(false)`), or not yet written.
    y_fixed: Option<bool>,
    route: Route,
    /// The next factorization takes the full-vertex route (after a first escalation).
    once: bool,
    /// Escalations so far ([`Condensed::exact`]).
    escalations: usize,
    full: Option<(System, Option<Factor>)>,
    rhs_full: Vec<f64>,
    /// Q_jj estimates per condensed point, their largest, and ρ.
    qdiag: Vec<f64>,
    qmax: f64,
    rho: f64,
    scales: Scales,
    /// Work vectors (cond.n × d).
    wy: Vec<f64>,
    wk: Vec<f64>,
    wkt: Vec<f64>,
}

impl<'a> Condensed<'a> {
    /// The backend for the condensed points of `cond` (on `knots`), with data `q` (cond.n × d)
    /// and `sets` (one per condensed point; no point may have an empty polytope).
    ///
    /// # Errors
    /// [`Error::Energy`] (`Singular`) naming a vertex if T does not factor (impossible for
    /// valid knots; reported rather than assumed).
    pub(crate) fn new(
        cond: &'a Condensation,
        knots: &'a Knots,
        q: Vec<f64>,
        sets: Vec<PointSet>,
        d: usize,
    ) -> Result<Self, Error> {
        let n = cond.n;
        let size = cond.len();
        let closed = cond.closed;
        let singular = |j: usize| {
            Error::from(energy::Error::Singular {
                vertex: cond.vertices[j.min(n - 1)],
            })
        };
        let topology = if closed {
            Topology::Cyclic
        } else {
            Topology::Open
        };
        let mut tm = SymBand::<1>::zeros(size, topology);
        for j in 0..size {
            let _ = tm.add(j, j, cond.diag[j]);
            if closed || j + 1 < size {
                let _ = tm.add(j, (j + 1) % size, cond.off[j]);
            }
        }
        let t = tm
            .factor_with(&cholesky())
            .map_err(|e| singular(cond.first + pivot_row(&e)))?;
        let mut touching: Vec<[(usize, f64); 3]> = vec![[(usize::MAX, 0.0); 3]; n];
        let mut ntouch = vec![0usize; n];
        for (j, kr) in cond.krows.iter().enumerate() {
            for (tt, &kv) in kr.iter().enumerate() {
                let c = cond.col(j, tt);
                touching[c][ntouch[c]] = (j, kv);
                ntouch[c] += 1;
            }
        }
        // Q_jj = Σ_r K_rj² (T⁻¹)_rr, estimated with 1/T_rr.
        let mut qdiag = vec![0.0; n];
        for (j, kr) in cond.krows.iter().enumerate() {
            for (tt, &kv) in kr.iter().enumerate() {
                qdiag[cond.col(j, tt)] += kv * kv / cond.diag[j];
            }
        }
        let qmax = qdiag
            .iter()
            .fold(0.0f64, |a, &v| a.max(v))
            .max(f64::MIN_POSITIVE);
        let mut var_point = Vec::new();
        let mut cone_list = Vec::new();
        let mut b = Vec::new();
        let mut row_start = Vec::new();
        for (j, set) in sets.iter().enumerate() {
            match set {
                PointSet::Fixed => continue,
                PointSet::Ball(r) => {
                    row_start.push(b.len());
                    b.push(*r);
                    b.extend_from_slice(&q[j * d..(j + 1) * d]);
                    cone_list.push(Cone::SecondOrder(d + 1));
                }
                PointSet::Faces(faces) => {
                    row_start.push(b.len());
                    b.extend(faces.iter().map(|f| f.offset));
                    cone_list.push(Cone::Nonnegative(faces.len()));
                }
            }
            var_point.push(j);
        }
        let cones = Cones::new(cone_list).map_err(|_| Error::InvalidConstraint {
            constraint: 0,
            reason: "a data point with an empty set in the working set",
        })?;
        // Scales: forces ‖Q‖ δ (δ the largest coordinate step between consecutive condensed
        // points: Qy is computed from such differences), lengths the data's extent about
        // their centroid.
        let mut step: f64 = 0.0;
        let mut centroid = vec![0.0; d];
        for j in 0..n {
            for c in 0..d {
                centroid[c] += q[j * d + c] / n as f64;
            }
            let k = if j + 1 == n { 0 } else { j + 1 };
            if k > j || closed {
                for c in 0..d {
                    step = step.max((q[k * d + c] - q[j * d + c]).abs());
                }
            }
        }
        let mut length: f64 = 0.0;
        for j in 0..n {
            for c in 0..d {
                length = length.max((q[j * d + c] - centroid[c]).abs());
            }
        }
        let nv = var_point.len();
        let balls = var_point
            .iter()
            .all(|&j| matches!(sets[j], PointSet::Ball(_)));
        // S = T ⊗ I_d + K D⁻¹ Kᵀ: the scalar part T once, the blocks at each factorization.
        let mut sm = BlockBand::zeros(size, d, topology).map_err(|_| singular(0))?;
        for j in 0..size {
            let _ = sm.add_scalar(j, j, cond.diag[j]);
            if closed || j + 1 < size {
                let _ = sm.add_scalar(j, (j + 1) % size, cond.off[j]);
            }
        }
        Ok(Condensed {
            cond,
            knots,
            d,
            sets,
            q,
            var_point,
            cones,
            b,
            row_start,
            t,
            u: vec![0.0; size * d],
            s: vec![0.0; size * d],
            y: vec![0.0; n * d],
            g: vec![0.0; n * d],
            sm,
            sm_factor: BlockFactor::default(),
            touching,
            ntouch,
            dinv: vec![0.0; n * d * d],
            dmat: vec![0.0; nv * d * d],
            balls,
            theta: Vec::new(),
            identity: nv == n,
            y_fixed: None,
            route: Route::Condensed,
            once: false,
            escalations: 0,
            full: None,
            rhs_full: Vec::new(),
            qdiag,
            qmax,
            rho: REGULARIZATION * qmax,
            scales: Scales {
                force: qmax * step.max(f64::MIN_POSITIVE),
                length,
            },
            wy: vec![0.0; n * d],
            wk: vec![0.0; size * d],
            wkt: vec![0.0; n * d],
        })
    }

    /// The condensed point of each variable (the interpolated points are not variables).
    pub(crate) fn variables(&self) -> &[usize] {
        &self.var_point
    }

    /// The rows of variable `v`'s block.
    pub(crate) fn rows(&self, v: usize) -> std::ops::Range<usize> {
        self.row_start[v]..self.row_start[v] + self.cones.blocks()[v].dim()
    }

    /// A point for the active-set polish from a known answer (the previous knot iteration's,
    /// Algorithm 4.1): x the given positions of the variables' points (d each, in variable
    /// order), s = b − A x = (ε, q − x) per ball, and z from the balls' multipliers `w` (one per
    /// condensed point, Kersey (3.5): w = z₀/ε): z = (wε, −wε s̄/|s̄|) where w > 0 and s̄ ≠ 0 —
    /// complementary to s when s is on its boundary, which is what the polish reads its active
    /// set from — and 0 elsewhere. `None` when a polytope is present.
    pub(crate) fn warm_solution(&self, x: Vec<f64>, w: &[f64]) -> Option<conic::Solution> {
        let d = self.d;
        let m = self.cones.rows();
        if x.len() != self.var_point.len() * d || w.len() != self.sets.len() {
            return None;
        }
        let (mut s, mut z) = (vec![0.0; m], vec![0.0; m]);
        for (v, &j) in self.var_point.iter().enumerate() {
            let PointSet::Ball(r) = self.sets[j] else {
                return None;
            };
            let rows = self.rows(v);
            s[rows.start] = r;
            for c in 0..d {
                s[rows.start + 1 + c] = self.q[j * d + c] - x[v * d + c];
            }
            let len = banded::vector::norm(&s[rows.start + 1..rows.end]);
            let z0 = w[j] * r;
            if z0 > 0.0 && z0.is_finite() && len > 0.0 {
                z[rows.start] = z0;
                for c in 0..d {
                    z[rows.start + 1 + c] = -z0 * s[rows.start + 1 + c] / len;
                }
            }
        }
        Some(conic::Solution {
            x,
            s,
            z,
            residuals: conic::Residuals::default(),
            objective: 0.0,
            iterations: 0,
            status: conic::Status::Converged,
            polished: false,
        })
    }

    /// The start of the method for balls alone: y = q, s = (ε_j, 0) (the centre of each cone),
    /// z = (μ/ε_j, 0) with μ = F̃ ε̃ (F̃ the median of the balls' forces |(Qq)_j|, ε̃ the median
    /// radius), kept within [1e-6 F, F] (F the largest force component of Qq, or ‖Q‖δ): strictly
    /// feasible, and on the central path (s_j ∘ z_j = μ e at every ball) with the multipliers of
    /// a typical ball. `None` when a polytope is present (its data point need not lie inside
    /// it).
    ///
    /// The earlier start, z = (F, 0) at every ball, put the complementarity of each ball at
    /// F ε_j: as spread as the radii, and set by the stiffest vertex's force. After a knot
    /// update makes the spans unequal it began at a residual of 196 where this one begins at 1
    /// (the Python bench's noisy star, n = 10⁴, k = 3: 14 iterations, now 11). Measured with the
    /// binary on 36 ball problems at n = 2000 and 10⁴ (the star with radii × 0.5 … 4, open, in
    /// R³, radii over five decades, the wavy circle, random walks; `knot_iterations` 0 and 3):
    /// 810 iterations in all against 883, none more; on the 633 ball problems of twelve
    /// `refine.py` sweep runs: 15 036 against 15 285, and one more answered (none fewer).
    pub(crate) fn ball_start(&mut self) -> Option<conic::Start> {
        let d = self.d;
        if self
            .var_point
            .iter()
            .any(|&j| !matches!(self.sets[j], PointSet::Ball(_)))
        {
            return None;
        }
        let x: Vec<f64> = self
            .var_point
            .iter()
            .flat_map(|&j| self.q[j * d..(j + 1) * d].to_vec())
            .collect();
        // The forces at every condensed point (the interpolated ones too).
        self.scatter(&x, true);
        self.apply_q();
        let f0 = self.g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let f = if f0 > 0.0 { f0 } else { self.scales.force };
        let radii: Vec<f64> = (0..self.var_point.len())
            .map(|v| self.b[self.rows(v).start])
            .collect();
        let forces: Vec<f64> = self
            .var_point
            .iter()
            .map(|&j| banded::vector::norm(&self.g[j * d..(j + 1) * d]))
            .collect();
        let typical = median(forces).filter(|&m| m > 0.0).unwrap_or(f);
        let mu = typical * median(radii.clone()).unwrap_or(0.0);
        let m = self.cones.rows();
        let (mut s, mut z) = (vec![0.0; m], vec![0.0; m]);
        for (v, &eps) in radii.iter().enumerate() {
            let r = self.rows(v);
            s[r.start] = eps;
            // (A radius of 0 has no interior: the test below refuses it.)
            // (max/min, not clamp: neither panics on a non-finite F.)
            z[r.start] = if eps > 0.0 {
                (mu / eps).max(START_FORCE_RANGE * f).min(f)
            } else {
                f
            };
        }
        // A cone's interior test squares its entries: a radius whose square underflows (ε of
        // 1e-260 against data of size 1e-100) is no interior start; the method's own start is.
        if s.iter()
            .chain(&z)
            .any(|&v| v != 0.0 && !(v * v).is_normal())
        {
            return None;
        }
        Some(conic::Start {
            x,
            sz: Some((s, z)),
        })
    }

    /// Scatters the variables into the condensed y (interpolated points at their data, or at 0
    /// for a direction).
    fn scatter(&mut self, x: &[f64], with_fixed: bool) {
        let d = self.d;
        if self.identity {
            self.y.copy_from_slice(x);
            return;
        }
        if self.y_fixed != Some(with_fixed) {
            for (j, set) in self.sets.iter().enumerate() {
                if *set == PointSet::Fixed {
                    let yj = &mut self.y[j * d..(j + 1) * d];
                    if with_fixed {
                        yj.copy_from_slice(&self.q[j * d..(j + 1) * d]);
                    } else {
                        yj.fill(0.0);
                    }
                }
            }
            self.y_fixed = Some(with_fixed);
        }
        for (v, &j) in self.var_point.iter().enumerate() {
            self.y[j * d..(j + 1) * d].copy_from_slice(&x[v * d..(v + 1) * d]);
        }
    }

    /// g = Q y (all condensed points) and E(y) = ½ yᵀQy; afterwards `self.s` = T⁻¹ K y.
    fn apply_q(&mut self) -> f64 {
        let d = self.d;
        self.cond.apply_k(&self.y, d, &mut self.u);
        self.s.copy_from_slice(&self.u);
        // (sizes fixed at construction: the solve cannot fail)
        let _ = self.t.solve_in_place(&mut self.s, d);
        self.cond.apply_kt(&self.s, d, &mut self.g);
        0.5 * dot(&self.u, &self.s)
    }

    /// Q y at the variables into `out`, E(y) returned, for the variables `x` (interpolated
    /// points at their data with `with_fixed`, else at 0).
    fn q_at_variables(&mut self, x: &[f64], with_fixed: bool, out: &mut [f64]) -> f64 {
        let d = self.d;
        if self.identity {
            // x is y: no scatter, Kᵀs straight into `out`.
            self.cond.apply_k(x, d, &mut self.u);
            self.s.copy_from_slice(&self.u);
            let _ = self.t.solve_in_place(&mut self.s, d);
            self.cond.apply_kt(&self.s, d, out);
            return 0.5 * dot(&self.u, &self.s);
        }
        self.scatter(x, with_fixed);
        let e = self.apply_q();
        for (v, &j) in self.var_point.iter().enumerate() {
            out[v * d..(v + 1) * d].copy_from_slice(&self.g[j * d..(j + 1) * d]);
        }
        e
    }

    /// Whether every factorization takes the full-vertex route: after the second escalation
    /// with balls, after the first with polytopes ([`KktSystem::escalate`]).
    fn exact(&self) -> bool {
        self.escalations >= if self.balls { 2 } else { 1 }
    }

    /// The refined curve for the variables x (data vertices of W at y, free vertices by the
    /// second pass of the condensation), and Q y at every condensed point (the reactions of
    /// the fixed ones are −(Qy)_j).
    pub(crate) fn curve(
        &mut self,
        x: &[f64],
        stencil: &Stencil,
    ) -> Result<(Points, Vec<f64>), Error> {
        self.scatter(x, true);
        self.apply_q();
        let p = self
            .cond
            .reconstruct(self.knots, stencil, &self.y, &self.s, self.d)?;
        Ok((p, self.g.clone()))
    }

    /// D_j = A_jᵀΘ_jA_j (d × d) of variable v from its block's weight, dense.
    fn d_block(&self, weights: &Weights, v: usize, out: &mut [f64]) {
        let d = self.d;
        let j = self.var_point[v];
        out.fill(0.0);
        let m = self.cones.blocks()[v].dim();
        let mut col = vec![0.0; m];
        // Column c of A_j: ball rows (0; I) → e_{1+c}; faces → (n̂_k[c])_k.
        for c in 0..d {
            match &self.sets[j] {
                PointSet::Ball(_) => {
                    col.fill(0.0);
                    col[1 + c] = 1.0;
                }
                PointSet::Faces(faces) => {
                    for (k, f) in faces.iter().enumerate() {
                        col[k] = f.normal[c];
                    }
                }
                PointSet::Fixed => return,
            }
            weights.apply(v, &mut col);
            for r in 0..d {
                out[r * d + c] = match &self.sets[j] {
                    PointSet::Ball(_) => col[1 + r],
                    PointSet::Faces(faces) => {
                        faces.iter().zip(&col).map(|(f, x)| f.normal[r] * x).sum()
                    }
                    PointSet::Fixed => 0.0,
                };
            }
        }
    }

    /// The condensed route: (D + ρI)⁻¹ per variable from the NT weights, S = T + K D⁻¹ Kᵀ.
    fn factor_condensed(&mut self, weights: &Weights, sigma: f64) -> Result<(), conic::Error> {
        let size = self.cond.len();
        // Without aliasing blocks (a cyclic S of more than 2W + 1 rows), balls in d ≤ 3 take
        // the fixed-size kernels.
        let fixed = !self.cond.closed || size > 5;
        loop {
            let assembled = match (fixed, self.d) {
                (true, 1) => self.assemble_fixed::<1>(weights, sigma),
                (true, 2) => self.assemble_fixed::<2>(weights, sigma),
                (true, 3) => self.assemble_fixed::<3>(weights, sigma),
                _ => self.assemble_general(weights, sigma),
            };
            assembled?;
            match self.sm.factor_into(&cholesky(), &mut self.sm_factor) {
                Ok(()) => return Ok(()),
                Err(e) => {
                    let j = pivot_row(&e);
                    if self.rho >= MAX_REGULARIZATION * self.qmax {
                        return Err(conic::Error::Singular {
                            index: self.cond.vertices[(self.cond.first + j).min(self.cond.n - 1)],
                        });
                    }
                    self.rho *= REGULARIZATION_GROWTH;
                }
            }
        }
    }

    /// (D + ρI)⁻¹ and D of every variable and the blocks K (D + ρI)⁻¹ Kᵀ of S, any sets.
    fn assemble_general(&mut self, weights: &Weights, sigma: f64) -> Result<(), conic::Error> {
        let d = self.d;
        let normal_zero = vec![0.0; d];
        self.sm.clear_blocks();
        for v in 0..self.var_point.len() {
            let j = self.var_point[v];
            let shift = self.rho + sigma * self.qdiag[j];
            let di = &mut self.dinv[j * d * d..(j + 1) * d * d];
            let dm = &mut self.dmat[v * d * d..(v + 1) * d * d];
            match (weights.block(v), &self.sets[j]) {
                (BlockWeight::Nt { scaling, .. }, PointSet::Ball(_)) => {
                    // V⁻² lower-right block: η⁻²(I + 2 w̄₁w̄₁ᵀ).
                    let eta2 = scaling[0] * scaling[0];
                    let w1 = &scaling[2..];
                    ball_inverse(1.0 / eta2, 2.0 / eta2, w1, shift, di);
                    for a in 0..d {
                        for b in 0..d {
                            let id = if a == b { 1.0 } else { 0.0 };
                            dm[a * d + b] = (id + 2.0 * w1[a] * w1[b]) / eta2;
                        }
                    }
                }
                (weight, PointSet::Ball(_)) => {
                    // The polish: c I + p ūūᵀ (an active ball), or c I.
                    let (a, b, w1): (f64, f64, &[f64]) = match weight {
                        BlockWeight::Active {
                            curvature,
                            normal,
                            penalty,
                        } => (curvature, penalty, &normal[1..]),
                        BlockWeight::Scalar(c) => (c, 0.0, &normal_zero[..d]),
                        _ => {
                            return Err(conic::Error::Singular {
                                index: self.cond.vertices[j],
                            })
                        }
                    };
                    ball_inverse(a.max(POLISH_FLOOR * self.qdiag[j]), b, w1, shift, di);
                    for r in 0..d {
                        for c in 0..d {
                            let id = if r == c { a } else { 0.0 };
                            dm[r * d + c] = id + b * w1[r] * w1[c];
                        }
                    }
                }
                (weight, PointSet::Faces(faces)) => {
                    let theta: Vec<f64> = match weight {
                        BlockWeight::Nt { scaling, .. } => {
                            scaling.iter().map(|v| 1.0 / (v * v)).collect()
                        }
                        BlockWeight::Diagonal(t) => t.to_vec(),
                        BlockWeight::Scalar(c) => vec![c; faces.len()],
                        BlockWeight::Active { .. } => {
                            return Err(conic::Error::Singular {
                                index: self.cond.vertices[j],
                            })
                        }
                    };
                    let normals: Vec<&[f64]> = faces.iter().map(|f| f.normal.as_slice()).collect();
                    faces_inverse(&normals, &theta, shift, d, di);
                    for a in 0..d {
                        for b in 0..d {
                            dm[a * d + b] = faces
                                .iter()
                                .zip(&theta)
                                .map(|(f, t)| t * f.normal[a] * f.normal[b])
                                .sum::<f64>();
                        }
                    }
                }
                _ => {
                    return Err(conic::Error::Singular {
                        index: self.cond.vertices[j],
                    })
                }
            }
            let di = &self.dinv[j * d * d..(j + 1) * d * d];
            let nt = self.ntouch[j];
            for x in 0..nt {
                let (jx, kx) = self.touching[j][x];
                let _ = self.sm.add_scaled(jx, jx, kx * kx, di);
                for &(jy, ky) in &self.touching[j][x + 1..nt] {
                    // A row touching the point twice (a closed curve of two condensed
                    // points) meets itself: both (jx, jy) and (jy, jx) are its diagonal.
                    let f = if jx == jy { 2.0 * kx * ky } else { kx * ky };
                    let _ = self.sm.add_scaled(jx, jy, f, di);
                }
            }
        }
        Ok(())
    }

    /// [`Condensed::assemble_general`] in a compile-time d = `D` without aliasing blocks:
    /// (D + ρI)⁻¹ per point as in [`ball_inverse`] and [`faces_inverse`] (without allocating),
    /// then each row j of S written whole from the three points its row of K touches —
    /// S_jj = T_jj I + Σ_t K_jt² D⁻¹_(j,t), S_j,j+1 = T_j,j+1 I + K_j1 K_j+1,0 D⁻¹_(j,1) +
    /// K_j2 K_j+1,1 D⁻¹_(j,2), S_j,j+2 = K_j2 K_j+2,0 D⁻¹_(j,2) — instead of six scattered adds
    /// per point (the same sums).
    fn assemble_fixed<const D: usize>(
        &mut self,
        weights: &Weights,
        sigma: f64,
    ) -> Result<(), conic::Error> {
        let dd = D * D;
        for v in 0..self.var_point.len() {
            let j = self.var_point[v];
            if let PointSet::Faces(faces) = &self.sets[j] {
                let shift = self.rho + sigma * self.qdiag[j];
                let di = &mut self.dinv[j * dd..(j + 1) * dd];
                let dm = &mut self.dmat[v * dd..(v + 1) * dd];
                let theta = &mut self.theta;
                theta.clear();
                match weights.block(v) {
                    BlockWeight::Nt { scaling, .. } => {
                        theta.extend(scaling.iter().map(|v| 1.0 / (v * v)));
                    }
                    BlockWeight::Diagonal(t) => theta.extend_from_slice(t),
                    BlockWeight::Scalar(c) => theta.resize(faces.len(), c),
                    BlockWeight::Active { .. } => {
                        return Err(conic::Error::Singular {
                            index: self.cond.vertices[j],
                        })
                    }
                }
                faces_inverse_fixed::<D>(faces, theta, shift, di);
                for a in 0..D {
                    for b in 0..D {
                        dm[a * D + b] = faces
                            .iter()
                            .zip(theta.iter())
                            .map(|(f, t)| t * f.normal[a] * f.normal[b])
                            .sum::<f64>();
                    }
                }
                continue;
            }
            let shift = self.rho + sigma * self.qdiag[j];
            // D = a I + b w wᵀ: the NT weight η⁻²(I + 2 w̄₁w̄₁ᵀ), or the polish's c I + p ūūᵀ
            // (an active ball) or c I.
            let (a, b, w, nt): (f64, f64, [f64; D], Option<f64>) = match weights.block(v) {
                BlockWeight::Nt { scaling, .. } => {
                    let eta2 = scaling[0] * scaling[0];
                    (
                        1.0 / eta2,
                        2.0 / eta2,
                        std::array::from_fn(|k| scaling[2 + k]),
                        Some(eta2),
                    )
                }
                BlockWeight::Active {
                    curvature,
                    normal,
                    penalty,
                } => (
                    curvature,
                    penalty,
                    std::array::from_fn(|k| normal[1 + k]),
                    None,
                ),
                BlockWeight::Scalar(c) => (c, 0.0, [0.0; D], None),
                BlockWeight::Diagonal(_) => {
                    return Err(conic::Error::Singular {
                        index: self.cond.vertices[j],
                    })
                }
            };
            // ball_inverse, unrolled (the polish's weight floored, see POLISH_FLOOR).
            let mut w2 = 0.0;
            for k in 0..D {
                w2 += w[k] * w[k];
            }
            let floor = if nt.is_none() {
                POLISH_FLOOR * self.qdiag[j]
            } else {
                0.0
            };
            let ar = a.max(floor) + shift;
            let (across, along) = (1.0 / ar, 1.0 / (ar + b * w2));
            let wn = w2.sqrt();
            let di = &mut self.dinv[j * dd..(j + 1) * dd];
            let dm = &mut self.dmat[v * dd..(v + 1) * dd];
            for r in 0..D {
                for c in 0..D {
                    let id = if r == c { 1.0 } else { 0.0 };
                    let uu = if wn > 0.0 {
                        (w[r] / wn) * (w[c] / wn)
                    } else {
                        0.0
                    };
                    di[r * D + c] = across * (id - uu) + along * uu;
                    dm[r * D + c] = match nt {
                        Some(eta2) => (id + 2.0 * w[r] * w[c]) / eta2,
                        None => id * a + b * w[r] * w[c],
                    };
                }
            }
        }
        let size = self.cond.len();
        let closed = self.cond.closed;
        let cond = self.cond;
        let dinv = &self.dinv;
        let di = |p: usize| -> &[f64] { &dinv[p * dd..(p + 1) * dd] };
        let blocks = self.sm.blocks_mut();
        for j in 0..size {
            let kr = cond.krows[j];
            let (c0, c1, c2) = (cond.col(j, 0), cond.col(j, 1), cond.col(j, 2));
            let row = &mut blocks[j * 3 * dd..(j + 1) * 3 * dd];
            let (d0, d1, d2) = (di(c0), di(c1), di(c2));
            let (f0, f1, f2) = (kr[0] * kr[0], kr[1] * kr[1], kr[2] * kr[2]);
            for e in 0..dd {
                row[e] = f0 * d0[e] + f1 * d1[e] + f2 * d2[e];
            }
            if closed || j + 1 < size {
                let next = cond.krows[(j + 1) % size];
                let (g1, g2) = (kr[1] * next[0], kr[2] * next[1]);
                for e in 0..dd {
                    row[dd + e] = g1 * d1[e] + g2 * d2[e];
                }
            }
            if closed || j + 2 < size {
                let h = kr[2] * cond.krows[(j + 2) % size][0];
                for e in 0..dd {
                    row[2 * dd + e] = h * d2[e];
                }
            }
        }
        Ok(())
    }

    /// The full-vertex route: H ⊗ I + D at W's data vertices.
    fn factor_full(&mut self, weights: &Weights, sigma: f64) -> Result<(), conic::Error> {
        let d = self.d;
        if self.full.is_none() {
            let h = energy::Hessian::new(self.knots);
            let mut sys = System::new(&h, d).map_err(|_| conic::Error::Singular { index: 0 })?;
            for (j, set) in self.sets.iter().enumerate() {
                if *set == PointSet::Fixed {
                    sys.fix(self.cond.vertices[j])
                        .map_err(|_| conic::Error::Singular { index: 0 })?;
                }
            }
            self.full = Some((sys, None));
            self.rhs_full = vec![0.0; self.knots.vertex_count() * d];
        }
        let mut blocks = vec![0.0; self.var_point.len() * d * d];
        for v in 0..self.var_point.len() {
            let j = self.var_point[v];
            self.d_block(weights, v, &mut blocks[v * d * d..(v + 1) * d * d]);
            for c in 0..d {
                blocks[v * d * d + c * d + c] += sigma * self.qdiag[j];
            }
        }
        let (sys, factor) = self.full.as_mut().expect("built above");
        sys.clear_blocks();
        // The last factor's storage, refilled (`energy::System::factor_into`).
        let mut f = factor.take().unwrap_or_else(Factor::empty);
        for (v, &j) in self.var_point.iter().enumerate() {
            sys.add_block(self.cond.vertices[j], &blocks[v * d * d..(v + 1) * d * d])
                .map_err(|_| conic::Error::Singular {
                    index: self.cond.vertices[j],
                })?;
        }
        match sys.factor_into(super::full::NEWTON_PIVOT_RTOL, &mut f) {
            Ok(()) => {
                *factor = Some(f);
                Ok(())
            }
            Err(energy::Error::Singular { vertex }) => {
                Err(conic::Error::Singular { index: vertex })
            }
            Err(_) => Err(conic::Error::Singular { index: 0 }),
        }
    }
}

impl Condensed<'_> {
    /// The condensed route's solve (see [`KktSystem::solve`]) with d a compile-time constant
    /// for d ≤ 3 (`D` = 0: `self.d`).
    fn solve_condensed<const D: usize>(&mut self, r: &mut [f64]) {
        let d = if D == 0 { self.d } else { D };
        let dd = d * d;
        // (wy stays 0 at interpolated points.)
        for (v, &j) in self.var_point.iter().enumerate() {
            let di = &self.dinv[j * dd..(j + 1) * dd];
            let rv = &r[v * d..(v + 1) * d];
            let out = &mut self.wy[j * d..(j + 1) * d];
            for a in 0..d {
                let mut acc = 0.0;
                for b in 0..d {
                    acc += di[a * d + b] * rv[b];
                }
                out[a] = acc;
            }
        }
        self.cond.apply_k(&self.wy, d, &mut self.wk);
        let _ = self.sm_factor.solve_in_place(&mut self.wk, 1);
        self.cond.apply_kt(&self.wk, d, &mut self.wkt);
        let mut buf = [0.0; 16];
        let mut heap = Vec::new();
        let t: &mut [f64] = if d <= 16 {
            &mut buf[..d]
        } else {
            heap.resize(d, 0.0);
            &mut heap
        };
        for (v, &j) in self.var_point.iter().enumerate() {
            let di = &self.dinv[j * dd..(j + 1) * dd];
            let rv = &mut r[v * d..(v + 1) * d];
            let wv = &self.wkt[j * d..(j + 1) * d];
            for b in 0..d {
                t[b] = rv[b] - wv[b];
            }
            for a in 0..d {
                let mut acc = 0.0;
                for b in 0..d {
                    acc += di[a * d + b] * t[b];
                }
                rv[a] = acc;
            }
        }
    }

    /// y = A x for balls alone (rows (0; I) per ball), d a compile-time constant.
    fn apply_a_balls<const D: usize>(&self, x: &[f64], out: &mut [f64]) {
        for (xv, o) in x.chunks_exact(D).zip(out.chunks_exact_mut(D + 1)) {
            o[0] = 0.0;
            o[1..].copy_from_slice(xv);
        }
    }

    /// out = Aᵀ z for balls alone, d a compile-time constant.
    fn apply_at_balls<const D: usize>(&self, z: &[f64], out: &mut [f64]) {
        for (o, zv) in out.chunks_exact_mut(D).zip(z.chunks_exact(D + 1)) {
            o.copy_from_slice(&zv[1..]);
        }
    }
}

impl KktSystem for Condensed<'_> {
    fn num_vars(&self) -> usize {
        self.var_point.len() * self.d
    }

    fn cones(&self) -> &Cones {
        &self.cones
    }

    fn b(&self) -> &[f64] {
        &self.b
    }

    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
        self.q_at_variables(x, true, g)
    }

    fn apply_p(&mut self, v: &[f64], y: &mut [f64]) {
        self.q_at_variables(v, false, y);
    }

    fn apply_a(&self, x: &[f64], out: &mut [f64]) {
        let d = self.d;
        if self.balls {
            match d {
                1 => return self.apply_a_balls::<1>(x, out),
                2 => return self.apply_a_balls::<2>(x, out),
                3 => return self.apply_a_balls::<3>(x, out),
                _ => {}
            }
        }
        for (v, &j) in self.var_point.iter().enumerate() {
            let r = self.row_start[v];
            let xv = &x[v * d..(v + 1) * d];
            match &self.sets[j] {
                PointSet::Ball(_) => {
                    // s = (ε, q − y): A = (0; I).
                    out[r] = 0.0;
                    out[r + 1..r + 1 + d].copy_from_slice(xv);
                }
                PointSet::Faces(faces) => {
                    for (k, f) in faces.iter().enumerate() {
                        out[r + k] = dot(&f.normal, xv);
                    }
                }
                PointSet::Fixed => {}
            }
        }
    }

    fn apply_at(&self, z: &[f64], out: &mut [f64]) {
        let d = self.d;
        if self.balls {
            match d {
                1 => return self.apply_at_balls::<1>(z, out),
                2 => return self.apply_at_balls::<2>(z, out),
                3 => return self.apply_at_balls::<3>(z, out),
                _ => {}
            }
        }
        for (v, &j) in self.var_point.iter().enumerate() {
            let r = self.row_start[v];
            let o = &mut out[v * d..(v + 1) * d];
            match &self.sets[j] {
                PointSet::Ball(_) => o.copy_from_slice(&z[r + 1..r + 1 + d]),
                PointSet::Faces(faces) => {
                    o.fill(0.0);
                    for (k, f) in faces.iter().enumerate() {
                        for c in 0..d {
                            o[c] += f.normal[c] * z[r + k];
                        }
                    }
                }
                PointSet::Fixed => o.fill(0.0),
            }
        }
    }

    fn diagonal_scale(&self, block: usize) -> f64 {
        self.qdiag[self.var_point[block]].max(f64::MIN_POSITIVE)
    }

    fn scales(&self) -> Scales {
        self.scales
    }

    fn factor(&mut self, weights: &Weights, sigma: f64) -> Result<(), conic::Error> {
        // The interior-point weights (NT) and the polish's (an active ball's c I + p ūūᵀ, a
        // polytope's penalties on its active faces, 0 on inactive points) have D ⪰ 0 of known
        // structure: the condensed route. The polish's D may be indefinite (a multiplier turned
        // negative): then the exact full-vertex route.
        let nt =
            (0..self.var_point.len()).all(|v| matches!(weights.block(v), BlockWeight::Nt { .. }));
        let structured = (0..self.var_point.len()).all(|v| {
            match (weights.block(v), &self.sets[self.var_point[v]]) {
                (BlockWeight::Nt { .. } | BlockWeight::Scalar(_), _) => true,
                (BlockWeight::Active { curvature, .. }, PointSet::Ball(_)) => curvature >= 0.0,
                (BlockWeight::Diagonal(_), PointSet::Faces(_)) => true,
                _ => false,
            }
        });
        if !self.exact() && !self.once && structured {
            self.route = Route::Condensed;
            let rho = self.rho;
            match self.factor_condensed(weights, sigma) {
                Ok(()) => return Ok(()),
                Err(e) if nt => return Err(e),
                // (The polish's system on the full route, with the regularization it found.)
                Err(_) => self.rho = rho,
            }
        }
        self.route = Route::Full;
        self.once = false;
        self.factor_full(weights, sigma)
    }

    fn factor_is_exact(&self) -> bool {
        self.route == Route::Full
    }

    fn escalate(&mut self) -> bool {
        // The regularized elimination did not give this direction (D + ρI too far from D where
        // Q + D has directions of size ρ or less): the step is repeated on the full-vertex
        // route, exact at O(N) per factorization. With balls, the first time for that step
        // alone — a knot update's warm polish (noisy star, n = 10⁴) met it once, on its third
        // step, and the condensed route was accurate again for the seven steps after it, at a
        // third of the full route's cost (1 against 3 ms) — and from the second time on for
        // the rest of the solve, so a condensation that stays too inexact costs one more
        // condensed factorization at most. With polytopes for the rest of the solve at once:
        // there a condensed step after an escalation could be accurate by the refinement's
        // test and still leave the answer uncertified (the half-space property test).
        if self.exact() || self.route != Route::Condensed {
            return false;
        }
        self.escalations += 1;
        self.once = !self.exact();
        true
    }

    fn apply_newton(&mut self, v: &[f64], out: &mut [f64]) -> bool {
        if self.route != Route::Condensed {
            return false;
        }
        // (Q + D) v with the D of the last factorization.
        let d = self.d;
        self.apply_p(v, out);
        for k in 0..self.var_point.len() {
            let dm = &self.dmat[k * d * d..(k + 1) * d * d];
            for a in 0..d {
                out[k * d + a] += (0..d).map(|b| dm[a * d + b] * v[k * d + b]).sum::<f64>();
            }
        }
        true
    }

    fn solve(&mut self, r: &mut [f64]) {
        let d = self.d;
        match self.route {
            Route::Condensed => {
                // dy ← D⁻¹ r (temporarily, in condensed y-space), w = K D⁻¹ r, w ← S⁻¹ w,
                // dy = D⁻¹(r − Kᵀ w).
                match d {
                    1 => self.solve_condensed::<1>(r),
                    2 => self.solve_condensed::<2>(r),
                    3 => self.solve_condensed::<3>(r),
                    _ => self.solve_condensed::<0>(r),
                }
            }
            Route::Full => {
                let Some((_, Some(f))) = &self.full else {
                    return;
                };
                self.rhs_full.fill(0.0);
                for (v, &j) in self.var_point.iter().enumerate() {
                    let vx = self.cond.vertices[j];
                    self.rhs_full[vx * d..(vx + 1) * d].copy_from_slice(&r[v * d..(v + 1) * d]);
                }
                // (Fixed data vertices get value 0 in the right-hand side: a direction.)
                let _ = f.solve_flat(&mut self.rhs_full);
                for (v, &j) in self.var_point.iter().enumerate() {
                    let vx = self.cond.vertices[j];
                    r[v * d..(v + 1) * d].copy_from_slice(&self.rhs_full[vx * d..(vx + 1) * d]);
                }
            }
        }
    }
}

/// T and S are factored as Cholesky does: any positive pivot is accepted (the interior-point
/// method regularizes and retries on a failure, `factor_condensed`).
fn cholesky() -> FactorOptions<'static> {
    FactorOptions::default().pivot_rtol(0.0)
}

/// The row of a failing pivot (`banded` reports only `Singular` for a matrix of the sizes built
/// here).
fn pivot_row(e: &banded::Error) -> usize {
    match e {
        banded::Error::Singular { index } => *index,
        _ => 0,
    }
}

#[cfg(test)]
#[path = "condensed_routes.rs"]
mod routes;
