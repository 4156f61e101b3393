//! Scalar symmetric band matrices (half-bandwidth W ≤ 4), open or cyclic, and their LDLᵀ
//! factorization shared by any number of right-hand-side columns.
//!
//! # The factorization
//!
//! A = L D Lᵀ with L unit lower triangular and D diagonal, computed row by row without square
//! roots (Golub–Van Loan, *Matrix Computations*, 4th ed., §4.1.2 (LDLᵀ) and §4.3.5–4.3.6
//! (band LDLᵀ and band Cholesky)): with u_{ij} = L_{ij} D_j,
//!
//! u_{ij} = A_{ij} − Σ_{q<j} u_{iq} L_{jq},   L_{ij} = u_{ij} / D_j,   D_i = A_{ii} − Σ_{j<i} u_{ij} L_{ij},
//!
//! the sums running over the band only (L has the band of A: i − W ≤ q < j). O(n W²) work,
//! O(n W) memory; every solve is O(n W) per column, the columns advancing side by side.
//!
//! For W = 1 the pivots come from the determinant recurrence P_i = A_ii P_{i−1} − A_{i,i−1}² P_{i−2}
//! (P_{−1} = 1, P_{−2} = 0; GVL §4.3.6, the leading principal minors of a tridiagonal matrix) as
//! D_i = P_i / P_{i−1}: the continued fraction D_i = A_ii − A_{i,i−1}²/D_{i−1} puts a division on
//! the dependency chain of every row, the recurrence only a multiply-add (the divisions then
//! overlap). P is rescaled by exact powers of two whenever it leaves [2^−100, 2^100].
//!
//! # Cyclic matrices
//!
//! A cyclic band matrix (A_{i,i+k} ≠ 0 for k ≤ W with indices mod n) is factored in its natural
//! order with its last t = min(W, n) rows as a border (see `border.rs`): the first m = n − t
//! rows are an ordinary band, the border rows are dense, L = [[L₁₁, 0], [G, L₂₂]] with G = the
//! border of L and L₂₂ D₂ L₂₂ᵀ the LDLᵀ of the t×t Schur complement A₂₂ − G D₁ Gᵀ (GVL §4.5.4,
//! block elimination; the "arrowhead" form of a cyclic band). The border decays geometrically
//! and is flushed to exact zeros, so only a few of its rows are stored and visited. For n ≤ 2W
//! the band aliases: entries that name the same position add up, and the whole matrix is the
//! border.

// Dense d×d and band kernels index several arrays by the same row and column: index loops
// read more clearly than iterator chains here.
#![allow(clippy::needless_range_loop)]

use crate::border::{Border, BORDER_FLUSH_RTOL};
use crate::{check_eliminated, Error, FactorOptions, Topology};

/// The largest half-bandwidth of [`SymBand`] and [`crate::BlockBand`].
pub const MAX_HALF_BANDWIDTH: usize = 4;

/// A symmetric band matrix of half-bandwidth `W` (1 = tridiagonal, 2 = pentadiagonal, …, at
/// most [`MAX_HALF_BANDWIDTH`]), open or cyclic.
///
/// Stored as its diagonal and, for each row j, the W entries to its right:
/// `off()[j][k − 1]` = A_{j, j+k} (= A_{j+k, j}), indices mod n for cyclic matrices. For an
/// open matrix the entries with j + k ≥ n lie outside the matrix and are ignored. For a cyclic
/// matrix with n ≤ 2W several entries name the same position and add up (an entry with
/// j + k ≡ j mod n adds twice to the diagonal, as A_{j,j+k} and as A_{j+k,j}).
///
/// ```
/// use banded::{SymBand, Topology};
/// // The cyclic second-difference matrix plus the identity: 3 on the diagonal, −1 beside it.
/// let n = 6;
/// let a = SymBand::<1>::from_bands(Topology::Cyclic, vec![3.0; n], vec![[-1.0]; n]).unwrap();
/// let f = a.factor().unwrap();
/// // Two right-hand sides at once, stored row by row (n × 2).
/// let mut x: Vec<f64> = (0..2 * n).map(|k| k as f64).collect();
/// let b = x.clone();
/// f.solve_in_place(&mut x, 2).unwrap();
/// let mut ax = vec![0.0; 2 * n];
/// a.mul_add(&x, &mut ax, 2).unwrap();
/// assert!(ax.iter().zip(&b).all(|(u, v)| (u - v).abs() < 1e-13));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SymBand<const W: usize> {
    topology: Topology,
    diag: Vec<f64>,
    off: Vec<[f64; W]>,
}

/// One band row of an LDLᵀ factor: L_{i,i−k} at `l[k − 1]`, and 1/D_i.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Row<const W: usize> {
    l: [f64; W],
    inv: f64,
}

impl<const W: usize> Row<W> {
    const ZERO: Row<W> = Row {
        l: [0.0; W],
        inv: 0.0,
    };
}

/// The LDLᵀ factor of a [`SymBand`], reusable for any number of right-hand sides
/// ([`solve_in_place`](SymBandFactor::solve_in_place)) and refillable without allocating
/// ([`SymBand::factor_into`]).
#[derive(Clone, Debug)]
pub struct SymBandFactor<const W: usize> {
    n: usize,
    /// Band rows (n − t, t the number of border rows).
    m: usize,
    rows: Vec<Row<W>>,
    /// Cyclic: the stored border rows, and per stored row j the entries L_{m+r, j}, r < t.
    border: Border,
    g: Vec<[f64; W]>,
    /// Cyclic: the LDLᵀ of the t×t Schur complement, L₂₂ (strictly lower) and 1/D₂.
    tail_l: [[f64; W]; W],
    tail_inv: [f64; W],
}

impl<const W: usize> Default for SymBandFactor<W> {
    fn default() -> Self {
        SymBandFactor {
            n: 0,
            m: 0,
            rows: Vec::new(),
            border: Border::default(),
            g: Vec::new(),
            tail_l: [[0.0; W]; W],
            tail_inv: [0.0; W],
        }
    }
}

impl<const W: usize> SymBand<W> {
    const VALID: () = assert!(
        W >= 1 && W <= MAX_HALF_BANDWIDTH,
        "the half-bandwidth must be 1..=MAX_HALF_BANDWIDTH"
    );

    /// The zero matrix of size `n`.
    pub fn zeros(n: usize, topology: Topology) -> SymBand<W> {
        let () = Self::VALID;
        SymBand {
            topology,
            diag: vec![0.0; n],
            off: vec![[0.0; W]; n],
        }
    }

    /// The matrix with diagonal `diag` and off-diagonal entries `off` (`off[j][k − 1]` =
    /// A_{j,j+k}; see the type docs for open ends and aliasing).
    ///
    /// # Errors
    /// [`Error::WrongLength`] (field `"off"`) if `off` and `diag` differ in length.
    pub fn from_bands(
        topology: Topology,
        diag: Vec<f64>,
        off: Vec<[f64; W]>,
    ) -> Result<SymBand<W>, Error> {
        let () = Self::VALID;
        if off.len() != diag.len() {
            return Err(Error::WrongLength {
                field: "off",
                expected: diag.len(),
                got: off.len(),
            });
        }
        Ok(SymBand {
            topology,
            diag,
            off,
        })
    }

    /// The size n.
    pub fn len(&self) -> usize {
        self.diag.len()
    }

    /// Whether n = 0.
    pub fn is_empty(&self) -> bool {
        self.diag.is_empty()
    }

    /// Open or cyclic.
    pub fn topology(&self) -> Topology {
        self.topology
    }

    /// The diagonal.
    pub fn diag(&self) -> &[f64] {
        &self.diag
    }

    /// The diagonal, for assembly in place.
    pub fn diag_mut(&mut self) -> &mut [f64] {
        &mut self.diag
    }

    /// The off-diagonal entries: `off()[j][k − 1]` = A_{j,j+k}.
    pub fn off(&self) -> &[[f64; W]] {
        &self.off
    }

    /// The off-diagonal entries, for assembly in place.
    pub fn off_mut(&mut self) -> &mut [[f64; W]] {
        &mut self.off
    }

    /// Sets every entry to zero (keeping the storage).
    pub fn clear(&mut self) {
        self.diag.fill(0.0);
        self.off.fill([0.0; W]);
    }

    /// The forward distance k ∈ 1..=W from `i` to `j` (j = i + k, mod n when cyclic), if any.
    #[inline]
    fn forward(&self, i: usize, j: usize) -> Option<usize> {
        forward_distance(self.topology, self.len(), W, i, j)
    }

    /// Adds `v` to A_{ij} and A_{ji} (once, for i = j).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for an index ≥ n, [`Error::OutsideBand`] if i and j are more
    /// than W apart (cyclically, for cyclic matrices).
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> Result<(), Error> {
        check_index(i, j, self.len())?;
        if i == j {
            self.diag[i] += v;
        } else if let Some(k) = self.forward(i, j) {
            self.off[i][k - 1] += v;
        } else if let Some(k) = self.forward(j, i) {
            self.off[j][k - 1] += v;
        } else {
            return Err(Error::OutsideBand {
                row: i,
                col: j,
                half_bandwidth: W,
            });
        }
        Ok(())
    }

    /// A_{ij}: the sum of every stored entry at that position (0 outside the band).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for an index ≥ n.
    pub fn get(&self, i: usize, j: usize) -> Result<f64, Error> {
        check_index(i, j, self.len())?;
        Ok(self.entry(i, j))
    }

    /// A_{ij} for valid indices (aliasing entries summed).
    fn entry(&self, i: usize, j: usize) -> f64 {
        let n = self.len();
        let mut v = if i == j { self.diag[i] } else { 0.0 };
        for k in 1..=W {
            let (to_j, to_i) = match self.topology {
                Topology::Open => (i + k == j, j + k == i),
                Topology::Cyclic => ((i + k) % n == j, (j + k) % n == i),
            };
            if to_j {
                v += self.off[i][k - 1];
            }
            if to_i {
                v += self.off[j][k - 1];
            }
        }
        v
    }

    /// y ← y + A x for `ncols` columns stored row by row (x and y are n × ncols, row-major).
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` or `y` does not have n · ncols entries.
    pub fn mul_add(&self, x: &[f64], y: &mut [f64], ncols: usize) -> Result<(), Error> {
        let len = self.len() * ncols;
        check_len("x", x.len(), len)?;
        check_len("y", y.len(), len)?;
        match ncols {
            1 => self.mul_add_cols::<1>(x, y, 1),
            2 => self.mul_add_cols::<2>(x, y, 2),
            3 => self.mul_add_cols::<3>(x, y, 3),
            4 => self.mul_add_cols::<4>(x, y, 4),
            c => self.mul_add_cols::<0>(x, y, c),
        }
        Ok(())
    }

    /// [`mul_add`](SymBand::mul_add) with the column count a compile-time constant (`C` = 0:
    /// `cols` at run time).
    #[inline(always)]
    fn mul_add_cols<const C: usize>(&self, x: &[f64], y: &mut [f64], cols: usize) {
        let nc = if C == 0 { cols } else { C };
        let n = self.len();
        let cyclic = self.topology == Topology::Cyclic;
        for j in 0..n {
            let dj = self.diag[j];
            for c in 0..nc {
                y[j * nc + c] += dj * x[j * nc + c];
            }
            for k in 1..=W {
                let v = self.off[j][k - 1];
                // Zero entries are common (open ends, sparse assembly): skip their two passes.
                if v == 0.0 {
                    continue;
                }
                let l = if j + k < n {
                    j + k
                } else if cyclic {
                    (j + k) % n
                } else {
                    continue;
                };
                for c in 0..nc {
                    y[j * nc + c] += v * x[l * nc + c];
                    y[l * nc + c] += v * x[j * nc + c];
                }
            }
        }
    }

    /// The LDLᵀ factor of A with the default options ([`crate::PIVOT_RTOL`], nothing
    /// eliminated).
    ///
    /// # Errors
    /// [`Error::Singular`] naming the first row whose pivot D_i is not finite or not above
    /// [`crate::PIVOT_RTOL`] · A_ii.
    pub fn factor(&self) -> Result<SymBandFactor<W>, Error> {
        self.factor_with(&FactorOptions::default())
    }

    /// The LDLᵀ factor of A (with the rows in `options.eliminated` replaced by identity rows).
    ///
    /// # Errors
    /// [`Error::Singular`] naming the first row whose pivot D_i is not finite or not above
    /// `options.pivot_rtol` · A_ii; [`Error::WrongLength`] if `options.eliminated` does not
    /// have n entries.
    pub fn factor_with(&self, options: &FactorOptions<'_>) -> Result<SymBandFactor<W>, Error> {
        let mut f = SymBandFactor::default();
        self.factor_into(options, &mut f)?;
        Ok(f)
    }

    /// [`factor_with`](SymBand::factor_with) into an existing factor, reusing its storage
    /// (no allocation once it has held a factor of this size). On error `f` is left empty (of
    /// size 0: its solves report [`Error::WrongLength`]).
    ///
    /// # Errors
    /// As [`factor_with`](SymBand::factor_with).
    pub fn factor_into(
        &self,
        options: &FactorOptions<'_>,
        f: &mut SymBandFactor<W>,
    ) -> Result<(), Error> {
        let n = self.len();
        check_eliminated(options.eliminated, n)?;
        let t = match self.topology {
            Topology::Open => 0,
            Topology::Cyclic => W.min(n),
        };
        let m = n - t;
        f.n = n;
        f.m = m;
        f.rows.clear();
        f.rows.reserve(m);
        f.g.clear();
        f.border = Border::none(m);
        let rtol = options.pivot_rtol;
        let result = match options.eliminated {
            None => self.factor_rows::<false>(&[], m, rtol, &mut f.rows),
            Some(e) => self.factor_rows::<true>(e, m, rtol, &mut f.rows),
        }
        .and_then(|()| {
            if t > 0 {
                self.factor_border(options.eliminated, t, rtol, f)
            } else {
                Ok(())
            }
        });
        if result.is_err() {
            (f.n, f.m) = (0, 0);
            f.rows.clear();
            f.g.clear();
            f.border = Border::default();
        }
        result
    }

    /// The band rows 0..m of the factor. `E`: whether rows are eliminated (`elim`).
    fn factor_rows<const E: bool>(
        &self,
        elim: &[bool],
        m: usize,
        rtol: f64,
        rows: &mut Vec<Row<W>>,
    ) -> Result<(), Error> {
        let fixed = |i: usize| E && elim[i];
        // A_{i,i−k} (i ≥ k) and A_ii after elimination. Band rows never alias (module docs).
        let lower = |i: usize, k: usize| -> f64 {
            if fixed(i) || fixed(i - k) {
                0.0
            } else {
                self.off[i - k][k - 1]
            }
        };
        let diag = |i: usize| if fixed(i) { 1.0 } else { self.diag[i] };
        if W == 1 {
            // Determinant recurrence (module docs).
            const LO: f64 = 7.888609052210118e-31; // 2^-100
            const HI: f64 = 1.2676506002282294e30; // 2^100
            let (mut p2, mut p1) = (0.0f64, 1.0f64);
            let mut inv_prev = 0.0;
            for i in 0..m {
                let b = if i > 0 { lower(i, 1) } else { 0.0 };
                let a = diag(i);
                let p = a * p1 - b * b * p2;
                let inv = p1 / p;
                // D = 1/inv > rtol · a, with inv > 0 (so P_i > 0).
                if !(inv > 0.0 && inv.is_finite() && rtol * a * inv < 1.0) {
                    return Err(Error::Singular { index: i });
                }
                let mut l = [0.0; W];
                l[0] = b * inv_prev;
                rows.push(Row { l, inv });
                inv_prev = inv;
                (p2, p1) = (p1, p);
                if !(LO..=HI).contains(&p1) {
                    // P_i > 0: scale both by 2^(−exponent of P_i), exactly.
                    let e = ((p1.to_bits() >> 52) & 0x7ff) as i64 - 1023;
                    let s = f64::from_bits(((1023 - e) as u64) << 52);
                    (p2, p1) = (p2 * s, p1 * s);
                }
            }
            return Ok(());
        }
        // win[q]: row i − 1 − q of the factor.
        let mut win = [Row::<W>::ZERO; W];
        for i in 0..m {
            let mut u = [0.0; W];
            let mut l = [0.0; W];
            for k in (1..=W).rev() {
                if k > i {
                    continue;
                }
                let rj = &win[k - 1];
                let mut t = lower(i, k);
                for kk in k + 1..=W {
                    // q = i − kk; L_{jq} = row j's entry at distance kk − k.
                    t -= u[kk - 1] * rj.l[kk - k - 1];
                }
                u[k - 1] = t;
                l[k - 1] = t * rj.inv;
            }
            let a = diag(i);
            let mut p = a;
            for k in 0..W {
                p -= u[k] * l[k];
            }
            if !(p.is_finite() && p > rtol * a) {
                return Err(Error::Singular { index: i });
            }
            let row = Row { l, inv: 1.0 / p };
            rows.push(row);
            for q in (1..W).rev() {
                win[q] = win[q - 1];
            }
            win[0] = row;
        }
        Ok(())
    }

    /// The border rows m..n of a cyclic factor (module docs of `border.rs`).
    fn factor_border(
        &self,
        elim: Option<&[bool]>,
        t: usize,
        rtol: f64,
        f: &mut SymBandFactor<W>,
    ) -> Result<(), Error> {
        let m = f.m;
        let fixed = |i: usize| elim.is_some_and(|e| e[i]);
        let entry = |i: usize, j: usize| -> f64 {
            if fixed(i) || fixed(j) {
                if i == j {
                    1.0
                } else {
                    0.0
                }
            } else {
                self.entry(i, j)
            }
        };
        // uw[q][r] = u_{m+r, j−1−q} = L_{m+r, j−1−q} D_{j−1−q} (the undivided border entries).
        let mut uw = [[0.0f64; W]; W];
        // acc[r][s] = Σ_j u_{m+r, j} L_{m+s, j}: the update of the Schur complement.
        let mut acc = [[0.0f64; W]; W];
        let mut scale = [0.0f64; W];
        let tail0 = m.saturating_sub(W);
        let mut border = Border { head: m, tail: m };
        let mut j = 0;
        while j < m {
            if border.head == m && j >= W && j < tail0 && uw.iter().flatten().all(|&v| v == 0.0) {
                // The head has decayed to zero: rows up to m − W have no border (border.rs).
                border = Border {
                    head: j,
                    tail: tail0,
                };
                j = tail0;
                continue;
            }
            let row = f.rows[j];
            let mut g = [0.0; W];
            let mut u = [0.0; W];
            // Only rows j < W and j ≥ m − W couple to the border in A.
            let direct = j < W || j >= tail0;
            for r in 0..t {
                let mut s = if direct { entry(m + r, j) } else { 0.0 };
                for k in (1..=W).rev() {
                    s -= uw[k - 1][r] * row.l[k - 1];
                }
                let gv = s * row.inv;
                // Squared Cholesky-scaled magnitude |L̂|² = L² D = u² / D (no square root).
                let mag2 = s * s * row.inv;
                if mag2 < BORDER_FLUSH_RTOL * BORDER_FLUSH_RTOL * scale[r] {
                    continue;
                }
                scale[r] = scale[r].max(mag2);
                g[r] = gv;
                u[r] = s;
            }
            for r in 0..t {
                for s in 0..=r {
                    acc[r][s] += u[r] * g[s];
                }
            }
            f.g.push(g);
            for q in (1..W).rev() {
                uw[q] = uw[q - 1];
            }
            uw[0] = u;
            j += 1;
        }
        f.border = border;
        // LDLᵀ of the t×t Schur complement A₂₂ − Σ u Lᵀ, in the u-form of the band rows.
        let mut tu = [[0.0f64; W]; W];
        for r in 0..t {
            for s in 0..r {
                let mut v = entry(m + r, m + s) - acc[r][s];
                for q in 0..s {
                    v -= tu[r][q] * f.tail_l[s][q];
                }
                tu[r][s] = v;
                f.tail_l[r][s] = v * f.tail_inv[s];
            }
            let a = entry(m + r, m + r);
            let mut p = a - acc[r][r];
            for q in 0..r {
                p -= tu[r][q] * f.tail_l[r][q];
            }
            if !(p.is_finite() && p > rtol * a) {
                return Err(Error::Singular { index: m + r });
            }
            f.tail_inv[r] = 1.0 / p;
        }
        Ok(())
    }
}

impl<const W: usize> SymBandFactor<W> {
    /// The size n of the factored matrix.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether n = 0.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The pivots D_i (for tests and diagnostics; O(n)).
    pub fn pivots(&self) -> Vec<f64> {
        let t = self.n - self.m;
        self.rows
            .iter()
            .map(|r| 1.0 / r.inv)
            .chain(self.tail_inv[..t].iter().map(|v| 1.0 / v))
            .collect()
    }

    /// Solves A X = B in place for the `ncols` columns of X, stored row by row (n × ncols,
    /// row-major: entry (i, c) at `x[i * ncols + c]`; B on entry). Allocates nothing. Rows
    /// eliminated at factorization are identity rows: there x = b.
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` does not have n · ncols entries.
    pub fn solve_in_place(&self, x: &mut [f64], ncols: usize) -> Result<(), Error> {
        check_len("x", x.len(), self.n * ncols)?;
        match ncols {
            0 => {}
            1 => self.kernel::<1>(x, 1, 0),
            2 => self.kernel::<2>(x, 2, 0),
            3 => self.kernel::<3>(x, 3, 0),
            4 => self.kernel::<4>(x, 4, 0),
            _ => {
                for c in 0..ncols {
                    self.kernel::<1>(x, ncols, c);
                }
            }
        }
        Ok(())
    }

    /// Solves for the `C` columns c0..c0 + C of the row-major x with row stride `stride`.
    #[inline(always)]
    fn kernel<const C: usize>(&self, x: &mut [f64], stride: usize, c0: usize) {
        let (n, m) = (self.n, self.m);
        let t = n - m;
        let b = self.border;
        // Forward: z_i = b_i − Σ_k L_{i,i−k} z_{i−k}; border sums s_r = Σ_j L_{m+r,j} z_j.
        let mut zw = [[0.0f64; C]; W];
        let mut s = [[0.0f64; C]; W];
        self.forward::<C, true>(x, stride, c0, 0..b.head, 0, &mut zw, &mut s);
        self.forward::<C, false>(x, stride, c0, b.head..b.tail, 0, &mut zw, &mut s);
        self.forward::<C, true>(x, stride, c0, b.tail..m, b.tail_slot(), &mut zw, &mut s);
        // The t×t tail: forward, diagonal, backward.
        let mut xr = [[0.0f64; C]; W];
        if t > 0 {
            let mut zt = [[0.0f64; C]; W];
            for r in 0..t {
                let o = (m + r) * stride + c0;
                for c in 0..C {
                    let mut v = x[o + c] - s[r][c];
                    for q in 0..r {
                        v -= self.tail_l[r][q] * zt[q][c];
                    }
                    zt[r][c] = v;
                }
            }
            for r in (0..t).rev() {
                let o = (m + r) * stride + c0;
                for c in 0..C {
                    let mut v = zt[r][c] * self.tail_inv[r];
                    for q in r + 1..t {
                        v -= self.tail_l[q][r] * xr[q][c];
                    }
                    xr[r][c] = v;
                    x[o + c] = v;
                }
            }
        }
        // Backward: x_j = z_j / D_j − Σ_k L_{j+k,j} x_{j+k} − Σ_r L_{m+r,j} x_{m+r}.
        let mut xw = [[0.0f64; C]; W];
        self.backward::<C, true>(x, stride, c0, b.tail..m, b.tail_slot(), &xr, &mut xw);
        self.backward::<C, false>(x, stride, c0, b.head..b.tail, 0, &xr, &mut xw);
        self.backward::<C, true>(x, stride, c0, 0..b.head, 0, &xr, &mut xw);
    }

    /// Forward substitution over the band rows `range` (`B`: with border sums, the border of
    /// row `range.start` at slot `slot0`). `zw[q]` holds z of row i − 1 − q.
    ///
    /// With several columns the window of the W previous values stays in registers, one
    /// vector per row across the columns. With one column only the newest value does, and the
    /// older ones are read back from `x`, where they were stored rows ago, under a branch: a
    /// window of scalars, or a select, lets the compiler pack the W products of a row into one
    /// vector multiply, which puts shuffles and general-register moves instead of a multiply
    /// and a subtraction on each row's dependency chain (measured, W = 2, n = 10⁵: one column
    /// 6.7 ns/row that way, 5.1 this way, 5.3 for energy's former copy).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn forward<const C: usize, const B: bool>(
        &self,
        x: &mut [f64],
        stride: usize,
        c0: usize,
        range: std::ops::Range<usize>,
        slot0: usize,
        window: &mut [[f64; C]; W],
        s: &mut [[f64; C]; W],
    ) {
        let start = range.start;
        // Local copies: the loop's running values then live in registers, not behind `&mut`.
        let (mut zw, mut sums) = (*window, *s);
        for i in range {
            let row = &self.rows[i];
            let o = i * stride + c0;
            let mut z = [0.0; C];
            for c in 0..C {
                // The older terms first, off the critical path; z_{i−1} enters last.
                let mut v = x[o + c];
                for k in (2..=W).rev() {
                    // A branch, not a select: with a select the compiler packs this product
                    // with the newest one below into one vector multiply (see above).
                    if i >= k {
                        let zk = if C > 1 {
                            zw[k - 1][c]
                        } else {
                            x[(i - k) * stride + c0 + c]
                        };
                        v -= row.l[k - 1] * zk;
                    }
                }
                z[c] = v - row.l[0] * zw[0][c];
            }
            x[o..o + C].copy_from_slice(&z);
            if B {
                let g = &self.g[slot0 + (i - start)];
                for r in 0..W {
                    for c in 0..C {
                        sums[r][c] += g[r] * z[c];
                    }
                }
            }
            if C > 1 {
                for q in (1..W).rev() {
                    zw[q] = zw[q - 1];
                }
            }
            zw[0] = z;
        }
        (*window, *s) = (zw, sums);
    }

    /// Backward substitution over the band rows `range`, last row first (`B`: with the border
    /// terms, the border of row `range.start` at slot `slot0`; `xr` the border rows' solution).
    /// `xw[q]` holds x of row j + 1 + q (with one column only `xw[0]`; see
    /// [`forward`](SymBandFactor::forward)).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn backward<const C: usize, const B: bool>(
        &self,
        x: &mut [f64],
        stride: usize,
        c0: usize,
        range: std::ops::Range<usize>,
        slot0: usize,
        xr: &[[f64; C]; W],
        window: &mut [[f64; C]; W],
    ) {
        let m = self.m;
        let start = range.start;
        let mut xw = *window;
        for j in range.rev() {
            let row = &self.rows[j];
            let o = j * stride + c0;
            // L_{j+1,j} (0 past the band rows, where the window is 0 too).
            let l1 = if j + 1 < m {
                self.rows[j + 1].l[0]
            } else {
                0.0
            };
            let mut v = [0.0; C];
            for c in 0..C {
                let mut val = x[o + c] * row.inv;
                if B {
                    let g = &self.g[slot0 + (j - start)];
                    for r in 0..W {
                        val -= g[r] * xr[r][c];
                    }
                }
                for k in (2..=W).rev() {
                    if j + k < m {
                        let xk = if C > 1 {
                            xw[k - 1][c]
                        } else {
                            x[(j + k) * stride + c0 + c]
                        };
                        val -= self.rows[j + k].l[k - 1] * xk;
                    }
                }
                v[c] = val - l1 * xw[0][c];
            }
            x[o..o + C].copy_from_slice(&v);
            if C > 1 {
                for q in (1..W).rev() {
                    xw[q] = xw[q - 1];
                }
            }
            xw[0] = v;
        }
        *window = xw;
    }
}

/// The forward distance k ∈ 1..=w from i to j (j = i + k, mod n when cyclic), if any.
#[inline]
pub(crate) fn forward_distance(
    topology: Topology,
    n: usize,
    w: usize,
    i: usize,
    j: usize,
) -> Option<usize> {
    // No `%`: both indices are below n (a division would dominate assembly loops).
    let k = match topology {
        Topology::Open if j > i => j - i,
        Topology::Open => return None,
        Topology::Cyclic if j >= i => j - i,
        Topology::Cyclic => j + n - i,
    };
    (k >= 1 && k <= w).then_some(k)
}

pub(crate) fn check_index(i: usize, j: usize, n: usize) -> Result<(), Error> {
    for (field, index) in [("row", i), ("col", j)] {
        if index >= n {
            return Err(Error::IndexOutOfRange {
                field,
                index,
                len: n,
            });
        }
    }
    Ok(())
}

pub(crate) fn check_len(field: &'static str, got: usize, expected: usize) -> Result<(), Error> {
    if got == expected {
        Ok(())
    } else {
        Err(Error::WrongLength {
            field,
            expected,
            got,
        })
    }
}

#[cfg(test)]
impl<const W: usize> SymBandFactor<W> {
    /// The factors as dense matrices: L (unit lower triangular) and the pivots D.
    pub(crate) fn dense_factors(&self) -> (nalgebra::DMatrix<f64>, Vec<f64>) {
        let (n, m) = (self.n, self.m);
        let t = n - m;
        let mut l = nalgebra::DMatrix::<f64>::identity(n, n);
        for (i, row) in self.rows.iter().enumerate() {
            for k in 1..=W.min(i) {
                l[(i, i - k)] = row.l[k - 1];
            }
        }
        if t > 0 {
            let b = self.border;
            let stored = (0..b.head).chain(b.tail..m);
            for (slot, j) in stored.enumerate() {
                for r in 0..t {
                    l[(m + r, j)] = self.g[slot][r];
                }
            }
            for r in 0..t {
                for s in 0..r {
                    l[(m + r, m + s)] = self.tail_l[r][s];
                }
            }
        }
        (l, self.pivots())
    }

    /// The stored border rows (head, tail) of a cyclic factor.
    pub(crate) fn border_rows(&self) -> (usize, usize) {
        (self.border.head, self.border.tail)
    }
}
