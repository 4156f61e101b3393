//! Block pentadiagonal Cholesky K = L Lᵀ with D×D blocks (D = d ≤ 4, fixed at compile time),
//! with a border for closed curves: the fast path for systems with coupling blocks
//! (interior-point Newton systems). Rows 0..m−1 are banded (L has block subdiagonals L1, L2 and
//! lower triangular diagonal blocks); for a closed curve the two last block rows are the border
//! G0, G1 plus a 2×2 block tail. Every Schur complement is formed as K − Σ X Xᵀ (Gram form), so
//! it stays symmetric and accurate even when diagonal blocks are very ill-conditioned (barrier
//! terms of interior-point methods); no block is ever inverted explicitly.

// Dense d×d kernels index several arrays by the same row/column: index loops are clearer.
#![allow(clippy::needless_range_loop)]

use super::{Envelope, Parts};
use crate::Error;
use divdiff::Topology;

type Blk<const D: usize> = [[f64; D]; D];

/// Border entries (closed curves) decay geometrically away from the ends; below this magnitude
/// they are set to zero (they are invisible next to the entries near the ends, and computing
/// with denormals is slow).
const BORDER_FLUSH: f64 = 1e-200;

#[inline(always)]
fn zero<const D: usize>() -> Blk<D> {
    [[0.0; D]; D]
}

/// a bᵀ
#[inline(always)]
fn mul_t<const D: usize>(a: &Blk<D>, b: &Blk<D>) -> Blk<D> {
    let mut c = zero::<D>();
    for i in 0..D {
        for j in 0..D {
            let mut s = 0.0;
            for k in 0..D {
                s += a[i][k] * b[j][k];
            }
            c[i][j] = s;
        }
    }
    c
}

#[inline(always)]
fn sub_assign<const D: usize>(a: &mut Blk<D>, b: &Blk<D>) {
    for i in 0..D {
        for j in 0..D {
            a[i][j] -= b[i][j];
        }
    }
}

/// Lower Cholesky factor of the symmetric `s` (lower triangle read), with the relative pivot
/// test against `kref` (the diagonal of K in this block row).
#[inline(always)]
fn chol<const D: usize>(s: &Blk<D>, kref: &[f64; D], rtol: f64) -> Option<Blk<D>> {
    let mut l = zero::<D>();
    for c in 0..D {
        let mut p = s[c][c];
        for q in 0..c {
            p -= l[c][q] * l[c][q];
        }
        if !(p.is_finite() && p > rtol * kref[c]) {
            return None;
        }
        let lcc = p.sqrt();
        l[c][c] = lcc;
        for r in c + 1..D {
            let mut t = s[r][c];
            for q in 0..c {
                t -= l[r][q] * l[c][q];
            }
            l[r][c] = t / lcc;
        }
    }
    Some(l)
}

/// X = S L^{-T} for lower triangular L (each row x of X solves L xᵀ = row of S).
#[inline(always)]
fn right_solve_t<const D: usize>(s: &Blk<D>, l: &Blk<D>) -> Blk<D> {
    let mut x = *s;
    for r in 0..D {
        for c in 0..D {
            let mut t = x[r][c];
            for q in 0..c {
                t -= x[r][q] * l[c][q];
            }
            x[r][c] = t / l[c][c];
        }
    }
    x
}

/// v ← L⁻¹ v.
#[inline(always)]
fn lsolve<const D: usize>(l: &Blk<D>, v: &mut [f64; D]) {
    for r in 0..D {
        let mut t = v[r];
        for c in 0..r {
            t -= l[r][c] * v[c];
        }
        v[r] = t / l[r][r];
    }
}

/// v ← L⁻ᵀ v.
#[inline(always)]
fn ltsolve<const D: usize>(l: &Blk<D>, v: &mut [f64; D]) {
    for r in (0..D).rev() {
        let mut t = v[r];
        for c in r + 1..D {
            t -= l[c][r] * v[c];
        }
        v[r] = t / l[r][r];
    }
}

#[derive(Clone, Debug)]
pub(crate) struct BlockBand<const D: usize> {
    n: usize,
    m: usize,
    /// Per band row: L[i][i−1], L[i][i−2], L[i][i] (lower triangular).
    rows: Vec<[Blk<D>; 3]>,
    /// Closed: per band row, L[N−2][j] and L[N−1][j].
    border: Vec<[Blk<D>; 2]>,
    /// Closed: L[N−1][N−2] and the diagonal factors of the two border rows.
    tail: [Blk<D>; 3],
    /// Couplings between a free and a fixed vertex: (free, fixed, K_free,fixed).
    fixed_couplings: Vec<(usize, usize, Blk<D>)>,
}

impl<const D: usize> BlockBand<D> {
    pub(crate) fn new(s: &Parts<'_>) -> Result<Self, Error> {
        let n = s.n;
        let closed = s.topology == Topology::Closed;
        debug_assert!(s.dim == D && (!closed || n >= 5));
        let env = Envelope::new(s.topology, n);
        let m = if closed { n - 2 } else { n };
        let fx = s.fixed;
        let dd = D * D;
        // The assembled block K_ij (i ≥ j, in the envelope), before eliminating fixed vertices.
        // Scalar band entry K_ij, i ≥ j, without modular arithmetic (N ≥ 5 for closed curves, so
        // the four cases below are distinct).
        let scalar = |i: usize, j: usize| -> f64 {
            match i - j {
                0 => s.diag[i],
                1 => s.off1[j],
                2 => s.off2[j],
                g if closed && g == n - 1 => s.off1[i],
                g if closed && g == n - 2 => s.off2[i],
                _ => 0.0,
            }
        };
        let raw = |i: usize, j: usize| -> Blk<D> {
            let mut b = zero::<D>();
            let sv = scalar(i, j);
            for c in 0..D {
                b[c][c] = sv;
            }
            if let Some(blocks) = s.blocks {
                let base = env.index(i, j) * dd;
                for r in 0..D {
                    for c in 0..D {
                        b[r][c] += blocks[base + r * D + c];
                    }
                }
            }
            b
        };
        let mut fixed_couplings = Vec::new();
        // K_ij with fixed vertices eliminated (i > j); records the couplings to fixed vertices.
        let mut coupling = |i: usize, j: usize| -> Blk<D> {
            let b = raw(i, j);
            match (fx[i], fx[j]) {
                (false, false) => b,
                (true, true) => zero::<D>(),
                (false, true) => {
                    fixed_couplings.push((i, j, b));
                    zero::<D>()
                }
                (true, false) => {
                    let mut t = zero::<D>();
                    for r in 0..D {
                        for c in 0..D {
                            t[r][c] = b[c][r];
                        }
                    }
                    fixed_couplings.push((j, i, t));
                    zero::<D>()
                }
            }
        };
        let diag_block = |i: usize| -> (Blk<D>, [f64; D]) {
            let mut b = if fx[i] {
                let mut e = zero::<D>();
                for c in 0..D {
                    e[c][c] = 1.0;
                }
                e
            } else {
                raw(i, i)
            };
            // symmetrize
            for r in 0..D {
                for c in 0..r {
                    let v = 0.5 * (b[r][c] + b[c][r]);
                    b[r][c] = v;
                    b[c][r] = v;
                }
            }
            let mut kref = [0.0; D];
            for c in 0..D {
                kref[c] = b[c][c];
            }
            (b, kref)
        };

        let mut rows: Vec<[Blk<D>; 3]> = Vec::with_capacity(m);
        let mut border: Vec<[Blk<D>; 2]> = Vec::with_capacity(if closed { m } else { 0 });
        let (r0, r1) = (n.wrapping_sub(2), n.wrapping_sub(1));
        let (mut g_prev, mut g_prev2) = ([zero::<D>(); 2], [zero::<D>(); 2]);
        // Σ G0 G0ᵀ, Σ G1 G0ᵀ, Σ G1 G1ᵀ.
        let mut tail_acc = [zero::<D>(); 3];
        for i in 0..m {
            // L2 = K_{i,i−2} L_{i−2}^{−T}; L1 = (K_{i,i−1} − L2 L_{i−1,i−2}ᵀ) L_{i−1}^{−T};
            // L_ii = chol(K_ii − L1 L1ᵀ − L2 L2ᵀ).
            let l2 = if i >= 2 {
                right_solve_t(&coupling(i, i - 2), &rows[i - 2][2])
            } else {
                zero::<D>()
            };
            let l1 = if i >= 1 {
                let mut c1 = coupling(i, i - 1);
                if i >= 2 {
                    sub_assign(&mut c1, &mul_t(&l2, &rows[i - 1][0]));
                }
                right_solve_t(&c1, &rows[i - 1][2])
            } else {
                zero::<D>()
            };
            let (mut si, kref) = diag_block(i);
            sub_assign(&mut si, &mul_t(&l1, &l1));
            sub_assign(&mut si, &mul_t(&l2, &l2));
            let lii = chol(&si, &kref, s.rtol).ok_or(Error::Singular { vertex: i })?;
            if closed {
                // G[i] = (K_{R,i} − G[i−1] L1ᵀ − G[i−2] L2ᵀ) L_ii^{−T}.
                let mut g = [zero::<D>(); 2];
                let near_end = i <= 1 || i + 4 >= n;
                for (r, rv) in [r0, r1].into_iter().enumerate() {
                    if !near_end && g_prev[r] == zero::<D>() && g_prev2[r] == zero::<D>() {
                        continue; // the border row has decayed to exactly zero here
                    }
                    let mut e = if near_end {
                        coupling(rv, i)
                    } else {
                        zero::<D>()
                    };
                    sub_assign(&mut e, &mul_t(&g_prev[r], &l1));
                    sub_assign(&mut e, &mul_t(&g_prev2[r], &l2));
                    g[r] = right_solve_t(&e, &lii);
                    // Flush entries that have decayed below BORDER_FLUSH (invisible next to the
                    // O(1)-relative entries near the ends; denormal arithmetic is very slow).
                    if g[r].iter().flatten().all(|v| v.abs() < BORDER_FLUSH) {
                        g[r] = zero::<D>();
                    }
                }
                if g != [zero::<D>(); 2] {
                    let t00 = mul_t(&g[0], &g[0]);
                    let t10 = mul_t(&g[1], &g[0]);
                    let t11 = mul_t(&g[1], &g[1]);
                    for a in 0..D {
                        for b in 0..D {
                            tail_acc[0][a][b] += t00[a][b];
                            tail_acc[1][a][b] += t10[a][b];
                            tail_acc[2][a][b] += t11[a][b];
                        }
                    }
                }
                border.push(g);
                g_prev2 = g_prev;
                g_prev = g;
            }
            rows.push([l1, l2, lii]);
        }
        let mut tail = [zero::<D>(); 3];
        if closed {
            let (mut s0, kref0) = diag_block(r0);
            sub_assign(&mut s0, &tail_acc[0]);
            let l00 = chol(&s0, &kref0, s.rtol).ok_or(Error::Singular { vertex: r0 })?;
            let mut c10 = coupling(r1, r0);
            sub_assign(&mut c10, &tail_acc[1]);
            let l10 = right_solve_t(&c10, &l00);
            let (mut s1, kref1) = diag_block(r1);
            sub_assign(&mut s1, &tail_acc[2]);
            sub_assign(&mut s1, &mul_t(&l10, &l10));
            let l11 = chol(&s1, &kref1, s.rtol).ok_or(Error::Singular { vertex: r1 })?;
            tail = [l10, l00, l11];
        }
        Ok(BlockBand {
            n,
            m,
            rows,
            border,
            tail,
            fixed_couplings,
        })
    }

    pub(crate) fn solve(&self, x: &mut [f64]) {
        let (n, m) = (self.n, self.m);
        for (i, j, b) in &self.fixed_couplings {
            for r in 0..D {
                let mut s = 0.0;
                for c in 0..D {
                    s += b[r][c] * x[j * D + c];
                }
                x[i * D + r] -= s;
            }
        }
        let closed = m < n;
        let mv = |b: &Blk<D>, v: &[f64; D]| -> [f64; D] {
            let mut o = [0.0; D];
            for r in 0..D {
                for c in 0..D {
                    o[r] += b[r][c] * v[c];
                }
            }
            o
        };
        let mtv = |b: &Blk<D>, v: &[f64; D]| -> [f64; D] {
            let mut o = [0.0; D];
            for r in 0..D {
                for c in 0..D {
                    o[c] += b[r][c] * v[r];
                }
            }
            o
        };
        let load = |x: &[f64], i: usize| -> [f64; D] {
            let mut o = [0.0; D];
            o.copy_from_slice(&x[i * D..(i + 1) * D]);
            o
        };
        // Forward: z_i = L_ii⁻¹ (b_i − L1 z_{i−1} − L2 z_{i−2}); border sums Σ G z.
        let (mut z1, mut z2) = ([0.0; D], [0.0; D]);
        let (mut s0, mut s1) = ([0.0; D], [0.0; D]);
        for i in 0..m {
            let [l1, l2, lii] = &self.rows[i];
            let mut z = load(x, i);
            let u = mv(l1, &z1);
            let w = mv(l2, &z2);
            for c in 0..D {
                z[c] -= u[c] + w[c];
            }
            lsolve(lii, &mut z);
            x[i * D..(i + 1) * D].copy_from_slice(&z);
            if closed {
                let [g0, g1] = &self.border[i];
                let u0 = mv(g0, &z);
                let u1 = mv(g1, &z);
                for c in 0..D {
                    s0[c] += u0[c];
                    s1[c] += u1[c];
                }
            }
            z2 = z1;
            z1 = z;
        }
        let (mut xr0, mut xr1) = ([0.0; D], [0.0; D]);
        if closed {
            let [l10, l00, l11] = &self.tail;
            let (r0, r1) = (n - 2, n - 1);
            let mut zr0 = load(x, r0);
            for c in 0..D {
                zr0[c] -= s0[c];
            }
            lsolve(l00, &mut zr0);
            let mut zr1 = load(x, r1);
            let u = mv(l10, &zr0);
            for c in 0..D {
                zr1[c] -= s1[c] + u[c];
            }
            lsolve(l11, &mut zr1);
            // Backward on the tail.
            xr1 = zr1;
            ltsolve(l11, &mut xr1);
            let u = mtv(l10, &xr1);
            for c in 0..D {
                xr0[c] = zr0[c] - u[c];
            }
            ltsolve(l00, &mut xr0);
            x[r0 * D..(r0 + 1) * D].copy_from_slice(&xr0);
            x[r1 * D..(r1 + 1) * D].copy_from_slice(&xr1);
        }
        // Backward: x_j = L_jj^{−T}(z_j − L1_{j+1}ᵀ x_{j+1} − L2_{j+2}ᵀ x_{j+2} − G0_jᵀ x_R0 − G1_jᵀ x_R1).
        let (mut x1, mut x2) = ([0.0; D], [0.0; D]);
        let mut l1n = zero::<D>();
        let mut l2n = zero::<D>();
        let mut l2nn = zero::<D>();
        for j in (0..m).rev() {
            let [l1, l2, ljj] = &self.rows[j];
            let mut v = load(x, j);
            let u = mtv(&l1n, &x1);
            let w = mtv(&l2nn, &x2);
            for c in 0..D {
                v[c] -= u[c] + w[c];
            }
            if closed {
                let [g0, g1] = &self.border[j];
                let u0 = mtv(g0, &xr0);
                let u1 = mtv(g1, &xr1);
                for c in 0..D {
                    v[c] -= u0[c] + u1[c];
                }
            }
            ltsolve(ljj, &mut v);
            x[j * D..(j + 1) * D].copy_from_slice(&v);
            x2 = x1;
            x1 = v;
            l2nn = l2n;
            l1n = *l1;
            l2n = *l2;
        }
    }
}
