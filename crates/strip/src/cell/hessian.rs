//! Second derivatives of a cell's value φ(θ) by implicit differentiation.

use super::candidate::{build, Cell, CellSolution};
use super::knots::{gap_of, solve_k};

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
