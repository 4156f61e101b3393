//! Variational refinement of curves (Kersey §3–4).
//!
//! Implements S. N. Kersey, *near-interpolatory variational refinement of piecewise-linear
//! curves* (J. Comput. Appl. Math. 223, 2009; seed `000_8a81be4d4deadca6.txt`) §3–4 on top of
//! [`divdiff`] (knots, points, parametrizations) and [`energy`] (the Hessian H of (2.1) and its
//! O(N) solves), for open and closed curves in R^d, any d ≥ 1. Indices are 0-based (the seed's
//! are 1-based). (The uniform subdivision schemes of Khan et al. and Warren–Weimer live in the
//! `subdivision` crate.)
//!
//! # Kersey's refinement
//!
//! Data q_0..q_{n−1} with parameters u_0 = 0, u_{i+1} = u_i + |q_{i+1} − q_i|^e (not normalized;
//! e = 0, ½, 1 for [`Parametrization::Uniform`], [`Parametrization::Centripetal`],
//! [`Parametrization::Chordal`]) or given knots.
//!
//! - **k-level split (3.1)** ([`split`]): every span, including the closing span of a closed
//!   curve, is cut into k + 1 equal sub-spans: N = (k + 1)n vertices (closed) or
//!   (k + 1)(n − 1) + 1 (open); q_i sits at vertex i_k = (k + 1)i ([`data_vertex`]).
//! - **Interpolation (3.2)/(3.3)**: minimize E = ½pᵀHp subject to p_{i_k} = q_i; the free rows
//!   of Hp vanish. Solved in O(N) by condensing every data span onto one unknown per data
//!   vertex (a tridiagonal, for closed curves cyclic, system of size n).
//! - **Balls (3.4)/(3.5)**: |p_{i_k} − q_i| ≤ ε_i (ε_i = 0 interpolates). KKT:
//!   (H + W)p = W q̃, w_i ≥ 0, w_i(|p_{i_k} − q_i| − ε_i) = 0; at an inactive data vertex
//!   jmp = ½(Hp) = 0 (**Corollary 3.3**, reported by [`Refinement::jmp_inactive`]).
//! - **Smoothing (3.6)**: minimize E + ½Σ w_i |p_{i_k} − q_i|², i.e. (H + W)p = W q̃.
//! - **Open curves (§3.6)**: zero first and last rows of A; natural ends.
//! - **Algorithm 4.1**: part 1 is one k-level step alternating a fixed-knot solve with knot
//!   updates t_{j+1} = t_j + |p_{j+1} − p_j|^e on the refined vertices, each mapped affinely
//!   back onto the span of the knots it replaces — so every stage's knots span the data
//!   parameters, and derivatives (clamped and near-clamped ends, tangents) and E are with
//!   respect to the data parameter at every k (`knot_iterations` times, then a final solve, so
//!   the points always belong to the returned knots); part 2 is `levels`
//!   further interpolatory `level_k`-level steps, each re-initialized from the previous result.
//!
//! # Layout
//!
//! - **Constraints** (`constraint/`): one module per kind behind one trait — interpolation,
//!   balls, smoothing, half-space sets on data vertices; tangents (ball, wedge, tension,
//!   half-spaces on Df) and end conditions (natural, clamped, near-clamped) on derivative
//!   stencils. Each kind validates its field (naming it and the index), says which cone rows it
//!   adds to the conic problem, which point sets it puts on data vertices (for the condensed
//!   backend), its multipliers and its terms of the independent certificate, how it is
//!   projected in the common-point test and how it moves under translation and scaling. A new
//!   kind is one file and one enum arm.
//! - **One fixed-knot stage** (`stage.rs`): the problem at one set of knots, defined at the
//!   bottom and used by every solver above it.
//! - **Two fixed-knot solvers** ([`Solver`]): **exact** (the default) and the **paper's
//!   multiplier iteration** (w_i := w_i |p_{i_k} − q_i| / ε_i from w_i = 1), kept to reproduce
//!   the seed's figures (balls only). The exact solver is an ordered, documented list of
//!   strategies (`strategy.rs`): a linear solve for interpolation and smoothing; for sets on data
//!   vertices alone (balls, half-space sets) the `conic` crate's interior-point method on the
//!   **condensed** backend — the free vertices eliminated exactly, E(y) = ½(Ky)ᵀT⁻¹(Ky) with
//!   T, K tridiagonal (cyclic) from the interpolation condensation — run on a growing working
//!   set of the active sets; otherwise, and as their fallback, the same method on the
//!   **full-vertex** backend ([`ConicProblem`]: constraints L p ∈ K on stencils of at most
//!   three vertices). Both backends implement `conic::KktSystem`; with the `clarabel` feature
//!   the full-vertex program can also be handed to Clarabel ([`ConicProblem::solve_clarabel`]),
//!   which is slower on every class measured (`cargo xtask bench conic`).
//! - **Tuning** in [`SolveOptions`] (set with [`Problem::with_options`]), every default
//!   documented; only user-facing limits stay constants ([`MAX_CONIC_COORDS`],
//!   [`EXACT_ACCEPT_KKT`], the problem fields' defaults).
//! - **Exact means exact**: a fixed-knot result is accepted when its independent certificate
//!   (below) is at most [`SolveOptions::accept_kkt`] = [`EXACT_ACCEPT_KKT`] = 1e-9; otherwise
//!   the solve refuses with [`Error::NotConverged`] naming the best certificate reached.
//!
//! **The limit curve** ([`limit_curve`]): as k → ∞ the refined polygon tends to the cubic
//! spline ([`CubicSpline`]) through the constrained vertices at their knots, natural, periodic or
//! clamped as the problem's ends say — the curve to evaluate, differentiate and export
//! (derivation in `docs/limit.md`).
//!
//! **Optimal free knots** (beyond the paper, [`optimize_knots`]): minimize F(t) = E(p*(t), t)
//! over the data knots (each data span split into k + 1 equal sub-spans) with the total parameter
//! length T fixed, p*(t) being the exact fixed-knot optimum. Position constraints do not depend on
//! t, so by the envelope theorem dF/dt = ∂E/∂t at p* (the corrected Lemma 2.4 of `energy`);
//! tangent and end constraints do depend on t and are rejected. L-BFGS on log-spans
//! h = T·softmax(θ), started from centripetal knots; the result reports E and the corrected
//! Corollary 2.5–2.7 / Theorem 3.1–3.2 knot residuals before and after. Freeing every refined
//! knot instead ([`FreeKnots::All`]) is degenerate: sub-spans collapse.
//!
//! Every [`Refinement`] carries its certificate, recomputed from the points independently of the
//! solver: the energy, the multipliers, the active set, and a **relative KKT residual** — the
//! largest of the stationarity residual ‖Hp + Σ (constraint gradient × multiplier)‖_∞,
//! complementarity and negative multipliers (all over ‖H‖_∞ · δ, δ the largest step between
//! consecutive vertices, the rounding scale of Hp computed from differences), the constraint violation
//! (over L), where L is the largest coordinate distance of a vertex or data point from the data's
//! centroid, and the duality gap Σ ½w_i(ε_i² − |p_{i_k} − q_i|²) over E (a bound on the relative
//! energy excess over the optimum), and a run-off term that refuses a curve reaching beyond 1e6
//! times what its data and derivative bounds allow (its other terms are relative to its own
//! scales). Balls that share a common point make the constant curve optimal (E = 0); it is
//! returned directly.
//!
//! # Threads
//!
//! The O(N) passes over the refined vertices — the closed form and span condensation of
//! interpolation, the k-level split, the certificate — run in chunks on rayon's pool (one thread
//! per core, `RAYON_NUM_THREADS` to change it, or the pool a caller installs); a solve that spans
//! several chunks runs on the pool. The chunks are fixed by the problem's size, not by the
//! number of threads, so every result is the same to the last bit on any number of threads
//! (`tests/threads.rs`). On wasm32 everything runs on the calling thread.
//!
//! # Example
//!
//! ```
//! use divdiff::{Points, Topology};
//! use refine::{Constraint, Problem};
//! let q = Points::from_rows(&[[0.0, 0.0], [2.0, 0.1], [2.2, 1.9], [1.0, 3.0], [-0.1, 2.0]]).unwrap();
//! // Interpolation with the defaults of `curvefit refine`: closed, centripetal, k = 3, three knot updates.
//! let r = Problem::new(q.clone()).solve().unwrap();
//! assert_eq!(r.points.len(), 4 * 5);
//! assert!(r.kkt_residual <= 1e-9);
//! for (i, &v) in r.data_vertex.iter().enumerate() {
//!     assert!((r.points.point(v)[0] - q.point(i)[0]).abs() < 1e-12);
//! }
//! // Smoothing an open curve on the data's own knots: the interpolant is feasible with zero
//! // penalty, so the smoothing optimum has no more energy.
//! let open = Problem::new(q).with_topology(Topology::Open).with_knot_iterations(0);
//! let i = open.clone().solve().unwrap();
//! let s = open.with_constraint(Constraint::Smoothing(vec![1.0; 5])).solve().unwrap();
//! assert!(s.energy <= i.energy && s.kkt_residual <= 1e-9);
//! ```

mod algorithm;
mod arcs;
mod backend;
mod certify;
mod conic_problem;
mod constraint;
mod degenerate;
mod error;
mod fast;
mod freeknots;
mod limit;
mod linear;
mod multipliers;
mod operator;
mod options;
mod paper;
mod par;
mod problem;
mod progress;
mod slots;
mod solve;
mod split;
mod stage;
mod strategy;
mod uniform;

pub use algorithm::{Iterations, Refinement, Stage};
pub use conic_problem::{ConicConstraint, ConicOptions, ConicProblem, ConicSolution, ConvexSet};
pub use constraint::{Boundary, Constraint, HalfSpace, Tangent};
pub use divdiff::{DerivativeRule, Parametrization};
pub use error::Error;
pub use freeknots::{
    optimize_knots, reduced_objective, FreeKnotOptions, FreeKnotResult, FreeKnots, KnotDiagnostics,
};
pub use limit::{limit_curve, limit_curve_of, CubicSpline};
pub use multipliers::Multipliers;
pub use options::{
    CommonPointOptions, PaperOptions, SolveOptions, WorkingSetOptions, EXACT_ACCEPT_KKT,
    MAX_CERTIFIED_SPAN_RATIO,
};
pub use problem::{
    Problem, Solver, DEFAULT_K, DEFAULT_KNOT_ITERATIONS, DEFAULT_PAPER_ITERATIONS, EXTENT_RANGE,
    MAX_CONIC_COORDS,
};
pub use progress::{Observer, Progress};
pub use slots::halfplane_polygon;
pub use split::{data_vertex, split};
