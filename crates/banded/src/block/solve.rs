//! Solves with a [`BlockFactor`]: forward and backward substitution over the band rows, the
//! border and the dense tail (a kernel with d fixed at compile time for d ≤ 4, a general one
//! for larger d).

// Dense d×d kernels index several arrays by the same row and column.
#![allow(clippy::needless_range_loop)]

use super::BlockFactor;
use crate::scalar::check_len;
use crate::{dense, Error};

impl<const W: usize> BlockFactor<W> {
    /// The number of block rows n of the factored matrix.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether n = 0.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The block size d.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Solves A X = B in place for the `ncols` columns of X ((n·d) × ncols, row-major; B on
    /// entry). Allocates nothing. Block rows eliminated at factorization are identity rows:
    /// there x = b.
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` does not have n · d · ncols entries.
    pub fn solve_in_place(&self, x: &mut [f64], ncols: usize) -> Result<(), Error> {
        check_len("x", x.len(), self.n * self.dim * ncols)?;
        for c in 0..ncols {
            match (self.dim, ncols) {
                (1, 1) => self.kernel_fixed::<1, 1>(x, 1, 0),
                (2, 1) => self.kernel_fixed::<2, 1>(x, 1, 0),
                (3, 1) => self.kernel_fixed::<3, 1>(x, 1, 0),
                (4, 1) => self.kernel_fixed::<4, 1>(x, 1, 0),
                (1, _) => self.kernel_fixed::<1, 0>(x, ncols, c),
                (2, _) => self.kernel_fixed::<2, 0>(x, ncols, c),
                (3, _) => self.kernel_fixed::<3, 0>(x, ncols, c),
                (4, _) => self.kernel_fixed::<4, 0>(x, ncols, c),
                _ => self.kernel::<0>(x, ncols, c),
            }
        }
        Ok(())
    }

    /// Solves for column `c0` of the row-major x with `st` columns, for a block size `D` fixed
    /// at compile time: the running values of the recurrences stay in registers (reading back
    /// a value just stored would put store forwarding on each row's dependency chain), and
    /// every block is read at constant offsets. `S` = 1: one contiguous column (constant
    /// stride); 0: stride `st` at run time.
    #[inline(always)]
    fn kernel_fixed<const D: usize, const S: usize>(&self, x: &mut [f64], st: usize, c0: usize) {
        let (n, m) = (self.n, self.m);
        let t = n - m;
        let b = self.border;
        // Forward (zw[q] = z_{i−1−q}; sums[r] = Σ_j L_{m+r,j} z_j).
        let mut zw = [[0.0f64; D]; W];
        let mut sums = [[0.0f64; D]; W];
        self.forward_fixed::<D, S, true>(x, st, c0, 0..b.head, 0, &mut zw, &mut sums);
        self.forward_fixed::<D, S, false>(x, st, c0, b.head..b.tail, 0, &mut zw, &mut sums);
        let ts = b.tail_slot();
        self.forward_fixed::<D, S, true>(x, st, c0, b.tail..m, ts, &mut zw, &mut sums);
        // The t·d tail: L₂₂ L₂₂ᵀ x₂ = b₂ − Σ G z.
        let mut xr = [[0.0f64; D]; W];
        if t > 0 {
            let td = t * D;
            let tl = &self.tail[..td * td];
            for r in 0..t {
                let v = load::<D, S>(x, m + r, st, c0);
                for a in 0..D {
                    xr[r][a] = v[a] - sums[r][a];
                }
            }
            for p in 0..td {
                let mut s = xr[p / D][p % D];
                for q in 0..p {
                    s -= tl[p * td + q] * xr[q / D][q % D];
                }
                xr[p / D][p % D] = s * tl[p * td + p];
            }
            for p in (0..td).rev() {
                let mut s = xr[p / D][p % D];
                for q in p + 1..td {
                    s -= tl[q * td + p] * xr[q / D][q % D];
                }
                xr[p / D][p % D] = s * tl[p * td + p];
            }
            for (r, v) in xr.iter().enumerate().take(t) {
                store::<D, S>(x, m + r, st, c0, v);
            }
        }
        // Backward (xw[q] = x_{j+1+q}).
        let mut xw = [[0.0f64; D]; W];
        self.backward_fixed::<D, S, true>(x, st, c0, b.tail..m, ts, &xr, &mut xw);
        self.backward_fixed::<D, S, false>(x, st, c0, b.head..b.tail, 0, &xr, &mut xw);
        self.backward_fixed::<D, S, true>(x, st, c0, 0..b.head, 0, &xr, &mut xw);
    }

    /// z_i = L_ii⁻¹ (b_i − Σ_k L_{i,i−k} z_{i−k}) over `range` (`B`: and the border sums, the
    /// border of row `range.start` at slot `slot0`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn forward_fixed<const D: usize, const S: usize, const B: bool>(
        &self,
        x: &mut [f64],
        st: usize,
        c0: usize,
        range: std::ops::Range<usize>,
        slot0: usize,
        window: &mut [[f64; D]; W],
        border_sums: &mut [[f64; D]; W],
    ) {
        let dd = D * D;
        let (rs, gs) = ((W + 1) * dd, W * dd);
        let t = self.n - self.m;
        let (mut zw, mut sums) = (*window, *border_sums);
        let start = range.start;
        for i in range {
            let row = &self.rows[i * rs..(i + 1) * rs];
            let mut v = load::<D, S>(x, i, st, c0);
            // Oldest first: z_{i−1}, the newest, enters last (off the critical path). For d = 1
            // the older values are read back from x under a branch, as in the scalar kind
            // (`SymBandFactor::forward`): a window of scalars gets packed into one vector
            // multiply with the newest value, which lengthens each row's dependency chain.
            for k in (2..=W).rev() {
                if D == 1 {
                    if i >= k {
                        let older = load::<D, S>(x, i - k, st, c0);
                        sub_mv::<D>(&mut v, &row[k * dd..(k + 1) * dd], &older);
                    }
                } else {
                    sub_mv::<D>(&mut v, &row[k * dd..(k + 1) * dd], &zw[k - 1]);
                }
            }
            sub_mv::<D>(&mut v, &row[dd..2 * dd], &zw[0]);
            let l = &row[..dd];
            for r in 0..D {
                let mut s = v[r];
                for c in 0..r {
                    s -= l[r * D + c] * v[c];
                }
                v[r] = s * l[r * D + r];
            }
            store::<D, S>(x, i, st, c0, &v);
            if B {
                let g = &self.g[(slot0 + i - start) * gs..][..gs];
                for (r, sr) in sums.iter_mut().enumerate().take(t) {
                    let gr = &g[r * dd..(r + 1) * dd];
                    for a in 0..D {
                        for c in 0..D {
                            sr[a] += gr[a * D + c] * v[c];
                        }
                    }
                }
            }
            for q in (1..W).rev() {
                zw[q] = zw[q - 1];
            }
            zw[0] = v;
        }
        (*window, *border_sums) = (zw, sums);
    }

    /// x_j = L_jj⁻ᵀ (z_j − Σ_r L_{m+r,j}ᵀ x_{m+r} − Σ_k L_{j+k,j}ᵀ x_{j+k}) over `range`, last
    /// row first (`B`: with the border terms, the border of row `range.start` at `slot0`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn backward_fixed<const D: usize, const S: usize, const B: bool>(
        &self,
        x: &mut [f64],
        st: usize,
        c0: usize,
        range: std::ops::Range<usize>,
        slot0: usize,
        xr: &[[f64; D]; W],
        window: &mut [[f64; D]; W],
    ) {
        let dd = D * D;
        let (rs, gs) = ((W + 1) * dd, W * dd);
        let (t, m) = (self.n - self.m, self.m);
        let mut xw = *window;
        let start = range.start;
        for j in range.rev() {
            let mut v = load::<D, S>(x, j, st, c0);
            if B {
                let g = &self.g[(slot0 + j - start) * gs..][..gs];
                for (r, xrr) in xr.iter().enumerate().take(t) {
                    sub_mtv::<D>(&mut v, &g[r * dd..(r + 1) * dd], xrr);
                }
            }
            for k in (1..=W).rev() {
                if j + k < m {
                    let o = (j + k) * rs + k * dd;
                    sub_mtv::<D>(&mut v, &self.rows[o..o + dd], &xw[k - 1]);
                }
            }
            let l = &self.rows[j * rs..j * rs + dd];
            for r in (0..D).rev() {
                let mut s = v[r];
                for c in r + 1..D {
                    s -= l[c * D + r] * v[c];
                }
                v[r] = s * l[r * D + r];
            }
            store::<D, S>(x, j, st, c0, &v);
            for q in (1..W).rev() {
                xw[q] = xw[q - 1];
            }
            xw[0] = v;
        }
        *window = xw;
    }

    /// Solves for column `c0` of the row-major x with `st` columns (`D` = 0: `self.dim`).
    #[inline(always)]
    fn kernel<const D: usize>(&self, x: &mut [f64], st: usize, c0: usize) {
        let d = if D == 0 { self.dim } else { D };
        let dd = d * d;
        let (n, m) = (self.n, self.m);
        let t = n - m;
        let rs = (W + 1) * dd;
        let gs = W * dd;
        let at = |i: usize| i * d * st + c0;
        let b = self.border;
        // Forward: z_i = L_ii⁻¹ (b_i − Σ_k L_{i,i−k} z_{i−k}); the border rows collect
        // b_{m+r} − Σ_j L_{m+r,j} z_j in place.
        let forward = |x: &mut [f64], range: std::ops::Range<usize>, slot0: usize, border: bool| {
            let start = range.start;
            for i in range {
                let row = &self.rows[i * rs..(i + 1) * rs];
                for k in (1..=W.min(i)).rev() {
                    dense::sub_mul_vec(x, at(i), &row[k * dd..(k + 1) * dd], at(i - k), st, d);
                }
                dense::lower_solve(&row[..dd], x, at(i), st, d);
                if border {
                    let g = &self.g[(slot0 + i - start) * gs..][..gs];
                    for r in 0..t {
                        dense::sub_mul_vec(x, at(m + r), &g[r * dd..(r + 1) * dd], at(i), st, d);
                    }
                }
            }
        };
        forward(x, 0..b.head, 0, true);
        forward(x, b.head..b.tail, 0, false);
        forward(x, b.tail..m, b.tail_slot(), true);
        if t > 0 {
            dense::lower_solve(&self.tail, x, at(m), st, t * d);
            dense::lower_t_solve(&self.tail, x, at(m), st, t * d);
        }
        // Backward: x_j = L_jj⁻ᵀ (z_j − Σ_k L_{j+k,j}ᵀ x_{j+k} − Σ_r L_{m+r,j}ᵀ x_{m+r}).
        let backward = |x: &mut [f64],
                        range: std::ops::Range<usize>,
                        slot0: usize,
                        border: bool| {
            let start = range.start;
            for j in range.rev() {
                if border {
                    let g = &self.g[(slot0 + j - start) * gs..][..gs];
                    for r in 0..t {
                        dense::sub_mul_t_vec(x, at(j), &g[r * dd..(r + 1) * dd], at(m + r), st, d);
                    }
                }
                for k in (1..=W).rev() {
                    if j + k < m {
                        let lk = &self.rows[(j + k) * rs + k * dd..][..dd];
                        dense::sub_mul_t_vec(x, at(j), lk, at(j + k), st, d);
                    }
                }
                dense::lower_t_solve(&self.rows[j * rs..j * rs + dd], x, at(j), st, d);
            }
        };
        backward(x, b.tail..m, b.tail_slot(), true);
        backward(x, b.head..b.tail, 0, false);
        backward(x, 0..b.head, 0, true);
    }
}

#[cfg(test)]
impl<const W: usize> BlockFactor<W> {
    /// The Cholesky factor as a dense lower triangular matrix (diagonal no longer inverted).
    pub(crate) fn dense_factor(&self) -> nalgebra::DMatrix<f64> {
        let (n, m, d) = (self.n, self.m, self.dim);
        let (dd, t) = (d * d, n - m);
        let rs = (W + 1) * dd;
        let mut l = nalgebra::DMatrix::<f64>::zeros(n * d, n * d);
        let put = |l: &mut nalgebra::DMatrix<f64>, i: usize, j: usize, b: &[f64], diag: bool| {
            for r in 0..d {
                for c in 0..d {
                    let v = b[r * d + c];
                    l[(i * d + r, j * d + c)] = if diag && r == c { 1.0 / v } else { v };
                }
            }
        };
        for i in 0..m {
            let row = &self.rows[i * rs..(i + 1) * rs];
            put(&mut l, i, i, &row[..dd], true);
            for k in 1..=W.min(i) {
                put(&mut l, i, i - k, &row[k * dd..(k + 1) * dd], false);
            }
        }
        if t > 0 {
            let b = self.border;
            for (slot, j) in (0..b.head).chain(b.tail..m).enumerate() {
                for r in 0..t {
                    put(
                        &mut l,
                        m + r,
                        j,
                        &self.g[(slot * W + r) * dd..][..dd],
                        false,
                    );
                }
            }
            let td = t * d;
            for a in 0..td {
                for c in 0..=a {
                    let v = self.tail[a * td + c];
                    l[(m * d + a, m * d + c)] = if a == c { 1.0 / v } else { v };
                }
            }
        }
        l
    }

    /// The stored border rows (head, tail) of a cyclic factor.
    pub(crate) fn border_rows(&self) -> (usize, usize) {
        (self.border.head, self.border.tail)
    }
}

/// Unknowns of block row i of column c0 (stride `st`, or 1 when `S` = 1).
#[inline(always)]
fn load<const D: usize, const S: usize>(x: &[f64], i: usize, st: usize, c0: usize) -> [f64; D] {
    let mut v = [0.0; D];
    if S == 1 {
        v.copy_from_slice(&x[i * D..(i + 1) * D]);
    } else {
        for (r, vr) in v.iter_mut().enumerate() {
            *vr = x[(i * D + r) * st + c0];
        }
    }
    v
}

/// The inverse of [`load`].
#[inline(always)]
fn store<const D: usize, const S: usize>(
    x: &mut [f64],
    i: usize,
    st: usize,
    c0: usize,
    v: &[f64; D],
) {
    if S == 1 {
        x[i * D..(i + 1) * D].copy_from_slice(v);
    } else {
        for (r, vr) in v.iter().enumerate() {
            x[(i * D + r) * st + c0] = *vr;
        }
    }
}

/// v ← v − a u for the D×D block a (row-major).
#[inline(always)]
fn sub_mv<const D: usize>(v: &mut [f64; D], a: &[f64], u: &[f64; D]) {
    let a = &a[..D * D];
    for r in 0..D {
        // From the first product, not from 0.0: 0.0 + x is not x for x = −0.0, so the compiler
        // would keep an addition on the dependency chain.
        let mut s = a[r * D] * u[0];
        for c in 1..D {
            s += a[r * D + c] * u[c];
        }
        v[r] -= s;
    }
}

/// v ← v − aᵀ u for the D×D block a (row-major).
#[inline(always)]
fn sub_mtv<const D: usize>(v: &mut [f64; D], a: &[f64], u: &[f64; D]) {
    let a = &a[..D * D];
    for c in 0..D {
        let mut s = a[c] * u[0];
        for r in 1..D {
            s += a[r * D + c] * u[r];
        }
        v[c] -= s;
    }
}
