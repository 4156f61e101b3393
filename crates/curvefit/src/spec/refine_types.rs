//! JSON problem and result of `refine` (issue 7's contract, field for field).

use serde::{Deserialize, Serialize};

pub use super::points::Rows;

fn three() -> usize {
    3
}
fn one() -> usize {
    1
}

/// A Kersey refinement problem. Defaults: `closed` false, `parametrization` centripetal, `k` 3,
/// `knot_iterations` 3, `levels` 0, `level_k` 1, `constraint` interpolate, `derivative` bessel,
/// `boundary` natural, `solver` exact.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RefineProblem {
    /// The data points q_1..q_n, all of the same dimension d ≥ 1 (required; the command line can
    /// read them from `--points FILE.csv` instead).
    #[serde(default)]
    pub points: Rows,
    /// Closed curve (the last span, from the last point back to the first, closes it) or open
    /// (default: open, as scipy's splines and most curve fitters are).
    #[serde(default)]
    pub closed: bool,
    /// Data parameters: open n values, closed n + 1 (the last closes the curve).
    #[serde(default)]
    pub knots: Option<Vec<f64>>,
    /// How to compute data parameters (and knot updates) when `knots` is absent.
    #[serde(default)]
    pub parametrization: ParamSpec,
    /// Intermediate points per span in the near-interpolatory step (≥ 1).
    #[serde(default = "three")]
    pub k: usize,
    /// Knot updates alternating with solves in part 1 (0 = solve once on the initial knots).
    #[serde(default = "three")]
    pub knot_iterations: usize,
    /// Further interpolatory refinement steps (part 2).
    #[serde(default)]
    pub levels: usize,
    /// Intermediate points per span in each further step (≥ 1).
    #[serde(default = "one")]
    pub level_k: usize,
    /// The constraint on the data vertices.
    #[serde(default)]
    pub constraint: ConstraintSpec,
    /// Optional per-point constraints on the vertex derivative Df (one entry or null per point).
    #[serde(default)]
    pub tangents: Option<Vec<Option<TangentSpec>>>,
    /// Rule for Df: "average" (2.2) or "bessel" (corrected (2.3)).
    #[serde(default)]
    pub derivative: DerivativeSpec,
    /// End conditions of open curves.
    #[serde(default)]
    pub boundary: BoundarySpec,
    /// "exact" (interior point + polish, default) or "paper" (the multiplier iteration).
    #[serde(default)]
    pub solver: SolverSpec,
}

/// `"uniform" | "centripetal" | "chordal" | {"exponent": e}`.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ParamSpec {
    /// e = 0.
    Uniform,
    /// e = ½ (default).
    #[default]
    Centripetal,
    /// e = 1.
    Chordal,
    /// Any exponent e ≥ 0.
    Exponent(f64),
}

/// One half-space `normal · x ≤ offset`.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HalfSpaceSpec {
    /// Outward normal (length d, non-zero).
    pub normal: Vec<f64>,
    /// Offset c.
    pub offset: f64,
}

/// The constraint on the data vertices.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ConstraintSpec {
    /// p_{i_k} = q_i.
    #[default]
    Interpolate,
    /// |p_{i_k} − q_i| ≤ radii\[i\] (0 interpolates that point).
    Balls {
        /// One radius ≥ 0 per point.
        radii: Vec<f64>,
    },
    /// Minimize E + ½ Σ w_i |p_{i_k} − q_i|².
    Smoothing {
        /// One weight ≥ 0 per point.
        weights: Vec<f64>,
    },
    /// p_{i_k} in the polytope sets\[i\] (normal · x ≤ offset for each half-space).
    Halfspaces {
        /// One set of half-spaces per point.
        sets: Vec<Vec<HalfSpaceSpec>>,
    },
}

/// A constraint on the derivative Df at a data vertex.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum TangentSpec {
    /// |Df − center| ≤ radius.
    Ball {
        /// Centre v_i.
        center: Vec<f64>,
        /// Radius ≥ 0.
        radius: f64,
    },
    /// Df within `half_angle` of `direction` (length free).
    Wedge {
        /// Direction (non-zero).
        direction: Vec<f64>,
        /// Half opening angle in radians, in [0, π/2).
        half_angle: f64,
    },
    /// |Df| ≤ radius (tension).
    Tension {
        /// Radius ≥ 0.
        radius: f64,
    },
    /// normal · Df ≤ offset for each.
    Halfspaces {
        /// The half-spaces.
        halfspaces: Vec<HalfSpaceSpec>,
    },
}

/// `"average" | "bessel"`.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DerivativeSpec {
    /// (2.2): ½(s_{i−1} + s_i); one-sided differences at open ends.
    Average,
    /// The derivative at t_i of the quadratic through p_{i−1}, p_i, p_{i+1}; Bessel end quadratics.
    #[default]
    Bessel,
}

/// End conditions of an open curve.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum BoundarySpec {
    /// Natural ends (default).
    #[default]
    Natural,
    /// Df(t_1) = start, Df(t_N) = end.
    Clamped {
        /// Start derivative.
        start: Vec<f64>,
        /// End derivative.
        end: Vec<f64>,
    },
    /// |Df(t_1) − start| ≤ radius, |Df(t_N) − end| ≤ radius.
    NearClamped {
        /// Start derivative.
        start: Vec<f64>,
        /// End derivative.
        end: Vec<f64>,
        /// Radius ≥ 0.
        radius: f64,
    },
}

/// `"exact" | "paper"`.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SolverSpec {
    /// Interior point + polish: the exact optimum with a KKT certificate.
    #[default]
    Exact,
    /// Kersey's multiplier iteration (approximate; reproduces the paper's figures).
    Paper,
}

/// The result of `curvefit refine`.
#[derive(Clone, Debug, Serialize)]
pub struct RefineResult {
    /// Refined vertices p_1..p_N (a closed curve does not repeat p_1).
    pub points: Rows,
    /// Knots those points were solved with (open t_1..t_N, closed t_1..t_{N+1}).
    pub knots: Vec<f64>,
    /// 0-based index of the vertex attached to each data point.
    pub data_vertex: Vec<usize>,
    /// E of (2.1) for `points` and `knots`.
    pub energy: f64,
    /// Multipliers of the final solve, one list per data point (see the README for their
    /// meaning per constraint type).
    #[serde(serialize_with = "multiplier_rows")]
    pub multipliers: refine::Multipliers,
    /// Which data-point constraints are active at the optimum.
    pub active: Vec<bool>,
    /// Relative KKT residual of the final solve.
    pub kkt_residual: f64,
    /// Iteration counts.
    pub iterations: RefineIterations,
}

/// The multipliers as JSON: one array per data point.
pub struct MultiplierRows<'a>(pub &'a refine::Multipliers);

impl Serialize for MultiplierRows<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter())
    }
}

fn multiplier_rows<S: serde::Serializer>(m: &refine::Multipliers, s: S) -> Result<S::Ok, S::Error> {
    MultiplierRows(m).serialize(s)
}

/// Iteration counts of a refinement (fields in the order the result has always printed them).
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq)]
pub struct RefineIterations {
    /// Knot updates over all stages.
    pub knot_updates: usize,
    /// Inner iterations of the fixed-knot solver over all stages.
    pub solver: usize,
    /// Fixed-knot solves over all stages.
    pub solves: usize,
}
