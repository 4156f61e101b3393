//! Free-knot optimization: the chain-ruled envelope gradient against central finite differences,
//! descent below centripetal knots, optimality residuals, scaling, and typed errors.

use divdiff::{Points, Topology};
use refine::{
    optimize_knots, reduced_objective, Boundary, Constraint, Error, FreeKnotOptions, FreeKnots,
    HalfSpace, Problem, Solver, Tangent,
};

fn pentagon() -> Points {
    Points::from_rows(&[[0.0, 0.0], [2.0, 0.1], [2.2, 1.9], [1.0, 3.0], [-0.1, 2.0]]).unwrap()
}

/// Long chords alternating with short ones: centripetal knots are far from optimal here.
fn staircase() -> Points {
    Points::from_rows(&[
        [0.0, 0.0],
        [0.2, 0.0],
        [3.0, 1.0],
        [3.2, 1.0],
        [6.0, 0.0],
        [6.1, 0.05],
        [9.0, 1.0],
    ])
    .unwrap()
}

fn problems() -> Vec<(&'static str, Problem)> {
    let q = pentagon();
    let sets = (0..5)
        .map(|i| {
            let c = q.point(i);
            // A box of half-width 0.15 about each point.
            vec![
                HalfSpace {
                    normal: vec![1.0, 0.0],
                    offset: c[0] + 0.15,
                },
                HalfSpace {
                    normal: vec![-1.0, 0.0],
                    offset: -c[0] + 0.15,
                },
                HalfSpace {
                    normal: vec![0.0, 1.0],
                    offset: c[1] + 0.15,
                },
                HalfSpace {
                    normal: vec![0.0, -1.0],
                    offset: -c[1] + 0.15,
                },
            ]
        })
        .collect();
    vec![
        ("closed interpolation", Problem::new(q.clone()).with_k(2)),
        (
            "open interpolation",
            Problem::new(q.clone())
                .with_topology(Topology::Open)
                .with_k(2),
        ),
        (
            "closed balls",
            Problem::new(q.clone())
                .with_k(2)
                .with_constraint(Constraint::Balls(vec![0.2, 0.0, 0.3, 0.1, 0.25])),
        ),
        (
            "open half-spaces",
            Problem::new(q.clone())
                .with_topology(Topology::Open)
                .with_k(2)
                .with_constraint(Constraint::HalfSpaces(sets)),
        ),
        (
            "closed smoothing",
            Problem::new(q)
                .with_k(2)
                .with_constraint(Constraint::Smoothing(vec![5.0; 5])),
        ),
    ]
}

fn spans(problem: &Problem, free: FreeKnots) -> usize {
    let n = problem.points.len();
    let data_spans = match problem.topology {
        Topology::Open => n - 1,
        Topology::Closed => n,
    };
    match free {
        FreeKnots::Data => data_spans,
        FreeKnots::All => data_spans * (problem.k + 1),
    }
}

/// A deterministic, non-uniform θ (log-spans).
fn theta(m: usize) -> Vec<f64> {
    (0..m).map(|i| 0.4 * ((i as f64) * 1.7).sin()).collect()
}

#[test]
fn reduced_gradient_matches_central_differences() {
    // F(θ) includes the change of p*(t) (the fixed-knot optimum is re-solved for each θ), so this
    // checks the envelope theorem as well as the chain rule through softmax and the split.
    for (name, problem) in problems() {
        for free in [FreeKnots::Data, FreeKnots::All] {
            let th = theta(spans(&problem, free));
            let total = 5.0;
            let (f, g) = reduced_objective(&problem, free, &th, total).unwrap();
            let gnorm = g.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let step = 1e-5;
            // Conic problems are solved to the interior-point tolerance only; F's finite
            // differences then carry that error over 2·step.
            let conic = matches!(
                problem.constraint,
                Constraint::Balls(_) | Constraint::HalfSpaces(_)
            );
            let tol = if conic { 1e-4 } else { 1e-6 };
            for k in 0..th.len() {
                let mut tp = th.clone();
                let mut tm = th.clone();
                tp[k] += step;
                tm[k] -= step;
                let fp = reduced_objective(&problem, free, &tp, total).unwrap().0;
                let fm = reduced_objective(&problem, free, &tm, total).unwrap().0;
                let fd = (fp - fm) / (2.0 * step);
                assert!(
                    (fd - g[k]).abs() <= tol * gnorm,
                    "{name} {free:?} θ[{k}]: exact {} vs fd {fd} (F = {f}, |g| = {gnorm})",
                    g[k]
                );
            }
        }
    }
}

#[test]
fn optimum_is_below_centripetal_and_stationary() {
    for (name, problem) in problems() {
        let r = optimize_knots(&problem, &FreeKnotOptions::default()).unwrap();
        assert!(r.converged, "{name}: not converged, {:?}", r.after);
        assert!(
            r.after.objective <= r.before.objective,
            "{name}: {} > {}",
            r.after.objective,
            r.before.objective
        );
        // The starting knots are the centripetal split (no rescaling by default).
        assert!((r.before.energy - r.start.energy).abs() <= 1e-10 * r.start.energy);
        assert!(r.after.stationarity <= FreeKnotOptions::default().tolerance);
        // The corrected knot condition dF/du_b = 0 at every free data knot …
        assert!(
            r.after.knot_residual <= 2e-6,
            "{name}: {}",
            r.after.knot_residual
        );
        // … and, since the sub-spans stay equal, at every refined knot (Theorem 3.1–3.2, exact).
        assert!(
            r.after.vertex_knot_residual <= 2e-6,
            "{name}: {}",
            r.after.vertex_knot_residual
        );
        // Centripetal knots are not stationary.
        assert!(
            r.before.knot_residual > 1e-2,
            "{name}: {}",
            r.before.knot_residual
        );
        assert!(
            r.after.kkt_residual <= 1e-8,
            "{name}: kkt {}",
            r.after.kkt_residual
        );
        assert!(r.iterations <= refine::FreeKnotOptions::default().max_iterations);
        // The knots keep their total length.
        let t = r.knots.values();
        assert!((t[t.len() - 1] - t[0] - r.total_length).abs() <= 1e-12 * r.total_length);
    }
}

#[test]
fn optimum_scales_with_total_length() {
    // E is homogeneous of degree −3 in the knots, and the constraints do not involve them, so
    // the optimum for c·T is the optimum for T with knots scaled by c and E by c^−3.
    let problem = Problem::new(staircase()).with_topology(Topology::Open);
    let base = optimize_knots(&problem, &FreeKnotOptions::default()).unwrap();
    for c in [0.25, 3.0] {
        let opts = FreeKnotOptions::default().with_total_length(c * base.total_length);
        let r = optimize_knots(&problem, &opts).unwrap();
        assert!(r.converged);
        let expected = base.after.energy / (c * c * c);
        assert!(
            (r.after.energy - expected).abs() <= 1e-9 * expected,
            "c = {c}: {} vs {expected}",
            r.after.energy
        );
        for (a, b) in r.knots.values().iter().zip(base.knots.values()) {
            assert!(
                (a - c * b).abs() <= 1e-6 * r.total_length,
                "{a} vs {}",
                c * b
            );
        }
    }
}

#[test]
fn free_knots_differ_visibly_from_centripetal() {
    let problem = Problem::new(staircase()).with_topology(Topology::Open);
    let r = optimize_knots(&problem, &FreeKnotOptions::default()).unwrap();
    assert!(r.converged);
    let u: Vec<f64> = r.knots.values().iter().step_by(4).copied().collect();
    let u0: Vec<f64> = r.start.knots.values().iter().step_by(4).copied().collect();
    let ratios: Vec<f64> = u
        .windows(2)
        .zip(u0.windows(2))
        .map(|(a, b)| (a[1] - a[0]) / (b[1] - b[0]))
        .collect();
    // The short data spans shrink to well under half their centripetal length …
    assert!(ratios.iter().any(|&x| x < 0.5), "{ratios:?}");
    // … and the energy drops by far more than rounding.
    assert!(
        r.after.energy < 0.5 * r.before.energy,
        "{} vs {}",
        r.after.energy,
        r.before.energy
    );
}

#[test]
fn all_refined_knots_free_is_degenerate() {
    // Freeing every refined knot lets sub-spans next to the data points collapse: E falls below
    // the data-knot optimum (a stationary point, not a minimum, of the all-knot problem) and
    // some sub-span shrinks towards zero, so the iteration cannot converge.
    let problem = Problem::new(pentagon()).with_k(2);
    let data = optimize_knots(&problem, &FreeKnotOptions::default()).unwrap();
    let opts = FreeKnotOptions::default()
        .with_free(FreeKnots::All)
        .with_max_iterations(60)
        .with_total_length(data.total_length);
    let all = optimize_knots(&problem, &opts).unwrap();
    assert!(
        all.after.energy < data.after.energy,
        "{} vs {}",
        all.after.energy,
        data.after.energy
    );
    let t = all.knots.values();
    let min_span = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    assert!(min_span < 1e-3 * all.total_length, "{min_span}");
    assert!(!all.converged);
}

#[test]
fn collinear_data_reaches_zero_energy_on_chordal_knots() {
    // Collinear data: E = 0 exactly when the knots are proportional to the chords (the
    // interpolant is then linear in t), a global minimum since E ≥ 0.
    let q = Points::from_rows(&[[0.0, 0.0], [1.0, 1.0], [3.0, 3.0]]).unwrap();
    let r = optimize_knots(
        &Problem::new(q).with_topology(Topology::Open),
        &FreeKnotOptions::default(),
    )
    .unwrap();
    assert!(
        r.before.energy > 1e-3,
        "centripetal knots bend the parametrization"
    );
    assert!(r.converged && r.after.energy <= 1e-18 * r.before.energy);
    let t = r.knots.values();
    let ratio = (t[8] - t[4]) / (t[4] - t[0]);
    assert!((ratio - 2.0).abs() <= 1e-6, "{ratio}");
    // Equal chords: centripetal is chordal, E = 0 from the start, nothing to do.
    let q = Points::from_rows(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).unwrap();
    let r = optimize_knots(
        &Problem::new(q).with_topology(Topology::Open),
        &FreeKnotOptions::default(),
    )
    .unwrap();
    assert!(r.after.energy <= 1e-20 && r.converged && r.iterations == 0);
}

#[test]
fn knot_dependent_constraints_and_bad_options_are_typed_errors() {
    let q = pentagon();
    let opts = FreeKnotOptions::default();
    let tangents = Problem::new(q.clone()).with_tangents(vec![
        Some(Tangent::Tension { radius: 1.0 }),
        None,
        None,
        None,
        None,
    ]);
    assert!(matches!(
        optimize_knots(&tangents, &opts),
        Err(Error::Unsupported {
            field: "tangents",
            ..
        })
    ));
    let clamped = Problem::new(q.clone())
        .with_topology(Topology::Open)
        .with_boundary(Boundary::Clamped {
            start: vec![1.0, 0.0],
            end: vec![0.0, 1.0],
        });
    assert!(matches!(
        optimize_knots(&clamped, &opts),
        Err(Error::Unsupported {
            field: "boundary",
            ..
        })
    ));
    let paper = Problem::new(q.clone()).with_solver(Solver::Paper);
    assert!(matches!(
        optimize_knots(&paper, &opts),
        Err(Error::Unsupported {
            field: "solver",
            ..
        })
    ));
    let levels = Problem::new(q.clone()).with_levels(1, 1);
    assert!(matches!(
        optimize_knots(&levels, &opts),
        Err(Error::Unsupported {
            field: "levels",
            ..
        })
    ));
    let p = Problem::new(q);
    for (bad, field) in [
        (
            FreeKnotOptions::default().with_max_iterations(0),
            "max_iterations",
        ),
        (
            FreeKnotOptions::default().with_tolerance(f64::NAN),
            "tolerance",
        ),
        (
            FreeKnotOptions::default().with_total_length(-1.0),
            "total_length",
        ),
        (
            FreeKnotOptions::default().with_total_length(f64::INFINITY),
            "total_length",
        ),
    ] {
        assert!(
            matches!(optimize_knots(&p, &bad), Err(Error::InvalidParameter { field: f, .. }) if f == field),
            "{field}"
        );
    }
    assert!(matches!(
        reduced_objective(&p, FreeKnots::Data, &[0.0; 4], 1.0),
        Err(Error::WrongLength {
            field: "theta",
            expected: 5,
            got: 4
        })
    ));
    assert!(matches!(
        reduced_objective(&p, FreeKnots::Data, &[0.0, 0.0, f64::NAN, 0.0, 0.0], 1.0),
        Err(Error::InvalidValue {
            field: "theta",
            index: 2,
            ..
        })
    ));
}
