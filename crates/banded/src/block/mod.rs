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
//! The block size is a run-time value. For d = 1..4 the factorization and the solves run
//! kernels with d a compile-time constant: every block is an array value, fully unrolled, and
//! the recurrences' running values stay in registers (`factor::factor_rows_fixed`,
//! `solve::kernel_fixed`); larger d run a general path on flat blocks with d at run time
//! (`factor::factor_rows_general`, `solve::kernel`). The cyclic border, rarely more than a few
//! rows, has one implementation for both. The tests cover both paths.
//!
//! # Cyclic matrices
//!
//! As for [`SymBand`]: the last t = min(W, n) block rows are a border, the border decays and is
//! flushed, the t·d × t·d Schur complement is factored densely, and for n ≤ 2W aliasing blocks
//! add up.

// Dense d×d and band kernels index several arrays by the same row and column: index loops
// read more clearly than iterator chains here.
#![allow(clippy::needless_range_loop)]

mod factor;
mod solve;

use crate::border::Border;
use crate::scalar::{check_index, check_len, forward_distance};
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

    /// The coupling blocks B to write in place: block row i's W + 1 blocks B_{i,i+k},
    /// k = 0..=W (column indices mod n if cyclic; slots past the end of an open matrix are
    /// ignored), d² entries each, row-major, at ((i·(W + 1) + k)·d²) — n·(W + 1)·d² entries.
    /// A writer must keep B_{ii} (slot 0) symmetric; when the slots of several (i, k) name the
    /// same block (cyclic, n ≤ 2W) they add up, as with [`add`](BlockBand::add). The storage is
    /// allocated (zero) on first use; for assembling B row by row without the index checks of
    /// [`add_scaled`](BlockBand::add_scaled).
    pub fn blocks_mut(&mut self) -> &mut [f64] {
        if self.blocks.is_empty() {
            self.blocks = vec![0.0; self.len() * (W + 1) * self.dim * self.dim];
        }
        &mut self.blocks
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
}
