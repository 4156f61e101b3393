//! The per-interval problem (7)/(8) of Dontchev–Kolmanovsky §3 on its own: the least ∫f''² on
//! one interval \[0, h\] with Hermite data f(0) = y0, f'(0) = z0, f(h) = y1, f'(h) = z1 and
//! cubic (or linear) bounds. Its value φ(θ) is the summand of Φ in problem (5); its gradient is
//! (2f'''(0+), −2f''(0+), −2f'''(h−), 2f''(h−)) and its Hessian comes from implicit
//! differentiation of the contact equations. [`crate::solve()`] assembles many of these; this
//! entry point serves users who drive their own outer method (as the seed does with BFGS), and
//! the verification of the gradient formula against finite differences.

use crate::cell::{hessian, margin, solve_cell, Cell, CellStats, CellTol};
use crate::types::{Pruning, Shape};

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
