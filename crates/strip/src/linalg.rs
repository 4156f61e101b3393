//! The banded linear algebra of `strip`, in one place: a tridiagonal solve (splines) and a
//! symmetric banded LDLᵀ (Cholesky without square roots) for the outer Newton step. Every banded
//! call of the crate goes through this module, so that a shared banded crate can replace it here.
//!
//! Φ is a sum of terms that each couple the unknowns of two neighbouring grid points, so its
//! Hessian is banded: half-bandwidth 1 (tridiagonal) when only slopes are unknown, up to 3 when
//! values at extra grid points are unknown too (§4). O(N w²) work.

/// Solves the tridiagonal system a_i x_{i−1} + b_i x_i + c_i x_{i+1} = r_i (a_0 and c_{n−1}
/// unused) by elimination without pivoting — for diagonally dominant matrices. `b` is
/// overwritten by the elimination, `r` by the solution.
pub(crate) fn solve_tridiagonal(a: &[f64], b: &mut [f64], c: &[f64], r: &mut [f64]) {
    let n = b.len();
    for i in 1..n {
        let w = a[i] / b[i - 1];
        b[i] -= w * c[i - 1];
        r[i] -= w * r[i - 1];
    }
    r[n - 1] /= b[n - 1];
    for i in (0..n - 1).rev() {
        r[i] = (r[i] - c[i] * r[i + 1]) / b[i];
    }
}

/// Maximum half-bandwidth.
pub(crate) const MAX_BAND: usize = 3;

/// Symmetric band matrix: `a[i][k]` = A(i, i − k), k = 0..=MAX_BAND.
#[derive(Clone, Debug)]
pub(crate) struct Band {
    pub a: Vec<[f64; MAX_BAND + 1]>,
}

impl Band {
    pub fn zeros(n: usize) -> Self {
        Band {
            a: vec![[0.0; MAX_BAND + 1]; n],
        }
    }
    /// Adds v to A(i, j) (and A(j, i)); |i − j| ≤ MAX_BAND.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (hi, lo) = if i >= j { (i, j) } else { (j, i) };
        if hi - lo <= MAX_BAND {
            self.a[hi][hi - lo] += v;
        }
    }
    /// Solves A x = b in place by LDLᵀ; `None` when a pivot is not positive (A not SPD).
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let n = self.a.len();
        let w = MAX_BAND;
        // l[i][k] = L(i, i − k), d[i]
        let mut l = vec![[0.0; MAX_BAND + 1]; n];
        let mut d = vec![0.0; n];
        for i in 0..n {
            for k in (1..=w.min(i)).rev() {
                let j = i - k;
                // L(i,j) = (A(i,j) − Σ_{m<j} L(i,m) D(m) L(j,m)) / D(j)
                let mut s = self.a[i][k];
                for m in (i.saturating_sub(w))..j {
                    if j - m <= w {
                        s -= l[i][i - m] * d[m] * l[j][j - m];
                    }
                }
                l[i][k] = s / d[j];
            }
            let mut s = self.a[i][0];
            for k in 1..=w.min(i) {
                s -= l[i][k] * l[i][k] * d[i - k];
            }
            if s.is_nan() || s <= 0.0 || !s.is_finite() {
                return None;
            }
            d[i] = s;
        }
        let mut x = b.to_vec();
        for i in 0..n {
            for k in 1..=w.min(i) {
                x[i] -= l[i][k] * x[i - k];
            }
        }
        for i in 0..n {
            x[i] /= d[i];
        }
        for i in (0..n).rev() {
            for k in 1..=w.min(n - 1 - i) {
                x[i] -= l[i + k][k] * x[i + k];
            }
        }
        Some(x)
    }
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
