//! H = AᵀA, symmetry, the band layout, and E = ½ pᵀHp against the direct sum (2.1).

mod common;

use common::{max_abs, norm2, problem};
use divdiff::{Knots, Points};
use energy::{alpha_matrix, alphas, energy, Hessian};
use nalgebra::DMatrix;
use proptest::prelude::*;

/// Relative round-off budget for O(N) sums of products of O(1/h³) terms.
const REL_TOL: f64 = 1e-12;

fn column(p: &Points, c: usize) -> nalgebra::DVector<f64> {
    nalgebra::DVector::from_iterator(p.len(), p.iter().map(|x| x[c]))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn h_equals_at_a_and_is_symmetric(pr in problem(2..=12)) {
        let a = alpha_matrix(&pr.knots);
        let h = Hessian::new(&pr.knots).to_dense();
        let ata = a.transpose() * &a;
        let scale = ata.amax().max(f64::MIN_POSITIVE);
        prop_assert!((&ata - &h).amax() <= REL_TOL * scale, "|AᵀA − H| = {}", (&ata - &h).amax());
        prop_assert!((&h - h.transpose()).amax() <= REL_TOL * scale);
        // Rows of A sum to zero (the scheme reproduces constants).
        for row in alphas(&pr.knots) {
            prop_assert!(row.iter().sum::<f64>().abs() <= REL_TOL * max_abs(&row));
        }
    }

    /// The rows read off the knot values equal Kersey's formula through `Knots::h` (its periodic
    /// index), bit for bit, open and closed.
    #[test]
    fn alphas_are_the_formula_through_knots_h(pr in problem(2..=12)) {
        let k = &pr.knots;
        let n = k.vertex_count();
        let rows: Vec<usize> = if k.is_closed() { (0..n).collect() } else { (1..n - 1).collect() };
        for (i, got) in alphas(k).iter().enumerate() {
            let want = if rows.contains(&i) {
                let (hl, hr) = (k.h(i as isize - 1), k.h(i as isize));
                let root = (2.0 / (hl + hr)).sqrt();
                [root / hl, -root / hl - root / hr, root / hr]
            } else {
                [0.0; 3]
            };
            prop_assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "row {}", i);
        }
    }

    /// H's bands are AᵀA summed row by row in increasing row order (the reference scatter,
    /// indices mod N), bit for bit.
    #[test]
    fn hessian_bands_are_the_row_by_row_sums(pr in problem(2..=12)) {
        let k = &pr.knots;
        let n = k.vertex_count();
        let rows: Vec<usize> = if k.is_closed() { (0..n).collect() } else { (1..n - 1).collect() };
        let (mut d0, mut d1, mut d2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let a = alphas(k);
        for &i in &rows {
            let [a0, a1, a2] = a[i];
            let (l, r) = ((i + n - 1) % n, (i + 1) % n);
            d0[l] += a0 * a0;
            d0[i] += a1 * a1;
            d0[r] += a2 * a2;
            d1[l] += a0 * a1;
            d1[i] += a1 * a2;
            d2[l] += a0 * a2;
        }
        let h = Hessian::new(k);
        let (g0, g1, g2) = h.bands();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!(bits(g0), bits(&d0));
        prop_assert_eq!(bits(g1), bits(&d1));
        prop_assert_eq!(bits(g2), bits(&d2));
    }

    #[test]
    fn apply_matches_dense_product(pr in problem(2..=12)) {
        let hess = Hessian::new(&pr.knots);
        let h = hess.to_dense();
        let hp = hess.apply(&pr.points);
        for c in 0..pr.points.dim() {
            let want = &h * column(&pr.points, c);
            let got = column(&hp, c);
            let scale = h.amax() * max_abs(pr.points.coords());
            prop_assert!((want - got).amax() <= REL_TOL * scale);
        }
    }

    #[test]
    fn half_pthp_equals_direct_energy(pr in problem(2..=12)) {
        let hess = Hessian::new(&pr.knots);
        let e_direct = energy(&pr.knots, &pr.points).unwrap();
        let e_quad = hess.energy(&pr.points).unwrap();
        // Both are sums of O(N) terms bounded by |H|·|p|².
        let scale = hess.max_abs() * norm2(pr.points.coords());
        prop_assert!((e_direct - e_quad).abs() <= REL_TOL * scale, "{e_direct} vs {e_quad}");
        prop_assert!(e_direct >= 0.0);
    }
}

#[test]
fn open_bands_vanish_past_the_end() {
    let knots = Knots::open(vec![0.0, 0.3, 1.0, 1.2, 2.5, 2.6]).unwrap();
    let h = Hessian::new(&knots);
    let (_, o1, o2) = h.bands();
    let n = h.len();
    assert!(o1[n - 1].abs() + o2[n - 2].abs() + o2[n - 1].abs() <= 0.0);
    assert!(
        o2[0].abs() > 0.0,
        "the (0, 2) entry of an open H is non-zero"
    );
}

/// Closed curves with N = 3 and N = 4: bands alias (off2[j] sits at (j, j − 1) for N = 3, and
/// off2[j], off2[j + 2] share (j, j + 2) for N = 4); the dense export must still equal AᵀA.
#[test]
fn small_closed_curves_alias_bands_correctly() {
    for t in [vec![0.0, 0.4, 1.5, 2.0], vec![0.0, 0.4, 1.5, 2.0, 3.7]] {
        let knots = Knots::closed(t).unwrap();
        let a = alpha_matrix(&knots);
        let h = Hessian::new(&knots).to_dense();
        let ata = a.transpose() * &a;
        assert!((&ata - &h).amax() <= REL_TOL * ata.amax());
        // And apply agrees with the dense product.
        let p = Points::new(
            1,
            (0..knots.vertex_count())
                .map(|i| (i * i) as f64 + 0.5)
                .collect(),
        )
        .unwrap();
        let hp = Hessian::new(&knots).apply(&p);
        let want: DMatrix<f64> = &h * DMatrix::from_column_slice(p.len(), 1, p.coords());
        for i in 0..p.len() {
            assert!((hp.coords()[i] - want[(i, 0)]).abs() <= REL_TOL * h.amax() * 20.0);
        }
    }
}

/// The periodic extension h_{−1} = h_{N−1}: row 0 of a closed A uses the closing span, so on
/// non-uniform knots it differs from the printed shortcut α_{1,1} := α_{n,3}.
#[test]
fn closed_first_row_uses_the_closing_span() {
    let knots = Knots::closed(vec![0.0, 1.0, 1.5, 4.0]).unwrap();
    let a = alphas(&knots);
    let (h_last, h0) = (2.5f64, 1.0f64);
    let want = (2.0f64).sqrt() / (h_last * (h_last + h0).sqrt());
    assert!((a[0][0] - want).abs() <= 1e-15);
    let printed_shortcut = a[2][2];
    assert!(
        (a[0][0] - printed_shortcut).abs() > 1e-3,
        "shortcut differs on non-uniform knots"
    );
}

#[test]
fn apply_reports_size_mismatch() {
    let h = Hessian::new(&Knots::open(vec![0.0, 1.0, 2.0]).unwrap());
    let err = h.try_apply(&Points::zeros(4, 2)).unwrap_err();
    assert_eq!(
        err,
        energy::Error::WrongLength {
            field: "points",
            expected: 3,
            got: 4
        }
    );
}
