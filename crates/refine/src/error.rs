/// Errors of the `refine` crate. Variants name the offending field and index.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Invalid knots or points (from `divdiff`).
    #[error(transparent)]
    Divdiff(#[from] divdiff::Error),
    /// A linear-algebra failure (from `energy`).
    #[error(transparent)]
    Energy(#[from] energy::Error),
    /// A failure of the cone solver (from `conic`) not mapped to a variant of this crate.
    #[error(transparent)]
    Conic(conic::Error),
    /// The requested result would exceed a documented size limit (or overflow `usize`).
    #[error("{field}: the result would exceed the limit of {limit}")]
    TooLarge {
        /// What would grow too large (e.g. `"levels"`).
        field: &'static str,
        /// The limit that would be exceeded.
        limit: usize,
    },
    /// Too few data points for the curve's topology (`needed` is the smallest valid n).
    #[error("points: {topology} curve needs at least {needed} data points, got {got}")]
    TooFewPoints {
        /// `"open"` or `"closed"`.
        topology: &'static str,
        /// The smallest valid number of data points.
        needed: usize,
        /// The number given.
        got: usize,
    },
    /// Two consecutive data points coincide (the span from `index` to `next` has zero length;
    /// `next` wraps to 0 for the closing span of a closed curve).
    #[error("points[{index}] and points[{next}] coincide (consecutive data points must differ)")]
    CoincidentPoints {
        /// The first point of the span.
        index: usize,
        /// The second point of the span.
        next: usize,
    },
    /// A field that must have one entry per data point (or per knot) has the wrong length.
    #[error("{field} has length {got}, expected {expected}")]
    WrongLength {
        /// The field, e.g. `"radii"`.
        field: &'static str,
        /// The expected length.
        expected: usize,
        /// The given length.
        got: usize,
    },
    /// A vector has the wrong number of coordinates (`index` is the data point it belongs to,
    /// or the half-space within the set for nested fields).
    #[error("{field}[{index}] has {got} coordinates, expected {expected}")]
    WrongDimension {
        /// The field, e.g. `"tangents.center"`.
        field: &'static str,
        /// The index of the offending entry.
        index: usize,
        /// The dimension of the data points.
        expected: usize,
        /// The dimension given.
        got: usize,
    },
    /// A per-point value is out of its valid range (negative or NaN radius, weight, angle …).
    #[error("{field}[{index}] = {value} is invalid: {reason}")]
    InvalidValue {
        /// The field, e.g. `"radii"`.
        field: &'static str,
        /// The index of the offending entry.
        index: usize,
        /// The value given.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// A scalar parameter is out of range (e.g. `k = 0`).
    #[error("{field} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// The field, e.g. `"k"`.
        field: &'static str,
        /// The value given.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// A half-space of a constraint set is invalid (`point` is the data point, `index` the
    /// half-space within its set).
    #[error("{field}[{point}][{index}] is invalid: {reason}")]
    InvalidHalfSpace {
        /// The field, `"sets"` or `"tangents.halfspaces"`.
        field: &'static str,
        /// The data point the set belongs to.
        point: usize,
        /// The half-space within the set.
        index: usize,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// The data knots are not strictly increasing (or not finite) at `index`.
    #[error("knots[{index}] is invalid: {reason}")]
    InvalidKnots {
        /// The index of the first offending knot.
        index: usize,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// Smoothing weights do not pin the curve down: the kernel of H (constants for closed
    /// curves, linear polynomials for open ones) needs `needed` positive weights.
    #[error("weights: at least {needed} weights must be positive, got {got}")]
    TooFewWeights {
        /// The number of positive weights needed.
        needed: usize,
        /// The number of positive weights given.
        got: usize,
    },
    /// A knot update met two coincident refined vertices, so the span between them would have
    /// zero parameter length (`stage` 0 is the near-interpolatory step, `stage` ≥ 1 the levels).
    #[error("stage {stage}: refined vertices {index} and {next} coincide; the knot update would give a zero-length span")]
    DegenerateRefinedSpan {
        /// The stage of Algorithm 4.1 (0 = part 1, l ≥ 1 = level l of part 2).
        stage: usize,
        /// The first vertex of the span.
        index: usize,
        /// The second vertex of the span.
        next: usize,
    },
    /// A half-space set has no common point, proved before any solve: the half-spaces
    /// `half_spaces` (indices within the set, at most d + 1) have Farkas multipliers y ≥ 0 with
    /// Σ y_j n_j = 0 and Σ y_j c_j < 0, checked in exact integer arithmetic
    /// (`constraint/farkas.rs`). `field` is `"sets"` or `"tangents.halfspaces"`, `point` the
    /// data point.
    #[error("{field}[{point}] is empty: its half-spaces {half_spaces:?} have no common point")]
    EmptySet {
        /// The field.
        field: &'static str,
        /// The data point the set belongs to.
        point: usize,
        /// The half-spaces (indices within the set) that have no common point.
        half_spaces: Vec<usize>,
    },
    /// A data point's constraint cannot be met, proved: an empty polygon of the paper's slots,
    /// an empty half-space set found after a solve (the same proof as [`Error::EmptySet`]), or a
    /// constraint contradicting fixed vertices; `field` is `"sets"`, `"tangents"` or
    /// `"boundary"` and `point` the data point (for `"boundary"`: 0 = start, 1 = end). What is
    /// not proved is [`Error::NoFeasiblePointFound`].
    #[error("{field}[{point}] cannot be satisfied")]
    InfeasibleConstraint {
        /// The field.
        field: &'static str,
        /// The data point (or end).
        point: usize,
    },
    /// An open curve's end condition and the tangent set of the data point at the same end
    /// constrain the same derivative Df at that vertex, and their sets are `gap` apart (proved
    /// before any solve): no curve meets both. `end` is 0 for the start, 1 for the end; `point`
    /// the data point (0 or n − 1).
    #[error("tangents[{point}] and the end condition at the {} constrain the same derivative, and their sets are {gap:.3e} apart", if *end == 0 { "start" } else { "end" })]
    EndConflict {
        /// 0 = start, 1 = end.
        end: usize,
        /// The data point at that end.
        point: usize,
        /// The distance between the two sets (a lower bound for half-space sets).
        gap: f64,
    },
    /// The exact solver found no point that meets every constraint, but nothing proves that
    /// there is none: its interior-point method stopped uncertified with the primal residual
    /// `violation` (relative) and `field[point]` the constraint it violated most (named as in
    /// [`Error::InfeasibleConstraint`]). [`Error::InfeasibleConstraint`] is kept for what is
    /// proved (an empty half-space set, a constraint contradicting fixed vertices): this guess
    /// was wrong on feasible problems (ROBUSTNESS.md §4, 18).
    #[error("no feasible point found in {iterations} iterations: {field}[{point}] is the most violated constraint where the solver stopped (relative violation {violation:.2e}); this is not a proof that the constraints contradict each other")]
    NoFeasiblePointFound {
        /// The field.
        field: &'static str,
        /// The data point (or end).
        point: usize,
        /// The relative primal residual where the method stopped.
        violation: f64,
        /// Iterations taken.
        iterations: usize,
    },
    /// The requested combination is not supported (names the field and what is missing).
    #[error("{field}: {reason}")]
    Unsupported {
        /// The field, e.g. `"solver"`.
        field: &'static str,
        /// What is not supported.
        reason: &'static str,
    },
    /// A vertex index is out of range (conic problems).
    #[error("{field} vertex {index} is out of range (N = {len})")]
    VertexOutOfRange {
        /// The field.
        field: &'static str,
        /// The index given.
        index: usize,
        /// The number of vertices.
        len: usize,
    },
    /// A value is NaN or infinite (conic problems).
    #[error("{field}[{index}] is not finite")]
    NonFiniteInput {
        /// The field.
        field: &'static str,
        /// The vertex or constraint index.
        index: usize,
    },
    /// A constraint is malformed (negative radius, zero normal, non-unit axis, bad stencil …).
    #[error("constraint {constraint}: {reason}")]
    InvalidConstraint {
        /// The constraint index.
        constraint: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// The constraints cannot be met, proved: an empty polytope, or a constraint contradicting
    /// fixed vertices.
    #[error("constraint {constraint} cannot be satisfied")]
    Infeasible {
        /// The constraint index.
        constraint: usize,
    },
    /// The interior-point method found no feasible point (it stopped uncertified with the
    /// relative primal residual `violation`); `constraint` is the most violated there. Not a
    /// proof of infeasibility: the method has no infeasibility certificate.
    #[error("no feasible point found in {iterations} iterations: constraint {constraint} is the most violated (relative violation {violation:.2e}); not a proof of infeasibility")]
    NoFeasiblePoint {
        /// The constraint index.
        constraint: usize,
        /// The relative primal residual where the method stopped.
        violation: f64,
        /// Iterations taken.
        iterations: usize,
    },
    /// The exact solver could not certify the fixed-knot solve after knot update `update`
    /// (1-based) of stage `stage` of Algorithm 4.1, the solve on the knots before that update
    /// having been certified: each update |p_{j+1} − p_j|^e makes the refined spans more unequal
    /// where the data are clustered or the curve nearly stops, and this one took them past what
    /// the method resolves to the acceptance level. `residual` is the best certificate reached on
    /// the updated knots (as [`Error::NotConverged`]).
    #[error("stage {stage}, knot update {update}: {solver} did not converge in {iterations} iterations (best residual {residual:.2e}); the solve before this update was certified")]
    NotConvergedAfterUpdate {
        /// The stage of Algorithm 4.1 (0 = part 1, l ≥ 1 = level l of part 2).
        stage: usize,
        /// The knot update (1 = the first) whose solve was not certified.
        update: usize,
        /// The solver (the strategy entry that came closest).
        solver: &'static str,
        /// Iterations taken.
        iterations: usize,
        /// The best residual reached.
        residual: f64,
    },
    /// The refined knots' spans are `ratio` times apart, beyond `limit` (see
    /// [`crate::MAX_CERTIFIED_SPAN_RATIO`]): where balls, half-spaces or derivative constraints
    /// leave vertices free to move, the certificate cannot tell such an answer from the optimum,
    /// so none is returned.
    #[error("the refined knots' spans are {ratio:.1e} times apart, beyond the {limit:.0e} up to which an answer with balls, half-spaces or derivative constraints can be certified (rows of the energy scale like 1/span³, so the forces on a cluster of very short spans hide under the rounding of its stiff rows)")]
    SpansTooUnequal {
        /// max span / min span of the result's knots.
        ratio: f64,
        /// [`crate::MAX_CERTIFIED_SPAN_RATIO`].
        limit: f64,
    },
    /// An iterative solver did not reach its tolerance within its iteration limit; `residual` is
    /// the best (relative KKT) residual it reached.
    #[error("{solver} did not converge in {iterations} iterations (best residual {residual:e})")]
    NotConverged {
        /// The solver.
        solver: &'static str,
        /// Iterations taken.
        iterations: usize,
        /// The best residual reached.
        residual: f64,
    },
}
