//! Empty half-space sets are refused before any solve with an exact proof (`EmptySet`), and no
//! nonempty set is: random sets of 2–7 half-spaces in the plane and in space, judged
//! independently by Clarabel on the largest margin t with which every half-space can be shrunk
//! and still meet (maximize t subject to n_j·x + t|n_j| ≤ c_j, t ≤ 1). A margin above 1e-6
//! is a nonempty set, below −1e-6 an empty one even after growing every half-space by 1e-6;
//! the sets in between (touching, within Clarabel's tolerance) are not judged.

mod clarabel_support;

use clarabel::algebra::CscMatrix;
use clarabel::solver::SupportedConeT;
use divdiff::Points;
use proptest::prelude::*;
use refine::{Constraint, Error, HalfSpace, Problem};

/// Clarabel's largest margin (module docs).
fn margin(set: &[HalfSpace], d: usize) -> f64 {
    let m = set.len();
    let (mut rows, mut cols, mut vals) = (vec![], vec![], vec![]);
    let mut b = vec![];
    for (j, h) in set.iter().enumerate() {
        for (k, &v) in h.normal.iter().enumerate() {
            rows.push(j);
            cols.push(k);
            vals.push(v);
        }
        rows.push(j);
        cols.push(d);
        vals.push(h.normal.iter().map(|x| x * x).sum::<f64>().sqrt());
        b.push(h.offset);
    }
    rows.push(m);
    cols.push(d);
    vals.push(1.0);
    b.push(1.0);
    let a = CscMatrix::new_from_triplets(m + 1, d + 1, rows, cols, vals);
    let mut q = vec![0.0; d + 1];
    q[d] = -1.0;
    let cones = [SupportedConeT::NonnegativeConeT(m + 1)];
    clarabel_support::minimize_linear(&q, &a, &b, &cones, None)[d]
}

/// A set of 2–7 half-spaces with small integer normals (non-zero) and offsets in halves: exact
/// data, so touching and parallel cases occur; in a third of the sets the last normal is twice
/// the first's negated (opposed pairs, rare otherwise).
fn set() -> impl Strategy<Value = (usize, Vec<HalfSpace>)> {
    (2usize..4, 2usize..8, 0..3).prop_flat_map(|(d, m, opposed)| {
        let row = (proptest::collection::vec(-3i32..=3, d), -6i32..=6);
        proptest::collection::vec(row, m).prop_map(move |mut rows| {
            if rows[0].0.iter().all(|&x| x == 0) {
                rows[0].0[0] = 1;
            }
            if opposed == 0 {
                rows[m - 1].0 = rows[0].0.iter().map(|x| -2 * x).collect();
            }
            let set = rows
                .into_iter()
                .map(|(mut n, c)| {
                    if n.iter().all(|&x| x == 0) {
                        n[0] = 1;
                    }
                    HalfSpace {
                        normal: n.into_iter().map(f64::from).collect(),
                        offset: f64::from(c) / 2.0,
                    }
                })
                .collect::<Vec<_>>();
            (d, set)
        })
    })
}

fn verdict(d: usize, set: &[HalfSpace]) -> Result<(), Error> {
    // Three data points, the set at the middle one (the others free).
    let q = Points::new(d, (0..3 * d).map(|i| (i % 5) as f64).collect()).unwrap();
    Problem::new(q)
        .with_constraint(Constraint::HalfSpaces(vec![vec![], set.to_vec(), vec![]]))
        .validate()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn empty_exactly_when_clarabel_finds_no_margin((d, set) in set()) {
        let t = margin(&set, d);
        let v = verdict(d, &set);
        if t > 1e-6 {
            prop_assert!(v.is_ok(), "margin {t}: {v:?}");
        } else if t < -1e-6 {
            prop_assert!(
                matches!(&v, Err(Error::EmptySet { field: "sets", point: 1, half_spaces })
                    if half_spaces.len() <= d + 1),
                "margin {t}: {v:?}"
            );
        }
        // A proof names half-spaces that are empty on their own: Clarabel finds no margin.
        if let Err(Error::EmptySet { half_spaces, .. }) = &v {
            let sub: Vec<HalfSpace> = half_spaces.iter().map(|&j| set[j].clone()).collect();
            prop_assert!(margin(&sub, d) <= 1e-6, "{half_spaces:?}");
        }
    }
}

/// A polygon far from its data point and from the origin, thin and with sharp corners, is not
/// claimed empty.
#[test]
fn a_thin_far_polygon_is_not_claimed_empty() {
    let set = vec![
        HalfSpace {
            normal: vec![1.0, 1e-7],
            offset: 1e6 + 1e-7,
        },
        HalfSpace {
            normal: vec![-1.0, 1e-7],
            offset: -1e6 + 1e-7,
        },
        HalfSpace {
            normal: vec![0.0, -1.0],
            offset: 0.0,
        },
    ];
    assert!(margin(&set, 2) > 0.0);
    assert_eq!(verdict(2, &set), Ok(()));
}
