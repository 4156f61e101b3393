//! Exact solver for the fixed-knot convex refinement problems (conic constraints on banded stencils).
//!
//! # Problem
//!
//! For a curve p_0..p_{N−1} in R^d with the energy Hessian H (see [`energy::Hessian`]):
//!
//! minimize ½ pᵀ(H ⊗ I_d)p + ½ Σ_s w_s |p_{v_s} − q_s|²  (smoothing terms, Kersey (3.6))
//!
//! subject to fixed vertices p_v = a_v (interpolation, (3.2)) and constraints
//! L_c p := Σ_k c_k p_{v_k} ∈ K_c, where the stencil L_c spans at most three cyclically
//! consecutive vertices (the vertex itself, or a derivative rule Df) and K_c is a
//! [`ConvexSet`]: a ball (3.4), a polytope (3.7), a direction wedge (Fig. 3.5b) or a point.
//!
//! # Method
//!
//! Balls and wedges are second-order cones, half-spaces the nonnegative orthant, points and
//! zero-radius balls equalities. The problem is a convex QP with conic constraints, solved by a
//! primal–dual interior-point method (Mehrotra predictor–corrector with Nesterov–Todd scaling).
//! With the slack s_b = h_b + F_b L_c p ∈ K_b of every cone block b and duals z_b ∈ K_b, every
//! Newton system reduces to
//!
//! (H ⊗ I_d + W + Σ_b L_cᵀ F_bᵀ V_b⁻² F_b L_c) Δp = r,
//!
//! block-pentadiagonal (cyclic for closed curves), solved by [`energy::System`] in O(N): one
//! factorization per iteration, shared by predictor and corrector. Equalities on a single vertex
//! are eliminated ([`energy::System::fix`]); equalities on wider stencils are kept as a
//! quasi-definite block with regularization [`EQUALITY_REGULARIZATION`] and iterative refinement
//! against the unregularized system.
//!
//! # Certificate
//!
//! The result reports the relative KKT residual ([`Kkt`]) of the returned point p and the
//! returned forces z_c (projected onto the dual cones): with g = (H ⊗ I)p + W(p − q̃),
//! X the data scale (largest |coordinate| of the data, fixed values, centers + radii, offsets,
//! and of p) and P the largest diagonal entry of H + W,
//! - stationarity: ‖g + Σ_c L_cᵀ z_c‖∞ over free vertices / max(‖g‖∞, ‖Σ L_cᵀ z_c‖∞, P·X);
//! - primal: max_c dist(L_c p, K_c) / max(|L_c p|, scale of K_c) (0 when both vanish);
//! - complementarity: Σ_b |s_bᵀ z_b| / (max(‖g‖∞, ‖Σ L_cᵀ z_c‖∞, P·X) · X);
//! - total: the largest of the three. The solver stops when total ≤ [`ConicOptions::tolerance`]
//!   and fails with [`Error::NotConverged`] if it cannot reach [`CONIC_ACCEPT`].

// The cone algebra and block kernels index several small arrays by the same row/column.
#![allow(clippy::needless_range_loop)]

use crate::Error;
use divdiff::{Points, Topology};
use energy::{Factor, Hessian, System};

/// Default iteration limit of the interior-point method.
pub const CONIC_MAX_ITERATIONS: usize = 80;
/// Default target for the relative KKT residual (see the module docs).
pub const CONIC_TOLERANCE: f64 = 1e-12;
/// Largest relative KKT residual accepted as converged when the target cannot be reached
/// (e.g. stalled by rounding); above it the solver reports [`Error::NotConverged`].
pub const CONIC_ACCEPT: f64 = 1e-9;
/// A constraint is reported active when its slack (distance of L_c p to the boundary of K_c,
/// inside) is at most this times the constraint's scale (radius, |L_c p|, offsets).
pub const ACTIVE_RTOL: f64 = 1e-7;
/// Regularization δ of equality rows on wide stencils (rows of unit norm): δ is this times
/// min_v c_v²/K_vv over the row's stencil (c_v its coefficients, K_vv the local diagonal of the
/// Newton matrix without the penalty), so the penalty GᵀG/δ dominates the softest stencil
/// vertex by 1/this while pivots stay far above [`energy::PIVOT_RTOL`]; the penalty is removed
/// again by iterative refinement against the unregularized system.
pub const EQUALITY_REGULARIZATION: f64 = 1e-9;
/// Factor by which δ of the equality rows grows when the penalized Newton matrix fails to factor.
pub const EQUALITY_REGULARIZATION_RETRY: f64 = 1e3;
/// Attempts at factoring one Newton matrix with growing δ (δ up to
/// EQUALITY_REGULARIZATION × EQUALITY_REGULARIZATION_RETRY^(attempts − 1) = 1e-3).
pub const EQUALITY_REGULARIZATION_ATTEMPTS: i32 = 3;
/// Static regularization of a Newton matrix that fails to factor: every free vertex's diagonal
/// grows by this times its local diagonal (the matrix is positive definite by construction; the
/// failure is rounding on barrier terms that span many orders of magnitude).
pub const STATIC_REGULARIZATION: f64 = 1e-12;
/// Growth of the static regularization per further attempt.
pub const STATIC_REGULARIZATION_RETRY: f64 = 1e3;
/// Attempts with a static regularization (1e-12, 1e-9 relative).
pub const STATIC_REGULARIZATION_ATTEMPTS: i32 = 2;
/// Relative pivot tolerance of the interior-point and polish Newton systems (positive definite by
/// construction, with barrier terms that grow without bound on active rows, so pivots far below
/// [`energy::PIVOT_RTOL`] relative to their diagonal are legitimate there).
pub const IPM_PIVOT_RTOL: f64 = 1e-22;
/// Fraction of the step to the boundary of the cones taken by the interior-point method.
pub const STEP_FRACTION: f64 = 0.99;

/// A convex set in R^d that L_c p must lie in.
#[derive(Clone, Debug, PartialEq)]
pub enum ConvexSet {
    /// The closed ball |x − center| ≤ radius (radius ≥ 0; radius 0 is an equality).
    Ball {
        /// The center.
        center: Vec<f64>,
        /// The radius, ≥ 0.
        radius: f64,
    },
    /// The polytope ∩_i {x : normal_i · x ≤ offset_i} (normals nonzero).
    HalfSpaces(Vec<(Vec<f64>, f64)>),
    /// The direction wedge {v : v · axis ≥ |v| cos(half_angle)} (axis a unit vector,
    /// half_angle ∈ [0, π/2)); only the direction of v is constrained.
    Cone {
        /// The axis (unit vector).
        axis: Vec<f64>,
        /// The half opening angle in radians, in [0, π/2).
        half_angle: f64,
    },
    /// The single point x = value (an equality, e.g. a clamped end derivative).
    Point(Vec<f64>),
}

/// A constraint L p ∈ K on a stencil L = Σ_k c_k e_{v_k}ᵀ.
#[derive(Clone, Debug, PartialEq)]
pub struct ConicConstraint {
    /// The stencil [(v_k, c_k)]: at most three vertices within two steps of each other
    /// (cyclically for closed curves).
    pub stencil: Vec<(usize, f64)>,
    /// The set.
    pub set: ConvexSet,
}

/// Options of [`ConicProblem::solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct ConicOptions {
    /// Iteration limit (default [`CONIC_MAX_ITERATIONS`]).
    pub max_iterations: usize,
    /// Target relative KKT residual (default [`CONIC_TOLERANCE`]).
    pub tolerance: f64,
    /// Optional starting curve (e.g. the previous solution in Algorithm 4.1's alternation).
    pub warm_start: Option<Points>,
}

impl Default for ConicOptions {
    fn default() -> Self {
        ConicOptions {
            max_iterations: CONIC_MAX_ITERATIONS,
            tolerance: CONIC_TOLERANCE,
            warm_start: None,
        }
    }
}

/// The relative KKT residual of a solution (definitions in the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Kkt {
    /// Relative stationarity residual.
    pub stationarity: f64,
    /// Relative primal infeasibility.
    pub primal: f64,
    /// Relative complementarity.
    pub complementarity: f64,
    /// The largest of the three.
    pub total: f64,
}

/// The optimum of a [`ConicProblem`] with its certificate.
#[derive(Clone, Debug, PartialEq)]
pub struct ConicSolution {
    /// The optimal curve.
    pub points: Points,
    /// Per constraint: the force z_c ∈ R^d with (H⊗I)p + W(p − q̃) + Σ_c L_cᵀ z_c = 0 at the free
    /// vertices (for constraints that fix a vertex: the reaction force there).
    pub forces: Vec<Vec<f64>>,
    /// Per constraint: for a ball of positive radius the scalar w_c ≥ 0 with
    /// z_c = w_c (L_c p − center) (Kersey (3.5)); `None` otherwise.
    pub ball_weights: Vec<Option<f64>>,
    /// Per constraint: the dual of its cone blocks (ball / wedge: the second-order-cone dual;
    /// half-spaces: one multiplier ≥ 0 per half-space, for the unit normal).
    pub cone_duals: Vec<Vec<f64>>,
    /// Per constraint: whether it is active (slack ≤ [`ACTIVE_RTOL`] × scale; points always).
    pub active: Vec<bool>,
    /// E = ½ pᵀ(H⊗I)p.
    pub energy: f64,
    /// E plus the smoothing terms.
    pub objective: f64,
    /// The relative KKT residual.
    pub kkt: Kkt,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Whether the active-set polish produced this result. Then z_c = w_c (L_c p − center)
    /// holds exactly for balls; otherwise the forces are the interior-point duals (projected
    /// onto the dual cones), which satisfy it only up to O(√gap).
    pub polished: bool,
}

#[derive(Clone, Debug)]
struct Smoothing {
    vertex: usize,
    weight: f64,
    target: Vec<f64>,
}

/// A fixed-knot convex refinement problem (see the module docs).
#[derive(Clone, Debug)]
pub struct ConicProblem {
    topology: Topology,
    dim: usize,
    diag: Vec<f64>,
    off1: Vec<f64>,
    off2: Vec<f64>,
    fixed: Vec<Option<Vec<f64>>>,
    smoothing: Vec<Smoothing>,
    constraints: Vec<ConicConstraint>,
}

#[inline]
fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl ConicProblem {
    /// A problem on the energy Hessian `h` in R^dim, with no constraints yet.
    ///
    /// # Errors
    /// [`Error::Energy`] for `dim` = 0 or a closed curve with fewer than 3 vertices.
    pub fn new(h: &Hessian, dim: usize) -> Result<Self, Error> {
        let (d, o1, o2) = h.bands();
        Self::from_bands(h.topology(), d.to_vec(), o1.to_vec(), o2.to_vec(), dim)
    }

    /// A problem from the three bands of H (convention of [`energy::System::from_bands`]).
    ///
    /// # Errors
    /// As [`energy::System::from_bands`].
    pub fn from_bands(
        topology: Topology,
        diag: Vec<f64>,
        off1: Vec<f64>,
        off2: Vec<f64>,
        dim: usize,
    ) -> Result<Self, Error> {
        // Validate through System (same conventions).
        let s = System::from_bands(topology, diag.clone(), off1.clone(), off2.clone(), dim)?;
        let n = s.len();
        Ok(ConicProblem {
            topology,
            dim,
            diag,
            off1,
            off2,
            fixed: vec![None; n],
            smoothing: Vec::new(),
            constraints: Vec::new(),
        })
    }

    /// Number of vertices N.
    pub fn len(&self) -> usize {
        self.diag.len()
    }

    /// Whether there are no vertices (never for a constructed problem).
    pub fn is_empty(&self) -> bool {
        self.diag.is_empty()
    }

    /// The dimension d.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The constraints added so far, in index order.
    pub fn constraints(&self) -> &[ConicConstraint] {
        &self.constraints
    }

    fn check_vertex(&self, field: &'static str, v: usize) -> Result<(), Error> {
        if v >= self.len() {
            return Err(Error::VertexOutOfRange {
                field,
                index: v,
                len: self.len(),
            });
        }
        Ok(())
    }

    fn check_vec(&self, field: &'static str, index: usize, v: &[f64]) -> Result<(), Error> {
        if v.len() != self.dim {
            return Err(Error::WrongDimension {
                field,
                index,
                expected: self.dim,
                got: v.len(),
            });
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(Error::NonFiniteInput { field, index });
        }
        Ok(())
    }

    /// Prescribes p_vertex = value (interpolation).
    ///
    /// # Errors
    /// [`Error::VertexOutOfRange`], [`Error::WrongDimension`], [`Error::NonFiniteInput`].
    pub fn fix(&mut self, vertex: usize, value: &[f64]) -> Result<(), Error> {
        self.check_vertex("fixed", vertex)?;
        self.check_vec("fixed", vertex, value)?;
        self.fixed[vertex] = Some(value.to_vec());
        Ok(())
    }

    /// Adds the smoothing term ½ weight |p_vertex − target|² (weight ≥ 0).
    ///
    /// # Errors
    /// [`Error::VertexOutOfRange`], [`Error::WrongDimension`], [`Error::NonFiniteInput`], and
    /// [`Error::InvalidConstraint`] for a negative or non-finite weight.
    pub fn add_smoothing(
        &mut self,
        vertex: usize,
        weight: f64,
        target: &[f64],
    ) -> Result<(), Error> {
        self.check_vertex("smoothing", vertex)?;
        self.check_vec("smoothing", vertex, target)?;
        if !(weight.is_finite() && weight >= 0.0) {
            return Err(Error::InvalidConstraint {
                constraint: vertex,
                reason: "smoothing weight must be finite and ≥ 0",
            });
        }
        self.smoothing.push(Smoothing {
            vertex,
            weight,
            target: target.to_vec(),
        });
        Ok(())
    }

    /// Adds the constraint L p ∈ `set` on `stencil` and returns its index.
    ///
    /// # Errors
    /// [`Error::VertexOutOfRange`] for a stencil vertex ≥ N, [`Error::InvalidConstraint`] (naming the
    /// index the constraint would get) for an empty or too wide stencil, a negative radius, a
    /// zero normal, a non-unit axis or an angle outside [0, π/2), [`Error::WrongDimension`] /
    /// [`Error::NonFiniteInput`] for vectors of the wrong size or non-finite entries.
    pub fn add_constraint(
        &mut self,
        stencil: &[(usize, f64)],
        set: ConvexSet,
    ) -> Result<usize, Error> {
        let index = self.constraints.len();
        let invalid = |reason| Error::InvalidConstraint {
            constraint: index,
            reason,
        };
        if stencil.is_empty() || stencil.len() > 3 {
            return Err(invalid("a stencil has 1 to 3 vertices"));
        }
        let n = self.len();
        for &(v, c) in stencil {
            self.check_vertex("stencil", v)?;
            if !c.is_finite() {
                return Err(Error::NonFiniteInput {
                    field: "stencil",
                    index,
                });
            }
        }
        for &(a, _) in stencil {
            for &(b, _) in stencil {
                let gap = a.abs_diff(b);
                let gap = if self.topology == Topology::Closed {
                    gap.min(n - gap)
                } else {
                    gap
                };
                if gap > 2 {
                    return Err(invalid("stencil vertices must lie within two steps"));
                }
            }
        }
        if stencil.iter().all(|&(_, c)| c == 0.0) {
            return Err(invalid("stencil coefficients are all zero"));
        }
        match &set {
            ConvexSet::Ball { center, radius } => {
                self.check_vec("center", index, center)?;
                if !(radius.is_finite() && *radius >= 0.0) {
                    return Err(invalid("radius must be finite and ≥ 0"));
                }
            }
            ConvexSet::HalfSpaces(hs) => {
                if hs.is_empty() {
                    return Err(invalid("no half-spaces"));
                }
                for (nrm, off) in hs {
                    self.check_vec("normal", index, nrm)?;
                    if !off.is_finite() {
                        return Err(Error::NonFiniteInput {
                            field: "offset",
                            index,
                        });
                    }
                    if norm(nrm) == 0.0 {
                        return Err(invalid("zero normal"));
                    }
                }
            }
            ConvexSet::Cone { axis, half_angle } => {
                self.check_vec("axis", index, axis)?;
                if (norm(axis) - 1.0).abs() > 1e-9 {
                    return Err(invalid("axis must be a unit vector"));
                }
                if !(*half_angle >= 0.0 && *half_angle < std::f64::consts::FRAC_PI_2) {
                    return Err(invalid("half_angle must lie in [0, π/2)"));
                }
            }
            ConvexSet::Point(v) => self.check_vec("point", index, v)?,
        }
        self.constraints.push(ConicConstraint {
            stencil: stencil.to_vec(),
            set,
        });
        Ok(index)
    }

    /// Solves the problem to the exact optimum (see the module docs).
    ///
    /// # Errors
    /// [`Error::Infeasible`] naming a constraint that cannot be met (an empty polytope, a
    /// constraint contradicting fixed vertices, or the constraint with the largest violation
    /// when the interior-point method finds no feasible point), [`Error::NotConverged`],
    /// [`Error::Energy`] when the Newton matrix is singular (the data do not determine the
    /// curve, e.g. an open curve with less than two constrained vertices),
    /// [`Error::WrongDimension`] for a warm start of the wrong shape.
    pub fn solve(&self, opts: &ConicOptions) -> Result<ConicSolution, Error> {
        let prep = Prepared::new(self)?;
        match prep.ipm(self, opts) {
            Ok(sol) => Ok(sol),
            Err(Failure::Error(e)) => Err(e),
            Err(Failure::Stalled {
                iterations,
                best,
                primal,
                worst,
            }) => {
                // Diagnose: an empty polytope is named; otherwise a large primal residual
                // names the most violated constraint.
                for (c, con) in self.constraints.iter().enumerate() {
                    if let ConvexSet::HalfSpaces(hs) = &con.set {
                        if polytope_is_empty(hs, self.dim) {
                            return Err(Error::Infeasible { constraint: c });
                        }
                    }
                }
                if primal > 1e-6 {
                    if let Some(c) = worst {
                        return Err(Error::Infeasible { constraint: c });
                    }
                }
                Err(Error::NotConverged {
                    solver: "conic interior-point method",
                    iterations,
                    residual: best,
                })
            }
        }
    }
}

/// Is {x : n_i·x ≤ o_i} empty? Decided by the interior-point method itself on the one-vertex
/// problem min ½|x|² s.t. the half-spaces: it converges iff the polytope is nonempty.
fn polytope_is_empty(hs: &[(Vec<f64>, f64)], d: usize) -> bool {
    let Ok(mut p) = ConicProblem::from_bands(Topology::Open, vec![0.0], vec![0.0], vec![0.0], d)
    else {
        return false;
    };
    if p.add_smoothing(0, 1.0, &vec![0.0; d]).is_err()
        || p.add_constraint(&[(0, 1.0)], ConvexSet::HalfSpaces(hs.to_vec()))
            .is_err()
    {
        return false;
    }
    let Ok(prep) = Prepared::new(&p) else {
        return true;
    };
    prep.ipm(&p, &ConicOptions::default()).is_err()
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Zero,
    Nonneg,
    Soc,
}

/// One cone block: s = h + F (L x) ∈ K, L over free vertices only.
#[derive(Clone, Debug)]
struct Block {
    constraint: usize,
    kind: Kind,
    /// A ball (FᵀJF = −I): the only second-order cone the polish linearizes.
    ball: bool,
    m: usize,
    stencil: Vec<(usize, f64)>,
    /// m × d, row-major.
    f: Vec<f64>,
    h: Vec<f64>,
    off: usize,
}

enum Failure {
    Error(Error),
    Stalled {
        iterations: usize,
        best: f64,
        primal: f64,
        worst: Option<usize>,
    },
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure::Error(e)
    }
}

impl From<energy::Error> for Failure {
    fn from(e: energy::Error) -> Self {
        Failure::Error(Error::Energy(e))
    }
}

/// The problem with fixed vertices eliminated and the constraints turned into cone blocks.
struct Prepared {
    n: usize,
    d: usize,
    /// Fixed value per vertex.
    fixed: Vec<Option<Vec<f64>>>,
    /// The constraint that fixed a vertex (for its reaction force): (constraint, coefficient).
    owner: Vec<Option<(usize, f64)>>,
    /// H + smoothing weights, with fixed vertices marked.
    base: System,
    /// H + smoothing weights, nothing fixed (gradient of the certificate).
    full: System,
    /// H alone (energy of the certificate).
    hess: System,
    /// Linear term c (N·d), zero at fixed vertices.
    c: Vec<f64>,
    blocks: Vec<Block>,
    total_m: usize,
    /// Degree ν (orthant components + one per second-order cone).
    degree: f64,
    /// Data scale X.
    scale_x: f64,
    /// Largest diagonal entry of H + W over free vertices.
    scale_p: f64,
    /// Diagonal of H + W per vertex (local scale for the equality regularization).
    pdiag: Vec<f64>,
}

/// Householder basis of the orthogonal complement of the unit vector `a`: d − 1 rows.
fn complement_basis(a: &[f64]) -> Vec<Vec<f64>> {
    let d = a.len();
    // Reflection Q = I − 2uuᵀ/|u|² with Q a = ±e_k; rows of Q other than k span a⊥.
    let k = (0..d)
        .max_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
        .unwrap_or(0);
    let mut u = a.to_vec();
    let sgn = if a[k] >= 0.0 { 1.0 } else { -1.0 };
    u[k] += sgn;
    let uu = dot(&u, &u);
    (0..d)
        .filter(|&r| r != k)
        .map(|r| {
            (0..d)
                .map(|c| f64::from(u8::from(r == c)) - 2.0 * u[r] * u[c] / uu)
                .collect()
        })
        .collect()
}

impl Prepared {
    fn new(p: &ConicProblem) -> Result<Self, Error> {
        let (n, d) = (p.len(), p.dim);
        let mut fixed = p.fixed.clone();
        let mut owner: Vec<Option<(usize, f64)>> = vec![None; n];
        let mut scale_x: f64 = 0.0;
        for v in fixed.iter().flatten() {
            scale_x = scale_x.max(inf_norm(v));
        }
        for s in &p.smoothing {
            scale_x = scale_x.max(inf_norm(&s.target));
        }
        // Single-vertex equalities become fixed vertices.
        for (ci, con) in p.constraints.iter().enumerate() {
            let value = match &con.set {
                ConvexSet::Point(v) => Some(v),
                ConvexSet::Ball { center, radius } if *radius == 0.0 => Some(center),
                _ => None,
            };
            match &con.set {
                ConvexSet::Ball { center, radius } => {
                    scale_x = scale_x.max(inf_norm(center) + radius);
                }
                ConvexSet::Point(v) => scale_x = scale_x.max(inf_norm(v)),
                ConvexSet::HalfSpaces(hs) => {
                    for (nr, o) in hs {
                        scale_x = scale_x.max(o.abs() / norm(nr));
                    }
                }
                ConvexSet::Cone { .. } => {}
            }
            let merged = merge_stencil(&con.stencil);
            if let (Some(v), [(vert, coef)]) = (value, merged.as_slice()) {
                if *coef == 0.0 {
                    continue;
                }
                let target: Vec<f64> = v.iter().map(|x| x / coef).collect();
                match &fixed[*vert] {
                    Some(old) => {
                        let gap = norm(
                            &old.iter()
                                .zip(&target)
                                .map(|(a, b)| a - b)
                                .collect::<Vec<_>>(),
                        );
                        if gap > 1e-12 * (1.0 + inf_norm(old).max(inf_norm(&target))) {
                            return Err(Error::Infeasible { constraint: ci });
                        }
                    }
                    None => {
                        fixed[*vert] = Some(target);
                        owner[*vert] = Some((ci, *coef));
                    }
                }
            }
        }
        let mut base = System::from_bands(
            p.topology,
            p.diag.clone(),
            p.off1.clone(),
            p.off2.clone(),
            d,
        )?;
        let hess = base.clone();
        let mut c = vec![0.0; n * d];
        for s in &p.smoothing {
            base.add_weight(s.vertex, s.weight)?;
            for k in 0..d {
                c[s.vertex * d + k] -= s.weight * s.target[k];
            }
        }
        let full = base.clone();
        for (v, f) in fixed.iter().enumerate() {
            if f.is_some() {
                base.fix(v)?;
                for k in 0..d {
                    c[v * d + k] = 0.0;
                }
            }
        }
        let mut blocks = Vec::new();
        let mut off = 0;
        let mut degree = 0.0;
        for (ci, con) in p.constraints.iter().enumerate() {
            let merged = merge_stencil(&con.stencil);
            if let [(v, _)] = merged.as_slice() {
                if owner[*v].is_some_and(|(o, _)| o == ci) {
                    continue;
                }
            }
            // Split the stencil into free vertices and the fixed contribution.
            let mut yfix = vec![0.0; d];
            let mut free = Vec::new();
            for &(v, coef) in &merged {
                match &fixed[v] {
                    Some(val) => {
                        for k in 0..d {
                            yfix[k] += coef * val[k];
                        }
                    }
                    None => free.push((v, coef)),
                }
            }
            // Rows (F, g) of each block: s = g + F y, y = L p.
            let mut rows: Vec<(Kind, Vec<Vec<f64>>, Vec<f64>)> = Vec::new();
            match &con.set {
                ConvexSet::Ball { center, radius } if *radius > 0.0 => {
                    let mut f = vec![vec![0.0; d]];
                    let mut g = vec![*radius];
                    for k in 0..d {
                        let mut r = vec![0.0; d];
                        r[k] = 1.0;
                        f.push(r);
                        g.push(-center[k]);
                    }
                    rows.push((Kind::Soc, f, g));
                }
                ConvexSet::Ball { center: v, .. } | ConvexSet::Point(v) => {
                    let f = (0..d)
                        .map(|k| {
                            let mut r = vec![0.0; d];
                            r[k] = 1.0;
                            r
                        })
                        .collect();
                    rows.push((Kind::Zero, f, v.iter().map(|x| -x).collect()));
                }
                ConvexSet::HalfSpaces(hs) => {
                    let f = hs
                        .iter()
                        .map(|(nr, _)| {
                            let l = norm(nr);
                            nr.iter().map(|x| -x / l).collect()
                        })
                        .collect();
                    let g = hs.iter().map(|(nr, o)| o / norm(nr)).collect();
                    rows.push((Kind::Nonneg, f, g));
                }
                ConvexSet::Cone { axis, half_angle } => {
                    if d == 1 {
                        rows.push((Kind::Nonneg, vec![axis.clone()], vec![0.0]));
                    } else if *half_angle == 0.0 {
                        rows.push((Kind::Zero, complement_basis(axis), vec![0.0; d - 1]));
                        rows.push((Kind::Nonneg, vec![axis.clone()], vec![0.0]));
                    } else {
                        let ct = half_angle.cos();
                        let mut f = vec![axis.iter().map(|x| x / ct).collect::<Vec<_>>()];
                        for k in 0..d {
                            let mut r = vec![0.0; d];
                            r[k] = 1.0;
                            f.push(r);
                        }
                        rows.push((Kind::Soc, f, vec![0.0; d + 1]));
                    }
                }
            }
            for (kind, f, g) in rows {
                let m = f.len();
                let h: Vec<f64> = (0..m).map(|r| g[r] + dot(&f[r], &yfix)).collect();
                if free.is_empty() {
                    // A constant: check it.
                    let ok = match kind {
                        Kind::Zero => inf_norm(&h) <= 1e-12 * (1.0 + scale_x),
                        Kind::Nonneg => h.iter().all(|&x| x >= -1e-12 * (1.0 + scale_x)),
                        Kind::Soc => h[0] >= norm(&h[1..]) - 1e-12 * (1.0 + scale_x),
                    };
                    if !ok {
                        return Err(Error::Infeasible { constraint: ci });
                    }
                    continue;
                }
                degree += match kind {
                    Kind::Zero => 0.0,
                    Kind::Nonneg => m as f64,
                    Kind::Soc => 1.0,
                };
                blocks.push(Block {
                    constraint: ci,
                    kind,
                    ball: kind == Kind::Soc && matches!(con.set, ConvexSet::Ball { .. }),
                    m,
                    stencil: free.clone(),
                    f: f.concat(),
                    h,
                    off,
                });
                off += m;
            }
        }
        // Smoothing weight per vertex, summed in the order of the terms (one pass, O(N + terms)).
        let mut wsum = vec![0.0; n];
        for sm in &p.smoothing {
            wsum[sm.vertex] += sm.weight;
        }
        let pdiag: Vec<f64> = (0..n).map(|v| p.diag[v] + wsum[v]).collect();
        let scale_p = (0..n)
            .filter(|&v| fixed[v].is_none())
            .map(|v| pdiag[v])
            .fold(0.0, f64::max);
        Ok(Prepared {
            n,
            d,
            fixed,
            owner,
            base,
            full,
            hess,
            c,
            blocks,
            total_m: off,
            degree,
            scale_x,
            scale_p,
            pdiag,
        })
    }
}

/// Merges repeated vertices of a stencil (possible on tiny closed curves) and drops zeros.
fn merge_stencil(st: &[(usize, f64)]) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = Vec::new();
    for &(v, c) in st {
        if let Some(e) = out.iter_mut().find(|e| e.0 == v) {
            e.1 += c;
        } else {
            out.push((v, c));
        }
    }
    out.retain(|e| e.1 != 0.0);
    out
}

// ---------------------------------------------------------------------------------------------
// Cone algebra (per block). Scaling convention: V z = V⁻¹ s = λ.

/// NT scaling of one block: orthant: v_i = sqrt(s_i / z_i); SOC: [η, w̄...].
#[inline]
pub(crate) fn scaling(kind: Kind, s: &[f64], z: &[f64], out: &mut Vec<f64>) {
    out.clear();
    match kind {
        Kind::Zero => {}
        Kind::Nonneg => out.extend(s.iter().zip(z).map(|(a, b)| (a / b).sqrt())),
        Kind::Soc => {
            let js = soc_j(s).max(f64::MIN_POSITIVE);
            let jz = soc_j(z).max(f64::MIN_POSITIVE);
            let (rs, rz) = (js.sqrt(), jz.sqrt());
            // s̄ = s/√J(s), z̄ = z/√J(z), formed entry by entry (no allocation per block).
            let sbzb: f64 = s.iter().zip(z).map(|(a, b)| (a / rs) * (b / rz)).sum();
            let gamma = ((1.0 + sbzb) / 2.0).max(0.0).sqrt();
            let eta = (js / jz).sqrt().sqrt();
            out.push(eta);
            out.push((s[0] / rs + z[0] / rz) / (2.0 * gamma));
            for k in 1..s.len() {
                out.push((s[k] / rs - z[k] / rz) / (2.0 * gamma));
            }
        }
    }
}

#[inline]
pub(crate) fn soc_j(u: &[f64]) -> f64 {
    let r = norm(&u[1..]);
    (u[0] - r) * (u[0] + r)
}

/// u ← V u (inverse = false) or V⁻¹ u (inverse = true).
#[inline]
pub(crate) fn apply_v(kind: Kind, sc: &[f64], u: &mut [f64], inverse: bool) {
    match kind {
        Kind::Zero => {}
        Kind::Nonneg => {
            for (x, v) in u.iter_mut().zip(sc) {
                if inverse {
                    *x /= v;
                } else {
                    *x *= v;
                }
            }
        }
        Kind::Soc => {
            let eta = sc[0];
            let w0 = sc[1];
            let w1 = &sc[2..];
            let sg = if inverse { -1.0 } else { 1.0 };
            let u0 = u[0];
            let wu = dot(w1, &u[1..]);
            let new0 = w0 * u0 + sg * wu;
            let coef = sg * u0 + wu / (1.0 + w0);
            for (x, w) in u[1..].iter_mut().zip(w1) {
                *x += coef * w;
            }
            u[0] = new0;
            let f = if inverse { 1.0 / eta } else { eta };
            for x in u.iter_mut() {
                *x *= f;
            }
        }
    }
}

/// Jordan product u ∘ v.
#[inline]
pub(crate) fn jordan(kind: Kind, u: &[f64], v: &[f64], out: &mut [f64]) {
    match kind {
        Kind::Zero => out.fill(0.0),
        Kind::Nonneg => {
            for ((o, a), b) in out.iter_mut().zip(u).zip(v) {
                *o = a * b;
            }
        }
        Kind::Soc => {
            out[0] = dot(u, v);
            for k in 1..u.len() {
                out[k] = u[0] * v[k] + v[0] * u[k];
            }
        }
    }
}

/// x with λ ∘ x = r.
#[inline]
pub(crate) fn jordan_div(kind: Kind, lam: &[f64], r: &[f64], out: &mut [f64]) {
    match kind {
        Kind::Zero => out.fill(0.0),
        Kind::Nonneg => {
            for ((o, a), b) in out.iter_mut().zip(lam).zip(r) {
                *o = b / a;
            }
        }
        Kind::Soc => {
            let jl = soc_j(lam);
            let x0 = (lam[0] * r[0] - dot(&lam[1..], &r[1..])) / jl;
            out[0] = x0;
            for k in 1..lam.len() {
                out[k] = (r[k] - x0 * lam[k]) / lam[0];
            }
        }
    }
}

/// Largest α ≥ 0 (capped at `cap`) with u + α du in the cone.
#[inline]
pub(crate) fn max_step(kind: Kind, u: &[f64], du: &[f64], cap: f64) -> f64 {
    match kind {
        Kind::Zero => cap,
        Kind::Nonneg => u
            .iter()
            .zip(du)
            .fold(cap, |a, (x, dx)| if *dx < 0.0 { a.min(-x / dx) } else { a }),
        Kind::Soc => {
            // q(α) = J(u + α du) = a α² + b α + c, c = J(u) > 0; first positive root.
            let a = soc_j(du);
            let b = 2.0 * (u[0] * du[0] - dot(&u[1..], &du[1..]));
            let c = soc_j(u);
            let mut best = cap;
            let disc = b * b - 4.0 * a * c;
            if a.abs() <= f64::EPSILON * (b.abs() + c.abs()) {
                if b < 0.0 {
                    best = best.min(-c / b);
                }
            } else if disc >= 0.0 {
                let q = -0.5 * (b + b.signum() * disc.sqrt());
                for r in [q / a, if q != 0.0 { c / q } else { f64::INFINITY }] {
                    if r > 0.0 {
                        best = best.min(r);
                    }
                }
            }
            // Also keep u0 + α du0 ≥ 0 (same component of the cone).
            if du[0] < 0.0 {
                best = best.min(-u[0] / du[0]);
            }
            best.max(0.0)
        }
    }
}

/// Projection onto the (self-dual) cone.
fn project(kind: Kind, u: &mut [f64]) {
    match kind {
        Kind::Zero => {}
        Kind::Nonneg => {
            for x in u.iter_mut() {
                *x = x.max(0.0);
            }
        }
        Kind::Soc => {
            let r = norm(&u[1..]);
            if r <= u[0] {
                return;
            }
            if r <= -u[0] {
                u.fill(0.0);
                return;
            }
            let t = 0.5 * (u[0] + r);
            u[0] = t;
            for x in u[1..].iter_mut() {
                *x *= t / r;
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The interior-point method.

/// Working state of one IPM run.
struct State {
    x: Vec<f64>,
    s: Vec<f64>,
    z: Vec<f64>,
}

impl Prepared {
    /// y = L x for a block's stencil.
    fn stencil_apply(&self, b: &Block, x: &[f64], y: &mut [f64]) {
        let d = self.d;
        y.fill(0.0);
        for &(v, c) in &b.stencil {
            for k in 0..d {
                y[k] += c * x[v * d + k];
            }
        }
    }

    /// out[v] += Lᵀ (Fᵀ w) for a block (w has m entries).
    fn add_adjoint(&self, b: &Block, w: &[f64], out: &mut [f64]) {
        let d = self.d;
        let mut ft = [0.0; 16];
        let mut ftv = Vec::new();
        let ftw: &mut [f64] = if d <= 16 {
            &mut ft[..d]
        } else {
            ftv.resize(d, 0.0);
            &mut ftv
        };
        ftw.fill(0.0);
        for r in 0..b.m {
            for k in 0..d {
                ftw[k] += b.f[r * d + k] * w[r];
            }
        }
        for &(v, c) in &b.stencil {
            for k in 0..d {
                out[v * d + k] += c * ftw[k];
            }
        }
    }

    /// F (L x) for a block.
    fn block_map(&self, b: &Block, x: &[f64], out: &mut [f64]) {
        let d = self.d;
        let mut stack = [0.0; 16];
        let mut heap = Vec::new();
        let y: &mut [f64] = if d <= 16 {
            &mut stack[..d]
        } else {
            heap.resize(d, 0.0);
            &mut heap
        };
        self.stencil_apply(b, x, y);
        for r in 0..b.m {
            out[r] = dot(&b.f[r * d..(r + 1) * d], y);
        }
    }

    /// (H ⊗ I + W) x at free vertices (x zero at fixed vertices is not assumed).
    fn apply_p(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        self.apply_p_into(x, &mut y);
        y
    }

    /// [`apply_p`](Self::apply_p) into `y` (length N·d; zero if the sizes do not match).
    fn apply_p_into(&self, x: &[f64], y: &mut [f64]) {
        if self.base.apply_flat(x, y).is_err() {
            y.fill(0.0);
        }
    }

    fn is_free(&self, v: usize) -> bool {
        self.fixed[v].is_none()
    }

    fn initial_x(&self, warm: Option<&Points>) -> Result<Vec<f64>, Failure> {
        let (n, d) = (self.n, self.d);
        let mut x = vec![0.0; n * d];
        for (v, f) in self.fixed.iter().enumerate() {
            if let Some(val) = f {
                x[v * d..(v + 1) * d].copy_from_slice(val);
            }
        }
        if let Some(w) = warm {
            if w.len() != n || w.dim() != d {
                return Err(Failure::Error(Error::WrongDimension {
                    field: "warm_start",
                    index: 0,
                    expected: n * d,
                    got: w.len() * w.dim(),
                }));
            }
            for v in 0..n {
                if self.is_free(v) {
                    x[v * d..(v + 1) * d].copy_from_slice(w.point(v));
                }
            }
            return Ok(x);
        }
        // min ½xᵀPx + cᵀx + (ω/2) Σ |h + F L x|²: (P + ω Σ LᵀFᵀFL) x = −c − ω Σ LᵀFᵀh.
        let omega = if self.scale_p > 0.0 {
            self.scale_p
        } else {
            1.0
        };
        let mut sys = self.base.clone();
        let mut rhs = x.clone();
        for v in 0..n {
            if self.is_free(v) {
                for k in 0..d {
                    rhs[v * d + k] = -self.c[v * d + k];
                }
            }
        }
        let mut theta = vec![0.0; d * d];
        for b in &self.blocks {
            theta.fill(0.0);
            for r in 0..b.m {
                for i in 0..d {
                    for j in 0..d {
                        theta[i * d + j] += omega * b.f[r * d + i] * b.f[r * d + j];
                    }
                }
            }
            sys.add_stencil(&b.stencil, &theta)?;
            let w: Vec<f64> = b.h.iter().map(|h| -omega * h).collect();
            self.add_adjoint(b, &w, &mut rhs);
        }
        // Positive definite by construction, so the interior-point pivot tolerance applies; the
        // starting point is only a heuristic, so a system that still fails to factor (rounding
        // on a nearly singular P, ROBUSTNESS.md finding 4) falls back to the plain start.
        match sys.factor_with_tolerance(IPM_PIVOT_RTOL) {
            Ok(f) => {
                f.solve_flat(&mut rhs)?;
                Ok(rhs)
            }
            Err(_) => Ok(x),
        }
    }

    fn ipm(&self, problem: &ConicProblem, opts: &ConicOptions) -> Result<ConicSolution, Failure> {
        let (n, d) = (self.n, self.d);
        let tm = self.total_m;
        let x = self.initial_x(opts.warm_start.as_ref())?;
        let mut st = State {
            x,
            s: vec![0.0; tm],
            z: vec![0.0; tm],
        };
        let omega = if self.scale_p > 0.0 {
            self.scale_p
        } else {
            1.0
        };
        // Slacks from x, shifted into the interior; z = μ_b s⁻¹ with Θ ≈ ω.
        {
            let mut fx = vec![0.0; 16];
            for b in &self.blocks {
                fx.resize(b.m, 0.0);
                self.block_map(b, &st.x, &mut fx);
                let s = &mut st.s[b.off..b.off + b.m];
                for r in 0..b.m {
                    s[r] = b.h[r] + fx[r];
                }
                let sz = norm(s).max(self.scale_x * 1e-3).max(f64::MIN_POSITIVE);
                match b.kind {
                    Kind::Zero => {
                        s.fill(0.0);
                        continue;
                    }
                    Kind::Nonneg => {
                        let lo = s.iter().fold(f64::INFINITY, |a, &v| a.min(v));
                        let shift = (-lo).max(0.0) + 0.1 * sz;
                        for v in s.iter_mut() {
                            *v += shift;
                        }
                    }
                    Kind::Soc => {
                        let gap = norm(&s[1..]) - s[0];
                        s[0] += gap.max(0.0) + 0.1 * sz;
                    }
                }
                let mu = omega * norm(s).powi(2);
                let z = &mut st.z[b.off..b.off + b.m];
                match b.kind {
                    Kind::Zero => {}
                    Kind::Nonneg => {
                        for (zv, sv) in z.iter_mut().zip(s.iter()) {
                            *zv = mu / sv;
                        }
                    }
                    Kind::Soc => {
                        let js = soc_j(s);
                        z[0] = mu * s[0] / js;
                        for k in 1..b.m {
                            z[k] = -mu * s[k] / js;
                        }
                    }
                }
            }
        }

        let mut best = f64::INFINITY;
        let mut best_primal = f64::INFINITY;
        let mut sc: Vec<Vec<f64>> = vec![Vec::new(); self.blocks.len()];
        let mut lam = vec![0.0; tm];
        let mut iterations = 0;
        let mut tmp = vec![0.0; 16];
        let mut tmp2 = vec![0.0; 16];
        let mut wbuf = vec![0.0; 16];
        let mut best_state: Option<(f64, State)> = None;
        let mut polish_tried = false;
        let mut rx = vec![0.0; n * d];
        let mut rs = vec![0.0; tm];
        // Buffers reused across iterations: the Newton matrix (its coupling blocks are cleared and
        // re-added every iteration), P x, Σ LᵀFᵀz and the local diagonal scale.
        let mut sys = self.base.clone();
        let mut g = vec![0.0; n * d];
        let mut zsum = vec![0.0; n * d];
        let mut local = self.pdiag.clone();
        loop {
            // Residuals: r_x = Px + c − Σ LᵀFᵀz (free rows), r_s = s − h − F L x.
            self.apply_p_into(&st.x, &mut g);
            let mut gn: f64 = 0.0;
            for v in 0..n {
                if self.is_free(v) {
                    for k in 0..d {
                        let i = v * d + k;
                        rx[i] = g[i] + self.c[i];
                        gn = gn.max(rx[i].abs());
                    }
                } else {
                    rx[v * d..(v + 1) * d].fill(0.0);
                }
            }
            zsum.fill(0.0);
            for b in &self.blocks {
                wbuf.clear();
                wbuf.extend(st.z[b.off..b.off + b.m].iter().map(|v| -v));
                self.add_adjoint(b, &wbuf, &mut zsum);
            }
            let mut zn: f64 = 0.0;
            for v in 0..n {
                if self.is_free(v) {
                    for k in 0..d {
                        let i = v * d + k;
                        rx[i] += zsum[i];
                        zn = zn.max(zsum[i].abs());
                    }
                }
            }
            let mut sn: f64 = 0.0;
            for b in &self.blocks {
                tmp.resize(b.m, 0.0);
                self.block_map(b, &st.x, &mut tmp);
                for r in 0..b.m {
                    rs[b.off + r] = st.s[b.off + r] - b.h[r] - tmp[r];
                    sn = sn.max(b.h[r].abs()).max(tmp[r].abs());
                }
            }
            let gap: f64 = self
                .blocks
                .iter()
                .filter(|b| b.kind != Kind::Zero)
                .map(|b| dot(&st.s[b.off..b.off + b.m], &st.z[b.off..b.off + b.m]))
                .sum();
            let mu = if self.degree > 0.0 {
                gap / self.degree
            } else {
                0.0
            };
            // Cheap relative residuals of the iterate (the certificate is computed near the end).
            let xs = self.scale_x.max(inf_norm(&st.x)).max(f64::MIN_POSITIVE);
            let sden = gn.max(zn).max(self.scale_p * xs).max(f64::MIN_POSITIVE);
            let primal = inf_norm(&rs) / sn.max(f64::MIN_POSITIVE);
            let cheap = (inf_norm(&rx) / sden)
                .max(primal)
                .max(gap.abs() / (sden * xs));
            best_primal = best_primal.min(primal);
            if best_state.as_ref().is_none_or(|b| cheap < b.0) {
                best_state = Some((
                    cheap,
                    State {
                        x: st.x.clone(),
                        s: st.s.clone(),
                        z: st.z.clone(),
                    },
                ));
            }
            if cheap <= POLISH_FROM || iterations >= opts.max_iterations {
                let sol = self.certificate(problem, &st, iterations);
                let total = sol.kkt.total;
                best = best.min(total);
                if !polish_tried {
                    polish_tried = true;
                    let pol = self.polish(problem, &st, iterations);
                    if let Some(p) = pol {
                        best = best.min(p.kkt.total);
                        if p.kkt.total <= opts.tolerance {
                            return Ok(p);
                        }
                    }
                }
                if total <= opts.tolerance {
                    return Ok(sol);
                }
            }
            if iterations >= opts.max_iterations {
                break;
            }
            iterations += 1;

            // Scalings, λ, Newton matrix.
            sys.clear_blocks();
            let mut theta = vec![0.0; d * d];
            let mut vf = vec![0.0; 16];
            local.copy_from_slice(&self.pdiag);
            let mut eq_blocks = Vec::new();
            for (bi, b) in self.blocks.iter().enumerate() {
                let (s, z) = (&st.s[b.off..b.off + b.m], &st.z[b.off..b.off + b.m]);
                theta.fill(0.0);
                if b.kind == Kind::Zero {
                    eq_blocks.push(bi);
                    continue;
                }
                scaling(b.kind, s, z, &mut sc[bi]);
                let l = &mut lam[b.off..b.off + b.m];
                l.copy_from_slice(z);
                apply_v(b.kind, &sc[bi], l, false);
                // Θ = (V⁻¹F)ᵀ(V⁻¹F).
                vf.resize(b.m * d, 0.0);
                for k in 0..d {
                    tmp.resize(b.m, 0.0);
                    for r in 0..b.m {
                        tmp[r] = b.f[r * d + k];
                    }
                    apply_v(b.kind, &sc[bi], &mut tmp, true);
                    for r in 0..b.m {
                        vf[r * d + k] = tmp[r];
                    }
                }
                for i in 0..d {
                    for j in 0..d {
                        theta[i * d + j] = (0..b.m).map(|r| vf[r * d + i] * vf[r * d + j]).sum();
                    }
                }
                let tmax = (0..d).map(|k| theta[k * d + k]).fold(0.0, f64::max);
                for &(v, c) in &b.stencil {
                    local[v] += c * c * tmax;
                }
                sys.add_stencil(&b.stencil, &theta)?;
            }
            // Equality rows enter as penalties GᵀG/δ. If the penalized matrix fails to factor
            // (pivots lost to the penalty's size: clamped ends with tangent cones, ROBUSTNESS.md
            // finding 4), δ is enlarged by EQUALITY_REGULARIZATION_RETRY up to
            // EQUALITY_REGULARIZATION_ATTEMPTS times; iterative refinement against the
            // unpenalized system removes the penalty either way.
            let mut delta = vec![0.0; self.blocks.len()];
            let unpenalized = (!eq_blocks.is_empty()).then(|| sys.clone());
            let mut attempt = 0;
            let mut shifted = false;
            let eq_attempts = if unpenalized.is_some() {
                EQUALITY_REGULARIZATION_ATTEMPTS
            } else {
                1
            };
            let factor = loop {
                let eq_attempt = attempt.min(eq_attempts - 1);
                let reg = EQUALITY_REGULARIZATION * EQUALITY_REGULARIZATION_RETRY.powi(eq_attempt);
                if let Some(base) = &unpenalized {
                    sys = base.clone();
                }
                for &bi in &eq_blocks {
                    let b = &self.blocks[bi];
                    // δ relative to the softest stencil vertex (see EQUALITY_REGULARIZATION).
                    let loc = b
                        .stencil
                        .iter()
                        .map(|&(v, c)| local[v] / (c * c))
                        .fold(f64::INFINITY, f64::min);
                    delta[bi] = reg / loc.max(f64::MIN_POSITIVE);
                    for i in 0..d {
                        for j in 0..d {
                            theta[i * d + j] = (0..b.m)
                                .map(|r| b.f[r * d + i] * b.f[r * d + j])
                                .sum::<f64>()
                                / delta[bi];
                        }
                    }
                    sys.add_stencil(&b.stencil, &theta)?;
                }
                // After the equality attempts: a static diagonal shift (ROBUSTNESS.md finding 4),
                // removed by iterative refinement against the unshifted operator.
                let shift_attempt = attempt - eq_attempt;
                if shift_attempt > 0 {
                    let rel =
                        STATIC_REGULARIZATION * STATIC_REGULARIZATION_RETRY.powi(shift_attempt - 1);
                    for (v, &k) in local.iter().enumerate() {
                        if self.is_free(v) {
                            sys.add_weight(v, rel * k)?;
                        }
                    }
                    shifted = true;
                }
                match sys.factor_with_tolerance(IPM_PIVOT_RTOL) {
                    Ok(f) => break Some(f),
                    Err(e) => {
                        attempt += 1;
                        if attempt < eq_attempts + STATIC_REGULARIZATION_ATTEMPTS {
                            continue;
                        }
                        if iterations == 1 {
                            return Err(e.into());
                        }
                        break None;
                    }
                }
            };
            let Some(factor) = factor else { break };
            let ctx = NewtonCtx {
                prep: self,
                factor: &factor,
                shifted,
                sc: &sc,
                eq_blocks: &eq_blocks,
                delta: &delta,
                refine_steps: if cheap <= REFINE_FROM {
                    NEWTON_REFINEMENT_STEPS
                } else {
                    1
                },
            };

            // Predictor: ξ = −λ.
            let xi_aff: Vec<f64> = lam.iter().map(|v| -v).collect();
            let (_, ds_a, dz_a) = ctx.solve(&rx, &rs, &xi_aff);
            let mut alpha_a: f64 = 1.0;
            for b in &self.blocks {
                let r = b.off..b.off + b.m;
                alpha_a = max_step(b.kind, &st.s[r.clone()], &ds_a[r.clone()], alpha_a);
                alpha_a = max_step(b.kind, &st.z[r.clone()], &dz_a[r], alpha_a);
            }
            let mut sigma = 0.0;
            if self.degree > 0.0 && mu > 0.0 {
                let mut gap_a = 0.0;
                for b in self.blocks.iter().filter(|b| b.kind != Kind::Zero) {
                    gap_a += (b.off..b.off + b.m)
                        .map(|r| (st.s[r] + alpha_a * ds_a[r]) * (st.z[r] + alpha_a * dz_a[r]))
                        .sum::<f64>();
                }
                sigma = (gap_a / (mu * self.degree)).clamp(0.0, 1.0).powi(3);
            }
            // Corrector: ξ = λ⁻¹ ∘ (σμe − λ∘λ − (V⁻¹ds_a)∘(V dz_a)).
            let mut xi = vec![0.0; tm];
            let (mut ca, mut cc) = (Vec::with_capacity(16), Vec::with_capacity(16));
            for (bi, b) in self.blocks.iter().enumerate() {
                if b.kind == Kind::Zero {
                    continue;
                }
                let r = b.off..b.off + b.m;
                ca.clear();
                ca.extend_from_slice(&ds_a[r.clone()]);
                apply_v(b.kind, &sc[bi], &mut ca, true);
                cc.clear();
                cc.extend_from_slice(&dz_a[r.clone()]);
                apply_v(b.kind, &sc[bi], &mut cc, false);
                tmp.resize(b.m, 0.0);
                jordan(b.kind, &ca, &cc, &mut tmp);
                tmp2.resize(b.m, 0.0);
                let l = &lam[r.clone()];
                jordan(b.kind, l, l, &mut tmp2);
                let rhs = &mut wbuf;
                rhs.clear();
                rhs.extend((0..b.m).map(|k| -tmp2[k] - tmp[k]));
                match b.kind {
                    Kind::Nonneg => {
                        for v in rhs.iter_mut() {
                            *v += sigma * mu;
                        }
                    }
                    Kind::Soc => rhs[0] += sigma * mu,
                    Kind::Zero => {}
                }
                jordan_div(b.kind, l, rhs, &mut xi[r]);
            }
            let (dx, ds, dz) = ctx.solve(&rx, &rs, &xi);
            let mut alpha: f64 = 1.0 / STEP_FRACTION;
            for b in &self.blocks {
                let r = b.off..b.off + b.m;
                alpha = max_step(b.kind, &st.s[r.clone()], &ds[r.clone()], alpha);
                alpha = max_step(b.kind, &st.z[r.clone()], &dz[r], alpha);
            }
            alpha = (STEP_FRACTION * alpha).min(1.0);
            if !(alpha.is_finite() && alpha > 0.0) || dx.iter().any(|v| !v.is_finite()) {
                break;
            }
            for (xv, dv) in st.x.iter_mut().zip(&dx) {
                *xv += alpha * dv;
            }
            for b in &self.blocks {
                for r in b.off..b.off + b.m {
                    if b.kind != Kind::Zero {
                        st.s[r] += alpha * ds[r];
                    }
                    st.z[r] += alpha * dz[r];
                }
            }
        }
        // Not at the target: accept the best iterate if its certificate is within CONIC_ACCEPT.
        if let Some((_, bst)) = best_state {
            let sol = self.certificate(problem, &bst, iterations);
            best = best.min(sol.kkt.total);
            if sol.kkt.total <= CONIC_ACCEPT {
                return Ok(sol);
            }
            if let Some(p) = self.polish(problem, &bst, iterations) {
                best = best.min(p.kkt.total);
                if p.kkt.total <= CONIC_ACCEPT {
                    return Ok(p);
                }
            }
        }
        let worst = self.worst_constraint(problem, &st);
        Err(Failure::Stalled {
            iterations,
            best,
            primal: best_primal,
            worst,
        })
    }

    /// Active-set Newton polish from an interior-point iterate: the constraints identified as
    /// active (z/s above the scale of H) become equalities — second-order cones through
    /// J(s(x)) = 0 with z = w J s, orthant components through s_i(x) = 0 — and a few Newton
    /// steps on the resulting KKT system (quasi-definite, iterative refinement) remove the
    /// interior-point bias. Returns the certificate, or `None` if a step fails.
    fn polish(
        &self,
        problem: &ConicProblem,
        st: &State,
        iterations: usize,
    ) -> Option<ConicSolution> {
        let (n, d) = (self.n, self.d);
        let omega = if self.scale_p > 0.0 {
            self.scale_p
        } else {
            1.0
        };
        // Rows: (block, component or usize::MAX for a whole SOC, multiplier).
        struct Row {
            block: usize,
            comp: usize,
            mult: f64,
        }
        let mut rows = Vec::new();
        for (bi, b) in self.blocks.iter().enumerate() {
            let (s, z) = (&st.s[b.off..b.off + b.m], &st.z[b.off..b.off + b.m]);
            match b.kind {
                Kind::Zero => {
                    for (r, zr) in z.iter().enumerate() {
                        rows.push(Row {
                            block: bi,
                            comp: r,
                            mult: *zr,
                        });
                    }
                }
                Kind::Nonneg => {
                    let scale = norm(s).max(f64::MIN_POSITIVE);
                    for r in 0..b.m {
                        if z[r] >= omega * s[r] || s[r] <= POLISH_ACTIVE_RTOL * scale {
                            rows.push(Row {
                                block: bi,
                                comp: r,
                                mult: z[r],
                            });
                        }
                    }
                }
                Kind::Soc => {
                    // Both on the boundary and J-orthogonal (active): sᵀz ≪ |s||z|; inactive
                    // blocks on the central path have z ∝ J s, so sᵀz is comparable to |s||z|.
                    let ds = s[0] - norm(&s[1..]);
                    if norm(s) * norm(z) >= POLISH_SOC_RATIO * dot(s, z)
                        || ds <= POLISH_ACTIVE_RTOL * s[0]
                    {
                        if !b.ball || norm(s) <= 1e-9 * self.scale_x.max(f64::MIN_POSITIVE) {
                            // An active wedge has an indefinite curvature term, and at the apex
                            // J s = 0 carries no direction: the interior-point result stands.
                            return None;
                        }
                        rows.push(Row {
                            block: bi,
                            comp: usize::MAX,
                            mult: z[0] / s[0],
                        });
                    }
                }
            }
        }
        let mut in_rows = vec![false; problem.constraints.len()];
        for row in &rows {
            in_rows[self.blocks[row.block].constraint] = true;
        }
        let mut x = st.x.clone();
        let mut sv = vec![0.0; 16];
        let mut best: Option<ConicSolution> = None;
        for _ in 0..POLISH_STEPS {
            // Row gradients g (d-vectors on the block's stencil), constraint values.
            let mut grads: Vec<Vec<f64>> = Vec::with_capacity(rows.len());
            let mut vals = Vec::with_capacity(rows.len());
            for row in &rows {
                let b = &self.blocks[row.block];
                sv.resize(b.m, 0.0);
                self.block_map(b, &x, &mut sv);
                for r in 0..b.m {
                    sv[r] += b.h[r];
                }
                if row.comp == usize::MAX {
                    // g = (J s)ᵀ F, value J(s)/2.
                    let mut g = vec![0.0; d];
                    for r in 0..b.m {
                        let js = if r == 0 { sv[0] } else { -sv[r] };
                        for k in 0..d {
                            g[k] += js * b.f[r * d + k];
                        }
                    }
                    grads.push(g);
                    vals.push(0.5 * soc_j(&sv));
                } else {
                    grads.push(b.f[row.comp * d..(row.comp + 1) * d].to_vec());
                    vals.push(sv[row.comp]);
                }
            }
            // Stationarity residual R = Px + c − Σ mult Lᵀ g.
            let mut res = self.apply_p(&x);
            for (r, cv) in res.iter_mut().zip(&self.c) {
                *r += cv;
            }
            for (row, g) in rows.iter().zip(&grads) {
                let b = &self.blocks[row.block];
                for &(v, c) in &b.stencil {
                    for k in 0..d {
                        res[v * d + k] -= row.mult * c * g[k];
                    }
                }
            }
            for v in 0..n {
                if !self.is_free(v) {
                    res[v * d..(v + 1) * d].fill(0.0);
                }
            }
            // K = P + Σ_SOC (−w FᵀJF) (+ Σ ggᵀ/δ for the factorization).
            let mut sys = self.base.clone();
            let mut socs: Vec<(usize, Vec<f64>)> = Vec::new();
            let mut local = self.pdiag.clone();
            for row in rows.iter().filter(|r| r.comp == usize::MAX) {
                let b = &self.blocks[row.block];
                let mut blk = vec![0.0; d * d];
                for r in 0..b.m {
                    let sg = if r == 0 { -1.0 } else { 1.0 };
                    for i in 0..d {
                        for j in 0..d {
                            blk[i * d + j] += row.mult * sg * b.f[r * d + i] * b.f[r * d + j];
                        }
                    }
                }
                sys.add_stencil(&b.stencil, &blk).ok()?;
                let bmax = (0..d).map(|k| blk[k * d + k].abs()).fold(0.0, f64::max);
                for &(v, c) in &b.stencil {
                    local[v] += c * c * bmax;
                }
                socs.push((row.block, blk));
            }
            let gn: Vec<f64> = grads.iter().map(|g| norm(g)).collect();
            if gn.iter().any(|&v| v.is_nan() || v <= 0.0) {
                return best;
            }
            let mut delta = Vec::with_capacity(rows.len());
            for (row, g) in rows.iter().zip(&grads) {
                let b = &self.blocks[row.block];
                let loc = b
                    .stencil
                    .iter()
                    .map(|&(v, c)| local[v] / (c * c))
                    .fold(f64::INFINITY, f64::min);
                let dl = EQUALITY_REGULARIZATION / loc.max(f64::MIN_POSITIVE);
                delta.push(dl);
                let gg = dot(g, g);
                let mut blk = vec![0.0; d * d];
                for i in 0..d {
                    for j in 0..d {
                        blk[i * d + j] = g[i] * g[j] / (gg * dl);
                    }
                }
                sys.add_stencil(&b.stencil, &blk).ok()?;
            }
            let factor = sys.factor_with_tolerance(IPM_PIVOT_RTOL).ok()?;
            let apply_k = |v: &[f64]| -> Vec<f64> {
                let mut out = self.apply_p(v);
                for (bi, blk) in &socs {
                    let b = &self.blocks[*bi];
                    let mut y = vec![0.0; d];
                    self.stencil_apply(b, v, &mut y);
                    for &(u, c) in &b.stencil {
                        for i in 0..d {
                            out[u * d + i] +=
                                c * (0..d).map(|j| blk[i * d + j] * y[j]).sum::<f64>();
                        }
                    }
                }
                out
            };
            // Unit rows: ĝ = g/|g|, value/|g|, multiplier·|g|.
            let unit: Vec<Vec<f64>> = grads
                .iter()
                .zip(&gn)
                .map(|(g, l)| g.iter().map(|v| v / l).collect())
                .collect();
            let b1: Vec<f64> = res.iter().map(|v| -v).collect();
            let b2: Vec<f64> = vals.iter().zip(&gn).map(|(v, l)| -v / l).collect();
            let stencils: Vec<&[(usize, f64)]> = rows
                .iter()
                .map(|r| self.blocks[r.block].stencil.as_slice())
                .collect();
            let (dx, dm) = self.saddle_solve(&factor, &apply_k, &stencils, &unit, &delta, &b1, &b2);
            if dx.iter().chain(&dm).any(|v| !v.is_finite()) {
                return best;
            }
            for (a, c) in x.iter_mut().zip(&dx) {
                *a += c;
            }
            for ((row, m), l) in rows.iter_mut().zip(&dm).zip(&gn) {
                row.mult += m / l;
            }
            // Certificate of the polished point.
            let mut ps = State {
                x: x.clone(),
                s: vec![0.0; self.total_m],
                z: vec![0.0; self.total_m],
            };
            for row in &rows {
                let b = &self.blocks[row.block];
                if row.comp == usize::MAX {
                    sv.resize(b.m, 0.0);
                    self.block_map(b, &x, &mut sv);
                    for r in 0..b.m {
                        let s = sv[r] + b.h[r];
                        ps.z[b.off + r] = row.mult * if r == 0 { s } else { -s };
                    }
                } else {
                    ps.z[b.off + row.comp] = row.mult;
                }
            }
            let mut cert = self.certificate(problem, &ps, iterations);
            cert.polished = true;
            let better = best.as_ref().is_none_or(|b| cert.kkt.total < b.kkt.total);
            let done = cert.kkt.total <= CONIC_TOLERANCE;
            // A constraint treated as inactive that is violated by far more than the residuals
            // of the active-set system: the active set is wrong, and the remaining Newton steps
            // (whose displacements are of the size of those residuals) cannot repair it.
            let hopeless = {
                let (mut inactive, mut active) = (0.0f64, cert.kkt.stationarity);
                for (ci, con) in problem.constraints.iter().enumerate() {
                    let y = self.constraint_value(con, &x);
                    let (dist, scale) = set_distance(&con.set, &y);
                    let den = scale.max(norm(&y));
                    let rel = if dist > 0.0 && den > 0.0 {
                        dist / den
                    } else {
                        0.0
                    };
                    if in_rows[ci] {
                        active = active.max(rel);
                    } else {
                        inactive = inactive.max(rel);
                    }
                }
                inactive > CONIC_ACCEPT && inactive > POLISH_ABANDON_RATIO * active
            };
            if better {
                best = Some(cert);
            }
            if done || hopeless {
                break;
            }
        }
        best
    }

    /// Solves [K −Gᵀ; G 0][dx; dm] = [b1; b2] for unit rows G (one d-vector per row on its
    /// stencil) with the factorization of K + GᵀG/δ and iterative refinement.
    #[allow(clippy::too_many_arguments)]
    fn saddle_solve(
        &self,
        factor: &Factor,
        apply_k: &dyn Fn(&[f64]) -> Vec<f64>,
        stencils: &[&[(usize, f64)]],
        rows: &[Vec<f64>],
        delta: &[f64],
        b1: &[f64],
        b2: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let (n, d) = (self.n, self.d);
        let g_apply = |r: usize, v: &[f64]| -> f64 {
            let mut y = 0.0;
            for &(u, c) in stencils[r] {
                for k in 0..d {
                    y += c * rows[r][k] * v[u * d + k];
                }
            }
            y
        };
        let gt_add = |r: usize, w: f64, out: &mut [f64]| {
            for &(u, c) in stencils[r] {
                for k in 0..d {
                    out[u * d + k] += c * rows[r][k] * w;
                }
            }
        };
        let mask = |v: &mut [f64]| {
            for u in 0..n {
                if !self.is_free(u) {
                    v[u * d..(u + 1) * d].fill(0.0);
                }
            }
        };
        let mut dx = vec![0.0; n * d];
        let mut dm = vec![0.0; rows.len()];
        let mut e1 = b1.to_vec();
        let mut e2 = b2.to_vec();
        let bnorm = inf_norm(b1).max(inf_norm(b2)).max(f64::MIN_POSITIVE);
        for _ in 0..EQUALITY_REFINEMENT_STEPS {
            let mut r = e1.clone();
            for (k, e) in e2.iter().enumerate() {
                gt_add(k, e / delta[k], &mut r);
            }
            mask(&mut r);
            let _ = factor.solve_flat(&mut r);
            for (a, c) in dx.iter_mut().zip(&r) {
                *a += c;
            }
            for (k, m) in dm.iter_mut().enumerate() {
                *m += (e2[k] - g_apply(k, &r)) / delta[k];
            }
            let kdx = apply_k(&dx);
            e1 = b1.iter().zip(&kdx).map(|(a, c)| a - c).collect();
            for (k, m) in dm.iter().enumerate() {
                gt_add(k, *m, &mut e1);
            }
            mask(&mut e1);
            for (k, e) in e2.iter_mut().enumerate() {
                *e = b2[k] - g_apply(k, &dx);
            }
            if inf_norm(&e1).max(inf_norm(&e2)) <= REFINEMENT_RTOL * bnorm {
                break;
            }
        }
        (dx, dm)
    }

    fn worst_constraint(&self, problem: &ConicProblem, st: &State) -> Option<usize> {
        let mut worst = None;
        let mut wv = 0.0;
        for (ci, con) in problem.constraints.iter().enumerate() {
            let y = self.constraint_value(con, &st.x);
            let (dist, scale) = set_distance(&con.set, &y);
            let rel = dist / scale.max(norm(&y)).max(f64::MIN_POSITIVE);
            if rel > wv {
                wv = rel;
                worst = Some(ci);
            }
        }
        worst
    }

    fn constraint_value(&self, con: &ConicConstraint, x: &[f64]) -> Vec<f64> {
        let d = self.d;
        let mut y = vec![0.0; d];
        for &(v, c) in &con.stencil {
            for k in 0..d {
                y[k] += c * x[v * d + k];
            }
        }
        y
    }

    /// The solution record with its KKT certificate for the iterate `st`.
    fn certificate(&self, problem: &ConicProblem, st: &State, iterations: usize) -> ConicSolution {
        let (n, d) = (self.n, self.d);
        let nc = problem.constraints.len();
        let x = &st.x;
        // g = (H⊗I + W) x + c at all vertices (c is zero at fixed ones: recompute fully).
        let mut hx = vec![0.0; n * d];
        if self.full.apply_flat(x, &mut hx).is_err() {
            hx.fill(0.0);
        }
        let mut g = hx;
        for sm in &problem.smoothing {
            for k in 0..d {
                g[sm.vertex * d + k] -= sm.weight * sm.target[k];
            }
        }
        // Projected duals → forces.
        let mut forces = vec![vec![0.0; d]; nc];
        let mut cone_duals = vec![Vec::new(); nc];
        let mut zsum = vec![0.0; n * d];
        let mut comp = 0.0;
        let mut zp = Vec::new();
        let mut sv = vec![0.0; 16];
        for b in &self.blocks {
            zp.clear();
            zp.extend_from_slice(&st.z[b.off..b.off + b.m]);
            project(b.kind, &mut zp);
            cone_duals[b.constraint].extend_from_slice(&zp);
            let fz = &mut forces[b.constraint];
            for r in 0..b.m {
                for k in 0..d {
                    fz[k] -= b.f[r * d + k] * zp[r];
                }
            }
            sv.resize(b.m, 0.0);
            self.block_map(b, x, &mut sv);
            for r in 0..b.m {
                sv[r] += b.h[r];
            }
            if b.kind != Kind::Zero {
                comp += dot(&sv, &zp).abs();
            }
        }
        for (ci, con) in problem.constraints.iter().enumerate() {
            for &(v, c) in &con.stencil {
                if self.is_free(v) {
                    for k in 0..d {
                        zsum[v * d + k] += c * forces[ci][k];
                    }
                }
            }
        }
        // Reaction forces of constraints that fixed a vertex.
        for v in 0..n {
            if let Some((ci, coef)) = self.owner[v] {
                let mut other = vec![0.0; d];
                for (cj, con) in problem.constraints.iter().enumerate() {
                    if cj == ci {
                        continue;
                    }
                    for &(u, c) in &con.stencil {
                        if u == v {
                            for k in 0..d {
                                other[k] += c * forces[cj][k];
                            }
                        }
                    }
                }
                for k in 0..d {
                    forces[ci][k] = -(g[v * d + k] + other[k]) / coef;
                }
            }
        }
        let mut stat: f64 = 0.0;
        let mut gn: f64 = 0.0;
        let mut zn: f64 = 0.0;
        for v in 0..n {
            if !self.is_free(v) {
                continue;
            }
            for k in 0..d {
                let i = v * d + k;
                stat = stat.max((g[i] + zsum[i]).abs());
                gn = gn.max(g[i].abs());
                zn = zn.max(zsum[i].abs());
            }
        }
        let xs = self.scale_x.max(inf_norm(x)).max(f64::MIN_POSITIVE);
        let sden = gn.max(zn).max(self.scale_p * xs).max(f64::MIN_POSITIVE);
        let mut primal: f64 = 0.0;
        let mut active = vec![false; nc];
        let mut ball_weights = vec![None; nc];
        for (ci, con) in problem.constraints.iter().enumerate() {
            let y = self.constraint_value(con, x);
            let (dist, scale) = set_distance(&con.set, &y);
            let den = scale.max(norm(&y));
            if dist > 0.0 {
                primal = primal.max(if den > 0.0 { dist / den } else { f64::INFINITY });
            }
            let slack = set_slack(&con.set, &y);
            active[ci] = slack <= ACTIVE_RTOL * den;
            if let ConvexSet::Ball { radius, .. } = &con.set {
                if *radius > 0.0 {
                    ball_weights[ci] =
                        Some(cone_duals[ci].first().copied().unwrap_or(0.0) / radius);
                }
            }
        }
        let complementarity = comp / (sden * xs);
        let stationarity = stat / sden;
        let kkt = Kkt {
            stationarity,
            primal,
            complementarity,
            total: stationarity.max(primal).max(complementarity),
        };
        // Energy.
        let mut hxe = vec![0.0; n * d];
        if self.hess.apply_flat(x, &mut hxe).is_err() {
            hxe.fill(0.0);
        }
        let energy = 0.5 * dot(x, &hxe);
        let objective = energy
            + problem
                .smoothing
                .iter()
                .map(|sm| {
                    let p = &x[sm.vertex * d..(sm.vertex + 1) * d];
                    0.5 * sm.weight
                        * p.iter()
                            .zip(&sm.target)
                            .map(|(a, b)| (a - b) * (a - b))
                            .sum::<f64>()
                })
                .sum::<f64>();
        ConicSolution {
            points: Points::new(d, x.clone()).unwrap_or_else(|_| Points::zeros(n, d)),
            forces,
            ball_weights,
            cone_duals,
            active,
            energy,
            objective,
            kkt,
            iterations,
            polished: false,
        }
    }
}

/// (distance from y to the set, scale of the set).
fn set_distance(set: &ConvexSet, y: &[f64]) -> (f64, f64) {
    match set {
        ConvexSet::Ball { center, radius } => {
            let r = norm(&y.iter().zip(center).map(|(a, b)| a - b).collect::<Vec<_>>());
            ((r - radius).max(0.0), inf_norm(center) + radius)
        }
        ConvexSet::Point(v) => (
            norm(&y.iter().zip(v).map(|(a, b)| a - b).collect::<Vec<_>>()),
            inf_norm(v),
        ),
        ConvexSet::HalfSpaces(hs) => {
            let mut dist: f64 = 0.0;
            let mut scale: f64 = 0.0;
            for (nr, o) in hs {
                let l = norm(nr);
                dist = dist.max((dot(nr, y) - o) / l);
                scale = scale.max(o.abs() / l);
            }
            (dist.max(0.0), scale)
        }
        ConvexSet::Cone { axis, half_angle } => {
            let u = dot(axis, y);
            let w = (dot(y, y) - u * u).max(0.0).sqrt();
            let (st, ct) = half_angle.sin_cos();
            // Inside: u ≥ |y| cos θ ⇔ w cos θ ≤ u sin θ (u ≥ 0).
            let dist = if u >= 0.0 && w * ct <= u * st {
                0.0
            } else if u * ct + w * st <= 0.0 {
                norm(y)
            } else {
                w * ct - u * st
            };
            (dist, 0.0)
        }
    }
}

/// Distance from y to the boundary of the set when y is inside (0 on or outside the boundary).
fn set_slack(set: &ConvexSet, y: &[f64]) -> f64 {
    match set {
        ConvexSet::Ball { center, radius } => {
            let r = norm(&y.iter().zip(center).map(|(a, b)| a - b).collect::<Vec<_>>());
            (radius - r).max(0.0)
        }
        ConvexSet::Point(_) => 0.0,
        ConvexSet::HalfSpaces(hs) => hs
            .iter()
            .map(|(nr, o)| ((o - dot(nr, y)) / norm(nr)).max(0.0))
            .fold(f64::INFINITY, f64::min),
        ConvexSet::Cone { axis, half_angle } => {
            let u = dot(axis, y);
            let w = (dot(y, y) - u * u).max(0.0).sqrt();
            let (st, ct) = half_angle.sin_cos();
            (u * st - w * ct).max(0.0)
        }
    }
}

/// One Newton system: factor of P + Σ LᵀFᵀV⁻²FL (+ GᵀG/δ for equality blocks).
struct NewtonCtx<'a> {
    prep: &'a Prepared,
    factor: &'a Factor,
    sc: &'a [Vec<f64>],
    eq_blocks: &'a [usize],
    /// Regularization δ_b per block (equality blocks only).
    delta: &'a [f64],
    /// Refinement steps without equality rows (0 early on, when accuracy does not matter yet).
    refine_steps: usize,
    /// The factored matrix carries a static diagonal shift: refine as for equality rows.
    shifted: bool,
}

impl NewtonCtx<'_> {
    /// Solves for (dx, ds, dz) given r_x, r_s and ξ (see the module docs).
    fn solve(&self, rx: &[f64], rs: &[f64], xi: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let p = self.prep;
        let (n, d) = (p.n, p.d);
        let tm = p.total_m;
        // b1 = −r_x + Σ_ineq LᵀFᵀ(V⁻¹ξ + V⁻² r_s).
        let mut b1: Vec<f64> = rx.iter().map(|v| -v).collect();
        let mut t = Vec::new();
        let mut u = Vec::new();
        for (bi, b) in p.blocks.iter().enumerate() {
            if b.kind == Kind::Zero {
                continue;
            }
            let r = b.off..b.off + b.m;
            t.clear();
            t.extend_from_slice(&xi[r.clone()]);
            apply_v(b.kind, &self.sc[bi], &mut t, true);
            u.clear();
            u.extend_from_slice(&rs[r]);
            apply_v(b.kind, &self.sc[bi], &mut u, true);
            apply_v(b.kind, &self.sc[bi], &mut u, true);
            for (a, c) in t.iter_mut().zip(&u) {
                *a += c;
            }
            p.add_adjoint(b, &t, &mut b1);
        }
        for v in 0..n {
            if !p.is_free(v) {
                b1[v * d..(v + 1) * d].fill(0.0);
            }
        }
        let mut dx = vec![0.0; n * d];
        let mut dz = vec![0.0; tm];
        {
            // Iterative refinement on [K −Gᵀ; G 0][dx; dz_e] = [b1; r_s,e].
            let mut e1 = b1.clone();
            let mut e2: Vec<f64> = vec![0.0; tm];
            for &bi in self.eq_blocks {
                let b = &p.blocks[bi];
                e2[b.off..b.off + b.m].copy_from_slice(&rs[b.off..b.off + b.m]);
            }
            let bnorm = inf_norm(&b1).max(inf_norm(&e2)).max(f64::MIN_POSITIVE);
            let steps = if self.eq_blocks.is_empty() && !self.shifted {
                self.refine_steps
            } else {
                EQUALITY_REFINEMENT_STEPS
            };
            for step in 0..steps {
                // ddx = K_δ⁻¹(e1 + Gᵀ e2/δ); ddz = (e2 − G ddx)/δ.
                let mut r = e1.clone();
                for &bi in self.eq_blocks {
                    let b = &p.blocks[bi];
                    let w: Vec<f64> = e2[b.off..b.off + b.m]
                        .iter()
                        .map(|v| v / self.delta[bi])
                        .collect();
                    p.add_adjoint(b, &w, &mut r);
                }
                for v in 0..n {
                    if !p.is_free(v) {
                        r[v * d..(v + 1) * d].fill(0.0);
                    }
                }
                let _ = self.factor.solve_flat(&mut r);
                for (a, c) in dx.iter_mut().zip(&r) {
                    *a += c;
                }
                let mut gx = vec![0.0; 16];
                for &bi in self.eq_blocks {
                    let b = &p.blocks[bi];
                    gx.resize(b.m, 0.0);
                    p.block_map(b, &r, &mut gx);
                    for k in 0..b.m {
                        dz[b.off + k] += (e2[b.off + k] - gx[k]) / self.delta[bi];
                    }
                }
                if step + 1 == steps {
                    break;
                }
                // New residuals of the unregularized system.
                let kdx = self.apply_k(&dx);
                e1 = b1.clone();
                for (a, c) in e1.iter_mut().zip(&kdx) {
                    *a -= c;
                }
                for &bi in self.eq_blocks {
                    let b = &p.blocks[bi];
                    p.add_adjoint(b, &dz[b.off..b.off + b.m], &mut e1);
                    gx.resize(b.m, 0.0);
                    p.block_map(b, &dx, &mut gx);
                    for k in 0..b.m {
                        e2[b.off + k] = rs[b.off + k] - gx[k];
                    }
                }
                for v in 0..n {
                    if !p.is_free(v) {
                        e1[v * d..(v + 1) * d].fill(0.0);
                    }
                }
                if inf_norm(&e1).max(inf_norm(&e2)) <= REFINEMENT_RTOL * bnorm {
                    break;
                }
            }
        }
        // Inequality blocks: y = F L dx; dz = V⁻¹ξ + V⁻²(r_s − y); ds = −r_s + y.
        let mut ds = vec![0.0; tm];
        let mut y = vec![0.0; 16];
        for (bi, b) in p.blocks.iter().enumerate() {
            if b.kind == Kind::Zero {
                continue;
            }
            let r = b.off..b.off + b.m;
            y.resize(b.m, 0.0);
            p.block_map(b, &dx, &mut y);
            t.clear();
            t.extend(rs[r.clone()].iter().zip(&y).map(|(a, c)| a - c));
            apply_v(b.kind, &self.sc[bi], &mut t, true);
            u.clear();
            u.extend(xi[r.clone()].iter().zip(&t).map(|(a, c)| a + c));
            apply_v(b.kind, &self.sc[bi], &mut u, true);
            dz[r.clone()].copy_from_slice(&u);
            for k in 0..b.m {
                ds[b.off + k] = -rs[b.off + k] + y[k];
            }
        }
        (dx, ds, dz)
    }

    /// K_ineq v = (H⊗I + W) v + Σ_ineq LᵀFᵀV⁻²F L v at free vertices (v zero at fixed ones).
    fn apply_k(&self, v: &[f64]) -> Vec<f64> {
        let p = self.prep;
        let mut out = p.apply_p(v);
        let mut y = vec![0.0; 16];
        for (bi, b) in p.blocks.iter().enumerate() {
            if b.kind == Kind::Zero {
                continue;
            }
            y.resize(b.m, 0.0);
            p.block_map(b, v, &mut y);
            apply_v(b.kind, &self.sc[bi], &mut y, true);
            apply_v(b.kind, &self.sc[bi], &mut y, true);
            p.add_adjoint(b, &y, &mut out);
        }
        out
    }
}

/// Newton steps of the active-set polish.
pub const POLISH_STEPS: usize = 3;
/// The polish also treats a constraint as active when its slack is below this times its size
/// (weakly active constraints: zero multiplier on the boundary).
pub const POLISH_ACTIVE_RTOL: f64 = 1e-6;
/// A second-order-cone block counts as active in the polish when |s||z| ≥ this × sᵀz.
pub const POLISH_SOC_RATIO: f64 = 100.0;
/// The polish gives up after a Newton step that leaves a constraint outside its active set
/// violated (relative distance above [`CONIC_ACCEPT`]) by more than this times the residuals of
/// the active-set system (stationarity, active constraints): the active set is wrong, and the
/// remaining steps, whose displacements are of the size of those residuals, cannot repair it.
pub const POLISH_ABANDON_RATIO: f64 = 1e3;
/// The polish is first tried when the interior-point iterate's relative KKT residual is below this.
pub const POLISH_FROM: f64 = 1e-8;

/// Iterative-refinement steps (against the unregularized operator) of Newton systems without
/// equality rows: the first solve plus corrections.
pub const NEWTON_REFINEMENT_STEPS: usize = 2;
/// Newton systems without equality rows are refined only once the iterate's relative residual is
/// below this (early directions need no accuracy).
pub const REFINE_FROM: f64 = 1e-6;
/// Iterative refinement stops when the residual is below this times the right-hand side.
pub const REFINEMENT_RTOL: f64 = 1e-14;

/// Iterative-refinement steps for Newton systems with equality blocks on wide stencils.
pub const EQUALITY_REFINEMENT_STEPS: usize = 6;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nt_scaling_maps_s_and_z_to_the_same_point() {
        let s = [2.0, 0.5, -0.7, 0.3];
        let z = [1.5, -0.2, 0.4, 0.9];
        let mut sc = Vec::new();
        scaling(Kind::Soc, &s, &z, &mut sc);
        let mut vz = z.to_vec();
        apply_v(Kind::Soc, &sc, &mut vz, false);
        let mut vis = s.to_vec();
        apply_v(Kind::Soc, &sc, &mut vis, true);
        for k in 0..4 {
            assert!((vz[k] - vis[k]).abs() < 1e-12, "{vz:?} vs {vis:?}");
        }
        // V⁻¹ inverts V.
        let mut u = vec![0.3, -1.0, 2.0, 0.5];
        apply_v(Kind::Soc, &sc, &mut u, false);
        apply_v(Kind::Soc, &sc, &mut u, true);
        for (a, b) in u.iter().zip([0.3, -1.0, 2.0, 0.5]) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn jordan_division_inverts_the_product() {
        let lam = [2.0, 0.5, -0.7];
        let r = [0.4, 1.0, -2.0];
        let mut x = [0.0; 3];
        jordan_div(Kind::Soc, &lam, &r, &mut x);
        let mut back = [0.0; 3];
        jordan(Kind::Soc, &lam, &x, &mut back);
        for k in 0..3 {
            assert!((back[k] - r[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn soc_step_reaches_the_boundary() {
        let u = [2.0, 0.5, 0.0];
        let du = [-1.0, 1.0, 0.5];
        let a = max_step(Kind::Soc, &u, &du, 10.0);
        let v: Vec<f64> = u.iter().zip(&du).map(|(x, y)| x + a * y).collect();
        assert!(soc_j(&v).abs() < 1e-10 && v[0] > 0.0, "{a} {v:?}");
    }
}
