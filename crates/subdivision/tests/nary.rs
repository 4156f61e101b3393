//! The (2m+2)-point n-ary rules of Khan et al. (seed 001, (3.13); math.md §3): the named members,
//! polynomial reproduction, partition of unity, correct rounding, and application to closed and
//! open polygons against an independent reference implementation.

// Index loops mirror the formulas (rows, columns, coordinates) in this numerical test code.
#![allow(clippy::needless_range_loop)]

use divdiff::{Points, Topology};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Pow, Signed, Zero};
use proptest::prelude::*;
use subdivision::{rational_to_f64, Error, NaryScheme};

fn q(n: i64, d: i64) -> BigRational {
    BigRational::new(BigInt::from(n), BigInt::from(d))
}

fn scaled(num: &[i64], den: i64) -> Vec<BigRational> {
    num.iter().map(|&v| q(v, den)).collect()
}

/// The named members, with the reference weights from the literature as restated in math.md §3
/// (the seed's printed versions have lost signs and, for the ternary 6-point rule, repeat the
/// 4-point rule).
#[test]
fn named_members_are_reproduced_exactly() {
    let dd4 = NaryScheme::new(4, 2).unwrap();
    assert_eq!(dd4.offsets(), vec![-1, 0, 1, 2]);
    assert_eq!(dd4.exact_rule(0), scaled(&[0, 16, 0, 0], 16).as_slice());
    assert_eq!(dd4.exact_rule(1), scaled(&[-1, 9, 9, -1], 16).as_slice());

    let dd6 = NaryScheme::new(6, 2).unwrap();
    assert_eq!(
        dd6.exact_rule(1),
        scaled(&[3, -25, 150, 150, -25, 3], 256).as_slice()
    );

    let t4 = NaryScheme::new(4, 3).unwrap();
    assert_eq!(t4.exact_rule(1), scaled(&[-5, 60, 30, -4], 81).as_slice());
    assert_eq!(t4.exact_rule(2), scaled(&[-4, 30, 60, -5], 81).as_slice());
}

/// The 6-point ternary rule, derived independently: the unique weights on the nodes −2..3 that
/// reproduce 1, x, …, x⁵ at x = a/3 (a Vandermonde system solved here by exact elimination).
/// Result: (8, −70, 560, 280, −56, 7)/729 for a = 1 and its mirror for a = 2.
#[test]
fn ternary_six_point_rule_matches_an_independent_vandermonde_solve() {
    let t6 = NaryScheme::new(6, 3).unwrap();
    for a in 1..3 {
        let x = q(a, 3);
        let nodes: Vec<BigRational> = (-2..=3).map(|j| q(j, 1)).collect();
        // Rows d = 0..5: Σ_j w_j node_j^d = x^d.
        let mut m: Vec<Vec<BigRational>> = (0..6)
            .map(|d| nodes.iter().map(|t| Pow::pow(t, d as u32)).collect())
            .collect();
        let mut rhs: Vec<BigRational> = (0..6).map(|d| Pow::pow(&x, d as u32)).collect();
        for k in 0..6 {
            let piv = (k..6).find(|&r| !m[r][k].is_zero()).unwrap();
            m.swap(k, piv);
            rhs.swap(k, piv);
            for r in 0..6 {
                if r != k {
                    let f = &m[r][k] / &m[k][k];
                    for c in 0..6 {
                        let v = &f * &m[k][c];
                        m[r][c] -= v;
                    }
                    let v = &f * &rhs[k];
                    rhs[r] -= v;
                }
            }
        }
        let w: Vec<BigRational> = (0..6).map(|k| &rhs[k] / &m[k][k]).collect();
        assert_eq!(t6.exact_rule(a as usize), w.as_slice(), "residue {a}");
    }
    assert_eq!(
        t6.exact_rule(1),
        scaled(&[8, -70, 560, 280, -56, 7], 729).as_slice()
    );
}

/// Every rule (centred and one-sided) reproduces polynomials of degree ≤ 2m + 1 exactly, and
/// fails for the monomial of degree 2m + 2 (so the check has teeth); every rule sums to one.
#[test]
fn polynomial_reproduction_and_partition_of_unity_exactly() {
    for points in [2usize, 4, 6, 8, 10] {
        for arity in 2..=5usize {
            let s = NaryScheme::new(points, arity).unwrap();
            let m = s.m();
            for t in 0..=2 * m {
                for a in 0..arity {
                    let w = s.boundary_rule(t, a);
                    let sum: BigRational = w.iter().sum();
                    assert_eq!(sum, BigRational::one(), "P={points} n={arity} t={t} a={a}");
                    let x = q((t * arity + a) as i64, arity as i64);
                    for deg in 0..=(2 * m + 2) {
                        let lhs: BigRational = w
                            .iter()
                            .enumerate()
                            .map(|(j, wj)| wj * Pow::pow(&q(j as i64, 1), deg as u32))
                            .sum();
                        let exact = lhs == Pow::pow(&x, deg as u32);
                        if deg <= 2 * m + 1 || a == 0 {
                            assert!(
                                exact,
                                "degree {deg} not reproduced: P={points} n={arity} t={t} a={a}"
                            );
                        } else {
                            assert!(
                                !exact,
                                "degree {deg} unexpectedly reproduced: P={points} n={arity} a={a}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// The floats are the correctly rounded values of the exact weights: no neighbouring double is
/// closer (checked in exact arithmetic).
#[test]
fn floats_are_correctly_rounded() {
    for (points, arity) in [(4, 3), (6, 3), (8, 5), (12, 7), (20, 9)] {
        let s = NaryScheme::new(points, arity).unwrap();
        for a in 0..arity {
            for (w, f) in s.exact_rule(a).iter().zip(s.rule(a)) {
                let err = |g: f64| (BigRational::from_float(g).unwrap() - w).abs();
                let e = err(*f);
                let up = f64::from_bits(f.to_bits() + 1);
                let down = if *f > 0.0 {
                    f64::from_bits(f.to_bits() - 1)
                } else {
                    -f64::from_bits((-f).to_bits() + 1)
                };
                assert!(e <= err(up) && e <= err(down), "{w} -> {f}");
                assert_eq!(f.to_bits(), rational_to_f64(w).to_bits());
            }
        }
    }
}

/// Reference implementation for closed polygons: the exact rules (rounded per weight), periodic
/// indices by `rem_euclid`, written independently of the library's kernels.
fn reference_closed(s: &NaryScheme, p: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = p.len() as isize;
    let mut out = Vec::new();
    for i in 0..n {
        for a in 0..s.arity() {
            let mut v = vec![0.0; p[0].len()];
            for (off, w) in s.offsets().iter().zip(s.exact_rule(a)) {
                let w = rational_to_f64(w);
                let src = &p[(i + off).rem_euclid(n) as usize];
                for (d, x) in v.iter_mut().zip(src) {
                    *d += w * x;
                }
            }
            out.push(v);
        }
    }
    out
}

fn close(a: &[Vec<f64>], b: &[Vec<f64>], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.iter().zip(y).all(|(u, v)| (u - v).abs() <= tol))
}

/// Sums of at most 32 products of numbers of size ≤ 10 with weights ≤ 10: a few ulps of 100.
const APPLY_TOL: f64 = 1e-12;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Closed polygons in R^1..R^5 (covering the fixed-dimension and the general kernels),
    /// including polygons shorter than the stencil (which wrap more than once).
    #[test]
    fn closed_application_matches_reference(
        half in 0usize..4,
        arity in 2usize..5,
        dim in 1usize..6,
        levels in 1usize..3,
        seed in proptest::collection::vec(-10.0f64..10.0, 2 * 5..=14 * 5),
    ) {
        let s = NaryScheme::new(2 * half + 2, arity).unwrap();
        let count = seed.len() / dim;
        prop_assume!(count >= 2);
        let rows: Vec<Vec<f64>> = seed[..count * dim].chunks(dim).map(<[f64]>::to_vec).collect();
        let pts = Points::from_rows(&rows).unwrap();
        let got = s.subdivide(&pts, Topology::Closed, levels).unwrap();
        let mut expect = rows.clone();
        for _ in 0..levels {
            expect = reference_closed(&s, &expect);
        }
        prop_assert_eq!(got.len(), count * arity.pow(levels as u32));
        prop_assert!(close(&got.to_rows(), &expect, APPLY_TOL * 10.0));
        // Interpolation: the old points are copied, bit for bit.
        for (i, r) in rows.iter().enumerate() {
            let stride = arity.pow(levels as u32);
            prop_assert!(got.point(i * stride).iter().zip(r).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }

    /// Open polygons sampled from a vector-valued polynomial of degree ≤ 2m + 1 are refined to
    /// samples of the same polynomial at the new parameters — up to and including the ends,
    /// which is what the one-sided end stencils are for.
    #[test]
    fn open_application_reproduces_polynomials_to_the_ends(
        half in 0usize..3,
        arity in 2usize..5,
        extra in 0usize..6,
        coef in proptest::collection::vec(-1.0f64..1.0, 16),
    ) {
        let s = NaryScheme::new(2 * half + 2, arity).unwrap();
        let deg = 2 * half + 1;
        let count = 2 * half + 2 + extra;
        let poly = |x: f64, c: &[f64]| c[..=deg].iter().rev().fold(0.0, |acc, v| acc * x + v);
        let f = |x: f64| [poly(x, &coef[..8]), poly(x, &coef[8..])];
        let rows: Vec<[f64; 2]> = (0..count).map(|i| f(i as f64)).collect();
        let pts = Points::from_rows(&rows).unwrap();
        let got = s.subdivide(&pts, Topology::Open, 2).unwrap();
        let nn = (arity * arity) as f64;
        prop_assert_eq!(got.len(), (count - 1) * arity * arity + 1);
        // Values are O(count^deg); the rule weights are O(1): relative tolerance.
        let scale = (count as f64).powi(deg as i32).max(1.0);
        for k in 0..got.len() {
            let e = f(k as f64 / nn);
            for c in 0..2 {
                prop_assert!((got.point(k)[c] - e[c]).abs() <= 1e-12 * scale,
                    "k={} got {} expect {}", k, got.point(k)[c], e[c]);
            }
        }
    }
}

/// Every combination of short polygons (2..=10 points, shorter and longer than the stencil) and
/// stencils up to 8 points, dimensions 1..=4, open and closed: no panic, and closed results
/// match the periodic reference.
#[test]
fn short_polygons_every_stencil() {
    for points in [2usize, 4, 6, 8] {
        for arity in 2..=4usize {
            let s = NaryScheme::new(points, arity).unwrap();
            for count in 2..=10usize {
                for dim in 1..=4usize {
                    let rows: Vec<Vec<f64>> = (0..count)
                        .map(|i| {
                            (0..dim)
                                .map(|c| ((i * 7 + c * 3) % 5) as f64 - 2.0)
                                .collect()
                        })
                        .collect();
                    let pts = Points::from_rows(&rows).unwrap();
                    let closed = s.subdivide(&pts, Topology::Closed, 1).unwrap();
                    assert!(close(
                        &closed.to_rows(),
                        &reference_closed(&s, &rows),
                        APPLY_TOL
                    ));
                    let open = s.subdivide(&pts, Topology::Open, 1).unwrap();
                    assert_eq!(open.len(), (count - 1) * arity + 1);
                }
            }
        }
    }
}

/// An open polygon with fewer points than the stencil uses the interpolant through all of them:
/// 3 points on a parabola, refined by the 6-point rule, stay on the parabola.
#[test]
fn short_open_polygon_reproduces_its_own_degree() {
    let s = NaryScheme::new(6, 3).unwrap();
    let f = |x: f64| 2.0 * x * x - x + 0.5;
    let pts = Points::from_rows(&[[f(0.0)], [f(1.0)], [f(2.0)]]).unwrap();
    let got = s.subdivide(&pts, Topology::Open, 1).unwrap();
    assert_eq!(got.len(), 7);
    for k in 0..7 {
        assert!((got.point(k)[0] - f(k as f64 / 3.0)).abs() < 1e-14);
    }
}

#[test]
fn bad_parameters_are_typed_errors() {
    assert!(matches!(
        NaryScheme::new(3, 2),
        Err(Error::InvalidValue {
            field: "points",
            ..
        })
    ));
    assert!(matches!(
        NaryScheme::new(0, 2),
        Err(Error::TooFew {
            field: "points",
            minimum: 2,
            got: 0
        })
    ));
    assert!(matches!(
        NaryScheme::new(4, 1),
        Err(Error::TooFew {
            field: "arity",
            minimum: 2,
            got: 1
        })
    ));
    assert!(matches!(
        NaryScheme::new(34, 2),
        Err(Error::TooLarge {
            field: "points",
            limit: 32,
            got: 34
        })
    ));
    assert!(matches!(
        NaryScheme::new(4, 65),
        Err(Error::TooLarge {
            field: "arity",
            limit: 64,
            got: 65
        })
    ));
    let s = NaryScheme::new(4, 2).unwrap();
    let one = Points::from_rows(&[[1.0, 2.0]]).unwrap();
    assert!(matches!(
        s.subdivide(&one, Topology::Closed, 1),
        Err(Error::TooFew {
            field: "points",
            minimum: 2,
            got: 1
        })
    ));
    let two = Points::from_rows(&[[1.0, 2.0], [3.0, 4.0]]).unwrap();
    assert!(matches!(
        s.subdivide(&two, Topology::Closed, 40),
        Err(Error::TooLarge {
            field: "levels",
            ..
        })
    ));
    assert!(matches!(
        s.subdivide(&two, Topology::Open, usize::MAX),
        Err(Error::TooLarge { .. })
    ));
}
