//! The block Cholesky factorization of a [`BlockBand`]: the band rows (a kernel with d fixed
//! at compile time for d ≤ 4, a general one for larger d) and the border of cyclic matrices.

// Dense d×d kernels index several arrays by the same row and column.
#![allow(clippy::needless_range_loop)]

use super::{BlockBand, BlockFactor};
use crate::border::{Border, BORDER_FLUSH_RTOL};
use crate::{dense, Error, Topology};

/// A d×d block with d fixed at compile time.
type Blk<const D: usize> = [[f64; D]; D];

impl<const W: usize> BlockBand<W> {
    /// The factorization with the block size a compile-time constant (`D` = 0: `self.dim`)
    /// and `E`: whether rows are eliminated (`elim`).
    #[inline(always)]
    pub(super) fn factor_kernel<const D: usize, const E: bool>(
        &self,
        elim: &[bool],
        rtol: f64,
        f: &mut BlockFactor<W>,
    ) -> Result<(), Error> {
        let d = if D == 0 { self.dim } else { D };
        let dd = d * d;
        let n = self.len();
        let t = match self.topology() {
            Topology::Open => 0,
            Topology::Cyclic => W.min(n),
        };
        let m = n - t;
        let rs = (W + 1) * dd;
        f.n = n;
        f.m = m;
        f.dim = d;
        f.rows.clear();
        f.rows.reserve(m * rs);
        f.g.clear();
        f.border = Border::none(m);
        if D == 0 {
            let mut scratch = std::mem::take(&mut f.scratch);
            let r = self.factor_rows_general::<E>(elim, rtol, m, &mut f.rows, &mut scratch);
            f.scratch = scratch;
            r?;
        } else {
            self.factor_rows_fixed::<D, E>(elim, rtol, m, &mut f.rows)?;
        }
        if t > 0 {
            self.factor_border::<D>(if E { Some(elim) } else { None }, t, rtol, f)?;
        }
        Ok(())
    }

    /// The band rows 0..m of the factor for any block size d (flat blocks in scratch slices).
    fn factor_rows_general<const E: bool>(
        &self,
        elim: &[bool],
        rtol: f64,
        m: usize,
        rows: &mut Vec<f64>,
        scratch: &mut Vec<f64>,
    ) -> Result<(), Error> {
        let d = self.dim;
        let dd = d * d;
        let rs = (W + 1) * dd;
        let fixed = |i: usize| E && elim[i];
        let off = self.scalar.off();
        let sdiag = self.scalar.diag();
        let blocks = &self.blocks[..];
        let has_blocks = !blocks.is_empty();
        // Scratch: the row being computed (W + 1 blocks), one block and the reference diagonal.
        scratch.clear();
        scratch.resize(rs + dd + d, 0.0);
        let (cur, rest) = scratch.split_at_mut(rs);
        let (tmp, kref) = rest.split_at_mut(dd);
        for i in 0..m {
            let done = &rows[..];
            for k in (1..=W).rev() {
                if k > i {
                    cur[k * dd..(k + 1) * dd].fill(0.0);
                    continue;
                }
                let j = i - k;
                // A_{i,j} = S_{j,i} I + B_{j,i}ᵀ (stored at row j, slot k). Band rows never alias.
                tmp.fill(0.0);
                if !(fixed(i) || fixed(j)) {
                    let s = off[j][k - 1];
                    for c in 0..d {
                        tmp[c * d + c] = s;
                    }
                    if has_blocks {
                        let b = &blocks[(j * (W + 1) + k) * dd..][..dd];
                        for r in 0..d {
                            for c in 0..d {
                                tmp[r * d + c] += b[c * d + r];
                            }
                        }
                    }
                }
                let rj = &done[j * rs..(j + 1) * rs];
                for kk in k + 1..=W.min(i) {
                    // q = i − kk: L_{iq} (this row, slot kk) and L_{jq} (row j, slot kk − k).
                    dense::sub_mul_t(
                        tmp,
                        &cur[kk * dd..(kk + 1) * dd],
                        &rj[(kk - k) * dd..(kk - k + 1) * dd],
                        d,
                    );
                }
                dense::right_solve_lt(tmp, &rj[..dd], d);
                cur[k * dd..(k + 1) * dd].copy_from_slice(tmp);
            }
            tmp.fill(0.0);
            if fixed(i) {
                for c in 0..d {
                    tmp[c * d + c] = 1.0;
                }
            } else {
                for c in 0..d {
                    tmp[c * d + c] = sdiag[i];
                }
                if has_blocks {
                    let b = &blocks[i * (W + 1) * dd..][..dd];
                    for (o, v) in tmp.iter_mut().zip(b) {
                        *o += v;
                    }
                }
            }
            for c in 0..d {
                kref[c] = tmp[c * d + c];
            }
            for k in 1..=W.min(i) {
                dense::sub_gram_lower(tmp, &cur[k * dd..(k + 1) * dd], d);
            }
            dense::cholesky(tmp, kref, rtol, d).map_err(|_| Error::Singular { index: i })?;
            cur[..dd].copy_from_slice(tmp);
            rows.extend_from_slice(cur);
        }
        Ok(())
    }

    /// The band rows 0..m of the factor for a block size `D` fixed at compile time: every
    /// block is a `[[f64; D]; D]` value (registers), read from and written to the flat storage
    /// at constant offsets.
    fn factor_rows_fixed<const D: usize, const E: bool>(
        &self,
        elim: &[bool],
        rtol: f64,
        m: usize,
        rows: &mut Vec<f64>,
    ) -> Result<(), Error> {
        let dd = D * D;
        let rs = (W + 1) * dd;
        let fixed = |i: usize| E && elim[i];
        let off = self.scalar.off();
        let sdiag = self.scalar.diag();
        let blocks = &self.blocks[..];
        let has_blocks = !blocks.is_empty();
        for i in 0..m {
            // Constant loop bounds (W, not W.min(i)) keep `low` in registers: the loops unroll
            // and index it with constants.
            let mut low: [Blk<D>; W] = [[[0.0; D]; D]; W];
            for k in (1..=W).rev() {
                if k > i {
                    continue;
                }
                let j = i - k;
                // A_{i,j} = S_{j,i} I + B_{j,i}ᵀ (stored at row j, slot k). Band rows never alias.
                let mut a = [[0.0f64; D]; D];
                if !(fixed(i) || fixed(j)) {
                    let s = off[j][k - 1];
                    for c in 0..D {
                        a[c][c] = s;
                    }
                    if has_blocks {
                        let b = &blocks[(j * (W + 1) + k) * dd..][..dd];
                        for r in 0..D {
                            for c in 0..D {
                                a[r][c] += b[c * D + r];
                            }
                        }
                    }
                }
                let rj = &rows[j * rs..(j + 1) * rs];
                for kk in k + 1..=W {
                    // q = i − kk: L_{iq} (this row) and L_{jq} (row j, slot kk − k); both zero
                    // when q < 0 (kk > i), so no guard is needed.
                    let ljq = &rj[(kk - k) * dd..(kk - k + 1) * dd];
                    let liq = &low[kk - 1];
                    for r in 0..D {
                        for c in 0..D {
                            let mut t = liq[r][0] * ljq[c * D];
                            for q in 1..D {
                                t += liq[r][q] * ljq[c * D + q];
                            }
                            a[r][c] -= t;
                        }
                    }
                }
                // L_{ij} = a L_jj⁻ᵀ (diagonal inverted).
                let ljj = &rj[..dd];
                for r in 0..D {
                    for c in 0..D {
                        let mut t = a[r][c];
                        for q in 0..c {
                            t -= a[r][q] * ljj[c * D + q];
                        }
                        a[r][c] = t * ljj[c * D + c];
                    }
                }
                low[k - 1] = a;
            }
            let mut sblk = [[0.0f64; D]; D];
            if fixed(i) {
                for c in 0..D {
                    sblk[c][c] = 1.0;
                }
            } else {
                for c in 0..D {
                    sblk[c][c] = sdiag[i];
                }
                if has_blocks {
                    let b = &blocks[i * (W + 1) * dd..][..dd];
                    for r in 0..D {
                        for c in 0..D {
                            sblk[r][c] += b[r * D + c];
                        }
                    }
                }
            }
            let mut kref = [0.0; D];
            for c in 0..D {
                kref[c] = sblk[c][c];
            }
            for l in low.iter() {
                for r in 0..D {
                    for c in 0..=r {
                        let mut t = l[r][0] * l[c][0];
                        for q in 1..D {
                            t += l[r][q] * l[c][q];
                        }
                        sblk[r][c] -= t;
                    }
                }
            }
            // Cholesky of the diagonal block, diagonal inverted, upper triangle zero.
            let mut lii = [[0.0f64; D]; D];
            for c in 0..D {
                let mut p = sblk[c][c];
                for q in 0..c {
                    p -= lii[c][q] * lii[c][q];
                }
                if !(p.is_finite() && p > rtol * kref[c]) {
                    return Err(Error::Singular { index: i });
                }
                let inv = 1.0 / p.sqrt();
                lii[c][c] = inv;
                for r in c + 1..D {
                    let mut t = sblk[r][c];
                    for q in 0..c {
                        t -= lii[r][q] * lii[c][q];
                    }
                    lii[r][c] = t * inv;
                }
            }
            // One append per row (slot 0: L_ii, slot k: L_{i,i−k}).
            let len = rows.len();
            rows.resize(len + rs, 0.0);
            let out = &mut rows[len..len + rs];
            for (slot, blk) in std::iter::once(&lii).chain(low.iter()).enumerate() {
                for r in 0..D {
                    for c in 0..D {
                        out[slot * dd + r * D + c] = blk[r][c];
                    }
                }
            }
        }
        Ok(())
    }

    /// The border block rows m..n of a cyclic factor and the factor of the t·d × t·d Schur
    /// complement (module docs of `border.rs`).
    #[inline(always)]
    fn factor_border<const D: usize>(
        &self,
        elim: Option<&[bool]>,
        t: usize,
        rtol: f64,
        f: &mut BlockFactor<W>,
    ) -> Result<(), Error> {
        let d = if D == 0 { self.dim } else { D };
        let dd = d * d;
        let m = f.m;
        let rs = (W + 1) * dd;
        let gs = W * dd;
        let fixed = |i: usize| elim.is_some_and(|e| e[i]);
        // A_{ij} after elimination, added into `out`.
        let entry = |i: usize, j: usize, out: &mut [f64]| {
            if fixed(i) || fixed(j) {
                if i == j {
                    for c in 0..d {
                        out[c * d + c] += 1.0;
                    }
                }
            } else {
                self.add_entry(i, j, out);
            }
        };
        // The Schur complement T = A₂₂ − Σ_j G_j G_jᵀ: its lower blocks accumulate in `acc`
        // (block (r, s) at (r W + s) d², so the loops below have constant bounds and offsets for
        // a fixed d), and go to the dense (t·d)² `f.tail` at the end.
        let td = t * d;
        let mut scratch = std::mem::take(&mut f.scratch);
        scratch.clear();
        scratch.resize(dd + td + W * W * dd, 0.0);
        let (blk, rest) = scratch.split_at_mut(dd);
        let (kref, acc) = rest.split_at_mut(td);
        let mut scale = [0.0f64; W];
        let tail0 = m.saturating_sub(W);
        let mut border = Border { head: m, tail: m };
        // Slots of the border rows j − 1 − q (None: zero).
        let mut prev: [Option<usize>; W] = [None; W];
        let mut slot = 0;
        let mut j = 0;
        while j < m {
            if border.head == m && j >= W && j < tail0 && prev.iter().all(Option::is_none) {
                border = Border {
                    head: j,
                    tail: tail0,
                };
                j = tail0;
                continue;
            }
            let direct = j < W || j >= tail0;
            let lj = &f.rows[j * rs..(j + 1) * rs];
            f.g.resize((slot + 1) * gs, 0.0);
            let mut nonzero = false;
            for r in 0..W {
                if r >= t {
                    break;
                }
                blk.fill(0.0);
                if direct {
                    entry(m + r, j, blk);
                }
                for k in 1..=W {
                    if let (true, Some(p)) = (k <= j, prev[k - 1]) {
                        // G_{r, j−k} L_{j, j−k}ᵀ
                        let gp = &f.g[p * gs + r * dd..][..dd];
                        dense::sub_mul_t(blk, gp, &lj[k * dd..(k + 1) * dd], d);
                    }
                }
                dense::right_solve_lt(blk, &lj[..dd], d);
                let mag = blk.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                if mag < BORDER_FLUSH_RTOL * scale[r] {
                    continue;
                }
                scale[r] = scale[r].max(mag);
                if mag > 0.0 {
                    nonzero = true;
                }
                f.g[slot * gs + r * dd..][..dd].copy_from_slice(blk);
            }
            // T_{rs} −= G_r G_sᵀ (lower blocks, s ≤ r).
            if nonzero {
                let g = &f.g[slot * gs..(slot + 1) * gs];
                for r in 0..W {
                    for s in 0..=r {
                        if r < t {
                            let ars = &mut acc[(r * W + s) * dd..(r * W + s + 1) * dd];
                            let (gr, gsb) = (&g[r * dd..(r + 1) * dd], &g[s * dd..(s + 1) * dd]);
                            dense::sub_mul_t(ars, gr, gsb, d);
                        }
                    }
                }
            }
            for q in (1..W).rev() {
                prev[q] = prev[q - 1];
            }
            prev[0] = nonzero.then_some(slot);
            slot += 1;
            j += 1;
        }
        f.border = border;
        // T = A₂₂ + acc (lower blocks), then its dense Cholesky factor.
        f.tail.clear();
        f.tail.resize(td * td, 0.0);
        for r in 0..t {
            for s in 0..=r {
                blk.fill(0.0);
                entry(m + r, m + s, blk);
                let ars = &acc[(r * W + s) * dd..(r * W + s + 1) * dd];
                for a in 0..d {
                    for b in 0..d {
                        f.tail[(r * d + a) * td + s * d + b] = blk[a * d + b] + ars[a * d + b];
                    }
                }
                if r == s {
                    for a in 0..d {
                        kref[r * d + a] = blk[a * d + a];
                    }
                }
            }
        }
        let r = dense::cholesky(&mut f.tail, kref, rtol, td)
            .map_err(|c| Error::Singular { index: m + c / d });
        f.scratch = scratch;
        r
    }
}
