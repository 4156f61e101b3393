//! `BlockBand`: reconstruction, dense comparison, aliasing, elimination, errors.

use super::*;
use crate::{BlockBand, Error, FactorOptions, SymBand, Topology};
use nalgebra::DMatrix;

/// The BlockBand holding the dense block band matrix `a` (n blocks of size d), split into a
/// random scalar part S ⊗ I_d and the blocks B = A − S ⊗ I_d, checked block by block against
/// `a` through `get`.
fn block_band_of<const W: usize>(
    a: &DMatrix<f64>,
    n: usize,
    d: usize,
    topology: Topology,
    rng: &mut Rng,
) -> BlockBand<W> {
    let mut s = SymBand::<W>::zeros(n, topology);
    let mut bb = a.clone();
    // S: a random symmetric scalar band on the positions of the band (aliasing included).
    for i in 0..n {
        for j in i..n {
            if (0..d).any(|c| a[(i * d + c, j * d + c)] != 0.0) && s.add(i, j, 0.0).is_ok() {
                let v = rng.range(-0.5, 0.5);
                s.add(i, j, v).unwrap();
                for c in 0..d {
                    bb[(i * d + c, j * d + c)] -= v;
                    if i != j {
                        bb[(j * d + c, i * d + c)] -= v;
                    }
                }
            }
        }
    }
    let mut m = BlockBand::from_scalar(s, d).unwrap();
    for i in 0..n {
        for j in i..n {
            let blk: Vec<f64> = (0..d * d)
                .map(|e| bb[(i * d + e / d, j * d + e % d)])
                .collect();
            if blk.iter().any(|&v| v != 0.0) {
                m.add(i, j, &blk).expect("random matrices stay in the band");
            }
        }
    }
    let mut out = vec![0.0; d * d];
    for i in 0..n {
        for j in 0..n {
            m.get(i, j, &mut out).unwrap();
            for e in 0..d * d {
                let want = a[(i * d + e / d, j * d + e % d)];
                assert!(
                    (out[e] - want).abs() <= 1e-15 * want.abs().max(1.0),
                    "get({i}, {j})[{e}] = {} vs {want}",
                    out[e]
                );
            }
        }
    }
    m
}

/// Factor, rebuild L Lᵀ densely and compare with A entry by entry against the rounding bound
/// γ · (|L| |Lᵀ|)_ij of Cholesky (Higham, *Accuracy and Stability of Numerical Algorithms*,
/// 2nd ed., Theorem 10.3), then solve several right-hand sides against nalgebra's dense LU.
fn check<const W: usize>(n: usize, d: usize, cyclic: bool, cond: Conditioning, seed: u64) {
    let mut rng = Rng::new(seed);
    let a = random_spd(n, d, W, cyclic, cond, &mut rng);
    let top = if cyclic {
        Topology::Cyclic
    } else {
        Topology::Open
    };
    let m = block_band_of::<W>(&a, n, d, top, &mut rng);
    // The matrix actually factored is the one `get` reports (the split rounds).
    let mut got = DMatrix::<f64>::zeros(n * d, n * d);
    let mut out = vec![0.0; d * d];
    for i in 0..n {
        for j in 0..n {
            m.get(i, j, &mut out).unwrap();
            for e in 0..d * d {
                got[(i * d + e / d, j * d + e % d)] = out[e];
            }
        }
    }
    let f = m
        .factor_with(&FactorOptions::default().pivot_rtol(0.0))
        .unwrap_or_else(|e| panic!("W={W} n={n} d={d} {top:?} {cond:?}: {e}"));
    let l = f.dense_factor();
    let rec = &l * l.transpose();
    let bound = l.abs() * l.transpose().abs();
    let nd = n * d;
    let gamma = 8.0 * (nd as f64 + 4.0) * EPS;
    for i in 0..nd {
        for j in 0..nd {
            let err = (rec[(i, j)] - got[(i, j)]).abs();
            assert!(
                err <= gamma * bound[(i, j)] + f64::MIN_POSITIVE,
                "W={W} n={n} d={d} {top:?} {cond:?}: |LLᵀ − A|({i},{j}) = {err:e} > {:e}",
                gamma * bound[(i, j)]
            );
        }
    }
    for ncols in [1, 2, 3] {
        let b = rhs(nd, ncols, &mut rng);
        let mut x = b.clone();
        f.solve_in_place(&mut x, ncols).unwrap();
        let be = backward_error(&got, &x, &b, ncols);
        assert!(
            be <= 64.0 * (nd as f64 + 4.0) * EPS,
            "W={W} n={n} d={d} {top:?} {cond:?} ncols={ncols}: backward error {be:e}"
        );
        if nd > 0 {
            let y = dense_solve(&got, &b, ncols);
            let kappa = condition(&got);
            let diff = relative_difference(&x, &y);
            assert!(
                diff <= 64.0 * (nd as f64 + 4.0) * EPS * kappa,
                "W={W} n={n} d={d} {top:?} {cond:?}: differs from the dense solve by {diff:e} (κ = {kappa:e})"
            );
        }
        // mul_add is A x with the same A.
        let mut ax = vec![0.0; nd * ncols];
        m.mul_add(&x, &mut ax, ncols).unwrap();
        // Against the dense product, relative to (|S ⊗ I| + |B|)|x|: the split of A into S and
        // B cancels when A is tiny (Ill), and so do S x + B x.
        for i in 0..nd {
            for c in 0..ncols {
                let (dx, scale) = (0..nd).fold((0.0, 0.0), |(s, t), j| {
                    let sij = if i % d == j % d {
                        m.scalar().get(i / d, j / d).unwrap()
                    } else {
                        0.0
                    };
                    let v = got[(i, j)] * x[j * ncols + c];
                    let w = (sij.abs() + (got[(i, j)] - sij).abs()) * x[j * ncols + c].abs();
                    (s + v, t + w)
                });
                assert!(
                    (ax[i * ncols + c] - dx).abs() <= 8.0 * (nd as f64 + 2.0) * EPS * scale,
                    "W={W} n={n} d={d} {top:?} ncols={ncols}: mul_add row {i}: {} vs {dx}",
                    ax[i * ncols + c]
                );
            }
        }
    }
}

fn sweep<const W: usize>(dims: &[usize], sizes: &[usize]) {
    for cyclic in [false, true] {
        for cond in [Conditioning::Dominant, Conditioning::Ill] {
            for &d in dims {
                for &n in sizes {
                    for seed in 0..2 {
                        check::<W>(n, d, cyclic, cond, 7919 * n as u64 + 31 * d as u64 + seed);
                    }
                }
            }
        }
    }
}

const SMALL: [usize; 12] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 13, 25];

#[test]
fn block_tridiagonal_reconstructs_and_solves() {
    sweep::<1>(&[1, 2, 3, 4, 5], &SMALL);
}

#[test]
fn block_pentadiagonal_reconstructs_and_solves() {
    sweep::<2>(&[1, 2, 3, 4, 6], &SMALL);
}

#[test]
fn wider_block_bands_reconstruct_and_solve() {
    sweep::<3>(&[1, 2, 3], &[0, 1, 3, 5, 7, 8, 12]);
    sweep::<4>(&[1, 2, 5], &[0, 1, 4, 8, 9, 10, 15]);
}

#[test]
fn eliminated_block_rows_become_identity_rows() {
    for cyclic in [false, true] {
        for (n, d) in [(1, 2), (3, 3), (5, 2), (9, 1), (12, 5), (30, 2)] {
            let mut rng = Rng::new((n * d) as u64);
            let a = random_spd(n, d, 2, cyclic, Conditioning::Dominant, &mut rng);
            let top = if cyclic {
                Topology::Cyclic
            } else {
                Topology::Open
            };
            let m = block_band_of::<2>(&a, n, d, top, &mut rng);
            let elim: Vec<bool> = (0..n).map(|i| i % 4 == 2 || i + 1 == n).collect();
            let mut reduced = DMatrix::<f64>::zeros(n * d, n * d);
            let mut out = vec![0.0; d * d];
            for i in 0..n {
                for j in 0..n {
                    m.get(i, j, &mut out).unwrap();
                    for e in 0..d * d {
                        let (r, c) = (i * d + e / d, j * d + e % d);
                        reduced[(r, c)] = if elim[i] || elim[j] {
                            if r == c {
                                1.0
                            } else {
                                0.0
                            }
                        } else {
                            out[e]
                        };
                    }
                }
            }
            let f = m
                .factor_with(&FactorOptions::default().eliminated(&elim))
                .unwrap();
            let b = rhs(n * d, 1, &mut rng);
            let mut x = b.clone();
            f.solve_in_place(&mut x, 1).unwrap();
            let y = dense_solve(&reduced, &b, 1);
            assert!(
                relative_difference(&x, &y) < 1e-12,
                "n={n} d={d} cyclic={cyclic}"
            );
        }
    }
}

#[test]
fn failing_block_pivots_name_the_block_row() {
    // Block row 3's diagonal block [[1, 2], [2, 1]] is indefinite.
    let mut m = BlockBand::<2>::zeros(6, 2, Topology::Open).unwrap();
    for i in 0..6 {
        m.add(i, i, &[3.0, 0.0, 0.0, 3.0]).unwrap();
    }
    m.add(3, 3, &[-2.0, 2.0, 2.0, -2.0]).unwrap();
    assert_eq!(m.factor().unwrap_err(), Error::Singular { index: 3 });
    // Cyclic: H ⊗ I_2 of the cyclic second difference is singular (constants); the failure is
    // in the border's dense Schur complement, at the last block row.
    let n = 9;
    let mut c = BlockBand::<1>::zeros(n, 2, Topology::Cyclic).unwrap();
    for i in 0..n {
        c.add_scalar(i, i, 2.0).unwrap();
        c.add_scalar(i, (i + 1) % n, -1.0).unwrap();
    }
    assert_eq!(c.factor().unwrap_err(), Error::Singular { index: n - 1 });
    // With a positive semidefinite coupling block that pins only one direction it stays
    // singular; pinning both coordinates at one vertex makes it definite.
    c.add(4, 4, &[1.0, 1.0, 1.0, 1.0]).unwrap();
    assert_eq!(c.factor().unwrap_err(), Error::Singular { index: n - 1 });
    c.add(4, 4, &[1.0, -1.0, -1.0, 1.0]).unwrap();
    assert!(c.factor().is_ok());
}

#[test]
fn bad_block_arguments_are_typed_errors() {
    assert_eq!(
        BlockBand::<2>::zeros(3, 0, Topology::Open).unwrap_err(),
        Error::TooFew {
            field: "dim",
            minimum: 1,
            got: 0
        }
    );
    let mut m = BlockBand::<2>::zeros(8, 3, Topology::Cyclic).unwrap();
    assert_eq!(
        m.add(0, 0, &[1.0; 4]).unwrap_err(),
        Error::WrongLength {
            field: "block",
            expected: 9,
            got: 4
        }
    );
    assert!(m.add(0, 6, &[0.0; 9]).is_ok());
    assert_eq!(
        m.add(0, 4, &[0.0; 9]).unwrap_err(),
        Error::OutsideBand {
            row: 0,
            col: 4,
            half_bandwidth: 2
        }
    );
    assert!(matches!(
        m.add(8, 0, &[0.0; 9]),
        Err(Error::IndexOutOfRange {
            field: "row",
            index: 8,
            len: 8
        })
    ));
    let mut out = [0.0; 4];
    assert!(matches!(
        m.get(0, 0, &mut out),
        Err(Error::WrongLength { field: "out", .. })
    ));
}

#[test]
fn clear_blocks_keeps_the_scalar_part() {
    let n = 12;
    let mut m = BlockBand::<2>::zeros(n, 2, Topology::Cyclic).unwrap();
    for i in 0..n {
        m.add_scalar(i, i, 6.0).unwrap();
        m.add_scalar(i, (i + 1) % n, -1.0).unwrap();
        m.add_scalar(i, (i + 2) % n, 0.5).unwrap();
    }
    let plain = m.clone();
    for i in (0..n).step_by(3) {
        m.add(i, (i + 1) % n, &[0.3, 0.1, -0.2, 0.4]).unwrap();
        m.add(i, i, &[2.0, 0.5, 0.5, 1.0]).unwrap();
    }
    m.clear_blocks();
    let b: Vec<f64> = (0..2 * n).map(|k| (k as f64).cos()).collect();
    let (mut x, mut y) = (b.clone(), b.clone());
    m.factor().unwrap().solve_in_place(&mut x, 1).unwrap();
    plain.factor().unwrap().solve_in_place(&mut y, 1).unwrap();
    assert_eq!(x, y);
}

#[test]
fn long_cyclic_block_bands_store_a_short_border() {
    let n = 3000;
    let d = 3;
    let mut rng = Rng::new(11);
    let mut m = BlockBand::<2>::zeros(n, d, Topology::Cyclic).unwrap();
    for i in 0..n {
        m.add_scalar(i, i, 8.0).unwrap();
        m.add_scalar(i, (i + 1) % n, -1.0).unwrap();
        m.add_scalar(i, (i + 2) % n, 0.5).unwrap();
        let blk: Vec<f64> = (0..d * d).map(|_| rng.range(-0.2, 0.2)).collect();
        m.add(i, (i + 1) % n, &blk).unwrap();
    }
    let f = m.factor().unwrap();
    let (head, tail) = f.border_rows();
    assert!(
        head < 200 && tail == n - 4,
        "border rows [0,{head}) ∪ [{tail},{})",
        n - 2
    );
    let b = rhs(n * d, 2, &mut rng);
    let mut x = b.clone();
    f.solve_in_place(&mut x, 2).unwrap();
    let mut ax = vec![0.0; n * d * 2];
    m.mul_add(&x, &mut ax, 2).unwrap();
    assert!(relative_difference(&ax, &b) < 1e-14);
}
