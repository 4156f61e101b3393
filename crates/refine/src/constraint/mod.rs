//! The constraints of a refinement problem: one module per kind behind one trait, [`Kind`].
//!
//! A kind is everything one field of a [`Problem`] asks of the curve:
//!
//! | kind | field | module | Kersey |
//! |---|---|---|---|
//! | interpolation p_{i_k} = q_i | `constraint` | [`interpolate`] | (3.2) |
//! | balls \|p_{i_k} − q_i\| ≤ ε_i | `constraint` | [`balls`] | (3.4) |
//! | smoothing ½ Σ w_i \|p_{i_k} − q_i\|² | `constraint` | [`smoothing`] | (3.6) |
//! | half-space sets p_{i_k} ∈ ∩_j {n_ij·x ≤ c_ij} | `constraint` | [`halfspaces`] | (3.7) |
//! | derivative constraints on Df(t_{i_k}) | `tangents` | [`tangents`] | §3.5, (3.9)–(3.10) |
//! | end conditions of an open curve | `boundary` | [`ends`] | §3.6 |
//!
//! Each kind says, in its own file:
//! - how its input is **validated** (errors name the user's field and index);
//! - the **cone rows** it adds to a stage's conic model ([`Rows`], a [`ConicProblem`] with the
//!   origin of every row): what the full-vertex backend solves; a kind acting on data vertices
//!   alone also gives its **point sets** ([`PointSet`]) for the condensed backend, and maps a
//!   solution back to **multipliers** in the convention of [`crate::Refinement::multipliers`];
//! - its **certificate terms** ([`Terms`]): its forces in the stationarity condition, its
//!   violation, complementarity and duality gap — recomputed from the points, independently of
//!   the solver ([`crate::certify`]);
//! - its part of the **common-point test** ([`crate::degenerate`]): the projection onto each data
//!   point's set, when a constant curve can be optimal;
//! - how it moves under **translation and scaling** of the data.
//!
//! Adding a kind is one file and one enum arm (in [`Constraint::kind`], [`Tangent`]'s or
//! [`Boundary`]'s dispatch).

pub(crate) mod balls;
pub(crate) mod ends;
pub(crate) mod farkas;
pub(crate) mod halfspaces;
pub(crate) mod interpolate;
pub(crate) mod smoothing;
pub(crate) mod tangents;

use divdiff::{DerivativeRule, Knots, Points};

use crate::backend::condensed::PointSet;
use crate::conic_problem::{ConicProblem, ConicSolution, ConvexSet};
use crate::problem::Problem;
use crate::stage::FixedProblem;
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

/// Where a row of the conic model comes from: the user's field and the index in it (the data
/// point, or for `boundary` 0 = start, 1 = end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Origin {
    pub field: &'static str,
    pub index: usize,
}

/// A stage's conic model as the kinds build it.
pub(crate) struct Rows {
    /// The conic problem (full-vertex form).
    pub problem: ConicProblem,
    /// The origin of each of its constraints.
    pub origin: Vec<Origin>,
    /// The data kind's constraint index per data point (`None`: fixed, smoothed or free).
    pub data: Vec<Option<usize>>,
    /// The derivative kinds' constraints, in order, with their stencils.
    pub derivative: Vec<(usize, Vec<(usize, f64)>)>,
}

impl Rows {
    /// An empty model of the stage's curve.
    pub(crate) fn new(stage: &FixedProblem<'_>) -> Result<Self, Error> {
        Ok(Rows {
            problem: ConicProblem::new(stage.knots, stage.q.dim())?,
            origin: Vec::new(),
            data: vec![None; stage.q.len()],
            derivative: Vec::new(),
        })
    }

    /// Adds a constraint on data point `index`'s vertex.
    pub(crate) fn data(
        &mut self,
        field: &'static str,
        index: usize,
        vertex: usize,
        set: ConvexSet,
    ) -> Result<(), Error> {
        let c = self.problem.add_constraint(&[(vertex, 1.0)], set)?;
        self.origin.push(Origin { field, index });
        self.data[index] = Some(c);
        Ok(())
    }

    /// Adds a constraint on a derivative stencil.
    pub(crate) fn derivative(
        &mut self,
        field: &'static str,
        index: usize,
        stencil: Vec<(usize, f64)>,
        set: ConvexSet,
    ) -> Result<(), Error> {
        let c = self.problem.add_constraint(&stencil, set)?;
        self.origin.push(Origin { field, index });
        self.derivative.push((c, stencil));
        Ok(())
    }

    /// The user's view of a conic-model error: an infeasible constraint (or the most violated
    /// one, when no feasible point was found) named by its field and index.
    pub(crate) fn user_error(&self, e: Error) -> Error {
        match e {
            Error::Infeasible { constraint } => match self.origin.get(constraint) {
                Some(o) => Error::InfeasibleConstraint {
                    field: o.field,
                    point: o.index,
                },
                None => Error::Infeasible { constraint },
            },
            Error::NoFeasiblePoint {
                constraint,
                violation,
                iterations,
            } => match self.origin.get(constraint) {
                Some(o) => Error::NoFeasiblePointFound {
                    field: o.field,
                    point: o.index,
                    violation,
                    iterations,
                },
                None => e,
            },
            e => e,
        }
    }
}

/// What a kind's certificate terms are computed from (see [`crate::certify`]).
pub(crate) struct At<'a> {
    pub p: &'a Points,
    /// The points at the data vertices, n × d (p_{i_k} of data point i: [`At::data_point`]).
    pub data_points: &'a [f64],
    pub q: &'a Points,
    pub knots: &'a Knots,
    pub data_vertex: &'a [usize],
    /// The data kind's multipliers, one entry per data point, in its convention.
    pub multipliers: &'a crate::Multipliers,
    /// The derivative kinds' (cone dual ζ_c, force z_c = −F_cᵀζ_c), one per derivative
    /// constraint in the order of [`Rows`] (a constraint the solver turned into a fixed vertex has
    /// no dual, only its reaction force).
    pub duals: &'a [(Vec<f64>, Vec<f64>)],
    pub rule: DerivativeRule,
    /// The length scale L (data and curve extent about the data's centroid).
    pub length: f64,
    /// A constraint within this relative slack of its boundary counts as active.
    pub active_tol: f64,
}

impl At<'_> {
    /// p_{i_k}, the point at data point i's vertex.
    pub(crate) fn data_point(&self, i: usize) -> &[f64] {
        let d = self.q.dim();
        &self.data_points[i * d..(i + 1) * d]
    }
}

/// A kind's certificate terms, accumulated (module docs of [`crate::certify`] for the units).
pub(crate) struct Terms {
    /// Σ (constraint gradient × multiplier) at the data vertices (n × d).
    pub force_data: Vec<f64>,
    /// The derivative constraints' forces L_cᵀ z_c at their stencils' vertices: (u·d + k,
    /// coefficient × force_k) for vertex u and coordinate k, in the order added (sum them with
    /// [`Terms::derivative_forces`]). Sparse: a few vertices each, where a dense N × d array
    /// cost a clamped curve of 8·10⁵ vertices 0.8 ms to clear and more to read.
    pub derivative: Vec<(usize, f64)>,
    /// Largest violation, in length units.
    pub primal: f64,
    /// Largest violation relative to the constraint's own scale (derivative constraints).
    pub primal_rel: f64,
    /// Largest negative multiplier (or dual-cone violation), in force units.
    pub dual: f64,
    /// Largest complementarity |multiplier × slack|, in force units.
    pub comp: f64,
    /// Σ |multiplier × slack|, in energy units: a bound on E(p) − E* (the duality gap).
    pub gap: f64,
    /// The largest curvature the kind adds to the Lagrangian's Hessian H + W (a ball's or a
    /// smoothing weight's w_i, in force per length): rounding of size ε|p| in the points moves
    /// its forces by this times ε|p|, so it enters the certificate's rounding level beside ‖H‖.
    pub stiffness: f64,
    /// The force that rounding the data vertex's coordinates to floating point can produce,
    /// per data point (n): a stiff smoothing weight w times u |p_{i_k}| — the stationarity at
    /// that vertex is judged beyond it (module docs of [`crate::certify`]).
    pub rounding_data: Vec<f64>,
    /// A penalty kind's part of the objective, ½ Σ w_i |p_{i_k} − q_i|² (smoothing), beside E.
    pub penalty: f64,
    /// Whether each data point's constraint is active.
    pub active: Vec<bool>,
    /// Data points that Corollary 3.3's inactive jumps do not concern (smoothing: a penalty,
    /// not a constraint).
    pub no_jump: Vec<bool>,
    /// The next derivative dual to read.
    pub next_dual: usize,
    /// The largest size of a derivative constraint's set (|centre| + radius, |offset| / |normal|;
    /// 0 for a wedge), in derivative units: how far its derivatives may take the curve from its
    /// data per unit of parameter (the certificate's run-off bound, [`crate::certify`]).
    pub reach: f64,
}

impl Terms {
    pub(crate) fn new(n: usize, d: usize) -> Self {
        Terms {
            force_data: vec![0.0; n * d],
            derivative: Vec::new(),
            primal: 0.0,
            primal_rel: 0.0,
            dual: 0.0,
            comp: 0.0,
            gap: 0.0,
            stiffness: 0.0,
            rounding_data: vec![0.0; n],
            penalty: 0.0,
            active: vec![false; n],
            no_jump: vec![false; n],
            next_dual: 0,
            reach: 0.0,
        }
    }

    /// The derivative forces `terms` (taken from [`Terms::derivative`]) summed per vertex
    /// coordinate: (u·d + k, Σ) sorted by u·d + k, each sum from 0 in the order the terms were
    /// added (as a dense array cleared to 0 and accumulated in that order gives it, bit for bit).
    pub(crate) fn derivative_forces(mut terms: Vec<(usize, f64)>) -> Vec<(usize, f64)> {
        // (stable: equal indices keep the order they were added in)
        terms.sort_by_key(|&(k, _)| k);
        let mut out: Vec<(usize, f64)> = Vec::with_capacity(terms.len());
        for (k, f) in terms {
            match out.last_mut() {
                Some((last, sum)) if *last == k => *sum += f,
                _ => out.push((k, 0.0 + f)),
            }
        }
        out
    }
}

/// What a kind contributes to the common-point test of [`crate::degenerate`].
pub(crate) enum CommonPoint<'a> {
    /// No data point is restricted (a constant curve is not even a candidate: interpolation,
    /// smoothing, derivative constraints).
    Never,
    /// Point i's set as a projection, its violation and a necessary test on consecutive sets.
    Sets(Box<dyn Projections + 'a>),
}

/// The sets of a common-point test.
pub(crate) trait Projections {
    /// A cheap necessary condition for a common point (false: there is none).
    fn possible(&self) -> bool {
        true
    }
    /// Projects x onto every set in turn (one sweep of alternating projections).
    fn sweep(&self, x: &mut [f64]);
    /// The largest violation of x over all sets (0 inside all), in length units.
    fn violation(&self, x: &[f64]) -> f64;
    /// Multipliers of the constant curve (all zero), in the kind's convention.
    fn zero_multipliers(&self, d: usize) -> Vec<Vec<f64>>;
}

/// One kind of constraint (module docs).
pub(crate) trait Kind {
    /// Checks the kind's input against the problem; errors name the user's field and index.
    fn validate(&self, problem: &Problem) -> Result<(), Error>;

    /// Whether it acts on derivative stencils (then only the full-vertex backend applies, and
    /// the knots enter the constraint).
    fn on_derivatives(&self) -> bool {
        false
    }

    /// The vertices v whose derivative stencils [`Kind::certify`] checks (what it passes
    /// [`certify_derivative`]), given the data vertices and the number of vertices: the
    /// certificate keeps Hp at their stencils' vertices beside the data vertices'. None for a
    /// kind that does not act on derivatives.
    fn derivative_vertices(&self, _data_vertex: &[usize], _vertices: usize) -> Vec<usize> {
        Vec::new()
    }

    /// Whether it may need the full-vertex backend on the whole first stage (then
    /// [`Problem::validate`] refuses problems beyond [`crate::MAX_CONIC_COORDS`]).
    fn may_need_full_vertex(&self) -> bool {
        self.on_derivatives()
    }

    /// Whether the problem with this kind alone is a linear system (interpolation, smoothing).
    fn linear(&self) -> bool {
        false
    }

    /// The field a data point's overflowing multiplier is refused naming, and why in this kind's
    /// words (`Problem::accept`: a multiplier beyond the doubles is no certificate).
    fn multiplier_overflow(&self) -> (&'static str, &'static str) {
        (
            "constraint",
            "the multiplier of this point's constraint overflows against the data's scale",
        )
    }

    /// Adds its rows to one stage's conic model.
    ///
    /// # Errors
    /// Errors of [`ConicProblem`] for malformed rows (impossible after validation).
    fn rows(&self, stage: &FixedProblem<'_>, rows: &mut Rows) -> Result<(), Error>;

    /// Its sets on the data vertices for the condensed backend, one per data point (`None`: no
    /// constraint there), when it is a set on data vertices alone.
    fn point_sets(&self, stage: &FixedProblem<'_>) -> Option<Vec<Option<PointSet>>> {
        let _ = stage;
        None
    }

    /// Its multipliers, one entry per data point in the convention of
    /// [`crate::Refinement::multipliers`], from a full-vertex solution of `rows` (`hp`: Hp at
    /// every vertex). Derivative kinds report none.
    fn multipliers(
        &self,
        stage: &FixedProblem<'_>,
        sol: &ConicSolution,
        rows: &Rows,
        hp: &[f64],
    ) -> Vec<Vec<f64>> {
        let _ = (stage, sol, rows, hp);
        Vec::new()
    }

    /// Adds its certificate terms.
    fn certify(&self, at: &At<'_>, terms: &mut Terms);

    /// Its part of the common-point test, for the data `q`.
    fn common_point<'s>(&'s self, q: &'s Points) -> CommonPoint<'s> {
        let _ = q;
        CommonPoint::Never
    }

    /// Moves its data with a translation of the data points by `offset`, in `into`.
    fn translate(&self, offset: &[f64], into: &mut Problem) {
        let _ = (offset, into);
    }

    /// Scales its data with the data points scaled by 2^`points` and the knots by 2^`knots`, in
    /// `into`, so that the problem stays the same one (`run_rescaled` in `solve.rs`): lengths
    /// (radii, offsets) by 2^points, derivative bounds by 2^(points − knots), smoothing weights
    /// by 2^(−3·knots) (E scales by 2^(2·points − 3·knots)); normals and wedges as given.
    ///
    /// # Errors
    /// An entry whose scaled value leaves the doubles, named (a smoothing weight whose w·h³
    /// exceeds them).
    fn rescale(&self, points: i32, knots: i32, into: &mut Problem) -> Result<(), Error> {
        let _ = (points, knots, into);
        Ok(())
    }

    /// A penalty kind's weight at each data point (smoothing): its data vertices are free, and
    /// their forces are part of the objective's gradient. `None` (the default): the data
    /// vertices are constrained, and the certificate's arc test ([`crate::arcs`]) ends its arcs
    /// there.
    fn penalty_weights(&self) -> Option<&[f64]> {
        None
    }

    /// The power of two the multipliers of data point `i` scale by under [`Kind::rescale`]'s
    /// scaling (data kinds, in the convention of [`crate::Refinement::multipliers`]): forces
    /// (reactions, half-space multipliers) scale as Hp, by 2^(points − 3·knots); weights (a
    /// ball's force over its radius, a smoothing weight) by 2^(−3·knots).
    fn multiplier_power(&self, i: usize, points: i32, knots: i32) -> i32 {
        let _ = i;
        points - 3 * knots
    }
}

impl Constraint {
    /// The kind behind this data constraint.
    pub(crate) fn kind(&self) -> Box<dyn Kind + '_> {
        match self {
            Constraint::Interpolate => Box::new(interpolate::Interpolate),
            Constraint::Balls(r) => Box::new(balls::Balls(r)),
            Constraint::Smoothing(w) => Box::new(smoothing::Smoothing(w)),
            Constraint::HalfSpaces(s) => Box::new(halfspaces::HalfSpaces(s)),
        }
    }
}

impl Problem {
    /// Every kind of the problem: the data constraint, then the tangents and the end conditions
    /// when present.
    pub(crate) fn kinds(&self) -> Vec<Box<dyn Kind + '_>> {
        let mut out = vec![self.constraint.kind()];
        if let Some(t) = &self.tangents {
            if t.iter().any(Option::is_some) {
                out.push(Box::new(tangents::Tangents(t)));
            }
        }
        if self.boundary != Boundary::Natural {
            out.push(Box::new(ends::Ends(&self.boundary)));
        }
        out
    }
}

// Shared validation helpers (errors name the user's field and index).

pub(crate) fn check_len(field: &'static str, got: usize, expected: usize) -> Result<(), Error> {
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

pub(crate) fn check_nonneg_one(field: &'static str, index: usize, value: f64) -> Result<(), Error> {
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

pub(crate) fn check_nonneg(field: &'static str, v: &[f64]) -> Result<(), Error> {
    v.iter()
        .enumerate()
        .try_for_each(|(i, &x)| check_nonneg_one(field, i, x))
}

pub(crate) fn check_dim(
    field: &'static str,
    index: usize,
    v: &[f64],
    d: usize,
) -> Result<(), Error> {
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

/// Checks each half-space of one set (dimension, finite, a usable normal), then that the set is
/// not provably empty ([`farkas`]; the witness search starts at `start`, the data point where
/// the set must hold it; `budget` is the problem's search budget).
pub(crate) fn check_halfspaces(
    field: &'static str,
    point: usize,
    set: &[HalfSpace],
    d: usize,
    start: Option<&[f64]>,
    budget: &mut usize,
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
    let row = |j: usize| (&set[j].normal[..], set[j].offset);
    match farkas::search(set.len(), row, d, start, budget) {
        Some(half_spaces) => Err(Error::EmptySet {
            field,
            point,
            half_spaces,
        }),
        None => Ok(()),
    }
}

/// The Euclidean distance |a − b| (scaled: no overflow or underflow of the squares).
pub(crate) use banded::vector::dist;

/// How far beyond the data, in multiples of the data's extent L (the largest distance from
/// `points[0]`, as validation measures it), the solvers see a data constraint's bound: a ball's
/// radius or a half-space's offset past this is capped there ([`far_cap`]).
///
/// Why: a bound far beyond the data is a user's "no bound" (a radius of 1e10 for a free point,
/// an offset of 1e20 for an open side of a box, as other solvers spell infinity). It left the
/// interior-point method's slacks many orders above everything else: it stopped without a
/// certificate (balls on closed curves from ~1e9·L, half-spaces from 1e20), or its start was
/// refused as outside its cone (1e200); on random hard problems a cap of 1e6·L still left one
/// in ten such problems uncertified, 1e2·L none that bounded ones did not (ROBUSTNESS.md §4,
/// 29). The certificate keeps the bounds as given, and that is exact: a capped bound the
/// optimum leaves clearly inactive carries no multiplier there (both kinds project multipliers
/// onto complementarity), so its certificate terms — force 0, violation, complementarity and
/// gap 0 — are those of the bound as given. Were a capped bound active at a solution (a data
/// vertex 100·L from its point), the certificate, which reads the given bound as clearly
/// inactive, would charge its force to stationarity and refuse the solve: never a wrong answer.
pub(crate) const FAR_BOUND: f64 = 1e2;

/// [`FAR_BOUND`] times the extent of the data `q`.
pub(crate) fn far_cap(q: &Points) -> f64 {
    FAR_BOUND * banded::vector::max_dist_from(q.coords(), q.point(0))
}

/// How far beyond the data's largest slope max_i |q_{i+1} − q_i| / (t_{i_{k+1}} − t_{i_k}) a
/// derivative bound lies when the solvers leave it to the certificate
/// ([`split_far_derivative_set`]): a ball (tension, a tangent ball, near-clamped ends) whose
/// radius exceeds its centre's length by this, a side of a tangent polytope holding Df = 0
/// whose offset exceeds this times its normal's length. Such a bound is "no bound" spelled as a
/// number, and the solvers met its size as a scale: tension of 1e10 with balls was refused
/// uncertified, 1e300 as a singular system; tangent half-spaces of offset 1e50 as not
/// converged, 1e200 as a singular system (ROBUSTNESS.md §4, 29 and 30). Solved without it and
/// certified with its violation ([`derivative_violation`]), the answer is exact. Larger than
/// [`FAR_BOUND`]: a bound that the optimum reaches would be violated by the solution without
/// it, which the certificate refuses, and a threshold this far leaves every derivative bound of
/// ordinary size to the solvers.
pub(crate) const FAR_DERIVATIVE_BOUND: f64 = 1e6;

/// [`FAR_DERIVATIVE_BOUND`] times the largest slope of data `q` at `data_vertex` on `knots`:
/// the threshold of [`split_far_derivative_set`] (computed once per kind and pass, for
/// [`derivative_rows`] and [`certify_derivative`]).
pub(crate) fn far_derivative_threshold(q: &Points, knots: &Knots, data_vertex: &[usize]) -> f64 {
    let (t, dv) = (knots.values(), data_vertex);
    // (the chords four at a time, as `dist` gives them: one at a time they were most of it)
    let mut chords = vec![0.0; q.len().saturating_sub(1)];
    banded::vector::consecutive_dists(q.coords(), q.dim(), &mut chords);
    let slope = (chords.iter().zip(dv.windows(2)))
        .fold(0.0f64, |a, (chord, v)| a.max(chord / (t[v[1]] - t[v[0]])));
    FAR_DERIVATIVE_BOUND * slope
}

/// The solver rows of the derivative constraint `set` on the stencil at vertex `v` (`field` and
/// `index` name it in errors): none for a far bound, which only the certificate checks
/// ([`split_far_derivative_set`] at `far`, [`far_derivative_threshold`]).
pub(crate) fn derivative_rows(
    stage: &FixedProblem<'_>,
    rows: &mut Rows,
    (field, index): (&'static str, usize),
    v: usize,
    set: ConvexSet,
    far: f64,
) -> Result<(), Error> {
    if let (Some(set), _) = split_far_derivative_set(set, far) {
        let stencil = divdiff::derivative_stencil(stage.knots, v, stage.problem.derivative)?;
        rows.derivative(field, index, stencil.to_vec(), set)?;
    }
    Ok(())
}

/// The certificate terms of the derivative constraint `set` at vertex `v`: the full terms of
/// the part the solvers saw ([`derivative_terms`]) and the violation alone of a far part
/// ([`derivative_violation`]), split as [`derivative_rows`] split it.
pub(crate) fn certify_derivative(
    at: &At<'_>,
    terms: &mut Terms,
    v: usize,
    set: ConvexSet,
    far: f64,
) {
    terms.reach = terms.reach.max(crate::conic_problem::set_scale(&set));
    let (solved, checked) = split_far_derivative_set(set, far);
    if let Some(set) = solved {
        derivative_terms(at, terms, v, &set);
    }
    if let Some(set) = checked {
        derivative_violation(at, terms, v, &set);
    }
}

/// A derivative set split at `cap` into what the solvers see and what only the certificate
/// checks: a ball {|Df − c| ≤ r} with r > |c| + `cap` (it holds every Df with |Df| ≤ cap) is
/// left to the certificate whole; of a polytope that holds Df = 0 (every offset ≥ 0), the sides
/// with offset > `cap` |normal| are; every other set goes to the solvers as given. Returns
/// (solved, checked): either may be `None`.
fn split_far_derivative_set(set: ConvexSet, cap: f64) -> (Option<ConvexSet>, Option<ConvexSet>) {
    match set {
        ConvexSet::Ball { center, radius } if radius > banded::vector::norm(&center) + cap => {
            (None, Some(ConvexSet::Ball { center, radius }))
        }
        ConvexSet::HalfSpaces(hs) if hs.iter().all(|(_, offset)| *offset >= 0.0) => {
            let (far, near): (Vec<_>, Vec<_>) = hs
                .into_iter()
                .partition(|(normal, offset)| *offset > cap * banded::vector::norm(normal));
            let some =
                |v: Vec<(Vec<f64>, f64)>| (!v.is_empty()).then_some(ConvexSet::HalfSpaces(v));
            (some(near), some(far))
        }
        set => (Some(set), None),
    }
}

/// Half-spaces with their offsets times 2^k (normals as given): the data's under
/// [`Kind::rescale`], or a tangent set's.
pub(crate) fn scaled_halfspaces(set: &[HalfSpace], k: i32) -> Vec<HalfSpace> {
    set.iter()
        .map(|h| HalfSpace {
            normal: h.normal.clone(),
            offset: crate::solve::times_power_of_two(h.offset, k),
        })
        .collect()
}

/// The half-spaces as the conic model's polytope.
pub(crate) fn polytope(set: &[HalfSpace]) -> ConvexSet {
    ConvexSet::HalfSpaces(set.iter().map(|h| (h.normal.clone(), h.offset)).collect())
}

/// The reaction −(Hp)_v at a fixed data vertex (interpolation's multiplier), from Hp at every
/// vertex.
pub(crate) fn reaction(hp: &[f64], v: usize, d: usize) -> Vec<f64> {
    hp[v * d..(v + 1) * d].iter().map(|x| -x).collect()
}

/// The certificate terms of one derivative constraint L p ∈ K on the stencil at vertex `v`,
/// with its dual ζ (the next in `at.duals`): its force −Lᵀ Fᵀ ζ at the stencil's vertices, its
/// violation dist(L p, K) relative to max(|L p|, the set's scale), the dual-cone violation of ζ
/// (as a force), and |sᵀζ| with s = g + F L p in the duality gap (the rows (F, g) of
/// [`crate::backend::full`], recomputed here from the set).
///
/// `set` is the part the solvers saw ([`split_far_derivative_set`]); the part left to the
/// certificate adds its violation alone ([`derivative_violation`]).
fn derivative_terms(at: &At<'_>, terms: &mut Terms, v: usize, set: &ConvexSet) {
    let d = at.q.dim();
    let Some((stencil, y)) = derivative_violation(at, terms, v, set) else {
        return;
    };
    let (zeta, force) = match at.duals.get(terms.next_dual) {
        Some(z) => z,
        None => {
            terms.primal_rel = f64::INFINITY;
            return;
        }
    };
    terms.next_dual += 1;
    let cmax = stencil.iter().fold(0.0f64, |a, &(_, c)| a.max(c.abs()));
    for &(u, c) in stencil.iter() {
        for (k, f) in force[..d].iter().enumerate() {
            terms.derivative.push((u * d + k, c * f));
        }
    }
    let rows = crate::backend::full::set_rows(set, d);
    let m: usize = rows.iter().map(|(cone, _, _)| cone.dim()).sum();
    if zeta.len() != m {
        // The solver fixed a vertex for it: its reaction force is all there is to check.
        return;
    }
    let mut off = 0;
    for (cone, f, g) in rows {
        let mb = cone.dim();
        let zb = &zeta[off..off + mb];
        let mut proj = zb.to_vec();
        conic::cone::project_dual(cone.kind(), &mut proj);
        // The dual-cone violation as a force: |Fᵀ(ζ − Π ζ)| times the stencil's size.
        let mut fz = vec![0.0; d];
        for r in 0..mb {
            for k in 0..d {
                fz[k] += f[r][k] * (zb[r] - proj[r]);
            }
        }
        terms.dual = terms
            .dual
            .max(cmax * fz.iter().fold(0.0f64, |a, x| a.max(x.abs())));
        if cone.kind() != conic::Kind::Zero {
            let sz: f64 = (0..mb)
                .map(|r| (g[r] + f[r].iter().zip(&y).map(|(a, b)| a * b).sum::<f64>()) * zb[r])
                .sum();
            terms.gap += sz.abs();
        }
        off += mb;
    }
}

/// A derivative stencil [(vertex, coefficient)] and the derivative L p it gives.
type DerivativeAt = ([(usize, f64); 3], Vec<f64>);

/// The violation of a derivative set at the stencil of vertex `v` (dist(L p, K) relative to
/// max(|L p|, the set's scale, the stencil's rounding scale)) added to `terms`, and the stencil
/// and L p; `None` (and an infinite violation) when the stencil cannot be formed. A far bound
/// the solvers did not see ([`split_far_derivative_set`]) adds this alone: the solvers' problem
/// without it is certified by the other terms, and a solution of that problem which keeps to
/// the bound is the given problem's optimum (its feasible set lies inside the other's), with a
/// zero multiplier for the bound.
fn derivative_violation(
    at: &At<'_>,
    terms: &mut Terms,
    v: usize,
    set: &ConvexSet,
) -> Option<DerivativeAt> {
    let d = at.q.dim();
    let Ok(stencil) = divdiff::derivative_stencil(at.knots, v, at.rule) else {
        terms.primal_rel = f64::INFINITY;
        return None;
    };
    let x = at.p.coords();
    // L p in difference form, Σ_u c_u (p_u − p_v) (the coefficients sum to zero: a derivative
    // of a constant vanishes), and its rounding scale Σ_u |c_u| |p_u − p_v|_∞: the size of the
    // derivative the stencil sees. A zero or tiny target (clamped ends [0, 0], 1e-9) has no
    // scale of its own, so the violation is measured against this one; relative to |L p|
    // alone a curve that meets Df = 0 to rounding showed a relative violation of 1.
    let mut y = vec![0.0; d];
    let mut rounding: f64 = 0.0;
    for &(u, c) in stencil.iter() {
        let mut step: f64 = 0.0;
        for k in 0..d {
            let diff = x[u * d + k] - x[v * d + k];
            y[k] += c * diff;
            step = step.max(diff.abs());
        }
        rounding += c.abs() * step;
    }
    let (dist_y, scale) = crate::conic_problem::set_distance(set, &y);
    let den = scale
        .max(y.iter().map(|a| a * a).sum::<f64>().sqrt())
        .max(rounding);
    if dist_y > 0.0 {
        terms.primal_rel = terms.primal_rel.max(if den > 0.0 {
            dist_y / den
        } else {
            f64::INFINITY
        });
    }
    Some((stencil, y))
}
