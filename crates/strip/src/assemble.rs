//! The solution in the caller's frame: pieces, extra knots and certificates assembled from the
//! cells of the normalized problem and mapped back.

use crate::cell::CellSolution;
use crate::cell::CellStats;
use crate::error::Error;
use crate::frame::Frame;
use crate::outer::Outer;
use crate::piece::shift;
use crate::types::{Bound, ExtraKnot, KnotKind, Problem, Shape, Side, Solution};

/// The grid in the caller's frame: data sites and polyline vertices exactly as given, other
/// points t₀ + λu.
pub(crate) fn caller_grid(
    p: &Problem,
    q: &Problem,
    fr: &Frame,
    grid: &[(f64, Option<usize>)],
) -> Vec<f64> {
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
pub(crate) fn to_caller(
    p: &Problem,
    fr: &Frame,
    grid: &[(f64, Option<usize>)],
    s: Solution,
) -> Solution {
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

#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble(
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
            coefficients.push(shift(&piece, error(j, h * pw.x[k])));
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
