//! The refinement problem: data, constraints, options, and their validation.

use divdiff::{DerivativeRule, Knots, Parametrization, Points, Topology};

use crate::constraint::{Boundary, Constraint, Tangent};
use crate::options::SolveOptions;
use crate::Error;

/// Which solver handles the fixed-knot problem of each stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Solver {
    /// The exact optimum of the convex fixed-knot problem (linear solves for interpolation and
    /// smoothing; the conic solver for constraint sets). Certified by its KKT residual.
    #[default]
    Exact,
    /// Kersey's multiplier iteration, Algorithm 4.1 (iii): (H + W)p = W q̃, w_i := w_i |p_{i_k} − q_i|/ε_i,
    /// kept to reproduce the seed's figures. Approximate.
    Paper,
}

/// Largest first-stage problem (refined vertices × dimension) accepted for the general
/// interior-point method, i.e. with derivative constraints (tangents, clamped ends) or
/// half-spaces under the exact solver. Interpolation, smoothing and balls alone have O(N)
/// closed-form or condensed solvers and only the CLI's output limit.
pub const MAX_CONIC_COORDS: usize = 2_000_000;

/// Default number of intermediate points per span in the near-interpolatory step.
pub const DEFAULT_K: usize = 3;

/// The range of the data's extent (the largest distance of a data point from the first,
/// computed with a scaled norm so that it does not overflow) that [`Problem::validate`] accepts;
/// outside it the problem is refused naming `points` (rescale the data). Beyond 1e±150 the
/// squares of coordinates and of the parameter spans h ~ L^e in E ~ L²/h³ and H ~ 1/h³ leave
/// the floating-point range for every parametrization. Inside it a problem can still be too
/// badly scaled — chordal spans of 1e-100 make H ~ 1e300 — and the solve then refuses with the
/// singular or non-finite system it met (the command line names `points`).
pub const EXTENT_RANGE: (f64, f64) = (1e-150, 1e150);
/// Default number of knot updates per stage (Algorithm 4.1 step (v)).
pub const DEFAULT_KNOT_ITERATIONS: usize = 3;
/// Default number of multiplier updates of the paper's iteration (Algorithm 4.1 (iii)(c):
/// "iterate several times").
pub const DEFAULT_PAPER_ITERATIONS: usize = 50;

/// A refinement problem (Kersey §3–4, Algorithm 4.1). Build it with [`Problem::new`] and the
/// `with_*` setters (defaults as in `curvefit refine`), then call [`Problem::solve`].
///
/// Fields are public so a front end can fill them directly; [`Problem::validate`] checks them
/// all and is called by [`Problem::solve`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Problem {
    /// The data q_1..q_n (any dimension d ≥ 1).
    pub points: Points,
    /// Open or closed (default closed).
    pub topology: Topology,
    /// Optional data parameters: n values (open) or n + 1 (closed, the last closing the curve).
    pub knots: Option<Vec<f64>>,
    /// The parametrization of the data (when `knots` is `None`) and of every knot update
    /// (default centripetal).
    pub parametrization: Parametrization,
    /// Intermediate points per span in the near-interpolatory step, k ≥ 1 (default 3).
    pub k: usize,
    /// Knot updates per stage (default 3; 0 = solve once on the initial knots).
    pub knot_iterations: usize,
    /// Further interpolatory steps (Algorithm 4.1 part 2; default 0).
    pub levels: usize,
    /// Intermediate points per span in each further step (default 1).
    pub level_k: usize,
    /// The data constraint (default interpolation).
    pub constraint: Constraint,
    /// Optional derivative constraints, one entry (or `None`) per data point.
    pub tangents: Option<Vec<Option<Tangent>>>,
    /// The derivative rule for tangent and end constraints (default Bessel).
    pub derivative: DerivativeRule,
    /// End conditions of an open curve (default natural).
    pub boundary: Boundary,
    /// The fixed-knot solver (default exact).
    pub solver: Solver,
    /// Multiplier updates per solve of the paper's iteration (default
    /// [`DEFAULT_PAPER_ITERATIONS`]).
    pub paper_iterations: usize,
    /// The solvers' tuning (default [`SolveOptions::default`]).
    pub options: SolveOptions,
}

impl Problem {
    /// A problem with the given data and every option at its default: closed, centripetal,
    /// k = 3, 3 knot iterations, no further levels (level_k = 1), interpolation, Bessel
    /// derivatives, natural ends, exact solver.
    pub fn new(points: Points) -> Self {
        Problem {
            points,
            topology: Topology::Closed,
            knots: None,
            parametrization: Parametrization::Centripetal,
            k: DEFAULT_K,
            knot_iterations: DEFAULT_KNOT_ITERATIONS,
            levels: 0,
            level_k: 1,
            constraint: Constraint::Interpolate,
            tangents: None,
            derivative: DerivativeRule::Bessel,
            boundary: Boundary::Natural,
            solver: Solver::Exact,
            paper_iterations: DEFAULT_PAPER_ITERATIONS,
            options: SolveOptions::default(),
        }
    }

    /// Sets open or closed.
    pub fn with_topology(mut self, topology: Topology) -> Self {
        self.topology = topology;
        self
    }
    /// Sets the data parameters (n values open, n + 1 closed).
    pub fn with_knots(mut self, knots: Vec<f64>) -> Self {
        self.knots = Some(knots);
        self
    }
    /// Sets the parametrization.
    pub fn with_parametrization(mut self, p: Parametrization) -> Self {
        self.parametrization = p;
        self
    }
    /// Sets k, the intermediate points per span of the near-interpolatory step.
    pub fn with_k(mut self, k: usize) -> Self {
        self.k = k;
        self
    }
    /// Sets the number of knot updates per stage.
    pub fn with_knot_iterations(mut self, n: usize) -> Self {
        self.knot_iterations = n;
        self
    }
    /// Sets the further interpolatory levels and their k.
    pub fn with_levels(mut self, levels: usize, level_k: usize) -> Self {
        self.levels = levels;
        self.level_k = level_k;
        self
    }
    /// Sets the data constraint.
    pub fn with_constraint(mut self, c: Constraint) -> Self {
        self.constraint = c;
        self
    }
    /// Sets the derivative constraints.
    pub fn with_tangents(mut self, t: Vec<Option<Tangent>>) -> Self {
        self.tangents = Some(t);
        self
    }
    /// Sets the derivative rule.
    pub fn with_derivative(mut self, rule: DerivativeRule) -> Self {
        self.derivative = rule;
        self
    }
    /// Sets the end conditions (open curves).
    pub fn with_boundary(mut self, b: Boundary) -> Self {
        self.boundary = b;
        self
    }
    /// Sets the solver.
    pub fn with_solver(mut self, s: Solver) -> Self {
        self.solver = s;
        self
    }
    /// Sets the solvers' tuning ([`SolveOptions`], every field with a documented default).
    pub fn with_options(mut self, options: SolveOptions) -> Self {
        self.options = options;
        self
    }

    /// The smallest valid number of data points: 2 for an open curve (a segment), 3 for a
    /// closed one (its data polygon needs three vertices, as `divdiff::Knots::closed` does).
    pub fn min_points(topology: Topology) -> usize {
        match topology {
            Topology::Open => 2,
            Topology::Closed => 3,
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::TooFewPoints`], [`Error::CoincidentPoints`], [`Error::InvalidParameter`] (k = 0,
    /// level_k = 0, negative or NaN exponent), [`Error::WrongLength`], [`Error::InvalidKnots`],
    /// [`Error::InvalidValue`] (negative/NaN radius or weight, bad angle), [`Error::WrongDimension`],
    /// [`Error::TooFewWeights`], [`Error::Unsupported`] (boundary on a closed curve, the paper
    /// solver with tangents or end constraints), [`Error::TooLarge`] (`k`) when the exact solver
    /// would need the general interior-point method on more than [`MAX_CONIC_COORDS`]
    /// coordinates, [`Error::EndConflict`] when an end condition and the tangent set at the
    /// same end are clearly apart (both constrain Df at that vertex).
    pub fn validate(&self) -> Result<(), Error> {
        let n = self.points.len();
        let d = self.points.dim();
        let topo = match self.topology {
            Topology::Open => "open",
            Topology::Closed => "closed",
        };
        let needed = Self::min_points(self.topology);
        if n < needed {
            return Err(Error::TooFewPoints {
                topology: topo,
                needed,
                got: n,
            });
        }
        // Branch-free scans first (the index is searched for only when one fails): a row at a
        // time they were ~1.5 ms of a 10⁵-point solve.
        if let Some((index, next)) = self
            .points
            .coincident_span(self.topology == Topology::Closed)
        {
            return Err(Error::CoincidentPoints { index, next });
        }
        let extent = banded::vector::max_dist_from(self.points.coords(), self.points.point(0));
        if !(EXTENT_RANGE.0..=EXTENT_RANGE.1).contains(&extent) {
            // The first point farthest from points[0] (where the extent is not NaN).
            let far = (0..n)
                .position(|i| {
                    let r = banded::vector::dist(self.points.point(i), self.points.point(0));
                    r.to_bits() == extent.to_bits()
                })
                .unwrap_or(0);
            return Err(Error::InvalidValue {
                field: "points",
                index: far,
                value: extent,
                reason: "the data's extent (distance from points[0]) must be within 1e-150 ..= 1e150; rescale the points",
            });
        }
        if self.k == 0 {
            return Err(Error::InvalidParameter {
                field: "k",
                value: 0.0,
                reason: "at least one intermediate point per span (k >= 1)",
            });
        }
        if self.levels > 0 && self.level_k == 0 {
            return Err(Error::InvalidParameter {
                field: "level_k",
                value: 0.0,
                reason: "at least one intermediate point per span (level_k >= 1)",
            });
        }
        let e = self.parametrization.exponent();
        if !(e.is_finite() && e >= 0.0) {
            return Err(Error::InvalidParameter {
                field: "parametrization.exponent",
                value: e,
                reason: "the exponent must be finite and >= 0",
            });
        }
        if let Some(u) = &self.knots {
            let expected = match self.topology {
                Topology::Open => n,
                Topology::Closed => n + 1,
            };
            if u.len() != expected {
                return Err(Error::WrongLength {
                    field: "knots",
                    expected,
                    got: u.len(),
                });
            }
            if let Some(i) = u.iter().position(|x| !x.is_finite()) {
                return Err(Error::InvalidKnots {
                    index: i,
                    reason: "not finite",
                });
            }
            if let Some(i) = (1..u.len()).find(|&i| u[i] <= u[i - 1]) {
                return Err(Error::InvalidKnots {
                    index: i,
                    reason: "not greater than the previous knot",
                });
            }
        }
        for kind in self.kinds() {
            kind.validate(self)?;
        }
        // An end condition and a tangent set at the same end must meet (proved apart: refused).
        if let Some((end, point, gap)) = crate::constraint::ends::conflict(self) {
            return Err(Error::EndConflict { end, point, gap });
        }
        // The general interior-point method (derivative constraints, half-spaces) costs O(N) per
        // iteration over tens of iterations on the first stage's N vertices; beyond this size
        // one solve takes minutes (4 points, k = 10⁶, tangent wedges: 8 minutes), so it is
        // refused up front.
        let general = self.kinds().iter().any(|k| k.may_need_full_vertex())
            && self.linear_clamped_ends().is_none();
        if general && self.solver == Solver::Exact {
            let spans = if self.topology == Topology::Closed {
                n
            } else {
                n - 1
            };
            let coords = spans
                .checked_mul(self.k.saturating_add(1))
                .and_then(|v| v.checked_add(1))
                .and_then(|v| v.checked_mul(d));
            if coords.is_none_or(|c| c > MAX_CONIC_COORDS) {
                return Err(Error::TooLarge {
                    field: "k",
                    limit: MAX_CONIC_COORDS,
                });
            }
        }
        Ok(())
    }

    /// The clamped ends (start, end) when the first stage is a linear system with them, solved
    /// like interpolation in O(N) ([`crate::linear::clamped`]'s bordered solve): interpolation or
    /// smoothing (balls of radius 0 count as interpolation), [`Boundary::Clamped`] ends, no
    /// tangent set, the exact solver, and for interpolation a new vertex in every span (k ≥ 1),
    /// so that each end's derivative stencil reaches a vertex the data do not fix.
    pub(crate) fn linear_clamped_ends(&self) -> Option<[&[f64]; 2]> {
        let Boundary::Clamped { start, end } = &self.boundary else {
            return None;
        };
        let applies = self
            .tangents
            .as_ref()
            .is_none_or(|t| t.iter().all(Option::is_none))
            && self.constraint.kind().linear()
            && (self.k >= 1 || matches!(self.constraint, Constraint::Smoothing(_)))
            && self.solver == Solver::Exact;
        applies.then_some([start, end])
    }

    /// Whether any tangent constraint or an end condition other than natural is present (the
    /// constraints on Df that only the general interior-point method handles).
    pub(crate) fn has_derivative_constraints(&self) -> bool {
        self.kinds().iter().any(|k| k.on_derivatives())
    }

    /// Interpolation with natural ends (no tangent, no end condition): the linear problem (3.3)
    /// that the closed form and the span condensation solve directly.
    pub(crate) fn interpolates_with_natural_ends(&self) -> bool {
        self.constraint == Constraint::Interpolate && !self.has_derivative_constraints()
    }

    /// The number of refined vertices after one `k`-level split of `n` data points (3.1):
    /// (k + 1)n closed, (k + 1)(n − 1) + 1 open; `usize::MAX` where that overflows.
    pub fn refined_len(topology: Topology, n: usize, k: usize) -> usize {
        let m = k.saturating_add(1);
        match topology {
            Topology::Closed => m.saturating_mul(n),
            Topology::Open => m.saturating_mul(n.max(1) - 1).saturating_add(1),
        }
    }

    /// The validated data knots: the given ones, or the parametrization of the data.
    ///
    /// # Errors
    /// As [`Problem::validate`].
    pub fn data_knots(&self) -> Result<Knots, Error> {
        self.validate()?;
        self.data_knots_unvalidated()
    }

    /// [`Problem::data_knots`] of a problem already validated.
    pub(crate) fn data_knots_unvalidated(&self) -> Result<Knots, Error> {
        match &self.knots {
            Some(u) => Ok(Knots::new(self.topology, u.clone())?),
            None => crate::par::parametrize(&self.points, self.topology, self.parametrization)
                .map_err(|e| match e {
                    divdiff::Error::ZeroLengthSpan { index, next } => {
                        Error::CoincidentPoints { index, next }
                    }
                    // A span |q_{i+1} − q_i|^e that overflows, or vanishes against the knot
                    // before it: the exponent when it is above 1, else the data's extent.
                    divdiff::Error::NonIncreasingKnots { index }
                    | divdiff::Error::NonFinite { index, .. } => {
                        let e = self.parametrization.exponent();
                        if e > 1.0 {
                            Error::InvalidParameter {
                                field: "parametrization.exponent",
                                value: e,
                                reason: "the data parameters' spans |q_{i+1} - q_i|^e over- or underflow, or vanish against the knot values, at this exponent; use a smaller one",
                            }
                        } else {
                            Error::InvalidValue {
                                field: "points",
                                index,
                                value: f64::NAN,
                                reason: "the data parameters overflow, or this span vanishes against them: the points' extent is outside the floating-point range; rescale the points",
                            }
                        }
                    }
                    e => Error::Divdiff(e),
                }),
        }
    }
}
