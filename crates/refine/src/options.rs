//! The solvers' tuning, grouped in option structs with documented defaults, set on a
//! [`crate::Problem`] with [`crate::Problem::with_options`].

pub use crate::backend::working_set::WorkingSetOptions;

/// The largest relative KKT residual (of the independent certificate, module `certify`) with
/// which [`crate::Solver::Exact`] returns a result: above it the solve refuses with
/// [`crate::Error::NotConverged`] naming the best certificate reached. The default of
/// [`SolveOptions::accept_kkt`].
pub const EXACT_ACCEPT_KKT: f64 = 1e-9;

/// The largest ratio of the refined knots' longest span to their shortest at which an exact
/// answer with balls (of positive radius), half-spaces or derivative constraints is returned;
/// beyond it [`crate::Error::SpansTooUnequal`]. Rows of the energy scale like 1/span³, so at a
/// spread R a cluster of very short spans carries rounding ε R³ times the forces at the longest
/// ones: past 1e7 that is 2·10⁵, and a net force on the cluster that moves the energy by 1 %
/// hides under it (`xtask/sweeps/refine.py` seed 2 case 259, spans 2.3·10⁸ apart, certified at
/// 4.8e-11 with an energy 1 % above a feasible point Clarabel found; ROBUSTNESS.md item 31). Up
/// to 10⁶ every kind certifies and is right (`tests/conditioning.rs`, `span_ratios_up_to_1e6`).
/// Interpolation and smoothing without derivative constraints are linear solves with no free
/// cluster to hide a force and are not limited.
pub const MAX_CERTIFIED_SPAN_RATIO: f64 = 1e7;

/// Everything the solvers of a [`crate::Problem`] can be tuned by.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveOptions {
    /// The cone solver (interior-point method and polish) of the exact strategies
    /// ([`conic::Options`]; its defaults are the method's). The strict entries of the strategy
    /// list (module `strategy`) tighten its tolerance to [`SolveOptions::strict_tolerance`].
    pub conic: conic::Options,
    /// The tolerance of the strict retries (default 1e-13: an active set read off at the default
    /// 1e-10 is sometimes not settled enough for the polish; at 1e-13 the interior-point method
    /// has the optimum's to rounding).
    pub strict_tolerance: f64,
    /// The working set of the condensed method.
    pub working_set: WorkingSetOptions,
    /// The acceptance level of the independent certificate (default [`EXACT_ACCEPT_KKT`]): every
    /// stage of an exact solve is certified at most this, or the solve refuses.
    pub accept_kkt: f64,
    /// The condensed method polishes a result whose certificate is above this (default 1e-11,
    /// a hundredth of the default acceptance: the interior-point iterate is usually certified far
    /// below the acceptance, and when it is not, the polish — whose systems cost O(N) — gives the
    /// margin back).
    pub polish_above: f64,
    /// A data constraint counts as active when its slack is at most this relative to its size
    /// (the radius, or the length scale for half-spaces) (default 1e-7); a clearly inactive
    /// constraint's leftover multiplier is charged to stationarity.
    pub active_rtol: f64,
    /// The paper's multiplier iteration.
    pub paper: PaperOptions,
    /// The common-point test.
    pub common_point: CommonPointOptions,
    /// Told of each fixed-knot solve and each interior-point iteration (default `None`; see
    /// [`crate::Progress`]).
    pub progress: Option<crate::Observer>,
}

impl SolveOptions {
    /// Sets [`SolveOptions::progress`] to an observer calling `f`.
    pub fn with_progress(mut self, f: impl Fn(&crate::Progress) + Send + Sync + 'static) -> Self {
        self.progress = Some(crate::Observer::new(f));
        self
    }
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            conic: conic::Options::default(),
            strict_tolerance: 1e-13,
            working_set: WorkingSetOptions::default(),
            accept_kkt: EXACT_ACCEPT_KKT,
            polish_above: 1e-11,
            active_rtol: 1e-7,
            paper: PaperOptions::default(),
            common_point: CommonPointOptions::default(),
            progress: None,
        }
    }
}

/// The paper's multiplier iteration ([`crate::Solver::Paper`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PaperOptions {
    /// Relative floor of the weights: w_i ≥ this · mean(H_jj) (default 1e-10). Inactive
    /// constraints drive their weights to zero geometrically; without a floor a curve whose
    /// constraints all turn inactive (collinear data in balls) would make H + W singular.
    pub weight_floor: f64,
    /// The certificate's active tolerance for the iteration, which approaches the boundary only
    /// to within its own accuracy (default 1e-3).
    pub active_rtol: f64,
}

impl Default for PaperOptions {
    fn default() -> Self {
        PaperOptions {
            weight_floor: 1e-10,
            active_rtol: 1e-3,
        }
    }
}

/// The common-point test (module `degenerate`): alternating projections onto the data
/// constraint sets.
#[derive(Clone, Debug, PartialEq)]
pub struct CommonPointOptions {
    /// Sweeps before giving up (default 2000; a cheap necessary test runs first, so this only
    /// runs when it can succeed).
    pub sweeps: usize,
    /// A point counts as common when it violates no set by more than this times the data's
    /// extent (default 1e-13).
    pub tolerance: f64,
    /// The projections stop when a sweep reduces the largest violation by less than this
    /// fraction: they stall on an empty intersection (default 1e-4).
    pub stagnation: f64,
}

impl Default for CommonPointOptions {
    fn default() -> Self {
        CommonPointOptions {
            sweeps: 2000,
            tolerance: 1e-13,
            stagnation: 1e-4,
        }
    }
}
