//! What the workspace's former private factorizations tested, against `banded`, plus the
//! shapes their callers build: strip's banded Newton Hessian, refine's cyclic tridiagonal
//! data-row system T (several columns) and its span LU (first and last rows of B⁻¹), and the
//! condensed balls method's block system S = T ⊗ I + K D⁻¹ Kᵀ with interior-point scalings.

use super::*;
use crate::{BlockBand, Error, FactorOptions, SymBand, Topology, TridiagonalLu};
use nalgebra::DMatrix;

#[test]
fn strip_heptadiagonal_band_solves_a_pentadiagonal_spd_system() {
    // (strip::banded) A = tridiag(−1, 4, −1) + 0.5 on the second off-diagonal, stored with
    // strip's half-bandwidth 3; checked by the residual of A x = b computed by hand.
    let n = 9;
    let mut m = SymBand::<3>::zeros(n, Topology::Open);
    for i in 0..n {
        m.add(i, i, 4.0).unwrap();
        if i >= 1 {
            m.add(i, i - 1, -1.0).unwrap();
        }
        if i >= 2 {
            m.add(i, i - 2, 0.5).unwrap();
        }
    }
    let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
    let mut x = b.clone();
    m.factor().unwrap().solve_in_place(&mut x, 1).unwrap();
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
fn strip_indefinite_matrix_is_reported() {
    // (strip::banded) [[1, 2], [2, 1]] is indefinite: the second pivot is 1 − 4.
    let mut m = SymBand::<3>::zeros(2, Topology::Open);
    m.add(0, 0, 1.0).unwrap();
    m.add(1, 1, 1.0).unwrap();
    m.add(1, 0, 2.0).unwrap();
    assert_eq!(
        m.factor_with(&FactorOptions::default().pivot_rtol(0.0))
            .unwrap_err(),
        Error::Singular { index: 1 }
    );
}

/// refine's data-row matrix T = I + L Lᵀ on n data rows: diagonal 1 + a² + b², coupling a b
/// (cyclic), from random positive α's — symmetric positive definite and diagonally dominant.
fn data_row_system(n: usize, rng: &mut Rng) -> (Vec<f64>, Vec<f64>) {
    let a: Vec<f64> = (0..n).map(|_| rng.range(0.1, 3.0)).collect();
    let b: Vec<f64> = (0..n).map(|_| rng.range(0.1, 3.0)).collect();
    let diag = (0..n).map(|i| 1.0 + a[i] * a[i] + b[i] * b[i]).collect();
    let off = (0..n).map(|i| a[i] * b[(i + 1) % n]).collect();
    (diag, off)
}

#[test]
fn cyclic_tridiagonal_data_row_system_with_several_columns() {
    // (refine::kersey::fast::solve_tridiagonal, condensed's T) T s = K y for d = 1..4 columns,
    // closed (cyclic) and open, against nalgebra's dense LU of the same T.
    for n in [1, 2, 3, 4, 5, 8, 33, 200] {
        for cyclic in [false, true] {
            for d in 1..=4 {
                let mut rng = Rng::new((n * 10 + d) as u64);
                let (diag, off) = data_row_system(n, &mut rng);
                let top = if cyclic {
                    Topology::Cyclic
                } else {
                    Topology::Open
                };
                let off: Vec<[f64; 1]> = off.iter().map(|&v| [v]).collect();
                let t = SymBand::<1>::from_bands(top, diag, off).unwrap();
                let dense = DMatrix::from_fn(n, n, |i, j| t.get(i, j).unwrap());
                let b = rhs(n, d, &mut rng);
                let mut x = b.clone();
                t.factor().unwrap().solve_in_place(&mut x, d).unwrap();
                let y = dense_solve(&dense, &b, d);
                assert!(
                    relative_difference(&x, &y) < 1e-14,
                    "n={n} cyclic={cyclic} d={d}"
                );
            }
        }
    }
}

/// The α-rows of Kersey's A restricted to one data span's k free vertices (refine's B_i):
/// row r holds α_{r,1}, α_{r,2} = −α_{r,1} − α_{r,3}, α_{r,3} with α's from random spans.
fn span_matrix(k: usize, rng: &mut Rng) -> Vec<[f64; 3]> {
    (0..k)
        .map(|_| {
            let (hm, hp) = (rng.range(0.2, 2.0), rng.range(0.2, 2.0));
            let s = (hm + hp).sqrt();
            let a1 = std::f64::consts::SQRT_2 / (hm * s);
            let a3 = std::f64::consts::SQRT_2 / (hp * s);
            [a1, -a1 - a3, a3]
        })
        .collect()
}

#[test]
fn span_lu_has_negative_pivots_and_gives_the_end_rows_of_the_inverse() {
    // (refine::kersey::fast::span_lu / span_gh) B is weakly diagonally dominant with strict
    // dominance in its first and last rows and a negative diagonal: its pivots are negative,
    // and g = B⁻ᵀ e₀, h = B⁻ᵀ e_{k−1} are the first and last rows of B⁻¹.
    for k in 1..=12 {
        let mut rng = Rng::new(k as u64);
        let rows = span_matrix(k, &mut rng);
        let lu = TridiagonalLu::factor(&rows).unwrap();
        assert!(
            lu.inverse_pivots().all(|v| v < 0.0 && v.is_finite()),
            "k={k}"
        );
        let dense = DMatrix::from_fn(k, k, |i, j| {
            if j + 1 == i {
                rows[i][0]
            } else if j == i {
                rows[i][1]
            } else if j == i + 1 {
                rows[i][2]
            } else {
                0.0
            }
        });
        let inv = dense.clone().try_inverse().unwrap();
        for (row, e) in [(0, 0), (k - 1, k - 1)] {
            let mut g = vec![0.0; k];
            g[e] = 1.0;
            lu.solve_transposed_in_place(&mut g, 1).unwrap();
            let want: Vec<f64> = (0..k).map(|j| inv[(row, j)]).collect();
            assert!(relative_difference(&g, &want) < 1e-13, "k={k} row {row}");
        }
        // And B x = b for two columns.
        let b = rhs(k, 2, &mut rng);
        let mut x = b.clone();
        lu.solve_in_place(&mut x, 2).unwrap();
        assert!(relative_difference(&x, &dense_solve(&dense, &b, 2)) < 1e-13);
    }
}

#[test]
fn tridiagonal_lu_matches_dense_and_reports_zero_pivots() {
    // strip's spline-slope system: a z_{i−1} + b z_i + c z_{i+1} = r, diagonally dominant,
    // with one end row replaced by an identity row (a clamped slope).
    let n = 40;
    let mut rng = Rng::new(9);
    let h: Vec<f64> = (0..n).map(|_| rng.range(0.01, 3.0)).collect();
    let mut rows = vec![[0.0; 3]; n];
    for i in 1..n - 1 {
        rows[i] = [
            2.0 / h[i - 1],
            4.0 * (1.0 / h[i - 1] + 1.0 / h[i]),
            2.0 / h[i],
        ];
    }
    rows[0] = [0.0, 1.0, 0.0];
    rows[n - 1] = [2.0 / h[n - 2], 4.0 / h[n - 2], 0.0];
    let lu = TridiagonalLu::factor(&rows).unwrap();
    let dense = DMatrix::from_fn(n, n, |i, j| {
        if j + 1 == i {
            rows[i][0]
        } else if j == i {
            rows[i][1]
        } else if j == i + 1 {
            rows[i][2]
        } else {
            0.0
        }
    });
    for ncols in [1, 3] {
        let b = rhs(n, ncols, &mut rng);
        let mut x = b.clone();
        lu.solve_in_place(&mut x, ncols).unwrap();
        assert!(relative_difference(&x, &dense_solve(&dense, &b, ncols)) < 1e-13);
        let mut y = b.clone();
        lu.solve_transposed_in_place(&mut y, ncols).unwrap();
        let dt = dense.transpose();
        assert!(relative_difference(&y, &dense_solve(&dt, &b, ncols)) < 1e-13);
    }
    // [[1, 1], [1, 1]]: the second pivot is exactly 0.
    assert_eq!(
        TridiagonalLu::factor(&[[0.0, 1.0, 1.0], [1.0, 1.0, 0.0]]).unwrap_err(),
        Error::Singular { index: 1 }
    );
    assert!(matches!(
        lu.solve_in_place(&mut [0.0; 3], 1),
        Err(Error::WrongLength { field: "x", .. })
    ));
}

#[test]
fn condensed_block_system_with_interior_point_scalings() {
    // (refine::kersey::condensed::Banded) S = T ⊗ I_d + K D⁻¹ Kᵀ: T the cyclic data-row
    // matrix, K tridiagonal (cyclic) on the data points, D⁻¹ per point a d×d SPD block with
    // eigenvalues from 1e−10 to 1e10 (an active cone's Nesterov–Todd scaling next to an
    // inactive one's). Factored with a tiny relative pivot tolerance, as interior-point
    // methods do, and compared with nalgebra's dense LU.
    for (n, d) in [(3, 2), (4, 3), (7, 2), (40, 2), (40, 3), (25, 5)] {
        let mut rng = Rng::new((n * d) as u64);
        let (tdiag, toff) = data_row_system(n, &mut rng);
        let mut s = BlockBand::<2>::zeros(n, d, Topology::Cyclic).unwrap();
        for j in 0..n {
            s.add_scalar(j, j, tdiag[j]).unwrap();
            s.add_scalar(j, (j + 1) % n, toff[j]).unwrap();
        }
        let k: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                [
                    rng.range(-1.0, 1.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-1.0, 1.0),
                ]
            })
            .collect();
        for i in 0..n {
            // D⁻¹ = a (I − u uᵀ) + b u uᵀ with a, b spread over 20 orders of magnitude.
            let u: Vec<f64> = (0..d).map(|_| rng.range(-1.0, 1.0)).collect();
            let un = crate::vector::norm(&u);
            let (a, b) = (rng.log_uniform(-10.0, 10.0), rng.log_uniform(-10.0, 10.0));
            let dinv: Vec<f64> = (0..d * d)
                .map(|e| {
                    let (r, c) = (e / d, e % d);
                    let uu = u[r] * u[c] / (un * un);
                    a * (if r == c { 1.0 } else { 0.0 } - uu) + b * uu
                })
                .collect();
            // Point i touches the rows i − 1, i, i + 1 of K.
            let touch = [
                ((i + n - 1) % n, k[i][0]),
                (i, k[i][1]),
                ((i + 1) % n, k[i][2]),
            ];
            for x in 0..3 {
                for y in x..3 {
                    let ((jx, kx), (jy, ky)) = (touch[x], touch[y]);
                    s.add_scaled(jx, jy, kx * ky, &dinv).unwrap();
                }
            }
        }
        let f = s
            .factor_with(&FactorOptions::default().pivot_rtol(1e-22))
            .unwrap();
        let nd = n * d;
        let mut dense = DMatrix::<f64>::zeros(nd, nd);
        let mut out = vec![0.0; d * d];
        for i in 0..n {
            for j in 0..n {
                s.get(i, j, &mut out).unwrap();
                for e in 0..d * d {
                    dense[(i * d + e / d, j * d + e % d)] = out[e];
                }
            }
        }
        let b = rhs(nd, 1, &mut rng);
        let mut x = b.clone();
        f.solve_in_place(&mut x, 1).unwrap();
        let be = backward_error(&dense, &x, &b, 1);
        assert!(be < 1e-12, "n={n} d={d}: backward error {be:e}");
        let y = dense_solve(&dense, &b, 1);
        let kappa = condition(&dense);
        assert!(
            relative_difference(&x, &y) <= 1e3 * EPS * kappa,
            "n={n} d={d}: κ = {kappa:e}"
        );
    }
}
