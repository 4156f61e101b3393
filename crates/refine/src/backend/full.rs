//! The full-vertex backend: every refined vertex is a variable and the Newton matrix is
//! H ⊗ I_d + W + Σ_b L_bᵀ F_bᵀ Θ_b F_b L_b, block-pentadiagonal (cyclic for closed curves),
//! factored in O(N) by [`energy::System`].
//!
//! # The conic program
//!
//! A [`ConicProblem`] — fixed vertices p_v = a_v, smoothing terms ½ w |p_v − t|² and
//! constraints L_c p ∈ K_c on stencils of at most three vertices — becomes, with x = p
//! (vertex-major, N·d entries):
//!
//! - P = H ⊗ I_d + W on the free vertices; a fixed vertex is kept as a variable with the
//!   decoupled objective ½|x_v − a_v|² (P = I there, q = −a_v), its coupling to the free
//!   vertices folded into q. Every start puts x_v = a_v and every direction leaves it there.
//! - Each constraint's rows s = h + F (L x) ∈ K (F: m × d, h: m), i.e. b = h and A = −F L over
//!   the free stencil vertices (the fixed ones folded into h): a ball |y − c| ≤ r is
//!   (r, y − c) ∈ Q^{d+1}; a polytope ∩{n_i·y ≤ o_i} is (o_i − n̂_i·y)/|n_i| ≥ 0 (unit normals); a
//!   wedge {v·a ≥ |v| cos θ} is (v·a/cos θ, v) ∈ Q^{d+1} (θ = 0: v ∥ a as equalities across a
//!   and v·a ≥ 0; d = 1: v·a ≥ 0); a point or a radius-0 ball is a zero block (on a single
//!   vertex it fixes the vertex instead).
//!
//! P x + q is evaluated in difference form through the α-rows of A (H = AᵀA,
//! [`crate::operator`]), so its rounding scales with the steps between vertices, not
//! with |x|: the certificate's force scale is ‖H‖ times those steps.

// The block kernels index several small arrays by the same row/column.
#![allow(clippy::needless_range_loop)]

use banded::vector::{dot, norm};
use conic::{BlockWeight, Cone, Cones, KktSystem, Scales, Weights};
use energy::{Factor, System};

use crate::conic_problem::{set_scale, ConicProblem, ConvexSet};
use crate::operator::Stencil;
use crate::Error;

/// Relative pivot tolerance of the Newton systems: positive definite by construction, with
/// barrier terms that grow without bound on active rows, so pivots far below
/// [`energy::PIVOT_RTOL`] relative to their diagonal are legitimate there.
pub(crate) const NEWTON_PIVOT_RTOL: f64 = 1e-22;

/// One cone block: s = h + F (L x), L over free vertices only.
#[derive(Clone, Debug)]
pub(crate) struct Block {
    /// The constraint it comes from.
    pub constraint: usize,
    pub cone: Cone,
    /// The free stencil vertices and their coefficients.
    pub stencil: Vec<(usize, f64)>,
    /// F, m × d row-major.
    pub f: Vec<f64>,
}

/// The full-vertex backend (module docs).
pub(crate) struct FullVertex {
    pub n: usize,
    pub d: usize,
    /// The value of each fixed vertex.
    pub fixed: Vec<Option<Vec<f64>>>,
    /// The constraint that fixed a vertex (its reaction force) and the stencil coefficient.
    pub owner: Vec<Option<(usize, f64)>>,
    stencil: Stencil,
    /// Smoothing weight and weighted target Σ w t per vertex.
    weight: Vec<f64>,
    target: Vec<f64>,
    /// Σ ½ w |t|² (the objective's constant).
    constant: f64,
    /// H + W with the fixed vertices marked, and a working copy that takes the blocks.
    base: System,
    work: System,
    factor: Option<Factor>,
    pub blocks: Vec<Block>,
    cones: Cones,
    b: Vec<f64>,
    /// Diagonal of H + W per vertex.
    pdiag: Vec<f64>,
    scales: Scales,
    /// Work vector (N·d).
    buf: Vec<f64>,
}

/// Merges repeated vertices of a stencil (possible on tiny closed curves) and drops zeros.
pub(crate) fn merge_stencil(st: &[(usize, f64)]) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = Vec::new();
    for &(v, c) in st {
        if let Some(e) = out.iter_mut().find(|e| e.0 == v) {
            e.1 += c;
        } else {
            out.push((v, c));
        }
    }
    out.retain(|e| e.1 != 0.0);
    out
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Householder basis of the orthogonal complement of the unit vector `a`: d − 1 rows.
fn complement_basis(a: &[f64]) -> Vec<Vec<f64>> {
    let d = a.len();
    // Reflection Q = I − 2uuᵀ/|u|² with Q a = ±e_k; rows of Q other than k span a⊥.
    let k = (0..d)
        .max_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
        .unwrap_or(0);
    let mut u = a.to_vec();
    let sgn = if a[k] >= 0.0 { 1.0 } else { -1.0 };
    u[k] += sgn;
    let uu = dot(&u, &u);
    (0..d)
        .filter(|&r| r != k)
        .map(|r| {
            (0..d)
                .map(|c| f64::from(u8::from(r == c)) - 2.0 * u[r] * u[c] / uu)
                .collect()
        })
        .collect()
}

/// The rows (cone, F rows, g) of a set: s = g + F y, y = L p (the certificate recomputes them,
/// [`crate::constraint::derivative_terms`]).
pub(crate) fn set_rows(set: &ConvexSet, d: usize) -> Vec<(Cone, Vec<Vec<f64>>, Vec<f64>)> {
    let unit = |k: usize| {
        let mut r = vec![0.0; d];
        r[k] = 1.0;
        r
    };
    match set {
        ConvexSet::Ball { center, radius } if *radius > 0.0 => {
            let mut f = vec![vec![0.0; d]];
            let mut g = vec![*radius];
            for k in 0..d {
                f.push(unit(k));
                g.push(-center[k]);
            }
            vec![(Cone::SecondOrder(d + 1), f, g)]
        }
        ConvexSet::Ball { center: v, .. } | ConvexSet::Point(v) => {
            vec![(
                Cone::Zero(d),
                (0..d).map(unit).collect(),
                v.iter().map(|x| -x).collect(),
            )]
        }
        ConvexSet::HalfSpaces(hs) => {
            let f = hs
                .iter()
                .map(|(nr, _)| {
                    let l = norm(nr);
                    nr.iter().map(|x| -x / l).collect()
                })
                .collect();
            let g = hs.iter().map(|(nr, o)| o / norm(nr)).collect();
            vec![(Cone::Nonnegative(hs.len()), f, g)]
        }
        ConvexSet::Cone { axis, half_angle } => {
            if d == 1 {
                vec![(Cone::Nonnegative(1), vec![axis.clone()], vec![0.0])]
            } else if *half_angle == 0.0 {
                vec![
                    (Cone::Zero(d - 1), complement_basis(axis), vec![0.0; d - 1]),
                    (Cone::Nonnegative(1), vec![axis.clone()], vec![0.0]),
                ]
            } else {
                let ct = half_angle.cos();
                let mut f = vec![axis.iter().map(|x| x / ct).collect::<Vec<_>>()];
                for k in 0..d {
                    f.push(unit(k));
                }
                vec![(Cone::SecondOrder(d + 1), f, vec![0.0; d + 1])]
            }
        }
    }
}

impl FullVertex {
    /// Multiplies the force floor F₀ of [`conic::KktSystem::scales`] by `factor` (the last
    /// attempt of [`crate::conic_problem::ConicProblem::solve_judged`]).
    pub(crate) fn lower_force_floor(&mut self, factor: f64) {
        self.scales.force *= factor;
    }

    /// The backend of `problem`.
    ///
    /// # Errors
    /// [`Error::Infeasible`] naming a constraint that contradicts fixed vertices (or a
    /// constraint whose stencil is all fixed and which its constant violates); [`Error::Energy`]
    /// from assembling the system.
    pub(crate) fn new(problem: &ConicProblem) -> Result<Self, Error> {
        let (n, d) = (problem.len(), problem.dim());
        let mut fixed = problem.fixed.clone();
        let mut owner: Vec<Option<(usize, f64)>> = vec![None; n];
        let mut scale_x: f64 = 0.0;
        for v in fixed.iter().flatten() {
            scale_x = scale_x.max(inf_norm(v));
        }
        for s in &problem.smoothing {
            scale_x = scale_x.max(inf_norm(&s.2));
        }
        // Single-vertex equalities become fixed vertices.
        for (ci, con) in problem.constraints.iter().enumerate() {
            scale_x = scale_x.max(set_scale(&con.set));
            let value = match &con.set {
                ConvexSet::Point(v) => Some(v),
                ConvexSet::Ball { center, radius } if *radius == 0.0 => Some(center),
                _ => None,
            };
            let merged = merge_stencil(&con.stencil);
            if let (Some(v), [(vert, coef)]) = (value, merged.as_slice()) {
                let target: Vec<f64> = v.iter().map(|x| x / coef).collect();
                match &fixed[*vert] {
                    Some(old) => {
                        let gap = norm(
                            &old.iter()
                                .zip(&target)
                                .map(|(a, b)| a - b)
                                .collect::<Vec<_>>(),
                        );
                        if gap > 1e-12 * (1.0 + inf_norm(old).max(inf_norm(&target))) {
                            return Err(Error::Infeasible { constraint: ci });
                        }
                    }
                    None => {
                        fixed[*vert] = Some(target);
                        owner[*vert] = Some((ci, *coef));
                    }
                }
            }
        }
        let mut base = problem.system()?;
        let mut weight = vec![0.0; n];
        let mut target = vec![0.0; n * d];
        let mut constant = 0.0;
        for (v, w, t) in &problem.smoothing {
            base.add_weight(*v, *w)?;
            weight[*v] += w;
            for k in 0..d {
                target[v * d + k] += w * t[k];
                constant += 0.5 * w * t[k] * t[k];
            }
        }
        let (hd, _, _) = problem.hessian_bands();
        let pdiag: Vec<f64> = (0..n).map(|v| hd[v] + weight[v]).collect();
        for (v, f) in fixed.iter().enumerate() {
            if f.is_some() {
                base.fix(v)?;
            }
        }
        let mut blocks = Vec::new();
        let mut cone_list = Vec::new();
        let mut b = Vec::new();
        for (ci, con) in problem.constraints.iter().enumerate() {
            let merged = merge_stencil(&con.stencil);
            if let [(v, _)] = merged.as_slice() {
                if owner[*v].is_some_and(|(o, _)| o == ci) {
                    continue;
                }
            }
            // Split the stencil into free vertices and the fixed contribution.
            let mut yfix = vec![0.0; d];
            let mut free = Vec::new();
            for &(v, coef) in &merged {
                match &fixed[v] {
                    Some(val) => {
                        for k in 0..d {
                            yfix[k] += coef * val[k];
                        }
                    }
                    None => free.push((v, coef)),
                }
            }
            for (cone, f, g) in set_rows(&con.set, d) {
                let m = f.len();
                let h: Vec<f64> = (0..m).map(|r| g[r] + dot(&f[r], &yfix)).collect();
                if free.is_empty() {
                    // A constant: check it.
                    let tol = 1e-12 * (1.0 + scale_x);
                    let ok = match cone {
                        Cone::Zero(_) => inf_norm(&h) <= tol,
                        Cone::Nonnegative(_) => h.iter().all(|&x| x >= -tol),
                        Cone::SecondOrder(_) => h[0] >= norm(&h[1..]) - tol,
                    };
                    if !ok {
                        return Err(Error::Infeasible { constraint: ci });
                    }
                    continue;
                }
                blocks.push(Block {
                    constraint: ci,
                    cone,
                    stencil: free.clone(),
                    f: f.concat(),
                });
                cone_list.push(cone);
                b.extend(h);
            }
        }
        let cones = Cones::new(cone_list).map_err(|_| Error::InvalidConstraint {
            constraint: 0,
            reason: "an empty cone block",
        })?;
        // Scales: forces ‖H‖ × (the largest step between consecutive vertices of the data:
        // fixed values, set scales), lengths the data's extent.
        let hmax = (0..n)
            .filter(|&v| fixed[v].is_none())
            .fold(0.0f64, |a, v| a.max(pdiag[v]));
        let scales = Scales {
            force: hmax * scale_x,
            length: scale_x,
        };
        let work = base.clone();
        Ok(FullVertex {
            n,
            d,
            fixed,
            owner,
            stencil: problem.stencil(),
            weight,
            target,
            constant,
            base,
            work,
            factor: None,
            blocks,
            cones,
            b,
            pdiag,
            scales,
            buf: vec![0.0; n * d],
        })
    }

    /// Whether vertex `v` is free.
    #[inline]
    pub(crate) fn is_free(&self, v: usize) -> bool {
        self.fixed[v].is_none()
    }

    /// The start x: the fixed values, zeros elsewhere (or `warm` at the free vertices).
    pub(crate) fn start(&self, warm: Option<&[f64]>) -> Vec<f64> {
        let d = self.d;
        let mut x = warm.map_or_else(|| vec![0.0; self.n * d], <[f64]>::to_vec);
        for (v, f) in self.fixed.iter().enumerate() {
            if let Some(val) = f {
                x[v * d..(v + 1) * d].copy_from_slice(val);
            }
        }
        x
    }

    /// (H ⊗ I) p + W p − Σ w t at every vertex (no masking), in difference form, and the
    /// objective E + ½Σ w|p − t|².
    pub(crate) fn full_gradient(&self, x: &[f64], g: &mut [f64]) -> f64 {
        let d = self.d;
        let e = self.stencil.apply_h_flat(x, d, g);
        let mut smooth = 0.0;
        for v in 0..self.n {
            let w = self.weight[v];
            if w == 0.0 {
                continue;
            }
            for k in 0..d {
                let i = v * d + k;
                g[i] += w * x[i] - self.target[i];
                // ½w|x − t̄|² up to the constant (t̄ = Σwt/w): w x² /2 − (Σwt) x.
                smooth += 0.5 * w * x[i] * x[i] - self.target[i] * x[i];
            }
        }
        e + smooth + self.constant
    }

    /// The energy ½|A p|² alone.
    pub(crate) fn energy(&self, x: &[f64]) -> f64 {
        let mut g = vec![0.0; x.len()];
        self.stencil.apply_h_flat(x, self.d, &mut g)
    }
}

impl KktSystem for FullVertex {
    fn num_vars(&self) -> usize {
        self.n * self.d
    }

    fn cones(&self) -> &Cones {
        &self.cones
    }

    fn b(&self) -> &[f64] {
        &self.b
    }

    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
        let d = self.d;
        // The fixed vertices at their values (the objective of the module docs).
        let mut xs = std::mem::take(&mut self.buf);
        xs.copy_from_slice(x);
        for (v, f) in self.fixed.iter().enumerate() {
            if let Some(val) = f {
                xs[v * d..(v + 1) * d].copy_from_slice(val);
            }
        }
        let f = self.full_gradient(&xs, g);
        let mut fixed_part = 0.0;
        for (v, fv) in self.fixed.iter().enumerate() {
            if let Some(val) = fv {
                for k in 0..d {
                    let r = x[v * d + k] - val[k];
                    g[v * d + k] = r;
                    fixed_part += 0.5 * r * r;
                }
            }
        }
        self.buf = xs;
        f + fixed_part
    }

    fn apply_p(&mut self, v: &[f64], y: &mut [f64]) {
        let d = self.d;
        let mut xs = std::mem::take(&mut self.buf);
        xs.copy_from_slice(v);
        for (u, f) in self.fixed.iter().enumerate() {
            if f.is_some() {
                xs[u * d..(u + 1) * d].fill(0.0);
            }
        }
        if self.base.apply_flat(&xs, y).is_err() {
            y.fill(0.0);
        }
        for (u, f) in self.fixed.iter().enumerate() {
            if f.is_some() {
                y[u * d..(u + 1) * d].copy_from_slice(&v[u * d..(u + 1) * d]);
            }
        }
        self.buf = xs;
    }

    fn apply_a(&self, x: &[f64], y: &mut [f64]) {
        let d = self.d;
        let mut off = 0;
        let mut lx = [0.0; 16];
        let mut heap = Vec::new();
        let l: &mut [f64] = if d <= 16 {
            &mut lx[..d]
        } else {
            heap.resize(d, 0.0);
            &mut heap
        };
        for blk in &self.blocks {
            l.fill(0.0);
            for &(v, c) in &blk.stencil {
                for k in 0..d {
                    l[k] += c * x[v * d + k];
                }
            }
            let m = blk.cone.dim();
            for r in 0..m {
                y[off + r] = -dot(&blk.f[r * d..(r + 1) * d], l);
            }
            off += m;
        }
    }

    fn apply_at(&self, z: &[f64], out: &mut [f64]) {
        let d = self.d;
        out.fill(0.0);
        let mut off = 0;
        let mut ft = [0.0; 16];
        let mut heap = Vec::new();
        let ftz: &mut [f64] = if d <= 16 {
            &mut ft[..d]
        } else {
            heap.resize(d, 0.0);
            &mut heap
        };
        for blk in &self.blocks {
            let m = blk.cone.dim();
            ftz.fill(0.0);
            for r in 0..m {
                for k in 0..d {
                    ftz[k] -= blk.f[r * d + k] * z[off + r];
                }
            }
            for &(v, c) in &blk.stencil {
                for k in 0..d {
                    out[v * d + k] += c * ftz[k];
                }
            }
            off += m;
        }
    }

    fn block_gram(&self, block: usize, out: &mut [f64]) {
        // A_b = −F ⊗ (the stencil's coefficients c): A_b A_bᵀ = (Σ c²) F Fᵀ.
        let blk = &self.blocks[block];
        let (d, m) = (self.d, blk.cone.dim());
        let cc: f64 = blk.stencil.iter().map(|&(_, c)| c * c).sum();
        for i in 0..m {
            for j in 0..m {
                let fij: f64 = (0..d).map(|k| blk.f[i * d + k] * blk.f[j * d + k]).sum();
                out[i * m + j] = cc * fij;
            }
        }
    }

    fn diagonal_scale(&self, block: usize) -> f64 {
        let blk = &self.blocks[block];
        let fmax = blk
            .f
            .iter()
            .fold(0.0f64, |a, &v| a.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        blk.stencil
            .iter()
            .map(|&(v, c)| self.pdiag[v] / (c * c))
            .fold(f64::INFINITY, f64::min)
            / (fmax * fmax)
    }

    fn scales(&self) -> Scales {
        self.scales
    }

    fn factor(&mut self, weights: &Weights, sigma: f64) -> Result<(), conic::Error> {
        let d = self.d;
        // The last factor's storage, refilled (`energy::System::factor_into`).
        let mut factor = self.factor.take().unwrap_or_else(Factor::empty);
        if sigma > 0.0 {
            self.work = self.base.clone();
        } else {
            self.work.clear_blocks();
        }
        let mut local = if sigma > 0.0 {
            self.pdiag.clone()
        } else {
            Vec::new()
        };
        let mut theta = vec![0.0; d * d];
        let mut col = Vec::new();
        for (bi, blk) in self.blocks.iter().enumerate() {
            if matches!(weights.block(bi), BlockWeight::Scalar(c) if c == 0.0) {
                continue;
            }
            let m = blk.cone.dim();
            // FᵀΘF: Θ applied to each column of F.
            for i in 0..d {
                col.clear();
                col.extend((0..m).map(|r| blk.f[r * d + i]));
                weights.apply(bi, &mut col);
                for j in 0..d {
                    theta[j * d + i] = (0..m).map(|r| blk.f[r * d + j] * col[r]).sum();
                }
            }
            if sigma > 0.0 {
                let tmax = (0..d).map(|k| theta[k * d + k]).fold(0.0, f64::max);
                for &(v, c) in &blk.stencil {
                    local[v] += c * c * tmax;
                }
            }
            self.work
                .add_stencil(&blk.stencil, &theta)
                .map_err(|_| conic::Error::Singular { index: bi })?;
        }
        if sigma > 0.0 {
            for v in 0..self.n {
                if self.is_free(v) {
                    self.work
                        .add_weight(v, sigma * local[v])
                        .map_err(|_| conic::Error::Singular { index: v })?;
                }
            }
        }
        match self.work.factor_into(NEWTON_PIVOT_RTOL, &mut factor) {
            Ok(()) => {
                self.factor = Some(factor);
                Ok(())
            }
            Err(energy::Error::Singular { vertex }) => {
                Err(conic::Error::Singular { index: vertex })
            }
            Err(_) => Err(conic::Error::Singular { index: 0 }),
        }
    }

    fn factor_is_exact(&self) -> bool {
        true
    }

    fn solve(&mut self, rhs: &mut [f64]) {
        let d = self.d;
        if let Some(f) = &self.factor {
            // K = K_ff ⊕ I: the system's solve would move the fixed rows' values into the free
            // rows' right-hand side (prescribed values), so they are solved as zeros and put
            // back. (The length is N·d by construction.)
            let mut saved = std::mem::take(&mut self.buf);
            for (v, fv) in self.fixed.iter().enumerate() {
                if fv.is_some() {
                    saved[v * d..(v + 1) * d].copy_from_slice(&rhs[v * d..(v + 1) * d]);
                    rhs[v * d..(v + 1) * d].fill(0.0);
                }
            }
            let _ = f.solve_flat(rhs);
            for (v, fv) in self.fixed.iter().enumerate() {
                if fv.is_some() {
                    rhs[v * d..(v + 1) * d].copy_from_slice(&saved[v * d..(v + 1) * d]);
                }
            }
            self.buf = saved;
        }
    }
}

/// The same program for Clarabel (module docs of `conic::clarabel`), with the energy factored:
/// z = (A ⊗ I_d) x (the α-rows of H = AᵀA, zero-cone rows), P = I on z plus the smoothing
/// weights on x — Clarabel's KKT system then does not carry H, whose condition number (~N⁴)
/// stops it at `InsufficientProgress` as posed. The fixed vertices are zero-cone rows
/// x_v = a_v. The backend's m rows come first, with its A and b, so the duals map back.
#[cfg(feature = "clarabel")]
impl conic::clarabel::Sparse for FullVertex {
    fn sparse(&self) -> Result<conic::clarabel::SparseProgram, conic::Error> {
        use conic::clarabel::{SparseProgram, Triplets};
        let (n, d) = (self.n, self.d);
        let nx = n * d;
        let rows = self.stencil.row_range(n);
        let nz = rows.len() * d;
        let mut p = Triplets::default();
        let mut q = vec![0.0; nx + nz];
        for v in 0..n {
            if self.weight[v] > 0.0 {
                for k in 0..d {
                    p.push(v * d + k, v * d + k, self.weight[v]);
                    q[v * d + k] = -self.target[v * d + k];
                }
            }
        }
        for j in 0..nz {
            p.push(nx + j, nx + j, 1.0);
        }
        // The backend's rows: A = −F L over the free stencil vertices.
        let mut a = Triplets::default();
        let mut b = self.b.clone();
        let mut cones = self.cones.blocks().to_vec();
        let mut row = 0;
        for blk in &self.blocks {
            for r in 0..blk.cone.dim() {
                for &(v, c) in &blk.stencil {
                    for k in 0..d {
                        let f = blk.f[r * d + k];
                        if f != 0.0 {
                            a.push(row + r, v * d + k, -c * f);
                        }
                    }
                }
            }
            row += blk.cone.dim();
        }
        // z − (A ⊗ I) x = 0.
        for (zi, i) in rows.clone().enumerate() {
            let alpha = self.stencil.rows[i];
            let cols = self.stencil.cols(i, n);
            for k in 0..d {
                let r = row + zi * d + k;
                for (t, &col) in cols.iter().enumerate() {
                    if alpha[t] != 0.0 {
                        a.push(r, col * d + k, -alpha[t]);
                    }
                }
                a.push(r, nx + zi * d + k, 1.0);
                b.push(0.0);
            }
        }
        row += nz;
        // Fixed vertices.
        let mut fixed_rows = 0;
        for (v, f) in self.fixed.iter().enumerate() {
            if let Some(val) = f {
                for k in 0..d {
                    a.push(row + fixed_rows, v * d + k, 1.0);
                    b.push(val[k]);
                    fixed_rows += 1;
                }
            }
        }
        if nz > 0 {
            cones.push(conic::Cone::Zero(nz));
        }
        if fixed_rows > 0 {
            cones.push(conic::Cone::Zero(fixed_rows));
        }
        Ok(SparseProgram {
            n: nx + nz,
            p,
            q,
            a,
            b,
            cones,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::FullVertex;
    use crate::conic_problem::{ConicProblem, ConvexSet};
    use conic::KktSystem;
    use divdiff::Knots;

    /// The local Gram matrices are A_b A_bᵀ as `apply_at` applies A: wedges, balls, half-spaces
    /// and a point on three-vertex stencils with a fixed vertex among them.
    #[test]
    fn block_gram_is_the_rows_gram() {
        let knots = Knots::closed(vec![0.0, 0.7, 1.9, 2.4, 3.8, 4.5, 5.0]).unwrap();
        let mut p = ConicProblem::new(&knots, 2).unwrap();
        p.fix(0, &[1.0, 0.5]).unwrap();
        let st = [(5, -0.4), (0, 0.1), (1, 0.3)];
        let (c, s) = (0.6f64, 0.8f64);
        p.add_constraint(
            &st,
            ConvexSet::Cone {
                axis: vec![c, s],
                half_angle: 0.3,
            },
        )
        .unwrap();
        p.add_constraint(
            &[(2, 1.0)],
            ConvexSet::Ball {
                center: vec![0.2, -1.0],
                radius: 0.4,
            },
        )
        .unwrap();
        let hs = vec![(vec![1.0, 2.0], 0.5), (vec![-0.3, 0.7], 1.0)];
        p.add_constraint(&[(2, -1.5), (3, 1.0), (4, 0.5)], ConvexSet::HalfSpaces(hs))
            .unwrap();
        p.add_constraint(&[(3, 1.0), (4, -1.0)], ConvexSet::Point(vec![0.1, 0.2]))
            .unwrap();
        let be = FullVertex::new(&p).unwrap();
        for b in 0..be.cones().len() {
            let m = be.cones().range(b).len();
            let (mut g, mut reference) = (vec![0.0; m * m], vec![0.0; m * m]);
            be.block_gram(b, &mut g);
            conic::gram_through_apply_at(&be, b, &mut reference);
            for i in 0..m {
                for j in 0..m {
                    let want = reference[i * m + j];
                    let scale = want.abs().max(1.0);
                    assert!(
                        (g[i * m + j] - want).abs() <= 1e-14 * scale,
                        "block {b} ({i}, {j})"
                    );
                }
            }
        }
    }
}
