//! `SymBand`: reconstruction, dense comparison, aliasing, elimination, errors.

use super::*;
use crate::{Error, FactorOptions, SymBand, Topology};
use nalgebra::DMatrix;

/// The SymBand holding the dense band matrix `a` (each position added once), checked entry by
/// entry against `a` through `get`.
fn band_of<const W: usize>(a: &DMatrix<f64>, topology: Topology) -> SymBand<W> {
    let n = a.nrows();
    let mut s = SymBand::<W>::zeros(n, topology);
    for i in 0..n {
        for j in i..n {
            let v = a[(i, j)];
            if v != 0.0 {
                s.add(i, j, v).expect("random matrices stay in the band");
            }
        }
    }
    for i in 0..n {
        for j in 0..n {
            assert_eq!(s.get(i, j).unwrap(), a[(i, j)], "get({i}, {j})");
        }
    }
    s
}

/// Factor, rebuild L D Lᵀ densely and compare with A entry by entry against the rounding bound
/// γ · (|L| |D| |Lᵀ|)_ij of LDLᵀ (Higham, *Accuracy and Stability of Numerical Algorithms*,
/// 2nd ed., Theorem 10.3 / §10.4.1), then solve several right-hand sides and compare with
/// nalgebra's dense LU.
fn check<const W: usize>(n: usize, cyclic: bool, cond: Conditioning, seed: u64) {
    let mut rng = Rng::new(seed);
    let a = random_spd(n, 1, W, cyclic, cond, &mut rng);
    let top = if cyclic {
        Topology::Cyclic
    } else {
        Topology::Open
    };
    let s = band_of::<W>(&a, top);
    let opts = FactorOptions::default().pivot_rtol(0.0);
    let f = s
        .factor_with(&opts)
        .unwrap_or_else(|e| panic!("W={W} n={n} {top:?} {cond:?}: {e}"));
    let (l, dv) = f.dense_factors();
    let dm = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(dv.clone()));
    let rec = &l * &dm * l.transpose();
    let bound = l.abs() * dm.abs() * l.transpose().abs();
    let gamma = 8.0 * (n as f64 + 4.0) * EPS;
    for i in 0..n {
        for j in 0..n {
            let err = (rec[(i, j)] - a[(i, j)]).abs();
            assert!(
                err <= gamma * bound[(i, j)] + f64::MIN_POSITIVE,
                "W={W} n={n} {top:?} {cond:?}: |LDLᵀ − A|({i},{j}) = {err:e} > {:e}",
                gamma * bound[(i, j)]
            );
        }
    }
    for ncols in [1, 2, 3, 4, 5] {
        let b = rhs(n, ncols, &mut rng);
        let mut x = b.clone();
        f.solve_in_place(&mut x, ncols).unwrap();
        let be = backward_error(&a, &x, &b, ncols);
        // Componentwise backward error of a banded LDLᵀ solve: a small multiple of ε where the
        // pivots grow little (SPD), |L||D||Lᵀ| ≈ |A| (Higham Theorem 10.4).
        assert!(
            be <= 64.0 * (n as f64 + 4.0) * EPS,
            "W={W} n={n} {top:?} {cond:?} ncols={ncols}: backward error {be:e}"
        );
        if n > 0 {
            let y = dense_solve(&a, &b, ncols);
            let kappa = condition(&a);
            let diff = relative_difference(&x, &y);
            assert!(
                diff <= 64.0 * (n as f64 + 4.0) * EPS * kappa,
                "W={W} n={n} {top:?} {cond:?}: differs from the dense solve by {diff:e} (κ = {kappa:e})"
            );
        }
    }
}

fn sweep<const W: usize>() {
    for cyclic in [false, true] {
        for cond in [Conditioning::Dominant, Conditioning::Ill] {
            for n in (0..=12).chain([17, 40]) {
                for seed in 0..3 {
                    check::<W>(n, cyclic, cond, 1000 * n as u64 + seed + 7 * W as u64);
                }
            }
        }
    }
}

#[test]
fn tridiagonal_reconstructs_and_solves() {
    sweep::<1>();
}

#[test]
fn pentadiagonal_reconstructs_and_solves() {
    sweep::<2>();
}

#[test]
fn heptadiagonal_reconstructs_and_solves() {
    sweep::<3>();
}

#[test]
fn half_bandwidth_four_reconstructs_and_solves() {
    sweep::<4>();
}

#[test]
fn ill_conditioned_instances_reach_condition_1e12() {
    // The "Ill" generator must actually produce the hard cases the sweeps claim to cover.
    let mut worst = 0.0f64;
    for (n, cyclic) in [(8, false), (8, true), (17, true), (40, false)] {
        let mut rng = Rng::new(n as u64);
        let a = random_spd(n, 1, 2, cyclic, Conditioning::Ill, &mut rng);
        worst = worst.max(condition(&a));
        assert!(
            condition(&a) >= 1e10,
            "n={n} cyclic={cyclic}: κ = {:e}",
            condition(&a)
        );
    }
    assert!(worst >= 1e12, "largest condition {worst:e}");
}

#[test]
fn aliasing_entries_of_small_cyclic_bands_add_up() {
    // n = 3, W = 2: off[j][0] and off[j][1] name the two other rows; every position is named
    // twice, and an entry with j + k ≡ j (n = 1, 2) lands on the diagonal twice.
    let a = SymBand::<2>::from_bands(
        Topology::Cyclic,
        vec![10.0, 20.0, 30.0],
        vec![[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]],
    )
    .unwrap();
    // A_01 = off[0][0] (0→1) + off[1][1] (1→3≡0) = 1 + 4.
    assert_eq!(a.get(0, 1).unwrap(), 5.0);
    assert_eq!(a.get(1, 0).unwrap(), 5.0);
    assert_eq!(a.get(0, 2).unwrap(), 2.0 + 5.0);
    assert_eq!(a.get(1, 2).unwrap(), 3.0 + 6.0);
    let one = SymBand::<2>::from_bands(Topology::Cyclic, vec![1.0], vec![[0.5, 0.25]]).unwrap();
    assert_eq!(one.get(0, 0).unwrap(), 1.0 + 2.0 * 0.5 + 2.0 * 0.25);
    // mul_add agrees with get on every aliasing pattern (the factor is tested against get).
    for n in 1..=8 {
        let mut rng = Rng::new(n as u64);
        let diag: Vec<f64> = (0..n).map(|_| rng.range(5.0, 6.0)).collect();
        let off: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                [
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ]
            })
            .collect();
        let s = SymBand::<3>::from_bands(Topology::Cyclic, diag, off).unwrap();
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let mut col = vec![0.0; n];
            s.mul_add(&e, &mut col, 1).unwrap();
            for i in 0..n {
                assert!(
                    (col[i] - s.get(i, j).unwrap()).abs() < 1e-15,
                    "n={n} ({i},{j})"
                );
            }
        }
        // And the factor solves that matrix (diagonally dominant by construction).
        let f = s.factor().unwrap();
        let b: Vec<f64> = (0..n).map(|i| i as f64 + 1.0).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x, 1).unwrap();
        let mut ax = vec![0.0; n];
        s.mul_add(&x, &mut ax, 1).unwrap();
        assert!(relative_difference(&ax, &b) < 1e-14, "n={n}");
    }
}

#[test]
fn eliminated_rows_become_identity_rows() {
    for cyclic in [false, true] {
        for n in [1, 2, 3, 5, 9, 30] {
            let mut rng = Rng::new(n as u64 + 100);
            let a = random_spd(n, 1, 2, cyclic, Conditioning::Dominant, &mut rng);
            let top = if cyclic {
                Topology::Cyclic
            } else {
                Topology::Open
            };
            let s = band_of::<2>(&a, top);
            let elim: Vec<bool> = (0..n).map(|i| i % 3 == 1 || i + 1 == n).collect();
            let mut reduced = a.clone();
            for i in 0..n {
                if elim[i] {
                    for j in 0..n {
                        reduced[(i, j)] = 0.0;
                        reduced[(j, i)] = 0.0;
                    }
                    reduced[(i, i)] = 1.0;
                }
            }
            let f = s
                .factor_with(&FactorOptions::default().eliminated(&elim))
                .unwrap();
            let b = rhs(n, 2, &mut rng);
            let mut x = b.clone();
            f.solve_in_place(&mut x, 2).unwrap();
            let y = dense_solve(&reduced, &b, 2);
            assert!(relative_difference(&x, &y) < 1e-13, "n={n} cyclic={cyclic}");
            for i in (0..n).filter(|&i| elim[i]) {
                assert_eq!(&x[2 * i..2 * i + 2], &b[2 * i..2 * i + 2]);
            }
        }
    }
}

#[test]
fn failing_pivots_are_typed_errors_naming_the_row() {
    // Open: the 2×2 leading block [[1, 2], [2, 1]] is indefinite: row 1's pivot is 1 − 4 < 0.
    let mut a = SymBand::<1>::zeros(4, Topology::Open);
    for i in 0..4 {
        a.add(i, i, 1.0).unwrap();
    }
    a.add(0, 1, 2.0).unwrap();
    assert_eq!(a.factor().unwrap_err(), Error::Singular { index: 1 });
    // The same through the general (W = 2) path.
    let mut a2 = SymBand::<2>::zeros(4, Topology::Open);
    for i in 0..4 {
        a2.add(i, i, 1.0).unwrap();
    }
    a2.add(0, 1, 2.0).unwrap();
    assert_eq!(a2.factor().unwrap_err(), Error::Singular { index: 1 });
    // A zero row deep inside, and NaN.
    let mut z = SymBand::<2>::zeros(8, Topology::Open);
    for i in 0..8 {
        z.add(i, i, if i == 5 { 0.0 } else { 2.0 }).unwrap();
    }
    assert_eq!(z.factor().unwrap_err(), Error::Singular { index: 5 });
    z.diag_mut()[5] = f64::NAN;
    assert_eq!(z.factor().unwrap_err(), Error::Singular { index: 5 });
    // Cyclic: the singular energy-like matrix (second differences, kernel = constants) fails in
    // the border, at the last row, because everything before it is definite.
    let n = 10;
    let mut c = SymBand::<1>::zeros(n, Topology::Cyclic);
    for i in 0..n {
        c.add(i, i, 2.0).unwrap();
        c.add(i, (i + 1) % n, -1.0).unwrap();
    }
    assert_eq!(c.factor().unwrap_err(), Error::Singular { index: n - 1 });
    // Relative, not absolute: the same matrix scaled by 1e-200 factors (pinned by a weight).
    let mut tiny = c.clone();
    tiny.add(0, 0, 1.0).unwrap();
    for v in tiny.diag_mut() {
        *v *= 1e-200;
    }
    for o in tiny.off_mut() {
        o[0] *= 1e-200;
    }
    assert!(tiny.factor().is_ok());
    // A matrix with condition ~1e15 fails the default relative test but passes with 0.
    let mut rng = Rng::new(5);
    let mut worst = SymBand::<1>::zeros(3, Topology::Open);
    let _ = rng.next();
    worst.add(0, 0, 1.0).unwrap();
    worst.add(1, 1, 1.0).unwrap();
    worst.add(0, 1, 1.0 - 1e-15).unwrap();
    worst.add(2, 2, 1.0).unwrap();
    assert_eq!(worst.factor().unwrap_err(), Error::Singular { index: 1 });
    assert!(worst
        .factor_with(&FactorOptions::default().pivot_rtol(0.0))
        .is_ok());
}

#[test]
fn bad_arguments_are_typed_errors() {
    let mut a = SymBand::<2>::zeros(6, Topology::Open);
    assert_eq!(
        a.add(0, 3, 1.0).unwrap_err(),
        Error::OutsideBand {
            row: 0,
            col: 3,
            half_bandwidth: 2
        }
    );
    assert_eq!(
        a.add(6, 0, 1.0).unwrap_err(),
        Error::IndexOutOfRange {
            field: "row",
            index: 6,
            len: 6
        }
    );
    // Cyclic: 0 and 5 are neighbours, 0 and 3 are not.
    let mut c = SymBand::<2>::zeros(6, Topology::Cyclic);
    assert!(c.add(0, 5, 1.0).is_ok() && c.add(4, 0, 1.0).is_ok());
    assert!(matches!(c.add(0, 3, 1.0), Err(Error::OutsideBand { .. })));
    assert_eq!(
        SymBand::<1>::from_bands(Topology::Open, vec![1.0; 3], vec![[0.0]; 2]).unwrap_err(),
        Error::WrongLength {
            field: "off",
            expected: 3,
            got: 2
        }
    );
    for i in 0..6 {
        c.add(i, i, 4.0).unwrap();
    }
    let f = c.factor().unwrap();
    let mut x = vec![0.0; 7];
    assert_eq!(
        f.solve_in_place(&mut x, 1).unwrap_err(),
        Error::WrongLength {
            field: "x",
            expected: 6,
            got: 7
        }
    );
    assert!(matches!(
        c.factor_with(&FactorOptions::default().eliminated(&[false; 5])),
        Err(Error::WrongLength {
            field: "eliminated",
            ..
        })
    ));
    let mut y = vec![0.0; 6];
    assert!(c.mul_add(&x, &mut y, 1).is_err());
}

#[test]
fn long_cyclic_bands_store_a_short_border() {
    // A well-conditioned cyclic band: the border decays geometrically and is flushed, so only
    // rows near both ends carry it; the solve still matches the matrix to rounding.
    for n in [200, 5000] {
        let mut rng = Rng::new(n as u64);
        let mut s = SymBand::<2>::zeros(n, Topology::Cyclic);
        for i in 0..n {
            s.add(i, i, rng.range(6.0, 7.0)).unwrap();
            s.add(i, (i + 1) % n, rng.range(-1.0, 1.0)).unwrap();
            s.add(i, (i + 2) % n, rng.range(-1.0, 1.0)).unwrap();
        }
        let f = s.factor().unwrap();
        let (head, tail) = f.border_rows();
        assert!(
            head < 200.min(n - 2) && tail == n - 4,
            "n={n}: border rows [0,{head}) ∪ [{tail},{})",
            n - 2
        );
        let b = rhs(n, 3, &mut rng);
        let mut x = b.clone();
        f.solve_in_place(&mut x, 3).unwrap();
        let mut ax = vec![0.0; 3 * n];
        s.mul_add(&x, &mut ax, 3).unwrap();
        assert!(relative_difference(&ax, &b) < 1e-14, "n={n}");
    }
    // A nearly singular one (a tiny weight on the cyclic second difference): the border does
    // not decay, is stored on every row, and the solve is still right.
    let n = 300;
    let mut s = SymBand::<1>::zeros(n, Topology::Cyclic);
    for i in 0..n {
        s.add(i, i, 2.0 + 1e-9).unwrap();
        s.add(i, (i + 1) % n, -1.0).unwrap();
    }
    let f = s.factor().unwrap();
    assert_eq!(f.border_rows(), (n - 1, n - 1));
    let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
    let mut x = b.clone();
    f.solve_in_place(&mut x, 1).unwrap();
    // κ ≈ 4e9 here: judge the backward error, and the forward error against the dense LU.
    let dense = DMatrix::from_fn(n, n, |i, j| s.get(i, j).unwrap());
    let be = backward_error(&dense, &x, &b, 1);
    assert!(be < 1e-13, "backward error {be:e}");
    let y = dense_solve(&dense, &b, 1);
    assert!(relative_difference(&x, &y) < 64.0 * n as f64 * EPS * condition(&dense));
}

#[test]
fn refactoring_reuses_the_factor() {
    let mut rng = Rng::new(3);
    let a = random_spd(20, 1, 2, true, Conditioning::Dominant, &mut rng);
    let s = band_of::<2>(&a, Topology::Cyclic);
    let mut f = crate::SymBandFactor::default();
    s.factor_into(&FactorOptions::default(), &mut f).unwrap();
    let b = rhs(20, 1, &mut rng);
    let mut x1 = b.clone();
    f.solve_in_place(&mut x1, 1).unwrap();
    // Refactor a different matrix into the same factor, then the first again.
    let a2 = random_spd(20, 1, 2, true, Conditioning::Ill, &mut rng);
    let s2 = band_of::<2>(&a2, Topology::Cyclic);
    s2.factor_into(&FactorOptions::default().pivot_rtol(0.0), &mut f)
        .unwrap();
    s.factor_into(&FactorOptions::default(), &mut f).unwrap();
    let mut x2 = b.clone();
    f.solve_in_place(&mut x2, 1).unwrap();
    assert_eq!(x1, x2);
}

#[test]
fn a_failed_refactor_leaves_an_empty_factor() {
    let mut good = SymBand::<2>::zeros(6, Topology::Cyclic);
    for i in 0..6 {
        good.add(i, i, 4.0).unwrap();
    }
    let mut bad = good.clone();
    bad.diag_mut()[2] = -1.0;
    let mut f = good.factor().unwrap();
    assert_eq!(
        bad.factor_into(&FactorOptions::default(), &mut f),
        Err(Error::Singular { index: 2 })
    );
    assert!(f.is_empty());
    assert!(matches!(
        f.solve_in_place(&mut [1.0; 6], 1),
        Err(Error::WrongLength { .. })
    ));
    let mut gb = crate::BlockBand::from_scalar(good, 2).unwrap();
    let mut fb = gb.factor().unwrap();
    gb.add(2, 2, &[-9.0, 0.0, 0.0, -9.0]).unwrap();
    assert!(gb.factor_into(&FactorOptions::default(), &mut fb).is_err());
    assert!(fb.is_empty());
    assert!(fb.solve_in_place(&mut [1.0; 12], 1).is_err());
}
