//! The grid of an outer problem (data sites plus polyline vertices), its cells, the boxes of the
//! free grid values, and the starting point.

use super::phi::{clamp_safe, Outer, RealCell};
use crate::cell::{Cell, CellTol};
use crate::error::{bound_field, Error, Infeasibility};
use crate::linalg::solve_tridiagonal;
use crate::piece::cubic3;
use crate::types::{cell_bound, Bound, Options, Problem, Side, CONTACT_TOL, FEASIBILITY_TOL};
use crate::validate::validate;

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
    // diagonally dominant: no pivoting needed
    solve_tridiagonal(&a, &mut b, &c, &mut r);
    r
}

pub(crate) fn hermite_eval(
    t0: f64,
    t1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    z1: f64,
    t: f64,
) -> (f64, f64) {
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

/// Starting points other than the natural spline, tried in turn when its slopes lie outside Φ's
/// domain: the slopes at the data sites replaced by Bessel's three-point slopes, by the
/// Fritsch–Carlson slopes (weighted harmonic means of the chord slopes, zero at extrema) and by
/// the slopes of the data polygon on either side (prescribed end slopes and free grid values
/// stay as they are).
pub(crate) fn alternative_starts(
    o: &Outer,
    grid: &[(f64, Option<usize>)],
    x0: &[f64],
) -> Vec<Vec<f64>> {
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

pub(crate) struct Setup {
    pub(crate) outer: Outer,
    pub(crate) grid: Vec<(f64, Option<usize>)>,
    pub(crate) x0: Vec<f64>,
    pub(crate) shifted: Vec<usize>,
}

/// The grid, cells and starting point of `problem`; `vscale` is its value scale (tolerances on
/// values are relative to it).
pub(crate) fn setup(problem: &Problem, opts: &Options, vscale: f64) -> Result<Setup, Error> {
    validate(problem)?;
    if !(0.0..0.5).contains(&opts.boundary_margin) {
        return Err(Error::InvalidValue {
            field: "options.boundary_margin",
            index: 0,
            reason: "the margin must lie in [0, 0.5)",
        });
    }
    if opts.gradient_tol.is_nan() || opts.gradient_tol <= 0.0 {
        return Err(Error::InvalidValue {
            field: "options.gradient_tol",
            index: 0,
            reason: "the tolerance must be positive",
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
                if cubic3(&d, s).0 <= 0.0 {
                    return Err(closed(problem, c.interval, c.a + s));
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
        for (cj, at_end) in [(j.wrapping_sub(1), true), (j, false)] {
            if let Some(c) = cells.get(cj) {
                let s = if at_end { c.h } else { 0.0 };
                let l = c.lower.map(|g| cubic3(&g, s).0);
                let u = c.upper.map(|g| cubic3(&g, s).0);
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
                    return Err(Error::Infeasible {
                        field: "y",
                        index: i,
                        reason: Infeasibility::OutsideBound {
                            side: Side::Lower,
                            by: lo - v,
                        },
                    });
                }
                if v > hi + on_bound_tol {
                    return Err(Error::Infeasible {
                        field: "y",
                        index: i,
                        reason: Infeasibility::OutsideBound {
                            side: Side::Upper,
                            by: v - hi,
                        },
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
        let slope_end = |g: &[f64; 4], h: f64| cubic3(g, h).1;
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
        fields: [
            bound_field(&problem.lower, Side::Lower),
            bound_field(&problem.upper, Side::Upper),
        ],
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

/// The error for a strip that closes at `at` (in data interval `interval`): named after the
/// lower bound's piece, or the polyline vertex at or before `at`.
fn closed(p: &Problem, interval: usize, at: f64) -> Error {
    let index = match &p.lower {
        Bound::Polyline(v) => v.partition_point(|q| q[0] <= at).clamp(1, v.len()) - 1,
        _ => interval,
    };
    Error::Infeasible {
        field: bound_field(&p.lower, Side::Lower),
        index,
        reason: Infeasibility::Closed { at },
    }
}

/// Free grid values start at least this fraction of the strip width inside the strip.
const INITIAL_INSET: f64 = 0.01;
