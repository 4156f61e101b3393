//! The paper's slot iteration for polygonal constraints (Kersey §4, Fig. 4.1) against the exact
//! solver: same optimum up to the iteration's accuracy, same multipliers, typed errors.

use divdiff::{Points, Topology};
use refine::{Constraint, Error, HalfSpace, Problem, Solver};

fn square(x: f64, y: f64, w: f64) -> Vec<HalfSpace> {
    let h = |n: [f64; 2], c: f64| HalfSpace {
        normal: n.to_vec(),
        offset: c,
    };
    vec![
        h([1.0, 0.0], x + w),
        h([-1.0, 0.0], w - x),
        h([0.0, 1.0], y + w),
        h([0.0, -1.0], w - y),
    ]
}

fn triangle(x: f64, y: f64, r: f64) -> Vec<HalfSpace> {
    (0..3)
        .map(|k| {
            let a = std::f64::consts::FRAC_PI_2 + 2.0 * std::f64::consts::PI * k as f64 / 3.0;
            let (nx, ny) = (a.cos(), a.sin());
            // Unnormalized normals on purpose: the slots must use the unit normal.
            HalfSpace {
                normal: vec![2.0 * nx, 2.0 * ny],
                offset: 2.0 * (nx * x + ny * y + r),
            }
        })
        .collect()
}

fn problem(solver: Solver, topology: Topology) -> Problem {
    let c = [
        [0.0, 0.0],
        [3.0, -0.5],
        [5.0, 1.5],
        [4.0, 4.0],
        [1.0, 4.5],
        [-1.5, 2.5],
    ];
    let sets = c
        .iter()
        .enumerate()
        .map(|(i, &[x, y])| {
            if i % 2 == 0 {
                square(x, y, 0.5)
            } else {
                triangle(x, y, 0.45)
            }
        })
        .collect();
    Problem::new(Points::from_rows(&c).unwrap())
        .with_topology(topology)
        .with_k(3)
        .with_knot_iterations(0)
        .with_constraint(Constraint::HalfSpaces(sets))
        .with_solver(solver)
}

#[test]
fn slot_iteration_reaches_the_exact_optimum() {
    for topology in [Topology::Closed, Topology::Open] {
        let exact = problem(Solver::Exact, topology).solve().unwrap();
        let paper = problem(Solver::Paper, topology).solve().unwrap();
        let rel = (paper.energy - exact.energy).abs() / exact.energy;
        assert!(
            rel < 1e-6,
            "{topology:?}: energies {} vs {} ({rel:e})",
            paper.energy,
            exact.energy
        );
        assert_eq!(
            paper.active, exact.active,
            "{topology:?}: same active points"
        );
        for (i, (a, b)) in paper.multipliers.iter().zip(&exact.multipliers).enumerate() {
            for (x, y) in a.iter().zip(b) {
                assert!(
                    (x - y).abs() <= 1e-3 * (1.0 + y.abs()),
                    "{topology:?} point {i}: {a:?} vs {b:?}"
                );
            }
        }
    }
}

#[test]
fn slot_iteration_is_planar_and_reports_empty_polygons() {
    let p3 = Points::from_rows(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
    // Disjoint sets (x ≥ 2 and x ≤ −2), so no common point short-cuts the solve.
    let h = |n: [f64; 3], c: f64| HalfSpace {
        normal: n.to_vec(),
        offset: c,
    };
    let sets = vec![
        vec![h([-1.0, 0.0, 0.0], -2.0)],
        vec![h([1.0, 0.0, 0.0], -2.0)],
        vec![],
    ];
    let e = Problem::new(p3)
        .with_constraint(Constraint::HalfSpaces(sets))
        .with_solver(Solver::Paper)
        .solve();
    assert!(matches!(e, Err(Error::Unsupported { .. })), "{e:?}");

    let p2 = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    let empty = vec![
        HalfSpace {
            normal: vec![1.0, 0.0],
            offset: -1.0,
        },
        HalfSpace {
            normal: vec![-1.0, 0.0],
            offset: -1.0,
        },
    ];
    let e = Problem::new(p2)
        .with_constraint(Constraint::HalfSpaces(vec![empty, vec![], vec![]]))
        .with_solver(Solver::Paper)
        .solve();
    assert!(matches!(e, Err(Error::EmptySet { point: 0, .. })), "{e:?}");
}
