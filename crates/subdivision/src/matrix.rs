//! Small dense matrices of exact rationals, used only to *derive* rules (subdivision and
//! interpolation matrices of the natural cubic scheme) and to check identities exactly. Sizes
//! are bounded by [`crate::MAX_EXACT_INTERVALS`]; no solve path of the library runs on them.

use num_rational::BigRational;
use num_traits::{One, Zero};

/// A dense matrix of exact rationals, row-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RationalMatrix {
    rows: usize,
    cols: usize,
    data: Vec<BigRational>,
}

impl RationalMatrix {
    /// The `rows × cols` zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        RationalMatrix {
            rows,
            cols,
            data: vec![BigRational::zero(); rows * cols],
        }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Entry (i, j).
    ///
    /// # Panics
    /// If (i, j) is out of range.
    pub fn get(&self, i: usize, j: usize) -> &BigRational {
        assert!(i < self.rows && j < self.cols, "index out of range");
        &self.data[i * self.cols + j]
    }

    /// Sets entry (i, j).
    ///
    /// # Panics
    /// If (i, j) is out of range.
    pub fn set(&mut self, i: usize, j: usize, v: BigRational) {
        assert!(i < self.rows && j < self.cols, "index out of range");
        self.data[i * self.cols + j] = v;
    }

    /// Row i.
    ///
    /// # Panics
    /// If `i >= rows`.
    pub fn row(&self, i: usize) -> &[BigRational] {
        &self.data[i * self.cols..(i + 1) * self.cols]
    }

    /// The transpose.
    pub fn transpose(&self) -> Self {
        let mut t = RationalMatrix::zeros(self.cols, self.rows);
        for i in 0..self.rows {
            for j in 0..self.cols {
                t.data[j * self.rows + i] = self.data[i * self.cols + j].clone();
            }
        }
        t
    }

    /// The product `self · other`, or `None` if the shapes do not match. Zero entries are
    /// skipped, so products of the sparse matrices used here stay cheap.
    pub fn mul(&self, other: &RationalMatrix) -> Option<RationalMatrix> {
        if self.cols != other.rows {
            return None;
        }
        let mut p = RationalMatrix::zeros(self.rows, other.cols);
        for i in 0..self.rows {
            for k in 0..self.cols {
                let a = &self.data[i * self.cols + k];
                if a.is_zero() {
                    continue;
                }
                for j in 0..other.cols {
                    let b = &other.data[k * other.cols + j];
                    if !b.is_zero() {
                        p.data[i * other.cols + j] += a * b;
                    }
                }
            }
        }
        Some(p)
    }

    /// The determinant (exact Gaussian elimination; 0 for a non-square matrix).
    pub fn determinant(&self) -> BigRational {
        let n = self.rows;
        if self.cols != n {
            return BigRational::zero();
        }
        let mut a = self.data.clone();
        let mut det = BigRational::one();
        for k in 0..n {
            let Some(piv) = (k..n).find(|&r| !a[r * n + k].is_zero()) else {
                return BigRational::zero();
            };
            if piv != k {
                for j in 0..n {
                    a.swap(k * n + j, piv * n + j);
                }
                det = -det;
            }
            let p = a[k * n + k].clone();
            det *= &p;
            for r in k + 1..n {
                if a[r * n + k].is_zero() {
                    continue;
                }
                let f = &a[r * n + k] / &p;
                for j in k..n {
                    let v = &f * &a[k * n + j];
                    a[r * n + j] -= v;
                }
            }
        }
        det
    }

    /// The matrix with every entry correctly rounded to `f64`, as rows.
    pub fn to_f64_rows(&self) -> Vec<Vec<f64>> {
        (0..self.rows)
            .map(|i| self.row(i).iter().map(crate::rational_to_f64).collect())
            .collect()
    }

    /// The nonzero entries of row i as (column, value).
    ///
    /// # Panics
    /// If `i >= rows`.
    pub fn row_nonzeros(&self, i: usize) -> Vec<(usize, BigRational)> {
        self.row(i)
            .iter()
            .enumerate()
            .filter(|(_, v)| !v.is_zero())
            .map(|(j, v)| (j, v.clone()))
            .collect()
    }
}

/// Solves the square system `a x = b` exactly by Gaussian elimination (first nonzero pivot),
/// or `None` if `a` is singular or not square.
pub(super) fn solve(mut a: RationalMatrix, mut b: Vec<BigRational>) -> Option<Vec<BigRational>> {
    let n = a.rows;
    if a.cols != n || b.len() != n {
        return None;
    }
    for k in 0..n {
        let piv = (k..n).find(|&r| !a.get(r, k).is_zero())?;
        if piv != k {
            for j in 0..n {
                a.data.swap(k * n + j, piv * n + j);
            }
            b.swap(k, piv);
        }
        let inv = BigRational::one() / a.get(k, k);
        for r in k + 1..n {
            let f = a.get(r, k) * &inv;
            if f.is_zero() {
                continue;
            }
            for j in k..n {
                let v = &f * a.get(k, j);
                a.data[r * n + j] -= v;
            }
            let v = &f * &b[k];
            b[r] -= v;
        }
    }
    let mut x = vec![BigRational::zero(); n];
    for k in (0..n).rev() {
        let mut s = b[k].clone();
        for (j, xj) in x.iter().enumerate().skip(k + 1) {
            s -= a.get(k, j) * xj;
        }
        x[k] = s / a.get(k, k);
    }
    Some(x)
}
