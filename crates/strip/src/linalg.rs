//! The banded linear algebra of `strip`, in one place: the symmetric band Hessian of the outer
//! Newton step, factored by [`banded::SymBand`] (LDLᵀ without square roots), and the small dense
//! solve of the whole Jacobian that places a short segment's abscissae again in the caller's
//! frame ([`solve_dense`], `resolve.rs`). The spline's tridiagonal systems, and that Jacobian
//! when it is tridiagonal, go to [`banded::TridiagonalLu`] directly (`spline.rs`, `resolve.rs`).
//!
//! Φ is a sum of terms that each couple the unknowns of two neighbouring grid points, so its
//! Hessian is banded: half-bandwidth 1 (tridiagonal) when only slopes are unknown, up to
//! [`MAX_BAND`] when values at extra grid points are unknown too (§4). O(N w²) work.

use banded::{FactorOptions, SymBand, Topology};

/// Maximum half-bandwidth.
pub(crate) const MAX_BAND: usize = 3;

/// Symmetric band matrix of half-bandwidth [`MAX_BAND`].
#[derive(Clone, Debug)]
pub(crate) struct Band(SymBand<MAX_BAND>);

impl Band {
    pub fn zeros(n: usize) -> Self {
        Band(SymBand::zeros(n, Topology::Open))
    }
    /// Adds v to A(i, j) (and A(j, i)); entries farther than [`MAX_BAND`] from the diagonal are
    /// not stored (Φ's terms never make them).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let _ = self.0.add(i, j, v);
    }
    /// The diagonal A(i, i).
    pub fn diagonal(&self) -> &[f64] {
        self.0.diag()
    }
    /// max_i |A(i, i)|.
    pub fn max_abs_diagonal(&self) -> f64 {
        self.0.diag().iter().fold(0.0f64, |m, d| m.max(d.abs()))
    }
    /// Adds λ to every diagonal entry (a Levenberg–Marquardt shift).
    pub fn shift_diagonal(&mut self, lambda: f64) {
        self.0.diag_mut().iter_mut().for_each(|d| *d += lambda);
    }
    /// Solves A x = b by LDLᵀ; `None` when a pivot is not positive (A not SPD).
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let mut x = b.to_vec();
        if x.is_empty() {
            return Some(x);
        }
        let f = self
            .0
            .factor_with(&FactorOptions::default().pivot_rtol(0.0))
            .ok()?;
        f.solve_in_place(&mut x, 1).ok()?;
        Some(x)
    }
}

/// Solves the m × m system `a` (row-major, overwritten) x = `b` in place by Gaussian elimination
/// with partial pivoting; `None` where a pivot vanishes or is not finite.
pub(crate) fn solve_dense(a: &mut [f64], b: &mut [f64], m: usize) -> Option<()> {
    for c in 0..m {
        let p = (c..m).max_by(|&i, &k| a[i * m + c].abs().total_cmp(&a[k * m + c].abs()))?;
        let pivot = a[p * m + c];
        if pivot == 0.0 || !pivot.is_finite() {
            return None;
        }
        if p != c {
            for k in 0..m {
                a.swap(p * m + k, c * m + k);
            }
            b.swap(p, c);
        }
        for i in c + 1..m {
            let l = a[i * m + c] / pivot;
            for k in c..m {
                a[i * m + k] -= l * a[c * m + k];
            }
            b[i] -= l * b[c];
        }
    }
    for c in (0..m).rev() {
        let tail: f64 = (c + 1..m).map(|k| a[c * m + k] * b[k]).sum();
        b[c] = (b[c] - tail) / a[c * m + c];
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pentadiagonal_spd_system() {
        // A = tridiag(-1, 4, -1) + 0.5 on the second off-diagonal; check A x = b by residual.
        let n = 9;
        let mut m = Band::zeros(n);
        for i in 0..n {
            m.add(i, i, 4.0);
            if i >= 1 {
                m.add(i, i - 1, -1.0);
            }
            if i >= 2 {
                m.add(i, i - 2, 0.5);
            }
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let x = m.solve(&b).unwrap();
        for i in 0..n {
            let mut r = 4.0 * x[i];
            if i >= 1 {
                r -= x[i - 1];
            }
            if i + 1 < n {
                r -= x[i + 1];
            }
            if i >= 2 {
                r += 0.5 * x[i - 2];
            }
            if i + 2 < n {
                r += 0.5 * x[i + 2];
            }
            assert!((r - b[i]).abs() < 1e-13);
        }
    }

    #[test]
    fn indefinite_matrix_is_reported() {
        let mut m = Band::zeros(2);
        m.add(0, 0, 1.0);
        m.add(1, 1, 1.0);
        m.add(1, 0, 2.0);
        assert!(m.solve(&[1.0, 1.0]).is_none());
    }
}
