//! Block pentadiagonal LDLᵀ with D×D blocks (D = d ≤ 4, fixed at compile time), with a border
//! for closed curves: the fast path for systems with coupling blocks (interior-point Newton
//! systems). Rows 0..m−1 are banded (L has block subdiagonals A1, A2; D_i⁻¹ stored); for a closed
//! curve the two last block rows are the border G0, G1 plus a 2×2 block tail.

use super::{Envelope, Parts, PIVOT_RTOL};
use crate::Error;
use divdiff::Topology;

type Blk<const D: usize> = [[f64; D]; D];

#[inline(always)]
fn zero<const D: usize>() -> Blk<D> {
    [[0.0; D]; D]
}

#[inline(always)]
fn mul<const D: usize>(a: &Blk<D>, b: &Blk<D>) -> Blk<D> {
    let mut c = zero::<D>();
    for i in 0..D {
        for k in 0..D {
            let aik = a[i][k];
            for j in 0..D {
                c[i][j] += aik * b[k][j];
            }
        }
    }
    c
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

/// Inverse of the symmetric positive definite `s` by Cholesky, with the relative pivot test
/// against `kref` (the diagonal of K in this block row).
#[inline(always)]
fn spd_inverse<const D: usize>(s: &Blk<D>, kref: &[f64; D]) -> Option<Blk<D>> {
    let mut l = zero::<D>();
    for c in 0..D {
        let mut p = s[c][c];
        for q in 0..c {
            p -= l[c][q] * l[c][q];
        }
        if !(p.is_finite() && p > PIVOT_RTOL * kref[c]) {
            return None;
        }
        let lcc = p.sqrt();
        l[c][c] = lcc;
        for r in c + 1..D {
            let mut t = 0.5 * (s[r][c] + s[c][r]);
            for q in 0..c {
                t -= l[r][q] * l[c][q];
            }
            l[r][c] = t / lcc;
        }
    }
    // L⁻¹ (lower), then S⁻¹ = L⁻ᵀ L⁻¹.
    let mut li = zero::<D>();
    for j in 0..D {
        li[j][j] = 1.0 / l[j][j];
        for i in j + 1..D {
            let mut t = 0.0;
            for k in j..i {
                t -= l[i][k] * li[k][j];
            }
            li[i][j] = t / l[i][i];
        }
    }
    let mut inv = zero::<D>();
    for i in 0..D {
        for j in 0..=i {
            let mut t = 0.0;
            for k in i..D {
                t += li[k][i] * li[k][j];
            }
            inv[i][j] = t;
            inv[j][i] = t;
        }
    }
    Some(inv)
}

#[derive(Clone, Debug)]
pub(crate) struct BlockBand<const D: usize> {
    n: usize,
    m: usize,
    /// Per band row: L[i][i−1], L[i][i−2], D_i⁻¹.
    rows: Vec<[Blk<D>; 3]>,
    /// Closed: per band row, L[N−2][j] and L[N−1][j].
    border: Vec<[Blk<D>; 2]>,
    /// Closed: L[N−1][N−2], D⁻¹ of the two border rows.
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
        let scalar = |i: usize, j: usize| -> f64 {
            if i == j {
                return s.diag[i];
            }
            let mut v = 0.0;
            for (band, step) in [(s.off1, 1), (s.off2, 2)] {
                if (j + step) % n == i && (closed || j + step < n) {
                    v += band[j];
                }
                if (i + step) % n == j && (closed || i + step < n) {
                    v += band[i];
                }
            }
            v
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
        // Rolling: A1_{i−1}, K_{i−1,i−2}… kept as C-forms.
        let mut a1_prev = zero::<D>(); // A1 of row i−1
        let mut c1_prev = zero::<D>(); // C1 = A1 D of row i−1
        let mut k2_prev = zero::<D>(); // K_{i−1,i−3} (= A2 D of row i−1)
        let mut g_prev = [zero::<D>(); 2]; // G[j−1]
        let mut g_prev2 = [zero::<D>(); 2]; // G[j−2]
        let mut tail_acc = [zero::<D>(); 3]; // Σ G0 E0ᵀ, Σ G1 E0ᵀ, Σ G1 E1ᵀ
        for i in 0..m {
            let k2 = if i >= 2 { coupling(i, i - 2) } else { zero::<D>() };
            let k1 = if i >= 1 { coupling(i, i - 1) } else { zero::<D>() };
            let (kii, kref) = diag_block(i);
            let a2 = if i >= 2 { mul(&k2, &rows[i - 2][2]) } else { zero::<D>() };
            // C1 = K_{i,i−1} − K_{i,i−2} A1_{i−1}ᵀ; A1 = C1 D_{i−1}⁻¹.
            let mut c1 = k1;
            if i >= 2 {
                sub_assign(&mut c1, &mul_t(&k2, &a1_prev));
            }
            let a1 = if i >= 1 { mul(&c1, &rows[i - 1][2]) } else { zero::<D>() };
            // D_i = K_ii − A1 C1ᵀ − A2 K_{i,i−2}ᵀ.
            let mut di = kii;
            sub_assign(&mut di, &mul_t(&a1, &c1));
            sub_assign(&mut di, &mul_t(&a2, &k2));
            let dinv = spd_inverse(&di, &kref).ok_or(Error::Singular { vertex: i })?;
            rows.push([a1, a2, dinv]);
            if closed {
                // E[i] = K_{R,i} − G[i−1] C1_iᵀ − G[i−2] K_{i,i−2}ᵀ; G[i] = E[i] D_i⁻¹.
                let mut g = [zero::<D>(); 2];
                for (r, rv) in [r0, r1].into_iter().enumerate() {
                    let cyc = i.abs_diff(rv).min(n - i.abs_diff(rv));
                    let mut e = if cyc <= 2 { coupling(rv, i) } else { zero::<D>() };
                    sub_assign(&mut e, &mul_t(&g_prev[r], &c1));
                    sub_assign(&mut e, &mul_t(&g_prev2[r], &k2));
                    g[r] = mul(&e, &dinv);
                    // Accumulate G E0ᵀ / G E1ᵀ for the tail: need E too.
                    if r == 0 {
                        let t = mul_t(&g[0], &e);
                        for a in 0..D {
                            for b in 0..D {
                                tail_acc[0][a][b] += t[a][b];
                            }
                        }
                    } else {
                        // G1 E0ᵀ = G1 (G0 D)ᵀ... use E0 = G0 D_i: G1 D_i G0ᵀ = E1 G0ᵀ.
                        let t10 = mul_t(&e, &g[0]);
                        let t11 = mul_t(&g[1], &e);
                        for a in 0..D {
                            for b in 0..D {
                                tail_acc[1][a][b] += t10[a][b];
                                tail_acc[2][a][b] += t11[a][b];
                            }
                        }
                    }
                }
                border.push(g);
                g_prev2 = g_prev;
                g_prev = g;
            }
            a1_prev = a1;
            c1_prev = c1;
            k2_prev = k2;
        }
        let _ = (c1_prev, k2_prev);
        let mut tail = [zero::<D>(); 3];
        if closed {
            let (mut d0, kref0) = diag_block(r0);
            sub_assign(&mut d0, &tail_acc[0]);
            let d0inv = spd_inverse(&d0, &kref0).ok_or(Error::Singular { vertex: r0 })?;
            let mut c10 = coupling(r1, r0);
            sub_assign(&mut c10, &tail_acc[1]);
            let l10 = mul(&c10, &d0inv);
            let (mut d1, kref1) = diag_block(r1);
            sub_assign(&mut d1, &tail_acc[2]);
            sub_assign(&mut d1, &mul_t(&l10, &c10));
            let d1inv = spd_inverse(&d1, &kref1).ok_or(Error::Singular { vertex: r1 })?;
            tail = [l10, d0inv, d1inv];
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
        // Forward.
        let (mut z1, mut z2) = ([0.0; D], [0.0; D]);
        let (mut s0, mut s1) = ([0.0; D], [0.0; D]);
        for i in 0..m {
            let [a1, a2, _] = &self.rows[i];
            let mut z = load(x, i);
            let u = mv(a1, &z1);
            let w = mv(a2, &z2);
            for c in 0..D {
                z[c] -= u[c] + w[c];
            }
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
            let [l10, d0inv, d1inv] = &self.tail;
            let (r0, r1) = (n - 2, n - 1);
            let mut zr0 = load(x, r0);
            for c in 0..D {
                zr0[c] -= s0[c];
            }
            let mut zr1 = load(x, r1);
            let u = mv(l10, &zr0);
            for c in 0..D {
                zr1[c] -= s1[c] + u[c];
            }
            xr1 = mv(d1inv, &zr1);
            let y0 = mv(d0inv, &zr0);
            let u = mtv(l10, &xr1);
            for c in 0..D {
                xr0[c] = y0[c] - u[c];
            }
            x[r0 * D..(r0 + 1) * D].copy_from_slice(&xr0);
            x[r1 * D..(r1 + 1) * D].copy_from_slice(&xr1);
        }
        // Backward: x_j = D_j⁻¹ z_j − A1_{j+1}ᵀ x_{j+1} − A2_{j+2}ᵀ x_{j+2} − G0_jᵀ x_R0 − G1_jᵀ x_R1.
        let (mut x1, mut x2) = ([0.0; D], [0.0; D]);
        let mut a1n = zero::<D>();
        let mut a2n = zero::<D>();
        let mut a2nn = zero::<D>();
        for j in (0..m).rev() {
            let [a1, a2, dinv] = &self.rows[j];
            let z = load(x, j);
            let mut v = mv(dinv, &z);
            let u = mtv(&a1n, &x1);
            let w = mtv(&a2nn, &x2);
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
            x[j * D..(j + 1) * D].copy_from_slice(&v);
            x2 = x1;
            x1 = v;
            a2nn = a2n;
            a1n = *a1;
            a2n = *a2;
        }
    }
}
