//! The balls problem (3.4) on fixed knots, condensed exactly onto the n data vertices and solved
//! by a primal–dual interior-point method (Mehrotra predictor–corrector, Nesterov–Todd scaling).
//!
//! Only the data vertices are constrained, so the free vertices are eliminated exactly
//! ([`super::fast::Condensation`]): with the data vertices at y, the energy minimized over the
//! free vertices is E(y) = ½ Σ_coords (Ky)ᵀ T⁻¹ (Ky), T symmetric positive definite tridiagonal
//! and K tridiagonal on the data rows (both cyclic for a closed curve). The problem is
//!
//!   min_y ½ yᵀ Q y,  Q = Kᵀ T⁻¹ K ⊗ I_d,   s.t. s_i = (ε_i, q_i − y_i) ∈ SOC_{d+1}  (ε_i > 0),
//!
//! with y_i = q_i for ε_i = 0. Q is dense but applied in O(n d) (one tridiagonal solve). Each
//! Newton system (Q + D)Δy = r, D block diagonal with the lower-right d × d block of V⁻² per cone
//! (V the NT scaling, V z = V⁻¹ s = λ), is solved through the augmented form
//! [[D, Kᵀ], [K, −T]]: (T + K D⁻¹ Kᵀ) w = K D⁻¹ r, then Δy = D⁻¹(r − Kᵀ w) — a block
//! pentadiagonal (cyclic) positive definite system of n blocks of size d, factored by a banded
//! block Cholesky (a cyclic band becomes an ordinary band of twice the width in the zig-zag order
//! 0, n−1, 1, n−2, …). Fixed vertices have D⁻¹ = 0 and Δy = 0. For the cone (η, w̄) of the NT
//! scaling, D = η⁻²(I + 2 w̄₁w̄₁ᵀ). D vanishes on inactive cones, where D⁻¹ would make
//! T + K D⁻¹ Kᵀ as ill-conditioned as D⁻¹ is large (K annihilates constants), so D + ρI is
//! factored ([`CONDENSED_REGULARIZATION`]) and iterative refinement against Q + D (Q applied
//! exactly) removes ρ from the corrector direction.
//!
//! The start y = q is strictly feasible (s = (ε, 0), the centre of the cone, z = (F, 0) with F the
//! largest force |Qq|); s is its own iterate, with the primal residual s − (ε, q − y) kept in the
//! Newton systems (the slack ε − |q − y| cannot be resolved through y near the spheres). The
//! multiplier of ball i in the convention of (3.5) is w_i = z_{i,0}/ε_i: complementarity s∘z = 0
//! gives z₁ = (z₀/ε)(y − q), so Qy + z₁ = 0 reads (Hp)_{i_k} + w_i (p_{i_k} − q_i) = 0. Off the
//! central path the vector part of s∘z, and with it the tangential position on an active sphere,
//! converges only like √μ, so an active-set polish follows ([`CONDENSED_POLISH_STEPS`]: Newton
//! steps on the full-vertex system H ⊗ I + D, which needs no D⁻¹). The interior is recovered by
//! the second pass of [`super::fast`] with the data vertices at y; the caller certifies the
//! result independently (`certify`).
//!
//! **Working set.** At the optimum most balls are usually inactive (the bench's closed curves:
//! 3.6 % active at n = 10⁴, 0.9 % at n = 10⁵), and a ball that is inactive at the optimum can be
//! dropped without changing it. So the method above runs on a working set W of balls: the
//! condensation is taken onto the data vertices of W only ([`Condensation::at_vertices_reusing`]; the
//! other data vertices become free vertices of longer spans), and the optimum of the relaxed
//! problem is accepted when its curve stays strictly inside every ball outside W (margin
//! [`WORKING_SET_MARGIN`]) — then it is feasible for all balls and optimal among a superset of
//! curves, so optimal. Otherwise balls join W and the round repeats: all the violated (and
//! nearly violated, [`WORKING_SET_NEAR`]) ones when they are few, else the local maxima of
//! |p − q|/ε ([`WORKING_SET_WINDOW`]). W only grows, so this ends (at worst with all balls,
//! taken at once after [`WORKING_SET_MAX_ROUNDS`], or from round [`WORKING_SET_DENSE_ROUND`]
//! when most balls outside W are violated, [`WORKING_SET_DENSE`]); it starts from the fixed
//! points, the ends of an open curve and every [`WORKING_SET_START_STEP`]-th ball (and, in
//! Algorithm 4.1, the balls active in the previous knot iteration). A round is judged when its
//! residual reaches [`CONDENSED_ROUND_TOLERANCE`], and only an accepted one is solved to the
//! full tolerance and polished. Each round's condensation reuses the spans of the previous one
//! that no new point splits. The multipliers of the balls outside W are 0. (Rounds cost O(N)
//! passes each: with fewer than [`WORKING_SET_MIN_POINTS`] points or more than
//! [`WORKING_SET_MAX_STRIDE`] vertices per span, one round on all balls is taken instead.)

// The block kernels index several small arrays by the same row/column.
#![allow(clippy::needless_range_loop)]

use divdiff::{Knots, Points};

use super::fast::Condensation;
use super::operator::Stencil;
use crate::Error;
use conic::cone::{
    apply_nt as apply_v, jordan_divide as jordan_div, jordan_product as jordan,
    nt_scaling as scaling, step_to_boundary as max_step, Kind,
};

use super::fixed::dist;

/// Iteration limit of the condensed interior-point method.
pub const CONDENSED_MAX_ITERATIONS: usize = 80;
/// Target of the condensed interior-point method: the dual residual ‖Qy + z₁‖_∞ relative to the
/// force scale (the largest of ‖Qy‖_∞, ‖z₁‖_∞), and the duality gap sᵀz relative to the energy
/// (it bounds E(y) − E*), both at most this.
pub const CONDENSED_TOLERANCE: f64 = 1e-10;
/// The stricter target of a second run when the first result is not certified at
/// [`super::exact::EXACT_KKT_TARGET`] (its active set, read off at [`CONDENSED_TOLERANCE`], was
/// not settled enough for the polish).
pub const CONDENSED_STRICT_TOLERANCE: f64 = 1e-13;
/// Fraction of the step to the boundary of the cones taken.
pub const CONDENSED_STEP_FRACTION: f64 = 0.99;
/// The corrector's Newton system is refined (against Q + D applied exactly) until its residual
/// is below this times the iterate's relative residual times its right-hand side (but never
/// asked for less than [`CONDENSED_REFINEMENT_RTOL`]): early directions need no accuracy. The
/// predictor, which only sets the centring, is not refined.
pub const CONDENSED_NEWTON_ACCURACY: f64 = 1e-3;
/// Static regularization of the Newton systems: D + ρI is factored instead of D, with ρ this
/// times the largest diagonal entry of Q, so D⁻¹ stays below 1/ρ. Without it the elimination
/// through D⁻¹ cancels catastrophically on inactive cones (D → 0 makes T + K D⁻¹ Kᵀ as
/// ill-conditioned as D⁻¹ is large: K has the constants in its kernel). Iterative refinement
/// against Q + D removes the regularization from the directions.
pub const CONDENSED_REGULARIZATION: f64 = 1e-13;
/// Factor by which ρ grows when T + K (D + ρI)⁻¹ Kᵀ does not factor (a pivot lost to the
/// cancellation), up to [`CONDENSED_MAX_REGULARIZATION`] times the largest diagonal entry of Q.
pub const CONDENSED_REGULARIZATION_GROWTH: f64 = 100.0;
/// Largest regularization tried (relative to the largest diagonal entry of Q).
pub const CONDENSED_MAX_REGULARIZATION: f64 = 1e-7;
/// Iterative refinement stops when the residual of the Newton system is below this times its
/// right-hand side (or after [`CONDENSED_MAX_REFINEMENT_STEPS`]).
pub const CONDENSED_REFINEMENT_RTOL: f64 = 1e-12;
/// Upper limit of iterative-refinement steps per Newton solve.
pub const CONDENSED_MAX_REFINEMENT_STEPS: usize = 6;
/// Newton steps of the active-set polish after the interior-point method: its iterates approach
/// the optimum only like √μ in the directions tangent to active spheres (the vector part of s∘z
/// is not driven below √μ off the central path), which the certificate's stationarity with the
/// multiplier w = z₀/ε of (3.5) measures. The polish fixes the active set (slack ≤
/// [`CONDENSED_POLISH_ACTIVE_RTOL`] ε), takes Newton steps on Qy + w(y − q) = 0,
/// |y_i − q_i| = ε_i with the normal direction held by a penalty
/// [`CONDENSED_POLISH_STIFFNESS`] · max Q_ii, re-projects onto the spheres and keeps a step only
/// if it lowers the stationarity residual, keeps every inactive vertex inside its ball and every
/// multiplier non-negative.
pub const CONDENSED_POLISH_STEPS: usize = 3;
/// The polish is skipped when the interior-point result's stationarity residual
/// ‖Qy + w(y − q)‖_∞ is already at most this times the force scale (the certificate, which the
/// caller computes anyway, still judges the result; the second run, at
/// [`CONDENSED_STRICT_TOLERANCE`], always polishes).
pub const CONDENSED_POLISH_SKIP: f64 = 1e-12;
/// Changes of the polish's active set (a vertex leaving its ball joins it, a negative
/// multiplier leaves it), each followed by a retried Newton step.
pub const CONDENSED_POLISH_ACTIVE_CHANGES: usize = 3;
/// A working-set round is judged (its curve checked against the balls outside the set) when
/// its residual first reaches this; only an accepted round continues to the full tolerance.
pub const CONDENSED_ROUND_TOLERANCE: f64 = 1e-6;
/// A ball counts as active in the polish when its slack is at most this times its radius.
pub const CONDENSED_POLISH_ACTIVE_RTOL: f64 = 1e-6;
/// Normal stiffness of the polish's penalty, relative to the largest diagonal entry of Q.
pub const CONDENSED_POLISH_STIFFNESS: f64 = 1e8;
/// When the iteration limit is reached or a step fails, the best iterate is still returned (for
/// the independent certificate to judge — `fixed::exact` accepts it only at
/// `EXACT_KKT_TARGET`) if its own residual is at most this. Loose on purpose: with many
/// vertices per span (k = 10⁵…10⁶) the method stalls at residuals 1e-8…1e-7 while the polished
/// result certifies at 2e-11…5e-13; refusing it sent those problems to the full-vertex
/// fallbacks (45 s instead of 1.7 s at k = 10⁶).
pub const CONDENSED_ACCEPT: f64 = 1e-6;

/// A symmetric positive definite block-banded matrix (blocks of `bs` × `bs`, `bw` blocks below
/// the diagonal after the ordering) and its Cholesky factor, in place.
struct Banded {
    nb: usize,
    bs: usize,
    bw: usize,
    /// Position of each block in the factored order.
    pos: Vec<usize>,
    /// Block (p, p − t) at [(p (bw + 1) + t) bs², …), row-major.
    a: Vec<f64>,
    /// Solve workspace (positions × columns).
    work: Vec<f64>,
    /// Reciprocals of the diagonal entries of the factor's diagonal blocks (by position).
    rdiag: Vec<f64>,
}

impl Banded {
    /// `nb` blocks coupled within `band` (cyclically when `cyclic`), solves with up to
    /// `ncols` right-hand sides.
    fn new(nb: usize, bs: usize, band: usize, cyclic: bool, ncols: usize) -> Self {
        let half = nb.div_ceil(2);
        let pos: Vec<usize> = if cyclic {
            (0..nb)
                .map(|i| {
                    if i < half {
                        2 * i
                    } else {
                        2 * (nb - 1 - i) + 1
                    }
                })
                .collect()
        } else {
            (0..nb).collect()
        };
        let bw = if cyclic { 2 * band } else { band }.min(nb.saturating_sub(1));
        Banded {
            nb,
            bs,
            bw,
            pos,
            a: vec![0.0; nb * (bw + 1) * bs * bs],
            work: vec![0.0; nb * bs * ncols],
            rdiag: vec![0.0; nb * bs],
        }
    }

    fn clear(&mut self) {
        self.a.fill(0.0);
    }

    #[inline]
    fn at(&self, p: usize, t: usize) -> usize {
        (p * (self.bw + 1) + t) * self.bs * self.bs
    }

    /// Adds `f · blk` to block (i, j) of the symmetric matrix (and so its transpose to (j, i));
    /// `blk(r, c)` is the entry of row r of block i and column c of block j.
    #[inline]
    fn add(&mut self, i: usize, j: usize, f: f64, blk: &[f64]) {
        let bs = self.bs;
        let (pi, pj) = (self.pos[i], self.pos[j]);
        if pi >= pj {
            let o = self.at(pi, pi - pj);
            for (x, b) in self.a[o..o + bs * bs].iter_mut().zip(blk) {
                *x += f * b;
            }
        } else {
            let o = self.at(pj, pj - pi);
            for r in 0..bs {
                for c in 0..bs {
                    self.a[o + r * bs + c] += f * blk[c * bs + r];
                }
            }
        }
    }

    /// Adds f to the scalar-identity part of block (i, j): f I_bs.
    #[inline]
    fn add_identity(&mut self, i: usize, j: usize, f: f64) {
        let bs = self.bs;
        let (pi, pj) = (self.pos[i], self.pos[j]);
        let (p, t) = if pi >= pj {
            (pi, pi - pj)
        } else {
            (pj, pj - pi)
        };
        let o = self.at(p, t);
        for r in 0..bs {
            self.a[o + r * bs + r] += f;
        }
    }

    /// Block Cholesky in place. Returns the (original) block index of a non-positive pivot.
    fn factor(&mut self) -> Result<(), usize> {
        match self.bs {
            1 => self.factor_impl::<1>(),
            2 => self.factor_impl::<2>(),
            3 => self.factor_impl::<3>(),
            _ => self.factor_impl::<0>(),
        }
    }

    /// [`Banded::factor`] with the block size a compile-time constant (`BS` = 0: `self.bs`).
    fn factor_impl<const BS: usize>(&mut self) -> Result<(), usize> {
        let bs = if BS == 0 { self.bs } else { BS };
        let bw = self.bw;
        let bb = bs * bs;
        let mut inv_pos = vec![0; self.nb];
        for (i, &p) in self.pos.iter().enumerate() {
            inv_pos[p] = i;
        }
        let mut mbuf = [0.0; 16];
        let mut mvec = Vec::new();
        let m: &mut [f64] = if bb <= mbuf.len() {
            &mut mbuf[..bb]
        } else {
            mvec.resize(bb, 0.0);
            &mut mvec
        };
        for p in 0..self.nb {
            let lo = p.saturating_sub(bw);
            for c in lo..=p {
                // M = A[p][c] − Σ_{c' < c} L[p][c'] L[c][c']ᵀ.
                let o = self.at(p, p - c);
                m.copy_from_slice(&self.a[o..o + bb]);
                for cp in lo.max(c.saturating_sub(bw))..c {
                    let x = self.at(p, p - cp);
                    let y = self.at(c, c - cp);
                    let (xs, ys) = (&self.a[x..x + bb], &self.a[y..y + bb]);
                    for r in 0..bs {
                        for s in 0..bs {
                            let mut acc = 0.0;
                            for t in 0..bs {
                                acc += xs[r * bs + t] * ys[s * bs + t];
                            }
                            m[r * bs + s] -= acc;
                        }
                    }
                }
                if c < p {
                    // L[p][c] = M L[c][c]⁻ᵀ: each row solves L[c][c] xᵀ = mᵀ.
                    let dgo = self.at(c, 0);
                    let dg = &self.a[dgo..dgo + bb];
                    let rc = &self.rdiag[c * bs..(c + 1) * bs];
                    for r in 0..bs {
                        for s in 0..bs {
                            let mut v = m[r * bs + s];
                            for t in 0..s {
                                v -= m[r * bs + t] * dg[s * bs + t];
                            }
                            m[r * bs + s] = v * rc[s];
                        }
                    }
                    self.a[o..o + bb].copy_from_slice(m);
                } else {
                    // Dense Cholesky of the diagonal block (lower triangle stored).
                    for s in 0..bs {
                        let mut v = m[s * bs + s];
                        for t in 0..s {
                            v -= m[s * bs + t] * m[s * bs + t];
                        }
                        if v.is_nan() || v <= 0.0 {
                            return Err(inv_pos[p]);
                        }
                        let piv = v.sqrt();
                        let rpiv = 1.0 / piv;
                        self.rdiag[p * bs + s] = rpiv;
                        m[s * bs + s] = piv;
                        for r in s + 1..bs {
                            let mut w = m[r * bs + s];
                            for t in 0..s {
                                w -= m[r * bs + t] * m[s * bs + t];
                            }
                            m[r * bs + s] = w * rpiv;
                        }
                        for r in 0..s {
                            m[r * bs + s] = 0.0;
                        }
                    }
                    self.a[o..o + bb].copy_from_slice(m);
                }
            }
        }
        Ok(())
    }

    /// Solves A x = b in place for `ncols` columns (b in the original block order, unknown-major).
    fn solve(&mut self, b: &mut [f64], ncols: usize) {
        match (self.bs, ncols) {
            (1, 1) => self.solve_impl::<1, 1>(b),
            (1, 2) => self.solve_impl::<1, 2>(b),
            (1, 3) => self.solve_impl::<1, 3>(b),
            (2, 1) => self.solve_impl::<2, 1>(b),
            (3, 1) => self.solve_impl::<3, 1>(b),
            _ => self.solve_general(b, ncols),
        }
    }

    fn solve_general(&mut self, b: &mut [f64], ncols: usize) {
        // Block size and column count at run time (d > 3).
        self.solve_inner(b, self.bs, ncols);
    }

    /// [`Banded::solve`] with block size and column count compile-time constants.
    fn solve_impl<const BS: usize, const NC: usize>(&mut self, b: &mut [f64]) {
        self.solve_inner(b, BS, NC);
    }

    #[inline(always)]
    fn solve_inner(&mut self, b: &mut [f64], bs: usize, ncols: usize) {
        let (bw, nb) = (self.bw, self.nb);
        let row = bs * ncols;
        let w = &mut self.work[..nb * row];
        for i in 0..nb {
            let p = self.pos[i];
            w[p * row..(p + 1) * row].copy_from_slice(&b[i * row..(i + 1) * row]);
        }
        let a = &self.a;
        let rd = &self.rdiag;
        let bb = bs * bs;
        let at = |p: usize, t: usize| (p * (bw + 1) + t) * bb;
        // The unknowns of one block row are accumulated in a local buffer (no stores to `w`
        // between the contributions of its neighbours).
        let mut buf = [0.0; 16];
        let mut vbuf = Vec::new();
        let x: &mut [f64] = if row <= buf.len() {
            &mut buf[..row]
        } else {
            vbuf.resize(row, 0.0);
            &mut vbuf
        };
        // Forward: L x = b.
        for p in 0..nb {
            x.copy_from_slice(&w[p * row..(p + 1) * row]);
            for c in p.saturating_sub(bw)..p {
                let blk = &a[at(p, p - c)..at(p, p - c) + bb];
                let xc = &w[c * row..(c + 1) * row];
                for r in 0..bs {
                    for e in 0..ncols {
                        let mut acc = 0.0;
                        for t in 0..bs {
                            acc += blk[r * bs + t] * xc[t * ncols + e];
                        }
                        x[r * ncols + e] -= acc;
                    }
                }
            }
            let dg = &a[at(p, 0)..at(p, 0) + bb];
            let rp = &rd[p * bs..(p + 1) * bs];
            for r in 0..bs {
                for e in 0..ncols {
                    let mut v = x[r * ncols + e];
                    for t in 0..r {
                        v -= dg[r * bs + t] * x[t * ncols + e];
                    }
                    x[r * ncols + e] = v * rp[r];
                }
            }
            w[p * row..(p + 1) * row].copy_from_slice(x);
        }
        // Backward: Lᵀ x = y.
        for p in (0..nb).rev() {
            x.copy_from_slice(&w[p * row..(p + 1) * row]);
            for rr in p + 1..(p + bw + 1).min(nb) {
                let blk = &a[at(rr, rr - p)..at(rr, rr - p) + bb];
                let xr = &w[rr * row..(rr + 1) * row];
                for s in 0..bs {
                    for e in 0..ncols {
                        let mut acc = 0.0;
                        for t in 0..bs {
                            acc += blk[t * bs + s] * xr[t * ncols + e];
                        }
                        x[s * ncols + e] -= acc;
                    }
                }
            }
            let dg = &a[at(p, 0)..at(p, 0) + bb];
            let rp = &rd[p * bs..(p + 1) * bs];
            for r in (0..bs).rev() {
                for e in 0..ncols {
                    let mut v = x[r * ncols + e];
                    for t in r + 1..bs {
                        v -= dg[t * bs + r] * x[t * ncols + e];
                    }
                    x[r * ncols + e] = v * rp[r];
                }
            }
            w[p * row..(p + 1) * row].copy_from_slice(x);
        }
        for i in 0..nb {
            let p = self.pos[i];
            b[i * row..(i + 1) * row].copy_from_slice(&w[p * row..(p + 1) * row]);
        }
    }
}

/// The matrix H ⊗ I_d + D (D at the data vertices of the balls, fixed data vertices
/// eliminated) and its factor: its Schur complement on the data vertices is Q + D, so the data
/// part of the solution of (H ⊗ I + D) Δp = (r at the data vertices, 0 elsewhere) is
/// Δy = (Q + D)⁻¹ r, with no inverse of D (which vanishes at inactive vertices).
struct NewtonSystem<'a> {
    sys: energy::System,
    factor: Option<energy::Factor>,
    /// The vertex of each (condensed) data point.
    vertices: &'a [usize],
    rhs: Vec<f64>,
}

impl NewtonSystem<'_> {
    /// Rebuilds H ⊗ I + D with D_i = `blocks[i]` (d × d) at the balls' data vertices and factors
    /// it.
    fn build(&mut self, ball: &[bool], blocks: &[f64], d: usize) -> Result<(), Error> {
        self.factor = None;
        self.sys.clear_blocks();
        for (i, _) in ball.iter().enumerate().filter(|(_, &b)| b) {
            self.sys
                .add_block(self.vertices[i], &blocks[i * d * d..(i + 1) * d * d])?;
        }
        self.factor = Some(
            self.sys
                .factor_with_tolerance(crate::backend::full::NEWTON_PIVOT_RTOL)?,
        );
        Ok(())
    }

    /// dy = (Q + D)⁻¹ r on the balls (0 at fixed data points).
    fn solve(&mut self, ball: &[bool], r: &[f64], dy: &mut [f64], d: usize) {
        self.rhs.fill(0.0);
        for (i, _) in ball.iter().enumerate().filter(|(_, &b)| b) {
            let v = self.vertices[i];
            self.rhs[v * d..(v + 1) * d].copy_from_slice(&r[i * d..(i + 1) * d]);
        }
        if let Some(f) = &self.factor {
            // The length is N·d by construction.
            let _ = f.solve_flat(&mut self.rhs);
        }
        for (i, &b) in ball.iter().enumerate() {
            let o = i * d;
            if b {
                let v = self.vertices[i];
                dy[o..o + d].copy_from_slice(&self.rhs[v * d..(v + 1) * d]);
            } else {
                dy[o..o + d].fill(0.0);
            }
        }
    }
}

/// The optimum of the condensed balls problem.
pub(crate) struct CondensedSolution {
    /// The refined vertices (data vertices at y, free vertices by the second pass).
    pub points: Points,
    /// Multipliers in the conventions of [`crate::Refinement::multipliers`]: `[w_i]` for
    /// ε_i > 0, the reaction −(Hp)_{i_k} for ε_i = 0.
    pub multipliers: Vec<Vec<f64>>,
    /// Interior-point iterations.
    pub iterations: usize,
    /// False when the caller's acceptance test refused the curve, at the judging residual, at
    /// the end or after the polish (a working-set round; `multipliers` is then empty).
    pub complete: bool,
}

/// Q = Kᵀ T⁻¹ K ⊗ I_d applied to y, with T's factor; returns E(y) = ½ yᵀ Q y.
struct QOp<'a, const D: usize> {
    cond: &'a Condensation,
    t: Banded,
    u: Vec<f64>,
    s: Vec<f64>,
    d: usize,
}

impl<const D: usize> QOp<'_, D> {
    /// out = Q y; afterwards `self.s` = T⁻¹ K y (the data-row values).
    fn apply(&mut self, y: &[f64], out: &mut [f64]) -> f64 {
        let d = if D == 0 { self.d } else { D };
        self.cond.apply_k(y, d, &mut self.u);
        self.s.copy_from_slice(&self.u);
        self.t.solve(&mut self.s, d);
        self.cond.apply_kt(&self.s, d, out);
        0.5 * self.u.iter().zip(&self.s).map(|(a, b)| a * b).sum::<f64>()
    }
}

/// Solves the balls problem with radii `radii` (0 = interpolate) at the data vertices
/// 0, stride, 2·stride, … of `knots`, by the working-set method of the module docs.
///
/// # Errors
/// [`Error::Energy`] (`Singular`) if a pivot fails (impossible for valid knots and positive
/// radii; reported rather than assumed); [`Error::NotConverged`] with the best residual when the
/// method does not reach `tolerance` ([`CONDENSED_TOLERANCE`], [`CONDENSED_STRICT_TOLERANCE`])
/// within [`CONDENSED_MAX_ITERATIONS`] (on the working set and then on all balls).
pub(crate) fn solve_balls(
    knots: &Knots,
    stencil: &Stencil,
    q: &Points,
    radii: &[f64],
    stride: usize,
    tolerance: f64,
    start: Option<&[bool]>,
) -> Result<CondensedSolution, Error> {
    // Each round costs O(N) passes besides the interior-point method on the set: with few balls
    // or many vertices per span a single round on all balls is cheaper.
    // (So is a start set holding most balls: most are active.)
    let dense = start.is_some_and(|s| {
        s.iter().filter(|&&a| a).count() as f64 > WORKING_SET_DENSE * q.len() as f64
    });
    let step = if q.len() < WORKING_SET_MIN_POINTS || stride > WORKING_SET_MAX_STRIDE || dense {
        1
    } else {
        (q.len() / WORKING_SET_START_POINTS).clamp(1, WORKING_SET_START_STEP)
    };
    solve_balls_from(knots, stencil, q, radii, stride, tolerance, step, start)
}

/// [`solve_balls`] with the working set started from every `step`-th ball (1: all balls, a
/// single round) and the balls marked in `start`.
#[allow(clippy::too_many_arguments)]
fn solve_balls_from(
    knots: &Knots,
    stencil: &Stencil,
    q: &Points,
    radii: &[f64],
    stride: usize,
    tolerance: f64,
    step: usize,
    start: Option<&[bool]>,
) -> Result<CondensedSolution, Error> {
    let n = q.len();
    let d = q.dim();
    let closed = knots.is_closed();
    // The fixed points and the ends of an open curve are always in the working set; of the
    // balls, every `step`-th to start with.
    let mut work: Vec<bool> = (0..n)
        .map(|i| {
            radii[i] == 0.0
                || i % step == 0
                || (!closed && i + 1 == n)
                || start.is_some_and(|s| s.get(i) == Some(&true))
        })
        .collect();
    let mut iterations = 0;
    // (point, |p − q|/ε) of the balls outside the set whose points are near their spheres.
    let mut near: Vec<(usize, f64)> = Vec::new();
    let mut ratio = vec![0.0; n];
    let mut prev: Option<Condensation> = None;
    let mut rounds = 0;
    loop {
        let idx: Vec<usize> = (0..n).filter(|&i| work[i]).collect();
        let everything = idx.len() == n;
        let mut coords = Vec::with_capacity(idx.len() * d);
        for &i in &idx {
            coords.extend_from_slice(q.point(i));
        }
        let qw = Points::new(d, coords)?;
        let rw: Vec<f64> = idx.iter().map(|&i| radii[i]).collect();
        let vertices: Vec<usize> = idx.iter().map(|&i| i * stride).collect();
        // (The spans the new points do not split keep their factors.)
        let cond = Condensation::at_vertices_reusing(knots, stencil, vertices, prev.take())?;
        // The curve of a round is accepted when it stays inside every ball outside the set.
        let mut accept = |p: &Points| {
            near.clear();
            for i in (0..n).filter(|&i| !work[i]) {
                let r = dist(p.point(i * stride), q.point(i)) / radii[i];
                if r >= 1.0 - WORKING_SET_NEAR {
                    near.push((i, r));
                }
            }
            !near.iter().any(|v| v.1 >= 1.0 - WORKING_SET_MARGIN)
        };
        let sub = match d {
            1 => solve_balls_d::<1>(knots, stencil, &qw, &rw, &cond, tolerance, &mut accept),
            2 => solve_balls_d::<2>(knots, stencil, &qw, &rw, &cond, tolerance, &mut accept),
            3 => solve_balls_d::<3>(knots, stencil, &qw, &rw, &cond, tolerance, &mut accept),
            _ => solve_balls_d::<0>(knots, stencil, &qw, &rw, &cond, tolerance, &mut accept),
        };
        prev = Some(cond);
        let sub = match sub {
            Ok(sub) => sub,
            // A round that fails on a subset is repeated on all balls.
            Err(_) if !everything => {
                work.fill(true);
                continue;
            }
            Err(e) => return Err(e),
        };
        iterations += sub.iterations;
        if sub.complete {
            let mut multipliers = vec![vec![0.0]; n];
            for (m, &i) in sub.multipliers.into_iter().zip(&idx) {
                multipliers[i] = m;
            }
            return Ok(CondensedSolution {
                points: sub.points,
                multipliers,
                iterations,
                complete: true,
            });
        }
        rounds += 1;
        let outside = n - idx.len();
        if rounds >= WORKING_SET_MAX_ROUNDS
            || (rounds >= WORKING_SET_DENSE_ROUND
                && near.len() as f64 > WORKING_SET_DENSE * outside as f64)
        {
            // (A bound on the work: the next round takes every ball. So does a later round that
            // still leaves most balls outside the set violated: most balls are active.)
            work.fill(true);
        } else if near.len() * WORKING_SET_ADD_ALL <= idx.len() {
            // Few left: all of them (and the near ones) join.
            for &(i, _) in &near {
                work[i] = true;
            }
        } else {
            // Many: only those leaving their balls farthest within WORKING_SET_WINDOW points on
            // either side (the curve moves near them, which settles most of the others).
            for &(i, r) in &near {
                ratio[i] = r;
            }
            for &(i, r) in &near {
                let top = r >= 1.0 - WORKING_SET_MARGIN
                    && (1..=WORKING_SET_WINDOW.min(n / 2)).all(|o| {
                        let right = if closed || i + o < n {
                            Some((i + o) % n)
                        } else {
                            None
                        };
                        let left = if closed || i >= o {
                            Some((i + n - o) % n)
                        } else {
                            None
                        };
                        [right, left]
                            .into_iter()
                            .flatten()
                            .all(|j| match ratio[j].total_cmp(&r) {
                                std::cmp::Ordering::Less => true,
                                std::cmp::Ordering::Equal => j > i,
                                std::cmp::Ordering::Greater => false,
                            })
                    });
                if top {
                    work[i] = true;
                }
            }
            for &(i, _) in &near {
                ratio[i] = 0.0;
            }
        }
    }
}

/// The working-set method runs with at least this many data points (fewer: one round on all
/// balls).
pub const WORKING_SET_MIN_POINTS: usize = 64;
/// The working-set method runs with at most this many vertices per span, k + 1 (more: the O(N)
/// passes of each round outweigh the interior-point work saved; one round on all balls).
pub const WORKING_SET_MAX_STRIDE: usize = 32;
/// The working set starts with about this many balls (every
/// n / `WORKING_SET_START_POINTS`-th, at most every [`WORKING_SET_START_STEP`]-th).
pub const WORKING_SET_START_POINTS: usize = 4;
/// The working set starts with at least every this-many-th ball.
pub const WORKING_SET_START_STEP: usize = 64;
/// A ball outside the working set whose point is at least this close (relative to its radius)
/// to its sphere counts as violated: the round is not accepted.
pub const WORKING_SET_MARGIN: f64 = 1e-9;
/// Balls outside the working set within this relative distance of their spheres are "near":
/// when few balls are violated, the near ones join the set with them (they are the likely
/// next violations).
pub const WORKING_SET_NEAR: f64 = 0.02;
/// When the near balls number at most 1/this of the working set, all of them join; otherwise
/// only the local maxima of |p − q|/ε within [`WORKING_SET_WINDOW`] points.
pub const WORKING_SET_ADD_ALL: usize = 2;
/// After this many rounds the working set becomes all balls (one more round ends the method),
/// which bounds its work at this many + 1 solves however the sets grow.
pub const WORKING_SET_MAX_ROUNDS: usize = 16;
/// From round [`WORKING_SET_DENSE_ROUND`] on, when more than this fraction of the balls outside
/// the working set are (nearly) violated, the next round takes all balls: most balls are active
/// and the rounds would add them a few at a time. A start set (the previous knot iteration's active balls)
/// holding more than this fraction of the balls also means one round on all balls.
pub const WORKING_SET_DENSE: f64 = 0.5;
/// The round from which [`WORKING_SET_DENSE`] applies (earlier rounds, from a small start set,
/// leave most balls violated whether or not most are active: n = 10³ on the bench curve).
pub const WORKING_SET_DENSE_ROUND: usize = 4;
/// Half-width (in data points) of the window of the local-maximum rule.
pub const WORKING_SET_WINDOW: usize = 16;

/// [`solve_balls`] with the dimension a compile-time constant for d = 1, 2, 3 (`D` = 0: any d,
/// read from the data), so the per-coordinate loops unroll.
fn solve_balls_d<const D: usize>(
    knots: &Knots,
    stencil: &Stencil,
    q: &Points,
    radii: &[f64],
    cond: &Condensation,
    tolerance: f64,
    accept: &mut dyn FnMut(&Points) -> bool,
) -> Result<CondensedSolution, Error> {
    let n = q.len();
    let d = if D == 0 { q.dim() } else { D };
    let m = d + 1;
    let vertices = &cond.vertices;
    let size = cond.len();
    let closed = cond.closed;
    let singular = |j: usize| {
        Error::from(energy::Error::Singular {
            vertex: vertices[j],
        })
    };
    let ball: Vec<bool> = radii.iter().map(|&e| e > 0.0).collect();
    let nballs = ball.iter().filter(|&&b| b).count();
    let qc = q.coords();

    // T (scalar, d columns) for applying Q.
    let mut t = Banded::new(size, 1, 1, closed, d);
    for j in 0..size {
        t.add_identity(j, j, cond.diag[j]);
        if closed || j + 1 < size {
            t.add_identity(j, (j + 1) % size, cond.off[j]);
        }
    }
    t.factor().map_err(|j| singular(cond.first + j))?;
    let mut qop = QOp::<D> {
        cond,
        t,
        u: vec![0.0; size * d],
        s: vec![0.0; size * d],
        d,
    };
    // S = T + K D⁻¹ Kᵀ (blocks of d).
    let mut sm = Banded::new(size, d, 2, closed, 1);
    // Rows of K touching each data point: (row, coefficient).
    let mut touching: Vec<[(usize, f64); 3]> = vec![[(usize::MAX, 0.0); 3]; n];
    let mut ntouch = vec![0usize; n];
    for (j, kr) in cond.krows.iter().enumerate() {
        for (tt, &kv) in kr.iter().enumerate() {
            let c = cond.col(j, tt);
            touching[c][ntouch[c]] = (j, kv);
            ntouch[c] += 1;
        }
    }

    // Length and force scales.
    let mut centroid = vec![0.0; d];
    for x in q.iter() {
        for (c, v) in centroid.iter_mut().zip(x) {
            *c += v / n as f64;
        }
    }
    let length = q
        .iter()
        .flat_map(|x| x.iter().zip(&centroid).map(|(a, b)| (a - b).abs()))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);

    // ρ of CONDENSED_REGULARIZATION: Q_ii = Σ_j K_ji² (T⁻¹)_jj, estimated with 1/T_jj.
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
    let mut rho = CONDENSED_REGULARIZATION * qmax;

    let mut step: f64 = 0.0;
    for i in 0..n {
        let j = if i + 1 == n { 0 } else { i + 1 };
        if j > i || closed {
            for c in 0..d {
                step = step.max((qc[j * d + c] - qc[i * d + c]).abs());
            }
        }
    }
    let step = step.max(f64::MIN_POSITIVE);

    let mut y = qc.to_vec();
    let mut g = vec![0.0; n * d];
    qop.apply(&y, &mut g);
    let f0 = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let f_init = if f0 > 0.0 { f0 } else { qmax * step };
    // s = (ε, 0) (the centre of each cone, y = q) and z = (F, 0): s∘z = (ε F, 0).
    let mut s = vec![0.0; n * m];
    let mut z = vec![0.0; n * m];
    for i in 0..n {
        if ball[i] {
            s[i * m] = radii[i];
            z[i * m] = f_init;
        }
    }

    let mut rd = vec![0.0; n * d];
    let mut rp = vec![0.0; n * m];
    let mut sc = vec![0.0; n * (m + 1)];
    let mut lam = vec![0.0; n * m];
    let mut dinv = vec![0.0; n * d * d];
    let mut dfac = vec![0.0; n * d * d]; // D itself, for the refinement residual
    let mut scv: Vec<f64> = Vec::with_capacity(m + 1);
    let mut xi = vec![0.0; n * m];
    let (mut dy, mut dz, mut ds) = (vec![0.0; n * d], vec![0.0; n * m], vec![0.0; n * m]);
    let (mut dya, mut dza, mut dsa) = (vec![0.0; n * d], vec![0.0; n * m], vec![0.0; n * m]);
    let mut ns = NewtonWork {
        r: vec![0.0; n * d],
        w: vec![0.0; size * d],
        kt: vec![0.0; n * d],
        res: vec![0.0; n * d],
        corr: vec![0.0; n * d],
        qd: vec![0.0; n * d],
        tm: vec![0.0; m],
        tm2: vec![0.0; m],
    };
    let (mut ca, mut cc, mut t1, mut t2) = (vec![0.0; m], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    let mut best = f64::INFINITY;
    let (mut best_y, mut best_z) = (y.clone(), z.clone());
    let mut stalled = false;
    let mut judged = false;
    let mut iterations = 0;
    let mut residual;
    let cone = |v: &[f64], i: usize| -> std::ops::Range<usize> {
        let _ = v;
        i * m..(i + 1) * m
    };
    loop {
        // Residuals at (y, s, z): r_d = Qy + z₁, r_p = s − (ε, q − y).
        let energy = qop.apply(&y, &mut g);
        let (mut rdn, mut rpn): (f64, f64) = (0.0, 0.0);
        let mut fscale: f64 = 0.0;
        let mut gap = 0.0;
        for i in 0..n {
            for c in 0..d {
                fscale = fscale.max(g[i * d + c].abs());
            }
            if !ball[i] {
                rd[i * d..(i + 1) * d].fill(0.0);
                continue;
            }
            let o = i * m;
            rp[o] = s[o] - radii[i];
            rpn = rpn.max(rp[o].abs());
            gap += s[o] * z[o];
            for c in 0..d {
                let z1 = z[o + 1 + c];
                rd[i * d + c] = g[i * d + c] + z1;
                rdn = rdn.max(rd[i * d + c].abs());
                fscale = fscale.max(z1.abs());
                rp[o + 1 + c] = s[o + 1 + c] - (qc[i * d + c] - y[i * d + c]);
                rpn = rpn.max(rp[o + 1 + c].abs());
                gap += s[o + 1 + c] * z1;
            }
        }
        // Floors from fixed scales, as in the certificate: forces ‖Q‖ δ (δ the largest
        // coordinate step between consecutive data points; Qy is computed from such
        // differences), energies at rounding level of forces × lengths — for optima with E* = 0
        // (e.g. data within reach of a straight open curve).
        let fscale = fscale.max(qmax * step);
        let mu = gap / nballs.max(1) as f64;
        residual = (rdn / fscale)
            .max(rpn / length)
            .max(gap.abs() / energy.max(f64::EPSILON * fscale * length));
        if residual < best {
            best = residual;
            best_y.copy_from_slice(&y);
            best_z.copy_from_slice(&z);
        }
        if residual <= tolerance || nballs == 0 {
            break;
        }
        // A working-set round is judged once the iterate is good enough to tell which balls
        // outside the set the curve leaves: only a round that is accepted there goes on to the
        // full tolerance (and is judged again at the end).
        if !judged && residual <= CONDENSED_ROUND_TOLERANCE {
            judged = true;
            let points = cond.reconstruct(knots, stencil, &y, &qop.s, d)?;
            if !accept(&points) {
                return Ok(CondensedSolution {
                    points,
                    multipliers: Vec::new(),
                    iterations,
                    complete: false,
                });
            }
        }
        if iterations >= CONDENSED_MAX_ITERATIONS {
            stalled = true;
            break;
        }
        iterations += 1;

        // NT scalings, λ = V z, D⁻¹, and S = T + K D⁻¹ Kᵀ; ρ grows (see
        // CONDENSED_MAX_REGULARIZATION) while S does not factor.
        let mut factored = false;
        loop {
            // NT scalings, λ = V z, D⁻¹, and S = T + K D⁻¹ Kᵀ.
            sm.clear();
            for j in 0..size {
                sm.add_identity(j, j, cond.diag[j]);
                if closed || j + 1 < size {
                    sm.add_identity(j, (j + 1) % size, cond.off[j]);
                }
            }
            for i in 0..n {
                if !ball[i] {
                    continue;
                }
                let zi = &z[cone(&z, i)];
                scaling(Kind::SecondOrder, &s[cone(&s, i)], zi, &mut scv);
                sc[i * (m + 1)..(i + 1) * (m + 1)].copy_from_slice(&scv);
                let l = &mut lam[i * m..(i + 1) * m];
                l.copy_from_slice(zi);
                apply_v(Kind::SecondOrder, &scv, l, false);
                // D = a I + b w̄₁w̄₁ᵀ, a = η⁻², b = 2η⁻²; D + ρI has the eigenvalue a + ρ + b|w̄₁|²
                // along u = w̄₁/|w̄₁| and a + ρ across it, inverted per eigenspace (no cancellation
                // when b|w̄₁|² ≫ a, on active cones).
                let eta2 = scv[0] * scv[0];
                let w1 = &scv[2..];
                let w2: f64 = w1.iter().map(|v| v * v).sum();
                let (da, db) = (1.0 / eta2, 2.0 / eta2);
                let ar = da + rho;
                let (inv_across, inv_along) = (1.0 / ar, 1.0 / (ar + db * w2));
                let wn = w2.sqrt();
                let di = &mut dinv[i * d * d..(i + 1) * d * d];
                let df = &mut dfac[i * d * d..(i + 1) * d * d];
                for a in 0..d {
                    for b in 0..d {
                        let id = if a == b { 1.0 } else { 0.0 };
                        let uu = if wn > 0.0 {
                            (w1[a] / wn) * (w1[b] / wn)
                        } else {
                            0.0
                        };
                        di[a * d + b] = inv_across * (id - uu) + inv_along * uu;
                        df[a * d + b] = da * id + db * w1[a] * w1[b];
                    }
                }
                let nt = ntouch[i];
                for x in 0..nt {
                    let (jx, kx) = touching[i][x];
                    sm.add(jx, jx, kx * kx, di);
                    for &(jy, ky) in &touching[i][x + 1..nt] {
                        sm.add(jx, jy, kx * ky, di);
                    }
                }
            }
            if sm.factor().is_ok() {
                factored = true;
                break;
            }
            if rho >= CONDENSED_MAX_REGULARIZATION * qmax {
                break;
            }
            rho *= CONDENSED_REGULARIZATION_GROWTH;
        }
        if !factored {
            stalled = true;
            break;
        }
        let mut ctx = NewtonCtx::<D> {
            cond,
            ball: &ball,
            sc: &sc,
            dinv: &dinv,
            dfac: &dfac,
            rp: &rp,
            d,
            refine: 0,
            rtol: (CONDENSED_NEWTON_ACCURACY * residual).max(CONDENSED_REFINEMENT_RTOL),
        };

        // Predictor: ξ = −λ.
        for (x, l) in xi.iter_mut().zip(&lam) {
            *x = -l;
        }
        ctx.solve(
            &mut sm, &mut qop, &rd, &xi, &mut dya, &mut dsa, &mut dza, &mut ns,
        );
        let mut alpha_a: f64 = 1.0;
        for i in (0..n).filter(|&i| ball[i]) {
            let r = cone(&s, i);
            alpha_a = max_step(Kind::SecondOrder, &s[r.clone()], &dsa[r.clone()], alpha_a);
            alpha_a = max_step(Kind::SecondOrder, &z[r.clone()], &dza[r], alpha_a);
        }
        let mut gap_a = 0.0;
        for i in (0..n).filter(|&i| ball[i]) {
            for k in cone(&s, i) {
                gap_a += (s[k] + alpha_a * dsa[k]) * (z[k] + alpha_a * dza[k]);
            }
        }
        let sigma = if gap > 0.0 {
            (gap_a / gap).clamp(0.0, 1.0).powi(3)
        } else {
            0.0
        };
        // Corrector: ξ = λ⁻¹ ∘ (σμe − λ∘λ − (V⁻¹Δs_a)∘(VΔz_a)).
        for i in (0..n).filter(|&i| ball[i]) {
            let scv = &sc[i * (m + 1)..(i + 1) * (m + 1)];
            let r = cone(&s, i);
            ca.copy_from_slice(&dsa[r.clone()]);
            apply_v(Kind::SecondOrder, scv, &mut ca, true);
            cc.copy_from_slice(&dza[r.clone()]);
            apply_v(Kind::SecondOrder, scv, &mut cc, false);
            jordan(Kind::SecondOrder, &ca, &cc, &mut t1);
            let l = &lam[r.clone()];
            jordan(Kind::SecondOrder, l, l, &mut t2);
            for k in 0..m {
                t2[k] = -t2[k] - t1[k];
            }
            t2[0] += sigma * mu;
            jordan_div(Kind::SecondOrder, l, &t2, &mut xi[r]);
        }
        ctx.refine = CONDENSED_MAX_REFINEMENT_STEPS;
        ctx.solve(
            &mut sm, &mut qop, &rd, &xi, &mut dy, &mut ds, &mut dz, &mut ns,
        );
        let mut alpha: f64 = 1.0 / CONDENSED_STEP_FRACTION;
        for i in (0..n).filter(|&i| ball[i]) {
            let r = cone(&s, i);
            alpha = max_step(Kind::SecondOrder, &s[r.clone()], &ds[r.clone()], alpha);
            alpha = max_step(Kind::SecondOrder, &z[r.clone()], &dz[r], alpha);
        }
        let alpha = (CONDENSED_STEP_FRACTION * alpha).min(1.0);
        if !(alpha.is_finite() && alpha > 0.0) || dy.iter().any(|v| !v.is_finite()) {
            stalled = true;
            break;
        }
        for (a, b) in y.iter_mut().zip(&dy) {
            *a += alpha * b;
        }
        for i in (0..n).filter(|&i| ball[i]) {
            for k in cone(&s, i) {
                s[k] += alpha * ds[k];
                z[k] += alpha * dz[k];
            }
        }
    }

    if stalled {
        if best > CONDENSED_ACCEPT {
            return Err(Error::NotConverged {
                solver: "condensed balls interior-point method",
                iterations,
                residual: best,
            });
        }
        y.copy_from_slice(&best_y);
        z.copy_from_slice(&best_z);
        qop.apply(&y, &mut g);
    }
    // The curve at the interior-point result (qop.s holds T⁻¹Ky for this y); a round of the
    // working-set method that does not accept it ends here, unpolished.
    let unpolished = cond.reconstruct(knots, stencil, &y, &qop.s, d)?;
    if !accept(&unpolished) {
        return Ok(CondensedSolution {
            points: unpolished,
            multipliers: Vec::new(),
            iterations,
            complete: false,
        });
    }
    let mut polished = false;
    // Active-set polish (see CONDENSED_POLISH_STEPS).
    let mut w: Vec<f64> = (0..n)
        .map(|i| if ball[i] { z[i * m] / radii[i] } else { 0.0 })
        .collect();
    {
        let mut active: Vec<bool> = (0..n)
            .map(|i| {
                ball[i]
                    && radii[i] - dist(&y[i * d..(i + 1) * d], &qc[i * d..(i + 1) * d])
                        <= CONDENSED_POLISH_ACTIVE_RTOL * radii[i]
            })
            .collect();
        let stationarity = |g: &[f64], y: &[f64], w: &[f64]| -> f64 {
            let mut r: f64 = 0.0;
            for i in (0..n).filter(|&i| ball[i]) {
                for c in 0..d {
                    let v = g[i * d + c] + w[i] * (y[i * d + c] - qc[i * d + c]);
                    r = r.max(v.abs());
                }
            }
            r
        };
        qop.apply(&y, &mut g);
        let mut current = stationarity(&g, &y, &w);
        // The force scale of the residuals (as in the iterations).
        let fscale = g.iter().fold(qmax * step, |a, v| a.max(v.abs()));
        let polish_steps = if current <= CONDENSED_POLISH_SKIP * fscale
            && tolerance > CONDENSED_STRICT_TOLERANCE
        {
            0
        } else {
            CONDENSED_POLISH_STEPS
        };
        let mut yp = y.clone();
        let mut wp = w.clone();
        let mut rhs = vec![0.0; n * d];
        let mut u = vec![0.0; d];
        // The polish's Newton systems: H ⊗ I_d + D at the data vertices, fixed ones eliminated
        // (D vanishes at inactive vertices, so it is not eliminated through D⁻¹ as in the
        // interior-point iterations).
        let mut full = if polish_steps > 0 {
            let mut sys = super::fixed::hessian_system(knots, d)?;
            for i in (0..n).filter(|&i| !ball[i]) {
                sys.fix(vertices[i])?;
            }
            Some(NewtonSystem {
                sys,
                factor: None,
                vertices,
                rhs: vec![0.0; knots.vertex_count() * d],
            })
        } else {
            None
        };
        let mut changes = 0;
        let mut taken = 0;
        while taken < polish_steps {
            taken += 1;
            // Newton step on Qy + w(y − q) = 0, |y_i − q_i| = ε_i (active), with the normal
            // direction held by the penalty M: (Q + W + M uuᵀ)Δy = −(Qy + w(y − q)).
            qop.apply(&yp, &mut g);
            let stiff = CONDENSED_POLISH_STIFFNESS * qmax;
            for i in 0..n {
                let o = i * d;
                if !ball[i] {
                    rhs[o..o + d].fill(0.0);
                    continue;
                }
                let df = &mut dfac[i * d * d..(i + 1) * d * d];
                if active[i] {
                    let gap = dist(&yp[o..o + d], &qc[o..o + d]);
                    for c in 0..d {
                        u[c] = (yp[o + c] - qc[o + c]) / gap;
                    }
                    // Least-squares multiplier at the current point.
                    let wi = (-(0..d).map(|c| g[o + c] * u[c]).sum::<f64>() / gap).max(0.0);
                    wp[i] = wi;
                    for a in 0..d {
                        for b in 0..d {
                            let id = if a == b { 1.0 } else { 0.0 };
                            df[a * d + b] = wi * id + stiff * u[a] * u[b];
                        }
                        rhs[o + a] = -(g[o + a] + wi * (yp[o + a] - qc[o + a]))
                            + stiff * (radii[i] - gap) * u[a];
                    }
                } else {
                    wp[i] = 0.0;
                    df.fill(0.0);
                    for a in 0..d {
                        rhs[o + a] = -g[o + a];
                    }
                }
            }
            let Some(full) = full.as_mut() else { break };
            if full.build(&ball, &dfac, d).is_err() {
                break;
            }
            full.solve(&ball, &rhs, &mut dy, d);
            for (a, b) in yp.iter_mut().zip(&dy) {
                *a += b;
            }
            // Back onto the spheres. An inactive vertex outside its ball, or an active one
            // whose multiplier turns negative, means a wrong active set: it is changed and the
            // step retried from y (at most CONDENSED_POLISH_ACTIVE_CHANGES times).
            let mut changed = Vec::new();
            for i in (0..n).filter(|&i| ball[i]) {
                let o = i * d;
                let gap = dist(&yp[o..o + d], &qc[o..o + d]);
                if active[i] {
                    for c in 0..d {
                        yp[o + c] = qc[o + c] + radii[i] * (yp[o + c] - qc[o + c]) / gap;
                    }
                } else if gap > radii[i] {
                    changed.push(i);
                }
            }
            if changed.is_empty() {
                qop.apply(&yp, &mut g);
                for i in (0..n).filter(|&i| active[i]) {
                    let o = i * d;
                    let gap = dist(&yp[o..o + d], &qc[o..o + d]);
                    let wi = -(0..d)
                        .map(|c| g[o + c] * (yp[o + c] - qc[o + c]))
                        .sum::<f64>()
                        / (gap * gap);
                    if wi < 0.0 {
                        changed.push(i);
                    }
                    wp[i] = wi.max(0.0);
                }
            }
            if !changed.is_empty() {
                if changes == CONDENSED_POLISH_ACTIVE_CHANGES
                    || changed.iter().any(|&i| {
                        !active[i] && dist(&y[i * d..(i + 1) * d], &qc[i * d..(i + 1) * d]) <= 0.0
                    })
                {
                    break;
                }
                changes += 1;
                taken -= 1;
                for &i in &changed {
                    active[i] = !active[i];
                }
                yp.copy_from_slice(&y);
                wp.copy_from_slice(&w);
                continue;
            }
            let next = stationarity(&g, &yp, &wp);
            if next < current {
                current = next;
                polished = true;
                y.copy_from_slice(&yp);
                w.copy_from_slice(&wp);
            } else {
                break;
            }
        }
        qop.apply(&y, &mut g);
    }
    // The curve: data-row values at the final y (left in qop.s by the last Q y) and the
    // second pass.
    let points = if polished {
        // The polish moves the curve a little: a working-set round judges it again.
        let points = cond.reconstruct(knots, stencil, &y, &qop.s, d)?;
        if !accept(&points) {
            return Ok(CondensedSolution {
                points,
                multipliers: Vec::new(),
                iterations,
                complete: false,
            });
        }
        points
    } else {
        unpolished
    };
    let multipliers = (0..n)
        .map(|i| {
            if ball[i] {
                vec![w[i]]
            } else {
                g[i * d..(i + 1) * d].iter().map(|v| -v).collect()
            }
        })
        .collect();
    Ok(CondensedSolution {
        points,
        multipliers,
        iterations,
        complete: true,
    })
}

/// Buffers of the Newton solves.
struct NewtonWork {
    r: Vec<f64>,
    w: Vec<f64>,
    kt: Vec<f64>,
    res: Vec<f64>,
    corr: Vec<f64>,
    qd: Vec<f64>,
    tm: Vec<f64>,
    tm2: Vec<f64>,
}

/// One Newton system's data: scalings, D⁻¹ and D per cone, the primal residual.
struct NewtonCtx<'a, const D: usize> {
    cond: &'a Condensation,
    ball: &'a [bool],
    sc: &'a [f64],
    dinv: &'a [f64],
    dfac: &'a [f64],
    rp: &'a [f64],
    d: usize,
    refine: usize,
    /// Refinement target relative to the right-hand side.
    rtol: f64,
}

impl<const D: usize> NewtonCtx<'_, D> {
    /// Δy = (Q + D)⁻¹ r for r on the ball vertices (zero elsewhere), through S = T + K D⁻¹ Kᵀ
    /// (factored in `sm`).
    fn reduced(&self, sm: &mut Banded, r: &[f64], dy: &mut [f64], nw: &mut NewtonWork) {
        let d = if D == 0 { self.d } else { D };
        let n = self.ball.len();
        // dy ← D⁻¹ r (temporarily), w = K D⁻¹ r.
        for i in 0..n {
            let o = i * d;
            if !self.ball[i] {
                dy[o..o + d].fill(0.0);
                continue;
            }
            let di = &self.dinv[i * d * d..(i + 1) * d * d];
            for a in 0..d {
                dy[o + a] = (0..d).map(|b| di[a * d + b] * r[o + b]).sum();
            }
        }
        self.cond.apply_k(dy, d, &mut nw.w);
        sm.solve(&mut nw.w, 1);
        self.cond.apply_kt(&nw.w, d, &mut nw.kt);
        for i in 0..n {
            let o = i * d;
            if !self.ball[i] {
                continue;
            }
            let di = &self.dinv[i * d * d..(i + 1) * d * d];
            for a in 0..d {
                dy[o + a] = (0..d)
                    .map(|b| di[a * d + b] * (r[o + b] - nw.kt[o + b]))
                    .sum();
            }
        }
    }

    /// Δy = (Q + D)⁻¹ r with iterative refinement against Q + D (D unregularized).
    fn refined(
        &self,
        sm: &mut Banded,
        qop: &mut QOp<'_, D>,
        r: &[f64],
        dy: &mut [f64],
        nw: &mut NewtonWork,
    ) {
        let d = if D == 0 { self.d } else { D };
        let n = self.ball.len();
        self.reduced(sm, r, dy, nw);
        let rnorm = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut last = f64::INFINITY;
        nw.corr.fill(0.0);
        for _ in 0..self.refine {
            // res = r − (Q + D) dy.
            let mut qd = std::mem::take(&mut nw.qd);
            qop.apply(dy, &mut qd);
            for i in 0..n {
                let o = i * d;
                if !self.ball[i] {
                    nw.res[o..o + d].fill(0.0);
                    continue;
                }
                let df = &self.dfac[i * d * d..(i + 1) * d * d];
                for a in 0..d {
                    let ddy: f64 = (0..d).map(|b| df[a * d + b] * dy[o + b]).sum();
                    nw.res[o + a] = r[o + a] - qd[o + a] - ddy;
                }
            }
            nw.qd = qd;
            let rn = nw.res.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if rn > last {
                // Diverging (the regularized factor is too far from Q + D): undo the last
                // correction.
                for (a, b) in dy.iter_mut().zip(&nw.corr) {
                    *a -= b;
                }
                break;
            }
            last = rn;
            if rn <= self.rtol * rnorm {
                break;
            }
            let res = std::mem::take(&mut nw.res);
            let mut corr = std::mem::take(&mut nw.corr);
            self.reduced(sm, &res, &mut corr, nw);
            for (a, b) in dy.iter_mut().zip(&corr) {
                *a += b;
            }
            nw.res = res;
            nw.corr = corr;
        }
    }

    /// Solves the Newton system for (Δy, Δz) given the dual residual `rd` and ξ (Δs = (0, −Δy)).
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &self,
        sm: &mut Banded,
        qop: &mut QOp<'_, D>,
        rd: &[f64],
        xi: &[f64],
        dy: &mut [f64],
        ds: &mut [f64],
        dz: &mut [f64],
        nw: &mut NewtonWork,
    ) {
        let d = if D == 0 { self.d } else { D };
        let m = d + 1;
        let n = self.ball.len();
        // r = −r_d − (V⁻¹(ξ + V⁻¹ r_p))₁.
        for i in 0..n {
            let o = i * d;
            if !self.ball[i] {
                nw.r[o..o + d].fill(0.0);
                continue;
            }
            let scv = &self.sc[i * (m + 1)..(i + 1) * (m + 1)];
            nw.tm2.copy_from_slice(&self.rp[i * m..(i + 1) * m]);
            apply_v(Kind::SecondOrder, scv, &mut nw.tm2, true);
            for k in 0..m {
                nw.tm[k] = xi[i * m + k] + nw.tm2[k];
            }
            apply_v(Kind::SecondOrder, scv, &mut nw.tm, true);
            for c in 0..d {
                nw.r[o + c] = -rd[o + c] - nw.tm[1 + c];
            }
        }
        let r = std::mem::take(&mut nw.r);
        self.refined(sm, qop, &r, dy, nw);
        nw.r = r;
        // Δs = −r_p − (0, Δy), Δz = V⁻¹(ξ − V⁻¹ Δs).
        for i in 0..n {
            if !self.ball[i] {
                continue;
            }
            let scv = &self.sc[i * (m + 1)..(i + 1) * (m + 1)];
            let rp = &self.rp[i * m..(i + 1) * m];
            ds[i * m] = -rp[0];
            for c in 0..d {
                ds[i * m + 1 + c] = -rp[1 + c] - dy[i * d + c];
            }
            for k in 0..m {
                nw.tm2[k] = -ds[i * m + k];
            }
            apply_v(Kind::SecondOrder, scv, &mut nw.tm2, true);
            let out = &mut dz[i * m..(i + 1) * m];
            for k in 0..m {
                out[k] = xi[i * m + k] + nw.tm2[k];
            }
            apply_v(Kind::SecondOrder, scv, out, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use divdiff::{Knots, Points, Topology};
    use proptest::prelude::*;

    use super::super::algorithm::FixedProblem;
    use super::super::certify::{certify, ACTIVE_REL_TOL};
    use super::super::exact::EXACT_KKT_TARGET;
    use super::super::fast::Condensation;
    use super::super::operator::Stencil;
    use super::super::problem::{Constraint, Problem};
    use super::{solve_balls, Banded, CONDENSED_TOLERANCE};

    /// Energies below this times the interpolation energy count as E* = 0.
    const ZERO_ENERGY_RTOL: f64 = 1e-12;

    /// Knots with spacings `h` (closed: one span per vertex; open: one fewer).
    fn knots(h: &[f64], topo: Topology) -> Knots {
        let mut t = vec![0.0];
        for x in h {
            t.push(t.last().unwrap() + x);
        }
        Knots::new(topo, t).unwrap()
    }

    /// (knots, n, stride, data, topology) with n data points, k free vertices per span.
    fn case() -> impl Strategy<Value = (Knots, usize, usize, Vec<f64>, usize)> {
        (3usize..9, 1usize..5, 1usize..4, any::<bool>()).prop_flat_map(|(n, k, d, closed)| {
            let m = k + 1;
            let topo = if closed {
                Topology::Closed
            } else {
                Topology::Open
            };
            let spans = if closed { m * n } else { m * (n - 1) };
            (
                proptest::collection::vec(0.2f64..2.0, spans),
                proptest::collection::vec(-1.0f64..1.0, n * d),
            )
                .prop_map(move |(h, y)| (knots(&h, topo), n, m, y, d))
        })
    }

    fn condensed_energy(cond: &Condensation, y: &[f64], d: usize) -> (f64, Vec<f64>) {
        let size = cond.len();
        let mut t = Banded::new(size, 1, 1, cond.closed, d);
        for j in 0..size {
            t.add_identity(j, j, cond.diag[j]);
            if cond.closed || j + 1 < size {
                t.add_identity(j, (j + 1) % size, cond.off[j]);
            }
        }
        t.factor().unwrap();
        let mut u = vec![0.0; size * d];
        cond.apply_k(y, d, &mut u);
        let mut s = u.clone();
        t.solve(&mut s, d);
        (0.5 * u.iter().zip(&s).map(|(a, b)| a * b).sum::<f64>(), s)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// E(y) = ½ (Ky)ᵀ T⁻¹ (Ky) is the energy (2.1) of the reconstructed curve (computed
        /// by `energy::energy`), that curve is stationary at its free vertices, and Kᵀs is
        /// its gradient (Hp) at the data vertices.
        #[test]
        fn condensed_energy_is_the_minimal_energy((kn, n, m, y, d) in case()) {
            let stencil = Stencil::new(&kn);
            let cond = Condensation::new(&kn, &stencil, n, m).unwrap();
            let (e, s) = condensed_energy(&cond, &y, d);
            let p = cond.reconstruct(&kn, &stencil, &y, &s, d).unwrap();
            let e_full = energy::energy(&kn, &p).unwrap();
            prop_assert!((e - e_full).abs() <= 1e-11 * e_full.max(1.0), "{e} vs {e_full}");
            let (hp, _) = stencil.apply_h(&p);
            let mut kts = vec![0.0; n * d];
            cond.apply_kt(&s, d, &mut kts);
            let scale = hp.iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for v in 0..p.len() {
                for c in 0..d {
                    let want = if v % m == 0 { kts[(v / m) * d + c] } else { 0.0 };
                    prop_assert!((hp[v * d + c] - want).abs() <= 1e-10 * scale,
                        "vertex {v}: Hp {} vs {want}", hp[v * d + c]);
                }
            }
        }

        /// The condensed interior-point optimum is certified at the exact target and agrees
        /// with the full-vertex conic solver's optimum (energies to 1e-8 relative; where that
        /// solver's own result is not certified, the condensed energy is not above it), with
        /// radius-0 (fixed) data points mixed among the balls.
        #[test]
        fn condensed_balls_match_the_conic_solver(
            (kn, n, m, y, d) in case(),
            r in proptest::collection::vec(0.0f64..0.6, 9),
            fixed in proptest::collection::vec(any::<bool>(), 9),
        ) {
            let q = Points::new(d, y).unwrap();
            let radii: Vec<f64> = (0..n).map(|i| if fixed[i] { 0.0 } else { r[i] + 0.01 }).collect();
            prop_assume!(radii.iter().any(|&e| e > 0.0));
            // Valid problems have distinct consecutive data points (Problem::validate).
            prop_assume!((0..n - 1).all(|i| super::super::fixed::dist(q.point(i), q.point(i + 1)) > 0.05));
            let stencil = Stencil::new(&kn);
            let sol = solve_balls(&kn, &stencil, &q, &radii, m, CONDENSED_TOLERANCE, None).unwrap();
            let data_vertex: Vec<usize> = (0..n).map(|i| i * m).collect();
            let c = Constraint::Balls(radii.clone());
            let (cert, _) = certify(&stencil, &sol.points, &q, &data_vertex, &c,
                Some(sol.multipliers.clone()), ACTIVE_REL_TOL, &[]);
            let problem = Problem::new(q.clone()).with_constraint(c.clone());
            let fp = FixedProblem {
                knots: &kn,
                q: &q,
                data_vertex: &data_vertex,
                constraint: &c,
                problem: &problem,
                stride: m,
                // Random knots, not a k-level split.
                uniform_spans: false,
                working_set: None,
            };
            let (conic, _, _) = super::super::exact::solve(&fp, super::super::exact::CONIC_TOLERANCE).unwrap();
            let e_conic = energy::energy(&kn, &conic.points).unwrap();
            // The reference's own certificate: only a certified reference is an optimum to agree
            // with both ways; an uncertified one (the full-vertex method reaches 3e-8…6e-8 on some
            // open curves with very unequal spans) only bounds the optimum from above.
            let (reference, _) = certify(&stencil, &conic.points, &q, &data_vertex, &c,
                conic.multipliers.clone(), ACTIVE_REL_TOL, &[]);
            // Optima with E* = 0 (data within reach of a straight open curve) are reached by
            // each solver only to its tolerance: both must then be below 1e-12 × the energy of
            // interpolating the centres.
            let e_interp = energy::energy(
                &kn,
                &super::super::fast::interpolate(&kn, &stencil, &q, m).unwrap(),
            )
            .unwrap();
            if e_conic <= ZERO_ENERGY_RTOL * e_interp {
                prop_assert!(cert.energy <= ZERO_ENERGY_RTOL * e_interp,
                    "condensed {} vs conic {e_conic} (E* = 0)", cert.energy);
            } else {
                // (With E* = 0 the certificate's duality gap relative to E is meaningless; such
                // problems — a common point of all balls — are answered by `degenerate` before
                // any solver runs.)
                prop_assert!(cert.kkt_residual <= EXACT_KKT_TARGET, "kkt {:e}", cert.kkt_residual);
                if reference.kkt_residual <= EXACT_KKT_TARGET {
                    prop_assert!((cert.energy - e_conic).abs() <= 1e-8 * e_conic,
                        "condensed {} vs conic {e_conic}", cert.energy);
                } else {
                    prop_assert!(cert.energy <= e_conic * (1.0 + 1e-8),
                        "condensed {} above the uncertified conic {e_conic} (kkt {:e})",
                        cert.energy, reference.kkt_residual);
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The working-set method (started from every 2nd…9th ball, and also with a random start
        /// set) reaches the optimum of the single round on all balls: energies to 1e-9 relative,
        /// all certified at the exact target, every ball respected.
        #[test]
        fn the_working_set_reaches_the_optimum_of_all_balls(
            n in 8usize..40,
            k in 1usize..4,
            d in 1usize..4,
            closed in any::<bool>(),
            step in 2usize..10,
            seed in any::<u64>(),
        ) {
            let m = k + 1;
            let spans = if closed { m * n } else { m * (n - 1) };
            let mut state = seed | 1;
            let mut uniform = move || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let h: Vec<f64> = (0..spans).map(|_| 0.2 + 1.8 * uniform()).collect();
            let topo = if closed { Topology::Closed } else { Topology::Open };
            let kn = knots(&h, topo);
            // A wiggly curve with noise, so some balls are active and most are not.
            let mut y = Vec::with_capacity(n * d);
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                for c in 0..d {
                    let v = if c % 2 == 0 { a.cos() } else { a.sin() };
                    y.push(v * (1.0 + 0.2 * (3.0 * a).sin()) + 0.1 * (uniform() - 0.5));
                }
            }
            let q = Points::new(d, y).unwrap();
            prop_assume!((0..n - 1).all(|i| super::super::fixed::dist(q.point(i), q.point(i + 1)) > 1e-3));
            let radii: Vec<f64> = (0..n)
                .map(|i| if i % 11 == 5 { 0.0 } else { (0.02 + 0.3 * uniform()) * std::f64::consts::TAU / n as f64 })
                .collect();
            let stencil = Stencil::new(&kn);
            let data_vertex: Vec<usize> = (0..n).map(|i| i * m).collect();
            let c = Constraint::Balls(radii.clone());
            let judge = |sol: &super::CondensedSolution| {
                certify(&stencil, &sol.points, &q, &data_vertex, &c,
                    Some(sol.multipliers.clone()), ACTIVE_REL_TOL, &[]).0
            };
            let all = super::solve_balls_from(&kn, &stencil, &q, &radii, m, CONDENSED_TOLERANCE, 1, None).unwrap();
            let ws = super::solve_balls_from(&kn, &stencil, &q, &radii, m, CONDENSED_TOLERANCE, step, None).unwrap();
            let (ca, cw) = (judge(&all), judge(&ws));
            prop_assert!(ca.kkt_residual <= EXACT_KKT_TARGET, "all: kkt {:e}", ca.kkt_residual);
            prop_assert!(cw.kkt_residual <= EXACT_KKT_TARGET, "working set: kkt {:e}", cw.kkt_residual);
            prop_assert!((ca.energy - cw.energy).abs() <= 1e-9 * ca.energy,
                "all {} vs working set {}", ca.energy, cw.energy);
            // A start set (as the previous knot iteration's active balls give it): any set works.
            let start: Vec<bool> = (0..n).map(|_| uniform() < 0.2).collect();
            let hinted = super::solve_balls_from(&kn, &stencil, &q, &radii, m, CONDENSED_TOLERANCE, step, Some(&start)).unwrap();
            let ch = judge(&hinted);
            prop_assert!(ch.kkt_residual <= EXACT_KKT_TARGET, "started: kkt {:e}", ch.kkt_residual);
            prop_assert!((ca.energy - ch.energy).abs() <= 1e-9 * ca.energy,
                "all {} vs started working set {}", ca.energy, ch.energy);
            for i in 0..n {
                let g = super::super::fixed::dist(ws.points.point(i * m), q.point(i));
                prop_assert!(g <= radii[i] * (1.0 + 1e-9) + 1e-12, "ball {i}: {g} > {}", radii[i]);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// All radii 0: the solver has no cone and returns the interpolating curve of
        /// `fast::interpolate`; radii far larger than the data: a constant curve is feasible, so
        /// E* = 0 and the optimum found has E at the rounding level of the interpolation energy.
        #[test]
        fn zero_radii_interpolate_and_huge_radii_give_zero_energy((kn, n, m, y, d) in case()) {
            let q = Points::new(d, y).unwrap();
            let stencil = Stencil::new(&kn);
            let fixed = solve_balls(&kn, &stencil, &q, &vec![0.0; n], m, CONDENSED_TOLERANCE, None).unwrap();
            let interp = super::super::fast::interpolate(&kn, &stencil, &q, m).unwrap();
            let scale = interp.coords().iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for (a, b) in fixed.points.coords().iter().zip(interp.coords()) {
                prop_assert!((a - b).abs() <= 1e-13 * scale, "{a} vs {b}");
            }
            let e_interp = energy::energy(&kn, &interp).unwrap();
            let sol = solve_balls(&kn, &stencil, &q, &vec![10.0; n], m, CONDENSED_TOLERANCE, None).unwrap();
            let e = energy::energy(&kn, &sol.points).unwrap();
            prop_assert!(e <= ZERO_ENERGY_RTOL * e_interp.max(f64::MIN_POSITIVE), "E = {e} (interpolation {e_interp})");
        }
    }
}
