//! The seed's outer method, quasi-Newton on Φ(z) with the analytic gradient
//! ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)): argmin's limited-memory BFGS (`Vec<f64>` parameters,
//! argmin-math's "vec" backend). The seed's BFGS keeps a dense nv × nv inverse Hessian; the
//! limited-memory form keeps [`HISTORY`] pairs, so memory and work per iteration stay O(nv).

use std::cell::RefCell;

use argmin::core::{CostFunction, Executor, Gradient, State, TerminationReason};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;

use super::newton::DECREMENT_TOL;
use super::phi::{Hints, Outer, OuterOut};
use crate::cell::CellStats;
use crate::error::Error;
use crate::types::Options;

/// Evaluations of Φ allowed per permitted iteration (argmin's Moré–Thuente line search has no
/// iteration limit of its own; this bounds the whole solve).
const EVALUATIONS_PER_ITERATION: usize = 100;

/// Correction pairs kept by the limited-memory BFGS (Nocedal–Wright §7.2 suggest 3–20).
pub(crate) const HISTORY: usize = 10;

struct Phi<'a> {
    outer: &'a Outer,
    hints: &'a RefCell<Hints>,
    stats: &'a RefCell<(CellStats, usize)>,
    /// The cost reported outside Φ's domain (no feasible candidate in some interval).
    outside: f64,
    /// Evaluations so far and the budget.
    evaluations: &'a RefCell<(usize, usize)>,
}

impl Phi<'_> {
    fn vg(&self, x: &[f64]) -> Result<(f64, Vec<f64>), argmin::core::Error> {
        {
            let mut e = self.evaluations.borrow_mut();
            e.0 += 1;
            if e.0 > e.1 {
                return Err(argmin::core::Error::msg(format!(
                    "evaluation budget of {} exhausted",
                    e.1
                )));
            }
        }
        let mut h = self.hints.borrow_mut();
        let mut st = self.stats.borrow_mut();
        let (s, n) = &mut *st;
        match self.outer.eval(x, &mut h, None, s, n) {
            Ok(e) => Ok((e.phi, e.grad)),
            // outside the domain (no feasible candidate): a cost far above Φ(x₀) makes the line
            // search step back. It must be finite: an infinite cost turns the Moré–Thuente
            // cubic interpolation into NaN, and the search then never terminates.
            Err(_) => Ok((self.outside, vec![0.0; x.len()])),
        }
    }
}

impl CostFunction for Phi<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        self.vg(x).map(|v| v.0)
    }
}

impl Gradient for Phi<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        self.vg(x).map(|v| v.1)
    }
}

/// argmin stopped with an error (its evaluation budget, [`EVALUATIONS_PER_ITERATION`] per
/// permitted iteration, is the only one it can report here): out of iterations.
fn not_converged(iterations: usize) -> Error {
    Error::NotConverged {
        solver: "argmin BFGS",
        iterations,
        residual: f64::INFINITY,
    }
}

/// Outside Φ's domain BFGS sees the cost `OUTSIDE_FACTOR`·(1 + |Φ(x₀)|).
const OUTSIDE_FACTOR: f64 = 1e6;

/// argmin's BFGS on Φ from `x0` (data-site grids only: no box-constrained unknowns).
pub(crate) fn bfgs(
    outer: &Outer,
    x0: Vec<f64>,
    opts: &Options,
    stats: &mut CellStats,
    solves: &mut usize,
) -> Result<OuterOut, Error> {
    let nv = x0.len();
    let hints = RefCell::new(vec![None; outer.cells.len()]);
    let counters = RefCell::new((CellStats::default(), 0));
    let budget = EVALUATIONS_PER_ITERATION * (opts.max_iterations + 1);
    let evaluations = RefCell::new((0, budget));
    let mut phi = Phi {
        outer,
        hints: &hints,
        stats: &counters,
        outside: f64::INFINITY,
        evaluations: &evaluations,
    };
    let (f0, g0) = phi
        .vg(&x0)
        .map_err(|_| not_converged(opts.max_iterations))?;
    if !f0.is_finite() {
        // the start is outside Φ's domain
        let mut h = hints.borrow().clone();
        return match outer.eval(&x0, &mut h, None, stats, solves) {
            Err(j) => Err(outer.no_candidate(j)),
            Ok(_) => Err(crate::frame::scaled("y", 0)),
        };
    }
    phi.outside = OUTSIDE_FACTOR * (1.0 + f0.abs());
    let g0n = g0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut best = x0.clone();
    let mut iters = 0;
    let mut out_of_iterations = false;
    if nv > 0 {
        let ls = MoreThuenteLineSearch::new();
        let solver = LBFGS::new(ls, HISTORY)
            .with_tolerance_grad(opts.gradient_tol * (1.0 + g0n))
            // stop when an iteration no longer changes Φ beyond rounding (the gradient can stall
            // above its tolerance along stiff directions; the line search would then loop)
            .and_then(|s| s.with_tolerance_cost(DECREMENT_TOL * (1.0 + f0.abs())))
            .map_err(|_| not_converged(opts.max_iterations))?;
        let res = Executor::new(phi, solver)
            .configure(|s| s.param(x0).max_iters(opts.max_iterations as u64))
            .run()
            .map_err(|_| not_converged(opts.max_iterations))?;
        if let Some(p) = res.state().get_best_param() {
            best = p.clone();
        }
        iters = res.state().get_iter() as usize;
        out_of_iterations = matches!(
            res.state().get_termination_reason(),
            Some(TerminationReason::MaxItersReached)
        );
    }
    let mut h = hints.borrow().clone();
    let (st, n) = *counters.borrow();
    stats.candidates += st.candidates;
    *solves += n;
    let ev = outer
        .eval(&best, &mut h, None, stats, solves)
        .map_err(|j| outer.no_candidate(j))?;
    let (g, sols, phi) = (ev.grad, ev.sols, ev.phi);
    // out of iterations with neither the gradient (argmin's 2-norm test) nor Φ converged: the
    // strategy refuses it with the gap (never a silent answer)
    let g2 = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    let converged = !(out_of_iterations && g2 > opts.gradient_tol * (1.0 + g0n));
    Ok(OuterOut {
        decrement: f64::NAN,
        iterations: iters,
        converged,
        sols,
        x: best,
        grad: g,
        phi,
    })
}
