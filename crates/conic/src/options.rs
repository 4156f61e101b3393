//! Tuning of the method, with documented defaults.

/// Options of [`crate::solve`]. `Options::default()` is what every caller in the workspace
/// starts from; each field says why its default is what it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Iteration limit of the interior-point method (default 80: the problems of `refine`
    /// converge in 10–60 iterations; a run that needs more has stalled).
    pub max_iterations: usize,
    /// The method stops when the iterate's relative KKT residual ([`crate::Residuals::total`])
    /// is at most this (default 1e-10: below it the gap, relative to the objective, bounds the
    /// relative excess energy by 1e-10, and the polish finishes the rest).
    pub tolerance: f64,
    /// Fraction of the step to the boundary of the cones taken (default 0.99, Mehrotra's).
    pub step_fraction: f64,
    /// Iterative refinement of the Newton directions.
    pub refinement: RefinementOptions,
    /// Regularization of the Newton matrix.
    pub regularization: Regularization,
    /// The active-set polish ([`crate::polish`]); `None` turns it off.
    pub polish: Option<PolishOptions>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iterations: 80,
            tolerance: 1e-10,
            step_fraction: 0.99,
            refinement: RefinementOptions::default(),
            regularization: Regularization::default(),
            polish: Some(PolishOptions::default()),
        }
    }
}

impl Options {
    /// Sets [`Options::tolerance`].
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
    /// Sets [`Options::max_iterations`].
    pub fn with_max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }
    /// Sets [`Options::polish`].
    pub fn with_polish(mut self, polish: Option<PolishOptions>) -> Self {
        self.polish = polish;
        self
    }
}

/// Iterative refinement of each Newton direction against the exact operators (the factored
/// matrix may be regularized; see [`crate::KktSystem`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RefinementOptions {
    /// Most refinement steps per corrector solve (default 6; each costs one application of
    /// P, A and Aᵀ and one solve).
    pub max_steps: usize,
    /// The corrector is refined until its residual is below this times the iterate's relative
    /// KKT residual times its right-hand side (default 1e-3): early directions need no
    /// accuracy. The predictor, which only sets the centring, is refined only when equality rows
    /// make it necessary.
    pub accuracy: f64,
    /// …but never asked for less than this relative residual (default 1e-12).
    pub floor: f64,
    /// With an exact factorization ([`crate::KktSystem::factor_is_exact`]) and no equality
    /// rows, the corrector is refined only once the iterate's residual is below this (default
    /// 1e-6: early directions need no accuracy)…
    pub exact_from: f64,
    /// …and then by at most this many steps (default 1: rounding only).
    pub exact_steps: usize,
}

impl Default for RefinementOptions {
    fn default() -> Self {
        RefinementOptions {
            max_steps: 6,
            accuracy: 1e-3,
            floor: 1e-12,
            exact_from: 1e-6,
            exact_steps: 1,
        }
    }
}

/// Regularization of the Newton matrix, tried in order while it fails to factor.
#[derive(Clone, Debug, PartialEq)]
pub struct Regularization {
    /// δ of equality rows relative to [`crate::KktSystem::diagonal_scale`]: the penalty
    /// AᵀA/δ then dominates P there by 1/this (default 1e-9: far above rounding, far below
    /// pivots that fail).
    pub equality: f64,
    /// Growth of δ per failed factorization (default 1e3).
    pub equality_growth: f64,
    /// Attempts with growing δ (default 3: δ up to 1e-3 relative).
    pub equality_attempts: u32,
    /// Static regularization σ after the equality attempts (default 1e-12 relative: the
    /// matrix is positive definite by construction, a failure is rounding on barrier terms that
    /// span many orders of magnitude).
    pub static_shift: f64,
    /// Growth of σ per further attempt (default 1e3).
    pub static_growth: f64,
    /// Attempts with a static regularization (default 2: 1e-12, 1e-9).
    pub static_attempts: u32,
}

impl Default for Regularization {
    fn default() -> Self {
        Regularization {
            equality: 1e-9,
            equality_growth: 1e3,
            equality_attempts: 3,
            static_shift: 1e-12,
            static_growth: 1e3,
            static_attempts: 2,
        }
    }
}

/// The active-set polish ([`crate::polish`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PolishOptions {
    /// The polish is first tried when the iterate's residual is at most this (default 1e-8:
    /// the active set is settled; a polished point at the tolerance ends the method early).
    pub from: f64,
    /// Newton steps per polish (default 3: the steps converge quadratically from an
    /// interior-point iterate near the optimum).
    pub steps: usize,
    /// Changes of the active set (a violated inactive constraint joins, a negative multiplier
    /// leaves), each followed by a retried step (default 3).
    pub active_changes: usize,
    /// An orthant row or a second-order block within this relative slack of its boundary counts
    /// as active (default 1e-6; weakly active constraints with zero multipliers).
    pub active_rtol: f64,
    /// A second-order block also counts as active when |s||z| ≥ this × sᵀz (default 100: on the
    /// central path an inactive block has z ∝ J s, so sᵀz is comparable to |s||z|; an active one
    /// is J-orthogonal).
    pub soc_ratio: f64,
    /// The penalty δ on active rows relative to [`crate::KktSystem::diagonal_scale`] (default
    /// 1e-9, as [`Regularization::equality`]); removed by refinement.
    pub penalty: f64,
    /// A polish stops after a step that leaves an inactive constraint violated (relative to L)
    /// by more than this many times the active-set system's own residual (default 1e3): the
    /// active set is wrong and the remaining steps cannot repair it.
    pub abandon_ratio: f64,
    /// Refinement steps of each polish solve (default 6).
    pub refinement_steps: usize,
    /// The final interior-point iterate is not polished when its certificate is already at most
    /// this (default 1e-13).
    pub skip_below: f64,
    /// Hold second-order blocks at their apex ([`crate::polish`]'s module docs; default false:
    /// the polish declines when an active block is at its apex). Where the optimum has no
    /// block at its apex the apex tests can still move constraints there and cost steps (the
    /// bench's tangent class, a wedge at every eighth point of a noisy star of 10⁵ points:
    /// 2.7 s instead of 1.5 s, for the same answer), so the method's own polishes leave it off
    /// and a caller turns it on for a last attempt (refine's `ConicProblem::solve_judged`).
    pub apex: bool,
    /// Normalize a second-order boundary constraint ½ sᵀJ s/ν by ν = |J s| where it joins the
    /// active set, fixed thereafter (default true: its Hessian is exact and the steps converge
    /// quadratically; [`crate::polish`]'s module docs). False: by the current |J s| at every
    /// step, whose Hessian lacks the derivative of 1/|J s| and whose steps converge linearly —
    /// the older polish, kept because on direction wedges the two end on different points: of
    /// a sweep of wedge problems each certified some the other refused (refine's full-vertex
    /// route polishes this way first and with fixed normals as its last attempt).
    pub fixed_normals: bool,
    /// The polish gives up (returns no point) when its first Newton step, before any change of
    /// the active set, leaves the certificate's relative residual above this (default `None`:
    /// never). From a start near the optimum with the right active set, that step lands in
    /// Newton's quadratic regime; a residual of 1e-2 after it says the start is far off, and the
    /// steps and active-set changes that follow cost more than a fresh solve (refine's warm
    /// starts after a knot update set it).
    pub abandon_first: Option<f64>,
    /// When the polish's matrix does not factor, factor it again with a static regularization
    /// (default false: the polish then returns what it has). The matrix is singular where the
    /// optimum is a face rather than a point (P's null space orthogonal to every active normal:
    /// a curve free to slide between the faces of its boxes), and the shifted factorization
    /// only preconditions the refinement against the exact system. refine's condensed working
    /// set sets it (its ROBUSTNESS.md item 41); its full-vertex route leaves it off, where on
    /// hard derivative constraints the shifted steps ended on worse points than a refusal of the
    /// polish and the method's own later iterates (two fixtures of refine's error messages then
    /// went from certified to refused).
    pub shift_singular: bool,
}

impl Default for PolishOptions {
    fn default() -> Self {
        PolishOptions {
            from: 1e-8,
            steps: 3,
            active_changes: 3,
            active_rtol: 1e-6,
            soc_ratio: 100.0,
            penalty: 1e-9,
            abandon_ratio: 1e3,
            refinement_steps: 6,
            skip_below: 1e-13,
            apex: false,
            fixed_normals: true,
            abandon_first: None,
            shift_singular: false,
        }
    }
}
