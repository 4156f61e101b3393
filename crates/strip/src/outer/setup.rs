//! The cells of the outer problem on the data sites, and its starting point.

use super::phi::{Outer, RealCell};
use crate::cell::{Cell, CellTol};
use crate::error::{bound_field, Error};
use crate::spline::Spline;
use crate::types::{Bound, Options, Problem, Side, CONTACT_TOL, FEASIBILITY_TOL};

/// Starting points other than the natural spline, tried in turn when its slopes lie outside Φ's
/// domain: the slopes at the data sites replaced by Bessel's three-point slopes, by the
/// Fritsch–Carlson slopes (weighted harmonic means of the chord slopes, zero at extrema) and by
/// the slopes of the data polygon on either side (prescribed end slopes and free grid values
/// stay as they are).
pub(crate) fn alternative_starts(o: &Outer, t: &[f64], x0: &[f64]) -> Vec<Vec<f64>> {
    let sites: Vec<(usize, f64, f64)> =
        t.iter().enumerate().map(|(j, &u)| (j, u, o.y[j])).collect();
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

/// An outer problem ready to solve.
/// An outer problem ready to solve.
pub(crate) struct Setup {
    pub(crate) outer: Outer,
    /// The starting point: the natural (or clamped) spline's slopes.
    pub(crate) x0: Vec<f64>,
}

/// The cells and starting point of the normalized `problem` (data inside the strip, no
/// polyline bound); `vscale` is the value scale (tolerances on values are relative to it).
pub(crate) fn setup(problem: &Problem, opts: &Options, vscale: f64) -> Result<Setup, Error> {
    if opts.gradient_tol.is_nan() || opts.gradient_tol <= 0.0 {
        return Err(Error::InvalidValue {
            field: "options.gradient_tol",
            index: 0,
            reason: "the tolerance must be positive",
        });
    }
    let t = &problem.t;
    let n = t.len();
    let piece = |b: &Bound, i: usize| match b {
        Bound::Pieces(p) => Some(p[i]),
        _ => None,
    };
    let cells: Vec<RealCell> = (0..n - 1)
        .map(|i| RealCell {
            h: t[i + 1] - t[i],
            lower: piece(&problem.lower, i),
            upper: piece(&problem.upper, i),
        })
        .collect();
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
    let fixed_slope: Vec<Option<f64>> = (0..n)
        .map(|i| match i {
            0 => problem.end_slopes[0],
            _ if i == n - 1 => problem.end_slopes[1],
            _ => None,
        })
        .collect();
    let mut zv = vec![None; n];
    let mut nvar = 0;
    for i in 0..n {
        if fixed_slope[i].is_none() {
            zv[i] = Some(nvar);
            nvar += 1;
        }
    }
    let outer = Outer {
        cells,
        norm,
        y: problem.y.clone(),
        fixed_slope,
        zv,
        nvar,
        tol: CellTol {
            feas: FEASIBILITY_TOL * vscale,
            c2: CONTACT_TOL,
        },
        pruning: opts.pruning,
        unit: vec![1.0; nvar],
        fields: [
            bound_field(&problem.lower, Side::Lower),
            bound_field(&problem.upper, Side::Upper),
        ],
    };
    // the natural (or clamped) spline through the data
    let start = Spline::through(t.clone(), problem.y.clone(), problem.end_slopes).to_curve();
    let mut x0 = vec![0.0; nvar];
    for i in 0..n {
        if let Some(k) = outer.zv[i] {
            x0[k] = start.eval(t[i]).1;
        }
    }
    Ok(Setup { outer, x0 })
}
