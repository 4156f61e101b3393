//! Property tests of the free-knot reduced objective on random data: the exact gradient against
//! central finite differences, and the homogeneity identities behind the fixed-length multiplier.

use divdiff::{Points, Topology};
use proptest::prelude::*;
use refine::{optimize_knots, reduced_objective, FreeKnotOptions, FreeKnots, Problem};

fn data() -> impl Strategy<Value = (Vec<[f64; 2]>, bool, Vec<f64>, usize)> {
    (4usize..8).prop_flat_map(|n| {
        (
            prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0), n),
            any::<bool>(),
            prop::collection::vec(-0.7f64..0.7, n),
            1usize..4,
        )
            .prop_map(|(pts, closed, theta, k)| {
                (
                    pts.into_iter().map(|(x, y)| [x, y]).collect(),
                    closed,
                    theta,
                    k,
                )
            })
    })
}

fn problem(rows: &[[f64; 2]], closed: bool, k: usize) -> Option<Problem> {
    // Keep consecutive points apart (coincident data is a typed error, tested elsewhere).
    let n = rows.len();
    let spans = if closed { n } else { n - 1 };
    for i in 0..spans {
        let (a, b) = (rows[i], rows[(i + 1) % n]);
        if ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() < 0.2 {
            return None;
        }
    }
    let topo = if closed {
        Topology::Closed
    } else {
        Topology::Open
    };
    Some(
        Problem::new(Points::from_rows(rows).ok()?)
            .with_topology(topo)
            .with_k(k),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn data_knot_gradient_matches_central_differences((rows, closed, theta, k) in data()) {
        let p = problem(&rows, closed, k);
        prop_assume!(p.is_some());
        let p = p.unwrap();
        let m = if closed { rows.len() } else { rows.len() - 1 };
        let th = &theta[..m];
        let (_, g) = reduced_objective(&p, FreeKnots::Data, th, 3.0).unwrap();
        let gn = g.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let step = 1e-5;
        for i in 0..m {
            let (mut a, mut b) = (th.to_vec(), th.to_vec());
            a[i] += step;
            b[i] -= step;
            let fa = reduced_objective(&p, FreeKnots::Data, &a, 3.0).unwrap().0;
            let fb = reduced_objective(&p, FreeKnots::Data, &b, 3.0).unwrap().0;
            let fd = (fa - fb) / (2.0 * step);
            prop_assert!((fd - g[i]).abs() <= 1e-6 * gn.max(1e-12), "θ[{}]: {} vs {}", i, g[i], fd);
        }
        // Softmax is invariant under θ + c: the gradient sums to 0.
        prop_assert!(g.iter().sum::<f64>().abs() <= 1e-10 * gn.max(1e-12) * m as f64);
    }

    #[test]
    fn optimum_never_above_centripetal((rows, closed, _theta, k) in data()) {
        let p = problem(&rows, closed, k);
        prop_assume!(p.is_some());
        let p = p.unwrap();
        let r = optimize_knots(&p, &FreeKnotOptions::default()).unwrap();
        prop_assert!(r.after.objective <= r.before.objective * (1.0 + 1e-12));
        prop_assert!(r.converged, "stationarity {}", r.after.stationarity);
        prop_assert!(r.after.knot_residual <= 1e-5, "{}", r.after.knot_residual);
    }
}
