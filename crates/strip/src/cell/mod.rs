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

mod candidate;
mod hessian;
mod knots;

pub(crate) use candidate::{Cell, CellSolution, Pw};
pub(crate) use hessian::hessian;

use crate::piece::{cubic_min, shift};
use crate::types::{Pruning, Shape, Side};
use candidate::build;
use knots::{knot_candidates, polish};

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
