//! Φ of problem (5) on the data sites: Φ(z) = Σ_i φ_i(y_i, z_i, y_{i+1}, z_{i+1}) over the
//! slopes z (those not prescribed), each φ_i the value of the per-interval problem (7)/(8), with
//! ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)) and a tridiagonal Hessian (implicit differentiation of the
//! contact equations in each cell).

use crate::cell::{hessian, solve_cell, Cell, CellSolution, CellStats, CellTol};
use crate::error::Error;
use crate::linalg::Band;
use crate::types::{Pruning, Shape};

/// One data interval in real units.
#[derive(Clone, Debug)]
pub(crate) struct RealCell {
    pub h: f64,
    pub lower: Option<[f64; 4]>,
    pub upper: Option<[f64; 4]>,
}

/// The outer problem.
pub(crate) struct Outer {
    pub(crate) cells: Vec<RealCell>,
    /// The cells on \[0, 1\] (bounds scaled to the interval).
    pub(crate) norm: Vec<Cell>,
    /// The data values.
    pub(crate) y: Vec<f64>,
    /// Prescribed end slopes.
    pub(crate) fixed_slope: Vec<Option<f64>>,
    /// The unknown's index of each slope (`None` where prescribed).
    pub(crate) zv: Vec<Option<usize>>,
    pub(crate) nvar: usize,
    pub(crate) tol: CellTol,
    pub(crate) pruning: Pruning,
    /// Factor from each unknown's gradient component to the caller's frame (see `frame.rs`):
    /// c/λ² (ones when solving in the caller's frame).
    pub(crate) unit: Vec<f64>,
    /// The user's field names of the lower and upper bound (for errors).
    pub(crate) fields: [&'static str; 2],
}

pub(crate) struct Eval {
    pub(crate) phi: f64,
    pub(crate) grad: Vec<f64>,
    pub(crate) sols: Vec<CellSolution>,
    /// max|f''| over the whole solution (normalized frame): the scale of the gradient, whose
    /// components are twice the f'' jumps at the sites.
    pub(crate) f2: f64,
}

/// The C² defect of a solution of the cells: its f'' jumps at the data sites with a free slope
/// (half the gradient of Φ; at a natural end, f'' itself) and at the extra knots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct C2Defect {
    /// The largest jump over max|f''|.
    pub relative: f64,
    /// The largest jump over its rounding level ([`crate::types::C2_ROUNDING`]): at most 1 when
    /// the solution is C² to rounding.
    pub rounding: f64,
}

/// The shape and knots of each cell's last solution, tried first at the next evaluation.
pub(crate) type Hints = Vec<Option<(Shape, [f64; 2])>>;

impl Outer {
    /// The slopes at the sites for the unknowns x.
    pub(crate) fn slopes(&self, x: &[f64]) -> Vec<f64> {
        (0..self.y.len())
            .map(|j| match (self.fixed_slope[j], self.zv[j]) {
                (Some(v), _) => v,
                (None, Some(k)) => x[k],
                _ => 0.0,
            })
            .collect()
    }

    /// Φ and ∇Φ (and the tridiagonal Hessian when `hess`). Err(cell) when a cell has no
    /// feasible candidate.
    pub(crate) fn eval(
        &self,
        x: &[f64],
        hints: &mut Hints,
        hess: Option<&mut Band>,
        stats: &mut CellStats,
        solves: &mut usize,
    ) -> Result<Eval, usize> {
        let z = self.slopes(x);
        let mut phi = 0.0;
        let mut grad = vec![0.0; self.nvar];
        let mut sols = Vec::with_capacity(self.cells.len());
        let mut f2 = 0.0f64;
        let mut hb = hess;
        for j in 0..self.cells.len() {
            let h = self.cells[j].h;
            let th = [self.y[j], h * z[j], self.y[j + 1], h * z[j + 1]];
            *solves += 1;
            let sol = solve_cell(&self.norm[j], &th, &self.tol, self.pruning, hints[j], stats)
                .ok_or(j)?;
            hints[j] = Some((sol.shape, sol.tau));
            let h3 = h * h * h;
            phi += sol.energy / h3;
            f2 = f2.max(sol.pw.f2_max() / (h * h));
            // the unknowns are the slopes, components 1 and 3 of θ (scaled by h)
            let g = sol.pw.grad();
            let ids = [(1, self.zv[j]), (3, self.zv[j + 1])];
            for (a, k) in ids {
                if let Some(k) = k {
                    grad[k] += g[a] * h / h3;
                }
            }
            if let Some(band) = hb.as_deref_mut() {
                let hn = hessian(&self.norm[j], &th, &sol);
                for (a, ka) in ids {
                    for (b, kb) in ids {
                        if let (Some(ka), Some(kb)) = (ka, kb) {
                            if ka >= kb {
                                band.add(ka, kb, hn[a][b] * h * h / h3);
                            }
                        }
                    }
                }
            }
            sols.push(sol);
        }
        Ok(Eval {
            phi,
            grad,
            sols,
            f2,
        })
    }

    /// The C² defect of the cells' solutions `sols` with gradient `grad` (see [`C2Defect`]).
    pub(crate) fn c2_defect(&self, sols: &[CellSolution], grad: &[f64]) -> C2Defect {
        let f2 = sols
            .iter()
            .zip(&self.cells)
            .fold(0.0f64, |m, (s, c)| m.max(s.pw.f2_max() / (c.h * c.h)));
        let (mut relative, mut rounding) = (0.0f64, 0.0f64);
        let mut add = |jump: f64, floor: f64| {
            let jump = jump.abs();
            if jump.is_nan() || floor.is_nan() {
                relative = f64::NAN;
                rounding = f64::NAN;
            } else if !relative.is_nan() {
                relative = relative.max(jump / f2.max(f64::MIN_POSITIVE));
                rounding = rounding.max(if jump == 0.0 { 0.0 } else { jump / floor });
            }
        };
        // the extra knots, in each cell's units (f'' there is h² times the normalized one)
        for (s, c) in sols.iter().zip(&self.cells) {
            let h2 = c.h * c.h;
            let (jumps, floors) = (s.pw.jumps2(), s.pw.jumps2_floor(f2 * h2));
            for k in 0..s.pw.n - 2 {
                add(jumps[k] / h2, floors[k] / h2);
            }
        }
        // the data sites with a free slope: ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+))
        let m = sols.len();
        for (i, zv) in self.zv.iter().enumerate() {
            let Some(k) = *zv else { continue };
            let mut terms = 0.0;
            if i > 0 {
                let (s, h) = (&sols[i - 1], self.cells[i - 1].h);
                terms += s.pw.terms(s.pw.n - 2).1 / (h * h);
            }
            if i < m {
                let (s, h) = (&sols[i], self.cells[i].h);
                terms += s.pw.terms(0).0 / (h * h);
            }
            add(0.5 * grad[k], crate::types::C2_ROUNDING * (f2 + terms));
        }
        C2Defect { relative, rounding }
    }

    /// The error for cell `j` without a feasible candidate (a cubic bound whose solution needs
    /// more than Theorem 2.1's two extra knots there).
    pub(crate) fn no_candidate(&self, j: usize) -> Error {
        let c = &self.cells[j];
        Error::Unsupported {
            field: if c.lower.is_some() {
                self.fields[0]
            } else {
                self.fields[1]
            },
            index: j,
            reason: "no feasible candidate in this interval: a cubic bound whose solution needs more than two extra knots here (Theorem 2.1 enumerates at most two; Remark 3.2)",
        }
    }
}

pub(crate) fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// What both outer methods return.
pub(crate) struct OuterOut {
    /// Newton decrement ½gᵀH⁻¹g at the final point (NaN for BFGS).
    pub decrement: f64,
    /// Iterations.
    pub iterations: usize,
    /// Whether the stopping test was met (else the iteration limit stopped the method).
    pub converged: bool,
    /// The cells' solutions, the unknowns and the gradient at the final point.
    pub sols: Vec<CellSolution>,
    pub x: Vec<f64>,
    pub grad: Vec<f64>,
    /// Φ at the final point.
    pub phi: f64,
}
