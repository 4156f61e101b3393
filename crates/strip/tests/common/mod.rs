//! Shared test helpers: the independent lower bound from Clarabel.
#![allow(dead_code)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use strip::{lower_bound_qp, Problem, Solution};

/// min(primal, dual) objective of the lower-bound QP on the data sites plus `extra` points:
/// a lower bound on the strip optimum (weak duality for the dual value).
pub fn qp_lower_bound(problem: &Problem, extra: &[f64]) -> f64 {
    let qp = lower_bound_qp(problem, extra);
    let n = qp.n_vars;
    let m = qp.b.len();
    let (pi, pj, pv) = unzip(&qp.p);
    let (ai, aj, av) = unzip(&qp.a);
    let p = CscMatrix::new_from_triplets(n, n, pi, pj, pv);
    let a = CscMatrix::new_from_triplets(m, n, ai, aj, av);
    let q = vec![0.0; n];
    let cones = [
        SupportedConeT::ZeroConeT(qp.n_eq),
        SupportedConeT::NonnegativeConeT(qp.n_ineq),
    ];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .max_iter(400)
        .build()
        .unwrap();
    let mut solver = DefaultSolver::new(&p, &q, &a, &qp.b, &cones, settings).unwrap();
    solver.solve();
    let status = solver.solution.status;
    assert!(
        matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved),
        "clarabel: {status:?}"
    );
    solver.solution.obj_val.min(solver.solution.obj_val_dual)
}

fn unzip(t: &[(usize, usize, f64)]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    (
        t.iter().map(|x| x.0).collect(),
        t.iter().map(|x| x.1).collect(),
        t.iter().map(|x| x.2).collect(),
    )
}

/// A grid for the QP: `per_interval` uniform points in each data interval, plus `cluster`
/// points clustered geometrically around every extra knot and break of `near` (any grid gives a
/// valid lower bound; clustering only tightens it).
pub fn qp_grid(problem: &Problem, per_interval: usize, near: Option<&Solution>) -> Vec<f64> {
    let t = &problem.t;
    let mut g = Vec::new();
    for w in t.windows(2) {
        for k in 1..per_interval {
            g.push(w[0] + (w[1] - w[0]) * k as f64 / per_interval as f64);
        }
    }
    if let Some(s) = near {
        let span = t[t.len() - 1] - t[0];
        for b in s.breaks.iter().chain(s.extra_knots.iter().map(|k| &k.t)) {
            g.push(*b);
            for e in 1..8 {
                let d = span * 1e-2 * 0.5f64.powi(e);
                g.push(b - d);
                g.push(b + d);
            }
        }
    }
    g.retain(|x| *x > t[0] && *x < t[t.len() - 1]);
    g.sort_by(f64::total_cmp);
    g.dedup_by(|a, b| (*a - *b).abs() < 1e-13);
    g
}

/// The largest bound violation of `s` over a dense sample (and at the breaks).
pub fn max_violation(problem: &Problem, s: &Solution, samples: usize) -> f64 {
    let t = &problem.t;
    let n = t.len();
    let mut xs: Vec<f64> = (0..=samples)
        .map(|k| t[0] + (t[n - 1] - t[0]) * k as f64 / samples as f64)
        .collect();
    xs.extend(s.breaks.iter());
    let mut worst = 0.0f64;
    for x in xs {
        let i = t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
        let f = s.eval(x);
        if let Some(lo) = bound_at(&problem.lower, i, t[i], x) {
            worst = worst.max(lo - f);
        }
        if let Some(up) = bound_at(&problem.upper, i, t[i], x) {
            worst = worst.max(f - up);
        }
    }
    worst
}

pub fn bound_at(b: &strip::Bound, i: usize, ti: f64, x: f64) -> Option<f64> {
    match b {
        strip::Bound::None => None,
        strip::Bound::Pieces(p) => {
            let c = p[i];
            let s = x - ti;
            Some(c[0] + s * (c[1] + s * (c[2] + s * c[3])))
        }
        strip::Bound::Polyline(p) => {
            let k = p.partition_point(|v| v[0] <= x).clamp(1, p.len() - 1);
            let (a, b) = (p[k - 1], p[k]);
            Some(a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]))
        }
    }
}
