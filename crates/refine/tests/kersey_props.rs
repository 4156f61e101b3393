//! Property tests of Kersey refinement over random data: the exact solves satisfy their KKT
//! conditions and agree with Clarabel (an independent conic solver); split invariants hold.

mod kersey_support;

use divdiff::{Points, Topology};
use kersey_support::clarabel_solve;
use proptest::prelude::*;
use refine::{Constraint, Problem, Solver};

/// n points in R^d on a perturbed circle (angles sorted, so consecutive points differ).
fn data() -> impl Strategy<Value = (Points, Topology, usize)> {
    (3usize..9, 1usize..4, any::<bool>(), 1usize..5).prop_flat_map(|(n, d, closed, k)| {
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
    fn smoothing_kkt_and_clarabel((q, topo, k) in data(), w in proptest::collection::vec(0.05f64..20.0, 9)) {
        let n = q.len();
        let c = Constraint::Smoothing(w[..n].to_vec());
        let r = Problem::new(q.clone()).with_topology(topo).with_k(k)
            .with_constraint(c.clone()).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        let reference = clarabel_solve(&r.knots, &q, &r.data_vertex, &c).unwrap();
        let pen: f64 = (0..n).map(|i| {
            let v = r.data_vertex[i];
            0.5 * w[i] * r.points.point(v).iter().zip(q.point(i)).map(|(a, b)| (a - b) * (a - b)).sum::<f64>()
        }).sum();
        prop_assert!(rel(r.energy + pen, reference.objective) <= 1e-8,
            "{} vs {}", r.energy + pen, reference.objective);
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
