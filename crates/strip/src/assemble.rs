//! The solution in the caller's frame: pieces, extra knots and certificates assembled from the
//! cells of the normalized problem and mapped back.

use crate::cell::CellStats;
use crate::frame::Frame;
use crate::outer::{Outer, OuterOut};
use crate::piece::shift;
use crate::types::{Bound, ExtraKnot, KnotKind, Problem, Shape, Solution};

/// Maps the values of a solution of the normalized problem (abscissae already placed in the
/// caller's frame by `assemble`) back: values ℓ(t) + c·v (unshifted data values exactly),
/// slopes ℓ' + c·z/λ (prescribed end slopes exactly), cubic coefficients c_k·c/λ^k (plus ℓ in
/// the first two), energies ·c²/λ³.
pub(crate) fn to_caller(p: &Problem, fr: &Frame, s: Solution) -> Solution {
    // the exact data value at data site j unless Remark 4.2 moved it (the solution's grid is the
    // data sites)
    let mut shifted = vec![false; p.y.len()];
    for &i in &s.shifted_data {
        shifted[i] = true;
    }
    let data_at = |j: usize| (!shifted[j]).then(|| p.y[j]);
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
    without_empty_pieces(Solution {
        coefficients,
        slopes,
        grid_values,
        energy,
        norm: energy.sqrt(),
        newton_decrement: s.newton_decrement * ef,
        ..s
    })
}

/// `s` without its pieces of length 0 and with each contact once. Two knots closer than the
/// rounding of their abscissa (sites ~10⁸ spacings from the origin, where one ulp of t is 1e-8
/// of a span) are placed on the same abscissa: the piece between them has no extent, and a
/// touch found on both sides of it was reported twice (`xtask/sweeps/strip.py` at offsets of
/// 10⁶ ranges: 11 of 123 breaks repeated, `breaks` no longer increasing). The piece after the
/// empty one starts at the same abscissa, so dropping the empty piece and its end changes no
/// value of the curve.
fn without_empty_pieces(mut s: Solution) -> Solution {
    if s.breaks.windows(2).all(|w| w[0] < w[1]) {
        return s;
    }
    let (mut breaks, mut coefficients) = (vec![s.breaks[0]], Vec::new());
    for (j, c) in s.coefficients.iter().enumerate() {
        let end = s.breaks[j + 1];
        if end > s.breaks[j] {
            coefficients.push(*c);
            breaks.push(end);
        }
    }
    s.breaks = breaks;
    s.coefficients = coefficients;
    s.extra_knots
        .dedup_by(|b, a| a.t.to_bits() == b.t.to_bits() && a.kind == b.kind);
    s
}

/// The solution of the cells of the Φ-problem, in the normalized frame with its breaks placed in
/// the caller's by `place(site, offset)`; `error(site, offset)` is how far (normalized units) a
/// placed abscissa lies from the exact one, so that each piece is re-expanded about the
/// abscissa actually returned. [`to_caller`] maps the values.
pub(crate) fn assemble(
    place: &dyn Fn(usize, f64) -> f64,
    error: &dyn Fn(usize, f64) -> f64,
    o: &Outer,
    out: &OuterOut,
    solves: usize,
    stats: CellStats,
    shifted: Vec<usize>,
) -> Solution {
    let sols = &out.sols;
    let z = o.slopes(&out.x);
    let mut breaks = Vec::new();
    let mut coefficients = Vec::new();
    let mut extra = Vec::new();
    let mut energy = 0.0;
    let mut uncertified = Vec::new();
    for (j, sol) in sols.iter().enumerate() {
        let h = o.cells[j].h;
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
        let mut knot = |k: usize, kind: KnotKind| {
            extra.push(ExtraKnot {
                t: place(j, h * sol.tau[k]),
                kind,
                interval: j,
            })
        };
        match sol.shape {
            Shape::Free => {}
            Shape::Touch(sd) => knot(0, KnotKind::Touch(sd)),
            Shape::Subarc(sd) => {
                knot(0, KnotKind::SubarcStart(sd));
                knot(1, KnotKind::SubarcEnd(sd));
            }
            Shape::Pair(sd) => {
                knot(0, KnotKind::Touch(sd));
                knot(1, KnotKind::Touch(sd.other()));
            }
        }
    }
    breaks.push(place(sols.len(), 0.0));
    Solution {
        breaks,
        coefficients,
        slopes: z,
        grid: (0..=sols.len()).map(|j| place(j, 0.0)).collect(),
        grid_values: o.y.clone(),
        shapes: sols.iter().map(|s| s.shape).collect(),
        extra_knots: extra,
        energy,
        norm: energy.sqrt(),
        gradient_norm: 0.0,
        newton_decrement: f64::NAN,
        gap: f64::NAN,
        rounds: 1,
        iterations: out.iterations,
        cell_solves: solves,
        candidates: stats.candidates,
        shifted_data: shifted,
        uncertified,
        violation: 0.0,
    }
}

/// The solution of the exchange (polyline bounds): the spline through the data and the active
/// points, in the normalized frame with its breaks placed in the caller's (data sites and
/// polyline vertices exactly as given); [`to_caller`] maps the values.
pub(crate) fn assemble_spline(
    p: &Problem,
    q: &Problem,
    fr: &Frame,
    ex: &crate::exchange::Exchanged,
    shifted: Vec<usize>,
) -> Solution {
    let s = &ex.spline;
    let curve = s.to_curve();
    let n = q.t.len();
    // the caller's abscissa of a knot: a data site, a polyline vertex, or t₀ + λu
    let vertex = |u: f64| -> Option<f64> {
        for (bq, bp) in [(&q.lower, &p.lower), (&q.upper, &p.upper)] {
            if let (Bound::Polyline(vq), Bound::Polyline(vp)) = (bq, bp) {
                let k = vq.partition_point(|v| v[0] < u);
                if k < vq.len() && vq[k][0].to_bits() == u.to_bits() {
                    return Some(vp[k][0]);
                }
            }
        }
        None
    };
    let mut site = 0;
    let caller: Vec<f64> =
        s.x.iter()
            .map(|&u| {
                while site < n && q.t[site] < u {
                    site += 1;
                }
                if site < n && q.t[site].to_bits() == u.to_bits() {
                    p.t[site]
                } else {
                    vertex(u).unwrap_or_else(|| fr.time(u))
                }
            })
            .collect();
    let coefficients: Vec<[f64; 4]> = curve
        .coeffs
        .iter()
        .zip(&s.x)
        .zip(&caller)
        .map(|((c, u), b)| shift(c, (b - fr.t0) / fr.lam - u))
        .collect();
    let mut extra = Vec::with_capacity(ex.active.len());
    let mut shapes = vec![Shape::Free; n - 1];
    let mut a = 0;
    for (k, &u) in s.x.iter().enumerate() {
        if a < ex.active.len() && ex.active[a].x.to_bits() == u.to_bits() {
            let c = ex.active[a];
            let interval = q.t.partition_point(|v| *v <= u).clamp(1, n - 1) - 1;
            if shapes[interval] == Shape::Free {
                shapes[interval] = Shape::Touch(c.side);
            }
            extra.push(ExtraKnot {
                t: caller[k],
                kind: KnotKind::Touch(c.side),
                interval,
            });
            a += 1;
        }
    }
    let slopes: Vec<f64> = q.t.iter().map(|&u| curve.eval(u).1).collect();
    let energy = s.energy();
    let decrement = ex.gap * energy;
    Solution {
        breaks: caller,
        coefficients,
        slopes,
        grid: p.t.clone(),
        grid_values: q.y.clone(),
        shapes,
        extra_knots: extra,
        energy,
        norm: energy.sqrt(),
        gradient_norm: 0.0,
        newton_decrement: decrement,
        gap: ex.gap,
        rounds: ex.sweeps,
        iterations: ex.steps,
        cell_solves: ex.solves,
        candidates: ex.steps,
        shifted_data: shifted,
        uncertified: Vec::new(),
        violation: 0.0,
    }
}
