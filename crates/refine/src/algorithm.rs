//! Algorithm 4.1: the near-interpolatory k-level step with knot updates (part 1), then further
//! interpolatory steps (part 2); and the result with its certificates.

use divdiff::{Knots, Parametrization, Points};

use crate::certify::{certify, Certificate};
use crate::constraint::{Constraint, Kind};
use crate::degenerate;
use crate::problem::{Problem, Solver};
use crate::stage::{FixedProblem, FixedSolution};
use crate::Error;

/// Iteration counts of a refinement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Iterations {
    /// Fixed-knot solves over all stages ((knot_iterations + 1)(levels + 1) unless degenerate).
    pub solves: usize,
    /// Knot updates over all stages.
    pub knot_updates: usize,
    /// Inner iterations of the fixed-knot solver over all stages (multiplier updates of the
    /// paper's iteration, interior-point steps of the exact conic solver; 1 per linear solve).
    pub solver: usize,
}

/// The report of one stage of Algorithm 4.1 (stage 0 is part 1, stage l ≥ 1 is level l).
#[derive(Clone, Debug, PartialEq)]
pub struct Stage {
    /// The split parameter of this stage (k for stage 0, level_k after).
    pub k: usize,
    /// The number of refined vertices.
    pub vertices: usize,
    /// E of the stage's final points on its final knots.
    pub energy: f64,
    /// The relative KKT residual of the stage's final fixed-knot solve.
    pub kkt_residual: f64,
    /// max over inactive data vertices of |jmp| relative to the certificate's force scale
    /// (Corollary 3.3); `None` when no data vertex is inactive.
    pub jmp_inactive: Option<f64>,
}

/// The result of a refinement: what `curvefit refine` reports.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Refinement {
    /// The refined vertices p_1..p_N (a closed curve does not repeat p_1).
    pub points: Points,
    /// The knots those points were solved with: t_1..t_N open, t_1..t_{N+1} closed.
    pub knots: Knots,
    /// The 0-based index of the vertex attached to each data point q_i.
    pub data_vertex: Vec<usize>,
    /// E of (2.1) for `points` on `knots`.
    pub energy: f64,
    /// The multipliers of the constrained step (stage 0), per data point, in the convention of
    /// the constraint:
    /// - interpolation (and balls of radius 0): the d components of the reaction
    ///   λ_i = −(Hp)_{i_k}, so that (Hp)_{i_k} + λ_i = 0;
    /// - balls of radius ε_i > 0: `[w_i]`, Kersey's weight in (3.5), (Hp)_{i_k} + w_i(p_{i_k} − q_i) = 0;
    /// - smoothing: `[w_i]`, the given weight;
    /// - half-spaces: `[w_i1, …, w_im]`, (Hp)_{i_k} + Σ_j w_ij n_ij = 0 (3.8).
    pub multipliers: crate::Multipliers,
    /// Whether each data point's constraint is active in stage 0 (always for interpolation,
    /// never for smoothing).
    pub active: Vec<bool>,
    /// The largest relative KKT residual over all stages (see the crate docs for its definition).
    pub kkt_residual: f64,
    /// Iteration counts.
    pub iterations: Iterations,
    /// Per-stage energies and certificates.
    pub stages: Vec<Stage>,
}

impl Refinement {
    /// max over inactive data vertices of the relative |jmp| in stage 0 (Corollary 3.3), or
    /// `None` when every data vertex is active.
    pub fn jmp_inactive(&self) -> Option<f64> {
        self.stages.first().and_then(|s| s.jmp_inactive)
    }
}

fn dispatch(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    match fp.problem.solver {
        Solver::Exact => crate::strategy::exact(fp),
        Solver::Paper => crate::paper::paper(fp),
    }
}

/// Runs Algorithm 4.1 on a validated problem ([`Problem::solve`] validates it).
pub(crate) fn run(problem: &Problem) -> Result<Refinement, Error> {
    run_on(problem, problem.data_knots_unvalidated()?)
}

/// [`run`] from the data knots `u` (the problem's, [`Problem::data_knots_unvalidated`], formed
/// once by a caller that needed them first).
pub(crate) fn run_on(problem: &Problem, u: Knots) -> Result<Refinement, Error> {
    let q = &problem.points;
    let e = problem.parametrization;
    let mut iterations = Iterations::default();
    let mut stages = Vec::new();

    // A common point of all constraint sets makes a constant curve optimal (E = 0).
    let constant = degenerate::common_point(problem);

    // Part 1: the near-interpolatory k-level step.
    let k = problem.k;
    let mut data_vertex: Vec<usize> = (0..q.len()).map(|i| (k + 1) * i).collect();
    let (knots, first) = if constant.is_none() && closed_form_first(problem) {
        // The first solve is the closed form (`crate::uniform`), which needs only the data
        // knots on the split's grid, not the split knots: both at once, so that the serial
        // steps of each (the grid and the knots' validation, the data-row band solve and the
        // clearing of the output) overlap with the other's parallel ones. The same results bit
        // for bit as one after the other (`interpolate_from_data_values`).
        let v = exact_split_grid(u.values(), k + 1);
        let closed = u.is_closed();
        let vertices = Problem::refined_len(u.topology(), q.len(), k);
        let (knots, first) = crate::par::join(
            vertices,
            || split_on_grid(&v, u.topology(), k + 1),
            || crate::uniform::interpolate_from_data_values(&v, closed, q, k + 1),
        );
        // (A failed closed form is left to the strategies, which meet it again in order.)
        let first = first.ok().map(|p| FixedSolution::new(p, None, 1));
        (knots, first)
    } else {
        (split_knots(&u, k), None)
    };
    let mut knots = knots.map_err(|e| split_error(e, problem, k))?;
    let (mut p, multipliers, cert) = if let Some(c) = &constant {
        // The constant curve on the split knots; no knot update is possible (zero spans).
        let pts = constant_points(knots.vertex_count(), &c.point);
        let (cert, mult) = certify(
            &knots,
            &pts,
            q,
            &data_vertex,
            &problem.kinds(),
            Some(c.multipliers.clone()),
            &[],
            problem.derivative,
            problem.options.active_rtol,
        );
        iterations.solves += 1;
        (pts, mult, cert)
    } else {
        stage_loop(
            0,
            &mut knots,
            q,
            &data_vertex,
            &problem.constraint,
            problem,
            k + 1,
            e,
            first,
            &mut iterations,
        )?
    };
    let active = cert.active.clone();
    let mut energy = cert.energy;
    stages.push(stage_report(k, p.len(), &cert));
    let mut worst = cert.kkt_residual;

    // Part 2: further interpolatory level_k-level steps, re-initialized from the previous result.
    for level in 1..=problem.levels {
        let lk = problem.level_k;
        let mut next_knots = split_knots(&knots, lk)?;
        let dv: Vec<usize> = (0..p.len()).map(|i| (lk + 1) * i).collect();
        let (np, _, cert) = if constant.is_some() {
            let np = constant_points(next_knots.vertex_count(), p.point(0));
            let interpolate: [Box<dyn Kind>; 1] = [Constraint::Interpolate.kind()];
            let (cert, mult) = certify(
                &next_knots,
                &np,
                &p,
                &dv,
                &interpolate,
                None,
                &[],
                problem.derivative,
                problem.options.active_rtol,
            );
            iterations.solves += 1;
            (np, mult, cert)
        } else {
            stage_loop(
                level,
                &mut next_knots,
                &p,
                &dv,
                &Constraint::Interpolate,
                problem,
                lk + 1,
                e,
                None,
                &mut iterations,
            )?
        };
        worst = worst.max(cert.kkt_residual);
        energy = cert.energy;
        stages.push(stage_report(lk, np.len(), &cert));
        for v in &mut data_vertex {
            *v *= lk + 1;
        }
        p = np;
        knots = next_knots;
    }
    Ok(Refinement {
        points: p,
        knots,
        data_vertex,
        energy,
        multipliers,
        active,
        kkt_residual: worst,
        iterations,
        stages,
    })
}

/// The knots of the k-level split (3.1), without the points (interpolation does not need them).
///
/// The split is exact in floating point: the data knots are first rounded to the grid
/// g = (k + 1)·2^e, 2^e the smallest power of two with max|u| ≤ 2^52·2^e (a move of at most
/// (k + 1)/2 units in the last place of the largest knot), and every sub-knot is
/// u_i + j·((u_{i+1} − u_i)/(k + 1)), each operation exact on that grid. The sub-spans of a span
/// are then equal to the last bit. Why it matters: the closed-form interpolation
/// ([`crate::uniform`]) is the optimum on equal sub-spans, and with (1 − s)a + s·b the sub-spans
/// differ by rounding of the knot *values*, a relative error of order ε·N in the spans of the
/// N-vertex curve — at N = 8·10⁵ (noisy star, n = 10⁵, k = 7) enough to leave free vertices
/// 5·10⁻⁹ out of balance on the certificate's scale, and the solve refused.
pub(crate) fn split_knots(u: &Knots, k: usize) -> Result<Knots, Error> {
    let m = k + 1;
    split_on_grid(&exact_split_grid(u.values(), m), u.topology(), m)
}

/// The split of [`split_knots`] into `m` sub-spans per span of the data knot values `v`
/// already on its [`exact_split_grid`].
fn split_on_grid(v: &[f64], topology: divdiff::Topology, m: usize) -> Result<Knots, Error> {
    let spans = v.len() - 1;
    // Span by span, collected in parallel chunks (`crate::par`); the last unit is the last
    // knot alone. (Non-finite values are refused by `Knots::new` below.)
    let t = crate::par::collect_units(crate::par::Units {
        len: m * spans + 1,
        per_unit: m,
        head: |i: usize| match v.get(i + 1) {
            Some(&b) => (v[i], (b - v[i]) / m as f64),
            None => (v[spans], 0.0),
        },
        value: |&(a, step): &(f64, f64), j: usize| a + j as f64 * step,
        bad: |_: &f64| false,
    })
    .expect("no value is marked bad");
    Ok(Knots::new(topology, t)?)
}

/// The knot values rounded to the grid of [`split_knots`] on which the split into `m` equal
/// sub-spans is exact; the values unchanged when that grid is not representable (knots near the
/// bottom of the floating-point range, which validation refuses before they get here).
fn exact_split_grid(v: &[f64], m: usize) -> Vec<f64> {
    let big = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    // 2^e: the smallest power of two with big ≤ 2^52·2^e.
    let unit = power_of_two_at_least(big) * f64::EPSILON;
    let grid = m as f64 * unit;
    if !(unit.is_normal() && grid.is_finite()) {
        return v.to_vec();
    }
    // |round(x/g)|·m ≤ 2^52 + m: every product and sum of the split is an integer multiple of
    // `unit` below 2^53, so exact.
    crate::par::vectorized(OnGrid { v, grid })
}

/// The rounding of [`exact_split_grid`] as [`crate::par::vectorized`] runs it: with SSE4.1
/// `round` is a few vector instructions, on the x86-64 baseline a call into libm per knot
/// (~0.3 ms of the 10⁵-point interpolation's ~10).
struct OnGrid<'a> {
    v: &'a [f64],
    grid: f64,
}

impl pulp::WithSimd for OnGrid<'_> {
    type Output = Vec<f64>;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Vec<f64> {
        let grid = self.grid;
        self.v.iter().map(|&x| (x / grid).round() * grid).collect()
    }
}

/// The smallest power of two at least `x` (x > 0 finite; 0 for x = 0).
fn power_of_two_at_least(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return 0.0;
    }
    let mut p = 2f64.powi(x.log2().ceil() as i32);
    if p < x {
        p *= 2.0;
    }
    if p / 2.0 >= x {
        p /= 2.0;
    }
    p
}

/// The user's view of a failed split of the data knots: a data span too short, against the
/// knot values, to be cut into k + 1 increasing sub-spans — `knots[i]` when given, else the
/// data points (or the exponent) that made it.
fn split_error(e: Error, problem: &Problem, k: usize) -> Error {
    let Error::Divdiff(divdiff::Error::NonIncreasingKnots { index }) = e else {
        return e;
    };
    // Refined knot `index` lies in data span (index − 1)/(k + 1).
    let span = (index - 1) / (k + 1);
    if problem.knots.is_some() {
        Error::InvalidKnots {
            index: span + 1,
            reason:
                "too close to the previous knot to split the span into k + 1 increasing sub-spans",
        }
    } else {
        Error::InvalidValue {
            field: "points",
            index: (span + 1) % problem.points.len(),
            value: f64::NAN,
            reason: "so close to the previous point, against the curve's parameter length, that its span cannot be split into k + 1 sub-spans (or the parametrization's exponent is too large)",
        }
    }
}

fn stage_report(k: usize, vertices: usize, cert: &Certificate) -> Stage {
    Stage {
        k,
        vertices,
        energy: cert.energy,
        kkt_residual: cert.kkt_residual,
        jmp_inactive: cert.jmp_inactive,
    }
}

fn constant_points(n: usize, c: &[f64]) -> Points {
    let mut coords = Vec::with_capacity(n * c.len());
    for _ in 0..n {
        coords.extend_from_slice(c);
    }
    Points::new(c.len(), coords).expect("a finite common point")
}

/// The knot update of stage `stage` in place (Algorithm 4.1, [`crate::par::update_knots`]): the
/// knots of the refined vertices `points`, t_{j+1} = t_j + |p_{j+1} − p_j|^e, mapped affinely
/// onto the span [a, b] of the knots they replace: t'_j = a + (b − a)(t_j − t_0)/(t_N − t_0).
/// Every stage starts from the k-level split of the data parameters (or of the previous stage,
/// itself on the data span), so all knots of a refinement span the data parameters u_0 … u_n
/// whatever k and the number of updates: a derivative Df (clamped and near-clamped ends, tangent
/// constraints) is a derivative with respect to the data's parameter at every k, and E of (2.1)
/// is measured in that parameter. Without it the chords of the refined vertices set the scale
/// (knots 0…36 at k = 30 where the data span 0…3.2), and a clamped end derivative meant a
/// different curve at every k.
fn update_knots(
    knots: &mut Knots,
    points: &Points,
    param: Parametrization,
    stage: usize,
) -> Result<(), Error> {
    let vertices = knots.vertex_count();
    crate::par::update_knots(knots, points, param).map_err(|err| match err {
        crate::par::KnotUpdateError::Spans(err) => match err {
            divdiff::Error::ZeroLengthSpan { index, next } => {
                Error::DegenerateRefinedSpan { stage, index, next }
            }
            // A span |p_{j+1} − p_j|^e lost to rounding or overflowing: the exponent.
            divdiff::Error::NonIncreasingKnots { .. } | divdiff::Error::NonFinite { .. } => {
                Error::InvalidParameter {
                    field: "parametrization.exponent",
                    value: param.exponent(),
                    reason: "the knot update's spans |p_{j+1} - p_j|^e over- or underflow, or vanish against the knot values, at this exponent; use a smaller exponent or knot_iterations 0",
                }
            }
            e => Error::Divdiff(e),
        },
        crate::par::KnotUpdateError::Mapped(err) => match err {
            divdiff::Error::NonIncreasingKnots { index } => Error::DegenerateRefinedSpan {
                stage,
                index: index - 1,
                next: index % vertices,
            },
            e => Error::Divdiff(e),
        },
    })
}

/// Why a system that turned singular after a knot update is refused (`knot_iterations`).
const SINGULAR_AFTER_UPDATE: &str = "a knot update made the refined spans too unequal for a floating-point solve (the spans |p_{j+1} - p_j|^e nearly vanish where the curve almost stops, e.g. at a turning point of a heavily smoothed curve); use fewer knot updates or knot_iterations 0";

/// Why a singular smoothing system is refused (`weights`).
const SINGULAR_SMOOTHING: &str = "the smoothing system H + W is singular to rounding: the weights are too small against the curve's stiffness (about 1/h^3 of its shortest parameter spans h); use larger weights, fewer intermediate points (k), or a parametrization with less unequal spans";

/// Whether the exact solver's first entry answers stage 0's first solve with the closed form of
/// [`crate::uniform`]: interpolation with natural ends (the linear entry of
/// [`crate::strategy`], on the knots of the split).
fn closed_form_first(problem: &Problem) -> bool {
    problem.solver == Solver::Exact && problem.interpolates_with_natural_ends()
}

/// Solve on the initial knots (or take `first`, the first solve's answer computed beside the
/// knots), then `knot_iterations` times: update the knots from the refined vertices
/// (t_{i+1} = t_i + |p_{i+1} − p_i|^e), mapped back onto the data parameters' span
/// ([`update_knots`]), and solve again — so the returned points are the solution for the returned
/// knots.
#[allow(clippy::too_many_arguments)]
fn stage_loop(
    stage: usize,
    knots: &mut Knots,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
    problem: &Problem,
    stride: usize,
    param: Parametrization,
    mut first: Option<FixedSolution>,
    iterations: &mut Iterations,
) -> Result<(Points, crate::Multipliers, Certificate), Error> {
    let mut sol: Option<FixedSolution> = None;
    for knot_iteration in 0..=problem.knot_iterations {
        crate::progress::report(
            problem.options.progress.as_ref(),
            crate::Progress::Solve {
                stage,
                knot_iteration,
                knot_iterations: problem.knot_iterations,
            },
        );
        if let Some(FixedSolution { points, .. }) = &sol {
            // A constant curve is optimal on any knots, and its spans |p_{j+1} − p_j|^e all
            // vanish: there is nothing to update (`degenerate::is_constant`).
            if degenerate::is_constant(points) {
                break;
            }
            update_knots(knots, points, param, stage)?;
            iterations.knot_updates += 1;
        }
        // The last answer's points, when no warm start reads them (no multipliers), are the
        // next solve's to write into.
        let recycled = sol.take_if(|s| s.multipliers.is_none()).map(|s| s.points);
        let fp = FixedProblem {
            knots,
            q,
            data_vertex,
            constraint,
            problem,
            derivatives: stage == 0,
            stride,
            // Until the first knot update the knots are those of `split_knots`.
            uniform_spans: knot_iteration == 0,
            // The last solution starts the next solve (its active set, or all of it).
            warm: sol
                .as_ref()
                .and_then(|s| Some((&s.points, s.multipliers.as_deref()?))),
            recycled: std::cell::Cell::new(recycled),
            options: &problem.options,
        };
        let s = match first.take() {
            Some(s) => Ok(s),
            None => dispatch(&fp),
        }
        .map_err(|e| match e {
            // The same problem solved on the knots before this update: the update made the
            // refined spans too unequal for the floating-point solve (ROBUSTNESS.md §4, 14).
            Error::Energy(energy::Error::Singular { .. }) if knot_iteration > 0 => {
                Error::InvalidParameter {
                    field: "knot_iterations",
                    value: problem.knot_iterations as f64,
                    reason: SINGULAR_AFTER_UPDATE,
                }
            }
            // Smoothing alone: H + W is singular to rounding where the weights are small
            // against the stiffness ~1/h³ of the shortest spans (ROBUSTNESS.md §4, 5) — a
            // remedy only while the weight that makes a vertex fixed, ‖H‖/ε, is representable
            // (points at 1e-100 are badly scaled, not under-weighted). The Hessian is formed
            // again on this error path only.
            Error::Energy(energy::Error::Singular { .. }) => match constraint {
                Constraint::Smoothing(w)
                    if crate::linear::stiff_weight(&energy::Hessian::new(fp.knots)).is_finite() =>
                {
                    Error::InvalidParameter {
                        field: "weights",
                        value: w.iter().fold(0.0, |a: f64, &x| a.max(x)),
                        reason: SINGULAR_SMOOTHING,
                    }
                }
                _ => e,
            },
            // The solve before this update was certified: the updated knots are what the
            // method could not resolve (ROBUSTNESS.md §4, 15).
            Error::NotConverged {
                solver,
                iterations,
                residual,
            } if knot_iteration > 0 => Error::NotConvergedAfterUpdate {
                stage,
                update: knot_iteration,
                solver,
                iterations,
                residual,
            },
            // The same constraints were met on the knots before this update: what failed is
            // the method on the updated knots, and the guess at an infeasible constraint
            // (`ConicProblem::diagnose`) would send the user after the wrong cause.
            Error::NoFeasiblePointFound {
                violation,
                iterations,
                ..
            } if knot_iteration > 0 => Error::NotConvergedAfterUpdate {
                stage,
                update: knot_iteration,
                solver: "full-vertex interior point",
                iterations,
                residual: violation,
            },
            e => e,
        })?;
        iterations.solves += 1;
        iterations.solver += s.iterations;
        sol = Some(s);
    }
    let s = sol.expect("at least one solve");
    let tol = match problem.solver {
        Solver::Exact => problem.options.active_rtol,
        Solver::Paper => problem.options.paper.active_rtol,
    };
    let fp = FixedProblem {
        knots,
        q,
        data_vertex,
        constraint,
        problem,
        derivatives: stage == 0,
        stride,
        uniform_spans: false,
        warm: None,
        recycled: Default::default(),
        options: &problem.options,
    };
    let judge = |points: &Points, multipliers, derivative: &[(Vec<f64>, Vec<f64>)]| {
        certify(
            fp.knots,
            points,
            q,
            data_vertex,
            &fp.kinds(),
            multipliers,
            derivative,
            problem.derivative,
            tol,
        )
    };
    // (The exact solver's certificate, when it computed one to accept the points, is this one.)
    let (cert, mult) = match s.certificate {
        Some(c) if problem.solver == Solver::Exact => c,
        _ => judge(&s.points, s.multipliers, &s.derivative),
    };
    // A smoothing solve with one step of refinement that its certificate refuses (a cluster of
    // very short spans: `linear::linear`) is solved again, refined until its corrections are at
    // rounding. Only the stage that is returned: the stages before a knot update are not
    // certified, and this is where one step's answer is judged.
    let refuted = cert.kkt_residual.is_nan() || cert.kkt_residual > problem.options.accept_kkt;
    if refuted
        && problem.solver == Solver::Exact
        && matches!(constraint, Constraint::Smoothing(_))
        && fp.kinds().iter().all(|k| k.linear())
    {
        if let Ok(r) = crate::linear::solve(&fp, crate::linear::CONVERGED_STEPS) {
            let (c, m) = judge(&r.points, r.multipliers, &r.derivative);
            if c.kkt_residual < cert.kkt_residual || cert.kkt_residual.is_nan() {
                return Ok((r.points, m, c));
            }
        }
    }
    Ok((s.points, mult, cert))
}
