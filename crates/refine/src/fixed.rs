//! The fixed-knot problems of one stage: the exact optimum and the paper's multiplier iteration.

use divdiff::{Knots, Points};
use energy::{Hessian, System};

use crate::algorithm::{FixedProblem, FixedSolution};
use crate::backend::condensed::PointSet;
use crate::operator::{self, Stencil};
use crate::problem::Constraint;
use crate::Error;

/// Relative floor of the paper iteration's weights: w_i ≥ PAPER_WEIGHT_FLOOR · mean(H_jj).
/// Inactive constraints drive their weights to zero geometrically; without a floor a curve
/// whose constraints all turn inactive (collinear data in balls) would make H + W singular.
pub const PAPER_WEIGHT_FLOOR: f64 = 1e-10;

/// The system H ⊗ I_d on the given knots.
pub(crate) fn hessian_system(knots: &Knots, dim: usize) -> Result<System, Error> {
    let h = Hessian::new(knots);
    let (d0, d1, d2) = h.bands();
    Ok(System::from_bands(
        knots.topology(),
        d0.to_vec(),
        d1.to_vec(),
        d2.to_vec(),
        dim,
    )?)
}

fn has_extra_constraints(fp: &FixedProblem<'_>) -> bool {
    fp.problem.has_derivative_constraints()
}

/// Interpolation at the data vertices whose `fixed` flag is set, plus weights `w` (0 = none) at
/// the others: (H + W)p = W q̃ with p_v = q_i at fixed data vertices (3.3), (3.5), (3.6).
fn linear(fp: &FixedProblem<'_>, fixed: &[bool], w: &[f64]) -> Result<Points, Error> {
    let n_vert = fp.knots.vertex_count();
    let d = fp.q.dim();
    let mut sys = hessian_system(fp.knots, d)?;
    let mut rhs = vec![0.0; n_vert * d];
    for (i, &v) in fp.data_vertex.iter().enumerate() {
        let qi = fp.q.point(i);
        if fixed[i] {
            sys.fix(v)?;
            rhs[v * d..(v + 1) * d].copy_from_slice(qi);
        } else if w[i] > 0.0 {
            sys.add_weight(v, w[i])?;
            for c in 0..d {
                rhs[v * d + c] = w[i] * qi[c];
            }
        }
    }
    let f = sys.factor()?;
    f.solve_flat(&mut rhs)?;
    Ok(Points::new(d, rhs)?)
}

/// The ball multiplier w that makes (Hp)_v + w (p_v − q) = 0 hold in the least-squares sense:
/// w = −(Hp)_v · (p_v − q) / |p_v − q|².
fn ball_weight(hp_v: &[f64], p_v: &[f64], q: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((h, x), y) in hp_v.iter().zip(p_v).zip(q) {
        num -= h * (x - y);
        den += (x - y) * (x - y);
    }
    num / den
}

/// The exact optimum of the fixed-knot problem.
pub(crate) fn exact(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    let n = fp.q.len();
    if !has_extra_constraints(fp) {
        match fp.constraint {
            Constraint::Interpolate => return interpolate(fp),
            Constraint::Balls(r) if r.iter().all(|&e| e == 0.0) => return interpolate(fp),
            Constraint::Smoothing(w) => {
                let p = linear(fp, &vec![false; n], w)?;
                return Ok(FixedSolution {
                    points: p,
                    multipliers: Some(w.iter().map(|&x| vec![x]).collect()),
                    iterations: 1,
                    stencil: None,
                    extra: Vec::new(),
                    solver_kkt: None,
                    certificate: None,
                });
            }
            _ => {}
        }
    }
    // Data constraints alone: the interior-point method condensed onto the data vertices
    // (crate::backend), accepted when the independent certificate reaches the target.
    if let (Some(sets), false) = (condensed_sets(fp), has_extra_constraints(fp)) {
        match condensed_data(fp, &sets)? {
            Ok(sol) => return Ok(sol),
            // The full-vertex fallbacks cost minutes beyond the general solver's size limit
            // (a 10-point star with k = 10⁶ ran 15 minutes): refuse with the best residual.
            Err((iterations, residual))
                if fp.knots.vertex_count().saturating_mul(fp.q.dim())
                    > crate::problem::MAX_CONIC_COORDS =>
            {
                return Err(Error::NotConverged {
                    solver: "condensed balls",
                    iterations,
                    residual,
                });
            }
            Err(_) => {}
        }
    }
    // Fallbacks. Balls alone: the paper's multiplier iteration (scalar banded solves) finds the active set
    // approximately, the active-set polish makes it exact; the certificate decides. The
    // interior-point solver is the fallback.
    if let (Constraint::Balls(radii), false) = (fp.constraint, has_extra_constraints(fp)) {
        // A failure here (e.g. a singular system when every ball is inactive and nothing pins
        // the kernel of H) only means this shortcut does not apply.
        if let Ok(start) = paper(fp) {
            if let Ok(Some((polished, kp))) = polish_balls(fp, &start, radii) {
                if kp <= crate::exact::EXACT_KKT_TARGET {
                    return Ok(FixedSolution {
                        iterations: start.iterations + polished.iterations,
                        ..polished
                    });
                }
            }
        }
    }
    let certified = |tol: f64| -> Result<(FixedSolution, f64), Error> {
        let (mut sol, extra, kkt) = crate::exact::solve(fp, tol)?;
        sol.extra = extra;
        sol.solver_kkt = Some(kkt);
        let (cert, _) = crate::certify::certify(
            &Stencil::new(fp.knots),
            &sol.points,
            fp.q,
            fp.data_vertex,
            fp.constraint,
            sol.multipliers.clone(),
            crate::certify::ACTIVE_REL_TOL,
            &sol.extra,
        );
        Ok((sol, cert.kkt_residual.max(kkt)))
    };
    let (first, k1) = certified(crate::exact::CONIC_TOLERANCE)?;
    if k1 <= crate::exact::EXACT_KKT_TARGET {
        return Ok(first);
    }
    let (mut best, mut k) = match certified(crate::exact::EXACT_CONIC_TOLERANCE) {
        Ok((second, k2)) if k2 < k1 => (
            FixedSolution {
                iterations: first.iterations + second.iterations,
                ..second
            },
            k2,
        ),
        _ => (first, k1),
    };
    if let (Constraint::Balls(radii), false) = (fp.constraint, has_extra_constraints(fp)) {
        if k > crate::exact::EXACT_KKT_TARGET {
            if let Ok(Some((polished, kp))) = polish_balls(fp, &best, radii) {
                if kp < k {
                    best = FixedSolution {
                        iterations: best.iterations + 1,
                        ..polished
                    };
                    k = kp;
                }
            }
        }
    }
    if let (Constraint::HalfSpaces(sets), false) = (fp.constraint, has_extra_constraints(fp)) {
        if k > crate::exact::EXACT_KKT_TARGET {
            if let Ok(Some((polished, kp))) = polish_halfspaces(fp, &best, sets) {
                if kp < k {
                    best = FixedSolution {
                        iterations: best.iterations + polished.iterations,
                        ..polished
                    };
                    k = kp;
                }
            }
        }
    }
    let _ = k;
    Ok(best)
}

/// The data constraint of each point as the condensed backend's sets, or `None` when the
/// condensed method does not apply (no data constraint, or an unconstrained point where the
/// condensation must start: point 0, and the last point of an open curve).
fn condensed_sets(fp: &FixedProblem<'_>) -> Option<Vec<Option<PointSet>>> {
    use crate::backend::condensed::Face;
    let n = fp.q.len();
    let sets: Vec<Option<PointSet>> = match fp.constraint {
        Constraint::Balls(r) => r
            .iter()
            .map(|&e| {
                Some(if e == 0.0 {
                    PointSet::Fixed
                } else {
                    PointSet::Ball(e)
                })
            })
            .collect(),
        Constraint::HalfSpaces(sets) => sets
            .iter()
            .map(|set| {
                (!set.is_empty()).then(|| {
                    PointSet::Faces(
                        set.iter()
                            .map(|h| {
                                let norm = h.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                                Face {
                                    normal: h.normal.iter().map(|x| x / norm).collect(),
                                    offset: h.offset / norm,
                                    norm,
                                }
                            })
                            .collect(),
                    )
                })
            })
            .collect(),
        _ => return None,
    };
    // The condensation needs data rows: two points of a closed curve (one would couple its row
    // to itself), three of an open one (whose end rows are zero).
    let constrained = sets.iter().filter(|s| s.is_some()).count();
    let enough = if fp.knots.is_closed() {
        constrained >= 2
    } else {
        constrained >= 3 && sets[n - 1].is_some()
    };
    (sets[0].is_some() && enough).then_some(sets)
}

/// The condensed working-set solution of data constraints alone ([`crate::backend`]) if its
/// certificate is at most [`crate::exact::EXACT_KKT_TARGET`]; otherwise (use a fallback) the
/// iterations spent and the best certificate reached (∞ if the method failed).
fn condensed_data(
    fp: &FixedProblem<'_>,
    sets: &[Option<PointSet>],
) -> Result<Result<FixedSolution, (usize, f64)>, Error> {
    let stencil = Stencil::new(fp.knots);
    let mut iterations = 0;
    let mut best = f64::INFINITY;
    // The method's default tolerance, then a stricter one when the certificate is not reached
    // (its active set, read off at the default, was not settled enough for the polish).
    for tolerance in [1e-10, 1e-13] {
        let opts = conic::Options::default().with_tolerance(tolerance);
        let mut judge = |p: &Points, m: &[Vec<f64>]| {
            let (cert, mult) = crate::certify::certify(
                &stencil,
                p,
                fp.q,
                fp.data_vertex,
                fp.constraint,
                Some(m.to_vec()),
                crate::certify::ACTIVE_REL_TOL,
                &[],
            );
            (cert.kkt_residual, (cert, mult))
        };
        // A failure of the method (not converged) only means the fallbacks run.
        let Ok(sol) = crate::backend::working_set::solve(
            fp.knots,
            &stencil,
            fp.q,
            sets,
            fp.stride,
            &opts,
            &crate::backend::working_set::WorkingSetOptions::default(),
            fp.working_set,
            &mut judge,
            crate::exact::EXACT_KKT_TARGET,
        ) else {
            return Ok(Err((iterations, best)));
        };
        iterations += sol.iterations;
        let (cert, mult) = sol.certificate;
        if cert.kkt_residual <= crate::exact::EXACT_KKT_TARGET {
            return Ok(Ok(FixedSolution {
                points: sol.points,
                multipliers: Some(sol.multipliers),
                iterations,
                stencil: Some(stencil),
                extra: Vec::new(),
                solver_kkt: None,
                certificate: Some((cert, mult)),
            }));
        }
        best = best.min(cert.kkt_residual);
    }
    Ok(Err((iterations, best)))
}

/// A data vertex on its sphere to this relative accuracy is treated as active by the polish.
pub const BALL_POLISH_ACTIVE_RTOL: f64 = 1e-6;

/// Newton steps on the settled active set at the end of the polish.
pub const BALL_POLISH_NEWTON_STEPS: usize = 4;
/// Stiffness of the penalty that holds an active vertex's normal direction during those steps,
/// relative to the largest diagonal entry of H.
/// (A moderate value: the normal component is re-projected after each step anyway, and a
/// stiffer penalty trips the factorization's relative pivot test.)
pub const BALL_POLISH_STIFFNESS: f64 = 1e4;

/// Rounds of the active-set polish (each one scalar banded solve).
pub const BALL_POLISH_ROUNDS: usize = 100;

/// Active-set polish of a ball solution: the data vertices on their spheres are projected onto
/// them exactly and fixed there, the others are freed (w = 0), and the curve is re-solved — one
/// scalar banded solve. Freed vertices that leave their balls join the active set (at the
/// projection of the new position), active ones whose multiplier w_i = −(Hp)·r/|r|² turns
/// negative are freed, and the solve repeats (a primal active-set method started from the
/// interior-point solution) for at most [`BALL_POLISH_ROUNDS`] rounds. When the set settles, every
/// complementarity term vanishes exactly and the certificate measures what is left: the
/// tangential part of (Hp)_{i_k} at the active vertices. `None` if it does not settle.
fn polish_balls(
    fp: &FixedProblem<'_>,
    sol: &FixedSolution,
    radii: &[f64],
) -> Result<Option<(FixedSolution, f64)>, Error> {
    let n = fp.q.len();
    let d = fp.q.dim();
    let nv = fp.knots.vertex_count();
    // Positions the active vertices are pinned at (on their spheres).
    let mut pin: Vec<Option<Vec<f64>>> = vec![None; n];
    let project = |pv: &[f64], i: usize| -> Option<Vec<f64>> {
        let qi = fp.q.point(i);
        let g = dist(pv, qi);
        (g > 0.0).then(|| {
            qi.iter()
                .zip(pv)
                .map(|(q, p)| q + radii[i] * (p - q) / g)
                .collect()
        })
    };
    for i in 0..n {
        let pv = sol.points.point(fp.data_vertex[i]);
        if radii[i] > 0.0 && dist(pv, fp.q.point(i)) >= (1.0 - BALL_POLISH_ACTIVE_RTOL) * radii[i] {
            pin[i] = project(pv, i);
        }
    }
    for round in 1..=BALL_POLISH_ROUNDS {
        let mut sys = hessian_system(fp.knots, d)?;
        let mut rhs = vec![0.0; nv * d];
        for i in 0..n {
            let v = fp.data_vertex[i];
            if radii[i] == 0.0 {
                sys.fix(v)?;
                rhs[v * d..(v + 1) * d].copy_from_slice(fp.q.point(i));
            } else if let Some(y) = &pin[i] {
                sys.fix(v)?;
                rhs[v * d..(v + 1) * d].copy_from_slice(y);
            }
        }
        let f = sys.factor()?;
        f.solve_flat(&mut rhs)?;
        let p = Points::new(d, rhs)?;
        let hp = operator::apply_h(fp.knots, &p);
        let mut multipliers = Vec::with_capacity(n);
        let mut changed = false;
        for i in 0..n {
            let v = fp.data_vertex[i];
            let qi = fp.q.point(i);
            let h = &hp[v * d..(v + 1) * d];
            if radii[i] == 0.0 {
                multipliers.push(h.iter().map(|x| -x).collect());
            } else if pin[i].is_some() {
                let w = ball_weight(h, p.point(v), qi);
                if w < 0.0 {
                    pin[i] = None;
                    changed = true;
                }
                multipliers.push(vec![w.max(0.0)]);
            } else {
                if dist(p.point(v), qi) > radii[i] {
                    pin[i] = project(p.point(v), i);
                    changed = true;
                }
                multipliers.push(vec![0.0]);
            }
        }
        if changed {
            continue;
        }
        let certify_here = |p: &Points, m: &[Vec<f64>]| {
            crate::certify::certify(
                &Stencil::new(fp.knots),
                p,
                fp.q,
                fp.data_vertex,
                fp.constraint,
                Some(m.to_vec()),
                crate::certify::ACTIVE_REL_TOL,
                &[],
            )
            .0
            .kkt_residual
        };
        let mut best = (p, multipliers);
        let mut k = certify_here(&best.0, &best.1);
        // Newton steps on the equality-constrained problem of the settled active set: the
        // tangential positions on the spheres move, with the Lagrangian's curvature w_i I there
        // and the normal direction held by a stiff penalty; then re-project and re-certify.
        for _ in 0..BALL_POLISH_NEWTON_STEPS {
            if k <= crate::exact::EXACT_KKT_TARGET {
                break;
            }
            // A failed step (e.g. a pivot test tripped by the penalty) only ends the polish.
            // Damped: halve the step while it would free a vertex out of its ball or turn a
            // multiplier negative.
            let mut tn = Ok(None);
            for scale in [1.0, 0.5, 0.25, 0.125, 0.0625] {
                tn = tangential_newton(fp, radii, &pin, &best.0, &best.1, scale);
                if !matches!(tn, Ok(None)) {
                    break;
                }
            }
            match tn {
                Ok(Some((p2, m2))) => {
                    let k2 = certify_here(&p2, &m2);
                    if k2 < k {
                        best = (p2, m2);
                        k = k2;
                    } else {
                        break;
                    }
                }
                _ => break,
            }
        }
        return Ok(Some((
            FixedSolution {
                points: best.0,
                multipliers: Some(best.1),
                iterations: round,
                stencil: None,
                extra: Vec::new(),
                solver_kkt: None,
                certificate: None,
            },
            k,
        )));
    }
    Ok(None)
}

/// Rounds of the half-space polish's active-set method.
pub const HALFSPACE_POLISH_ROUNDS: usize = 12;
/// Augmented-Lagrangian steps per round of the half-space polish (one factorization each
/// round; each step cuts the violation of the active faces by about the stiffness ratio).
pub const HALFSPACE_POLISH_AL_STEPS: usize = 10;
/// A face leaves the half-space polish's active set when its multiplier is below −this times
/// the largest multiplier, and joins it when violated by more than this times the length scale.
pub const HALFSPACE_POLISH_CHANGE_RTOL: f64 = 1e-12;
/// Refinement solves per augmented-Lagrangian step of the half-space polish (the first step
/// starts from the interior-point solution).
pub const HALFSPACE_POLISH_REFINEMENT_STEPS: usize = 2;
/// Penalty of the half-space polish relative to the largest diagonal entry of H.
pub const HALFSPACE_POLISH_STIFFNESS: f64 = 1e2;
/// A face starts in the half-space polish's active set when its interior-point force is above
/// this times the largest (or, without multipliers, its slack is below this times the length
/// scale).
pub const HALFSPACE_POLISH_ACTIVE_RTOL: f64 = 1e-6;

/// Active-set polish of a half-space solution: on the faces active at the interior-point
/// solution the equality-constrained problem min ½pᵀ(H ⊗ I)p, n̂ᵀp_v = ĉ (unit normals) is solved
/// by the method of multipliers — (H ⊗ I + M Σ n̂n̂ᵀ)p = Σ n̂ (M ĉ − λ), λ ← λ + M(n̂ᵀp_v − ĉ),
/// one factorization, [`HALFSPACE_POLISH_AL_STEPS`] solves — which ends with the faces met to
/// rounding and Hp + Σ λ n̂ = 0. Faces with λ < 0 leave the set, violated ones join it, and the
/// round repeats (a primal active-set method started from the interior-point solution), at most
/// [`HALFSPACE_POLISH_ROUNDS`] times. The interior-point method reaches the optimum of large
/// problems only to ~1e-7 (H's condition grows like N⁴); this makes it exact. `None` if the set
/// does not settle or a system does not factor; the caller keeps the result only if its
/// certificate is better.
fn polish_halfspaces(
    fp: &FixedProblem<'_>,
    start: &FixedSolution,
    sets: &[Vec<crate::problem::HalfSpace>],
) -> Result<Option<(FixedSolution, f64)>, Error> {
    let n = fp.q.len();
    let d = fp.q.dim();
    let hmax = Hessian::new(fp.knots)
        .bands()
        .0
        .iter()
        .fold(0.0f64, |a, &v| a.max(v.abs()));
    let stiff = HALFSPACE_POLISH_STIFFNESS * hmax.max(f64::MIN_POSITIVE);
    let mut lo = vec![f64::INFINITY; d];
    let mut hi = vec![f64::NEG_INFINITY; d];
    for x in fp.q.iter() {
        for c in 0..d {
            lo[c] = lo[c].min(x[c]);
            hi[c] = hi[c].max(x[c]);
        }
    }
    let length = (0..d)
        .map(|c| hi[c] - lo[c])
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    // Unit normals and offsets.
    let unit: Vec<Vec<(Vec<f64>, f64, f64)>> = sets
        .iter()
        .map(|s| {
            s.iter()
                .map(|h| {
                    let norm = h.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                    (
                        h.normal.iter().map(|x| x / norm).collect(),
                        h.offset / norm,
                        norm,
                    )
                })
                .collect()
        })
        .collect();
    let slack = |i: usize, j: usize, p: &[f64]| -> f64 {
        let (u, c, _) = &unit[i][j];
        c - u.iter().zip(p).map(|(a, b)| a * b).sum::<f64>()
    };
    // The start: faces carrying a clear share of the interior-point multipliers (forces on unit
    // normals); without multipliers, faces within HALFSPACE_POLISH_ACTIVE_RTOL of the point.
    let force = |i: usize, j: usize| -> f64 {
        start
            .multipliers
            .as_ref()
            .and_then(|m| m.get(i))
            .and_then(|m| m.get(j))
            .map_or(0.0, |w| w * unit[i][j].2)
    };
    let fmax = (0..n)
        .flat_map(|i| (0..sets[i].len()).map(move |j| (i, j)))
        .fold(0.0f64, |a, (i, j)| a.max(force(i, j)));
    let mut active: Vec<Vec<bool>> = (0..n)
        .map(|i| {
            let pv = start.points.point(fp.data_vertex[i]);
            (0..sets[i].len())
                .map(|j| {
                    if fmax > 0.0 {
                        force(i, j) > HALFSPACE_POLISH_ACTIVE_RTOL * fmax
                    } else {
                        slack(i, j, pv) <= HALFSPACE_POLISH_ACTIVE_RTOL * length
                    }
                })
                .collect()
        })
        .collect();
    let stencil = Stencil::new(fp.knots);
    // H ⊗ I once; each round replaces the penalty blocks.
    let mut sys = hessian_system(fp.knots, d)?;
    let mut block = vec![0.0; d * d];
    for round in 1..=HALFSPACE_POLISH_ROUNDS {
        sys.clear_blocks();
        for i in 0..n {
            block.fill(0.0);
            let mut any = false;
            for (j, (u, _, _)) in unit[i].iter().enumerate() {
                if active[i][j] {
                    any = true;
                    for a in 0..d {
                        for b in 0..d {
                            block[a * d + b] += stiff * u[a] * u[b];
                        }
                    }
                }
            }
            if any {
                sys.add_block(fp.data_vertex[i], &block)?;
            }
        }
        let Ok(f) = sys.factor() else {
            return Ok(None);
        };
        let mut lambda: Vec<Vec<f64>> = unit.iter().map(|s| vec![0.0; s.len()]).collect();
        // Each step solves (H ⊗ I + M Σ n̂n̂ᵀ)x = Σ n̂(M n̂ᵀx_f − λ) by refinement from the last x,
        // the residual −(Hx + Σ n̂(λ + M n̂ᵀ(x_v − x_f))) formed from differences (x_f the data
        // point projected onto the face): its rounding scales with the steps and the slacks,
        // not with M|x|.
        let mut x = start.points.coords().to_vec();
        let face_slack = |i: usize, j: usize, xv: &[f64]| -> f64 {
            let (u, _, _) = &unit[i][j];
            let qi = fp.q.point(i);
            // n̂ᵀ(x_v − x_f) with x_f = q_i + (ĉ − n̂ᵀq_i) n̂.
            let off = slack(i, j, qi);
            u.iter()
                .zip(xv)
                .zip(qi)
                .map(|((a, b), c)| a * (b - c))
                .sum::<f64>()
                - off
        };
        for _ in 0..HALFSPACE_POLISH_AL_STEPS {
            for _ in 0..HALFSPACE_POLISH_REFINEMENT_STEPS {
                let (mut r, _) = stencil.apply_h(&Points::new(d, x.clone())?);
                for i in 0..n {
                    let v = fp.data_vertex[i];
                    for (j, (u, _, _)) in unit[i].iter().enumerate() {
                        if active[i][j] {
                            let t = lambda[i][j] + stiff * face_slack(i, j, &x[v * d..(v + 1) * d]);
                            for a in 0..d {
                                r[v * d + a] += u[a] * t;
                            }
                        }
                    }
                }
                for ri in r.iter_mut() {
                    *ri = -*ri;
                }
                f.solve_flat(&mut r)?;
                for (xi, ri) in x.iter_mut().zip(&r) {
                    *xi += ri;
                }
            }
            for i in 0..n {
                let v = fp.data_vertex[i];
                for j in 0..unit[i].len() {
                    if active[i][j] {
                        lambda[i][j] += stiff * face_slack(i, j, &x[v * d..(v + 1) * d]);
                    }
                }
            }
        }
        let p = Points::new(d, x.clone())?;
        // Faces with negative multipliers leave; violated faces join (beyond rounding-level
        // thresholds, so that degenerate faces — multiplier and slack both ≈ 0 — do not cycle).
        let lmax = lambda.iter().flatten().fold(0.0f64, |a, &l| a.max(l.abs()));
        // In the first half of the rounds both changes are made at once; later a round either
        // frees the faces with negative multipliers or, when there are none, takes in the
        // violated faces (both at once can cycle).
        let freeing = round > HALFSPACE_POLISH_ROUNDS / 2
            && (0..n).any(|i| {
                (0..unit[i].len())
                    .any(|j| active[i][j] && lambda[i][j] < -HALFSPACE_POLISH_CHANGE_RTOL * lmax)
            });
        let mut changed = false;
        for i in 0..n {
            let pv = p.point(fp.data_vertex[i]);
            for j in 0..unit[i].len() {
                if active[i][j] && lambda[i][j] < -HALFSPACE_POLISH_CHANGE_RTOL * lmax {
                    active[i][j] = false;
                    changed = true;
                } else if !freeing
                    && !active[i][j]
                    && slack(i, j, pv) < -HALFSPACE_POLISH_CHANGE_RTOL * length
                {
                    active[i][j] = true;
                    changed = true;
                }
            }
        }
        if changed {
            continue;
        }
        // Multipliers of the unnormalized normals: w = λ / |n|.
        let multipliers: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..unit[i].len())
                    .map(|j| {
                        if active[i][j] {
                            lambda[i][j] / unit[i][j].2
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        let (cert, _) = crate::certify::certify(
            &stencil,
            &p,
            fp.q,
            fp.data_vertex,
            fp.constraint,
            Some(multipliers.clone()),
            crate::certify::ACTIVE_REL_TOL,
            &[],
        );
        return Ok(Some((
            FixedSolution {
                points: p,
                multipliers: Some(multipliers),
                iterations: round,
                stencil: None,
                extra: Vec::new(),
                solver_kkt: None,
                certificate: None,
            },
            cert.kkt_residual,
        )));
    }
    Ok(None)
}

/// Interpolation (3.3) at every data vertex: the closed forms of [`crate::uniform`] on the knots
/// of the split, else the fused banded solver of [`crate::fast`].
fn interpolate(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    if fp.uniform_spans {
        return Ok(FixedSolution {
            points: crate::uniform::interpolate(fp.knots, fp.q, fp.stride)?,
            multipliers: None,
            iterations: 1,
            stencil: None,
            extra: Vec::new(),
            solver_kkt: None,
            certificate: None,
        });
    }
    let stencil = Stencil::new(fp.knots);
    let p = crate::fast::interpolate(fp.knots, &stencil, fp.q, fp.stride)?;
    Ok(FixedSolution {
        points: p,
        multipliers: None,
        iterations: 1,
        stencil: Some(stencil),
        extra: Vec::new(),
        solver_kkt: None,
        certificate: None,
    })
}

/// Kersey's multiplier iteration, Algorithm 4.1 (iii): start from w_i = 1, solve
/// (H + W)p = W q̃ (radius-0 points interpolated), update w_i := w_i |p_{i_k} − q_i| / ε_i, and
/// repeat `paper_iterations` times. The reported multipliers are the weights of the last solve,
/// so (H + W)p = W q̃ holds to rounding and the KKT residual measures the complementarity the
/// iteration has not reached.
pub(crate) fn paper(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    if has_extra_constraints(fp) {
        return Err(Error::Unsupported {
            field: "solver",
            reason: "the paper's iteration handles data constraints only; use the exact solver for tangents and end conditions",
        });
    }
    let n = fp.q.len();
    match fp.constraint {
        Constraint::Interpolate | Constraint::Smoothing(_) => exact(fp),
        Constraint::Balls(r) => {
            let fixed: Vec<bool> = r.iter().map(|&e| e == 0.0).collect();
            if fixed.iter().all(|&f| f) {
                return interpolate(fp);
            }
            let h = Hessian::new(fp.knots);
            let floor = PAPER_WEIGHT_FLOOR * h.bands().0.iter().sum::<f64>() / h.len() as f64;
            let mut w: Vec<f64> = fixed.iter().map(|&f| if f { 0.0 } else { 1.0 }).collect();
            let d = fp.q.dim();
            let iters = fp.problem.paper_iterations.max(1);
            let mut p = linear(fp, &fixed, &w)?;
            for _ in 1..iters {
                for i in 0..n {
                    if !fixed[i] {
                        let v = fp.data_vertex[i];
                        let gap = dist(p.point(v), fp.q.point(i));
                        w[i] = (w[i] * gap / r[i]).max(floor);
                    }
                }
                p = linear(fp, &fixed, &w)?;
            }
            let hp = operator::apply_h(fp.knots, &p);
            let multipliers = (0..n)
                .map(|i| {
                    let v = fp.data_vertex[i];
                    if fixed[i] {
                        hp[v * d..(v + 1) * d].iter().map(|x| -x).collect()
                    } else {
                        vec![w[i]]
                    }
                })
                .collect();
            Ok(FixedSolution {
                points: p,
                multipliers: Some(multipliers),
                iterations: iters,
                stencil: None,
                extra: Vec::new(),
                solver_kkt: None,
                certificate: None,
            })
        }
        Constraint::HalfSpaces(sets) => paper_slots(fp, sets),
    }
}

/// The paper's slot iteration for polygonal constraints in the plane (Fig. 4.1; see
/// [`crate::slots`]): one d×d spring block per slot at its data vertex, weights updated by
/// w := w |u·p − m| / ε.
fn paper_slots(
    fp: &FixedProblem<'_>,
    sets: &[Vec<crate::problem::HalfSpace>],
) -> Result<FixedSolution, Error> {
    let d = fp.q.dim();
    if d != 2 {
        return Err(Error::Unsupported {
            field: "solver",
            reason: "the paper's slot iteration (Fig. 4.1) is planar; use the exact solver for half-spaces in R^d, d ≠ 2",
        });
    }
    let n = fp.q.len();
    let extent =
        fp.q.iter()
            .flat_map(|x| x.iter().map(|v| v.abs()))
            .fold(1.0f64, f64::max)
            * 4.0;
    let mut all: Vec<Vec<crate::slots::Slot>> = Vec::with_capacity(n);
    for (i, set) in sets.iter().enumerate() {
        let q = fp.q.point(i);
        let s =
            crate::slots::slots(set, [q[0], q[1]], extent).ok_or(Error::InfeasibleConstraint {
                field: "sets",
                point: i,
            })?;
        all.push(s);
    }
    let h = Hessian::new(fp.knots);
    let floor = PAPER_WEIGHT_FLOOR * h.bands().0.iter().sum::<f64>() / h.len() as f64;
    let mut w: Vec<Vec<f64>> = all.iter().map(|s| vec![1.0; s.len()]).collect();
    let solve = |w: &[Vec<f64>]| -> Result<Points, Error> {
        let mut sys = hessian_system(fp.knots, d)?;
        let mut rhs = vec![0.0; fp.knots.vertex_count() * d];
        for (i, slots) in all.iter().enumerate() {
            let v = fp.data_vertex[i];
            for (slot, &wij) in slots.iter().zip(&w[i]) {
                let u = slot.unit;
                sys.add_block(
                    v,
                    &[
                        wij * u[0] * u[0],
                        wij * u[0] * u[1],
                        wij * u[1] * u[0],
                        wij * u[1] * u[1],
                    ],
                )?;
                rhs[v * 2] += wij * slot.centre * u[0];
                rhs[v * 2 + 1] += wij * slot.centre * u[1];
            }
        }
        let f = sys.factor()?;
        f.solve_flat(&mut rhs)?;
        Ok(Points::new(d, rhs)?)
    };
    let iters = fp.problem.paper_iterations.max(1);
    let mut p = solve(&w)?;
    for _ in 1..iters {
        for (i, slots) in all.iter().enumerate() {
            let x = p.point(fp.data_vertex[i]);
            for (slot, wij) in slots.iter().zip(w[i].iter_mut()) {
                let off = (slot.unit[0] * x[0] + slot.unit[1] * x[1] - slot.centre).abs();
                *wij = (*wij * off / slot.half_width).max(floor);
            }
        }
        p = solve(&w)?;
    }
    // Multipliers in the convention of (3.8): (Hp)_v + Σ_j λ_j n_j = 0 over the active edges.
    // A slot pushes from both of its sides, so the slot forces do not map one-to-one onto the
    // half-planes; the multipliers are recovered from the final point instead: one active edge
    // (λ = −(Hp)_v·n / |n|²) or a corner (a 2×2 solve), clamped at 0.
    let hp = operator::apply_h(fp.knots, &p);
    let active_tol = 1e-6 * extent;
    let multipliers = sets
        .iter()
        .enumerate()
        .map(|(i, set)| {
            let v = fp.data_vertex[i];
            let x = p.point(v);
            let g = [-hp[v * 2], -hp[v * 2 + 1]];
            let act: Vec<usize> = (0..set.len())
                .filter(|&j| {
                    let nrm = &set[j].normal;
                    (nrm[0] * x[0] + nrm[1] * x[1] - set[j].offset) / nrm[0].hypot(nrm[1])
                        >= -active_tol
                })
                .collect();
            let mut lam = vec![0.0; set.len()];
            match act.as_slice() {
                [j] => {
                    let nrm = &set[*j].normal;
                    lam[*j] = ((g[0] * nrm[0] + g[1] * nrm[1])
                        / (nrm[0] * nrm[0] + nrm[1] * nrm[1]))
                        .max(0.0);
                }
                [a, b] => {
                    let (na, nb) = (&set[*a].normal, &set[*b].normal);
                    let det = na[0] * nb[1] - na[1] * nb[0];
                    if det.abs() > f64::EPSILON * na[0].hypot(na[1]) * nb[0].hypot(nb[1]) {
                        lam[*a] = ((g[0] * nb[1] - g[1] * nb[0]) / det).max(0.0);
                        lam[*b] = ((na[0] * g[1] - na[1] * g[0]) / det).max(0.0);
                    }
                }
                _ => {
                    for (j, (s, &wij)) in all[i].iter().zip(&w[i]).enumerate() {
                        lam[j] = (wij * (s.unit[0] * x[0] + s.unit[1] * x[1] - s.centre) / s.norm)
                            .max(0.0);
                    }
                }
            }
            lam
        })
        .collect();
    Ok(FixedSolution {
        points: p,
        multipliers: Some(multipliers),
        iterations: iters,
        stencil: None,
        extra: Vec::new(),
        solver_kkt: None,
        certificate: None,
    })
}

/// A curve with its multipliers.
type PointsAndMultipliers = (Points, Vec<Vec<f64>>);

/// One Newton step of the polish (see [`polish_balls`]); `None` if a freed vertex leaves its
/// ball or an active multiplier turns negative.
fn tangential_newton(
    fp: &FixedProblem<'_>,
    radii: &[f64],
    pin: &[Option<Vec<f64>>],
    p: &Points,
    w: &[Vec<f64>],
    scale: f64,
) -> Result<Option<PointsAndMultipliers>, Error> {
    let n = fp.q.len();
    let d = fp.q.dim();
    let h = Hessian::new(fp.knots);
    let hmax = h.bands().0.iter().fold(0.0f64, |a, &x| a.max(x));
    let mut sys = hessian_system(fp.knots, d)?;
    let mut g = operator::apply_h(fp.knots, p);
    for i in 0..n {
        let v = fp.data_vertex[i];
        if radii[i] == 0.0 {
            sys.fix(v)?;
            g[v * d..(v + 1) * d].iter_mut().for_each(|x| *x = 0.0);
        } else if pin[i].is_some() {
            let r: Vec<f64> = p
                .point(v)
                .iter()
                .zip(fp.q.point(i))
                .map(|(a, b)| a - b)
                .collect();
            let rn = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            let wi = w[i][0];
            let mut block = vec![0.0; d * d];
            for a in 0..d {
                g[v * d + a] += wi * r[a];
                for b in 0..d {
                    block[a * d + b] = BALL_POLISH_STIFFNESS * hmax * r[a] * r[b] / (rn * rn);
                }
                block[a * d + a] += wi;
            }
            sys.add_block(v, &block)?;
        }
    }
    let f = sys.factor()?;
    let mut step: Vec<f64> = g.iter().map(|x| -x).collect();
    f.solve_flat(&mut step)?;
    let mut coords = p.coords().to_vec();
    for (x, s) in coords.iter_mut().zip(&step) {
        *x += scale * s;
    }
    for i in 0..n {
        if pin[i].is_some() {
            // Back onto the sphere.
            let v = fp.data_vertex[i];
            let qi = fp.q.point(i);
            let pv = &mut coords[v * d..(v + 1) * d];
            let gap = dist(pv, qi);
            for (x, q) in pv.iter_mut().zip(qi) {
                *x = q + radii[i] * (*x - q) / gap;
            }
        }
    }
    let p2 = Points::new(d, coords)?;
    let hp = operator::apply_h(fp.knots, &p2);
    let mut m = Vec::with_capacity(n);
    for i in 0..n {
        let v = fp.data_vertex[i];
        let qi = fp.q.point(i);
        let hv = &hp[v * d..(v + 1) * d];
        if radii[i] == 0.0 {
            m.push(hv.iter().map(|x| -x).collect());
        } else if pin[i].is_some() {
            let wi = ball_weight(hv, p2.point(v), qi);
            if wi < 0.0 {
                return Ok(None);
            }
            m.push(vec![wi]);
        } else {
            if dist(p2.point(v), qi) > radii[i] {
                return Ok(None);
            }
            m.push(vec![0.0]);
        }
    }
    Ok(Some((p2, m)))
}

pub(crate) fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}
