//! Dense exports, for tests and verification only: the solve path never forms an N×N matrix.

use divdiff::{Knots, Topology};
use nalgebra::DMatrix;

use crate::{alphas, Error, Hessian};

impl Hessian {
    /// H as a dense N×N matrix (aliased band entries of small closed curves are summed).
    ///
    /// For tests and verification; O(N²) memory.
    ///
    /// ```
    /// use divdiff::Knots;
    /// use energy::{alpha_matrix, Hessian};
    /// let knots = Knots::closed(vec![0.0, 0.5, 2.0, 2.25, 3.0]).unwrap();
    /// let a = alpha_matrix(&knots);
    /// let h = Hessian::new(&knots).to_dense();
    /// assert!((a.transpose() * a - &h).amax() < 1e-12 * h.amax());
    /// ```
    pub fn to_dense(&self) -> DMatrix<f64> {
        let n = self.len();
        let closed = self.topology() == Topology::Closed;
        let (diag, off1, off2) = self.bands();
        let mut m = DMatrix::zeros(n, n);
        for j in 0..n {
            m[(j, j)] += diag[j];
            for (k, band) in [(1, off1), (2, off2)] {
                let r = j + k;
                let r = if closed {
                    r % n
                } else if r < n {
                    r
                } else {
                    continue;
                };
                m[(j, r)] += band[j];
                m[(r, j)] += band[j];
            }
        }
        m
    }
}

/// The N×N matrix A of Kersey §2.1 (§3.6 for open curves), built from [`alphas`]: row i holds
/// α_{i,1}, α_{i,2}, α_{i,3} on columns i − 1, i, i + 1 (modulo N for closed curves).
///
/// For tests and verification; O(N²) memory.
pub fn alpha_matrix(knots: &Knots) -> DMatrix<f64> {
    let n = knots.vertex_count();
    let closed = knots.is_closed();
    let mut a = DMatrix::zeros(n, n);
    for (i, row) in alphas(knots).iter().enumerate() {
        for (k, &v) in row.iter().enumerate() {
            let c = i as isize + k as isize - 1;
            if closed {
                a[(i, c.rem_euclid(n as isize) as usize)] += v;
            } else if (0..n as isize).contains(&c) {
                a[(i, c as usize)] += v;
            }
        }
    }
    a
}

/// The (n − 2)×n second-difference matrix D₂ with rows (1, −2, 1) (Warren–Weimer §6.2).
///
/// # Errors
/// [`Error::WrongLength`] if `n < 3` (there is no second difference).
pub fn second_difference_matrix(n: usize) -> Result<DMatrix<f64>, Error> {
    if n < 3 {
        return Err(Error::WrongLength {
            field: "n",
            expected: 3,
            got: n,
        });
    }
    let mut d = DMatrix::zeros(n - 2, n);
    for i in 0..n - 2 {
        d[(i, i)] = 1.0;
        d[(i, i + 1)] = -2.0;
        d[(i, i + 2)] = 1.0;
    }
    Ok(d)
}

/// Warren–Weimer's inner-product matrix E_k = 8^k D₂ᵀD₂ on n grid points of the grid 2^{−k} Z
/// (§6.2; interior rows (1, −4, 6, −4, 1), boundary rows (1, −2, 1), (−2, 5, −4, 1)).
///
/// It equals Kersey's open-curve Hessian H on uniform knots of spacing 2^{−k} **as a matrix**:
/// there α = 2^{3k/2}(1, −2, 1), so A = 2^{3k/2} D₂ (padded with zero end rows) and
/// H = AᵀA = 8^k D₂ᵀD₂. The energies differ by the factor ½: Kersey's E = ½ pᵀHp discretizes
/// ½∫|f''|², Warren–Weimer's pᵀE_k p discretizes ∫|f''|².
///
/// # Errors
/// [`Error::WrongLength`] if `n < 3`.
pub fn warren_weimer_matrix(n: usize, level: u32) -> Result<DMatrix<f64>, Error> {
    let d = second_difference_matrix(n)?;
    Ok(d.transpose() * d * 8f64.powi(level as i32))
}
