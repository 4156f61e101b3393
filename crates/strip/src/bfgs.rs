//! The seed's outer method: argmin's BFGS on Φ(z) with the analytic gradient
//! ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)) (`Vec<f64>` parameters, argmin-math's "vec" backend).

use std::cell::RefCell;

use argmin::core::{CostFunction, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::BFGS;

use crate::cell::{CellSolution, CellStats};
use crate::error::Error;
use crate::solve::{Hints, Options, OuterRef};

struct Phi<'a> {
    outer: &'a OuterRef<'a>,
    hints: &'a RefCell<Hints>,
    stats: &'a RefCell<(CellStats, usize)>,
}

impl Phi<'_> {
    fn vg(&self, x: &[f64]) -> Result<(f64, Vec<f64>), argmin::core::Error> {
        let mut h = self.hints.borrow_mut();
        let mut st = self.stats.borrow_mut();
        let (s, n) = &mut *st;
        match self.outer.value_grad(x, &mut h, s, n) {
            Ok((f, g, _)) => Ok((f, g)),
            // outside the domain (no feasible candidate): an infinite cost makes the line
            // search step back
            Err(_) => Ok((f64::INFINITY, vec![0.0; x.len()])),
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

type Out = (f64, usize, (Vec<CellSolution>, Vec<f64>, Vec<f64>));

pub(crate) fn bfgs(
    outer: &OuterRef<'_>,
    x0: Vec<f64>,
    opts: &Options,
    stats: &mut CellStats,
    solves: &mut usize,
) -> Result<Out, Error> {
    let nv = x0.len();
    let hints = RefCell::new(vec![None; outer.cells()]);
    let counters = RefCell::new((CellStats::default(), 0));
    let phi = Phi {
        outer,
        hints: &hints,
        stats: &counters,
    };
    let (_, g0) = phi.vg(&x0).map_err(|e| Error::Bfgs {
        message: e.to_string(),
    })?;
    let g0n = g0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut best = x0.clone();
    let mut iters = 0;
    if nv > 0 {
        let ls = MoreThuenteLineSearch::new();
        let solver = BFGS::new(ls)
            .with_tolerance_grad(opts.gradient_tol * (1.0 + g0n))
            .and_then(|s| s.with_tolerance_cost(0.0))
            .map_err(|e| Error::Bfgs {
                message: e.to_string(),
            })?;
        let mut h0 = vec![vec![0.0; nv]; nv];
        for (i, row) in h0.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        let res = Executor::new(phi, solver)
            .configure(|s| {
                s.param(x0)
                    .inv_hessian(h0)
                    .max_iters(opts.max_iterations as u64)
            })
            .run()
            .map_err(|e| Error::Bfgs {
                message: e.to_string(),
            })?;
        if let Some(p) = res.state().get_best_param() {
            best = p.clone();
        }
        iters = res.state().get_iter() as usize;
    }
    let mut h = hints.borrow().clone();
    let (st, n) = *counters.borrow();
    stats.candidates += st.candidates;
    *solves += n;
    let (_, g, sols) = outer
        .value_grad(&best, &mut h, stats, solves)
        .map_err(|interval| Error::NoFeasibleCandidate { interval })?;
    Ok((f64::NAN, iters, (sols, best, g)))
}
