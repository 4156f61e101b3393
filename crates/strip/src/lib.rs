//! Best interpolation in a strip (Dontchev & Kolmanovsky, seed `002`; curvefit's `math.md` §4).
//!
//! Minimize ∫ f''² over f ∈ W^{2,2}\[t_1, t_n\] subject to f(t_i) = y_i and
//! e(t) ≤ f(t) ≤ d(t). For bounds that are linear (or cubic) in each interval the answer is an
//! exact C² cubic spline with knots t_i plus at most two extra knots per interval (Theorem 2.1):
//! a touching point, a subarc, or a touching pair.
//!
//! * **Per interval** (problem (7)/(8)): for Hermite data (y_i, z_i, y_{i+1}, z_{i+1}) every
//!   candidate shape is built exactly — the touching point from a cubic equation (`roots`), a
//!   subarc from two linear equations, a touching pair from the Sylvester resultant of its two
//!   polynomial equations (real roots isolated by a derivative cascade, polished by Newton) —
//!   its feasibility is decided from the exact extrema of f − e and d − f on every cubic piece,
//!   and the feasible candidate of least energy wins. [`Pruning`] skips candidates (the seed's §3
//!   rules, or an optimality certificate) without changing the answer.
//! * **Outer problem** (5): Φ(z) = Σ φ_i(z_i, z_{i+1}) is convex with
//!   ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)). [`Method::Newton`] (default) uses the banded Hessian
//!   (per-interval Hessians by implicit differentiation of the contact equations) with a
//!   backtracking line search: O(n) per iteration. [`Method::Bfgs`] is the seed's argmin BFGS
//!   (dense n×n inverse Hessian, for small n; it is what the seed ran). Starting point: the
//!   natural (or clamped, with [`Problem::end_slopes`]) cubic spline. This is the method for
//!   bounds given as cubic pieces.
//! * **§4, polyline bounds** ([`Bound::Polyline`], or [`Bound::from_fn`], the piecewise-linear
//!   approximation of a continuous function, any number M of vertices): solved exactly by a
//!   dual active-set (Goldfarb–Idnani) exchange on point constraints — the spline through the data
//!   and the points held on a bound, its multipliers the f''' jumps, each step a tridiagonal
//!   solve — driven by exact O(M) sweeps of the strip. Its answer is a C² spline that interpolates,
//!   leaves the strip nowhere by more than 10⁻¹² of the value scale, and is optimal for the points
//!   it holds (so its energy is a lower bound on the optimum, within [`Solution::gap`] of it).
//!   The seed's problem (10) — Newton on Φ over every vertex value and slope — is not used: its
//!   Hessian has condition ~M⁴ and it stalls at vertex contacts (the measurements are in the
//!   docs of the `strategy` module).
//! * **Feasibility** is decided before any solve, in O(M + n): a strip that closes anywhere
//!   (checked exactly between every pair of breakpoints), data outside the bounds, or data on a
//!   kink no smooth curve can pass are refused with [`Error::Infeasible`] naming the field and
//!   index. When Newton on Φ stops at its iteration limit, the exchange solves the problem, so a
//!   feasible problem always ends in an answer or a typed refusal: an answer whose gap estimate
//!   exceeds 1e-9 (hair-thin strips, and data whose slopes are steep against the strip's width:
//!   10 % of the random hard strips in ROBUSTNESS.md §4 item 17) is refused with
//!   [`Error::Uncertified`] and its gap, and the exchange stopped with the curve still outside
//!   the strip with [`Error::NotConverged`] and the excursion left.
//! * **Remark 4.2**: data on a bound are moved inside by ε ([`Options::boundary_margin`] of the
//!   strip width; reported in [`Solution::shifted_data`]); the solution converges as ε → 0.
//!
//! **Touching pairs.** With w = f − e (p, q its value and slope at t_i) and G = d − e, the pair
//! (τ₁ on e, τ₂ on d) solves two polynomial equations: f'' continuous at τ₁ is a cubic in
//! L₂ = τ₂ − τ₁ and f'' continuous at τ₂ a quadratic in L₂, both with coefficients polynomial in
//! τ₂. Their 5×5 Sylvester resultant (Laplace expansion over polynomials) is one polynomial in τ₂;
//! its real roots in the (normalized) interval are isolated by a derivative cascade (the roots of
//! p' split the interval into monotone pieces, bisected where p changes sign; near-double roots are
//! kept), each root gives L₂ from the quadratic (and, as extra starting points, the cubic), and
//! Newton's method on the two original equations polishes every start. Spurious starts are
//! discarded by ordering, convergence and the exact feasibility test.
//!
//! **Normalized frame.** The problem is exactly equivariant: adding a line ℓ to y, e and d,
//! scaling values by c and mapping sites by t ↦ t₀ + λt map solutions to solutions (∫f''² scales
//! by c²/λ³). [`solve()`] therefore works on a normalized copy — sites from 0 over a unit-order
//! range, the line through the first and last data point subtracted, values divided by the value
//! scale V (the largest deviation of the data, of the end slopes and of the bounds that push f
//! off that line), all scalings powers of two — and maps the answer back exactly (data sites,
//! polyline vertices and unshifted data values as given). Every stopping and feasibility
//! tolerance is relative to these scales, so the answer does not depend on the units: scaled
//! problems agree to rounding for c ∈ \[1e-8, 1e8\], λ ∈ \[1e-4, 1e4\] (ROBUSTNESS.md). The
//! subtraction of the line rounds each value by ~ε|y|, which on very short spans moves f'' (a
//! slope moves by ε|y|/h): the answer — the natural (or clamped) spline through the data when it
//! touches no bound, the exchange's spline through the data and the points it holds on the
//! bounds, or Newton's pieces with their tangencies and subarcs — is therefore solved again
//! through the same points in the caller's frame (on the bound over each subarc, Newton's
//! abscissae placed again on their conditions), where the divided differences carry one rounding
//! of their own size, and returned when it meets the optimality conditions to rounding (f'' joins,
//! its contacts' multipliers keep their signs) and keeps to the strip (exact to the doubles:
//! `tests/offset.rs`; the `resolve` module). The
//! returned pieces are then checked exactly against the strip in the caller's units: a violation
//! above [`RESULT_FEASIBILITY_TOL`]·V (+ rounding, [`ROUNDING_TOL`]) is
//! [`Error::StripViolated`], never an answer ([`Solution::violation`] reports it).
//!
//! **Optimality certificate.** A feasible candidate whose f''' jumps up at every lower contact
//! and down at every upper contact is *the* minimizer of its interval: for any feasible g,
//! ∫g''² − ∫f''² = ∫(g − f)''² + 2 Σ jump·(g − f)(τ) ≥ 0. Every interval of a [`Solution`] is
//! checked; [`Solution::uncertified`] lists those where no candidate carried it.
//!
//! **Limitations.** For cubic bounds (Remark 3.2) only Theorem 2.1's shapes are enumerated; a
//! cell needing more than two extra knots sends the problem to the exchange, whose answer lists
//! its contacts as touching points ([`Solution::extra_knots`]; [`Solution::shapes`] then only
//! says which intervals touch). Subarcs on a polyline bound likewise appear as runs of touching
//! points, as many as the exchange needed to hold f on the segment to the tolerance.
//!
//! ```
//! use strip::{solve, Bound, Options, Problem};
//! // Five points; a lower bound y ≥ -0.05 that the natural spline would cross.
//! let t = vec![0.0, 1.0, 2.0, 3.0, 4.0];
//! let y = vec![0.0, 1.0, 0.0, 0.0, 1.0];
//! let lower = Bound::Pieces(vec![[-0.05, 0.0, 0.0, 0.0]; 4]);
//! let p = Problem { t, y, lower, upper: Bound::None, end_slopes: [None, None] };
//! let s = solve(&p, &Options::default()).unwrap();
//! assert!(!s.extra_knots.is_empty());
//! for k in 0..=400 {
//!     let x = 4.0 * k as f64 / 400.0;
//!     assert!(s.eval(x) >= -0.05 - 1e-9);
//! }
//! assert!((s.eval(1.0) - 1.0).abs() < 1e-12);
//! ```

// Index loops mirror the formulas (several arrays indexed together); iterator chains would
// obscure them.
#![allow(clippy::needless_range_loop)]

mod assemble;
mod cell;
mod check;
mod compensated;
mod error;
mod exchange;
mod frame;
pub mod interval;
mod linalg;
mod outer;
mod piece;
mod poly;
mod prepare;
mod progress;
mod resolve;
mod solve;
mod spline;
mod strategy;
mod types;
mod validate;

pub use error::{sites_rounding_hint, Error, Infeasibility, SITES_ROUNDING_COUNTS};

/// The name [`Error::NotConverged`] and [`Error::Uncertified`] give the dual active-set exchange
/// (the exact solver for polyline bounds, and the fallback of Newton on Φ), whose
/// `NotConverged::residual` is the excursion left outside the strip, not a gap.
pub const EXCHANGE: &str = "dual active-set exchange";
/// The name of Newton's method on Φ in messages and progress lines.
pub const NEWTON: &str = "Newton on Φ";
pub use progress::Progress;
pub use solve::{solve, solve_observed};
pub use types::{
    Bound, ExtraKnot, KnotKind, Method, Options, Problem, Pruning, Shape, Side, Solution,
    C2_ROUNDING, CONTACT_TOL, DEFAULT_BOUNDARY_MARGIN, DEFAULT_GRADIENT_TOL,
    DEFAULT_MAX_ITERATIONS, FEASIBILITY_TOL, MAX_MAGNITUDE, RESULT_FEASIBILITY_TOL, ROUNDING_TOL,
};
