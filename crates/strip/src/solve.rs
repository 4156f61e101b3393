//! Problem setup, the outer minimization of Φ (problem (5), and (10) for §4 grids), and the
//! assembled solution.

use crate::banded::Band;
use crate::cell::{
    hessian, solve_cell, Cell, CellSolution, CellStats, CellTol, Pruning, Shape, Side,
};
use crate::error::Error;
use crate::frame::Frame;

/// A bound of the strip.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Bound {
    /// No bound on this side.
    #[default]
    None,
    /// One cubic per data interval \[t_i, t_{i+1}\]: c0 + c1 s + c2 s² + c3 s³ in s = t − t_i
    /// (linear bounds have c2 = c3 = 0; bounds may jump at the data sites).
    Pieces(Vec<[f64; 4]>),
    /// A continuous polyline (t, value), strictly increasing in t and covering \[t_1, t_n\];
    /// its vertices become extra grid points with free values (§4, problem (10)).
    Polyline(Vec<[f64; 2]>),
}

impl Bound {
    /// Piecewise-linear interpolation of a continuous function on `cells` equal cells of
    /// \[t0, t1\] — the approximations e_m, d_m of §4 (Theorem 4.1: as the grid refines, the
    /// solutions converge in W^{2,2}).
    pub fn from_fn(f: impl Fn(f64) -> f64, t0: f64, t1: f64, cells: usize) -> Bound {
        let m = cells.max(1);
        Bound::Polyline(
            (0..=m)
                .map(|k| {
                    let t = if k == m {
                        t1
                    } else {
                        t0 + (t1 - t0) * k as f64 / m as f64
                    };
                    [t, f(t)]
                })
                .collect(),
        )
    }
}

/// A strip-interpolation problem: minimize ∫f''² subject to f(t_i) = y_i, lower ≤ f ≤ upper.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Problem {
    /// Data sites t_1 < … < t_n.
    pub t: Vec<f64>,
    /// Data values y_i.
    pub y: Vec<f64>,
    /// Lower bound e.
    pub lower: Bound,
    /// Upper bound d.
    pub upper: Bound,
    /// Optional prescribed slopes f'(t_1), f'(t_n) (natural ends where `None`).
    pub end_slopes: [Option<f64>; 2],
}

/// The outer minimization method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Newton's method on the banded Hessian of Φ (implicitly differentiated per cell), with a
    /// projected backtracking line search. Default; O(n) per iteration.
    #[default]
    Newton,
    /// argmin's BFGS with a Moré–Thuente line search, as in the seed (dense n×n inverse Hessian:
    /// for small n; not available with polyline bounds, whose grid values are box-constrained).
    Bfgs,
}

/// Default iteration limit of the outer solver.
pub const DEFAULT_MAX_ITERATIONS: usize = 200;
/// Default gradient tolerance: stop when ‖∇Φ‖∞ ≤ tol · (1 + ‖∇Φ(z₀)‖∞) (projected for boxes),
/// in the normalized frame of [`solve`] (where Φ and its gradient are of unit order).
pub const DEFAULT_GRADIENT_TOL: f64 = 1e-11;
/// Default margin ε of Remark 4.2 and problem (10), relative to the local strip width: data on a
/// bound are moved inside by ε·width, and free grid values stay ε·width inside the strip.
pub const DEFAULT_BOUNDARY_MARGIN: f64 = 1e-7;
/// Feasibility tolerance of a candidate in an interval, relative to the value scale V (the
/// largest deviation of the data, the end slopes or the bounds from the line through the first
/// and last data point; see the crate documentation).
pub const FEASIBILITY_TOL: f64 = 1e-10;
/// The returned pieces satisfy the strip to this fraction of the value scale V, plus the
/// rounding allowance [`ROUNDING_TOL`] (checked exactly on every cubic piece in the caller's
/// frame; a larger violation is [`Error::StripViolated`]). Ten times [`FEASIBILITY_TOL`]: room
/// for the rounding of the map back from the normalized frame.
pub const RESULT_FEASIBILITY_TOL: f64 = 1e-9;
/// Rounding allowance of the returned pieces relative to the magnitude of the values
/// M = max|y_i| + |ℓ'|·(t_n − t_1) + V (ℓ the line through the first and last data point):
/// values of size M carry rounding errors of this order whatever the solver does. (The check
/// that the pieces join also allows this fraction of Σ|c_k|h^k + |f'|·|t|, the terms of each
/// end value and the rounding of its abscissa.)
pub const ROUNDING_TOL: f64 = 1e-14;
/// Relative tolerance of the f'' continuity equations solved for the extra knots.
pub const CONTACT_TOL: f64 = 1e-12;

/// Solver options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Outer method.
    pub method: Method,
    /// Candidate pruning in each interval (all choices give the same answer).
    pub pruning: Pruning,
    /// Maximum outer iterations.
    pub max_iterations: usize,
    /// Gradient tolerance (see [`DEFAULT_GRADIENT_TOL`]).
    pub gradient_tol: f64,
    /// Margin ε (see [`DEFAULT_BOUNDARY_MARGIN`]).
    pub boundary_margin: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::Newton,
            pruning: Pruning::Certificate,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            gradient_tol: DEFAULT_GRADIENT_TOL,
            boundary_margin: DEFAULT_BOUNDARY_MARGIN,
        }
    }
}

/// What an extra knot is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum KnotKind {
    /// A single touching point (f = bound, f' = bound').
    Touch(Side),
    /// Start of a subarc on the bound.
    SubarcStart(Side),
    /// End of a subarc on the bound.
    SubarcEnd(Side),
}

/// An extra knot of the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtraKnot {
    /// Where.
    pub t: f64,
    /// What.
    pub kind: KnotKind,
    /// The grid interval it lies in (0-based).
    pub interval: usize,
}

/// The solution: an exact C² piecewise cubic.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Breakpoints (data sites, grid points and extra knots), increasing.
    pub breaks: Vec<f64>,
    /// `coefficients[j]` = \[c0, c1, c2, c3\] of the cubic on \[breaks\[j\], breaks\[j+1\]\] in
    /// s = t − breaks\[j\].
    pub coefficients: Vec<[f64; 4]>,
    /// Slopes z_i = f'(t_i) at the data sites.
    pub slopes: Vec<f64>,
    /// The solver's grid: data sites plus interior polyline vertices (= `t` without polylines).
    pub grid: Vec<f64>,
    /// f at the grid points.
    pub grid_values: Vec<f64>,
    /// The shape of the solution in each grid interval.
    pub shapes: Vec<Shape>,
    /// The extra knots with their kinds, sorted by t. With polyline bounds this includes grid
    /// vertices where f touches a bound (its value held ε·width inside, problem (10)).
    pub extra_knots: Vec<ExtraKnot>,
    /// ∫ f''².
    pub energy: f64,
    /// ‖f''‖_{L²} = √energy.
    pub norm: f64,
    /// Final (projected) gradient norm ‖∇Φ‖₂ in the caller's units (∂Φ/∂z_i for slopes,
    /// ∂Φ/∂s_j for free grid values).
    pub gradient_norm: f64,
    /// Newton decrement ½ gᵀH⁻¹g at the solution (≈ Φ − min Φ, in the units of ∫f''²; NaN for
    /// BFGS).
    pub newton_decrement: f64,
    /// Outer iterations.
    pub iterations: usize,
    /// Per-interval solves (all outer iterations and line-search trials).
    pub cell_solves: usize,
    /// Candidates examined in those solves.
    pub candidates: usize,
    /// Data points moved inside by the margin because they lay on a bound (Remark 4.2).
    pub shifted_data: Vec<usize>,
    /// Grid intervals whose chosen candidate lacks the optimality certificate (empty for linear
    /// bounds; see [`Pruning::Certificate`]).
    pub uncertified: Vec<usize>,
    /// The largest violation of the strip by the returned pieces in the caller's units (exact
    /// extrema of every cubic piece; ≤ 0 when the pieces are inside, 0 without bounds). At most
    /// [`RESULT_FEASIBILITY_TOL`]·V + [`ROUNDING_TOL`]·M, else [`solve`] returns
    /// [`Error::StripViolated`].
    pub violation: f64,
}

impl Solution {
    fn locate(&self, t: f64) -> usize {
        let n = self.coefficients.len();
        match self.breaks.binary_search_by(|b| b.total_cmp(&t)) {
            Ok(j) => j.min(n - 1),
            Err(j) => j.saturating_sub(1).min(n - 1),
        }
    }
    /// The k-th derivative (k = 0..3) of f at t (clamped to the piece containing t; the right
    /// piece at a break).
    pub fn derivative(&self, t: f64, k: usize) -> f64 {
        let j = self.locate(t);
        let c = &self.coefficients[j];
        let s = t - self.breaks[j];
        match k {
            0 => c[0] + s * (c[1] + s * (c[2] + s * c[3])),
            1 => c[1] + s * (2.0 * c[2] + 3.0 * s * c[3]),
            2 => 2.0 * c[2] + 6.0 * s * c[3],
            3 => 6.0 * c[3],
            _ => 0.0,
        }
    }
    /// f(t).
    pub fn eval(&self, t: f64) -> f64 {
        self.derivative(t, 0)
    }
}

/// One grid interval in real units.
#[derive(Clone, Debug)]
struct RealCell {
    a: f64,
    h: f64,
    lower: Option<[f64; 4]>,
    upper: Option<[f64; 4]>,
    interval: usize,
}

/// Taylor shift of a cubic in s = t − t0 to s = t − t1.
fn shift_cubic(c: &[f64; 4], d: f64) -> [f64; 4] {
    let (v, d1, d2) = crate::cell::cubic3(c, d);
    [v, d1, 0.5 * d2, c[3]]
}

pub(crate) fn polyline_at(p: &[[f64; 2]], t: f64) -> f64 {
    let k = p.partition_point(|v| v[0] <= t).clamp(1, p.len() - 1);
    let (a, b) = (p[k - 1], p[k]);
    a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
}

fn cell_bound(b: &Bound, interval: usize, ti: f64, a: f64, h: f64) -> Option<[f64; 4]> {
    match b {
        Bound::None => None,
        Bound::Pieces(p) => Some(shift_cubic(&p[interval], a - ti)),
        Bound::Polyline(p) => {
            let (va, vb) = (polyline_at(p, a), polyline_at(p, a + h));
            Some([va, (vb - va) / h, 0.0, 0.0])
        }
    }
}

fn validate(p: &Problem) -> Result<(), Error> {
    let n = p.t.len();
    if n < 2 {
        return Err(Error::TooFewPoints { len: n });
    }
    if p.y.len() != n {
        return Err(Error::LengthMismatch {
            field: "y",
            expected: n,
            found: p.y.len(),
        });
    }
    for (field, v) in [("t", &p.t), ("y", &p.y)] {
        if let Some(index) = v.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite { field, index });
        }
        if let Some(index) = v.iter().position(|x| x.abs() > MAX_MAGNITUDE) {
            return Err(Error::TooLarge {
                field,
                index,
                max: MAX_MAGNITUDE,
            });
        }
    }
    for i in 1..n {
        if p.t[i] <= p.t[i - 1] {
            return Err(Error::NonIncreasingSites { index: i });
        }
    }
    for (k, s) in p.end_slopes.iter().enumerate() {
        if s.is_some_and(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                field: "end_slopes",
                index: k,
            });
        }
    }
    for (side, b, name) in [
        (Side::Lower, &p.lower, "lower.pieces"),
        (Side::Upper, &p.upper, "upper.pieces"),
    ] {
        match b {
            Bound::None => {}
            Bound::Pieces(c) => {
                if c.len() != n - 1 {
                    return Err(Error::LengthMismatch {
                        field: name,
                        expected: n - 1,
                        found: c.len(),
                    });
                }
                if let Some(index) = c.iter().position(|x| x.iter().any(|v| !v.is_finite())) {
                    return Err(Error::NonFinite { field: name, index });
                }
                if let Some(index) = c
                    .iter()
                    .position(|x| x.iter().any(|v| v.abs() > MAX_MAGNITUDE))
                {
                    return Err(Error::TooLarge {
                        field: name,
                        index,
                        max: MAX_MAGNITUDE,
                    });
                }
            }
            Bound::Polyline(v) => {
                let name = if side == Side::Lower {
                    "lower.polyline"
                } else {
                    "upper.polyline"
                };
                if let Some(index) = v.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
                    return Err(Error::NonFinite { field: name, index });
                }
                if let Some(index) = v
                    .iter()
                    .position(|x| x.iter().any(|c| c.abs() > MAX_MAGNITUDE))
                {
                    return Err(Error::TooLarge {
                        field: name,
                        index,
                        max: MAX_MAGNITUDE,
                    });
                }
                if v.len() < 2 {
                    return Err(Error::PolylineDoesNotCover { side });
                }
                for k in 1..v.len() {
                    if v[k][0] <= v[k - 1][0] {
                        return Err(Error::NonIncreasingPolyline { side, index: k });
                    }
                }
                if v[0][0] > p.t[0] || v[v.len() - 1][0] < p.t[n - 1] {
                    return Err(Error::PolylineDoesNotCover { side });
                }
            }
        }
    }
    Ok(())
}

/// The outer problem on a grid.
struct Outer {
    cells: Vec<RealCell>,
    norm: Vec<Cell>,
    /// Fixed value at grid point j (data), or the box of a free value.
    fixed_val: Vec<Option<f64>>,
    boxes: Vec<(f64, f64)>,
    fixed_slope: Vec<Option<f64>>,
    /// Kink cones of the lower and upper bound at each grid point (slope intervals).
    cones: Vec<[(f64, f64); 2]>,
    sv: Vec<Option<usize>>,
    zv: Vec<Option<usize>>,
    nvar: usize,
    tol: CellTol,
    pruning: Pruning,
    /// Factor from each unknown's gradient component to the caller's frame (see `frame.rs`):
    /// c/λ² for slopes, c/λ³ for grid values (ones when solving in the caller's frame).
    unit: Vec<f64>,
}

struct Eval {
    phi: f64,
    grad: Vec<f64>,
    sols: Vec<CellSolution>,
}

pub(crate) type Hints = Vec<Option<(Shape, [f64; 2])>>;

impl Outer {
    fn unpack(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let m = self.fixed_val.len();
        let mut s = vec![0.0; m];
        let mut z = vec![0.0; m];
        for j in 0..m {
            s[j] = match (self.fixed_val[j], self.sv[j]) {
                (Some(v), _) => v,
                (None, Some(k)) => x[k],
                _ => 0.0,
            };
            z[j] = match (self.fixed_slope[j], self.zv[j]) {
                (Some(v), _) => v,
                (None, Some(k)) => x[k],
                _ => 0.0,
            };
        }
        (s, z)
    }

    fn theta(&self, j: usize, s: &[f64], z: &[f64]) -> [f64; 4] {
        let h = self.cells[j].h;
        [s[j], h * z[j], s[j + 1], h * z[j + 1]]
    }

    /// The box of every unknown at x: free grid values have their strip interval; the slope at
    /// a grid point whose value sits on a bound is confined to the bound's kink cone (f − e ≥ 0
    /// next to a contact at a vertex needs e'(τ+) ≤ f'(τ) ≤ e'(τ−); likewise for d). Elsewhere
    /// slopes are free.
    fn var_boxes(&self, x: &[f64]) -> Vec<Option<(f64, f64)>> {
        let mut b = vec![None; x.len()];
        for (j, v) in self.sv.iter().enumerate() {
            if let Some(k) = *v {
                let (lo, hi) = self.boxes[j];
                b[k] = Some((lo, hi));
                if let Some(kz) = self.zv[j] {
                    if x[k] <= lo {
                        b[kz] = Some(self.cones[j][0]);
                    } else if x[k] >= hi {
                        b[kz] = Some(self.cones[j][1]);
                    }
                }
            }
        }
        b
    }

    /// Projection on the (x-dependent) boxes: values first, then the slopes they confine.
    fn project(&self, x: &mut [f64]) {
        for (j, v) in self.sv.iter().enumerate() {
            if let Some(k) = *v {
                let (lo, hi) = self.boxes[j];
                x[k] = clamp_safe(x[k], lo, hi);
            }
        }
        let b = self.var_boxes(x);
        for j in 0..self.zv.len() {
            if let (Some(kz), Some(_)) = (self.zv[j], self.sv[j]) {
                if let Some((lo, hi)) = b[kz] {
                    if lo <= hi {
                        x[kz] = clamp_safe(x[kz], lo, hi);
                    }
                }
            }
        }
    }

    fn var_ids(&self, j: usize) -> [Option<usize>; 4] {
        [self.sv[j], self.zv[j], self.sv[j + 1], self.zv[j + 1]]
    }

    /// Φ and ∇Φ (and the banded Hessian when `hess`). Err(cell) when a cell has no feasible
    /// candidate.
    fn eval(
        &self,
        x: &[f64],
        hints: &mut Hints,
        hess: Option<&mut Band>,
        stats: &mut CellStats,
        solves: &mut usize,
    ) -> Result<Eval, usize> {
        let (s, z) = self.unpack(x);
        let mut phi = 0.0;
        let mut grad = vec![0.0; self.nvar];
        let mut sols = Vec::with_capacity(self.cells.len());
        let mut hb = hess;
        for j in 0..self.cells.len() {
            let th = self.theta(j, &s, &z);
            *solves += 1;
            let sol = solve_cell(&self.norm[j], &th, &self.tol, self.pruning, hints[j], stats)
                .ok_or(j)?;
            hints[j] = Some((sol.shape, sol.tau));
            let h = self.cells[j].h;
            let h3 = h * h * h;
            let dscale = [1.0, h, 1.0, h];
            phi += sol.energy / h3;
            let g = sol.pw.grad();
            let ids = self.var_ids(j);
            for a in 0..4 {
                if let Some(k) = ids[a] {
                    grad[k] += g[a] * dscale[a] / h3;
                }
            }
            if let Some(band) = hb.as_deref_mut() {
                let hn = hessian(&self.norm[j], &th, &sol);
                for a in 0..4 {
                    for b in 0..=a {
                        if let (Some(ka), Some(kb)) = (ids[a], ids[b]) {
                            let v = hn[a][b] * dscale[a] * dscale[b] / h3;
                            band.add(ka, kb, if ka == kb && a != b { 2.0 * v } else { v });
                        }
                    }
                }
            }
            sols.push(sol);
        }
        Ok(Eval { phi, grad, sols })
    }
}

/// Slopes of the cubic spline through (t, y): natural ends, or the given end slopes.
pub(crate) fn spline_slopes(t: &[f64], y: &[f64], ends: [Option<f64>; 2]) -> Vec<f64> {
    let n = t.len();
    // tridiagonal system a z_{i-1} + b z_i + c z_{i+1} = r
    let mut a = vec![0.0; n];
    let mut b = vec![0.0; n];
    let mut c = vec![0.0; n];
    let mut r = vec![0.0; n];
    let hs: Vec<f64> = (0..n - 1).map(|i| t[i + 1] - t[i]).collect();
    let ds: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / hs[i]).collect();
    for i in 1..n - 1 {
        a[i] = 2.0 / hs[i - 1];
        b[i] = 4.0 * (1.0 / hs[i - 1] + 1.0 / hs[i]);
        c[i] = 2.0 / hs[i];
        r[i] = 6.0 * ds[i - 1] / hs[i - 1] + 6.0 * ds[i] / hs[i];
    }
    match ends[0] {
        Some(v) => {
            b[0] = 1.0;
            r[0] = v;
        }
        None => {
            b[0] = 4.0 / hs[0];
            c[0] = 2.0 / hs[0];
            r[0] = 6.0 * ds[0] / hs[0];
        }
    }
    match ends[1] {
        Some(v) => {
            b[n - 1] = 1.0;
            r[n - 1] = v;
        }
        None => {
            a[n - 1] = 2.0 / hs[n - 2];
            b[n - 1] = 4.0 / hs[n - 2];
            r[n - 1] = 6.0 * ds[n - 2] / hs[n - 2];
        }
    }
    // Thomas algorithm (diagonally dominant)
    for i in 1..n {
        let w = a[i] / b[i - 1];
        b[i] -= w * c[i - 1];
        r[i] -= w * r[i - 1];
    }
    let mut zs = vec![0.0; n];
    zs[n - 1] = r[n - 1] / b[n - 1];
    for i in (0..n - 1).rev() {
        zs[i] = (r[i] - c[i] * zs[i + 1]) / b[i];
    }
    zs
}

fn hermite_eval(t0: f64, t1: f64, y0: f64, y1: f64, z0: f64, z1: f64, t: f64) -> (f64, f64) {
    let h = t1 - t0;
    let d = (y1 - y0) / h;
    let c2 = (3.0 * d - 2.0 * z0 - z1) / h;
    let c3 = (z0 + z1 - 2.0 * d) / (h * h);
    let s = t - t0;
    (
        y0 + s * (z0 + s * (c2 + s * c3)),
        z0 + s * (2.0 * c2 + 3.0 * s * c3),
    )
}

/// Solves the strip problem.
///
/// The solver works on the normalized problem (sites over a unit-order range starting at 0, the
/// line through the first and last data point subtracted, values divided by the value scale V;
/// see the crate documentation), so the answer is equivariant under t ↦ t₀ + λt, values ↦ c·v
/// and adding a line, and every tolerance is relative to V or the site range. The returned
/// pieces are checked against the strip in the caller's frame (exact extrema of every cubic
/// piece): a violation above [`RESULT_FEASIBILITY_TOL`]·V plus the rounding allowance
/// [`ROUNDING_TOL`]·M (M the magnitude of the values, see [`Solution::violation`]) is an
/// [`Error::StripViolated`], never an answer.
///
/// # Errors
/// Invalid input (lengths, non-finite numbers, non-increasing sites or polylines, data outside
/// the bounds, an empty strip) and an interval without a feasible candidate give an [`Error`]
/// naming the field or interval; numbers too badly scaled for double precision give
/// [`Error::Overflow`]; running out of iterations gives [`Error::NotConverged`].
pub fn solve(problem: &Problem, opts: &Options) -> Result<Solution, Error> {
    validate(problem)?;
    let frame = Frame::of(problem)?;
    let normalized = frame.forward(problem)?;
    let sol = solve_normalized(problem, &normalized, &frame, opts).map_err(|e| match e {
        Error::DataOutsideBounds {
            index,
            interval,
            side,
            by,
        } => Error::DataOutsideBounds {
            index,
            interval,
            side,
            by: by * frame.c,
        },
        Error::EmptyStrip { interval, t } => Error::EmptyStrip {
            interval,
            t: frame.time(t),
        },
        other => other,
    })?;
    let finite = sol.energy.is_finite()
        && sol.slopes.iter().all(|z| z.is_finite())
        && sol.coefficients.iter().flatten().all(|c| c.is_finite())
        && sol.breaks.iter().all(|b| b.is_finite());
    if !finite {
        return Err(Error::Overflow);
    }
    let mut sol = sol;
    let tolerance = RESULT_FEASIBILITY_TOL * frame.scale + ROUNDING_TOL * frame.magnitude;
    // the pieces must join (each starts at its exact value): coefficients c·v/λ^k that
    // underflow (values tiny against the site scale) break this, and the answer would not
    // interpolate
    let last = sol.coefficients.len() - 1;
    for j in 0..=last {
        let (k, h) = (&sol.coefficients[j], sol.breaks[j + 1] - sol.breaks[j]);
        let (end, slope, _) = crate::cell::cubic3(k, h);
        // the end value carries the rounding of its terms c_k h^k and of the abscissa (steep
        // next to short spans: slope × ulp(t))
        let terms = k[0].abs()
            + h * (k[1].abs() + h * (k[2].abs() + h * k[3].abs()))
            + slope.abs() * sol.breaks[j + 1].abs();
        let next = if j < last {
            Some(sol.coefficients[j + 1][0])
        } else {
            let n = problem.y.len();
            (!sol.shifted_data.contains(&(n - 1))).then_some(problem.y[n - 1])
        };
        if let Some(next) = next {
            let by = (end - next).abs();
            let tolerance = tolerance + ROUNDING_TOL * terms;
            if by.is_nan() || by > tolerance {
                return Err(Error::Discontinuous {
                    at: sol.breaks[j + 1],
                    by,
                    tolerance,
                });
            }
        }
    }
    if let Some((by, interval, side)) = worst_violation(problem, &sol) {
        sol.violation = by;
        if by.is_nan() || by > tolerance {
            return Err(Error::StripViolated {
                interval,
                side,
                by,
                tolerance,
            });
        }
    }
    Ok(sol)
}

/// Solves `q`, the normalized form of `problem` in `frame`, and returns the solution in the
/// caller's frame.
fn solve_normalized(
    problem: &Problem,
    q: &Problem,
    frame: &Frame,
    opts: &Options,
) -> Result<Solution, Error> {
    let Setup {
        mut outer,
        grid,
        x0: x,
        shifted,
    } = setup(q, opts, frame.scale / frame.c)?;
    let ef = frame.energy_factor();
    for j in 0..grid.len() {
        if let Some(k) = outer.sv[j] {
            outer.unit[k] = ef / frame.c;
        }
        if let Some(k) = outer.zv[j] {
            outer.unit[k] = ef * frame.lam / frame.c;
        }
    }
    let m = grid.len();
    let mut stats = CellStats::default();
    let mut solves = 0usize;
    let mut hints: Hints = vec![None; m - 1];
    // the natural spline's slopes may lie outside Φ's domain (hair-thin strips, very short
    // spans): then the first alternative start inside it
    let mut x = x;
    let inside = |x: &[f64], stats: &mut CellStats, solves: &mut usize| {
        outer
            .eval(x, &mut vec![None; m - 1], None, stats, solves)
            .is_ok()
    };
    if !inside(&x, &mut stats, &mut solves) {
        if let Some(alt) = alternative_starts(&outer, &grid, &x)
            .into_iter()
            .find(|alt| inside(alt, &mut stats, &mut solves))
        {
            x = alt;
        }
    }
    let (decrement, iterations, ev) = match opts.method {
        Method::Newton => newton(&outer, x, opts, &mut hints, &mut stats, &mut solves)?,
        Method::Bfgs => {
            if outer.sv.iter().any(Option::is_some) {
                return Err(Error::BadOption { name: "method" });
            }
            crate::bfgs::bfgs(&outer_ref(&outer), x, opts, &mut stats, &mut solves)?
        }
    };
    let pg = projected_grad(&outer, &ev.1, &ev.2);
    let gradient_norm = pg
        .iter()
        .zip(&outer.unit)
        .map(|(g, u)| (g * u) * (g * u))
        .sum::<f64>()
        .sqrt();
    // abscissae in the caller's frame, placed from their grid point (a break or knot inside a
    // short interval keeps its offset exactly; t₀ + λu would round it to ulp(u))
    let gt = caller_grid(problem, q, frame, &grid);
    let place = |j: usize, offset: f64| gt[j] + frame.lam * offset;
    // how far the rounded abscissa lies from the exact one, in normalized units: pieces are
    // re-expanded about the abscissa actually returned (a bound of slope 1e12 moves by 2.6e-4
    // over the 2e-16 rounding of a break near t = 2.5)
    let error =
        |j: usize, offset: f64| ((place(j, offset) - gt[j]) - frame.lam * offset) / frame.lam;
    let mut sol = assemble(
        &place, &error, &outer, &grid, &ev.0, ev.1, pg, iterations, solves, stats, shifted,
    )?;
    sol.newton_decrement = decrement;
    let mut sol = to_caller(problem, frame, &grid, sol);
    sol.gradient_norm = gradient_norm;
    Ok(sol)
}

/// Starting points other than the natural spline, tried in turn when its slopes lie outside Φ's
/// domain: the slopes at the data sites replaced by Bessel's three-point slopes, by the
/// Fritsch–Carlson slopes (weighted harmonic means of the chord slopes, zero at extrema) and by
/// the slopes of the data polygon on either side (prescribed end slopes and free grid values
/// stay as they are).
fn alternative_starts(o: &Outer, grid: &[(f64, Option<usize>)], x0: &[f64]) -> Vec<Vec<f64>> {
    let sites: Vec<(usize, f64, f64)> = grid
        .iter()
        .enumerate()
        .filter_map(|(j, g)| Some((j, g.0, o.fixed_val[j]?)))
        .filter(|(j, _, _)| grid[*j].1.is_some())
        .collect();
    let n = sites.len();
    if n < 2 {
        return Vec::new();
    }
    let h: Vec<f64> = (0..n - 1).map(|i| sites[i + 1].1 - sites[i].1).collect();
    let d: Vec<f64> = (0..n - 1)
        .map(|i| (sites[i + 1].2 - sites[i].2) / h[i])
        .collect();
    let interior = |f: &dyn Fn(usize) -> f64| -> Vec<f64> {
        (0..n)
            .map(|i| match i {
                0 => d[0],
                _ if i == n - 1 => d[n - 2],
                _ => f(i),
            })
            .collect()
    };
    let bessel = interior(&|i| (h[i] * d[i - 1] + h[i - 1] * d[i]) / (h[i - 1] + h[i]));
    let fritsch_carlson = interior(&|i| {
        if d[i - 1] * d[i] <= 0.0 {
            0.0
        } else {
            let (w1, w2) = (2.0 * h[i] + h[i - 1], h[i] + 2.0 * h[i - 1]);
            (w1 + w2) / (w1 / d[i - 1] + w2 / d[i])
        }
    });
    let left = interior(&|i| d[i - 1]);
    let right = interior(&|i| d[i]);
    [bessel, fritsch_carlson, left, right]
        .into_iter()
        .map(|z| {
            let mut x = x0.to_vec();
            for (k, (j, _, _)) in sites.iter().enumerate() {
                if let Some(v) = o.zv[*j] {
                    x[v] = z[k];
                }
            }
            x
        })
        .collect()
}

/// The grid in the caller's frame: data sites and polyline vertices exactly as given, other
/// points t₀ + λu.
fn caller_grid(p: &Problem, q: &Problem, fr: &Frame, grid: &[(f64, Option<usize>)]) -> Vec<f64> {
    let vertex = |u: f64| -> Option<f64> {
        for (bq, bp) in [(&q.lower, &p.lower), (&q.upper, &p.upper)] {
            if let (Bound::Polyline(vq), Bound::Polyline(vp)) = (bq, bp) {
                if let Some(k) = vq.iter().position(|v| v[0].to_bits() == u.to_bits()) {
                    return Some(vp[k][0]);
                }
            }
        }
        None
    };
    grid.iter()
        .map(|(u, i)| match i {
            Some(i) => p.t[*i],
            None => vertex(*u).unwrap_or_else(|| fr.time(*u)),
        })
        .collect()
}

/// Maps the values of a solution of the normalized problem (abscissae already placed in the
/// caller's frame by `assemble`) back: values ℓ(t) + c·v (unshifted data values exactly),
/// slopes ℓ' + c·z/λ (prescribed end slopes exactly), cubic coefficients c_k·c/λ^k (plus ℓ in
/// the first two), energies ·c²/λ³.
fn to_caller(p: &Problem, fr: &Frame, grid: &[(f64, Option<usize>)], s: Solution) -> Solution {
    // the exact data value at grid point j when it is a data site not moved by Remark 4.2
    let mut shifted = vec![false; p.y.len()];
    for &i in &s.shifted_data {
        shifted[i] = true;
    }
    let data_at = |j: usize| grid[j].1.filter(|i| !shifted[*i]).map(|i| p.y[i]);
    let at_grid = |t: f64| {
        s.grid
            .binary_search_by(|g| g.total_cmp(&t))
            .ok()
            .and_then(data_at)
    };
    let (c, lam) = (fr.c, fr.lam);
    let r = c / lam;
    let coefficients = s
        .coefficients
        .iter()
        .zip(&s.breaks)
        .map(|(k, t)| {
            let c0 = at_grid(*t).unwrap_or_else(|| fr.value(*t, k[0]));
            [c0, fr.b + r * k[1], r * k[2] / lam, r * k[3] / lam / lam]
        })
        .collect();
    let grid_values = s
        .grid_values
        .iter()
        .enumerate()
        .map(|(j, v)| data_at(j).unwrap_or_else(|| fr.value(s.grid[j], *v)))
        .collect();
    let n = s.slopes.len();
    let slopes = s
        .slopes
        .iter()
        .enumerate()
        .map(|(i, z)| match (i, p.end_slopes) {
            (0, [Some(v), _]) => v,
            (i, [_, Some(v)]) if i + 1 == n => v,
            _ => fr.slope(*z),
        })
        .collect();
    let ef = fr.energy_factor();
    let energy = s.energy * ef;
    Solution {
        coefficients,
        slopes,
        grid_values,
        energy,
        norm: energy.sqrt(),
        newton_decrement: s.newton_decrement * ef,
        ..s
    }
}

/// The largest violation of the strip by the pieces of `s` (exact extrema of the cubic
/// difference on every piece, split at polyline vertices), with its data interval and side;
/// `None` without bounds.
fn worst_violation(p: &Problem, s: &Solution) -> Option<(f64, usize, Side)> {
    let n = p.t.len();
    let mut worst: Option<(f64, usize, Side)> = None;
    for j in 0..s.coefficients.len() {
        let (x0, x1) = (s.breaks[j], s.breaks[j + 1]);
        if x1 <= x0 {
            continue;
        }
        let i = p.t.partition_point(|t| *t <= x0).clamp(1, n - 1) - 1;
        for (side, b) in [(Side::Lower, &p.lower), (Side::Upper, &p.upper)] {
            let mut cuts = vec![x0];
            if let Bound::Polyline(v) = b {
                cuts.extend(v.iter().map(|q| q[0]).filter(|x| *x > x0 && *x < x1));
            }
            cuts.push(x1);
            for w in cuts.windows(2) {
                let g = match b {
                    Bound::None => continue,
                    Bound::Pieces(pc) => shift_cubic(&pc[i], w[0] - p.t[i]),
                    Bound::Polyline(v) => {
                        let (ga, gb) = (polyline_at(v, w[0]), polyline_at(v, w[1]));
                        [ga, (gb - ga) / (w[1] - w[0]), 0.0, 0.0]
                    }
                };
                let f = shift_cubic(&s.coefficients[j], w[0] - x0);
                let d: [f64; 4] = std::array::from_fn(|k| match side {
                    Side::Lower => f[k] - g[k],
                    Side::Upper => g[k] - f[k],
                });
                let by = -crate::cell::cubic_min(&d, w[1] - w[0]);
                if worst.is_none_or(|(m, _, _)| by > m || by.is_nan()) {
                    worst = Some((by, i, side));
                }
            }
        }
    }
    worst
}

/// `x` clamped to [lo, hi]; unlike `f64::clamp` never panics: when the bounds are NaN or
/// crossed (only possible after an overflow) `x` is returned unchanged, and the overflow is
/// reported by the final finiteness check of [`solve`].
fn clamp_safe(x: f64, lo: f64, hi: f64) -> f64 {
    if lo <= hi {
        x.clamp(lo, hi)
    } else {
        x
    }
}

/// Largest magnitude accepted for any input number: squares and cubes of differences of such
/// numbers stay far from overflow, leaving room for badly spaced sites.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// Φ and ∇Φ at the unknowns `x` (slopes at the data sites without prescribed end slopes, in
/// order; for polyline bounds also the free grid values, interleaved as (s_j, z_j)), and the
/// starting point (natural/clamped spline). For tests of the analytic gradient.
///
/// # Errors
/// As [`solve`]; `NoFeasibleCandidate` when x is outside Φ's domain.
pub fn objective(problem: &Problem, x: Option<&[f64]>) -> Result<(f64, Vec<f64>, Vec<f64>), Error> {
    let vscale = 1.0 + problem.y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let st = setup(problem, &Options::default(), vscale)?;
    let x = x.map_or_else(|| st.x0.clone(), <[f64]>::to_vec);
    if x.len() != st.outer.nvar {
        return Err(Error::LengthMismatch {
            field: "x",
            expected: st.outer.nvar,
            found: x.len(),
        });
    }
    let mut hints: Hints = vec![None; st.grid.len() - 1];
    let e = st
        .outer
        .eval(&x, &mut hints, None, &mut CellStats::default(), &mut 0)
        .map_err(|interval| Error::NoFeasibleCandidate { interval })?;
    Ok((e.phi, e.grad, st.x0))
}

struct Setup {
    outer: Outer,
    grid: Vec<(f64, Option<usize>)>,
    x0: Vec<f64>,
    shifted: Vec<usize>,
}

/// The grid, cells and starting point of `problem`; `vscale` is its value scale (tolerances on
/// values are relative to it).
fn setup(problem: &Problem, opts: &Options, vscale: f64) -> Result<Setup, Error> {
    validate(problem)?;
    if !(0.0..0.5).contains(&opts.boundary_margin) {
        return Err(Error::BadOption {
            name: "boundary_margin",
        });
    }
    if opts.gradient_tol.is_nan() || opts.gradient_tol <= 0.0 {
        return Err(Error::BadOption {
            name: "gradient_tol",
        });
    }
    let t = &problem.t;
    let n = t.len();
    let range = t[n - 1] - t[0];
    // grid: data sites plus interior polyline vertices
    let mut grid: Vec<(f64, Option<usize>)> =
        t.iter().enumerate().map(|(i, &v)| (v, Some(i))).collect();
    for b in [&problem.lower, &problem.upper] {
        if let Bound::Polyline(p) = b {
            for v in p {
                if v[0] > t[0] && v[0] < t[n - 1] {
                    let k = t.partition_point(|x| *x < v[0]);
                    let near = (t[k] - v[0]).abs().min((v[0] - t[k - 1]).abs());
                    if near > 1e-12 * range {
                        grid.push((v[0], None));
                    }
                }
            }
        }
    }
    grid.sort_by(|a, b| a.0.total_cmp(&b.0));
    // a polyline vertex within 1e-12 of the range of a site (or of another vertex) is merged
    // into it, keeping the site's abscissa; two data sites are never merged (they are distinct,
    // however close: merging them paired cells with the wrong data intervals)
    grid.dedup_by(|a, b| {
        if (a.0 - b.0).abs() <= 1e-12 * range && (a.1.is_none() || b.1.is_none()) {
            if b.1.is_none() {
                *b = *a;
            }
            true
        } else {
            false
        }
    });
    let m = grid.len();
    let mut cells = Vec::with_capacity(m - 1);
    for j in 0..m - 1 {
        let a = grid[j].0;
        let h = grid[j + 1].0 - a;
        let interval = t.partition_point(|x| *x <= a).clamp(1, n - 1) - 1;
        cells.push(RealCell {
            a,
            h,
            lower: cell_bound(&problem.lower, interval, t[interval], a, h),
            upper: cell_bound(&problem.upper, interval, t[interval], a, h),
            interval,
        });
    }
    // strip width > 0 in every cell (exact minimum of the cubic d − e)
    for c in &cells {
        if let (Some(lo), Some(up)) = (&c.lower, &c.upper) {
            let d = [up[0] - lo[0], up[1] - lo[1], up[2] - lo[2], up[3] - lo[3]];
            let mut cand = vec![0.0, c.h];
            cand.extend(
                roots::find_roots_quadratic(3.0 * d[3], 2.0 * d[2], d[1])
                    .as_ref()
                    .iter()
                    .filter(|s| **s > 0.0 && **s < c.h),
            );
            for s in cand {
                if crate::cell::cubic3(&d, s).0 <= 0.0 {
                    return Err(Error::EmptyStrip {
                        interval: c.interval,
                        t: c.a + s,
                    });
                }
            }
        }
    }
    let on_bound_tol = 1e-12 * vscale;
    // data feasibility (condition (4)) and Remark 4.2
    let mut y = problem.y.clone();
    let mut shifted = Vec::new();
    let mut fixed_val: Vec<Option<f64>> = vec![None; m];
    let mut boxes = vec![(f64::NEG_INFINITY, f64::INFINITY); m];
    for j in 0..m {
        // bounds at grid point j from its two cells
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        let mut width = f64::INFINITY;
        let mut interval = 0;
        for (cj, at_end) in [(j.wrapping_sub(1), true), (j, false)] {
            if let Some(c) = cells.get(cj) {
                interval = c.interval;
                let s = if at_end { c.h } else { 0.0 };
                let l = c.lower.map(|g| crate::cell::cubic3(&g, s).0);
                let u = c.upper.map(|g| crate::cell::cubic3(&g, s).0);
                if let Some(l) = l {
                    lo = lo.max(l);
                }
                if let Some(u) = u {
                    hi = hi.min(u);
                }
                if let (Some(l), Some(u)) = (l, u) {
                    width = width.min(u - l);
                }
            }
        }
        let margin = if width.is_finite() {
            opts.boundary_margin * width
        } else {
            opts.boundary_margin * vscale
        };
        match grid[j].1 {
            Some(i) => {
                let mut v = y[i];
                if v < lo - on_bound_tol {
                    return Err(Error::DataOutsideBounds {
                        index: i,
                        interval,
                        side: Side::Lower,
                        by: lo - v,
                    });
                }
                if v > hi + on_bound_tol {
                    return Err(Error::DataOutsideBounds {
                        index: i,
                        interval,
                        side: Side::Upper,
                        by: v - hi,
                    });
                }
                if v < lo + on_bound_tol {
                    v = lo + margin;
                    shifted.push(i);
                } else if v > hi - on_bound_tol {
                    v = hi - margin;
                    shifted.push(i);
                }
                y[i] = v;
                fixed_val[j] = Some(v);
            }
            // problem (10): free grid values stay ε·width inside the strip (with ε = 0 they may
            // touch a bound at a vertex; their slope is then confined to the kink cone)
            None => boxes[j] = (lo + margin, hi - margin),
        }
    }
    let mut cones = vec![[(f64::NEG_INFINITY, f64::INFINITY); 2]; m];
    for (j, cone) in cones.iter_mut().enumerate() {
        let slope_end = |g: &[f64; 4], h: f64| crate::cell::cubic3(g, h).1;
        if j > 0 && j + 1 < m && opts.boundary_margin == 0.0 {
            let (l, r) = (&cells[j - 1], &cells[j]);
            if let (Some(gl), Some(gr)) = (&l.lower, &r.lower) {
                cone[0] = (gr[1], slope_end(gl, l.h));
            }
            if let (Some(gl), Some(gr)) = (&l.upper, &r.upper) {
                cone[1] = (slope_end(gl, l.h), gr[1]);
            }
        }
    }
    let mut fixed_slope = vec![None; m];
    fixed_slope[0] = problem.end_slopes[0];
    fixed_slope[m - 1] = problem.end_slopes[1];
    let mut sv = vec![None; m];
    let mut zv = vec![None; m];
    let mut nvar = 0;
    for j in 0..m {
        if fixed_val[j].is_none() {
            sv[j] = Some(nvar);
            nvar += 1;
        }
        if fixed_slope[j].is_none() {
            zv[j] = Some(nvar);
            nvar += 1;
        }
    }
    let norm: Vec<Cell> = cells
        .iter()
        .map(|c| {
            let sc = |g: [f64; 4]| [g[0], g[1] * c.h, g[2] * c.h * c.h, g[3] * c.h * c.h * c.h];
            Cell {
                lower: c.lower.map(sc),
                upper: c.upper.map(sc),
            }
        })
        .collect();
    let outer = Outer {
        cells,
        norm,
        fixed_val,
        boxes,
        fixed_slope,
        cones,
        sv,
        zv,
        nvar,
        tol: CellTol {
            feas: FEASIBILITY_TOL * vscale,
            c2: CONTACT_TOL,
        },
        pruning: opts.pruning,
        unit: vec![1.0; nvar],
    };
    // initial point: the natural (or clamped) spline through the data
    let z0 = spline_slopes(t, &y, problem.end_slopes);
    let mut x = vec![0.0; nvar];
    for j in 0..m {
        let tj = grid[j].0;
        let i = t.partition_point(|v| *v <= tj).clamp(1, n - 1) - 1;
        let (v, d) = hermite_eval(t[i], t[i + 1], y[i], y[i + 1], z0[i], z0[i + 1], tj);
        if let Some(k) = outer.sv[j] {
            // start strictly inside (every cell is then feasible for any slopes)
            let (lo, hi) = outer.boxes[j];
            let inset = INITIAL_INSET * (hi - lo);
            x[k] = clamp_safe(v, lo + inset, hi - inset);
        }
        if let Some(k) = outer.zv[j] {
            x[k] = match grid[j].1 {
                Some(i) => z0[i],
                None => d,
            };
        }
    }
    Ok(Setup {
        outer,
        grid,
        x0: x,
        shifted,
    })
}

/// Borrowed view for the BFGS module.
pub(crate) struct OuterRef<'a> {
    outer: &'a Outer,
}

fn outer_ref(o: &Outer) -> OuterRef<'_> {
    OuterRef { outer: o }
}

impl OuterRef<'_> {
    /// Φ and ∇Φ at x (Err(cell) when infeasible).
    pub(crate) fn value_grad(
        &self,
        x: &[f64],
        hints: &mut Hints,
        stats: &mut CellStats,
        solves: &mut usize,
    ) -> Result<(f64, Vec<f64>, Vec<CellSolution>), usize> {
        self.outer
            .eval(x, hints, None, stats, solves)
            .map(|e| (e.phi, e.grad, e.sols))
    }
    pub(crate) fn cells(&self) -> usize {
        self.outer.cells.len()
    }
    /// ‖g‖∞ in the caller's frame.
    pub(crate) fn caller_gradient_norm(&self, g: &[f64]) -> f64 {
        g.iter()
            .zip(&self.outer.unit)
            .fold(0.0f64, |m, (g, u)| m.max((g * u).abs()))
    }
}

fn projected_grad(o: &Outer, x: &[f64], g: &[f64]) -> Vec<f64> {
    let boxes = o.var_boxes(x);
    let mut pg = g.to_vec();
    for k in 0..x.len() {
        if let Some((lo, hi)) = boxes[k] {
            let eps = 1e-13 * (1.0 + x[k].abs());
            if (x[k] <= lo + eps && g[k] > 0.0) || (x[k] >= hi - eps && g[k] < 0.0) {
                pg[k] = 0.0;
            }
        }
    }
    pg
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Free grid values start at least this fraction of the strip width inside the strip.
const INITIAL_INSET: f64 = 0.01;
/// Stop when the Newton decrement ½ gᵀH⁻¹g is below this fraction of 1 + Φ and the Newton step
/// below [`STEP_TOL`] (normalized frame: Φ, unknowns and steps are of unit order).
pub const DECREMENT_TOL: f64 = 1e-15;
/// Newton steps below this fraction of 1 + ‖x‖∞ are negligible (with [`DECREMENT_TOL`]).
pub const STEP_TOL: f64 = 1e-12;
/// Once the decrement is below [`DECREMENT_TOL`], full Newton steps are taken without a line
/// search as long as Φ rises by at most this fraction of 1 + |Φ| (its rounding level) …
const PHI_ROUNDING: f64 = 1e-14;
/// … and at most this many of them.
const POLISH_STEPS: usize = 3;
/// Line-search backtracking steps before giving up.
const LINE_SEARCH_STEPS: usize = 60;
/// Armijo sufficient-decrease constant.
const ARMIJO: f64 = 1e-4;

type NewtonOut = (f64, usize, (Vec<CellSolution>, Vec<f64>, Vec<f64>));

/// Projected Newton on the banded Hessian. Returns (x, iterations, (cells, x, gradient)).
fn newton(
    o: &Outer,
    mut x: Vec<f64>,
    opts: &Options,
    hints: &mut Hints,
    stats: &mut CellStats,
    solves: &mut usize,
) -> Result<NewtonOut, Error> {
    let nv = o.nvar;
    let mut band = Band::zeros(nv);
    let mut ev = o
        .eval(&x, hints, Some(&mut band), stats, solves)
        .map_err(|interval| Error::NoFeasibleCandidate { interval })?;
    let g0 = inf_norm(&projected_grad(o, &x, &ev.grad));
    let tol = opts.gradient_tol * (1.0 + g0);
    let mut it = 0;
    let mut polished = 0;
    let mut newton_decrement = 0.0;
    while it < opts.max_iterations {
        let pg = projected_grad(o, &x, &ev.grad);
        if inf_norm(&pg) <= tol || nv == 0 {
            break;
        }
        it += 1;
        // active set: boxed variables at a bound with the gradient pushing outward
        let boxed = o.var_boxes(&x);
        let active: Vec<bool> = (0..nv)
            .map(|k| boxed[k].is_some() && pg[k] == 0.0 && ev.grad[k] != 0.0)
            .collect();
        let mut hb = band.clone();
        for k in 0..nv {
            if active[k] {
                hb.a[k] = [0.0; 4];
                hb.a[k][0] = 1.0;
                for d in 1..=3 {
                    if k + d < nv {
                        hb.a[k + d][d] = 0.0;
                    }
                }
            }
        }
        let rhs: Vec<f64> = (0..nv)
            .map(|k| if active[k] { 0.0 } else { -ev.grad[k] })
            .collect();
        newton_decrement = f64::INFINITY;
        let mut lambda = 0.0;
        let maxdiag =
            hb.a.iter()
                .fold(0.0f64, |m, r| m.max(r[0].abs()))
                .max(1e-300);
        let dir = loop {
            let mut hl = hb.clone();
            for r in hl.a.iter_mut() {
                r[0] += lambda;
            }
            if let Some(d) = hl.solve(&rhs) {
                break d;
            }
            lambda = if lambda == 0.0 {
                1e-12 * maxdiag
            } else {
                lambda * 10.0
            };
            if lambda > 1e6 * maxdiag {
                break rhs.clone();
            }
        };
        // Newton decrement: ½ gᵀH⁻¹g estimates Φ − min Φ; along very stiff directions (contacts
        // next to a grid point) it is the meaningful convergence measure, not ‖g‖. But
        // Φ − min Φ ~ 1e-15 Φ still leaves the unknowns off by up to ~√1e-15 along soft
        // directions, and Φ can no longer see progress there (Armijo tests at rounding level
        // accept or refuse at random). So once the decrement is that small, full Newton steps
        // are taken as long as Φ does not rise beyond rounding (at most POLISH_STEPS of them;
        // Newton converges quadratically), and the solve stops when the step is negligible.
        let mut polish = None;
        if lambda == 0.0 {
            newton_decrement = 0.5 * (0..nv).map(|k| rhs[k] * dir[k]).sum::<f64>();
            if newton_decrement <= DECREMENT_TOL * (1.0 + ev.phi.abs()) {
                if inf_norm(&dir) <= STEP_TOL * (1.0 + inf_norm(&x)) || polished >= POLISH_STEPS {
                    break;
                }
                polished += 1;
                let mut xn: Vec<f64> = (0..nv).map(|k| x[k] + dir[k]).collect();
                o.project(&mut xn);
                let mut h2 = hints.clone();
                match o.eval(&xn, &mut h2, None, stats, solves) {
                    Ok(e) if e.phi <= ev.phi + PHI_ROUNDING * (1.0 + ev.phi.abs()) => {
                        polish = Some((xn, h2, e.phi));
                    }
                    _ => break,
                }
            }
        }
        // projected backtracking line search along the Newton direction; if it cannot decrease
        // Φ (a Hessian that jumps across candidate regions), along the diagonally scaled and
        // then the plain negative gradient
        let diag_dir: Vec<f64> = (0..nv)
            .map(|k| {
                let d = band.a[k][0];
                if active[k] {
                    0.0
                } else {
                    -ev.grad[k] / if d > 0.0 { d } else { 1.0 }
                }
            })
            .collect();
        let grad_dir: Vec<f64> = (0..nv)
            .map(|k| if active[k] { 0.0 } else { -ev.grad[k] })
            .collect();
        let mut accepted = polish;
        for dir in [&dir, &diag_dir, &grad_dir] {
            if accepted.is_some() {
                break;
            }
            let mut alpha = 1.0;
            for _ in 0..LINE_SEARCH_STEPS {
                let mut xn: Vec<f64> = (0..nv).map(|k| x[k] + alpha * dir[k]).collect();
                o.project(&mut xn);
                let mut h2 = hints.clone();
                if let Ok(e) = o.eval(&xn, &mut h2, None, stats, solves) {
                    let dec: f64 = (0..nv).map(|k| ev.grad[k] * (xn[k] - x[k])).sum();
                    if dec < 0.0 && e.phi <= ev.phi + ARMIJO * dec {
                        accepted = Some((xn, h2, e.phi));
                        break;
                    }
                }
                alpha *= 0.5;
            }
            if accepted.is_some() {
                break;
            }
        }
        let Some((xn, h2, _)) = accepted else {
            break; // no further decrease representable: converged to rounding
        };
        x = xn;
        *hints = h2;
        band = Band::zeros(nv);
        ev = o
            .eval(&x, hints, Some(&mut band), stats, solves)
            .map_err(|interval| Error::NoFeasibleCandidate { interval })?;
    }
    // the decrement at the final point (on the free, non-active unknowns)
    let pg = projected_grad(o, &x, &ev.grad);
    let mut hb = band;
    for k in 0..nv {
        if pg[k] == 0.0 {
            hb.a[k] = [0.0; 4];
            hb.a[k][0] = 1.0;
            for d in 1..=3 {
                if k + d < nv {
                    hb.a[k + d][d] = 0.0;
                }
            }
        }
    }
    newton_decrement = match hb.solve(&pg) {
        Some(d) => 0.5 * pg.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>(),
        None => newton_decrement,
    };
    // Out of iterations with neither the gradient nor the decrement (the estimate of Φ − min Φ)
    // converged: an error carrying the best iterate's gradient norm, never a silent answer.
    let gradient_norm = inf_norm(&pg);
    let decrement_ok = newton_decrement <= ACCEPT_DECREMENT * (1.0 + ev.phi.abs());
    if it >= opts.max_iterations && gradient_norm > tol && !decrement_ok {
        return Err(Error::NotConverged {
            iterations: it,
            gradient_norm: pg
                .iter()
                .zip(&o.unit)
                .fold(0.0f64, |m, (g, u)| m.max((g * u).abs())),
        });
    }
    let g = ev.grad.clone();
    Ok((newton_decrement, it, (ev.sols, x, g)))
}

/// Relative Newton decrement below which a solve that ran out of iterations is still accepted
/// (Φ is within this fraction of its minimum: the gradient can stall at kinks of polyline bounds
/// while Φ has converged).
pub const ACCEPT_DECREMENT: f64 = 1e-9;

#[allow(clippy::too_many_arguments)]
fn assemble(
    place: &dyn Fn(usize, f64) -> f64,
    error: &dyn Fn(usize, f64) -> f64,
    o: &Outer,
    grid: &[(f64, Option<usize>)],
    sols: &[CellSolution],
    x: Vec<f64>,
    pg: Vec<f64>,
    iterations: usize,
    solves: usize,
    stats: CellStats,
    shifted: Vec<usize>,
) -> Result<Solution, Error> {
    let (s, z) = o.unpack(&x);
    let mut breaks = Vec::new();
    let mut coefficients = Vec::new();
    let mut extra = Vec::new();
    let mut energy = 0.0;
    let mut uncertified = Vec::new();
    for (j, sol) in sols.iter().enumerate() {
        let c = &o.cells[j];
        let h = c.h;
        energy += sol.energy / (h * h * h);
        if !sol.certified {
            uncertified.push(j);
        }
        let pw = &sol.pw;
        for k in 0..pw.n - 1 {
            breaks.push(place(j, h * pw.x[k]));
            let cn = pw.coeffs(k);
            let piece = [cn[0], cn[1] / h, cn[2] / (h * h), cn[3] / (h * h * h)];
            coefficients.push(shift_cubic(&piece, error(j, h * pw.x[k])));
        }
        let at = |k: usize| place(j, h * sol.tau[k]);
        match sol.shape {
            Shape::Free => {}
            Shape::Touch(sd) => extra.push(ExtraKnot {
                t: at(0),
                kind: KnotKind::Touch(sd),
                interval: j,
            }),
            Shape::Subarc(sd) => {
                extra.push(ExtraKnot {
                    t: at(0),
                    kind: KnotKind::SubarcStart(sd),
                    interval: j,
                });
                extra.push(ExtraKnot {
                    t: at(1),
                    kind: KnotKind::SubarcEnd(sd),
                    interval: j,
                });
            }
            Shape::Pair(sd) => {
                let other = if sd == Side::Lower {
                    Side::Upper
                } else {
                    Side::Lower
                };
                extra.push(ExtraKnot {
                    t: at(0),
                    kind: KnotKind::Touch(sd),
                    interval: j,
                });
                extra.push(ExtraKnot {
                    t: at(1),
                    kind: KnotKind::Touch(other),
                    interval: j,
                });
            }
        }
    }
    breaks.push(place(grid.len() - 1, 0.0));
    // contacts at grid vertices (§4): a free grid value held on its (ε-shrunk) box bound
    for (j, v) in o.sv.iter().enumerate() {
        if let Some(k) = *v {
            let (lo, hi) = o.boxes[j];
            let tol = 1e-12 * (1.0 + x[k].abs());
            let side = if x[k] <= lo + tol {
                Some(Side::Lower)
            } else if x[k] >= hi - tol {
                Some(Side::Upper)
            } else {
                None
            };
            if let Some(side) = side {
                extra.push(ExtraKnot {
                    t: place(j, 0.0),
                    kind: KnotKind::Touch(side),
                    interval: j.min(sols.len() - 1),
                });
            }
        }
    }
    extra.sort_by(|a, b| a.t.total_cmp(&b.t));
    let slopes: Vec<f64> = grid
        .iter()
        .enumerate()
        .filter(|(_, g)| g.1.is_some())
        .map(|(j, _)| z[j])
        .collect();
    let gn = pg.iter().map(|v| v * v).sum::<f64>().sqrt();
    Ok(Solution {
        breaks,
        coefficients,
        slopes,
        grid: (0..grid.len()).map(|j| place(j, 0.0)).collect(),
        grid_values: s,
        shapes: sols.iter().map(|s| s.shape).collect(),
        extra_knots: extra,
        energy,
        norm: energy.sqrt(),
        gradient_norm: gn,
        newton_decrement: f64::NAN,
        iterations,
        cell_solves: solves,
        candidates: stats.candidates,
        shifted_data: shifted,
        uncertified,
        violation: 0.0,
    })
}

/// The bound's value at t inside data interval `interval` (starting at `ti`).
pub(crate) fn bound_value(b: &Bound, interval: usize, ti: f64, t: f64) -> Option<f64> {
    match b {
        Bound::None => None,
        Bound::Pieces(p) => Some(crate::cell::cubic3(&p[interval], t - ti).0),
        Bound::Polyline(p) => Some(polyline_at(p, t)),
    }
}
