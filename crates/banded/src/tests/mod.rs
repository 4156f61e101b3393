//! Tests of the factorizations: reconstruction (factor, multiply the factors back, compare with
//! the matrix entry by entry, against the rounding bound of the factorization), solves against
//! nalgebra's dense Cholesky / LU of the same matrix (an independent implementation), edge
//! cases n = 0..8 where cyclic bands alias, ill-conditioned matrices (condition 1e12 and
//! beyond), elimination, and the typed errors.

// Dense d×d and band kernels index several arrays by the same row and column: index loops
// read more clearly than iterator chains here.
#![allow(clippy::needless_range_loop)]
// Some checks are exact on purpose: sums of exactly representable entries (aliasing), and the
// claim that a refactored factor reproduces a solve bit for bit.
#![allow(clippy::float_cmp)]

mod block;
mod ported;
mod scalar;

use nalgebra::DMatrix;

/// Small deterministic generator (xorshift64*), so a seed fixes a whole problem.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }
    pub(crate) fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    /// 10^u with u uniform in [lo, hi].
    pub(crate) fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(self.range(lo, hi))
    }
}

/// The unit roundoff.
pub(crate) const EPS: f64 = f64::EPSILON / 2.0;

/// How a random symmetric positive definite band matrix is conditioned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Conditioning {
    /// Diagonally dominant: condition O(1)–O(10).
    Dominant,
    /// Σ_j w_j v_j v_jᵀ over (cyclic) windows of W + 1 consecutive rows with weights w_j
    /// spread log-uniformly over 12 orders of magnitude: condition 1e12 and beyond.
    Ill,
}

/// A random SPD (block) band matrix as a dense symmetric matrix with the given (cyclic)
/// half-bandwidth `w` in blocks of size `d`.
pub(crate) fn random_spd(
    n: usize,
    d: usize,
    w: usize,
    cyclic: bool,
    cond: Conditioning,
    rng: &mut Rng,
) -> DMatrix<f64> {
    let nd = n * d;
    let mut a = DMatrix::<f64>::zeros(nd, nd);
    if n == 0 {
        return a;
    }
    // Windows of w + 1 consecutive block rows: every product v vᵀ stays in the (cyclic) band.
    let windows: Vec<Vec<usize>> = if cyclic {
        (0..n)
            .map(|j| {
                let mut v: Vec<usize> = (0..=w).map(|k| (j + k) % n).collect();
                v.sort_unstable();
                v.dedup();
                v
            })
            .collect()
    } else {
        (0..n).map(|j| (j..(j + w + 1).min(n)).collect()).collect()
    };
    let terms_per_window = d;
    for win in &windows {
        for _ in 0..terms_per_window {
            let weight = match cond {
                Conditioning::Dominant => rng.range(0.1, 1.0),
                Conditioning::Ill => rng.log_uniform(-12.0, 0.0),
            };
            let v: Vec<(usize, f64)> = win
                .iter()
                .flat_map(|&b| (0..d).map(move |c| b * d + c))
                .map(|idx| (idx, rng.range(-1.0, 1.0)))
                .collect();
            for &(i, x) in &v {
                for &(j, y) in &v {
                    a[(i, j)] += weight * x * y;
                }
            }
        }
    }
    match cond {
        Conditioning::Dominant => {
            for i in 0..nd {
                let s: f64 = (0..nd).filter(|&j| j != i).map(|j| a[(i, j)].abs()).sum();
                a[(i, i)] += s + rng.range(0.1, 1.0);
            }
        }
        Conditioning::Ill => {
            // A floor keeps the matrix definite in floating point (smallest eigenvalue ≳ 1e−14
            // of the largest) while its condition stays ≳ 1e12.
            let scale = (0..nd).map(|i| a[(i, i)]).fold(0.0f64, f64::max);
            for i in 0..nd {
                a[(i, i)] += 1e-15 * scale;
            }
        }
    }
    // Exact symmetry (the products above are symmetric term by term, but be explicit).
    let at = a.transpose();
    (a + at) * 0.5
}

/// The 2-norm condition number of a symmetric positive definite matrix (by eigenvalues).
pub(crate) fn condition(a: &DMatrix<f64>) -> f64 {
    let e = a.clone().symmetric_eigenvalues();
    let (lo, hi) = e.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &v| {
        (l.min(v), h.max(v.abs()))
    });
    hi / lo
}

/// Deterministic right-hand sides, n·d × ncols row-major.
pub(crate) fn rhs(rows: usize, ncols: usize, rng: &mut Rng) -> Vec<f64> {
    (0..rows * ncols).map(|_| rng.range(-1.0, 1.0)).collect()
}

/// max_i |b − A x|_i / (|A| |x| + |b|)_i: the componentwise backward error (Oettli–Prager).
pub(crate) fn backward_error(a: &DMatrix<f64>, x: &[f64], b: &[f64], ncols: usize) -> f64 {
    let n = a.nrows();
    let mut worst = 0.0f64;
    for c in 0..ncols {
        for i in 0..n {
            let (mut r, mut s) = (b[i * ncols + c], b[i * ncols + c].abs());
            for j in 0..n {
                r -= a[(i, j)] * x[j * ncols + c];
                s += (a[(i, j)] * x[j * ncols + c]).abs();
            }
            let e = if s > 0.0 { r.abs() / s } else { r.abs() };
            worst = worst.max(if e.is_nan() { f64::INFINITY } else { e });
        }
    }
    worst
}

/// max |x − y| / max |y| over all columns (y the reference).
pub(crate) fn relative_difference(x: &[f64], y: &[f64]) -> f64 {
    let den = y
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    x.iter()
        .zip(y)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / den
}

/// nalgebra's dense solution of A X = B (B row-major n × ncols), by LU with partial pivoting:
/// an independent reference.
pub(crate) fn dense_solve(a: &DMatrix<f64>, b: &[f64], ncols: usize) -> Vec<f64> {
    let n = a.nrows();
    let bm = DMatrix::from_row_slice(n, ncols, b);
    let x = a
        .clone()
        .lu()
        .solve(&bm)
        .expect("the reference matrix is nonsingular");
    let mut out = vec![0.0; n * ncols];
    for i in 0..n {
        for c in 0..ncols {
            out[i * ncols + c] = x[(i, c)];
        }
    }
    out
}
