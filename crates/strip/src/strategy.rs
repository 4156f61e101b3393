//! The solver's strategy, as one ordered list (all in the normalized frame of [`crate::solve()`]):
//!
//! 1. **Feasibility and Remark 4.2** ([`crate::prepare`]): a problem without solution (the strip
//!    closes, a data value outside its bounds or on a kink no smooth curve can pass) is refused
//!    before any solve, in O(M + n); for bounds given as cubic pieces, data values on a bound are
//!    moved inside by the margin ε (polyline problems keep them: the exchange needs no margin).
//! 2. **Bounds given as cubic pieces per data interval** (the seed's §3): Newton's method (or the
//!    seed's BFGS) on Φ over the slopes at the data sites, every cell solved exactly among
//!    Theorem 2.1's shapes — the answer carries the structure of the theorem (touching points,
//!    subarcs, touching pairs) and a per-cell optimality certificate. Its stop is an answer only
//!    with the relative gap ½gᵀH⁻¹g / Φ ≤ [`ACCEPT_GAP`] and every f'' jump (at the sites: half
//!    the gradient; at the extra knots) at its rounding level ([`crate::C2_ROUNDING`]); if Newton
//!    stops short of that (its
//!    iteration limit, a line search that can no longer decrease Φ, or a stall: ten iterations
//!    that neither lower Φ by a tenth nor halve the f'' jumps, or three line-search iterations
//!    that lower Φ by no more than its rounding and do not halve them) or meets a cell outside
//!    Theorem 2.1's shapes, step 3 solves the problem instead (BFGS, the seed's method chosen
//!    explicitly, is refused with the gap).
//! 3. **Polyline bounds** (§4, any M), and the fallback of step 2: the dual active-set exchange
//!    ([`crate::exchange`]) on point constraints, driven by exact sweeps of the strip; it
//!    cannot cycle, and its answer is optimal for the points it holds (a lower bound on the
//!    optimum) and leaves the strip by at most [`crate::exchange::EXCHANGE_TOL`] of the value
//!    scale.
//!
//! **Why not Newton's method on Φ over all polyline vertices** (problem (10) of the seed, what
//! this crate did before): measured on the issue-15 channel (M = 10⁴, 16 sites), its Hessian in
//! the vertex values is a discrete fourth-order operator with condition number ~M⁴ ≈ 10¹⁶ (its
//! banded solve returns directions without a correct digit), and the contact structure changes
//! in hundreds of cells on the way (each change a kink of Φ that stops the line search): 200
//! iterations with Φ still falling by ~10⁻⁶ per iteration, gradient norm 10¹¹–10¹⁴. Started
//! from the vertex relaxation (the point problem on the vertices alone) on a grid of the segments
//! around its contacts, it converged on some channels (14 iterations, 0.07 s) but stopped
//! elsewhere where a vertex value rests on its bound with its slope at the edge of the kink cone
//! (f'' jumps there, yet the projected gradient vanishes: 1.1·10⁻⁵ above the optimum on one
//! channel while its Newton decrement claimed 10⁻²³), and flipped barely-touching cells between
//! free and touching on runs of segments that approximate a convex curve (linear convergence,
//! 200 iterations, gap 7·10⁻⁸). The exchange has none of these failure modes: its iterates are
//! splines (C² by construction, so a corner cannot hide), its linear algebra is a diagonally
//! dominant tridiagonal solve, and its steps are exact. Measured: 12–90 ms at M = 10⁴ against
//! Clarabel's fine-grid QP on the same vertices (see `cargo xtask bench strip`).

use crate::cell::CellStats;
use crate::error::Error;
use crate::exchange::{exchange, Exchanged, EXCHANGE_TOL};

/// The exchange's answer is returned when its gap estimate is at most this.
pub(crate) const ACCEPT_GAP: f64 = 1e-9;
use crate::outer::{self, setup, Hints, OuterOut, Setup};
use crate::prepare::prepare;
use crate::types::{Bound, Method, Options, Problem};
use crate::Progress;

/// What the strategy produces: the cells of the exact Φ-problem, or the exchange's spline.
pub(crate) enum Staged {
    Cells(CellsOut),
    Spline { q: Problem, ex: Exchanged },
}

/// The Φ-problem's answer.
pub(crate) struct CellsOut {
    pub setup: Setup,
    pub out: OuterOut,
    pub stats: CellStats,
    pub cell_solves: usize,
}

/// The exchange on `q`; `NotConverged` with the excursion left (relative to the value scale)
/// when it stops with the curve still outside the strip, `Uncertified` with its gap when it
/// converged but the gap is beyond what is reported as optimal.
fn by_exchange(q: Problem, vscale: f64, progress: &dyn Fn(&Progress)) -> Result<Staged, Error> {
    let ex = exchange(&q, EXCHANGE_TOL * vscale, vscale, progress);
    if !ex.converged || ex.gap.is_nan() {
        return Err(Error::NotConverged {
            solver: crate::EXCHANGE,
            iterations: ex.sweeps,
            residual: ex.violation / vscale,
        });
    }
    if ex.gap > ACCEPT_GAP {
        return Err(Error::Uncertified {
            solver: crate::EXCHANGE,
            iterations: ex.sweeps,
            gap: ex.gap,
            required: ACCEPT_GAP,
        });
    }
    Ok(Staged::Spline { q, ex })
}

/// Runs the strategy on the normalized problem `q0`; `unit` converts the gradient components
/// (slopes) to the caller's frame. Returns also the data moved by Remark 4.2.
pub(crate) fn run(
    q0: &Problem,
    opts: &Options,
    vscale: f64,
    unit: f64,
    progress: &dyn Fn(&Progress),
) -> Result<(Staged, Vec<usize>), Error> {
    if !(0.0..0.5).contains(&opts.boundary_margin) {
        return Err(Error::InvalidValue {
            field: "options.boundary_margin",
            index: 0,
            reason: "the margin must lie in [0, 0.5)",
        });
    }
    let polyline = matches!(q0.lower, Bound::Polyline(_)) || matches!(q0.upper, Bound::Polyline(_));
    // Remark 4.2's margin only for the cells of Φ (the exchange takes data on a bound as is)
    let (q, shifted) = prepare(q0, opts, vscale, !polyline)?;
    if polyline {
        if opts.method == Method::Bfgs {
            return Err(Error::InvalidValue {
                field: "options.method",
                index: 0,
                reason: "BFGS is the seed's method for cubic pieces; polyline bounds are solved by the exchange",
            });
        }
        return Ok((by_exchange(q, vscale, progress)?, shifted));
    }
    let mut st = setup(&q, opts, vscale)?;
    st.outer.unit.iter_mut().for_each(|u| *u = unit);
    let mut stats = CellStats::default();
    let mut cell_solves = 0;
    let mut x = std::mem::take(&mut st.x0);
    let m = q.t.len();
    let inside = |x: &[f64], stats: &mut CellStats, solves: &mut usize| {
        st.outer
            .eval(x, &mut vec![None; m - 1], None, stats, solves)
            .is_ok()
    };
    // the natural spline's slopes may lie outside Φ's domain (hair-thin strips, very short
    // spans): then the first alternative start inside it
    if !inside(&x, &mut stats, &mut cell_solves) {
        if let Some(alt) = outer::alternative_starts(&st.outer, &q.t, &x)
            .into_iter()
            .find(|alt| inside(alt, &mut stats, &mut cell_solves))
        {
            x = alt;
        }
    }
    let mut hints: Hints = vec![None; m - 1];
    let out = match opts.method {
        Method::Newton => outer::newton(
            &st.outer,
            x,
            opts,
            &mut hints,
            &mut stats,
            &mut cell_solves,
            progress,
        ),
        // the seed's BFGS stops when Φ no longer changes beyond rounding, with f'' still jumping
        // by ~1e-8 of max|f''| at the sites (measured on `conditioning.rs`'s base strip: 17
        // iterations, then 1.2e-8): Newton's method on the banded Hessian finishes the jumps
        // from its point, within the same iteration limit
        Method::Bfgs => {
            outer::bfgs(&st.outer, x, opts, &mut stats, &mut cell_solves).and_then(|b| {
                if !b.converged {
                    return Ok(b);
                }
                let rest = Options {
                    max_iterations: opts.max_iterations.saturating_sub(b.iterations),
                    ..*opts
                };
                let mut n = outer::newton(
                    &st.outer,
                    b.x,
                    &rest,
                    &mut hints,
                    &mut stats,
                    &mut cell_solves,
                    progress,
                )?;
                n.iterations += b.iterations;
                Ok(n)
            })
        }
    };
    // the relative gap ½gᵀH⁻¹g / Φ of a stopped Newton or BFGS run: a line search that can no
    // longer decrease Φ ends the iteration early, and on hair-thin cells (a short span among
    // long ones: Φ ~ 1e27 in the normalized frame, gradient ~1e19) that happened with the gap
    // still at 0.34 — returned as an answer until the gap was checked here
    let gap = |out: &OuterOut| {
        let d = if out.decrement.is_nan() {
            outer::decrement_at(&st.outer, &out.x, &out.grad)
        } else {
            out.decrement
        };
        if out.phi > 0.0 {
            (d / out.phi).max(0.0)
        } else if d <= 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    };
    // the f'' jumps at the sites and extra knots against their rounding level: Newton's stop
    // on its decrement (or a user's gradient tolerance) can leave Φ converged to 1e-15 while a
    // stiff site still jumps (fuzz/regressions/strip_json-c2-at-shifted-site.json: 7e-6 of
    // max|f''| with the gap at 5e-15), and such an answer is not the strip's optimum
    let c2 = |out: &OuterOut| st.outer.c2_defect(&out.sols, &out.grad);
    match out {
        Ok(out) if out.converged && gap(&out) <= ACCEPT_GAP && c2(&out).rounding <= 1.0 => Ok((
            Staged::Cells(CellsOut {
                setup: st,
                out,
                stats,
                cell_solves,
            }),
            shifted,
        )),
        // the iteration limit with Φ not converged, a stop with the gap open or f'' jumping
        // above rounding, or a cell outside Theorem 2.1's shapes (no feasible candidate): the
        // exchange, which needs neither
        Ok(_) | Err(Error::Unsupported { .. }) if opts.method == Method::Newton => {
            Ok((by_exchange(q, vscale, progress)?, shifted))
        }
        // the seed's BFGS, chosen explicitly: refused with the larger of its gap and its C²
        // defect (relative to max|f''|)
        Ok(out) => Err(Error::NotConverged {
            solver: "argmin BFGS",
            iterations: out.iterations,
            residual: gap(&out).max(c2(&out).relative),
        }),
        Err(e) => Err(e),
    }
}
