//! Block symmetric band matrices S ⊗ I_d + B (d×d blocks, half-bandwidth W ≤ 4 blocks), open
//! or cyclic, and their block Cholesky factorization.
//!
//! # The matrix
//!
//! A = S ⊗ I_d + B: S a scalar [`SymBand`] (the part every coordinate shares: an energy
//! Hessian, a condensed operator), B a symmetric block band (what couples the coordinates:
//! interior-point scalings, tangent stencils). Both are stored; the factorization reads their
//! sum, so an iteration that changes only B rewrites only B ([`BlockBand::clear_blocks`]).
//!
//! # The factorization
//!
//! Block Cholesky A = L Lᵀ with lower triangular d×d diagonal blocks (Golub–Van Loan, *Matrix
//! Computations*, 4th ed., §4.2.9 (block Cholesky) and §4.3.5 (band Cholesky)):
//!
//! L_{ij} = (A_{ij} − Σ_{q<j} L_{iq} L_{jq}ᵀ) L_{jj}^{−T},   L_{ii} = chol(A_{ii} − Σ_{j<i} L_{ij} L_{ij}ᵀ),
//!
//! sums over the band. Every Schur complement is formed as A − Σ X Xᵀ (Gram form), so it stays
//! symmetric and accurate when diagonal blocks are very ill-conditioned (barrier terms of
//! interior-point methods), and no block is ever inverted: triangular blocks store their
//! diagonal inverted and are applied by substitution. O(n W² d³) work, O(n W d²) memory, each
//! solve O(n W d²) per column.
//!
//! The block size is a run-time value; d = 1..4 run monomorphized kernels with the block size
//! a compile-time constant (fully unrolled), larger d the same code with d at run time.
//!
//! # Cyclic matrices
//!
//! As for [`SymBand`]: the last t = min(W, n) block rows are a border, the border decays and is
//! flushed, the t·d × t·d Schur complement is factored densely, and for n ≤ 2W aliasing blocks
//! add up.

// Dense d×d and band kernels index several arrays by the same row and column: index loops
// read more clearly than iterator chains here.
#![allow(clippy::needless_range_loop)]

use crate::border::{Border, BORDER_FLUSH_RTOL};
use crate::dense;
use crate::scalar::{check_index, check_len, forward_distance};

/// A d×d block with d fixed at compile time.
type Blk<const D: usize> = [[f64; D]; D];
use crate::{check_eliminated, Error, FactorOptions, SymBand, Topology};

/// A symmetric block band matrix A = S ⊗ I_d + B of n×n blocks of size d×d and half-bandwidth
/// `W` blocks (at most [`crate::MAX_HALF_BANDWIDTH`]), open or cyclic (module docs).
///
/// Vectors are stored block row by block row: unknown a of block row i is entry i·d + a; for
/// several columns, x is (n·d) × ncols, row-major.
///
/// ```
/// use banded::{BlockBand, Topology};
/// // A closed chain of 2×2 blocks: S = cyclic tridiagonal (4, −1), B couples the coordinates.
/// let (n, d) = (7, 2);
/// let mut a = BlockBand::<1>::zeros(n, d, Topology::Cyclic).unwrap();
/// for i in 0..n {
///     a.add_scalar(i, i, 4.0).unwrap();
///     a.add_scalar(i, (i + 1) % n, -1.0).unwrap();
///     a.add(i, i, &[1.0, 0.5, 0.5, 1.0]).unwrap();
/// }
/// let f = a.factor().unwrap();
/// let b: Vec<f64> = (0..n * d).map(|k| (k as f64).sin()).collect();
/// let mut x = b.clone();
/// f.solve_in_place(&mut x, 1).unwrap();
/// let mut ax = vec![0.0; n * d];
/// a.mul_add(&x, &mut ax, 1).unwrap();
/// assert!(ax.iter().zip(&b).all(|(u, v)| (u - v).abs() < 1e-14));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct BlockBand<const W: usize> {
    dim: usize,
    scalar: SymBand<W>,
    /// B: per block row j the W + 1 blocks B_{j,j+k}, k = 0..=W (indices mod n if cyclic),
    /// d² entries each, row-major. Empty until the first block is added.
    blocks: Vec<f64>,
}

/// The block Cholesky factor of a [`BlockBand`], reusable for any number of right-hand sides
/// and refillable without allocating ([`BlockBand::factor_into`]).
#[derive(Clone, Debug, Default)]
pub struct BlockFactor<const W: usize> {
    n: usize,
    m: usize,
    dim: usize,
    /// Per band row i the W + 1 blocks L_ii (slot 0, lower, diagonal inverted) and
    /// L_{i,i−k} (slot k).
    rows: Vec<f64>,
    /// Cyclic: the stored border rows and per stored row j the W blocks L_{m+r, j}, r < t.
    border: Border,
    g: Vec<f64>,
    /// Cyclic: the lower Cholesky factor (diagonal inverted) of the t·d × t·d Schur complement.
    tail: Vec<f64>,
    /// Work space of the factorization (kept so that refactoring allocates nothing).
    scratch: Vec<f64>,
}

impl<const W: usize> BlockBand<W> {
    /// The zero matrix of n×n blocks of size `dim`.
    ///
    /// # Errors
    /// [`Error::TooFew`] (field `"dim"`) for `dim` = 0.
    pub fn zeros(n: usize, dim: usize, topology: Topology) -> Result<BlockBand<W>, Error> {
        BlockBand::from_scalar(SymBand::zeros(n, topology), dim)
    }

    /// A = S ⊗ I_dim (no coupling blocks yet).
    ///
    /// # Errors
    /// [`Error::TooFew`] (field `"dim"`) for `dim` = 0.
    pub fn from_scalar(scalar: SymBand<W>, dim: usize) -> Result<BlockBand<W>, Error> {
        if dim == 0 {
            return Err(Error::TooFew {
                field: "dim",
                minimum: 1,
                got: 0,
            });
        }
        Ok(BlockBand {
            dim,
            scalar,
            blocks: Vec::new(),
        })
    }

    /// The number of block rows n.
    pub fn len(&self) -> usize {
        self.scalar.len()
    }

    /// Whether n = 0.
    pub fn is_empty(&self) -> bool {
        self.scalar.is_empty()
    }

    /// The block size d.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Open or cyclic.
    pub fn topology(&self) -> Topology {
        self.scalar.topology()
    }

    /// The scalar part S.
    pub fn scalar(&self) -> &SymBand<W> {
        &self.scalar
    }

    /// The scalar part S, for assembly in place.
    pub fn scalar_mut(&mut self) -> &mut SymBand<W> {
        &mut self.scalar
    }

    /// Whether coupling blocks have been added (their storage exists).
    pub fn has_blocks(&self) -> bool {
        !self.blocks.is_empty()
    }

    /// Adds `v` to S_{ij} and S_{ji}, that is v I_d to the blocks A_{ij} and A_{ji}.
    ///
    /// # Errors
    /// As [`SymBand::add`].
    pub fn add_scalar(&mut self, i: usize, j: usize, v: f64) -> Result<(), Error> {
        self.scalar.add(i, j, v)
    }

    /// Adds the d×d `block` (row-major) to A_{ij} and its transpose to A_{ji}; for i = j its
    /// symmetric part ½(B + Bᵀ) to A_ii.
    ///
    /// # Errors
    /// As [`add_scaled`](BlockBand::add_scaled).
    pub fn add(&mut self, i: usize, j: usize, block: &[f64]) -> Result<(), Error> {
        self.add_scaled(i, j, 1.0, block)
    }

    /// Adds `f · block` as [`add`](BlockBand::add) does `block`.
    ///
    /// # Errors
    /// [`Error::WrongLength`] (field `"block"`) for a block without d² entries,
    /// [`Error::IndexOutOfRange`] for an index ≥ n, [`Error::OutsideBand`] if i and j are more
    /// than W apart (cyclically, for cyclic matrices).
    pub fn add_scaled(&mut self, i: usize, j: usize, f: f64, block: &[f64]) -> Result<(), Error> {
        let (n, d) = (self.len(), self.dim);
        let dd = d * d;
        check_len("block", block.len(), dd)?;
        check_index(i, j, n)?;
        let top = self.topology();
        let (row, k, transpose) = if i == j {
            (i, 0, false)
        } else if let Some(k) = forward_distance(top, n, W, i, j) {
            (i, k, false)
        } else if let Some(k) = forward_distance(top, n, W, j, i) {
            (j, k, true)
        } else {
            return Err(Error::OutsideBand {
                row: i,
                col: j,
                half_bandwidth: W,
            });
        };
        if self.blocks.is_empty() {
            self.blocks = vec![0.0; n * (W + 1) * dd];
        }
        let o = (row * (W + 1) + k) * dd;
        let dst = &mut self.blocks[o..o + dd];
        for r in 0..d {
            for c in 0..d {
                let v = if i == j {
                    0.5 * (block[r * d + c] + block[c * d + r])
                } else if transpose {
                    block[c * d + r]
                } else {
                    block[r * d + c]
                };
                dst[r * d + c] += f * v;
            }
        }
        Ok(())
    }

    /// Writes the block A_{ij} (d² entries, row-major) into `out`: S_{ij} I_d plus every
    /// coupling block at that position (aliasing blocks summed).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for an index ≥ n, [`Error::WrongLength`] (field `"out"`) if
    /// `out` does not have d² entries.
    pub fn get(&self, i: usize, j: usize, out: &mut [f64]) -> Result<(), Error> {
        check_index(i, j, self.len())?;
        check_len("out", out.len(), self.dim * self.dim)?;
        out.fill(0.0);
        self.add_entry(i, j, out);
        Ok(())
    }

    /// out += A_{ij} for valid indices (aliasing entries summed).
    fn add_entry(&self, i: usize, j: usize, out: &mut [f64]) {
        let (n, d) = (self.len(), self.dim);
        let dd = d * d;
        let s = self.scalar.get(i, j).unwrap_or(0.0);
        for c in 0..d {
            out[c * d + c] += s;
        }
        if self.blocks.is_empty() {
            return;
        }
        let names = |row: usize, k: usize, col: usize| match self.topology() {
            Topology::Open => row + k == col,
            Topology::Cyclic => (row + k) % n == col,
        };
        for k in 0..=W {
            if names(i, k, j) {
                let b = &self.blocks[(i * (W + 1) + k) * dd..][..dd];
                for (o, v) in out.iter_mut().zip(b) {
                    *o += v;
                }
            }
            if k > 0 && names(j, k, i) {
                let b = &self.blocks[(j * (W + 1) + k) * dd..][..dd];
                for r in 0..d {
                    for c in 0..d {
                        out[r * d + c] += b[c * d + r];
                    }
                }
            }
        }
    }

    /// Sets every coupling block to zero (A = S ⊗ I_d again), keeping their storage.
    pub fn clear_blocks(&mut self) {
        self.blocks.fill(0.0);
    }

    /// Sets every entry to zero, keeping the storage.
    pub fn clear(&mut self) {
        self.scalar.clear();
        self.clear_blocks();
    }

    /// y ← y + A x for `ncols` columns (x and y are (n·d) × ncols, row-major).
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` or `y` does not have n · d · ncols entries.
    pub fn mul_add(&self, x: &[f64], y: &mut [f64], ncols: usize) -> Result<(), Error> {
        let (n, d) = (self.len(), self.dim);
        // (S ⊗ I_d) acts on the n × (d·ncols) matrix of block rows.
        self.scalar.mul_add(x, y, d * ncols)?;
        if self.blocks.is_empty() {
            return Ok(());
        }
        let dd = d * d;
        let cyclic = self.topology() == Topology::Cyclic;
        for j in 0..n {
            for k in 0..=W {
                let l = if j + k < n {
                    j + k
                } else if cyclic {
                    (j + k) % n
                } else {
                    continue;
                };
                let b = &self.blocks[(j * (W + 1) + k) * dd..][..dd];
                if b.iter().all(|&v| v == 0.0) {
                    continue;
                }
                for r in 0..d {
                    for c in 0..d {
                        let v = b[r * d + c];
                        for e in 0..ncols {
                            y[(j * d + r) * ncols + e] += v * x[(l * d + c) * ncols + e];
                            if k > 0 {
                                y[(l * d + c) * ncols + e] += v * x[(j * d + r) * ncols + e];
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// The block Cholesky factor with the default options ([`crate::PIVOT_RTOL`], nothing
    /// eliminated).
    ///
    /// # Errors
    /// [`Error::Singular`] naming the first block row with a pivot that is not finite or not
    /// above [`crate::PIVOT_RTOL`] times the diagonal entry of its row.
    pub fn factor(&self) -> Result<BlockFactor<W>, Error> {
        self.factor_with(&FactorOptions::default())
    }

    /// The block Cholesky factor (with the block rows in `options.eliminated` replaced by
    /// identity rows).
    ///
    /// # Errors
    /// [`Error::Singular`] naming the first block row with a pivot that is not finite or not
    /// above `options.pivot_rtol` times the diagonal entry of its row; [`Error::WrongLength`]
    /// if `options.eliminated` does not have n entries.
    pub fn factor_with(&self, options: &FactorOptions<'_>) -> Result<BlockFactor<W>, Error> {
        let mut f = BlockFactor::default();
        self.factor_into(options, &mut f)?;
        Ok(f)
    }

    /// [`factor_with`](BlockBand::factor_with) into an existing factor, reusing its storage
    /// (no allocation once it has held a factor of this size). On error `f` is left empty (of
    /// size 0: its solves report [`Error::WrongLength`]).
    ///
    /// # Errors
    /// As [`factor_with`](BlockBand::factor_with).
    pub fn factor_into(
        &self,
        options: &FactorOptions<'_>,
        f: &mut BlockFactor<W>,
    ) -> Result<(), Error> {
        check_eliminated(options.eliminated, self.len())?;
        let result = match (self.dim, options.eliminated) {
            (1, None) => self.factor_kernel::<1, false>(&[], options.pivot_rtol, f),
            (2, None) => self.factor_kernel::<2, false>(&[], options.pivot_rtol, f),
            (3, None) => self.factor_kernel::<3, false>(&[], options.pivot_rtol, f),
            (4, None) => self.factor_kernel::<4, false>(&[], options.pivot_rtol, f),
            (_, None) => self.factor_kernel::<0, false>(&[], options.pivot_rtol, f),
            (1, Some(e)) => self.factor_kernel::<1, true>(e, options.pivot_rtol, f),
            (2, Some(e)) => self.factor_kernel::<2, true>(e, options.pivot_rtol, f),
            (3, Some(e)) => self.factor_kernel::<3, true>(e, options.pivot_rtol, f),
            (4, Some(e)) => self.factor_kernel::<4, true>(e, options.pivot_rtol, f),
            (_, Some(e)) => self.factor_kernel::<0, true>(e, options.pivot_rtol, f),
        };
        if result.is_err() {
            (f.n, f.m) = (0, 0);
            f.rows.clear();
            f.g.clear();
            f.tail.clear();
            f.border = Border::default();
        }
        result
    }

    /// The factorization with the block size a compile-time constant (`D` = 0: `self.dim`)
    /// and `E`: whether rows are eliminated (`elim`).
    #[inline(always)]
    fn factor_kernel<const D: usize, const E: bool>(
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
            let mut low: [Blk<D>; W] = [[[0.0; D]; D]; W];
            for k in (1..=W.min(i)).rev() {
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
                for kk in k + 1..=W.min(i) {
                    // q = i − kk: L_{iq} (this row) and L_{jq} (row j, slot kk − k).
                    let ljq = &rj[(kk - k) * dd..(kk - k + 1) * dd];
                    let liq = &low[kk - 1];
                    for r in 0..D {
                        for c in 0..D {
                            let mut t = 0.0;
                            for q in 0..D {
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
                        let mut t = 0.0;
                        for q in 0..D {
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
        // The Schur complement T = A₂₂ − Σ_j G_j G_jᵀ, dense (t·d)², lower triangle used.
        let td = t * d;
        f.tail.clear();
        f.tail.resize(td * td, 0.0);
        let mut scratch = std::mem::take(&mut f.scratch);
        scratch.clear();
        scratch.resize(dd + td, 0.0);
        let (blk, kref) = scratch.split_at_mut(dd);
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
            for r in 0..t {
                blk.fill(0.0);
                if direct {
                    entry(m + r, j, blk);
                }
                for k in 1..=W.min(j) {
                    if let Some(p) = prev[k - 1] {
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
                for r in 0..t {
                    for s in 0..=r {
                        let (gr, gs_) = (&g[r * dd..(r + 1) * dd], &g[s * dd..(s + 1) * dd]);
                        for a in 0..d {
                            for b in 0..d {
                                let mut v = 0.0;
                                for q in 0..d {
                                    v += gr[a * d + q] * gs_[b * d + q];
                                }
                                f.tail[(r * d + a) * td + s * d + b] -= v;
                            }
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
        // T += A₂₂ (lower blocks), then its dense Cholesky factor.
        for r in 0..t {
            for s in 0..=r {
                blk.fill(0.0);
                entry(m + r, m + s, blk);
                for a in 0..d {
                    for b in 0..d {
                        f.tail[(r * d + a) * td + s * d + b] += blk[a * d + b];
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
            // Oldest first: z_{i−1}, the newest, enters last (off the critical path).
            for k in (1..=W).rev() {
                sub_mv::<D>(&mut v, &row[k * dd..(k + 1) * dd], &zw[k - 1]);
            }
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
        let mut s = 0.0;
        for c in 0..D {
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
        let mut s = 0.0;
        for r in 0..D {
            s += a[r * D + c] * u[r];
        }
        v[c] -= s;
    }
}
