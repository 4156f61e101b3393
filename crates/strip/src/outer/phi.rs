//! Φ itself: the grid cells, the unknowns (slopes, and values at grid points that are not data
//! sites) with their boxes, and the evaluation of Φ, ∇Φ and the banded Hessian.

use crate::cell::{hessian, solve_cell, Cell, CellSolution, CellStats, CellTol};
use crate::error::Error;
use crate::linalg::Band;
use crate::types::{Pruning, Shape};

/// One grid interval in real units.
#[derive(Clone, Debug)]
pub(crate) struct RealCell {
    pub a: f64,
    pub h: f64,
    pub lower: Option<[f64; 4]>,
    pub upper: Option<[f64; 4]>,
    pub interval: usize,
}

/// The outer problem on a grid.
pub(crate) struct Outer {
    pub(crate) cells: Vec<RealCell>,
    pub(crate) norm: Vec<Cell>,
    /// Fixed value at grid point j (data), or the box of a free value.
    pub(crate) fixed_val: Vec<Option<f64>>,
    pub(crate) boxes: Vec<(f64, f64)>,
    pub(crate) fixed_slope: Vec<Option<f64>>,
    /// Kink cones of the lower and upper bound at each grid point (slope intervals).
    pub(crate) cones: Vec<[(f64, f64); 2]>,
    pub(crate) sv: Vec<Option<usize>>,
    pub(crate) zv: Vec<Option<usize>>,
    pub(crate) nvar: usize,
    pub(crate) tol: CellTol,
    pub(crate) pruning: Pruning,
    /// Factor from each unknown's gradient component to the caller's frame (see `frame.rs`):
    /// c/λ² for slopes, c/λ³ for grid values (ones when solving in the caller's frame).
    pub(crate) unit: Vec<f64>,
    /// The user's field names of the lower and upper bound (for errors).
    pub(crate) fields: [&'static str; 2],
}

pub(crate) struct Eval {
    pub(crate) phi: f64,
    pub(crate) grad: Vec<f64>,
    pub(crate) sols: Vec<CellSolution>,
}

pub(crate) type Hints = Vec<Option<(Shape, [f64; 2])>>;

impl Outer {
    pub(crate) fn unpack(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
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

    pub(crate) fn theta(&self, j: usize, s: &[f64], z: &[f64]) -> [f64; 4] {
        let h = self.cells[j].h;
        [s[j], h * z[j], s[j + 1], h * z[j + 1]]
    }

    /// The box of every unknown at x: free grid values have their strip interval; the slope at
    /// a grid point whose value sits on a bound is confined to the bound's kink cone (f − e ≥ 0
    /// next to a contact at a vertex needs e'(τ+) ≤ f'(τ) ≤ e'(τ−); likewise for d). Elsewhere
    /// slopes are free.
    pub(crate) fn var_boxes(&self, x: &[f64]) -> Vec<Option<(f64, f64)>> {
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
    pub(crate) fn project(&self, x: &mut [f64]) {
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

    pub(crate) fn var_ids(&self, j: usize) -> [Option<usize>; 4] {
        [self.sv[j], self.zv[j], self.sv[j + 1], self.zv[j + 1]]
    }

    /// Φ and ∇Φ (and the banded Hessian when `hess`). Err(cell) when a cell has no feasible
    /// candidate.
    pub(crate) fn eval(
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

/// `x` clamped to [lo, hi]; unlike `f64::clamp` never panics: when the bounds are NaN or
/// crossed (only possible after an overflow) `x` is returned unchanged, and the overflow is
/// reported by the final finiteness check of [`solve`].
pub(crate) fn clamp_safe(x: f64, lo: f64, hi: f64) -> f64 {
    if lo <= hi {
        x.clamp(lo, hi)
    } else {
        x
    }
}

pub(crate) fn projected_grad(o: &Outer, x: &[f64], g: &[f64]) -> Vec<f64> {
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

pub(crate) fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// What both outer methods return: the decrement (NaN for BFGS), the iterations, and the cells'
/// solutions, the unknowns and the gradient at the final point.
impl Outer {
    /// The error for grid cell `j` without a feasible candidate (a cubic bound whose solution
    /// needs more than Theorem 2.1's two extra knots there).
    pub(crate) fn no_candidate(&self, j: usize) -> Error {
        let c = &self.cells[j];
        Error::Unsupported {
            field: if c.lower.is_some() {
                self.fields[0]
            } else {
                self.fields[1]
            },
            index: c.interval,
            reason: "no feasible candidate in this interval: a cubic bound whose solution needs more than two extra knots here (Theorem 2.1 enumerates at most two; Remark 3.2)",
        }
    }

    /// ‖g‖∞ in the caller's frame.
    pub(crate) fn caller_gradient_norm(&self, g: &[f64]) -> f64 {
        g.iter()
            .zip(&self.unit)
            .fold(0.0f64, |m, (g, u)| m.max((g * u).abs()))
    }
}

pub(crate) type OuterOut = (f64, usize, (Vec<CellSolution>, Vec<f64>, Vec<f64>));
