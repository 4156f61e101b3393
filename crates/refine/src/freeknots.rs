//! Optimal free knots (beyond Kersey §4): minimize E over the knots for fixed total parameter
//! length.
//!
//! # The problem
//!
//! For the near-interpolatory k-level step of a [`Problem`] (stage 0 of Algorithm 4.1) with
//! refined knots t, let p*(t) be the exact fixed-knot optimum (the problem layer's exact solve)
//! and F(t) = E(p*(t), t) — for smoothing, F(t) = E + ½Σ w_i |p*_{i_k} − q_i|². The variational
//! ("free-knot") parametrization minimizes F over the free knots with the total length
//! T = t_last − t_first fixed (E is homogeneous of degree −3 in the knots, so without the length
//! constraint the infimum is 0 at T → ∞). The free knots ([`FreeKnots`]) are by default the data
//! knots u_i, each data span being split into k + 1 equal sub-spans as in (3.1); freeing every
//! refined knot, as Kersey's Theorems 3.1–3.2 do (i = 1:nk), turns out to be degenerate (the
//! sub-spans next to the data points collapse, see [`FreeKnots::All`]).
//!
//! **Envelope theorem.** The constraints (interpolation, balls, half-spaces, smoothing
//! penalties) act on the positions p_{i_k} only and do not depend on t, and p*(t) is the
//! unique minimizer; hence dF/dt = ∂E/∂t (p*(t), t): the exact knot gradient of
//! [`energy::knot_gradient`] (Lemma 2.4 corrected, math.md §1) evaluated at p*, with no
//! derivative of p* needed. **Tangent constraints and clamped ends do depend on t** (the
//! approximate derivative Df(t_i) is a knot-dependent stencil, Kersey §3.5: "one cannot vary t_i
//! freely with p_i fixed"), so the envelope formula would be wrong for them: they are rejected
//! with [`Error::Unsupported`]. The gradient is as accurate as p*: conic fixed-knot solves
//! (balls, half-spaces) carry their interior-point tolerance into it.
//!
//! **Parametrization.** The free spans are H = T·softmax(θ), so they stay positive and sum to T
//! for every θ; each is split into m equal refined spans (m = k + 1 for data knots, 1 for all
//! knots) and the knots are t_0 + cumulative sums. With g_j = ∂F/∂h_j per refined span (from
//! ∂E/∂t_k = g_{k−1} − g_k, so g_j = −Σ_{k≤j} ∂E/∂t_k) and G_i = (1/m) Σ_{j in span i} g_j, the chain
//! rule gives ∂F/∂θ_i = H_i (G_i − Ḡ), Ḡ = Σ_i H_i G_i / T. Homogeneity gives Σ_i H_i G_i = −3E,
//! so Ḡ = −3E/T: at a stationary point every G_i equals the fixed-length multiplier μ = −3E/T.
//! Everything is O(N) per evaluation (one banded fixed-knot solve, or one interior-point solve
//! whose steps are banded, plus O(N) gradients).
//!
//! **Optimizer.** L-BFGS in θ ([`FreeKnotOptions::memory`] pairs) with Armijo backtracking,
//! started from the centripetal knots (the problem's parametrization; see [`FreeKnots`] for the
//! exact start). At most [`FreeKnotOptions::max_iterations`] iterations; it stops when the
//! relative stationarity residual (below) is at most [`FreeKnotOptions::tolerance`], when E is 0
//! up to rounding ([`FreeKnotOptions::zero_energy`]), or when a line search finds no acceptable step
//! (then `converged` is false). Every accepted step lowers F (up to
//! [`FreeKnotOptions::rounding_slack`] relative, for steps taken in F's rounding noise).
//!
//! The iteration is written out here (the two-loop recursion and the line search, ~70 lines)
//! rather than taken from argmin: argmin's L-BFGS stops on the 2-norm of the gradient or on
//! the change of F, while this problem's test is the scale-free stationarity above (the
//! θ-gradient H_i(G_i − Ḡ) shrinks with the spans), and near the optimum it must accept steps
//! whose decrease is below F's rounding while the stationarity still falls — a line search that
//! requires strict sufficient decrease stalls there (strip's argmin BFGS needed an evaluation
//! budget for the same reason). So `refine` does not depend on argmin.
//!
//! # Residuals (Corollaries 2.5–2.7, Theorems 3.1–3.2, corrected)
//!
//! [`KnotDiagnostics`] reports, relative to the scale σ = 3E/T = |μ|:
//! - `stationarity` = max_i |∂F/∂H_i − μ| / σ, the first-order condition with the fixed-length
//!   multiplier removed (0 at optimal knots);
//! - `knot_residual` = max_b |dF/du_b| / σ over the free knots (every data knot of a closed curve,
//!   the interior ones of an open curve, whose end knots carry the multiplier);
//! - `vertex_knot_residual` = max_i |∂E/∂t_i| / σ over the refined vertices whose parameter is free
//!   (every vertex of a closed curve — vertex 0's parameter moving t_0 and t_N together — and the
//!   interior vertices of an open one): the **corrected Corollary 2.5 / Theorem 3.1–3.2 knot
//!   condition**. It is 0 at the data-knot optimum too (see [`FreeKnots::Data`]).
//! - `orthogonality_max` = max_i |Df(t_i)·(Hp)_i| / σ over the same vertices, **Corollary 2.7**'s
//!   approximate condition (and Theorem 3.2's w_i (p_{i_k} − q_i)·Df(t_{i_k}) ≈ 0, the same number
//!   at a data vertex since (Hp)_{i_k} = −w_i(p_{i_k} − q_i)). It is only approximately 0 at the
//!   optimum: the exact condition reads −Df(t_i)·(Hp)_i + |Δ_{i,2} f|² − |Δ_{i−2,2} f|² ≈ 0 (see
//!   [`energy::orthogonality_residuals`]).

use banded::vector::dot;
use divdiff::{Knots, Points, Topology};

use crate::{Boundary, Constraint, Error, Problem, Refinement, Solver};

/// Options of [`optimize_knots`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct FreeKnotOptions {
    /// Iteration limit (default 300).
    pub max_iterations: usize,
    /// Stop when the relative stationarity residual is at most this (default 1e-7: F is flat
    /// to second order near its minimum, so its decrease falls below rounding, ≈ 1e−16
    /// relative, once the residual is about 1e−8).
    pub tolerance: f64,
    /// L-BFGS correction pairs (default 8).
    pub memory: usize,
    /// Backtracking halvings per line search before the iteration stops (default 40).
    pub line_search_steps: usize,
    /// Armijo's sufficient-decrease constant (default 1e-4).
    pub armijo: f64,
    /// Largest change of any θ_j (log-span) in one step (default 2: spans change by at most a
    /// factor e²).
    pub max_step: f64,
    /// Relative slack of the sufficient-decrease test for rounding in F (default 1e-14): a step
    /// is also accepted when F rises by at most this times |F| while the stationarity residual
    /// falls (near the optimum F's decrease is below rounding while its gradient still
    /// decreases), so F may rise by rounding only.
    pub rounding_slack: f64,
    /// E counts as 0 (a straight or constant optimum: every knot vector is optimal) below this
    /// times L²/T³, L the data polygon's length (default 1e-20).
    pub zero_energy: f64,
    /// The fixed total parameter length T; `None` (default) keeps the length of the starting
    /// (centripetal) knots, which are rescaled to T otherwise.
    pub total_length: Option<f64>,
    /// Which knots are free (default [`FreeKnots::Data`]).
    pub free: FreeKnots,
}

/// Which knots the optimization moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FreeKnots {
    /// The data knots u_i (one per data point, n + 1 for a closed curve, the ends of an open
    /// curve and T fixed); every data span is split into k + 1 equal sub-spans as in (3.1).
    /// Well posed for interpolation: a data span of length → 0 between distinct interpolated
    /// points costs E → ∞. (With balls or half-space sets, if the sets of two consecutive data
    /// points intersect, p_{i_k} = p_{(i+1)_k} is feasible and that data span may shrink to 0:
    /// the infimum is then not attained and the iteration ends with `converged = false`.)
    /// The start is the split of the problem's data parametrization (Algorithm 4.1 with no knot
    /// update). At a free vertex (Hp)_i = 0, and with equal sub-spans on both sides the exact
    /// ∂E/∂t_i then vanishes identically (∂E/∂t_i = |J|²(h_{i−1} + h_i)(h_i − h_{i−1}) with J the common third
    /// difference), so the optimum also satisfies the corrected all-knot conditions of
    /// Theorem 3.1–3.2 ([`KnotDiagnostics::vertex_knot_residual`] ≈ 0).
    #[default]
    Data,
    /// Every refined knot (Kersey's Theorem 3.1–3.2 setting, i = 1:nk). **Degenerate:** the
    /// infimum is not attained — sub-spans next to the data vertices shrink to 0 and the
    /// intermediate vertices collapse onto the data points, E tending to the coarse polygon's
    /// energy; the iteration then stops at its limit with `converged = false`. (The
    /// [`FreeKnots::Data`] optimum is a stationary point of this problem but not a minimum.) Kept
    /// to demonstrate that. The start is Algorithm 4.1's stage 0 (with its knot updates).
    All,
}

impl Default for FreeKnotOptions {
    fn default() -> Self {
        FreeKnotOptions {
            max_iterations: 300,
            tolerance: 1e-7,
            memory: 8,
            line_search_steps: 40,
            armijo: 1e-4,
            max_step: 2.0,
            rounding_slack: 1e-14,
            zero_energy: 1e-20,
            total_length: None,
            free: FreeKnots::Data,
        }
    }
}

impl FreeKnotOptions {
    /// Sets the iteration limit.
    pub fn with_max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Sets the stopping tolerance.
    pub fn with_tolerance(mut self, tol: f64) -> Self {
        self.tolerance = tol;
        self
    }
    /// Sets the total parameter length T.
    pub fn with_total_length(mut self, t: f64) -> Self {
        self.total_length = Some(t);
        self
    }
    /// Sets which knots are free.
    pub fn with_free(mut self, free: FreeKnots) -> Self {
        self.free = free;
        self
    }
}

/// The knot optimality diagnostics of one fixed-knot optimum (see the module docs; all
/// residuals are relative to σ = 3E/T).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct KnotDiagnostics {
    /// E of (2.1).
    pub energy: f64,
    /// The minimized objective: E, plus ½Σ w_i |p_{i_k} − q_i|² for smoothing.
    pub objective: f64,
    /// The relative KKT residual of the fixed-knot solve.
    pub kkt_residual: f64,
    /// dF/du_b for every free knot u_b of the chosen [`FreeKnots`] (the data knots, or every
    /// refined knot), each moving the refined knots of its two adjacent groups affinely.
    pub free_knot_gradient: Vec<f64>,
    /// max |dF/du_b| / σ over the free knots: the corrected free-knot condition, 0 at the optimum.
    pub knot_residual: f64,
    /// max_i |∂F/∂H_i + 3E/T| / σ over the free spans H_i: stationarity with the fixed-length
    /// multiplier removed (what the iteration drives to its tolerance).
    pub stationarity: f64,
    /// The exact ∂E/∂t_i per refined vertex ([`energy::vertex_knot_gradient`]) at these points:
    /// Theorem 3.1–3.2's knot condition over all refined knots (i = 1:nk), corrected.
    pub knot_gradient: Vec<f64>,
    /// max |∂E/∂t_i| / σ over the refined vertices with a free parameter (all of a closed curve,
    /// the interior ones of an open curve). 0 only at a stationary point of [`FreeKnots::All`].
    pub vertex_knot_residual: f64,
    /// Df(t_i)·(Hp)_i per vertex (Corollary 2.7, with the problem's derivative rule).
    pub orthogonality: Vec<f64>,
    /// max |Df(t_i)·(Hp)_i| / σ over the vertices with a free parameter (as
    /// `vertex_knot_residual`; an open curve's end knots carry the length multiplier).
    pub orthogonality_max: f64,
}

/// The result of [`optimize_knots`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct FreeKnotResult {
    /// The refined vertices at the optimal knots (the exact fixed-knot optimum on `knots`).
    pub points: Points,
    /// The optimal refined knots (total length `total_length`).
    pub knots: Knots,
    /// The vertex attached to each data point.
    pub data_vertex: Vec<usize>,
    /// The fixed total parameter length T.
    pub total_length: f64,
    /// Which knots were free.
    pub free: FreeKnots,
    /// Diagnostics on the starting (centripetal by default) knots, rescaled to T.
    pub before: KnotDiagnostics,
    /// Diagnostics on the optimal knots.
    pub after: KnotDiagnostics,
    /// Algorithm 4.1's stage-0 refinement on the starting knots (before rescaling to T).
    pub start: Refinement,
    /// L-BFGS iterations taken.
    pub iterations: usize,
    /// Fixed-knot solves (function evaluations) in the optimization.
    pub solves: usize,
    /// Whether `after.stationarity` ≤ the tolerance, or E is 0 up to rounding
    /// ([`FreeKnotOptions::zero_energy`]).
    pub converged: bool,
}

fn unsupported(field: &'static str, reason: &'static str) -> Error {
    Error::Unsupported { field, reason }
}

/// Checks the problem and options for the free-knot optimization.
fn check(problem: &Problem, options: &FreeKnotOptions) -> Result<(), Error> {
    problem.validate()?;
    if problem
        .tangents
        .as_ref()
        .is_some_and(|t| t.iter().any(Option::is_some))
    {
        return Err(unsupported(
            "tangents",
            "free knots: derivative constraints depend on the knots (Df(t_i) is a knot-dependent stencil), so the envelope gradient does not apply",
        ));
    }
    if problem.boundary != Boundary::Natural {
        return Err(unsupported(
            "boundary",
            "free knots: end-derivative constraints depend on the knots, so the envelope gradient does not apply",
        ));
    }
    if problem.solver != Solver::Exact {
        return Err(unsupported(
            "solver",
            "free knots need the exact fixed-knot optimum (the envelope theorem); use the exact solver",
        ));
    }
    if problem.levels != 0 {
        return Err(unsupported(
            "levels",
            "free knots optimize the near-interpolatory step (stage 0) only; set levels = 0",
        ));
    }
    if options.max_iterations == 0 {
        return Err(Error::InvalidParameter {
            field: "max_iterations",
            value: 0.0,
            reason: "at least one iteration",
        });
    }
    if options.memory == 0 {
        return Err(Error::InvalidParameter {
            field: "memory",
            value: 0.0,
            reason: "at least one correction pair",
        });
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return Err(Error::InvalidParameter {
            field: "tolerance",
            value: options.tolerance,
            reason: "must be finite and > 0",
        });
    }
    if let Some(t) = options.total_length {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::InvalidParameter {
                field: "total_length",
                value: t,
                reason: "must be finite and > 0",
            });
        }
    }
    Ok(())
}

fn penalty(problem: &Problem, points: &Points) -> f64 {
    match &problem.constraint {
        Constraint::Smoothing(w) => {
            let stride = problem.k + 1;
            w.iter()
                .enumerate()
                .map(|(i, wi)| {
                    let d2: f64 = points
                        .point(stride * i)
                        .iter()
                        .zip(problem.points.point(i))
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum();
                    0.5 * wi * d2
                })
                .sum()
        }
        _ => 0.0,
    }
}

/// The L-BFGS two-loop recursion: −H_k g from the stored pairs (s, y), oldest first.
fn lbfgs_direction(g: &[f64], pairs: &[(Vec<f64>, Vec<f64>)]) -> Vec<f64> {
    let mut q: Vec<f64> = g.to_vec();
    let mut alpha = vec![0.0; pairs.len()];
    for (k, (s, y)) in pairs.iter().enumerate().rev() {
        let rho = 1.0 / dot(y, s);
        alpha[k] = rho * dot(s, &q);
        for (qi, yi) in q.iter_mut().zip(y) {
            *qi -= alpha[k] * yi;
        }
    }
    if let Some((s, y)) = pairs.last() {
        let gamma = dot(s, y) / dot(y, y);
        for qi in &mut q {
            *qi *= gamma;
        }
    }
    for (k, (s, y)) in pairs.iter().enumerate() {
        let rho = 1.0 / dot(y, s);
        let beta = rho * dot(y, &q);
        for (qi, si) in q.iter_mut().zip(s) {
            *qi += (alpha[k] - beta) * si;
        }
    }
    q.iter().map(|x| -x).collect()
}

/// How θ maps to the refined knots: T·softmax(θ) gives the free spans H_i ("groups"), each split
/// into `m` equal refined spans; the knots start at `t0`.
struct Layout {
    topology: Topology,
    t0: f64,
    total: f64,
    m: usize,
}

impl Layout {
    fn new(problem: &Problem, free: FreeKnots, t0: f64, total: f64) -> Self {
        Layout {
            topology: problem.topology,
            t0,
            total,
            m: match free {
                FreeKnots::Data => problem.k + 1,
                FreeKnots::All => 1,
            },
        }
    }

    /// The refined knots of θ.
    fn knots(&self, theta: &[f64]) -> Result<Knots, Error> {
        let mx = theta.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let e: Vec<f64> = theta.iter().map(|x| (x - mx).exp()).collect();
        let sum: f64 = e.iter().sum();
        let mut t = Vec::with_capacity(theta.len() * self.m + 1);
        let mut left = self.t0;
        let mut acc = 0.0;
        t.push(left);
        for x in e {
            acc += x;
            let right = self.t0 + self.total * acc / sum;
            for j in 1..self.m {
                let s = j as f64 / self.m as f64;
                t.push((1.0 - s) * left + s * right);
            }
            t.push(right);
            left = right;
        }
        Ok(Knots::new(self.topology, t)?)
    }

    /// θ of refined knots (the log of the group spans).
    fn theta(&self, knots: &Knots) -> Vec<f64> {
        let t = knots.values();
        (0..knots.span_count() / self.m)
            .map(|i| (t[(i + 1) * self.m] - t[i * self.m]).ln())
            .collect()
    }

    /// ∂F/∂H_i = (1/m) Σ_{j in group i} ∂F/∂h_j.
    fn group_gradient(&self, dh: &[f64]) -> Vec<f64> {
        dh.chunks(self.m)
            .map(|c| c.iter().sum::<f64>() / self.m as f64)
            .collect()
    }

    /// ∂F/∂θ_i = H_i (G_i − Ḡ), Ḡ = Σ H_j G_j / T.
    fn theta_gradient(&self, ev: &Eval) -> Vec<f64> {
        let g = self.group_gradient(&ev.dh);
        let big: Vec<f64> = self.theta(&ev.knots).iter().map(|x| x.exp()).collect();
        let mean = big.iter().zip(&g).map(|(a, b)| a * b).sum::<f64>() / self.total;
        big.iter().zip(&g).map(|(h, gi)| h * (gi - mean)).collect()
    }

    /// max_i |G_i − μ| / |μ|, μ = −3E/T.
    fn stationarity(&self, ev: &Eval) -> f64 {
        let mu = -3.0 * ev.energy / self.total;
        let sigma = mu.abs().max(f64::MIN_POSITIVE);
        self.group_gradient(&ev.dh)
            .iter()
            .fold(0.0f64, |a, g| a.max((g - mu).abs()))
            / sigma
    }

    fn diagnostics(&self, problem: &Problem, ev: &Eval) -> Result<KnotDiagnostics, Error> {
        let sigma = (3.0 * ev.energy / self.total).max(f64::MIN_POSITIVE);
        let free_range = |n: usize| match self.topology {
            Topology::Closed => 0..n,
            Topology::Open => 1..n.saturating_sub(1),
        };
        let vg = energy::vertex_knot_gradient(&ev.knots, &ev.points)?;
        let vertex_knot_residual = vg[free_range(vg.len())]
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()))
            / sigma;
        // dF/du_b = G_{b−1} − G_b at the group boundaries (wrapping for closed curves).
        let g = self.group_gradient(&ev.dh);
        let groups = g.len();
        let free_knot_gradient: Vec<f64> = match self.topology {
            Topology::Closed => (0..groups)
                .map(|b| g[(b + groups - 1) % groups] - g[b])
                .collect(),
            Topology::Open => (1..groups).map(|b| g[b - 1] - g[b]).collect(),
        };
        let knot_residual = free_knot_gradient
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()))
            / sigma;
        let orthogonality =
            energy::orthogonality_residuals(&ev.knots, &ev.points, problem.derivative)?;
        let orthogonality_max = orthogonality[free_range(orthogonality.len())]
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()))
            / sigma;
        Ok(KnotDiagnostics {
            energy: ev.energy,
            objective: ev.objective,
            kkt_residual: ev.kkt,
            free_knot_gradient,
            knot_residual,
            stationarity: self.stationarity(ev),
            knot_gradient: vg,
            vertex_knot_residual,
            orthogonality,
            orthogonality_max,
        })
    }
}

/// The reduced objective and its ingredients at one set of knots.
struct Eval {
    knots: Knots,
    points: Points,
    energy: f64,
    objective: f64,
    kkt: f64,
    /// ∂F/∂h_j per refined span.
    dh: Vec<f64>,
}

/// Solves the fixed-knot problem on `knots` and evaluates F and ∂F/∂h (envelope theorem).
fn evaluate(problem: &Problem, knots: Knots) -> Result<Eval, Error> {
    let (points, energy, kkt) = crate::solve::solve_stage0_on(problem, &knots)?;
    let gt = energy::knot_gradient(&knots, &points)?;
    let s = knots.span_count();
    let mut dh = Vec::with_capacity(s);
    let mut acc = 0.0;
    // ∂E/∂t_k = ∂E/∂h_{k−1} − ∂E/∂h_k  ⇒  ∂E/∂h_j = −Σ_{k≤j} ∂E/∂t_k.
    for g in gt.iter().take(s) {
        acc -= g;
        dh.push(acc);
    }
    let objective = energy + penalty(problem, &points);
    Ok(Eval {
        knots,
        points,
        energy,
        objective,
        kkt,
        dh,
    })
}

/// The reduced objective F(θ) = E(p*(t(θ)), t(θ)) (plus the smoothing penalty) and its exact
/// gradient in θ, for the parametrization of [`optimize_knots`]: the free spans are
/// T·softmax(θ), each split into equal refined sub-spans, the knots starting at 0. One θ per
/// free span: n − 1 (open) or n (closed) for [`FreeKnots::Data`], every refined span for
/// [`FreeKnots::All`]. Exposed so the chain rule can be tested against finite differences.
///
/// Returns (F, ∂F/∂θ).
///
/// # Errors
/// As [`optimize_knots`]; [`Error::WrongLength`] if θ has the wrong length,
/// [`Error::InvalidValue`] if an entry is not finite.
pub fn reduced_objective(
    problem: &Problem,
    free: FreeKnots,
    theta: &[f64],
    total_length: f64,
) -> Result<(f64, Vec<f64>), Error> {
    check(
        problem,
        &FreeKnotOptions::default().with_total_length(total_length),
    )?;
    let layout = Layout::new(problem, free, 0.0, total_length);
    let n = Problem::refined_len(problem.topology, problem.points.len(), problem.k);
    let refined_spans = match problem.topology {
        Topology::Open => n - 1,
        Topology::Closed => n,
    };
    let expected = refined_spans / layout.m;
    if theta.len() != expected {
        return Err(Error::WrongLength {
            field: "theta",
            expected,
            got: theta.len(),
        });
    }
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(Error::InvalidValue {
            field: "theta",
            index: i,
            value: theta[i],
            reason: "not finite",
        });
    }
    let ev = evaluate(problem, layout.knots(theta)?)?;
    Ok((ev.objective, layout.theta_gradient(&ev)))
}

/// Optimal free knots for the near-interpolatory step of `problem` (see the module docs).
///
/// Solves the problem on its starting knots ([`FreeKnots::Data`]: the split of the data
/// parametrization, centripetal by default; [`FreeKnots::All`]: Algorithm 4.1's stage 0), rescales
/// them to the total length T, then minimizes F(t) = E(p*(t), t) over the free knots with T
/// fixed by L-BFGS on log-spans, with the exact fixed-knot solve inside and the envelope-theorem
/// gradient.
///
/// # Errors
/// Any error of [`Problem::solve`] or of the fixed-knot solves; [`Error::Unsupported`] for
/// tangent constraints, end conditions (they depend on the knots), the paper's solver, or
/// `levels` > 0; [`Error::InvalidParameter`] for bad options.
///
/// ```
/// use divdiff::Points;
/// use refine::{optimize_knots, FreeKnotOptions, Problem};
/// let q = Points::from_rows(&[[0.0, 0.0], [3.0, 0.0], [3.2, 0.4], [0.0, 1.0]]).unwrap();
/// let r = optimize_knots(&Problem::new(q).with_k(2), &FreeKnotOptions::default()).unwrap();
/// assert!(r.after.energy <= r.before.energy);
/// assert!(r.converged && r.after.knot_residual < 1e-5);
/// ```
pub fn optimize_knots(
    problem: &Problem,
    options: &FreeKnotOptions,
) -> Result<FreeKnotResult, Error> {
    check(problem, options)?;
    let start = match options.free {
        FreeKnots::Data => problem.clone().with_knot_iterations(0).solve()?,
        FreeKnots::All => problem.solve()?,
    };
    let data_vertex = start.data_vertex.clone();
    let t_start = start.knots.values();
    let t0 = t_start[0];
    let length0 = t_start[t_start.len() - 1] - t0;
    let total = options.total_length.unwrap_or(length0);
    let layout = Layout::new(problem, options.free, t0, total);
    let scale = total / length0;
    let mut theta: Vec<f64> = layout
        .theta(&start.knots)
        .iter()
        .map(|x| x + scale.ln())
        .collect();
    let first = evaluate(problem, layout.knots(&theta)?)?;
    let mut solves = 1;
    let before = layout.diagnostics(problem, &first)?;
    let q = &problem.points;
    let polygon: f64 = (0..q.len() - 1)
        .chain((problem.topology == Topology::Closed).then_some(q.len() - 1))
        .map(|i| {
            let (a, b) = (q.point(i), q.point((i + 1) % q.len()));
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
                .sqrt()
        })
        .sum();
    let zero = options.zero_energy * polygon * polygon / (total * total * total);
    if first.energy <= zero {
        // A straight or constant optimum: E = 0 for every knot vector, nothing to optimize.
        return Ok(FreeKnotResult {
            points: first.points,
            knots: first.knots,
            data_vertex,
            total_length: total,
            free: options.free,
            after: before.clone(),
            before,
            start,
            iterations: 0,
            solves,
            converged: true,
        });
    }
    let mut cur = first;
    let mut grad = layout.theta_gradient(&cur);
    let mut stat = layout.stationarity(&cur);
    let mut pairs: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let mut iterations = 0;
    while stat > options.tolerance && cur.energy > zero && iterations < options.max_iterations {
        let mut dir = lbfgs_direction(&grad, &pairs);
        let mut slope = dot(&grad, &dir);
        if slope >= 0.0 {
            // Not a descent direction (stale curvature pairs): restart from steepest descent.
            pairs.clear();
            dir = grad.iter().map(|g| -g).collect();
            slope = dot(&grad, &dir);
        }
        let big = dir.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let limit = if pairs.is_empty() {
            0.5
        } else {
            options.max_step
        };
        let mut alpha = if big > limit { limit / big } else { 1.0 };
        let mut accepted = None;
        for _ in 0..options.line_search_steps {
            let trial: Vec<f64> = theta.iter().zip(&dir).map(|(t, d)| t + alpha * d).collect();
            let ev = layout.knots(&trial).and_then(|k| evaluate(problem, k));
            solves += 1;
            // A failed fixed-knot solve (e.g. a span below rounding) counts as too long a step.
            if let Ok(ev) = ev {
                let armijo = cur.objective + options.armijo * alpha * slope;
                let new_stat = layout.stationarity(&ev);
                let within_rounding = ev.objective
                    <= armijo + options.rounding_slack * cur.objective.abs()
                    && new_stat < stat;
                if ev.objective <= armijo || within_rounding {
                    accepted = Some((trial, ev, new_stat));
                    break;
                }
            }
            alpha *= 0.5;
        }
        let Some((trial, ev, new_stat)) = accepted else {
            break;
        };
        let new_grad = layout.theta_gradient(&ev);
        let s: Vec<f64> = trial.iter().zip(&theta).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = new_grad.iter().zip(&grad).map(|(a, b)| a - b).collect();
        if dot(&s, &y) > 1e-12 * dot(&s, &s).sqrt() * dot(&y, &y).sqrt() {
            pairs.push((s, y));
            if pairs.len() > options.memory {
                pairs.remove(0);
            }
        }
        theta = trial;
        grad = new_grad;
        stat = new_stat;
        cur = ev;
        iterations += 1;
    }
    let after = layout.diagnostics(problem, &cur)?;
    Ok(FreeKnotResult {
        points: cur.points,
        knots: cur.knots,
        data_vertex,
        total_length: total,
        free: options.free,
        converged: after.stationarity <= options.tolerance || after.energy <= zero,
        before,
        after,
        start,
        iterations,
        solves,
    })
}
