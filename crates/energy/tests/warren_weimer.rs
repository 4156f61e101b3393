//! Warren–Weimer §6.2: E_k = 8^k D₂ᵀD₂ equals Kersey's open-curve H on uniform knots of
//! spacing 2^{−k}.

use divdiff::{Knots, Points};
use energy::{energy, warren_weimer_matrix, Hessian};
use nalgebra::DMatrix;

/// E_k row by row from the stencils printed in math.md §5 (independent of D₂ᵀD₂):
/// boundary rows (1, −2, 1) and (−2, 5, −4, 1), interior rows (1, −4, 6, −4, 1), times 8^k.
fn stencil_matrix(n: usize, k: u32) -> DMatrix<f64> {
    assert!(n >= 5);
    let mut m = DMatrix::zeros(n, n);
    let put = |m: &mut DMatrix<f64>, r: usize, c0: usize, row: &[f64]| {
        for (j, v) in row.iter().enumerate() {
            m[(r, c0 + j)] = *v;
        }
    };
    put(&mut m, 0, 0, &[1.0, -2.0, 1.0]);
    put(&mut m, 1, 0, &[-2.0, 5.0, -4.0, 1.0]);
    for r in 2..n - 2 {
        put(&mut m, r, r - 2, &[1.0, -4.0, 6.0, -4.0, 1.0]);
    }
    put(&mut m, n - 2, n - 4, &[1.0, -4.0, 5.0, -2.0]);
    put(&mut m, n - 1, n - 3, &[1.0, -2.0, 1.0]);
    m * 8f64.powi(k as i32)
}

fn uniform_open(n: usize, k: u32) -> Knots {
    let h = 0.5f64.powi(k as i32);
    Knots::open((0..n).map(|i| 0.75 + i as f64 * h).collect()).unwrap()
}

#[test]
fn kersey_h_on_dyadic_knots_is_e_k() {
    for k in 0..=5 {
        for n in 3..=12 {
            let ek = warren_weimer_matrix(n, k).unwrap();
            let h = Hessian::new(&uniform_open(n, k)).to_dense();
            let err = (&ek - &h).amax();
            assert!(err <= 1e-13 * ek.amax(), "n={n} k={k}: |E_k − H| = {err}");
            if n >= 5 {
                let st = stencil_matrix(n, k);
                assert!((&st - &ek).amax() <= 1e-13 * ek.amax(), "n={n} k={k}");
            }
        }
    }
}

/// The energies differ by ½: Kersey's E = ½pᵀHp, Warren–Weimer's pᵀE_k p.
#[test]
fn energies_differ_by_one_half() {
    let (n, k) = (9, 3);
    let p: Vec<f64> = (0..n).map(|i| ((i * i) % 7) as f64 - 2.5).collect();
    let ek = warren_weimer_matrix(n, k).unwrap();
    let v = nalgebra::DVector::from_column_slice(&p);
    let ww = (v.transpose() * &ek * &v)[(0, 0)];
    let kersey = energy(&uniform_open(n, k), &Points::new(1, p).unwrap()).unwrap();
    assert!((kersey - 0.5 * ww).abs() <= 1e-12 * ww.abs());
}

#[test]
fn too_small_grids_are_errors() {
    assert!(matches!(
        warren_weimer_matrix(2, 0),
        Err(energy::Error::WrongLength { field: "n", .. })
    ));
}
