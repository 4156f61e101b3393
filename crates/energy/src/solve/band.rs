//! Scalar (cyclic) pentadiagonal LDLᵀ shared by all d coordinate columns.
//!
//! Rows 0..m−1 (m = N for open curves, N − 2 for closed ones) are banded: L has two
//! subdiagonals `l1`, `l2`. For closed curves the rows N−2 and N−1 are a border: the wrap-around
//! couplings fill them in completely, stored as `g0`, `g1` (length m), plus the 2×2 tail.
//! Factorization and both triangular solves are single fused passes with rolling state.

use super::Parts;
use crate::Error;
use divdiff::Topology;

#[derive(Clone, Debug)]
pub(crate) struct BandFactor {
    n: usize,
    dim: usize,
    m: usize,
    /// Per band row: [L[i][i−1], L[i][i−2], 1/D_i].
    rows: Vec<[f64; 3]>,
    /// Closed curves: per band row [L[N−2][j], L[N−1][j]].
    border: Vec<[f64; 2]>,
    /// Closed curves: L[N−1][N−2], 1/D_{N−2}, 1/D_{N−1}.
    tail: [f64; 3],
    /// Couplings between a free and a fixed vertex: (free, fixed, K_free,fixed).
    fixed_couplings: Vec<(usize, usize, f64)>,
}

#[inline(always)]
fn pivot_ok(p: f64, kii: f64, rtol: f64) -> bool {
    p.is_finite() && p > rtol * kii
}

impl BandFactor {
    pub(crate) fn new(s: &Parts<'_>) -> Result<Self, Error> {
        let n = s.n;
        let closed = s.topology == Topology::Closed;
        debug_assert!(!closed || n >= 5);
        let m = if closed { n - 2 } else { n };
        let fx = s.fixed;
        let any_fixed = fx.iter().any(|&f| f);
        // Every off-diagonal coupling as (i, j, v) with i > j in the band/border pattern.
        let mut fixed_couplings = Vec::new();
        if any_fixed {
            let mut push = |i: usize, j: usize, v: f64| {
                if v != 0.0 && fx[i] != fx[j] {
                    if fx[j] {
                        fixed_couplings.push((i, j, v));
                    } else {
                        fixed_couplings.push((j, i, v));
                    }
                }
            };
            for j in 0..n {
                if j + 1 < n || closed {
                    push((j + 1) % n, j, s.off1[j]);
                }
                if j + 2 < n || closed {
                    push((j + 2) % n, j, s.off2[j]);
                }
            }
        }
        // A coupling K_ij with fixed vertices eliminated.
        let cpl = |i: usize, j: usize, v: f64| -> f64 {
            if any_fixed && (fx[i] || fx[j]) {
                0.0
            } else {
                v
            }
        };
        let kd = |i: usize| if any_fixed && fx[i] { 1.0 } else { s.diag[i] };

        let mut rows = Vec::with_capacity(m);
        let mut border = Vec::with_capacity(if closed { m } else { 0 });
        // Border couplings K[N−2][j], K[N−1][j] (j < m) are nonzero only at j ∈ {0, 1, n−4, n−3}.
        let (r0, r1) = (n.wrapping_sub(2), n.wrapping_sub(1));
        let border_k = |j: usize| -> [f64; 2] {
            let mut k = [0.0; 2];
            if j == n - 4 {
                k[0] += cpl(r0, j, s.off2[n - 4]);
            }
            if j == n - 3 {
                k[0] += cpl(r0, j, s.off1[n - 3]);
                k[1] += cpl(r1, j, s.off2[n - 3]);
            }
            if j == 0 {
                k[0] += cpl(r0, 0, s.off2[n - 2]);
                k[1] += cpl(r1, 0, s.off1[n - 1]);
            }
            if j == 1 {
                k[1] += cpl(r1, 1, s.off2[n - 1]);
            }
            k
        };
        // Rolling state: D, 1/D, L[i−1][i−2] of the two previous rows; border entries.
        let (mut dm1, mut dm2, mut im1, mut im2, mut l1m1) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut gm1, mut gm2) = ([0.0f64; 2], [0.0f64; 2]);
        let (mut p0, mut c10, mut p1) = (0.0, 0.0, 0.0);
        for i in 0..m {
            let k2 = if i >= 2 {
                cpl(i, i - 2, s.off2[i - 2])
            } else {
                0.0
            };
            let k1 = if i >= 1 {
                cpl(i, i - 1, s.off1[i - 1])
            } else {
                0.0
            };
            let a2 = k2 * im2;
            let a1 = (k1 - a2 * dm2 * l1m1) * im1;
            let kii = kd(i);
            let p = kii - a1 * a1 * dm1 - a2 * a2 * dm2;
            if !pivot_ok(p, kii, s.rtol) {
                return Err(Error::Singular { vertex: i });
            }
            let inv = 1.0 / p;
            rows.push([a1, a2, inv]);
            if closed {
                let k = if i <= 1 || i + 4 >= n {
                    border_k(i)
                } else {
                    [0.0; 2]
                };
                let mut g = [0.0; 2];
                for r in 0..2 {
                    g[r] = (k[r] - gm1[r] * dm1 * a1 - gm2[r] * dm2 * a2) * inv;
                    // Border entries decay geometrically; flush before they turn denormal.
                    if g[r].abs() < 1e-200 {
                        g[r] = 0.0;
                    }
                }
                p0 += g[0] * g[0] * p;
                c10 += g[1] * g[0] * p;
                p1 += g[1] * g[1] * p;
                border.push(g);
                gm2 = gm1;
                gm1 = g;
            }
            dm2 = dm1;
            dm1 = p;
            im2 = im1;
            im1 = inv;
            l1m1 = a1;
        }
        let mut tail = [0.0; 3];
        if closed {
            let k0 = kd(r0);
            let q0 = k0 - p0;
            if !pivot_ok(q0, k0, s.rtol) {
                return Err(Error::Singular { vertex: r0 });
            }
            let l10 = (cpl(r1, r0, s.off1[n - 2]) - c10) / q0;
            let k1 = kd(r1);
            let q1 = k1 - p1 - l10 * l10 * q0;
            if !pivot_ok(q1, k1, s.rtol) {
                return Err(Error::Singular { vertex: r1 });
            }
            tail = [l10, 1.0 / q0, 1.0 / q1];
        }
        Ok(BandFactor {
            n,
            dim: s.dim,
            m,
            rows,
            border,
            tail,
            fixed_couplings,
        })
    }

    pub(crate) fn solve(&self, x: &mut [f64]) {
        let d = self.dim;
        for &(i, j, v) in &self.fixed_couplings {
            for c in 0..d {
                x[i * d + c] -= v * x[j * d + c];
            }
        }
        match d {
            1 => self.kernel::<1>(x, 1, 0),
            2 => self.kernel::<2>(x, 2, 0),
            3 => self.kernel::<3>(x, 3, 0),
            4 => self.kernel::<4>(x, 4, 0),
            _ => {
                for c in 0..d {
                    self.kernel::<1>(x, d, c);
                }
            }
        }
    }

    /// Solves for the W columns c0..c0+W of the vertex-major array x with row stride `stride`.
    #[inline(always)]
    fn kernel<const W: usize>(&self, x: &mut [f64], stride: usize, c0: usize) {
        let (n, m) = (self.n, self.m);
        let rows = &self.rows[..m];
        let closed = m < n;
        let at = |i: usize| i * stride + c0;
        // Forward: z_i = b_i − l1_i z_{i−1} − l2_i z_{i−2}; border sums.
        let (mut z1, mut z2) = ([0.0f64; W], [0.0f64; W]);
        let (mut s0, mut s1) = ([0.0f64; W], [0.0f64; W]);
        if closed {
            let border = &self.border[..m];
            for i in 0..m {
                let [a1, a2, _] = rows[i];
                let [g0, g1] = border[i];
                let xi = &mut x[at(i)..at(i) + W];
                let mut z = [0.0; W];
                for c in 0..W {
                    z[c] = xi[c] - a1 * z1[c] - a2 * z2[c];
                    xi[c] = z[c];
                    s0[c] += g0 * z[c];
                    s1[c] += g1 * z[c];
                }
                z2 = z1;
                z1 = z;
            }
        } else {
            for i in 0..m {
                let [a1, a2, _] = rows[i];
                let xi = &mut x[at(i)..at(i) + W];
                let mut z = [0.0; W];
                for c in 0..W {
                    z[c] = xi[c] - a1 * z1[c] - a2 * z2[c];
                    xi[c] = z[c];
                }
                z2 = z1;
                z1 = z;
            }
        }
        // Backward: x_j = z_j / D_j − l1_{j+1} x_{j+1} − l2_{j+2} x_{j+2} (− border terms).
        let (mut x1, mut x2) = ([0.0f64; W], [0.0f64; W]);
        let (mut a1n, mut a2n, mut a2nn) = (0.0, 0.0, 0.0);
        if closed {
            let [l10, i0, i1] = self.tail;
            let (r0, r1) = (n - 2, n - 1);
            let (mut xr0, mut xr1) = ([0.0f64; W], [0.0f64; W]);
            for c in 0..W {
                let z0 = x[at(r0) + c] - s0[c];
                let zr1 = x[at(r1) + c] - s1[c] - l10 * z0;
                xr1[c] = zr1 * i1;
                xr0[c] = z0 * i0 - l10 * xr1[c];
                x[at(r0) + c] = xr0[c];
                x[at(r1) + c] = xr1[c];
            }
            let border = &self.border[..m];
            for j in (0..m).rev() {
                let [a1, a2, inv] = rows[j];
                let [g0, g1] = border[j];
                let xj = &mut x[at(j)..at(j) + W];
                let mut v = [0.0; W];
                for c in 0..W {
                    v[c] = xj[c] * inv - a1n * x1[c] - a2nn * x2[c] - g0 * xr0[c] - g1 * xr1[c];
                    xj[c] = v[c];
                }
                x2 = x1;
                x1 = v;
                a2nn = a2n;
                a1n = a1;
                a2n = a2;
            }
        } else {
            for j in (0..m).rev() {
                let [a1, a2, inv] = rows[j];
                let xj = &mut x[at(j)..at(j) + W];
                let mut v = [0.0; W];
                for c in 0..W {
                    v[c] = xj[c] * inv - a1n * x1[c] - a2nn * x2[c];
                    xj[c] = v[c];
                }
                x2 = x1;
                x1 = v;
                a2nn = a2n;
                a1n = a1;
                a2n = a2;
            }
        }
    }
}
