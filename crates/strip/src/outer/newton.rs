//! Newton's method on the tridiagonal Hessian of Φ, with a backtracking line search.

use super::phi::{inf_norm, Hints, Outer, OuterOut};
use crate::cell::CellStats;
use crate::error::Error;
use crate::linalg::Band;
use crate::types::Options;
use crate::Progress;

/// Below this fraction of 1 + Φ the Newton decrement ½ gᵀH⁻¹g no longer shows progress in Φ
/// (normalized frame: Φ is of unit order), and the iteration polishes (see [`PHI_ROUNDING`]).
pub(crate) const DECREMENT_TOL: f64 = 1e-15;
/// Once the decrement is below [`DECREMENT_TOL`], full Newton steps are taken without a line
/// search as long as they reduce ‖∇Φ‖∞ (the f'' jumps at the sites) and Φ rises by at most this
/// fraction of 1 + |Φ| (its rounding level) …
const PHI_ROUNDING: f64 = 1e-14;
/// … and at most this many of them.
const POLISH_STEPS: usize = 3;
/// Line-search backtracking steps before giving up.
const LINE_SEARCH_STEPS: usize = 60;
/// Armijo sufficient-decrease constant.
const ARMIJO: f64 = 1e-4;
/// Newton stalls when Φ fell, over this many iterations, by less than [`STALL_PROGRESS`] of what
/// the Newton decrement says is left …
const STALL_ITERATIONS: usize = 10;
/// … this fraction. Then the cells' shapes keep the line search from making progress (Φ
/// jumps across candidate regions), and the iteration stops, not converged, for the exchange
/// to solve the problem (`crate::strategy`). Measured on 5000 alternating values with
/// cubic-piece bounds 10⁻⁷ from them (ROBUSTNESS.md §4 item 17): 154 iterations and 33.7 s
/// with the decrement at 35–92 % of Φ throughout while Φ fell by 2·10⁻⁴ of itself in all;
/// healthy runs take 5–20 iterations, each gaining a large part of the decrement.
const STALL_PROGRESS: f64 = 1e-3;
/// Newton also stalls when, over [`STALL_ITERATIONS`] iterations, Φ fell by no more than
/// [`STALL_PHI`] of itself (plus its rounding, [`PHI_ROUNDING`] of 1 + |Φ|) while ‖∇Φ‖∞ (twice
/// the largest f'' jump at a site) did not fall below this fraction of itself. Two kinds of run
/// end there, measured on sweep problems (`xtask/sweeps/strip.py`):
/// - a plateau: the line search accepts steps at Φ's rounding level (Armijo's decrease below
///   one ulp of Φ) that change neither Φ nor the jumps (seed 3, case 17: 300 clustered sites,
///   bounds 1.5e-5 of the value range about the data polygon; from iteration 25 to the limit of
///   200, Φ = 2.3104363425354486e17 and ‖∇Φ‖∞ = 2.7544361e6 unchanged, ten thousand cell solves
///   an iteration, 43 s, before the exchange took over: 0.1 s);
/// - a crawl: Φ falls by a few per cent an iteration with the jumps as large as f'' itself
///   (seed 1, case 42: 5000 sites with spans from 3e-9 to 304, half-width 2.3e-6; 30 iterations
///   and 31 s before [`STALL_PROGRESS`]'s test, which needs undamped steps, stopped it).
///
/// A converging Newton iteration halves ‖∇Φ‖∞ in fewer steps (quadratic convergence; the polish
/// steps near rounding reduce it or stop). On the sweep's seeds 1 … 5 (1000 problems) the crawl's
/// part of the test (`STALL_PHI` > 0) changed no answer: 881 outputs byte-identical with those
/// of the plateau's part alone, the same exit codes, and case 42 refused in 5.9 s instead of 36 s
/// (61 s with neither part).
const STALL_GRADIENT: f64 = 0.5;
/// See [`STALL_GRADIENT`].
const STALL_PHI: f64 = 0.1;
/// Newton also stalls sooner, after this many iterations in a row whose steps the line search
/// chose (the polish's full steps below [`DECREMENT_TOL`] keep Φ at its rounding on purpose, and
/// are not counted), when Φ fell over them by no more than its rounding ([`PHI_ROUNDING`] of
/// 1 + |Φ|) while ‖∇Φ‖∞ did not fall below [`STALL_GRADIENT`] of itself: the plateau of
/// [`STALL_GRADIENT`]'s first kind, where the decrement is still above [`DECREMENT_TOL`] (so no
/// full steps are tried) but the Armijo test's decrease lies below the rounding of Φ (a sum over
/// every cell), so a step is accepted or refused by its roundings and the line search halves its
/// way down to steps that change nothing. Such iterations cost the most: on `strip.py` seed 787,
/// case 189 (5000 even sites, step values, a band of 2.6e-6 of the range), iterations 14 … 21
/// moved Φ = 1.6456e19 by 6e3 in all (an ulp is 2e3) with ‖∇Φ‖∞ at 2.9e5 throughout, taking
/// 9 … 19 halvings and 55 000 … 105 000 cell solves each — 25 of the problem's 39 s before the
/// ten-iteration test stopped it and the exchange answered (refused, as now: gap 2.5e-9; now
/// 14 s). A converging iteration halves ‖∇Φ‖∞ in fewer steps, or takes the polish's full steps.
/// Once, on seed 719's case 9 (30 sites), Newton left such a plateau after five iterations (a
/// step that moved the cells' shapes); stopped after three, the exchange's answer has ∫f''²
/// 8.8e-11 of itself below Newton's (ROBUSTNESS.md item 52).
const STALL_ROUNDING_ITERATIONS: usize = 3;

/// Projected Newton on the banded Hessian. Returns (x, iterations, (cells, x, gradient)).
pub(crate) fn newton(
    o: &Outer,
    mut x: Vec<f64>,
    opts: &Options,
    hints: &mut Hints,
    stats: &mut CellStats,
    solves: &mut usize,
    progress: &dyn Fn(&Progress),
) -> Result<OuterOut, Error> {
    let nv = o.nvar;
    let mut band = Band::zeros(nv);
    let mut ev = o
        .eval(&x, hints, Some(&mut band), stats, solves)
        .map_err(|j| o.no_candidate(j))?;
    // ∂Φ/∂z_i is twice the f'' jump at site i: the tolerance is relative to the size of f'' at
    // the current iterate. (It was relative to 1 + ‖∇Φ(z₀)‖∞, which a start far from the
    // optimum makes huge: 3e8 on fuzz/regressions/strip_json-c2-at-shifted-site.json, where the
    // iteration then stopped with f'' jumping by 7e-6 of max|f''| at a site.)
    let tol = |ev: &super::phi::Eval| opts.gradient_tol * 2.0 * ev.f2;
    let mut it = 0;
    let mut polished = 0;
    let mut newton_decrement = 0.0;
    // Φ at the start of each iteration with an undamped Newton direction (where the decrement
    // is measured), for the stall test
    let mut history: Vec<f64> = Vec::new();
    // Φ and ‖∇Φ‖∞ at the start of every iteration, for the stall test of STALL_GRADIENT
    let mut trail: Vec<(f64, f64)> = Vec::new();
    let mut stalled = false;
    // iterations in a row whose step the line search chose (not a polish step, which keeps Φ
    // at its rounding on purpose), for the test of STALL_ROUNDING_ITERATIONS
    let mut searched = 0;
    while it < opts.max_iterations {
        let gnorm = inf_norm(&ev.grad);
        if gnorm <= tol(&ev) || nv == 0 {
            break;
        }
        trail.push((ev.phi, gnorm));
        // over the last `window` iterations Φ fell by no more than `fraction` of itself (plus
        // its rounding) while ‖∇Φ‖∞ did not fall below STALL_GRADIENT of itself
        let plateau = |window: usize, fraction: f64| {
            trail.len().checked_sub(window + 1).is_some_and(|k| {
                let (phi0, g0) = trail[k];
                phi0 - ev.phi <= fraction * phi0.abs() + PHI_ROUNDING * (1.0 + ev.phi.abs())
                    && gnorm > STALL_GRADIENT * g0
            })
        };
        if plateau(STALL_ITERATIONS, STALL_PHI)
            || (searched >= STALL_ROUNDING_ITERATIONS && plateau(STALL_ROUNDING_ITERATIONS, 0.0))
        {
            stalled = true;
            break;
        }
        it += 1;
        progress(&Progress::Newton {
            iteration: it,
            jump: gnorm / (2.0 * ev.f2.max(f64::MIN_POSITIVE)),
            cell_solves: *solves,
        });
        let hb = band.clone();
        let rhs: Vec<f64> = ev.grad.iter().map(|g| -g).collect();
        newton_decrement = f64::INFINITY;
        let mut lambda = 0.0;
        let maxdiag = hb.max_abs_diagonal().max(1e-300);
        let dir = loop {
            let mut hl = hb.clone();
            hl.shift_diagonal(lambda);
            if let Some(d) = hl.solve(&rhs) {
                break d;
            }
            lambda = if lambda == 0.0 {
                1e-12 * maxdiag
            } else {
                lambda * 10.0
            };
            if lambda > 1e6 * maxdiag {
                break rhs.clone();
            }
        };
        // Newton decrement: ½ gᵀH⁻¹g estimates Φ − min Φ; along very stiff directions (contacts
        // next to a grid point) it is the meaningful measure of progress in Φ, not ‖g‖. But
        // Φ − min Φ ~ 1e-15 Φ still leaves the unknowns off by up to ~√1e-15 along soft
        // directions, and the f'' jumps (the gradient) off by as much, while Φ can no longer see
        // progress there (Armijo tests at rounding level accept or refuse at random). So once the
        // decrement is that small, full Newton steps are taken as long as they reduce ‖g‖∞ and Φ
        // does not rise beyond rounding (at most POLISH_STEPS of them; Newton converges
        // quadratically), and the solve stops when a full step no longer reduces ‖g‖∞: the jumps
        // are then at the rounding level of their evaluation.
        let mut polish = None;
        if lambda == 0.0 {
            newton_decrement = 0.5 * (0..nv).map(|k| rhs[k] * dir[k]).sum::<f64>();
            history.push(ev.phi);
            if history.len() > STALL_ITERATIONS
                && newton_decrement > ACCEPT_DECREMENT * (1.0 + ev.phi.abs())
                && history[history.len() - 1 - STALL_ITERATIONS] - ev.phi
                    < STALL_PROGRESS * newton_decrement
            {
                stalled = true;
                break;
            }
            if newton_decrement <= DECREMENT_TOL * (1.0 + ev.phi.abs()) {
                if polished >= POLISH_STEPS {
                    break;
                }
                polished += 1;
                let xn: Vec<f64> = (0..nv).map(|k| x[k] + dir[k]).collect();
                let mut h2 = hints.clone();
                match o.eval(&xn, &mut h2, None, stats, solves) {
                    Ok(e)
                        if e.phi <= ev.phi + PHI_ROUNDING * (1.0 + ev.phi.abs())
                            && inf_norm(&e.grad) < inf_norm(&ev.grad) =>
                    {
                        polish = Some((xn, h2, e.phi));
                    }
                    _ => break,
                }
            }
        }
        // backtracking line search along the Newton direction; if it cannot decrease
        // Φ (a Hessian that jumps across candidate regions), along the diagonally scaled and
        // then the plain negative gradient
        let diag_dir: Vec<f64> = band
            .diagonal()
            .iter()
            .zip(&ev.grad)
            .map(|(&d, g)| -g / if d > 0.0 { d } else { 1.0 })
            .collect();
        let grad_dir: Vec<f64> = ev.grad.iter().map(|g| -g).collect();
        let polishing = polish.is_some();
        let mut accepted = polish;
        for dir in [&dir, &diag_dir, &grad_dir] {
            if accepted.is_some() {
                break;
            }
            let mut alpha = 1.0;
            for _ in 0..LINE_SEARCH_STEPS {
                let xn: Vec<f64> = (0..nv).map(|k| x[k] + alpha * dir[k]).collect();
                let mut h2 = hints.clone();
                if let Ok(e) = o.eval(&xn, &mut h2, None, stats, solves) {
                    let dec: f64 = (0..nv).map(|k| ev.grad[k] * (xn[k] - x[k])).sum();
                    if dec < 0.0 && e.phi <= ev.phi + ARMIJO * dec {
                        accepted = Some((xn, h2, e.phi));
                        break;
                    }
                }
                alpha *= 0.5;
            }
            if accepted.is_some() {
                break;
            }
        }
        let Some((xn, h2, _)) = accepted else {
            break; // no further decrease representable: converged to rounding
        };
        searched = if polishing { 0 } else { searched + 1 };
        x = xn;
        *hints = h2;
        band = Band::zeros(nv);
        ev = o
            .eval(&x, hints, Some(&mut band), stats, solves)
            .map_err(|j| o.no_candidate(j))?;
    }
    // the decrement at the final point
    newton_decrement = match band.solve(&ev.grad) {
        Some(d) => 0.5 * ev.grad.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>(),
        None => newton_decrement,
    };
    // out of iterations with neither the gradient nor the decrement (the estimate of Φ − min Φ)
    // converged: the caller decides (see `crate::strategy`)
    let decrement_ok = newton_decrement <= ACCEPT_DECREMENT * (1.0 + ev.phi.abs());
    let converged =
        !stalled && (it < opts.max_iterations || inf_norm(&ev.grad) <= tol(&ev) || decrement_ok);
    Ok(OuterOut {
        decrement: newton_decrement,
        iterations: it,
        converged,
        sols: ev.sols,
        x,
        grad: ev.grad,
        phi: ev.phi,
    })
}

/// The Newton decrement ½ gᵀH⁻¹g at `x` (the estimate of Φ − min Φ), from one evaluation of
/// the Hessian; NaN when that fails.
pub(crate) fn decrement_at(o: &Outer, x: &[f64], grad: &[f64]) -> f64 {
    let mut band = Band::zeros(o.nvar);
    let m = o.cells.len();
    if o.eval(
        x,
        &mut vec![None; m],
        Some(&mut band),
        &mut CellStats::default(),
        &mut 0,
    )
    .is_err()
    {
        return f64::NAN;
    }
    match band.solve(grad) {
        Some(d) => 0.5 * grad.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>(),
        None => f64::NAN,
    }
}

/// Relative Newton decrement below which a solve that ran out of iterations is still accepted
/// (Φ is within this fraction of its minimum: the gradient can stall at kinks of polyline bounds
/// while Φ has converged).
pub(crate) const ACCEPT_DECREMENT: f64 = 1e-9;
