//! The extra knots of each candidate shape: all real solutions of its contact equations
//! (touching point: a cubic; subarc: two linear equations; touching pair: a resultant), polished
//! by Newton's method.

use super::candidate::{build, Cell};
use crate::piece::cubic3;
use crate::poly::{det, real_roots, Poly};
use crate::types::Shape;

/// Newton iterations when polishing the extra knots of a candidate.
const POLISH_ITERS: usize = 30;
/// Full Newton steps taken beyond the contact tolerance while they reduce the residual (Newton
/// converges quadratically: one takes 1e-12 to rounding).
const EXTRA_STEPS: usize = 2;

/// The f'' jumps at the extra knots and the cell's largest |f''| (the scale of the contact
/// tolerance).
fn residual(cell: &Cell, th: &[f64; 4], shape: Shape, tau: &[f64; 2]) -> Option<([f64; 2], f64)> {
    let pw = build(cell, th, shape, tau)?;
    Some((pw.jumps2(), pw.f2_max().max(1.0)))
}

/// Solves the contact equations of `shape` by Newton's method from `tau` (finite-difference
/// Jacobian, step halving to keep the knots ordered). Returns the polished knots.
///
/// Newton's method converges quadratically here, so it is run to the rounding level of the f''
/// jumps, not only to `tol`: once the residual is within `tol` of the cell's largest |f''|, full
/// steps are taken while they reduce it (at most [`EXTRA_STEPS`]); one that no longer does means
/// rounding is reached. (Stopping at `tol` left f'' jumping at the extra knots
/// by up to 1e-12 of max|f''| — above rounding, and fed into the sites' jumps through the knots.)
pub(super) fn polish(
    cell: &Cell,
    th: &[f64; 4],
    shape: Shape,
    tau: [f64; 2],
    tol: f64,
) -> Option<[f64; 2]> {
    let k = shape.unknowns();
    let mut t = tau;
    let (mut r, mut scale) = residual(cell, th, shape, &t)?;
    let mut beyond = 0;
    for _ in 0..POLISH_ITERS {
        let rn = r[0].abs().max(r[1].abs());
        if rn == 0.0 || beyond > EXTRA_STEPS {
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
        if rn <= tol * scale {
            // within the tolerance: a full step, kept only when it reduces the residual (else
            // the residual is at its rounding level already)
            beyond += 1;
            let mut tn = t;
            for c in 0..k {
                tn[c] -= step[c];
            }
            match residual(cell, th, shape, &tn) {
                Some((rn2, s2)) if rn2[0].abs().max(rn2[1].abs()) < rn => {
                    t = tn;
                    r = rn2;
                    scale = s2;
                    continue;
                }
                _ => return Some(t),
            }
        }
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

pub(super) fn gap_of(t: &[f64; 2], k: usize, c: usize) -> f64 {
    let lo = if c == 0 { 0.0 } else { t[c - 1] };
    let hi = if c + 1 < k { t[c + 1] } else { 1.0 };
    (t[c] - lo).min(hi - t[c]).max(1e-300)
}

pub(super) fn solve_k(a: &[[f64; 2]; 2], b: &[f64; 2], k: usize) -> Option<[f64; 2]> {
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
pub(super) fn knot_candidates(cell: &Cell, th: &[f64; 4], shape: Shape) -> Vec<[f64; 2]> {
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
