//! An independent reference: the fixed-knot refinement problems of Kersey §3 posed as conic
//! programs for Clarabel (interior point, sparse LDLᵀ), shared by the tests and `cargo xtask`.
//!
//! minimize ½ xᵀ (H ⊗ I_d + W) x − (W q̃)ᵀx  s.t.  A x + s = b, s ∈ K, with x = p vertex-major:
//! interpolation rows in the zero cone, balls as second-order cones (ε_i, q_i − p_{i_k}),
//! half-spaces in the non-negative cone (c − n·p); with [`clarabel_problem_with_derivatives`] also
//! the constraints of §3.5–3.6 on the approximate derivative Df(t_v) = Σ c_k p_{v_k} (the stencil
//! of `divdiff::derivative_stencil`): balls and tension as second-order cones, wedges as the cone
//! Df·u ≥ cos(a)|Df|, half-spaces in the non-negative cone, clamped ends in the zero cone.
#![allow(dead_code)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use divdiff::{derivative_stencil, DerivativeRule, Knots, Points};
use refine::{Boundary, Constraint, Tangent};

/// Clarabel's answer.
pub struct Reference {
    /// The optimal vertices.
    pub points: Points,
    /// ½pᵀHp (+ ½Σ w|p − q|² for smoothing).
    pub objective: f64,
    /// Interior-point iterations.
    pub iterations: u32,
}

/// Gap and feasibility tolerances handed to Clarabel: its defaults (1e-8) are as loose as the
/// 1e-8 relative energy agreement we check; 1e-12 often ends in `AlmostSolved` (reduced
/// accuracy, seen 1e-7 inside active balls), so 1e-10 with status `Solved` required.
pub const CLARABEL_TOL: f64 = 1e-10;

/// Solves the fixed-knot problem with Clarabel, requiring status `Solved`; tolerances are tried
/// in the order of [`CLARABEL_LADDER`] (Clarabel sometimes stops at `AlmostSolved` for one
/// tolerance and solves at a neighbouring one). `Err` when no tolerance gives `Solved`.
pub fn clarabel_solve(
    knots: &Knots,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
) -> Result<Reference, String> {
    let mut last = String::new();
    for tol in CLARABEL_LADDER {
        match clarabel_solve_tol(knots, q, data_vertex, constraint, tol) {
            Ok(r) => return Ok(r),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// The tolerances tried by [`clarabel_solve`], most accurate useful first.
pub const CLARABEL_LADDER: [f64; 3] = [CLARABEL_TOL, 1e-11, 1e-9];

/// The kind of cone a block of rows of `A x + s = b` lies in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConeKind {
    /// `s = 0` (equalities).
    Zero,
    /// `s = (t, u)` with `|u| ≤ t`.
    SecondOrder,
    /// `s ≥ 0` componentwise.
    Nonnegative,
}

/// A sparse matrix as coordinate triplets; repeated (row, column) pairs add.
#[derive(Clone, Debug, Default)]
pub struct Triplets {
    /// Row indices.
    pub rows: Vec<usize>,
    /// Column indices.
    pub cols: Vec<usize>,
    /// Values.
    pub vals: Vec<f64>,
}

/// The conic program handed to Clarabel, solver-neutral (also written out for the Python peer of
/// `cargo xtask bench`): minimize ½xᵀPx + q_linᵀx + constant s.t. A x + s = b, s in the product
/// of `cones` (in row order).
#[derive(Clone, Debug)]
pub struct SocpData {
    /// Number of variables (vertices × dimension, vertex-major).
    pub n_vars: usize,
    /// The upper triangle of P (n_vars × n_vars).
    pub p: Triplets,
    /// The linear term.
    pub q_lin: Vec<f64>,
    /// The constraint matrix (b.len() × n_vars).
    pub a: Triplets,
    /// The constraint right-hand side.
    pub b: Vec<f64>,
    /// The cones, each with its number of rows, in row order.
    pub cones: Vec<(ConeKind, usize)>,
    /// The constant dropped from the objective (so the energy is the objective plus this).
    pub constant: f64,
}

/// The fixed-knot problem as the conic program [`clarabel_solve`] solves (the one builder).
pub fn clarabel_problem(
    knots: &Knots,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
) -> SocpData {
    let nv = knots.vertex_count();
    let d = q.dim();
    let nx = nv * d;
    let h = energy::Hessian::new(knots);
    let (d0, d1, d2) = h.bands();
    let closed = knots.is_closed();
    // Upper triangle of H ⊗ I_d (+ W), triplets (duplicates add, which also handles the
    // aliasing bands of tiny closed curves).
    let (mut pi, mut pj, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    let mut push = |a: usize, b: usize, v: f64| {
        if v == 0.0 {
            return;
        }
        for c in 0..d {
            let (r, s) = (a * d + c, b * d + c);
            let (r, s) = if r <= s { (r, s) } else { (s, r) };
            pi.push(r);
            pj.push(s);
            // An off-diagonal entry pair (a, b) and (b, a) is represented once in the upper
            // triangle; when a and b alias to the same vertex it lands on the diagonal twice.
            pv.push(v);
        }
    };
    for j in 0..nv {
        push(j, j, d0[j]);
        for (band, step) in [(d1, 1), (d2, 2)] {
            if !closed && j + step >= nv {
                continue;
            }
            let k = (j + step) % nv;
            if k == j {
                push(j, j, 2.0 * band[j]);
            } else {
                push(j, k, band[j]);
            }
        }
    }
    let mut lin = vec![0.0; nx];
    let (mut ai, mut aj, mut av, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut cones = Vec::new();
    let mut constant = 0.0;
    for (i, &v) in data_vertex.iter().enumerate() {
        let qi = q.point(i);
        let equality =
            |ai: &mut Vec<usize>, aj: &mut Vec<usize>, av: &mut Vec<f64>, b: &mut Vec<f64>| {
                for (c, &qc) in qi.iter().enumerate() {
                    ai.push(b.len());
                    aj.push(v * d + c);
                    av.push(1.0);
                    b.push(qc);
                }
            };
        match constraint {
            Constraint::Interpolate => {
                equality(&mut ai, &mut aj, &mut av, &mut b);
                cones.push((ConeKind::Zero, d));
            }
            Constraint::Balls(r) if r[i] == 0.0 => {
                equality(&mut ai, &mut aj, &mut av, &mut b);
                cones.push((ConeKind::Zero, d));
            }
            Constraint::Balls(r) => {
                b.push(r[i]);
                for (c, &qc) in qi.iter().enumerate() {
                    ai.push(b.len());
                    aj.push(v * d + c);
                    av.push(1.0);
                    b.push(qc);
                }
                cones.push((ConeKind::SecondOrder, d + 1));
            }
            Constraint::Smoothing(w) => {
                for (c, &qc) in qi.iter().enumerate() {
                    pi.push(v * d + c);
                    pj.push(v * d + c);
                    pv.push(w[i]);
                    lin[v * d + c] -= w[i] * qc;
                    constant += 0.5 * w[i] * qc * qc;
                }
            }
            Constraint::HalfSpaces(sets) => {
                for hs in &sets[i] {
                    for (c, &nc) in hs.normal.iter().enumerate() {
                        ai.push(b.len());
                        aj.push(v * d + c);
                        av.push(nc);
                    }
                    b.push(hs.offset);
                }
                if !sets[i].is_empty() {
                    cones.push((ConeKind::Nonnegative, sets[i].len()));
                }
            }
        }
    }
    SocpData {
        n_vars: nx,
        p: Triplets {
            rows: pi,
            cols: pj,
            vals: pv,
        },
        q_lin: lin,
        a: Triplets {
            rows: ai,
            cols: aj,
            vals: av,
        },
        b,
        cones,
        constant,
    }
}

/// Corollary 3.3 checked independently of the solver's certificate: the data vertices strictly
/// inside their ball (|p_{i_k} − q_i| < ε_i (1 − 1e-6), so weakly active balls do not count) and
/// the largest |jmp| there relative to the largest |jmp| of the curve, jmp from
/// `divdiff::jumps`. Returns (number of inactive data vertices, relative |jmp|). The scale is
/// at least 1e9 times the rounding level of jmp = ½Hp evaluated from points of size |p|,
/// 8 ε ‖H‖_∞ |p| (‖H‖_∞ ≤ 5 max|H_jk|): when E is 0 up to rounding, every jmp is rounding.
pub fn corollary_3_3(q: &Points, radii: &[f64], r: &refine::Refinement) -> (usize, f64) {
    let j = divdiff::jumps(&r.knots, &r.points).expect("one point per vertex");
    let pmax = r.points.coords().iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rounding = 8.0 * f64::EPSILON * 5.0 * energy::Hessian::new(&r.knots).max_abs() * pmax;
    let scale = j
        .coords()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(rounding / 1e-9);
    let (mut count, mut worst) = (0usize, 0.0f64);
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let dist = r
            .points
            .point(v)
            .iter()
            .zip(q.point(i))
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        if dist < radii[i] * (1.0 - 1e-6) {
            count += 1;
            for x in j.point(v) {
                let rel = x.abs() / scale.max(f64::MIN_POSITIVE);
                // NaN is kept (a comparison with NaN would drop it).
                worst = if rel.is_nan() {
                    f64::NAN
                } else {
                    worst.max(rel)
                };
            }
        }
    }
    (count, worst)
}

fn clarabel_solve_tol(
    knots: &Knots,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
    tol: f64,
) -> Result<Reference, String> {
    solve_socp_tol(
        clarabel_problem(knots, q, data_vertex, constraint),
        q.dim(),
        tol,
    )
}

/// Solves any conic program of this module (points of dimension `d`) with Clarabel, trying the
/// tolerances of [`CLARABEL_LADDER`] in order and requiring status `Solved`.
pub fn clarabel_solve_socp(data: &SocpData, d: usize) -> Result<Reference, String> {
    let mut last = String::new();
    for tol in CLARABEL_LADDER {
        match solve_socp_tol(data.clone(), d, tol) {
            Ok(r) => return Ok(r),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// The fixed-knot problem of [`clarabel_problem`] with the derivative constraints of Kersey
/// §3.5 (one optional [`Tangent`] per data point, on Df(t_{i_k})) and the end conditions of §3.6
/// (on Df(t_1) and Df(t_N) of an open curve), Df by `rule` through `divdiff::derivative_stencil`:
/// - `Tangent::Ball { center, radius }`: |Df − center| ≤ radius (second-order cone);
/// - `Tangent::Tension { radius }`: |Df| ≤ radius;
/// - `Tangent::Wedge { direction, half_angle }`: cos(half_angle)·|Df| ≤ Df·direction/|direction|
///   (the angle between Df and the direction is at most the half angle);
/// - `Tangent::HalfSpaces(h)`: n·Df ≤ c for each half-space;
/// - `Boundary::Clamped { start, end }`: Df(t_1) = start, Df(t_N) = end (zero cone);
/// - `Boundary::NearClamped { start, end, radius }`: |Df − start| ≤ radius, |Df − end| ≤ radius.
#[allow(clippy::too_many_arguments)]
pub fn clarabel_problem_with_derivatives(
    knots: &Knots,
    q: &Points,
    data_vertex: &[usize],
    constraint: &Constraint,
    tangents: Option<&[Option<Tangent>]>,
    boundary: &Boundary,
    rule: DerivativeRule,
) -> Result<SocpData, String> {
    let mut s = clarabel_problem(knots, q, data_vertex, constraint);
    let d = q.dim();
    let stencil = |v: usize| derivative_stencil(knots, v, rule).map_err(|e| e.to_string());
    // Rows b − (coef·Df-stencil) for each coordinate c, scaled by `scale`: s = b − A x.
    let push_df = |s: &mut SocpData, st: &[(usize, f64); 3], scale: &[f64], rhs: &[f64]| {
        for (c, (&sc, &r)) in scale.iter().zip(rhs).enumerate() {
            let row = s.b.len();
            for &(v, coef) in st {
                if coef != 0.0 && sc != 0.0 {
                    s.a.rows.push(row);
                    s.a.cols.push(v * d + c);
                    s.a.vals.push(sc * coef);
                }
            }
            s.b.push(r);
        }
    };
    // A second-order cone (radius, center − Df).
    let ball = |s: &mut SocpData, st: &[(usize, f64); 3], center: &[f64], radius: f64| {
        s.b.push(radius);
        push_df(s, st, &vec![1.0; d], center);
        s.cones.push((ConeKind::SecondOrder, d + 1));
    };
    for (i, t) in tangents.unwrap_or(&[]).iter().enumerate() {
        let Some(t) = t else { continue };
        let st = stencil(data_vertex[i])?;
        match t {
            Tangent::Ball { center, radius } => ball(&mut s, &st, center, *radius),
            Tangent::Tension { radius } => ball(&mut s, &st, &vec![0.0; d], *radius),
            Tangent::Wedge {
                direction,
                half_angle,
            } => {
                // s = (Df·û, cos(a) Df): both rows are −(coefficients)·x with b = 0.
                let len = direction.iter().map(|x| x * x).sum::<f64>().sqrt();
                let row = s.b.len();
                for &(v, coef) in &st {
                    for (c, u) in direction.iter().enumerate() {
                        s.a.rows.push(row);
                        s.a.cols.push(v * d + c);
                        s.a.vals.push(-coef * u / len);
                    }
                }
                s.b.push(0.0);
                push_df(&mut s, &st, &vec![-half_angle.cos(); d], &vec![0.0; d]);
                s.cones.push((ConeKind::SecondOrder, d + 1));
            }
            Tangent::HalfSpaces(hs) => {
                for h in hs {
                    let row = s.b.len();
                    for &(v, coef) in &st {
                        for (c, nc) in h.normal.iter().enumerate() {
                            s.a.rows.push(row);
                            s.a.cols.push(v * d + c);
                            s.a.vals.push(coef * nc);
                        }
                    }
                    s.b.push(h.offset);
                }
                if !hs.is_empty() {
                    s.cones.push((ConeKind::Nonnegative, hs.len()));
                }
            }
        }
    }
    let n = knots.vertex_count();
    match boundary {
        Boundary::Natural => {}
        Boundary::Clamped { start, end } => {
            for (v, want) in [(0, start), (n - 1, end)] {
                push_df(&mut s, &stencil(v)?, &vec![1.0; d], want);
                s.cones.push((ConeKind::Zero, d));
            }
        }
        Boundary::NearClamped { start, end, radius } => {
            for (v, want) in [(0, start), (n - 1, end)] {
                ball(&mut s, &stencil(v)?, want, *radius);
            }
        }
    }
    Ok(s)
}

fn solve_socp_tol(data: SocpData, d: usize, tol: f64) -> Result<Reference, String> {
    let SocpData {
        n_vars: nx,
        p,
        q_lin: lin,
        a,
        b,
        cones,
        constant,
    } = data;
    let cones: Vec<SupportedConeT<f64>> = cones
        .into_iter()
        .map(|(kind, dim)| match kind {
            ConeKind::Zero => SupportedConeT::ZeroConeT(dim),
            ConeKind::SecondOrder => SupportedConeT::SecondOrderConeT(dim),
            ConeKind::Nonnegative => SupportedConeT::NonnegativeConeT(dim),
        })
        .collect();
    let m = b.len();
    let p_mat = CscMatrix::new_from_triplets(nx, nx, p.rows, p.cols, p.vals);
    let a_mat = CscMatrix::new_from_triplets(m, nx, a.rows, a.cols, a.vals);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(200)
        .tol_gap_abs(tol)
        .tol_gap_rel(tol)
        .tol_feas(tol)
        .tol_ktratio(1e-10)
        .build()
        .map_err(|e| format!("{e:?}"))?;
    let mut solver = DefaultSolver::new(&p_mat, &lin, &a_mat, &b, &cones, settings)
        .map_err(|e| format!("{e:?}"))?;
    solver.solve();
    let sol = &solver.solution;
    match sol.status {
        SolverStatus::Solved => {}
        s => {
            return Err(format!(
                "clarabel status {s:?} after {} iterations",
                sol.iterations
            ))
        }
    }
    let points = Points::new(d, sol.x.clone()).map_err(|e| e.to_string())?;
    Ok(Reference {
        points,
        objective: sol.obj_val + constant,
        iterations: sol.iterations,
    })
}

pub mod cases;
