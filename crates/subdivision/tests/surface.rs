//! Tensor-product surfaces of the (2m+2)-point n-ary scheme (Khan et al. §4, (4.1)–(4.2)): the
//! seed's printed 2-D masks, separable application against direct 2-D mask application, bicubic
//! reproduction on open grids, and the OBJ quad mesh.

// Index loops mirror the formulas (rows, columns, coordinates) in this numerical test code.
#![allow(clippy::needless_range_loop)]

use divdiff::Points;
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed};
use proptest::prelude::*;
use subdivision::{quad_mesh_obj, rational_to_f64, Error, NaryScheme, QuadGrid};

fn q(n: i64, d: i64) -> BigRational {
    BigRational::new(BigInt::from(n), BigInt::from(d))
}

/// Magnitudes of the seed's printed 2-D masks, transcribed from seed 001, §4 (Remark 4.1), in
/// the order printed: offsets (r, s), r = −1..2 outer, s = −1..2 inner. The text extraction has
/// lost every minus sign, so signs are checked separately (they must make the mask sum to 1 and
/// follow the product of the curve rules' signs).
/// (residue, arity, printed magnitudes as (numerator, denominator)).
type PrintedMask = ((usize, usize), usize, Vec<(i64, i64)>);

fn seed_magnitudes() -> Vec<PrintedMask> {
    vec![
        // Kobbelt: tensor product of the binary 4-point scheme, p_{2i+1, 2j+1}.
        (
            (1, 1),
            2,
            vec![
                (1, 256),
                (9, 256),
                (9, 256),
                (1, 256),
                (9, 256),
                (81, 256),
                (81, 256),
                (9, 256),
                (9, 256),
                (81, 256),
                (81, 256),
                (9, 256),
                (1, 256),
                (9, 256),
                (9, 256),
                (1, 256),
            ],
        ),
        // Ternary 4-point tensor product, p_{3i+1, 3j+1}.
        (
            (1, 1),
            3,
            vec![
                (25, 6561),
                (100, 2187),
                (50, 2187),
                (20, 6561),
                (100, 2187),
                (400, 729),
                (200, 729),
                (80, 2187),
                (50, 2187),
                (200, 729),
                (100, 729),
                (40, 2187),
                (20, 6561),
                (80, 2187),
                (40, 2187),
                (16, 6561),
            ],
        ),
        // p_{3i+1, 3j+2}.
        (
            (1, 2),
            3,
            vec![
                (20, 6561),
                (50, 2187),
                (100, 2187),
                (25, 6561),
                (80, 2187),
                (200, 729),
                (400, 729),
                (100, 2187),
                (40, 2187),
                (100, 729),
                (200, 729),
                (50, 2187),
                (16, 6561),
                (40, 2187),
                (80, 2187),
                (20, 6561),
            ],
        ),
        // p_{3i+2, 3j+1}.
        (
            (2, 1),
            3,
            vec![
                (20, 6561),
                (80, 2187),
                (40, 2187),
                (16, 6561),
                (50, 2187),
                (200, 729),
                (100, 729),
                (40, 2187),
                (100, 2187),
                (400, 729),
                (200, 729),
                (80, 2187),
                (25, 6561),
                (100, 2187),
                (50, 2187),
                (20, 6561),
            ],
        ),
        // p_{3i+2, 3j+2}.
        (
            (2, 2),
            3,
            vec![
                (16, 6561),
                (40, 2187),
                (80, 2187),
                (20, 6561),
                (40, 2187),
                (100, 729),
                (200, 729),
                (50, 2187),
                (80, 2187),
                (200, 729),
                (400, 729),
                (100, 2187),
                (20, 6561),
                (50, 2187),
                (100, 2187),
                (25, 6561),
            ],
        ),
    ]
}

#[test]
fn seed_two_dimensional_masks_are_reproduced_exactly() {
    for (residue, arity, mags) in seed_magnitudes() {
        let s = NaryScheme::new(4, arity).unwrap();
        let rules = s.surface_rules();
        assert_eq!(rules.len(), arity * arity);
        let rule = rules.iter().find(|r| r.residue == residue).unwrap();
        let offsets: Vec<(isize, isize)> = (-1..=2)
            .flat_map(|r| (-1..=2).map(move |c| (r, c)))
            .collect();
        assert_eq!(rule.offsets, offsets);
        for (l, ((n, d), w)) in mags.iter().zip(&rule.weights).enumerate() {
            assert_eq!(w.abs(), q(*n, *d), "residue {residue:?} entry {l}");
            let (r, c) = (l / 4, l % 4);
            let sign = s.exact_rule(residue.0)[r].signum() * s.exact_rule(residue.1)[c].signum();
            assert_eq!(w.signum(), sign);
        }
        let sum: BigRational = rule.weights.iter().sum();
        assert_eq!(sum, BigRational::one());
    }
    // The seed's edge rules of the Kobbelt scheme: p_{2i, 2j+1} = the curve rule in j only.
    let kob = NaryScheme::new(4, 2).unwrap().surface_rules();
    let edge = kob.iter().find(|r| r.residue == (0, 1)).unwrap();
    let nonzero: Vec<_> = edge
        .offsets
        .iter()
        .zip(&edge.weights)
        .filter(|(_, w)| !num_traits::Zero::is_zero(*w))
        .map(|(o, w)| (*o, w.clone()))
        .collect();
    assert_eq!(
        nonzero,
        vec![
            ((0, -1), q(-1, 16)),
            ((0, 0), q(9, 16)),
            ((0, 1), q(9, 16)),
            ((0, 2), q(-1, 16))
        ]
    );
}

/// Direct application of the 2-D masks on a doubly periodic grid (reference, independent of the
/// separable implementation).
fn reference_torus(s: &NaryScheme, rows: usize, cols: usize, p: &[f64], dim: usize) -> Vec<f64> {
    let n = s.arity();
    let (nr, nc) = (rows * n, cols * n);
    let mut out = vec![0.0; nr * nc * dim];
    for rule in s.surface_rules() {
        let (a, b) = rule.residue;
        for i in 0..rows {
            for j in 0..cols {
                let dst = ((n * i + a) * nc + n * j + b) * dim;
                for ((r, c), w) in rule.offsets.iter().zip(&rule.weights) {
                    let w = rational_to_f64(w);
                    let si = (i as isize + r).rem_euclid(rows as isize) as usize;
                    let sj = (j as isize + c).rem_euclid(cols as isize) as usize;
                    for d in 0..dim {
                        out[dst + d] += w * p[(si * cols + sj) * dim + d];
                    }
                }
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn separable_application_equals_the_two_dimensional_masks(
        half in 0usize..3,
        arity in 2usize..4,
        rows in 2usize..6,
        cols in 2usize..6,
        dim in 1usize..4,
        vals in proptest::collection::vec(-5.0f64..5.0, 108),
    ) {
        let s = NaryScheme::new(2 * half + 2, arity).unwrap();
        let coords = vals[..rows * cols * dim].to_vec();
        let grid = QuadGrid::new(rows, cols, Points::new(dim, coords.clone()).unwrap(), true, true).unwrap();
        let fine = s.subdivide_grid(&grid, 1).unwrap();
        prop_assert_eq!((fine.rows(), fine.cols()), (rows * arity, cols * arity));
        let expect = reference_torus(&s, rows, cols, &coords, dim);
        for (g, e) in fine.points().coords().iter().zip(&expect) {
            prop_assert!((g - e).abs() <= 1e-11, "{} vs {}", g, e);
        }
    }

    /// On open grids, samples of a bicubic polynomial are refined to samples of the same
    /// polynomial (the 4-point rules reproduce cubics in each direction, ends included).
    #[test]
    fn open_grids_reproduce_bicubics(
        arity in 2usize..4,
        rows in 4usize..7,
        cols in 4usize..7,
        c in proptest::collection::vec(-1.0f64..1.0, 16),
    ) {
        let s = NaryScheme::new(4, arity).unwrap();
        let f = |x: f64, y: f64| {
            let mut v = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    v += c[a * 4 + b] * x.powi(a as i32) * y.powi(b as i32);
                }
            }
            v
        };
        let mut rowsv = Vec::new();
        for i in 0..rows {
            for j in 0..cols {
                rowsv.push([i as f64, j as f64, f(i as f64, j as f64)]);
            }
        }
        let grid = QuadGrid::new(rows, cols, Points::from_rows(&rowsv).unwrap(), false, false).unwrap();
        let fine = s.subdivide_grid(&grid, 1).unwrap();
        let n = arity as f64;
        for i in 0..fine.rows() {
            for j in 0..fine.cols() {
                let (x, y) = (i as f64 / n, j as f64 / n);
                let p = fine.point(i, j);
                prop_assert!((p[0] - x).abs() < 1e-12 && (p[1] - y).abs() < 1e-12);
                prop_assert!((p[2] - f(x, y)).abs() < 1e-9, "({}, {}): {} vs {}", i, j, p[2], f(x, y));
            }
        }
    }
}

#[test]
fn obj_quad_mesh_counts_and_wrapping() {
    let s = NaryScheme::new(4, 2).unwrap();
    let mut pts = Vec::new();
    for i in 0..4 {
        for j in 0..3 {
            let t = i as f64 * std::f64::consts::FRAC_PI_2;
            pts.push([
                t.cos() * (2.0 + j as f64),
                t.sin() * (2.0 + j as f64),
                j as f64,
            ]);
        }
    }
    // Closed in i (around the axis), open in j: a ring of 4 × 3 points.
    let grid = QuadGrid::new(4, 3, Points::from_rows(&pts).unwrap(), true, false).unwrap();
    let fine = s.subdivide_grid(&grid, 2).unwrap();
    assert_eq!((fine.rows(), fine.cols()), (16, 9));
    let obj = quad_mesh_obj(&fine).unwrap();
    let v = obj.lines().filter(|l| l.starts_with("v ")).count();
    let f: Vec<&str> = obj.lines().filter(|l| l.starts_with("f ")).collect();
    assert_eq!(v, 16 * 9);
    assert_eq!(f.len(), 16 * 8); // 16 spans around (wrapping), 8 along j
                                 // The last ring of quads joins row 15 to row 0: face indices stay within 1..=v.
    for line in &f {
        for idx in line.split_whitespace().skip(1) {
            let k: usize = idx.parse().unwrap();
            assert!((1..=v).contains(&k));
        }
    }
    assert!(f.contains(&"f 136 137 2 1")); // (15, 0), (15, 1), (0, 1), (0, 0), 1-based
                                           // Interpolation: coarse point (1, 2) is fine point (4, 8).
    assert_eq!(fine.point(4, 8), grid.point(1, 2));
}

#[test]
fn grid_errors_are_typed() {
    let p = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    assert!(matches!(
        QuadGrid::new(1, 3, p.clone(), false, false),
        Err(Error::TooFew { field: "rows", .. })
    ));
    assert!(matches!(
        QuadGrid::new(2, 2, p, false, false),
        Err(Error::WrongLength {
            field: "points",
            expected: 4,
            got: 3
        })
    ));
    let p4 = Points::from_rows(&[[0.0; 4], [1.0; 4], [2.0; 4], [3.0; 4]]).unwrap();
    let g = QuadGrid::new(2, 2, p4, false, false).unwrap();
    assert!(matches!(
        quad_mesh_obj(&g),
        Err(Error::Unsupported {
            field: "points",
            ..
        })
    ));
    let s = NaryScheme::new(4, 3).unwrap();
    assert!(matches!(
        s.subdivide_grid(&g, 30),
        Err(Error::TooLarge { .. })
    ));
}
