//! General (nonsymmetric) tridiagonal LU without pivoting.
//!
//! A = L U with L unit lower bidiagonal (multipliers l_i) and U upper bidiagonal (pivots u_i,
//! superdiagonal that of A): u_0 = A_00, l_i = A_{i,i−1}/u_{i−1}, u_i = A_ii − l_i A_{i−1,i}
//! (Golub–Van Loan, *Matrix Computations*, 4th ed., §4.3.6, "the Thomas algorithm"). Without
//! pivoting this is stable for diagonally dominant matrices (GVL §4.1.1, Theorem 4.1.1's
//! setting) and for the other classes the callers know to be safe; a pivot that is not finite
//! or not above `pivot_rtol · |A_ii|` in magnitude is reported, never divided by.
//! Symmetric positive definite tridiagonal matrices belong to [`crate::SymBand`]`<1>`.

use crate::scalar::check_len;
use crate::{Error, PIVOT_RTOL};

/// The LU factor of a general tridiagonal matrix given by rows `[A_{i,i−1}, A_ii, A_{i,i+1}]`
/// (the first row's A_{0,−1} and the last row's A_{n−1,n} are ignored).
///
/// ```
/// use banded::TridiagonalLu;
/// // A nonsymmetric, diagonally dominant matrix.
/// let rows = [[0.0, 4.0, 1.0], [2.0, 5.0, 1.0], [1.0, 3.0, 0.0]];
/// let lu = TridiagonalLu::factor(&rows).unwrap();
/// let mut x = [5.0, 8.0, 4.0]; // A (1, 1, 1)
/// lu.solve_in_place(&mut x, 1).unwrap();
/// assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-15));
/// let mut y = [6.0, 7.0, 4.0]; // Aᵀ (1, 1, 1)
/// lu.solve_transposed_in_place(&mut y, 1).unwrap();
/// assert!(y.iter().all(|v| (v - 1.0).abs() < 1e-15));
/// ```
#[derive(Clone, Debug, Default)]
pub struct TridiagonalLu {
    /// Per row: [l_i, 1/u_i, A_{i,i+1}].
    rows: Vec<[f64; 3]>,
}

impl TridiagonalLu {
    /// The LU factor with the default relative pivot tolerance [`PIVOT_RTOL`].
    ///
    /// # Errors
    /// [`Error::Singular`] naming the first row whose pivot is not finite or not above
    /// [`PIVOT_RTOL`] · |A_ii| in magnitude.
    pub fn factor(rows: &[[f64; 3]]) -> Result<TridiagonalLu, Error> {
        let mut f = TridiagonalLu::default();
        f.refactor(rows, PIVOT_RTOL)?;
        Ok(f)
    }

    /// Refactors in place for a new matrix (reusing the storage) with the relative pivot
    /// tolerance `pivot_rtol`. On error the factor is left empty (of size 0).
    ///
    /// # Errors
    /// [`Error::Singular`] naming the first row whose pivot is not finite or not above
    /// `pivot_rtol` · |A_ii| in magnitude.
    pub fn refactor(&mut self, rows: &[[f64; 3]], pivot_rtol: f64) -> Result<(), Error> {
        self.rows.clear();
        self.rows.reserve(rows.len());
        let (mut inv_prev, mut sup_prev) = (0.0, 0.0);
        let n = rows.len();
        for (i, &[sub, diag, sup]) in rows.iter().enumerate() {
            let sup = if i + 1 < n { sup } else { 0.0 };
            let l = if i > 0 { sub * inv_prev } else { 0.0 };
            let u = diag - l * sup_prev;
            if !(u.is_finite() && u.abs() > pivot_rtol * diag.abs()) || u == 0.0 {
                self.rows.clear();
                return Err(Error::Singular { index: i });
            }
            let inv = 1.0 / u;
            self.rows.push([l, inv, sup]);
            (inv_prev, sup_prev) = (inv, sup);
        }
        Ok(())
    }

    /// The size n.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether n = 0.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The reciprocal pivots 1/u_i (their signs tell callers that know the expected inertia
    /// whether the matrix is what they think it is).
    pub fn inverse_pivots(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        self.rows.iter().map(|r| r[1])
    }

    /// Solves A X = B in place for the `ncols` columns of X (n × ncols, row-major).
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` does not have n · ncols entries.
    pub fn solve_in_place(&self, x: &mut [f64], ncols: usize) -> Result<(), Error> {
        let n = self.len();
        check_len("x", x.len(), n * ncols)?;
        for c in 0..ncols {
            // L y = b, then U x = y; the running value stays in a register.
            let mut prev = 0.0;
            for (i, r) in self.rows.iter().enumerate() {
                prev = x[i * ncols + c] - r[0] * prev;
                x[i * ncols + c] = prev;
            }
            let mut next = 0.0;
            for (i, r) in self.rows.iter().enumerate().rev() {
                next = (x[i * ncols + c] - r[2] * next) * r[1];
                x[i * ncols + c] = next;
            }
        }
        Ok(())
    }

    /// Solves Aᵀ X = B in place for the `ncols` columns of X (n × ncols, row-major).
    ///
    /// # Errors
    /// [`Error::WrongLength`] if `x` does not have n · ncols entries.
    pub fn solve_transposed_in_place(&self, x: &mut [f64], ncols: usize) -> Result<(), Error> {
        let n = self.len();
        check_len("x", x.len(), n * ncols)?;
        for c in 0..ncols {
            // Aᵀ = Uᵀ Lᵀ: Uᵀ w = b (forward), then Lᵀ x = w (backward).
            let (mut prev, mut sup_prev) = (0.0, 0.0);
            for (i, r) in self.rows.iter().enumerate() {
                prev = (x[i * ncols + c] - sup_prev * prev) * r[1];
                x[i * ncols + c] = prev;
                sup_prev = r[2];
            }
            let (mut next, mut l_next) = (0.0, 0.0);
            for (i, r) in self.rows.iter().enumerate().rev() {
                next = x[i * ncols + c] - l_next * next;
                x[i * ncols + c] = next;
                l_next = r[0];
            }
        }
        Ok(())
    }
}
