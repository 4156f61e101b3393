//! The refinement problem: data, constraints, options, and their validation.

use divdiff::{DerivativeRule, Knots, Parametrization, Points, Topology};

use crate::Error;

/// One half-space {x : normal · x ≤ offset}.
#[derive(Clone, Debug, PartialEq)]
pub struct HalfSpace {
    /// The outward normal (any non-zero length).
    pub normal: Vec<f64>,
    /// The offset c in normal · x ≤ c.
    pub offset: f64,
}

/// The constraint that ties the data vertices p_{i_k} to the data q_i (Kersey §3).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Constraint {
    /// p_{i_k} = q_i (3.2).
    #[default]
    Interpolate,
    /// |p_{i_k} − q_i| ≤ ε_i (3.4); one radius per data point, 0 interpolates that point.
    Balls(Vec<f64>),
    /// Minimize E + ½ Σ w_i |p_{i_k} − q_i|² (3.6); one weight w_i ≥ 0 per data point.
    Smoothing(Vec<f64>),
    /// p_{i_k} ∈ K_i = ∩_j {x : n_ij · x ≤ c_ij} (3.7); one (possibly empty) set per data point.
    HalfSpaces(Vec<Vec<HalfSpace>>),
}

/// A constraint on the approximate derivative Df(t_{i_k}) at a data vertex (Kersey §3.5).
#[derive(Clone, Debug, PartialEq)]
pub enum Tangent {
    /// |Df − center| ≤ radius (Fig. 3.5a).
    Ball {
        /// The prescribed vector v_i.
        center: Vec<f64>,
        /// The tolerance ε¹_i ≥ 0.
        radius: f64,
    },
    /// The angle between Df and `direction` is at most `half_angle` (Fig. 3.5b).
    Wedge {
        /// The prescribed direction (non-zero).
        direction: Vec<f64>,
        /// Half the opening angle, in radians, in [0, π/2).
        half_angle: f64,
    },
    /// |Df| ≤ radius (Fig. 3.5c, tension).
    Tension {
        /// The tolerance ε¹_i ≥ 0.
        radius: f64,
    },
    /// Df satisfies every half-space.
    HalfSpaces(Vec<HalfSpace>),
}

/// End conditions of an open curve (Kersey §3.6).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Boundary {
    /// Natural ends: no end condition (an inactive end constraint gives Δ_{1,2} = 0).
    #[default]
    Natural,
    /// Df(t_1) = start, Df(t_N) = end.
    Clamped {
        /// The start derivative v_1.
        start: Vec<f64>,
        /// The end derivative v_n.
        end: Vec<f64>,
    },
    /// |Df(t_1) − start| ≤ radius, |Df(t_N) − end| ≤ radius.
    NearClamped {
        /// The start derivative v_1.
        start: Vec<f64>,
        /// The end derivative v_n.
        end: Vec<f64>,
        /// The tolerance ≥ 0.
        radius: f64,
    },
}

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
    /// coordinates.
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
        let spans = match self.topology {
            Topology::Open => n - 1,
            Topology::Closed => n,
        };
        for i in 0..spans {
            let j = if i + 1 == n { 0 } else { i + 1 };
            if self.points.point(i) == self.points.point(j) {
                return Err(Error::CoincidentPoints { index: i, next: j });
            }
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
        match &self.constraint {
            Constraint::Interpolate => {}
            Constraint::Balls(r) => {
                check_len("radii", r.len(), n)?;
                check_nonneg("radii", r)?;
            }
            Constraint::Smoothing(w) => {
                check_len("weights", w.len(), n)?;
                check_nonneg("weights", w)?;
                let positive = w.iter().filter(|&&x| x > 0.0).count();
                let needed = match self.topology {
                    Topology::Open => 2,
                    Topology::Closed => 1,
                };
                if positive < needed {
                    return Err(Error::TooFewWeights {
                        needed,
                        got: positive,
                    });
                }
            }
            Constraint::HalfSpaces(sets) => {
                check_len("sets", sets.len(), n)?;
                for (i, set) in sets.iter().enumerate() {
                    check_halfspaces("sets", i, set, d)?;
                }
            }
        }
        if let Some(t) = &self.tangents {
            check_len("tangents", t.len(), n)?;
            for (i, tan) in t.iter().enumerate() {
                match tan {
                    None => {}
                    Some(Tangent::Ball { center, radius }) => {
                        check_dim("tangents.center", i, center, d)?;
                        check_nonneg_one("tangents.radius", i, *radius)?;
                    }
                    Some(Tangent::Wedge {
                        direction,
                        half_angle,
                    }) => {
                        check_dim("tangents.direction", i, direction, d)?;
                        if direction.iter().all(|&x| x == 0.0) {
                            return Err(Error::InvalidValue {
                                field: "tangents.direction",
                                index: i,
                                value: 0.0,
                                reason: "the direction must be non-zero",
                            });
                        }
                        let a = *half_angle;
                        if !(a.is_finite() && (0.0..std::f64::consts::FRAC_PI_2).contains(&a)) {
                            return Err(Error::InvalidValue {
                                field: "tangents.half_angle",
                                index: i,
                                value: a,
                                reason: "must be in [0, pi/2)",
                            });
                        }
                    }
                    Some(Tangent::Tension { radius }) => {
                        check_nonneg_one("tangents.radius", i, *radius)?;
                    }
                    Some(Tangent::HalfSpaces(h)) => {
                        check_halfspaces("tangents.halfspaces", i, h, d)?;
                    }
                }
            }
        }
        match (&self.boundary, self.topology) {
            (Boundary::Natural, _) => {}
            (_, Topology::Closed) => {
                return Err(Error::Unsupported {
                    field: "boundary",
                    reason: "end conditions apply to open curves only",
                })
            }
            (Boundary::Clamped { start, end }, Topology::Open) => {
                check_dim("boundary.start", 0, start, d)?;
                check_dim("boundary.end", 0, end, d)?;
            }
            (Boundary::NearClamped { start, end, radius }, Topology::Open) => {
                check_dim("boundary.start", 0, start, d)?;
                check_dim("boundary.end", 0, end, d)?;
                check_nonneg_one("boundary.radius", 0, *radius)?;
            }
        }
        // The general interior-point method (derivative constraints, half-spaces) costs O(N) per
        // iteration over tens of iterations on the first stage's N vertices; beyond this size
        // one solve takes minutes (4 points, k = 10⁶, tangent wedges: 8 minutes), so it is
        // refused up front.
        let general = self.has_derivative_constraints()
            || matches!(self.constraint, Constraint::HalfSpaces(_));
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

    /// Whether any tangent constraint or an end condition other than natural is present (the
    /// constraints on Df that only the general interior-point method handles).
    pub(crate) fn has_derivative_constraints(&self) -> bool {
        self.tangents
            .as_ref()
            .is_some_and(|t| t.iter().any(Option::is_some))
            || self.boundary != Boundary::Natural
    }

    /// The number of refined vertices after one `k`-level split of `n` data points (3.1):
    /// (k + 1)n closed, (k + 1)(n − 1) + 1 open.
    pub fn refined_len(topology: Topology, n: usize, k: usize) -> usize {
        match topology {
            Topology::Closed => (k + 1) * n,
            Topology::Open => (k + 1) * (n.max(1) - 1) + 1,
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
            None => divdiff::parametrize(&self.points, self.topology, self.parametrization)
                .map_err(|e| match e {
                    divdiff::Error::ZeroLengthSpan { index, next } => {
                        Error::CoincidentPoints { index, next }
                    }
                    e => Error::Divdiff(e),
                }),
        }
    }
}

fn check_len(field: &'static str, got: usize, expected: usize) -> Result<(), Error> {
    if got == expected {
        Ok(())
    } else {
        Err(Error::WrongLength {
            field,
            expected,
            got,
        })
    }
}

fn check_nonneg_one(field: &'static str, index: usize, value: f64) -> Result<(), Error> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            field,
            index,
            value,
            reason: "must be finite and >= 0",
        })
    }
}

fn check_nonneg(field: &'static str, v: &[f64]) -> Result<(), Error> {
    v.iter()
        .enumerate()
        .try_for_each(|(i, &x)| check_nonneg_one(field, i, x))
}

fn check_dim(field: &'static str, index: usize, v: &[f64], d: usize) -> Result<(), Error> {
    if v.len() != d {
        return Err(Error::WrongDimension {
            field,
            index,
            expected: d,
            got: v.len(),
        });
    }
    if let Some(&x) = v.iter().find(|x| !x.is_finite()) {
        return Err(Error::InvalidValue {
            field,
            index,
            value: x,
            reason: "not finite",
        });
    }
    Ok(())
}

fn check_halfspaces(
    field: &'static str,
    point: usize,
    set: &[HalfSpace],
    d: usize,
) -> Result<(), Error> {
    for (j, h) in set.iter().enumerate() {
        let bad = |reason| Error::InvalidHalfSpace {
            field,
            point,
            index: j,
            reason,
        };
        if h.normal.len() != d {
            return Err(bad("the normal's dimension differs from the points'"));
        }
        if h.normal.iter().any(|x| !x.is_finite()) || !h.offset.is_finite() {
            return Err(bad("not finite"));
        }
        if h.normal.iter().all(|&x| x == 0.0) {
            return Err(bad("the normal must be non-zero"));
        }
        // The solvers divide by |n|² and |n| (projections, distances): both must be normal
        // floating-point numbers, and so must the offset in units of |n|.
        let nn: f64 = h.normal.iter().map(|x| x * x).sum();
        if !(nn.is_normal() && (h.offset / nn.sqrt()).is_finite()) {
            return Err(bad(
                "the normal's length (squared) must be a normal floating-point number and offset/|normal| finite: rescale the half-space",
            ));
        }
    }
    Ok(())
}
