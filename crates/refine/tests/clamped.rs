//! Interpolation and smoothing with clamped ends (Kersey §3.6) are a quadratic with linear
//! equality constraints: the bordered solve (`refine::linear::clamped`, the exact solver's second
//! entry) against an independent dense KKT solve of the same program (`linear_support`:
//! nalgebra's LU of [H + W  Cᵀ; C  0], C the interpolation rows and the two end stencils), and
//! the size limit of the general interior-point method no longer applies to them.

mod linear_support;

use divdiff::{DerivativeRule, Points, Topology};
use linear_support::{dense_kkt, max_dist, uniform};
use refine::{Boundary, Constraint, Error, Problem};

/// Open, jittered, unequally spaced data in d dimensions (d = 1, 2, 3), n points.
fn data(n: usize, d: usize, seed: u64) -> Points {
    let mut rnd = uniform(seed);
    let mut a = 0.0;
    let mut rows = Vec::with_capacity(n * d);
    for _ in 0..n {
        a += 0.2 + 1.3 * rnd();
        let r = 1.0 + 0.3 * (rnd() - 0.5);
        let p = [
            r * a.cos(),
            r * a.sin(),
            0.4 * (2.0 * a).sin() + 0.1 * rnd(),
        ];
        rows.extend_from_slice(&p[..d]);
    }
    Points::new(d, rows).unwrap()
}

fn extent(q: &Points) -> f64 {
    let c = q.coords();
    let (lo, hi) = c
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    hi - lo
}

/// How far interpolation's multipliers may be from the dense KKT solve's, relative to the largest
/// (measured: at most 4.3e-14, n = 7, d = 1, k = 3, Bessel).
const MULTIPLIER_RTOL: f64 = 1e-11;

/// Solves and checks one case against the dense KKT solve: certified, one linear solve (not
/// the interior-point method after a refused answer), the dense solution to 1e-9 of the data's
/// extent, the prescribed end derivatives.
fn check(q: &Points, k: usize, rule: DerivativeRule, weights: Option<&[f64]>, ends: [&[f64]; 2]) {
    let [start, end] = ends;
    let mut p = Problem::new(q.clone())
        .with_topology(Topology::Open)
        .with_k(k)
        .with_knot_iterations(0)
        .with_derivative(rule)
        .with_boundary(Boundary::Clamped {
            start: start.to_vec(),
            end: end.to_vec(),
        });
    if let Some(w) = weights {
        p = p.with_constraint(Constraint::Smoothing(w.to_vec()));
    }
    let r = p.solve().unwrap();
    let what = format!(
        "n {} d {} k {k} {rule:?} smoothing {}",
        q.len(),
        q.dim(),
        weights.is_some()
    );
    assert!(r.kkt_residual <= 1e-9, "{what}: kkt {}", r.kkt_residual);
    assert_eq!(r.iterations.solver, 1, "{what}");
    let (want, lambda) = dense_kkt(&r, q, weights, rule, Some(ends));
    let dist = max_dist(r.points.coords(), &want);
    assert!(
        dist <= 1e-9 * extent(q),
        "{what}: {dist:e} from the dense solve"
    );
    // Interpolation's multipliers are the data rows' λ: the reactions, the ends' forces at the
    // end data vertices included.
    if weights.is_none() {
        let n = q.len() * q.dim();
        let scale = lambda[..n].iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let off = max_dist(r.multipliers.values(), &lambda[..n]);
        assert!(
            off <= MULTIPLIER_RTOL * scale,
            "{what}: multipliers {off:e} from the dense solve's (largest {scale:e})"
        );
    }
    let last = r.points.len() - 1;
    for (v, target) in [(0, start), (last, end)] {
        let st = divdiff::derivative_stencil(&r.knots, v, rule).unwrap();
        for (c, &t) in target.iter().enumerate() {
            let df: f64 = st.iter().map(|&(u, w)| w * r.points.point(u)[c]).sum();
            assert!(
                (df - t).abs() <= 1e-9 * (1.0 + t.abs()),
                "{what}: {df} vs {t}"
            );
        }
    }
}

/// Long interpolations (more than 4 × 64 spans) take Y's columns from windows at the ends
/// (`linear::end_windows`): the same answer as the dense KKT solve of the whole curve.
#[test]
fn long_clamped_interpolation_matches_a_dense_kkt_solve() {
    for (k, rule, seed) in [
        (1, DerivativeRule::Bessel, 1),
        (2, DerivativeRule::Average, 2),
        (1, DerivativeRule::Average, 3),
    ] {
        let q = data(300, 2, seed);
        check(&q, k, rule, None, [&[0.3, -2.0], &[1.5, 0.25]]);
    }
}

/// Every d, k, derivative rule, interpolation and smoothing: the library's answer is the dense
/// KKT solution to 1e-9 of the data's extent, certified, with the prescribed end derivatives.
#[test]
fn clamped_ends_match_a_dense_kkt_solve() {
    let (start3, end3) = ([0.7, -1.2, 0.3], [-0.4, 0.9, 1.1]);
    let mut cases = 0;
    for d in 1..=3 {
        for k in 1..=3 {
            for rule in [DerivativeRule::Bessel, DerivativeRule::Average] {
                for smoothing in [false, true] {
                    let n = 7;
                    let q = data(n, d, (d * 100 + k * 10) as u64 + u64::from(smoothing));
                    let weights: Vec<f64> =
                        (0..n).map(|i| 0.5 * 10f64.powi(i as i32 % 4)).collect();
                    check(
                        &q,
                        k,
                        rule,
                        smoothing.then_some(&weights[..]),
                        [&start3[..d], &end3[..d]],
                    );
                    cases += 1;
                }
            }
        }
    }
    assert_eq!(cases, 36);
}

/// The knot updates of Algorithm 4.1 keep the ends clamped: each update solves the same
/// program on new knots (the default three).
#[test]
fn knot_updates_keep_the_ends_clamped() {
    let q = data(40, 2, 7);
    let (start, end) = (vec![0.0, 2.0], vec![-1.5, 0.5]);
    let r = Problem::new(q.clone())
        .with_topology(Topology::Open)
        .with_boundary(Boundary::Clamped {
            start: start.clone(),
            end: end.clone(),
        })
        .solve()
        .unwrap();
    assert_eq!(r.iterations.knot_updates, 3);
    assert_eq!(
        r.iterations.solver, 4,
        "one linear solve per knot iteration"
    );
    assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
    let (want, _) = dense_kkt(&r, &q, None, DerivativeRule::Bessel, Some([&start, &end]));
    let dist = max_dist(r.points.coords(), &want);
    assert!(
        dist <= 1e-9 * extent(&q),
        "{dist:e} from the dense solve on the final knots"
    );
}

/// Beyond the general interior-point method's size limit (`MAX_CONIC_COORDS` refined
/// coordinates), clamped interpolation is solved, and a problem that needs the interior-point
/// method (clamped ends with balls) is still refused up front.
#[test]
fn clamped_interpolation_is_not_held_to_the_interior_point_limit() {
    let n = 2_000;
    let k = refine::MAX_CONIC_COORDS / (2 * (n - 1)) + 1;
    let q = data(n, 2, 11);
    let clamped = Boundary::Clamped {
        start: vec![1.0, 0.0],
        end: vec![0.0, 1.0],
    };
    let p = Problem::new(q.clone())
        .with_topology(Topology::Open)
        .with_k(k)
        .with_knot_iterations(0)
        .with_boundary(clamped.clone());
    let r = p.solve().unwrap();
    assert!(r.points.len() * 2 > refine::MAX_CONIC_COORDS);
    assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
    let balls = Problem::new(q)
        .with_topology(Topology::Open)
        .with_k(k)
        .with_knot_iterations(0)
        .with_boundary(clamped)
        .with_constraint(Constraint::Balls(vec![0.01; n]));
    assert!(matches!(
        balls.solve(),
        Err(Error::TooLarge { field: "k", .. })
    ));
}
