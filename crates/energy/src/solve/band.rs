//! Scalar (cyclic) pentadiagonal LDLᵀ shared by all d coordinate columns.
//!
//! Rows 0..m−1 (m = N for open curves, N − 2 for closed ones) are banded: L has two
//! subdiagonals `l1`, `l2`. For closed curves the rows N−2 and N−1 are a border: the wrap-around
//! couplings fill them in completely, stored as `g0`, `g1` (length m), plus the 2×2 tail.

use super::{Parts, PIVOT_RTOL};
use crate::Error;
use divdiff::Topology;

#[derive(Clone, Debug)]
pub(crate) struct BandFactor {
    n: usize,
    dim: usize,
    m: usize,
    /// 1 / D_i.
    dinv: Vec<f64>,
    /// L[i][i−1] (0 for i = 0), padded with two zeros.
    l1: Vec<f64>,
    /// L[i][i−2] (0 for i < 2), padded with two zeros.
    l2: Vec<f64>,
    /// Border rows of a closed curve: L[N−2][j], L[N−1][j] for j < m, and L[N−1][N−2].
    g0: Vec<f64>,
    g1: Vec<f64>,
    l10: f64,
    /// Couplings between a free and a fixed vertex: (free, fixed, K_free,fixed).
    fixed_couplings: Vec<(usize, usize, f64)>,
}

fn pivot_ok(p: f64, kii: f64) -> bool {
    p.is_finite() && p > PIVOT_RTOL * kii
}

impl BandFactor {
    pub(crate) fn new(s: &Parts<'_>) -> Result<Self, Error> {
        let n = s.n;
        let closed = s.topology == Topology::Closed;
        debug_assert!(!closed || n >= 5);
        let m = if closed { n - 2 } else { n };
        let fx = s.fixed;
        let mut fixed_couplings = Vec::new();
        // A coupling K_ij (i ≠ j), with fixed vertices eliminated.
        let mut coupling = |i: usize, j: usize, v: f64| -> f64 {
            match (fx[i], fx[j]) {
                (false, false) => v,
                (true, true) => 0.0,
                (false, true) => {
                    if v != 0.0 {
                        fixed_couplings.push((i, j, v));
                    }
                    0.0
                }
                (true, false) => {
                    if v != 0.0 {
                        fixed_couplings.push((j, i, v));
                    }
                    0.0
                }
            }
        };
        let kd = |i: usize| if fx[i] { 1.0 } else { s.diag[i] };

        let mut dinv = vec![0.0; n];
        let mut l1 = vec![0.0; m + 2];
        let mut l2 = vec![0.0; m + 2];
        let mut dd = vec![0.0; m];
        for i in 0..m {
            let k2 = if i >= 2 {
                coupling(i, i - 2, s.off2[i - 2])
            } else {
                0.0
            };
            let k1 = if i >= 1 {
                coupling(i, i - 1, s.off1[i - 1])
            } else {
                0.0
            };
            let a2 = if i >= 2 { k2 * dinv[i - 2] } else { 0.0 };
            let a1 = if i >= 1 {
                let t = if i >= 2 { a2 * dd[i - 2] * l1[i - 1] } else { 0.0 };
                (k1 - t) * dinv[i - 1]
            } else {
                0.0
            };
            let mut p = kd(i);
            if i >= 1 {
                p -= a1 * a1 * dd[i - 1];
            }
            if i >= 2 {
                p -= a2 * a2 * dd[i - 2];
            }
            if !pivot_ok(p, kd(i)) {
                return Err(Error::Singular { vertex: i });
            }
            dd[i] = p;
            dinv[i] = 1.0 / p;
            l1[i] = a1;
            l2[i] = a2;
        }
        let (mut g0, mut g1, mut l10) = (Vec::new(), Vec::new(), 0.0);
        if closed {
            let (r0, r1) = (n - 2, n - 1);
            // Original border entries K[r][j], j < m.
            let mut k0 = vec![0.0; m];
            let mut k1 = vec![0.0; m];
            k0[n - 4] += coupling(r0, n - 4, s.off2[n - 4]);
            k0[n - 3] += coupling(r0, n - 3, s.off1[n - 3]);
            k0[0] += coupling(r0, 0, s.off2[n - 2]);
            k1[n - 3] += coupling(r1, n - 3, s.off2[n - 3]);
            k1[0] += coupling(r1, 0, s.off1[n - 1]);
            k1[1] += coupling(r1, 1, s.off2[n - 1]);
            let k10 = coupling(r1, r0, s.off1[n - 2]);
            let border = |k: &[f64]| -> Vec<f64> {
                let mut g = vec![0.0; m];
                for j in 0..m {
                    let mut v = k[j];
                    if j >= 1 {
                        v -= g[j - 1] * dd[j - 1] * l1[j];
                    }
                    if j >= 2 {
                        v -= g[j - 2] * dd[j - 2] * l2[j];
                    }
                    g[j] = v * dinv[j];
                }
                g
            };
            g0 = border(&k0);
            g1 = border(&k1);
            let mut p0 = kd(r0);
            let mut c10 = k10;
            let mut p1 = kd(r1);
            for j in 0..m {
                p0 -= g0[j] * g0[j] * dd[j];
                c10 -= g1[j] * g0[j] * dd[j];
                p1 -= g1[j] * g1[j] * dd[j];
            }
            if !pivot_ok(p0, kd(r0)) {
                return Err(Error::Singular { vertex: r0 });
            }
            l10 = c10 / p0;
            p1 -= l10 * l10 * p0;
            if !pivot_ok(p1, kd(r1)) {
                return Err(Error::Singular { vertex: r1 });
            }
            dinv[r0] = 1.0 / p0;
            dinv[r1] = 1.0 / p1;
        }
        Ok(BandFactor {
            n,
            dim: s.dim,
            m,
            dinv,
            l1,
            l2,
            g0,
            g1,
            l10,
            fixed_couplings,
        })
    }

    pub(crate) fn solve(&self, x: &mut [f64], fixed: &[bool]) {
        let d = self.dim;
        for &(i, j, v) in &self.fixed_couplings {
            for c in 0..d {
                x[i * d + c] -= v * x[j * d + c];
            }
        }
        let _ = fixed;
        match d {
            1 => self.solve_d::<1>(x, 1),
            2 => self.solve_d::<2>(x, 2),
            3 => self.solve_d::<3>(x, 3),
            4 => self.solve_d::<4>(x, 4),
            _ => self.solve_d::<0>(x, d),
        }
    }

    #[inline(always)]
    fn solve_d<const D: usize>(&self, x: &mut [f64], dyn_d: usize) {
        let d = if D == 0 { dyn_d } else { D };
        let (n, m) = (self.n, self.m);
        let (l1, l2, dinv) = (&self.l1[..m + 2], &self.l2[..m + 2], &self.dinv[..n]);
        // Forward: z_i = b_i − l1_i z_{i−1} − l2_i z_{i−2}.
        if m >= 2 {
            for c in 0..d {
                x[d + c] -= l1[1] * x[c];
            }
        }
        for i in 2..m {
            let (a1, a2) = (l1[i], l2[i]);
            let (head, tail) = x.split_at_mut(i * d);
            let zi = &mut tail[..d];
            let z1 = &head[(i - 1) * d..i * d];
            let z2 = &head[(i - 2) * d..(i - 1) * d];
            for c in 0..d {
                zi[c] -= a1 * z1[c] + a2 * z2[c];
            }
        }
        let closed = m < n;
        if closed {
            let (r0, r1) = (n - 2, n - 1);
            for c in 0..d {
                let (mut s0, mut s1) = (0.0, 0.0);
                for j in 0..m {
                    s0 += self.g0[j] * x[j * d + c];
                    s1 += self.g1[j] * x[j * d + c];
                }
                x[r0 * d + c] -= s0;
                x[r1 * d + c] -= s1 + self.l10 * x[r0 * d + c];
            }
        }
        // Diagonal.
        for (i, xi) in x.chunks_exact_mut(d).enumerate() {
            let s = dinv[i];
            for v in xi.iter_mut().take(d) {
                *v *= s;
            }
        }
        // Backward: x_j = y_j − l1_{j+1} x_{j+1} − l2_{j+2} x_{j+2} (− border terms).
        let mut xr = [0.0; 8];
        let mut xr_dyn = Vec::new();
        let xr: &mut [f64] = if 2 * d <= 8 {
            &mut xr[..2 * d]
        } else {
            xr_dyn.resize(2 * d, 0.0);
            &mut xr_dyn
        };
        if closed {
            let (r0, r1) = (n - 2, n - 1);
            for c in 0..d {
                x[r0 * d + c] -= self.l10 * x[r1 * d + c];
                xr[c] = x[r0 * d + c];
                xr[d + c] = x[r1 * d + c];
            }
            for j in (0..m).rev() {
                let (g0, g1) = (self.g0[j], self.g1[j]);
                for c in 0..d {
                    x[j * d + c] -= g0 * xr[c] + g1 * xr[d + c];
                }
            }
        }
        if m >= 2 {
            for c in 0..d {
                x[(m - 2) * d + c] -= l1[m - 1] * x[(m - 1) * d + c];
            }
        }
        for j in (0..m.saturating_sub(2)).rev() {
            let (a1, a2) = (l1[j + 1], l2[j + 2]);
            let (head, tail) = x.split_at_mut((j + 1) * d);
            let xj = &mut head[j * d..];
            let x1 = &tail[..d];
            let x2 = &tail[d..2 * d];
            for c in 0..d {
                xj[c] -= a1 * x1[c] + a2 * x2[c];
            }
        }
    }
}
