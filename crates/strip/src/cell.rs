//! The per-interval problem (7)/(8) of Dontchev–Kolmanovsky §3, on the normalized interval [0, 1].
//!
//! Given Hermite data θ = (y0, z0, y1, z1) and cubic (or linear) bounds g_lower ≤ f ≤ g_upper, the
//! minimizer of ∫₀¹ f''² is a C² piecewise cubic whose extra knots are found by enumerating the
//! candidate shapes of Theorem 2.1. Every candidate is written the same way: knots
//! 0 = x₀ < … < x_k = 1, values and slopes at the knots, a Hermite cubic on each piece. The unknown
//! extra knots τ solve "f'' is continuous at every interior knot" (the contact conditions f = g,
//! f' = g' are built into the knot values and slopes).
//!
//! With w = f − g (g the touched bound, p = w(0), q = w'(0), r = w(1), u = w'(1)), a cubic with a
//! double zero at τ has w''(τ−) = 2(3p + qτ)/τ² from the left and 2(3r − u(1−τ))/(1−τ)² from the
//! right, so:
//! * touching point: (3p + qτ)(1−τ)² = (3r − u(1−τ))τ², a cubic equation (solved with `roots`);
//! * subarc: w has a triple zero at each end, so 3p + qσ₁ = 0 and 3r − u(1−σ₂) = 0 (linear);
//! * touching pair (g₁ at τ₁, then g₂ at τ₂, G = g₂ − g₁, L₁ = τ₁, L₂ = τ₂ − τ₁, L₃ = 1 − τ₂):
//!   (3p + qL₁)L₂² = (3G − G'L₂)L₁² and −G''L₂²L₃² + (4G'L₂ − 6G)L₃² = 2(3r − uL₃)L₂²,
//!   with G, G', G'' taken at τ₂. In the unknowns (L₂, Y = τ₂) the second is a quadratic and the
//!   first a cubic in L₂ with coefficients polynomial in Y; their Sylvester resultant is one
//!   polynomial in Y whose real roots in (0, 1) are isolated by a derivative cascade
//!   ([`crate::poly::real_roots`]); each root gives L₂ from the quadratic, and the pair is polished
//!   by Newton's method on the original two equations.
//!
//! A candidate is *feasible* when the exact minimum of f − g_lower and g_upper − f over every
//! cubic piece is ≥ −tol, and *certified* when in addition f''' jumps up at lower contacts and down
//! at upper contacts: then ∫g''² − ∫f''² = ∫(g−f)''² + 2Σ jump·(g−f)(τ) ≥ 0 for every feasible g,
//! i.e. the candidate is the (unique) minimizer.

use crate::poly::{det, real_roots, Poly};

/// Which bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// The lower bound e.
    Lower,
    /// The upper bound d.
    Upper,
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Side::Lower => "lower",
            Side::Upper => "upper",
        })
    }
}

impl Side {
    fn other(self) -> Side {
        match self {
            Side::Lower => Side::Upper,
            Side::Upper => Side::Lower,
        }
    }
}

/// The candidate shape in one interval (Theorem 2.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Constraints inactive: one Hermite cubic.
    Free,
    /// One touching point on the given bound.
    Touch(Side),
    /// One subarc on the given bound.
    Subarc(Side),
    /// A touching pair: first the given bound, then the other.
    Pair(Side),
}

impl Shape {
    pub(crate) fn unknowns(self) -> usize {
        match self {
            Shape::Free => 0,
            Shape::Touch(_) => 1,
            Shape::Subarc(_) | Shape::Pair(_) => 2,
        }
    }
    pub(crate) const ALL: [Shape; 7] = [
        Shape::Free,
        Shape::Touch(Side::Lower),
        Shape::Touch(Side::Upper),
        Shape::Subarc(Side::Lower),
        Shape::Subarc(Side::Upper),
        Shape::Pair(Side::Lower),
        Shape::Pair(Side::Upper),
    ];
}

/// How much of the candidate enumeration is skipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Pruning {
    /// Every candidate is built; the feasible one of least energy wins.
    None,
    /// The seed's §3 rules: a feasible inactive candidate is the answer; if a touching-point or
    /// subarc candidate is feasible, touching pairs are not examined.
    Seed,
    /// Stop at the first feasible candidate that carries the optimality certificate (f''' jumps
    /// with the right sign at every contact). Default: provably the same answer, fastest.
    #[default]
    Certificate,
}

/// Bounds of one normalized cell: cubic coefficients in σ ∈ [0, 1].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cell {
    pub lower: Option<[f64; 4]>,
    pub upper: Option<[f64; 4]>,
}

impl Cell {
    fn bound(&self, s: Side) -> Option<&[f64; 4]> {
        match s {
            Side::Lower => self.lower.as_ref(),
            Side::Upper => self.upper.as_ref(),
        }
    }
}

/// Value, first and second derivative of a cubic.
pub(crate) fn cubic3(c: &[f64; 4], x: f64) -> (f64, f64, f64) {
    (
        c[0] + x * (c[1] + x * (c[2] + x * c[3])),
        c[1] + x * (2.0 * c[2] + 3.0 * x * c[3]),
        2.0 * c[2] + 6.0 * x * c[3],
    )
}

/// A candidate: knots, values and slopes (Hermite data at every knot), at most four knots.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pw {
    pub n: usize,
    pub x: [f64; 4],
    pub v: [f64; 4],
    pub m: [f64; 4],
}

/// f'' at the left and right end of the Hermite cubic on a piece of length `l`.
#[inline]
pub(crate) fn ends(l: f64, v0: f64, v1: f64, m0: f64, m1: f64) -> (f64, f64) {
    let d = (v1 - v0) / l;
    (
        (6.0 * d - 4.0 * m0 - 2.0 * m1) / l,
        (-6.0 * d + 2.0 * m0 + 4.0 * m1) / l,
    )
}

impl Pw {
    fn piece(&self, j: usize) -> (f64, f64, f64) {
        let l = self.x[j + 1] - self.x[j];
        let (a, b) = ends(l, self.v[j], self.v[j + 1], self.m[j], self.m[j + 1]);
        (l, a, b)
    }
    /// ∫ f''² over [0, 1] (f'' is linear on each piece).
    pub fn energy(&self) -> f64 {
        (0..self.n - 1)
            .map(|j| {
                let (l, a, b) = self.piece(j);
                l / 3.0 * (a * a + a * b + b * b)
            })
            .sum()
    }
    /// Jumps f''(x_j−) − f''(x_j+) at the interior knots.
    pub fn jumps2(&self) -> [f64; 2] {
        let mut r = [0.0; 2];
        for j in 1..self.n - 1 {
            let (_, _, b) = self.piece(j - 1);
            let (_, a, _) = self.piece(j);
            r[j - 1] = b - a;
        }
        r
    }
    /// Jumps f'''(x_j+) − f'''(x_j−) at the interior knots.
    pub fn jumps3(&self) -> [f64; 2] {
        let mut r = [0.0; 2];
        for j in 1..self.n - 1 {
            let (l0, a0, b0) = self.piece(j - 1);
            let (l1, a1, b1) = self.piece(j);
            r[j - 1] = (b1 - a1) / l1 - (b0 - a0) / l0;
        }
        r
    }
    /// Gradient of the energy with respect to (y0, z0, y1, z1):
    /// (2f'''(0+), −2f''(0+), −2f'''(1−), 2f''(1−)).
    pub fn grad(&self) -> [f64; 4] {
        let (l0, a0, b0) = self.piece(0);
        let (l1, a1, b1) = self.piece(self.n - 2);
        [
            2.0 * (b0 - a0) / l0,
            -2.0 * a0,
            -2.0 * (b1 - a1) / l1,
            2.0 * b1,
        ]
    }
    /// Monomial coefficients of piece j in s = x − x_j.
    pub fn coeffs(&self, j: usize) -> [f64; 4] {
        let l = self.x[j + 1] - self.x[j];
        let (v0, v1, m0, m1) = (self.v[j], self.v[j + 1], self.m[j], self.m[j + 1]);
        let d = (v1 - v0) / l;
        [
            v0,
            m0,
            (3.0 * d - 2.0 * m0 - m1) / l,
            (m0 + m1 - 2.0 * d) / (l * l),
        ]
    }
}

/// Builds the candidate of `shape` with extra knots `tau` (None if the knots are out of order).
pub(crate) fn build(cell: &Cell, th: &[f64; 4], shape: Shape, tau: &[f64; 2]) -> Option<Pw> {
    let [y0, z0, y1, z1] = *th;
    let mut pw = Pw {
        n: 2,
        x: [0.0, 1.0, 0.0, 0.0],
        v: [y0, y1, 0.0, 0.0],
        m: [z0, z1, 0.0, 0.0],
    };
    let (g1, g2, x1, x2) = match shape {
        Shape::Free => return Some(pw),
        Shape::Touch(s) => {
            let g = cell.bound(s)?;
            let t = tau[0];
            if !(t > 0.0 && t < 1.0) {
                return None;
            }
            let (gv, gd, _) = cubic3(g, t);
            pw.n = 3;
            pw.x = [0.0, t, 1.0, 0.0];
            pw.v = [y0, gv, y1, 0.0];
            pw.m = [z0, gd, z1, 0.0];
            return Some(pw);
        }
        Shape::Subarc(s) => {
            let g = cell.bound(s)?;
            (g, g, tau[0], tau[1])
        }
        Shape::Pair(s) => (cell.bound(s)?, cell.bound(s.other())?, tau[0], tau[1]),
    };
    if !(x1 > 0.0 && x1 < x2 && x2 < 1.0) {
        return None;
    }
    let (a, ad, _) = cubic3(g1, x1);
    let (b, bd, _) = cubic3(g2, x2);
    pw.n = 4;
    pw.x = [0.0, x1, x2, 1.0];
    pw.v = [y0, a, b, y1];
    pw.m = [z0, ad, bd, z1];
    Some(pw)
}

/// min over [0, l] of the cubic c (in s ∈ [0, l]).
pub(crate) fn cubic_min(c: &[f64; 4], l: f64) -> f64 {
    let mut m = c[0].min(cubic3(c, l).0);
    // critical points: c1 + 2 c2 s + 3 c3 s² = 0
    for s in roots::find_roots_quadratic(3.0 * c[3], 2.0 * c[2], c[1]).as_ref() {
        if *s > 0.0 && *s < l {
            m = m.min(cubic3(c, *s).0);
        }
    }
    m
}

/// Taylor coefficients of the cubic g about x0.
fn shift(g: &[f64; 4], x0: f64) -> [f64; 4] {
    let (v, d1, d2) = cubic3(g, x0);
    [v, d1, 0.5 * d2, g[3]]
}

/// Smallest margin min(f − lower, upper − f) over [0, 1] (exact: extrema of cubics).
pub(crate) fn margin(cell: &Cell, pw: &Pw) -> f64 {
    let mut m = f64::INFINITY;
    for j in 0..pw.n - 1 {
        let l = pw.x[j + 1] - pw.x[j];
        let f = pw.coeffs(j);
        if let Some(g) = &cell.lower {
            let gs = shift(g, pw.x[j]);
            let d = [f[0] - gs[0], f[1] - gs[1], f[2] - gs[2], f[3] - gs[3]];
            m = m.min(cubic_min(&d, l));
        }
        if let Some(g) = &cell.upper {
            let gs = shift(g, pw.x[j]);
            let d = [gs[0] - f[0], gs[1] - f[1], gs[2] - f[2], gs[3] - f[3]];
            m = m.min(cubic_min(&d, l));
        }
    }
    m
}

/// The contact sides at the interior knots of a shape.
fn contacts(shape: Shape) -> [Option<Side>; 2] {
    match shape {
        Shape::Free => [None, None],
        Shape::Touch(s) => [Some(s), None],
        Shape::Subarc(s) => [Some(s), Some(s)],
        Shape::Pair(s) => [Some(s), Some(s.other())],
    }
}

/// The optimality certificate: f''' jumps up at lower contacts, down at upper ones.
fn certified(pw: &Pw, shape: Shape, tol: f64) -> bool {
    let j3 = pw.jumps3();
    contacts(shape).iter().zip(j3).all(|(c, j)| match c {
        None => true,
        Some(Side::Lower) => j >= -tol,
        Some(Side::Upper) => j <= tol,
    })
}

/// Tolerances of the per-interval solver.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CellTol {
    /// Absolute feasibility tolerance on the value scale.
    pub feas: f64,
    /// Relative tolerance on the f'' continuity residual when polishing extra knots.
    pub c2: f64,
}

/// Newton iterations when polishing the extra knots of a candidate.
const POLISH_ITERS: usize = 30;

fn residual(cell: &Cell, th: &[f64; 4], shape: Shape, tau: &[f64; 2]) -> Option<([f64; 2], f64)> {
    let pw = build(cell, th, shape, tau)?;
    let r = pw.jumps2();
    let scale = (0..pw.n - 1).fold(1.0f64, |s, j| {
        let (_, a, b) = pw.piece(j);
        s.max(a.abs()).max(b.abs())
    });
    Some((r, scale))
}

/// Solves the contact equations of `shape` by Newton's method from `tau` (finite-difference
/// Jacobian, step halving to keep the knots ordered). Returns the polished knots.
fn polish(cell: &Cell, th: &[f64; 4], shape: Shape, tau: [f64; 2], tol: f64) -> Option<[f64; 2]> {
    let k = shape.unknowns();
    let mut t = tau;
    let (mut r, mut scale) = residual(cell, th, shape, &t)?;
    for _ in 0..POLISH_ITERS {
        let rn = r[0].abs().max(r[1].abs());
        if rn <= tol * scale {
            return Some(t);
        }
        // Jacobian by central differences
        let mut jac = [[0.0; 2]; 2];
        for c in 0..k {
            let gap = gap_of(&t, k, c);
            let d = 1e-7 * gap;
            let mut tp = t;
            let mut tm = t;
            tp[c] += d;
            tm[c] -= d;
            let (rp, _) = residual(cell, th, shape, &tp)?;
            let (rm, _) = residual(cell, th, shape, &tm)?;
            for row in 0..k {
                jac[row][c] = (rp[row] - rm[row]) / (2.0 * d);
            }
        }
        let step = solve_k(&jac, &r, k)?;
        let mut lam = 1.0;
        let mut ok = false;
        for _ in 0..30 {
            let mut tn = t;
            for c in 0..k {
                tn[c] -= lam * step[c];
            }
            if let Some((rn2, s2)) = residual(cell, th, shape, &tn) {
                if rn2[0].abs().max(rn2[1].abs()) < rn || lam < 1e-6 {
                    t = tn;
                    r = rn2;
                    scale = s2;
                    ok = true;
                    break;
                }
            }
            lam *= 0.5;
        }
        if !ok {
            return None;
        }
    }
    let rn = r[0].abs().max(r[1].abs());
    (rn <= tol * scale * 1e3).then_some(t)
}

fn gap_of(t: &[f64; 2], k: usize, c: usize) -> f64 {
    let lo = if c == 0 { 0.0 } else { t[c - 1] };
    let hi = if c + 1 < k { t[c + 1] } else { 1.0 };
    (t[c] - lo).min(hi - t[c]).max(1e-300)
}

fn solve_k(a: &[[f64; 2]; 2], b: &[f64; 2], k: usize) -> Option<[f64; 2]> {
    match k {
        1 => (a[0][0] != 0.0).then(|| [b[0] / a[0][0], 0.0]),
        2 => {
            let d = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            if d == 0.0 || !d.is_finite() {
                return None;
            }
            Some([
                (b[0] * a[1][1] - a[0][1] * b[1]) / d,
                (a[0][0] * b[1] - a[1][0] * b[0]) / d,
            ])
        }
        _ => Some([0.0; 2]),
    }
}

/// w-data (p, q) at 0 against bound g and (r, u) at 1 against bound g2.
fn wdata(th: &[f64; 4], g: &[f64; 4], g2: &[f64; 4]) -> (f64, f64, f64, f64) {
    let (g0, gd0, _) = cubic3(g, 0.0);
    let (g1, gd1, _) = cubic3(g2, 1.0);
    (th[0] - g0, th[1] - gd0, th[2] - g1, th[3] - gd1)
}

/// Initial guesses for the extra knots of `shape` (all real solutions of its equations).
fn knot_candidates(cell: &Cell, th: &[f64; 4], shape: Shape) -> Vec<[f64; 2]> {
    match shape {
        Shape::Free => vec![[0.0; 2]],
        Shape::Touch(s) => {
            let Some(g) = cell.bound(s) else {
                return vec![];
            };
            let (p, q, r, u) = wdata(th, g, g);
            // (3p + qτ)(1−τ)² − ((3r − u) + uτ)τ² = 0
            let e = Poly::new(&[3.0 * p, q])
                .mul(&Poly::new(&[1.0, -2.0, 1.0]))
                .sub(&Poly::new(&[0.0, 0.0, 3.0 * r - u, u]));
            let c = |k: usize| e.0.get(k).copied().unwrap_or(0.0);
            roots::find_roots_cubic(c(3), c(2), c(1), c(0))
                .as_ref()
                .iter()
                .filter(|t| **t > 0.0 && **t < 1.0)
                .map(|&t| [t, 0.0])
                .collect()
        }
        Shape::Subarc(s) => {
            let Some(g) = cell.bound(s) else {
                return vec![];
            };
            let (p, q, r, u) = wdata(th, g, g);
            if q == 0.0 || u == 0.0 {
                return vec![];
            }
            vec![[-3.0 * p / q, 1.0 - 3.0 * r / u]]
        }
        Shape::Pair(s) => {
            let (Some(g1), Some(g2)) = (cell.bound(s), cell.bound(s.other())) else {
                return vec![];
            };
            pair_candidates(th, g1, g2)
        }
    }
}

/// Touching-pair knots from the resultant (see the module docs).
fn pair_candidates(th: &[f64; 4], g1: &[f64; 4], g2: &[f64; 4]) -> Vec<[f64; 2]> {
    let (p, q, r, u) = wdata(th, g1, g2);
    let gp = Poly::new(g2).sub(&Poly::new(g1));
    let gd = gp.derivative();
    let gdd = gd.derivative();
    let y = Poly::new(&[0.0, 1.0]);
    let l3 = Poly::new(&[1.0, -1.0]);
    let l3s = l3.mul(&l3);
    // Q(L2) = A2 L2² + A1 L2 + A0
    let a2 = gdd
        .mul(&l3s)
        .scale(-1.0)
        .add(&Poly::constant(-6.0 * r))
        .add(&l3.scale(2.0 * u));
    let a1 = gd.mul(&l3s).scale(4.0);
    let a0 = gp.mul(&l3s).scale(-6.0);
    // P(L2) = B3 L2³ + B2 L2² + B1 L2 + B0
    let b3 = gd.sub(&Poly::constant(q));
    let b2 = Poly::new(&[3.0 * p, q])
        .sub(&gp.scale(3.0))
        .sub(&gd.mul(&y).scale(2.0));
    let b1 = gp.mul(&y).scale(6.0).add(&gd.mul(&y).mul(&y));
    let b0 = gp.mul(&y).mul(&y).scale(-3.0);
    let z = Poly::constant(0.0);
    let syl = vec![
        vec![b3.clone(), b2.clone(), b1.clone(), b0.clone(), z.clone()],
        vec![z.clone(), b3.clone(), b2.clone(), b1.clone(), b0.clone()],
        vec![a2.clone(), a1.clone(), a0.clone(), z.clone(), z.clone()],
        vec![z.clone(), a2.clone(), a1.clone(), a0.clone(), z.clone()],
        vec![z.clone(), z, a2.clone(), a1.clone(), a0.clone()],
    ];
    let res = det(&syl);
    let mut out = Vec::new();
    for yv in real_roots(&res, 0.0, 1.0, 1e-10) {
        let (c2, c1, c0) = (a2.eval(yv), a1.eval(yv), a0.eval(yv));
        let cands: Vec<f64> = if c2.abs() <= 1e-14 * (c1.abs() + c0.abs()) {
            if c1 == 0.0 {
                vec![]
            } else {
                vec![-c0 / c1]
            }
        } else {
            roots::find_roots_quadratic(c2, c1, c0).as_ref().to_vec()
        };
        // the common root of Q and P at this Y: both roots of the quadratic and the roots of
        // the cubic serve as starting points (near-degenerate configurations make one of the
        // two numerically unreliable); Newton polishing and validation sort them out
        let mut all = cands;
        all.extend_from_slice(
            roots::find_roots_cubic(b3.eval(yv), b2.eval(yv), b1.eval(yv), b0.eval(yv)).as_ref(),
        );
        for l2 in all {
            if l2 > 0.0 && l2 < yv {
                out.push([yv - l2, yv]);
            }
        }
    }
    out
}

/// The solution of one normalized cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CellSolution {
    pub shape: Shape,
    pub tau: [f64; 2],
    pub pw: Pw,
    pub energy: f64,
    /// Whether the optimality certificate held.
    pub certified: bool,
}

/// Counters of the candidate enumeration (for the pruning statistics).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CellStats {
    pub candidates: usize,
}

/// Solves the cell: enumerates the candidates (after trying `hint`, the previous shape and
/// knots, when given) and returns the best feasible one.
pub(crate) fn solve_cell(
    cell: &Cell,
    th: &[f64; 4],
    tol: &CellTol,
    pruning: Pruning,
    hint: Option<(Shape, [f64; 2])>,
    stats: &mut CellStats,
) -> Option<CellSolution> {
    let cert_tol = |pw: &Pw| 1e-8 * (1.0 + pw.jumps3().iter().fold(0.0f64, |m, j| m.max(j.abs())));
    let try_one = |shape: Shape, t0: [f64; 2], stats: &mut CellStats| -> Option<CellSolution> {
        stats.candidates += 1;
        let t = if shape.unknowns() == 0 {
            t0
        } else {
            polish(cell, th, shape, t0, tol.c2)?
        };
        let pw = build(cell, th, shape, &t)?;
        if margin(cell, &pw) < -tol.feas {
            return None;
        }
        let c = certified(&pw, shape, cert_tol(&pw));
        Some(CellSolution {
            shape,
            tau: t,
            pw,
            energy: pw.energy(),
            certified: c,
        })
    };
    if pruning == Pruning::Certificate {
        if let Some((shape, t0)) = hint {
            if let Some(s) = try_one(shape, t0, stats) {
                if s.certified {
                    return Some(s);
                }
            }
        }
    }
    let mut best: Option<CellSolution> = None;
    let mut single_feasible = false;
    for shape in Shape::ALL {
        if pruning == Pruning::Seed && single_feasible && matches!(shape, Shape::Pair(_)) {
            break;
        }
        for t0 in knot_candidates(cell, th, shape) {
            if let Some(s) = try_one(shape, t0, stats) {
                if pruning == Pruning::Certificate && s.certified {
                    return Some(s);
                }
                if pruning == Pruning::Seed && shape == Shape::Free {
                    return Some(s);
                }
                if matches!(shape, Shape::Touch(_) | Shape::Subarc(_)) {
                    single_feasible = true;
                }
                if best.as_ref().is_none_or(|b| s.energy < b.energy) {
                    best = Some(s);
                }
            }
        }
    }
    best
}

/// Gradient and Hessian of the cell's value φ(θ) at a solution, by implicit differentiation of
/// the contact equations R(τ, θ) = 0: dτ/dθ = −R_τ⁻¹R_θ, ∇²φ = G_θ + G_τ dτ/dθ, where G(τ, θ) is
/// the gradient formula (2f'''(0+), −2f''(0+), −2f'''(1−), 2f''(1−)). The partial derivatives are
/// central differences of these closed-form expressions (not of re-solved cells).
pub(crate) fn hessian(cell: &Cell, th: &[f64; 4], sol: &CellSolution) -> [[f64; 4]; 4] {
    let shape = sol.shape;
    let k = shape.unknowns();
    let t = sol.tau;
    let gr =
        |th: &[f64; 4], t: &[f64; 2]| build(cell, th, shape, t).map(|pw| (pw.grad(), pw.jumps2()));
    let mut g_th = [[0.0; 4]; 4]; // g_th[i][j] = ∂G_i/∂θ_j
    let mut r_th = [[0.0; 4]; 2];
    for j in 0..4 {
        let d = 1e-6 * (1.0 + th[j].abs());
        let mut tp = *th;
        let mut tm = *th;
        tp[j] += d;
        tm[j] -= d;
        let (Some((gp, rp)), Some((gm, rm))) = (gr(&tp, &t), gr(&tm, &t)) else {
            continue;
        };
        for i in 0..4 {
            g_th[i][j] = (gp[i] - gm[i]) / (2.0 * d);
        }
        for i in 0..k {
            r_th[i][j] = (rp[i] - rm[i]) / (2.0 * d);
        }
    }
    if k == 0 {
        return g_th;
    }
    let mut g_t = [[0.0; 2]; 4];
    let mut r_t = [[0.0; 2]; 2];
    for c in 0..k {
        let d = 1e-6 * gap_of(&t, k, c);
        let mut tp = t;
        let mut tm = t;
        tp[c] += d;
        tm[c] -= d;
        let (Some((gp, rp)), Some((gm, rm))) = (gr(th, &tp), gr(th, &tm)) else {
            return g_th;
        };
        for i in 0..4 {
            g_t[i][c] = (gp[i] - gm[i]) / (2.0 * d);
        }
        for i in 0..k {
            r_t[i][c] = (rp[i] - rm[i]) / (2.0 * d);
        }
    }
    let mut h = g_th;
    for j in 0..4 {
        let b = [r_th[0][j], r_th[1][j]];
        if let Some(dt) = solve_k(&r_t, &b, k) {
            // dτ/dθ_j = −dt
            for (i, row) in h.iter_mut().enumerate() {
                for c in 0..k {
                    row[j] -= g_t[i][c] * dt[c];
                }
            }
        }
    }
    // symmetrize (the exact Hessian is symmetric)
    for i in 0..4 {
        for j in 0..i {
            let a = 0.5 * (h[i][j] + h[j][i]);
            h[i][j] = a;
            h[j][i] = a;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tol() -> CellTol {
        CellTol {
            feas: 1e-10,
            c2: 1e-12,
        }
    }

    #[test]
    fn free_cell_energy_matches_closed_form() {
        // math.md §4: ∫f''² = (4/h)(z0²+z0z1+z1²) − (12Δ/h)(z0+z1) + 12Δ²/h, h = 1.
        let cell = Cell {
            lower: None,
            upper: None,
        };
        let th = [0.3, -1.2, 1.1, 0.7];
        let s = solve_cell(
            &cell,
            &th,
            &tol(),
            Pruning::None,
            None,
            &mut CellStats::default(),
        )
        .unwrap();
        let (z0, z1, d) = (th[1], th[3], th[2] - th[0]);
        let e = 4.0 * (z0 * z0 + z0 * z1 + z1 * z1) - 12.0 * d * (z0 + z1) + 12.0 * d * d;
        assert!((s.energy - e).abs() < 1e-12 * e.abs());
        assert_eq!(s.shape, Shape::Free);
    }

    #[test]
    fn touching_point_is_c2_and_tangent() {
        // Lower bound e = 0; data high at the ends with steep inward slopes forces contact.
        let cell = Cell {
            lower: Some([0.0; 4]),
            upper: None,
        };
        let th = [0.2, -2.0, 0.25, 2.0];
        let s = solve_cell(
            &cell,
            &th,
            &tol(),
            Pruning::None,
            None,
            &mut CellStats::default(),
        )
        .unwrap();
        assert!(matches!(
            s.shape,
            Shape::Touch(Side::Lower) | Shape::Subarc(Side::Lower)
        ));
        let j = s.pw.jumps2();
        assert!(j[0].abs() < 1e-9 && j[1].abs() < 1e-9);
        // tangency: value and slope of the bound at the contact
        assert!(s.pw.v[1].abs() < 1e-15 && s.pw.m[1].abs() < 1e-15);
        assert!(margin(&cell, &s.pw) > -1e-12);
        assert!(s.certified);
    }
}

pub(crate) mod internals {
    //! One interval in real units, and the outer objective, for tests and benchmarks.
    use super::*;
    pub use crate::solve::objective;

    /// The solution of one interval \[0, h\] with Hermite data θ = (y0, z0, y1, z1) and bounds
    /// given as cubics in s ∈ \[0, h\].
    #[derive(Clone, Debug)]
    pub struct IntervalSolution {
        /// The shape chosen.
        pub shape: Shape,
        /// Extra knots in \[0, h\].
        pub knots: Vec<f64>,
        /// ∫₀ʰ f''².
        pub energy: f64,
        /// ∂φ/∂(y0, z0, y1, z1).
        pub grad: [f64; 4],
        /// Hessian of φ (implicit differentiation).
        pub hess: [[f64; 4]; 4],
        /// Smallest margin to the bounds.
        pub margin: f64,
        /// Largest |f'' jump| at the extra knots.
        pub c2_residual: f64,
        /// Whether the optimality certificate holds.
        pub certified: bool,
        /// Candidates examined.
        pub candidates: usize,
        /// Piece breaks (in \[0, h\]) and monomial coefficients.
        pub pieces: Vec<(f64, [f64; 4])>,
    }

    /// Solves one interval; `None` when no candidate is feasible.
    pub fn solve_interval(
        h: f64,
        theta: [f64; 4],
        lower: Option<[f64; 4]>,
        upper: Option<[f64; 4]>,
        pruning: Pruning,
    ) -> Option<IntervalSolution> {
        let sc = |g: [f64; 4]| [g[0], g[1] * h, g[2] * h * h, g[3] * h * h * h];
        let cell = Cell {
            lower: lower.map(sc),
            upper: upper.map(sc),
        };
        let th = [theta[0], theta[1] * h, theta[2], theta[3] * h];
        let vscale = 1.0 + theta[0].abs().max(theta[2].abs());
        let tol = CellTol {
            feas: 1e-10 * vscale,
            c2: 1e-12,
        };
        let mut st = CellStats::default();
        let s = solve_cell(&cell, &th, &tol, pruning, None, &mut st)?;
        let hn = hessian(&cell, &th, &s);
        let d = [1.0, h, 1.0, h];
        let h3 = h * h * h;
        let g = s.pw.grad();
        let mut hess = [[0.0; 4]; 4];
        for a in 0..4 {
            for b in 0..4 {
                hess[a][b] = hn[a][b] * d[a] * d[b] / h3;
            }
        }
        let j2 = s.pw.jumps2();
        Some(IntervalSolution {
            shape: s.shape,
            knots: (1..s.pw.n - 1).map(|k| s.pw.x[k] * h).collect(),
            energy: s.energy / h3,
            grad: [g[0] / h3, g[1] * h / h3, g[2] / h3, g[3] * h / h3],
            hess,
            margin: margin(&cell, &s.pw),
            c2_residual: j2[0].abs().max(j2[1].abs()) / (h * h),
            certified: s.certified,
            candidates: st.candidates,
            pieces: (0..s.pw.n - 1)
                .map(|k| {
                    let c = s.pw.coeffs(k);
                    (s.pw.x[k] * h, [c[0], c[1] / h, c[2] / (h * h), c[3] / h3])
                })
                .collect(),
        })
    }
}
