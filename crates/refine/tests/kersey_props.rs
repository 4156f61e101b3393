//! Property tests of Kersey refinement over random data: the exact solves satisfy their KKT
//! conditions and agree with Clarabel (an independent conic solver); split invariants hold.

mod kersey_support;

use divdiff::{Points, Topology};
use kersey_support::clarabel_solve;
use proptest::prelude::*;
use refine::{Constraint, Problem, Solver};

/// n points in R^d, d ≥ 2, on a perturbed ellipse (angles in order, so consecutive points
/// differ). (In d = 1 a curve doubles back at its extremes, where knot updates on the refined
/// vertices can create spans so short that H is numerically singular — a typed error, tested
/// separately.)
fn data() -> impl Strategy<Value = (Points, Topology, usize)> {
    (3usize..9, 2usize..4, any::<bool>(), 1usize..5).prop_flat_map(|(n, d, closed, k)| {
        (
            proptest::collection::vec(-0.3f64..0.3, n * d),
            Just((n, d, closed, k)),
        )
            .prop_map(|(noise, (n, d, closed, k))| {
                let mut c = Vec::with_capacity(n * d);
                for i in 0..n {
                    let th = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                    for j in 0..d {
                        let base = if j % 2 == 0 { 2.0 * th.cos() } else { th.sin() };
                        c.push(base + noise[i * d + j]);
                    }
                }
                let topo = if closed {
                    Topology::Closed
                } else {
                    Topology::Open
                };
                (Points::new(d, c).unwrap(), topo, k)
            })
    })
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn interpolation_kkt_and_clarabel((q, topo, k) in data(), iters in 0usize..3) {
        let r = Problem::new(q.clone()).with_topology(topo).with_k(k)
            .with_knot_iterations(iters).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        prop_assert_eq!(r.points.len(), Problem::refined_len(topo, q.len(), k));
        let reference = clarabel_solve(&r.knots, &q, &r.data_vertex, &Constraint::Interpolate).unwrap();
        let e = energy::energy(&r.knots, &reference.points).unwrap();
        prop_assert!(rel(r.energy, e) <= 1e-8, "{} vs {}", r.energy, e);
        // The reported energy is E of the reported points on the reported knots.
        prop_assert!(rel(r.energy, energy::energy(&r.knots, &r.points).unwrap()) <= 1e-12);
    }

    #[test]
    fn smoothing_kkt_and_clarabel((q, topo, k) in data(), iters in 0usize..3, w in proptest::collection::vec(0.05f64..20.0, 9)) {
        let n = q.len();
        let c = Constraint::Smoothing(w[..n].to_vec());
        let r = Problem::new(q.clone()).with_topology(topo).with_k(k)
            .with_knot_iterations(iters).with_constraint(c.clone()).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        let reference = clarabel_solve(&r.knots, &q, &r.data_vertex, &c).unwrap();
        // The objective E + ½Σw|p − q|², evaluated by us at both solutions.
        let objective = |p: &Points| {
            energy::energy(&r.knots, p).unwrap()
                + (0..n).map(|i| {
                    let v = r.data_vertex[i];
                    0.5 * w[i] * p.point(v).iter().zip(q.point(i)).map(|(a, b)| (a - b) * (a - b)).sum::<f64>()
                }).sum::<f64>()
        };
        let (ours, theirs) = (objective(&r.points), objective(&reference.points));
        prop_assert!(rel(ours, theirs) <= 1e-8, "{} vs {}", ours, theirs);
    }

    /// The paper's iteration keeps (H + W)p = W q̃ for its weights: with every radius 0 it is
    /// plain interpolation and must agree with the exact solver.
    #[test]
    fn paper_with_zero_radii_is_interpolation((q, topo, k) in data()) {
        let n = q.len();
        let exact = Problem::new(q.clone()).with_topology(topo).with_k(k).solve().unwrap();
        let paper = Problem::new(q).with_topology(topo).with_k(k)
            .with_solver(Solver::Paper)
            .with_constraint(Constraint::Balls(vec![0.0; n])).solve().unwrap();
        prop_assert!(rel(exact.energy, paper.energy) <= 1e-10);
        prop_assert!(paper.active.iter().all(|&a| a));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Exact balls: KKT ≤ 1e-9, Clarabel's SOCP optimum to 1e-8, Corollary 3.3.
    #[test]
    fn exact_balls_kkt_clarabel_corollary((q, topo, k) in data(), eps in proptest::collection::vec(0.0f64..0.8, 9)) {
        let n = q.len();
        // Some radii exactly zero (interpolated points).
        let radii: Vec<f64> = eps[..n].iter().map(|&e| if e < 0.1 { 0.0 } else { e }).collect();
        let c = Constraint::Balls(radii.clone());
        let r = Problem::new(q.clone()).with_topology(topo).with_k(k)
            .with_knot_iterations(1).with_constraint(c.clone()).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        // Cases where Clarabel itself does not reach status `Solved` have no reference and are
        // discarded (proptest counts them as rejects, and fails if there are too many).
        let reference = clarabel_solve(&r.knots, &q, &r.data_vertex, &c);
        prop_assume!(reference.is_ok());
        let e = energy::energy(&r.knots, &reference.unwrap().points).unwrap();
        prop_assert!(rel(r.energy, e) <= 1e-8 || (r.energy - e).abs() <= 1e-12, "{} vs {}", r.energy, e);
        // Corollary 3.3 where some ball is inactive (proptest fails if too few cases have one).
        let (inactive, j) = kersey_support::corollary_3_3(&q, &radii, &r);
        prop_assume!(inactive > 0);
        prop_assert!(j <= 1e-9, "Corollary 3.3: {}", j);
    }
}
