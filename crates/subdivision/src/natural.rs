//! Natural cubic splines by variational subdivision on [0, L] (Warren–Weimer ch. 6, §6.2–6.3;
//! math.md §5).
//!
//! On the grid 2^{−k} Z ∩ [0, L] the discrete energy is p_kᵀ E_k p_k with E_k = 8^k D₂ᵀD₂
//! (D₂ the second-difference matrix). The subdivision matrices S_k are *solved* from the
//! two-scale relation E_{k+1} S_k = U_k E_k (Theorem 6.3). That relation fixes each column of
//! S_k only up to the kernel of E_{k+1} (constant and linear sequences, two numbers per
//! column); as in the book, the ambiguity is removed by asking the scheme to interpolate at the
//! ends of [0, L] (first and last rows of S_k unit vectors) — exactly two conditions per column,
//! so the solution is unique. Everything else (the (½, ½) and (⅛, ¾, ⅛) interior rows, the
//! banded structure, the relation holding also in the two rows not used to solve) is a
//! consequence, checked by the tests and by `cargo xtask verify`.

use divdiff::Points;
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};

use crate::matrix::{solve, RationalMatrix};
use crate::rational::rational_to_f64;
use crate::Error;

/// Largest number of grid intervals 2^k L of the exact (rational) matrices
/// ([`natural_subdivision_matrix`] etc.): they are dense, for derivation and checks only.
pub const MAX_EXACT_INTERVALS: usize = 512;

/// Largest number of output coordinates (points × dimension) [`NaturalScheme::subdivide_levels`] may
/// produce.
pub const MAX_NATURAL_COORDS: usize = 1 << 30;

/// Number of grid intervals 2^level · L, validated against [`MAX_EXACT_INTERVALS`].
fn exact_intervals(intervals: usize, level: usize) -> Result<usize, Error> {
    if intervals == 0 {
        return Err(Error::TooFew {
            field: "intervals",
            minimum: 1,
            got: 0,
        });
    }
    let n = u32::try_from(level)
        .ok()
        .and_then(|l| 1usize.checked_shl(l))
        .and_then(|f| f.checked_mul(intervals))
        .unwrap_or(usize::MAX);
    if n > MAX_EXACT_INTERVALS {
        return Err(Error::TooLarge {
            field: "level",
            limit: MAX_EXACT_INTERVALS,
            got: n,
        });
    }
    Ok(n)
}

/// The inner-product matrix E_level = 8^level D₂ᵀD₂ on the grid 2^{−level} Z ∩ [0, L]
/// (`intervals` = L), of size (2^level L + 1)²: interior rows 8^level (1, −4, 6, −4, 1), boundary
/// rows 8^level (1, −2, 1) and 8^level (−2, 5, −4, 1) (Warren–Weimer §6.2.2).
///
/// # Errors
/// [`Error::TooFew`] (`intervals`) for L = 0, [`Error::TooLarge`] (`level`) if 2^level L
/// exceeds [`MAX_EXACT_INTERVALS`].
pub fn natural_inner_product_matrix(
    intervals: usize,
    level: usize,
) -> Result<RationalMatrix, Error> {
    let n = exact_intervals(intervals, level)? + 1;
    let scale = BigRational::from_integer(BigInt::from(8).pow(level as u32));
    let mut e = RationalMatrix::zeros(n, n);
    let d2 = [1i64, -2, 1];
    for r in 0..n.saturating_sub(2) {
        for (a, &ca) in d2.iter().enumerate() {
            for (b, &cb) in d2.iter().enumerate() {
                let v = e.get(r + a, r + b) + BigRational::from_integer(BigInt::from(ca * cb));
                e.set(r + a, r + b, v);
            }
        }
    }
    for i in 0..n {
        for j in 0..n {
            let v = e.get(i, j) * &scale;
            e.set(i, j, v);
        }
    }
    Ok(e)
}

/// The upsampling matrix U_level from the grid 2^{−level} Z ∩ [0, L] to 2^{−level−1} Z ∩ [0, L]:
/// entry (i, j) is 1 if i = 2j and 0 otherwise.
///
/// # Errors
/// As [`natural_inner_product_matrix`] for the finer grid.
pub fn upsampling_matrix(intervals: usize, level: usize) -> Result<RationalMatrix, Error> {
    let fine = exact_intervals(intervals, level + 1)? + 1;
    let coarse = fine / 2 + 1;
    let mut u = RationalMatrix::zeros(fine, coarse);
    for j in 0..coarse {
        u.set(2 * j, j, BigRational::one());
    }
    Ok(u)
}

/// The subdivision matrix S_level (grid 2^{−level} Z to 2^{−level−1} Z on [0, L]) solved exactly
/// from the two-scale relation E_{level+1} S_level = U_level E_level (Theorem 6.3), with the
/// kernel of E_{level+1} pinned by interpolating ends (first row e_0, last row e_last).
///
/// The system for the interior rows is E_{level+1} without its first and last rows and columns:
/// symmetric positive definite (a sequence that is linear and vanishes at both ends is zero)
/// and pentadiagonal, so it is solved by banded elimination without pivoting.
///
/// ```
/// use subdivision::{natural_subdivision_matrix, BigRational};
/// let s = natural_subdivision_matrix(4, 0)?; // [0, 4]: 9 × 5
/// let eighth = BigRational::new(1.into(), 8.into());
/// assert_eq!(s.get(4, 1), &eighth); // row 2j: (1/8, 3/4, 1/8) around column j
/// assert_eq!(s.get(0, 0), &BigRational::from_integer(1.into()));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`natural_inner_product_matrix`] for the finer grid; [`Error::Singular`]
/// cannot occur for these matrices but is reported rather than panicking.
pub fn natural_subdivision_matrix(intervals: usize, level: usize) -> Result<RationalMatrix, Error> {
    let ef = natural_inner_product_matrix(intervals, level + 1)?;
    let ec = natural_inner_product_matrix(intervals, level)?;
    let u = upsampling_matrix(intervals, level)?;
    let rhs = u.mul(&ec).ok_or(Error::Singular { index: 0 })?;
    let (nf, nc) = (ef.rows(), ec.rows());
    let mut s = RationalMatrix::zeros(nf, nc);
    s.set(0, 0, BigRational::one());
    s.set(nf - 1, nc - 1, BigRational::one());
    // Interior unknowns x_1..x_{nf−2} for every column at once: A x = B with A the interior
    // block of E_f and B = (U E_c) minus the contribution of the fixed end values.
    let m = nf - 2;
    let mut a = RationalMatrix::zeros(m, m);
    let mut b = RationalMatrix::zeros(m, nc);
    for r in 0..m {
        for c in r.saturating_sub(2)..(r + 3).min(m) {
            a.set(r, c, ef.get(r + 1, c + 1).clone());
        }
        for j in 0..nc {
            let v = rhs.get(r + 1, j)
                - ef.get(r + 1, 0) * s.get(0, j)
                - ef.get(r + 1, nf - 1) * s.get(nf - 1, j);
            b.set(r, j, v);
        }
    }
    // Banded elimination (half-bandwidth 2); no fill-in outside the band without pivoting.
    for k in 0..m {
        if a.get(k, k).is_zero() {
            return Err(Error::Singular { index: k });
        }
        for r in k + 1..(k + 3).min(m) {
            let f = a.get(r, k) / a.get(k, k);
            if f.is_zero() {
                continue;
            }
            for c in k..(k + 3).min(m) {
                let v = a.get(r, c) - &f * a.get(k, c);
                a.set(r, c, v);
            }
            for j in 0..nc {
                let bk = b.get(k, j);
                if !bk.is_zero() {
                    let v = b.get(r, j) - &f * bk;
                    b.set(r, j, v);
                }
            }
        }
    }
    for k in (0..m).rev() {
        for j in 0..nc {
            let mut v = b.get(k, j).clone();
            for c in k + 1..(k + 3).min(m) {
                v -= a.get(k, c) * s.get(c + 1, j);
            }
            s.set(k + 1, j, v / a.get(k, k));
        }
    }
    Ok(s)
}

/// The interpolation matrix N_level on the grid 2^{−level} Z ∩ [0, L]: the limit function of
/// subdivision from p takes the values N p on the grid (Warren–Weimer §6.3.1).
///
/// Computed from the recurrence N_level = U_levelᵀ N_{level+1} S_level under the book's ansatz
/// that N is tridiagonal and stationary: row j of N, supported on columns j−1..j+1, equals row
/// 2j of N_{level+1} on the fine columns 2j−1..2j+1, so it is the left eigenvector ν = ν A_j
/// (normalized to sum 1, "rows sum to one") of the block A_j of S_level with rows 2j−1..2j+1 and
/// columns j−1..j+1. The tests check that the resulting matrices satisfy the full recurrence.
///
/// # Errors
/// As [`natural_subdivision_matrix`]; [`Error::Singular`] (with the row j) if some
/// A_j had no unique normalized fixed point.
pub fn natural_interpolation_matrix(
    intervals: usize,
    level: usize,
) -> Result<RationalMatrix, Error> {
    let s = natural_subdivision_matrix(intervals, level)?;
    let nc = s.cols();
    let mut n = RationalMatrix::zeros(nc, nc);
    for j in 0..nc {
        let cols: Vec<usize> = (j.saturating_sub(1)..=(j + 1).min(nc - 1)).collect();
        let rows: Vec<usize> =
            ((2 * j).saturating_sub(1)..=(2 * j + 1).min(s.rows() - 1)).collect();
        let k = cols.len();
        if rows.len() != k {
            return Err(Error::Singular { index: j });
        }
        // (A_jᵀ − I) νᵀ = 0 has rank k − 1; replace one equation by Σ ν = 1, trying each
        // equation in turn, and accept a solution only if it satisfies all k equations.
        let mut found = None;
        for drop in 0..k {
            let mut m = RationalMatrix::zeros(k, k);
            let mut rhs = vec![BigRational::zero(); k];
            for (e, &col) in cols.iter().enumerate() {
                for (c, &r) in rows.iter().enumerate() {
                    let mut v = s.get(r, col).clone();
                    if c == e {
                        v -= BigRational::one();
                    }
                    m.set(e, c, v);
                }
            }
            for c in 0..k {
                m.set(drop, c, BigRational::one());
            }
            rhs[drop] = BigRational::one();
            if let Some(nu) = solve(m, rhs) {
                let fixed = (0..k).all(|e| {
                    let v: BigRational = rows
                        .iter()
                        .enumerate()
                        .map(|(c, &r)| &nu[c] * s.get(r, cols[e]))
                        .sum();
                    v == nu[e]
                });
                if fixed {
                    found = Some(nu);
                    break;
                }
            }
        }
        let nu = found.ok_or(Error::Singular { index: j })?;
        for (c, v) in cols.iter().zip(nu) {
            n.set(j, *c, v);
        }
    }
    Ok(n)
}

/// One sparse matrix row: (column, exact weight, correctly rounded weight) for each nonzero.
pub type SparseRow = Vec<(usize, BigRational, f64)>;

type Row = SparseRow;

/// A family of matrices M(L) with ρL + 1 rows and L + 1 columns whose rows are local stencils,
/// identical (up to a shift) away from the ends. Built from one exactly derived member M(L_T)
/// and extended to any L > L_T by copying its end rows and shifting its middle rows; for
/// L ≤ L_T the member is derived exactly. The tests check the extension against exactly derived
/// matrices for many L.
#[derive(Clone, Debug)]
struct Template {
    rho: usize,
    lt: usize,
    rows: Vec<Row>,
    /// `rows` without the exact weights, for application.
    frows: Vec<Vec<(usize, f64)>>,
    derive: fn(usize) -> Result<RationalMatrix, Error>,
}

/// The rows of one member M(L) in `f64`, without materializing them for large L.
struct FloatRows<'a> {
    template: &'a Template,
    l: usize,
    /// The exactly derived rows when L ≤ L_T (empty otherwise).
    small: Vec<Vec<(usize, f64)>>,
}

impl FloatRows<'_> {
    fn count(&self) -> usize {
        self.template.rho * self.l + 1
    }

    /// Row r as (entries, shift): the entry (c, w) sits in column c + shift (the shift is
    /// negative for the first interior rows, which sit left of the template's middle row).
    fn row(&self, r: usize) -> (&[(usize, f64)], isize) {
        let t = self.template;
        if !self.small.is_empty() {
            return (&self.small[r], 0);
        }
        let (rho, b, l) = (t.rho, TEMPLATE_END, self.l);
        let shift = l - t.lt;
        let mid = t.lt / 2;
        if r < rho * b {
            (&t.frows[r], 0)
        } else if r > rho * (l - b) {
            (&t.frows[r - rho * shift], shift as isize)
        } else {
            // Interior: the template's middle row of this phase, moved from column mid to j.
            let (j, phase) = (r / rho, r % rho);
            (&t.frows[rho * mid + phase], j as isize - mid as isize)
        }
    }

    /// out = M(L) p, vertex-major, `dim` coordinates per point (`out` is resized; its
    /// allocation is reused).
    fn apply_into(&self, p: &[f64], dim: usize, out: &mut Vec<f64>) {
        out.resize(self.count() * dim, 0.0);
        match dim {
            1 => self.apply_dim::<1>(p, 1, out),
            2 => self.apply_dim::<2>(p, 2, out),
            3 => self.apply_dim::<3>(p, 3, out),
            _ => self.apply_dim::<0>(p, dim, out),
        }
    }

    /// `D` = dim as a constant (0: run-time dimension). End rows come from `row`; the interior
    /// rows (all of them shifts of the template's middle rows) run in a tight loop over the
    /// coarse index with the stencils hoisted, so the pass streams through memory.
    fn apply_dim<const D: usize>(&self, p: &[f64], dim: usize, out: &mut [f64]) {
        let t = self.template;
        let rho = t.rho;
        let (lo, hi) = if self.small.is_empty() {
            // Interior rows r = rho·j + phase for j in TEMPLATE_END..=l − TEMPLATE_END, phase <
            // rho, except the last j's phases beyond rho·(l − TEMPLATE_END) (end rows).
            (rho * TEMPLATE_END, rho * (self.l - TEMPLATE_END) + 1)
        } else {
            (0, 0)
        };
        let row_into = |r: usize, dst: &mut [f64]| {
            let (entries, shift) = self.row(r);
            combine::<D>(dim, entries, shift, p, dst);
        };
        for (r, dst) in out.chunks_exact_mut(dim).enumerate() {
            if r < lo || r >= hi {
                row_into(r, dst);
            }
        }
        if lo < hi {
            let mid = t.lt / 2;
            let stencils: Vec<&[(usize, f64)]> = (0..rho)
                .map(|phase| t.frows[rho * mid + phase].as_slice())
                .collect();
            for (k, dst) in out[lo * dim..hi * dim].chunks_exact_mut(dim).enumerate() {
                let r = lo + k;
                let (j, phase) = (r / rho, r % rho);
                combine::<D>(dim, stencils[phase], j as isize - mid as isize, p, dst);
            }
        }
    }
}

/// dst = Σ w · p[c + shift] over the (column, weight) entries.
#[inline(always)]
fn combine<const D: usize>(
    dim: usize,
    entries: &[(usize, f64)],
    shift: isize,
    p: &[f64],
    dst: &mut [f64],
) {
    if D > 0 {
        let mut acc = [0.0f64; D];
        for &(c, w) in entries {
            let col = (c as isize + shift) as usize;
            let src = &p[col * D..(col + 1) * D];
            for k in 0..D {
                acc[k] += w * src[k];
            }
        }
        dst.copy_from_slice(&acc);
    } else {
        dst.fill(0.0);
        for &(c, w) in entries {
            let col = (c as isize + shift) as usize;
            let src = &p[col * dim..(col + 1) * dim];
            for (d, &v) in dst.iter_mut().zip(src) {
                *d += w * v;
            }
        }
    }
}

/// Coarse intervals at each end taken verbatim from the template.
const TEMPLATE_END: usize = 3;
/// L_T: the template size, large enough for a middle row free of end effects.
const TEMPLATE_INTERVALS: usize = 8;

fn sparse_rows(m: &RationalMatrix) -> Vec<Row> {
    (0..m.rows())
        .map(|i| {
            m.row_nonzeros(i)
                .into_iter()
                .map(|(j, v)| {
                    let f = rational_to_f64(&v);
                    (j, v, f)
                })
                .collect()
        })
        .collect()
}

fn float_rows(rows: &[Row]) -> Vec<Vec<(usize, f64)>> {
    rows.iter()
        .map(|r| r.iter().map(|(c, _, f)| (*c, *f)).collect())
        .collect()
}

impl Template {
    fn new(rho: usize, derive: fn(usize) -> Result<RationalMatrix, Error>) -> Result<Self, Error> {
        let lt = TEMPLATE_INTERVALS;
        Ok(Template {
            rho,
            lt,
            rows: sparse_rows(&derive(lt)?),
            frows: Vec::new(),
            derive,
        }
        .with_floats())
    }

    fn with_floats(mut self) -> Self {
        self.frows = float_rows(&self.rows);
        self
    }

    fn float_rows_for(&self, l: usize) -> Result<FloatRows<'_>, Error> {
        let small = if l <= self.lt {
            float_rows(&sparse_rows(&(self.derive)(l)?))
        } else {
            Vec::new()
        };
        Ok(FloatRows {
            template: self,
            l,
            small,
        })
    }

    fn rows_for(&self, l: usize) -> Result<Vec<Row>, Error> {
        if l <= self.lt {
            return Ok(sparse_rows(&(self.derive)(l)?));
        }
        let (rho, b, lt) = (self.rho, TEMPLATE_END, self.lt);
        let shift = l - lt;
        let mid = lt / 2;
        Ok((0..=rho * l)
            .map(|r| {
                if r < rho * b {
                    self.rows[r].clone()
                } else if r > rho * (l - b) {
                    self.rows[r - rho * shift]
                        .iter()
                        .map(|(c, v, f)| (c + shift, v.clone(), *f))
                        .collect()
                } else {
                    let (j, phase) = (r / rho, r % rho);
                    self.rows[rho * mid + phase]
                        .iter()
                        .map(|(c, v, f)| (c + j - mid, v.clone(), *f))
                        .collect()
                }
            })
            .collect())
    }
}

/// Natural cubic spline subdivision on [0, L] with points at the integers, applied to points in
/// R^d coordinate by coordinate (parametric use, Warren–Weimer Fig. 6.6–6.7).
///
/// The rules are the exactly derived [`natural_subdivision_matrix`] and
/// [`natural_interpolation_matrix`], rounded to `f64` (they are dyadic or sixths: end rows unit
/// vectors, interior (½, ½), (⅛, ¾, ⅛) and (⅙, ⅔, ⅙)), applied as sparse rows in O(N).
///
/// ```
/// use divdiff::Points;
/// use subdivision::NaturalScheme;
/// let scheme = NaturalScheme::new()?;
/// let p0 = Points::from_rows(&[[0.0], [1.0], [0.0], [1.0], [0.0]])?;
/// let levels = scheme.subdivide_levels(&p0, 3)?;
/// let energies: Vec<f64> = (0..=3).map(|k| NaturalScheme::energy(&levels[k], k)).collect();
/// let exact = scheme.limit_energy(&p0)?; // p0ᵀ E0 N0 p0, Theorem 6.4
/// assert!(energies.windows(2).all(|w| w[1] < w[0]) && energies[3] > exact);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct NaturalScheme {
    subdivision: Template,
    interpolation: Template,
}

fn derive_s(l: usize) -> Result<RationalMatrix, Error> {
    natural_subdivision_matrix(l, 0)
}

fn derive_n(l: usize) -> Result<RationalMatrix, Error> {
    natural_interpolation_matrix(l, 0)
}

fn check_points(points: &Points) -> Result<usize, Error> {
    if points.len() < 2 {
        return Err(Error::TooFew {
            field: "points",
            minimum: 2,
            got: points.len(),
        });
    }
    Ok(points.len() - 1)
}

impl NaturalScheme {
    /// Derives the rules (exactly, from the two-scale relation; see the module docs).
    ///
    /// # Errors
    /// [`Error::Singular`] — does not occur for these matrices.
    pub fn new() -> Result<Self, Error> {
        Ok(NaturalScheme {
            subdivision: Template::new(2, derive_s)?,
            interpolation: Template::new(1, derive_n)?,
        })
    }

    /// The subdivision matrix for L intervals as sparse rows (column, exact weight, `f64`).
    ///
    /// # Errors
    /// [`Error::TooFew`] (`intervals`) for L = 0.
    pub fn subdivision_rows(&self, intervals: usize) -> Result<Vec<SparseRow>, Error> {
        self.subdivision.rows_for(intervals)
    }

    /// The interpolation matrix N for L intervals as sparse rows.
    ///
    /// # Errors
    /// [`Error::TooFew`] (`intervals`) for L = 0.
    pub fn interpolation_rows(&self, intervals: usize) -> Result<Vec<SparseRow>, Error> {
        self.interpolation.rows_for(intervals)
    }

    /// One level: p_{k+1} = S_k p_k, for the points of level k on [0, L] (any level: S_k on
    /// [0, L] is S_0 on [0, 2^k L]).
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 points.
    pub fn subdivide_once(&self, points: &Points) -> Result<Points, Error> {
        let mut out = Vec::new();
        self.subdivide_once_into(points, &mut out)?;
        Points::new(points.dim(), out).map_err(Error::from_output)
    }

    /// One level into a caller-owned buffer (resized as needed; repeated calls of the same size
    /// do not allocate): `out` receives S_k p_k, vertex-major, dimension `points.dim()`.
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 points.
    pub fn subdivide_once_into(&self, points: &Points, out: &mut Vec<f64>) -> Result<(), Error> {
        let l = check_points(points)?;
        let rows = self.subdivision.float_rows_for(l)?;
        rows.apply_into(points.coords(), points.dim(), out);
        Ok(())
    }

    /// The polygons p_0, p_1, …, p_levels of `levels` rounds of subdivision from p_0 = `points`.
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 points, [`Error::TooLarge`] (`levels`) if
    /// the levels together would exceed [`MAX_NATURAL_COORDS`] coordinates.
    pub fn subdivide_levels(&self, points: &Points, levels: usize) -> Result<Vec<Points>, Error> {
        let l = check_points(points)?;
        // Σ_k (2^k L + 1) d, saturating, stopping as soon as it exceeds the limit.
        let mut total = 0usize;
        for k in 0..=levels {
            let n = u32::try_from(k)
                .ok()
                .and_then(|k| 1usize.checked_shl(k))
                .and_then(|f| f.checked_mul(l)?.checked_add(1)?.checked_mul(points.dim()))
                .unwrap_or(usize::MAX);
            total = total.saturating_add(n);
            if total > MAX_NATURAL_COORDS {
                return Err(Error::TooLarge {
                    field: "levels",
                    limit: MAX_NATURAL_COORDS,
                    got: total,
                });
            }
        }
        let mut out = Vec::with_capacity(levels + 1);
        out.push(points.clone());
        for k in 0..levels {
            let next = self.subdivide_once(&out[k])?;
            out.push(next);
        }
        Ok(out)
    }

    /// The discrete energy p_kᵀ E_k p_k = 8^k Σ_i |p_i − 2p_{i+1} + p_{i+2}|² of the level-k
    /// polygon, summed over coordinates (E_k = 8^k D₂ᵀD₂, banded evaluation).
    pub fn energy(points: &Points, level: usize) -> f64 {
        let scale = 8f64.powi(level.min(i32::MAX as usize) as i32);
        let dim = points.dim();
        let c = points.coords();
        let mut sum = 0.0;
        for i in 0..points.len().saturating_sub(2) {
            for d in 0..dim {
                let v = c[i * dim + d] - 2.0 * c[(i + 1) * dim + d] + c[(i + 2) * dim + d];
                sum += v * v;
            }
        }
        scale * sum
    }

    /// The values N p on the integers 0..L of the limit curve of p (the limit interpolates
    /// these points).
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 points.
    pub fn limit_values(&self, points: &Points) -> Result<Points, Error> {
        let l = check_points(points)?;
        let rows = self.interpolation.float_rows_for(l)?;
        let mut out = Vec::new();
        rows.apply_into(points.coords(), points.dim(), &mut out);
        Points::new(points.dim(), out).map_err(Error::from_output)
    }

    /// The exact energy ∫ |p_∞''|² of the limit curve, p_0ᵀ E_0 N_0 p_0 (Theorem 6.4), summed
    /// over coordinates: (D₂ p_0) · (D₂ N_0 p_0).
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 points.
    pub fn limit_energy(&self, points: &Points) -> Result<f64, Error> {
        let v = self.limit_values(points)?;
        let dim = points.dim();
        let (a, b) = (points.coords(), v.coords());
        let d2 = |c: &[f64], i: usize, d: usize| {
            c[i * dim + d] - 2.0 * c[(i + 1) * dim + d] + c[(i + 2) * dim + d]
        };
        let mut sum = 0.0;
        for i in 0..points.len().saturating_sub(2) {
            for d in 0..dim {
                sum += d2(a, i, d) * d2(b, i, d);
            }
        }
        Ok(sum)
    }

    /// The control points p_0 = N⁻¹ b whose limit curve interpolates the values b at the
    /// integers (Fig. 6.7). N is tridiagonal and diagonally dominant (rows (1), (⅙, ⅔, ⅙)), so
    /// the system is solved by the Thomas algorithm in O(L).
    ///
    /// # Errors
    /// [`Error::TooFew`] (`points`) for fewer than 2 values; [`Error::Singular`]
    /// if N were not tridiagonal or a pivot vanished (does not occur for natural splines).
    pub fn interpolate(&self, values: &Points) -> Result<Points, Error> {
        let l = check_points(values)?;
        let rows = self.interpolation.float_rows_for(l)?;
        let n = l + 1;
        let (mut sub, mut diag, mut sup) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for i in 0..n {
            let (entries, shift) = rows.row(i);
            for (c, w) in entries {
                match *c as isize + shift - i as isize {
                    -1 => sub[i] = *w,
                    0 => diag[i] = *w,
                    1 => sup[i] = *w,
                    _ => return Err(Error::Singular { index: i }),
                }
            }
        }
        let dim = values.dim();
        let mut x = values.coords().to_vec();
        // Forward elimination, then back substitution, on all coordinates at once.
        let mut cp = vec![0.0; n];
        for i in 0..n {
            let piv = if i == 0 {
                diag[0]
            } else {
                diag[i] - sub[i] * cp[i - 1]
            };
            if piv.abs() <= f64::EPSILON {
                return Err(Error::Singular { index: i });
            }
            cp[i] = sup[i] / piv;
            for d in 0..dim {
                let prev = if i == 0 { 0.0 } else { x[(i - 1) * dim + d] };
                x[i * dim + d] = (x[i * dim + d] - sub[i] * prev) / piv;
            }
        }
        for i in (0..n - 1).rev() {
            for d in 0..dim {
                x[i * dim + d] -= cp[i] * x[(i + 1) * dim + d];
            }
        }
        Points::new(dim, x).map_err(Error::from_output)
    }
}
