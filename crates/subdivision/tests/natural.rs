//! Natural cubic splines by variational subdivision (Warren–Weimer ch. 6, seed 003; math.md §5):
//! E_k, U_k and S_k with the two-scale relation checked exactly, the structure of S and N, the
//! recurrence of N, the book's Bézier table on [0, 4], and the energies against an independent
//! natural-spline solver.

// Index loops mirror the formulas (rows, columns, coordinates) in this numerical test code.
#![allow(clippy::needless_range_loop)]

use divdiff::Points;
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};
use proptest::prelude::*;
use subdivision::{
    natural_inner_product_matrix, natural_interpolation_matrix, natural_subdivision_matrix,
    upsampling_matrix, NaturalScheme, RationalMatrix,
};

fn q(n: i64, d: i64) -> BigRational {
    BigRational::new(BigInt::from(n), BigInt::from(d))
}

fn nonzeros(m: &RationalMatrix, i: usize) -> Vec<(usize, BigRational)> {
    m.row_nonzeros(i)
}

/// E_k = 8^k D₂ᵀD₂: the book's rows (§6.2.2, math.md §5).
#[test]
fn inner_product_matrices_have_the_books_rows() {
    for level in 0..3usize {
        let e = natural_inner_product_matrix(4, level).unwrap();
        let n = 4 * (1 << level) + 1;
        assert_eq!((e.rows(), e.cols()), (n, n));
        let s = 8i64.pow(level as u32);
        let row = |vals: &[(usize, i64)]| -> Vec<(usize, BigRational)> {
            vals.iter().map(|&(c, v)| (c, q(v * s, 1))).collect()
        };
        assert_eq!(nonzeros(&e, 0), row(&[(0, 1), (1, -2), (2, 1)]));
        assert_eq!(nonzeros(&e, 1), row(&[(0, -2), (1, 5), (2, -4), (3, 1)]));
        for i in 2..n - 2 {
            let expect = row(&[(i - 2, 1), (i - 1, -4), (i, 6), (i + 1, -4), (i + 2, 1)]);
            assert_eq!(nonzeros(&e, i), expect);
        }
        assert_eq!(e, e.transpose());
    }
}

/// Theorem 6.3's two-scale relation E_{k+1} S_k = U_k E_k holds exactly — in every row,
/// including the first and last, which were *not* used to solve for S.
#[test]
fn two_scale_relation_holds_exactly() {
    for l in 1..=6 {
        for level in 0..3 {
            let s = natural_subdivision_matrix(l, level).unwrap();
            let ef = natural_inner_product_matrix(l, level + 1).unwrap();
            let ec = natural_inner_product_matrix(l, level).unwrap();
            let u = upsampling_matrix(l, level).unwrap();
            assert_eq!(
                ef.mul(&s).unwrap(),
                u.mul(&ec).unwrap(),
                "L={l} level={level}"
            );
        }
    }
}

/// The relation alone does not determine S: adding a linear sequence to a column keeps it.
/// (This is why the ends must be pinned; the pinned solution is the book's.)
#[test]
fn the_relation_leaves_a_linear_kernel_per_column() {
    let (l, level) = (3, 0);
    let s = natural_subdivision_matrix(l, level).unwrap();
    let mut t = s.clone();
    for i in 0..t.rows() {
        let v = t.get(i, 1) + q(3 * i as i64 - 2, 7);
        t.set(i, 1, v);
    }
    let ef = natural_inner_product_matrix(l, level + 1).unwrap();
    assert_eq!(ef.mul(&t).unwrap(), ef.mul(&s).unwrap());
    assert_ne!(t, s);
}

/// The solved S: end rows unit vectors, odd rows (½, ½), interior even rows (⅛, ¾, ⅛); and
/// S_k on [0, L] is S_0 on [0, 2^k L] (the scheme is stationary).
#[test]
fn subdivision_matrix_structure() {
    for l in 1..=10usize {
        let s = natural_subdivision_matrix(l, 0).unwrap();
        assert_eq!((s.rows(), s.cols()), (2 * l + 1, l + 1));
        assert_eq!(nonzeros(&s, 0), vec![(0, BigRational::one())]);
        assert_eq!(nonzeros(&s, 2 * l), vec![(l, BigRational::one())]);
        for j in 0..l {
            assert_eq!(
                nonzeros(&s, 2 * j + 1),
                vec![(j, q(1, 2)), (j + 1, q(1, 2))]
            );
        }
        for j in 1..l {
            assert_eq!(
                nonzeros(&s, 2 * j),
                vec![(j - 1, q(1, 8)), (j, q(3, 4)), (j + 1, q(1, 8))]
            );
        }
    }
    for level in 1..3 {
        assert_eq!(
            natural_subdivision_matrix(3, level).unwrap(),
            natural_subdivision_matrix(3 << level, 0).unwrap()
        );
    }
}

/// N: end rows unit, interior (⅙, ⅔, ⅙) (closed form, §6.3.1); it satisfies the recurrence
/// N_0 = U_0ᵀ N_1 S_0 exactly.
#[test]
fn interpolation_matrix_closed_form_and_recurrence() {
    for l in 1..=8usize {
        let n = natural_interpolation_matrix(l, 0).unwrap();
        assert_eq!(nonzeros(&n, 0), vec![(0, BigRational::one())]);
        assert_eq!(nonzeros(&n, l), vec![(l, BigRational::one())]);
        for j in 1..l {
            assert_eq!(
                nonzeros(&n, j),
                vec![(j - 1, q(1, 6)), (j, q(2, 3)), (j + 1, q(1, 6))]
            );
        }
        let n1 = natural_interpolation_matrix(l, 1).unwrap();
        let s0 = natural_subdivision_matrix(l, 0).unwrap();
        let u0 = upsampling_matrix(l, 0).unwrap();
        let rec = u0.transpose().mul(&n1).unwrap().mul(&s0).unwrap();
        assert_eq!(rec, n, "L={l}");
    }
}

/// The f64 scheme's rows (exactly derived for L ≤ 8, extended from the L = 8 template beyond)
/// agree with exactly derived matrices for every L up to 24.
#[test]
fn template_rows_match_exact_derivation() {
    let scheme = NaturalScheme::new().unwrap();
    for l in 1..=24usize {
        let s = natural_subdivision_matrix(l, 0).unwrap();
        let n = natural_interpolation_matrix(l, 0).unwrap();
        let srows = scheme.subdivision_rows(l).unwrap();
        let nrows = scheme.interpolation_rows(l).unwrap();
        assert_eq!(srows.len(), s.rows());
        for (i, row) in srows.iter().enumerate() {
            let got: Vec<(usize, BigRational)> =
                row.iter().map(|(c, v, _)| (*c, v.clone())).collect();
            assert_eq!(got, nonzeros(&s, i), "S, L={l}, row {i}");
        }
        for (i, row) in nrows.iter().enumerate() {
            let got: Vec<(usize, BigRational)> =
                row.iter().map(|(c, v, _)| (*c, v.clone())).collect();
            assert_eq!(got, nonzeros(&n, i), "N, L={l}, row {i}");
        }
    }
}

/// The O(N) application paths (subdivision, limit values, N⁻¹) agree with the exactly derived
/// matrices applied densely, for L on both sides of the template size.
#[test]
fn application_matches_exact_matrices() {
    let scheme = NaturalScheme::new().unwrap();
    for l in [1usize, 2, 5, 8, 9, 10, 17, 31] {
        let vals: Vec<f64> = (0..=l)
            .flat_map(|i| {
                [
                    (i as f64 * 0.7).sin(),
                    (i as f64 * 1.3).cos() + 0.1 * i as f64,
                ]
            })
            .collect();
        let p = Points::new(2, vals.clone()).unwrap();
        let s = natural_subdivision_matrix(l, 0).unwrap().to_f64_rows();
        let n = natural_interpolation_matrix(l, 0).unwrap().to_f64_rows();
        let vref = &vals;
        let dense = |m: &[Vec<f64>]| -> Vec<f64> {
            let mut out = Vec::new();
            for row in m {
                for d in 0..2 {
                    out.push(
                        row.iter()
                            .enumerate()
                            .map(|(c, w)| w * vref[2 * c + d])
                            .sum::<f64>(),
                    );
                }
            }
            out
        };
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-14)
        };
        assert!(
            close(scheme.subdivide_once(&p).unwrap().coords(), &dense(&s)),
            "S, L={l}"
        );
        let nv = dense(&n);
        assert!(
            close(scheme.limit_values(&p).unwrap().coords(), &nv),
            "N, L={l}"
        );
        let back = scheme.interpolate(&Points::new(2, nv).unwrap()).unwrap();
        assert!(close(back.coords(), &vals), "N^-1, L={l}");
    }
}

fn bernstein(k: usize, t: &BigRational) -> BigRational {
    let binom = [1, 3, 3, 1][k];
    let one_minus = BigRational::one() - t;
    let mut v = q(binom, 1);
    for _ in 0..k {
        v *= t;
    }
    for _ in 0..3 - k {
        v *= &one_minus;
    }
    v
}

fn solve4(mut m: Vec<Vec<BigRational>>, mut b: Vec<BigRational>) -> Vec<BigRational> {
    let n = b.len();
    for k in 0..n {
        let piv = (k..n).find(|&r| !m[r][k].is_zero()).unwrap();
        m.swap(k, piv);
        b.swap(k, piv);
        for r in 0..n {
            if r != k {
                let f = &m[r][k] / &m[k][k];
                for c in 0..n {
                    let v = &f * &m[k][c];
                    m[r][c] -= v;
                }
                let v = &f * &b[k];
                b[r] -= v;
            }
        }
    }
    (0..n).map(|k| &b[k] / &m[k][k]).collect()
}

/// The basis functions on [0, 4] in piecewise cubic Bézier form, the table of §6.2.4 (control
/// points at x = 0, ⅓, ⅔, 1, …, 4). Each basis function's exact limit values on the grid ¼Z
/// (N_2 S_1 S_0 e_i) determine a cubic per unit interval; its Bézier coefficients must equal the
/// table, and the values on ⅛Z (N_3 S_2 S_1 S_0 e_i) must lie on those cubics (so the limit is
/// piecewise cubic).
#[test]
fn bezier_table_on_zero_four_is_reproduced() {
    let table: [[(i64, i64); 13]; 5] = [
        [
            (1, 1),
            (2, 3),
            (1, 3),
            (1, 6),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
        ],
        [
            (0, 1),
            (1, 3),
            (2, 3),
            (2, 3),
            (2, 3),
            (1, 3),
            (1, 6),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
        ],
        [
            (0, 1),
            (0, 1),
            (0, 1),
            (1, 6),
            (1, 3),
            (2, 3),
            (2, 3),
            (2, 3),
            (1, 3),
            (1, 6),
            (0, 1),
            (0, 1),
            (0, 1),
        ],
        [
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (1, 6),
            (1, 3),
            (2, 3),
            (2, 3),
            (2, 3),
            (1, 3),
            (0, 1),
        ],
        [
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (0, 1),
            (1, 6),
            (1, 3),
            (2, 3),
            (1, 1),
        ],
    ];
    let s0 = natural_subdivision_matrix(4, 0).unwrap();
    let s1 = natural_subdivision_matrix(4, 1).unwrap();
    let s2 = natural_subdivision_matrix(4, 2).unwrap();
    let n2 = natural_interpolation_matrix(4, 2).unwrap();
    let n3 = natural_interpolation_matrix(4, 3).unwrap();
    let v2 = n2.mul(&s1).unwrap().mul(&s0).unwrap(); // 17 × 5: values on ¼Z
    let v3 = n3.mul(&s2).unwrap().mul(&s1).unwrap().mul(&s0).unwrap(); // 33 × 5: on ⅛Z
    let ts: Vec<BigRational> = (0..4).map(|k| q(k, 4)).collect();
    for (i, expect) in table.iter().enumerate() {
        let mut coeffs: Vec<BigRational> = Vec::new();
        for u in 0..4usize {
            let m: Vec<Vec<BigRational>> = ts
                .iter()
                .map(|t| (0..4).map(|k| bernstein(k, t)).collect())
                .collect();
            let b: Vec<BigRational> = (0..4).map(|k| v2.get(4 * u + k, i).clone()).collect();
            let bez = solve4(m, b);
            // The cubic must also match the 8 values of the finer grid on this interval and
            // the value at the right end.
            for k in 0..=8usize {
                let t = q(k as i64, 8);
                let val: BigRational = (0..4).map(|c| &bez[c] * bernstein(c, &t)).sum();
                assert_eq!(&val, v3.get(8 * u + k, i), "basis {i}, interval {u}, t={t}");
            }
            if u > 0 {
                assert_eq!(coeffs.last().unwrap(), &bez[0], "continuity at x={u}");
                coeffs.extend_from_slice(&bez[1..]);
            } else {
                coeffs.extend_from_slice(&bez);
            }
        }
        let expect: Vec<BigRational> = expect.iter().map(|&(n, d)| q(n, d)).collect();
        assert_eq!(coeffs, expect, "basis function {i}");
    }
}

/// Independent solver: the natural cubic spline through y_0..y_L at the integers (second
/// derivatives M from M_{i−1} + 4M_i + M_{i+1} = 6Δ²y_i, M_0 = M_L = 0, dense Gaussian
/// elimination) and its energy ∫ s''² = Σ (M_i² + M_i M_{i+1} + M_{i+1}²)/3.
fn natural_spline_energy(y: &[f64]) -> f64 {
    let l = y.len() - 1;
    if l < 2 {
        return 0.0;
    }
    let n = l - 1;
    let mut a = vec![vec![0.0; n]; n];
    let mut b = vec![0.0; n];
    for r in 0..n {
        let i = r + 1;
        a[r][r] = 4.0;
        if r > 0 {
            a[r][r - 1] = 1.0;
        }
        if r + 1 < n {
            a[r][r + 1] = 1.0;
        }
        b[r] = 6.0 * (y[i + 1] - 2.0 * y[i] + y[i - 1]);
    }
    for k in 0..n {
        for r in k + 1..n {
            let f = a[r][k] / a[k][k];
            for c in k..n {
                a[r][c] -= f * a[k][c];
            }
            b[r] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| a[k][c] * x[c]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    let mut m = vec![0.0];
    m.extend(x);
    m.push(0.0);
    (0..l)
        .map(|i| (m[i] * m[i] + m[i] * m[i + 1] + m[i + 1] * m[i + 1]) / 3.0)
        .sum()
}

/// Relative tolerance for energies: sums of O(L 2^k) squares of O(1) numbers in f64.
const ENERGY_RTOL: f64 = 1e-11;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// p_kᵀE_kp_k decreases monotonically toward p_0ᵀE_0N_0p_0, which equals ∫ s''² of the
    /// natural cubic spline through N_0 p_0 (independent solver), in R^1..R^3.
    #[test]
    fn energies_decrease_to_the_exact_limit_energy(
        l in 2usize..9,
        dim in 1usize..4,
        vals in proptest::collection::vec(-3.0f64..3.0, 27),
    ) {
        let scheme = NaturalScheme::new().unwrap();
        let p0 = Points::new(dim, vals[..(l + 1) * dim].to_vec()).unwrap();
        let levels = scheme.subdivide_levels(&p0, 6).unwrap();
        let e: Vec<f64> = levels.iter().enumerate().map(|(k, p)| NaturalScheme::energy(p, k)).collect();
        let exact = scheme.limit_energy(&p0).unwrap();
        let values = scheme.limit_values(&p0).unwrap();
        let independent: f64 = (0..dim)
            .map(|d| natural_spline_energy(&values.iter().map(|p| p[d]).collect::<Vec<_>>()))
            .sum();
        prop_assert!((exact - independent).abs() <= ENERGY_RTOL * independent.max(1.0),
            "Theorem 6.4 {} vs spline {}", exact, independent);
        let tol = ENERGY_RTOL * e[0].max(1.0);
        for k in 0..6 {
            prop_assert!(e[k + 1] <= e[k] + tol, "not decreasing at {}: {:?}", k, e);
            prop_assert!(e[k + 1] >= exact - tol, "below the limit at {}: {:?} < {}", k, e, exact);
        }
        // The gap shrinks by about 4 per level (error O(h²)); it must at least halve.
        let gap = |k: usize| e[k] - exact;
        if gap(0) > 1e-6 * e[0].max(1.0) {
            prop_assert!(gap(6) <= gap(0) / 64.0 + tol, "gaps {:?} / {}", e, exact);
        }
    }

    /// Interpolation via N⁻¹ (Fig. 6.7): the limit of p_0 = N⁻¹ b takes the values b on the
    /// integers, and the level-k points at the integers converge to them.
    #[test]
    fn interpolation_through_inverse_of_n(
        l in 1usize..12,
        vals in proptest::collection::vec(-3.0f64..3.0, 26),
    ) {
        let scheme = NaturalScheme::new().unwrap();
        let b = Points::new(2, vals[..(l + 1) * 2].to_vec()).unwrap();
        let p0 = scheme.interpolate(&b).unwrap();
        let back = scheme.limit_values(&p0).unwrap();
        for (x, y) in back.coords().iter().zip(b.coords()) {
            prop_assert!((x - y).abs() <= 1e-13);
        }
        let levels = scheme.subdivide_levels(&p0, 8).unwrap();
        let dist = |k: usize| -> f64 {
            (0..=l).map(|i| {
                let p = levels[k].point(i << k);
                ((p[0] - b.point(i)[0]).powi(2) + (p[1] - b.point(i)[1]).powi(2)).sqrt()
            }).fold(0.0, f64::max)
        };
        prop_assert!(dist(8) <= dist(0) / 100.0 + 1e-12, "{} -> {}", dist(0), dist(8));
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    use subdivision::Error;
    let scheme = NaturalScheme::new().unwrap();
    let one = Points::from_rows(&[[1.0]]).unwrap();
    assert!(matches!(
        scheme.subdivide_levels(&one, 1),
        Err(Error::TooFew {
            field: "points",
            ..
        })
    ));
    let two = Points::from_rows(&[[1.0], [2.0]]).unwrap();
    assert!(matches!(
        scheme.subdivide_levels(&two, 64),
        Err(Error::TooLarge { .. })
    ));
    assert!(matches!(
        natural_subdivision_matrix(0, 0),
        Err(Error::TooFew {
            field: "intervals",
            ..
        })
    ));
    assert!(matches!(
        natural_subdivision_matrix(300, 1),
        Err(Error::TooLarge { .. })
    ));
}
