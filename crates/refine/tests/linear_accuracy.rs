//! Smoothing on badly scaled knots (chordal spans over three orders of magnitude, weights up to
//! 1e4): the one banded solve alone left the answer 1e-6 … 7e-5 of the data's extent from the
//! optimum (objective 1e-6 too high) while its certificate, relative to the largest force,
//! read 1e-11. The solves now refine with a residual in difference form (`linear::Factored`).
//! The reference here: a dense LU of K = AᵀA + W (nalgebra, `linear_support`), refined with
//! that module's own residual Aᵀ(Ap) + Wp − b, to its rounding.

mod linear_support;

use divdiff::{DerivativeRule, Parametrization, Points, Topology};
use linear_support::{dense_kkt, max_dist, uniform};
use refine::{Boundary, Constraint, Problem};

/// n points on a loop whose spacing varies over three orders of magnitude (d = 3).
fn unequal(n: usize, seed: u64) -> (Points, Vec<f64>) {
    let mut rnd = uniform(seed);
    let mut g = Vec::with_capacity(n);
    let mut acc = 0.0;
    for _ in 0..n {
        acc += 10f64.powf(-3.0 * rnd());
        g.push(acc);
    }
    let mut rows = Vec::with_capacity(3 * n);
    for v in &g {
        let a = v / acc * 2.0 * std::f64::consts::PI;
        let r = 1.0 + 0.2 * (5.0 * a).sin();
        rows.extend_from_slice(&[r * a.cos(), r * a.sin(), 0.3 * (3.0 * a).sin()]);
    }
    let w = (0..n).map(|_| 10f64.powf(5.0 * rnd() - 1.0)).collect();
    (Points::new(3, rows).unwrap(), w)
}

#[test]
fn smoothing_on_badly_scaled_knots_is_the_optimum() {
    for (seed, clamped) in [(91, false), (91, true), (7, false), (7, true)] {
        let (q, w) = unequal(300, seed);
        let (start, end) = ([1.2, -1.0, 0.3], [0.1, 0.4, 1.4]);
        let mut p = Problem::new(q.clone())
            .with_topology(Topology::Open)
            .with_k(3)
            .with_knot_iterations(0)
            .with_parametrization(Parametrization::Chordal)
            .with_constraint(Constraint::Smoothing(w.clone()));
        if clamped {
            p = p.with_boundary(Boundary::Clamped {
                start: start.to_vec(),
                end: end.to_vec(),
            });
        }
        let r = p.solve().unwrap();
        assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        let (want, _) = dense_kkt(
            &r,
            &q,
            Some(&w),
            DerivativeRule::Bessel,
            clamped.then_some([&start[..], &end[..]]),
        );
        let c = q.coords();
        let extent = c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let dist = max_dist(r.points.coords(), &want);
        assert!(
            dist <= 1e-9 * extent,
            "seed {seed} clamped {clamped}: {dist:e} of {extent} from the refined dense optimum"
        );
    }
}
