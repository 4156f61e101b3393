//! A discretized QP whose optimal value is a *lower bound* on the strip problem's optimum, solved
//! by Clarabel for independent verification (tests, `cargo xtask verify`, `cargo xtask bench`).
//!
//! Unknowns: values v_k and second derivatives m_k at grid points x_0 < … < x_M (containing every
//! data site). The objective Σ_k (h_k/3)(m_k² + m_k m_{k+1} + m_{k+1}²) subject to the cubic
//! spline's tridiagonal consistency equations is the exact energy of the cubic spline through
//! (x_k, v_k) with natural (or the prescribed clamped) ends — by Holladay's theorem the least
//! energy of *any* function through those values. With v_k = y_i at data sites and
//! e(x_k) ≤ v_k ≤ d(x_k) only at the grid points, the true solution is feasible for the QP, so
//! the QP optimum is ≤ the true optimum, for every grid; it converges as the grid refines.

use std::collections::BTreeMap;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use strip::{Bound, Problem, Solution};

use crate::bound_at;

/// The QP  min ½xᵀPx  s.t.  A x + s = b,  s ∈ {0}^{n_eq} × R₊^{n_ineq}, in triplet form.
#[derive(Clone, Debug, PartialEq)]
pub struct LowerBoundQp {
    /// Number of unknowns (2 (M + 1): values then second derivatives).
    pub n_vars: usize,
    /// Upper-triangular entries (row, col, value) of P.
    pub p: Vec<(usize, usize, f64)>,
    /// Entries (row, col, value) of A.
    pub a: Vec<(usize, usize, f64)>,
    /// Right-hand side b.
    pub b: Vec<f64>,
    /// Leading equality rows.
    pub n_eq: usize,
    /// Trailing inequality rows.
    pub n_ineq: usize,
    /// The grid.
    pub grid: Vec<f64>,
}

/// Builds the lower-bound QP of `problem` on the data sites plus the interior points `extra`
/// (which must lie strictly inside \[t_1, t_n\]; duplicates of data sites are dropped).
/// The problem is assumed valid (see `strip::solve`). The bounds are evaluated by
/// [`crate::bound_at`], independently of the solver.
pub fn lower_bound_qp(problem: &Problem, extra: &[f64]) -> LowerBoundQp {
    let t = &problem.t;
    let n = t.len();
    let mut grid: Vec<(f64, Option<usize>)> =
        t.iter().enumerate().map(|(i, &v)| (v, Some(i))).collect();
    grid.extend(
        extra
            .iter()
            .filter(|x| **x > t[0] && **x < t[n - 1] && t.iter().all(|s| !s.total_cmp(x).is_eq()))
            .map(|&x| (x, None)),
    );
    grid.sort_by(|a, b| a.0.total_cmp(&b.0));
    grid.dedup_by(|a, b| a.0.total_cmp(&b.0).is_eq());
    let mm = grid.len();
    let vi = |k: usize| k;
    let mi = |k: usize| mm + k;
    let h: Vec<f64> = (0..mm - 1).map(|k| grid[k + 1].0 - grid[k].0).collect();
    let mut pm: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    for k in 0..mm - 1 {
        *pm.entry((mi(k), mi(k))).or_default() += 2.0 * h[k] / 3.0;
        *pm.entry((mi(k + 1), mi(k + 1))).or_default() += 2.0 * h[k] / 3.0;
        *pm.entry((mi(k), mi(k + 1))).or_default() += h[k] / 3.0;
    }
    let mut a = Vec::new();
    let mut b = Vec::new();
    let mut row = 0;
    // spline consistency at interior grid points
    for k in 1..mm - 1 {
        a.push((row, mi(k - 1), h[k - 1] / 6.0));
        a.push((row, mi(k), (h[k - 1] + h[k]) / 3.0));
        a.push((row, mi(k + 1), h[k] / 6.0));
        a.push((row, vi(k + 1), -1.0 / h[k]));
        a.push((row, vi(k), 1.0 / h[k] + 1.0 / h[k - 1]));
        a.push((row, vi(k - 1), -1.0 / h[k - 1]));
        b.push(0.0);
        row += 1;
    }
    // ends: natural (m = 0) or clamped
    match problem.end_slopes[0] {
        None => {
            a.push((row, mi(0), 1.0));
            b.push(0.0);
        }
        Some(s) => {
            // (v1 − v0)/h − h(2m0 + m1)/6 = s
            a.push((row, vi(1), 1.0 / h[0]));
            a.push((row, vi(0), -1.0 / h[0]));
            a.push((row, mi(0), -h[0] / 3.0));
            a.push((row, mi(1), -h[0] / 6.0));
            b.push(s);
        }
    }
    row += 1;
    let l = mm - 1;
    match problem.end_slopes[1] {
        None => {
            a.push((row, mi(l), 1.0));
            b.push(0.0);
        }
        Some(s) => {
            // (v_M − v_{M−1})/h + h(m_{M−1} + 2 m_M)/6 = s
            a.push((row, vi(l), 1.0 / h[l - 1]));
            a.push((row, vi(l - 1), -1.0 / h[l - 1]));
            a.push((row, mi(l - 1), h[l - 1] / 6.0));
            a.push((row, mi(l), h[l - 1] / 3.0));
            b.push(s);
        }
    }
    row += 1;
    for (k, g) in grid.iter().enumerate() {
        if let Some(i) = g.1 {
            a.push((row, vi(k), 1.0));
            b.push(problem.y[i]);
            row += 1;
        }
    }
    let n_eq = row;
    for (k, g) in grid.iter().enumerate() {
        if g.1.is_some() {
            continue;
        }
        if let Some(u) = bound_at(&problem.upper, t, g.0) {
            a.push((row, vi(k), 1.0));
            b.push(u);
            row += 1;
        }
        if let Some(lo) = bound_at(&problem.lower, t, g.0) {
            a.push((row, vi(k), -1.0));
            b.push(-lo);
            row += 1;
        }
    }
    LowerBoundQp {
        n_vars: 2 * mm,
        p: pm.into_iter().map(|((i, j), v)| (i, j, v)).collect(),
        a,
        b,
        n_eq,
        n_ineq: row - n_eq,
        grid: grid.iter().map(|g| g.0).collect(),
    }
}

/// Clarabel's answer to the lower-bound QP.
#[derive(Clone, Debug, PartialEq)]
pub struct LowerBound {
    /// min(primal, dual) objective: a lower bound on the strip optimum when `solved`.
    pub value: f64,
    /// The primal objective.
    pub primal: f64,
    /// The dual objective.
    pub dual: f64,
    /// Whether Clarabel reports `Solved` (an `AlmostSolved` answer is no bound: at M = 10⁴ it
    /// was seen 2·10⁻⁴ below the true QP optimum).
    pub solved: bool,
    /// Clarabel's status, for messages.
    pub status: String,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Grid points of the QP.
    pub grid_points: usize,
}

/// Solves the lower-bound QP on the data sites plus `extra` with Clarabel; `tight` asks for
/// 1e-12 gap and feasibility tolerances (verification), otherwise Clarabel's defaults (the
/// benchmark's peer, as a user would run it).
///
/// # Errors
/// Clarabel's setup errors, as text.
pub fn lower_bound(problem: &Problem, extra: &[f64], tight: bool) -> Result<LowerBound, String> {
    let qp = lower_bound_qp(problem, extra);
    let n = qp.n_vars;
    let rows = qp.b.len();
    let trip = |v: &[(usize, usize, f64)], r: usize| {
        CscMatrix::new_from_triplets(
            r,
            n,
            v.iter().map(|x| x.0).collect(),
            v.iter().map(|x| x.1).collect(),
            v.iter().map(|x| x.2).collect(),
        )
    };
    let cones = [
        SupportedConeT::ZeroConeT(qp.n_eq),
        SupportedConeT::NonnegativeConeT(qp.n_ineq),
    ];
    let mut settings = DefaultSettingsBuilder::default();
    settings.verbose(false);
    if tight {
        settings
            .tol_gap_abs(1e-12)
            .tol_gap_rel(1e-12)
            .tol_feas(1e-12)
            .max_iter(400);
    }
    let settings = settings.build().map_err(|e| format!("{e:?}"))?;
    let mut s = DefaultSolver::new(
        &trip(&qp.p, n),
        &vec![0.0; n],
        &trip(&qp.a, rows),
        &qp.b,
        &cones,
        settings,
    )
    .map_err(|e| format!("{e:?}"))?;
    s.solve();
    let (primal, dual) = (s.solution.obj_val, s.solution.obj_val_dual);
    Ok(LowerBound {
        value: primal.min(dual),
        primal,
        dual,
        solved: matches!(s.solution.status, SolverStatus::Solved),
        status: format!("{:?}", s.solution.status),
        iterations: s.solution.iterations,
        grid_points: qp.grid.len(),
    })
}

/// A grid for the QP: every polyline vertex, `per_interval` uniform points in each data
/// interval, and, when `near` is given, points clustered geometrically around its breaks and
/// extra knots (any grid gives a valid lower bound; clustering only tightens it).
pub fn fine_grid(problem: &Problem, per_interval: usize, near: Option<&Solution>) -> Vec<f64> {
    let t = &problem.t;
    let mut g = Vec::new();
    for w in t.windows(2) {
        for k in 1..per_interval {
            g.push(w[0] + (w[1] - w[0]) * k as f64 / per_interval as f64);
        }
    }
    for b in [&problem.lower, &problem.upper] {
        if let Bound::Polyline(v) = b {
            g.extend(v.iter().map(|q| q[0]));
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
    g.dedup_by(|a, b| (*a - *b).abs() < 1e-13 * (1.0 + b.abs()));
    g
}
