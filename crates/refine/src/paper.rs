//! Kersey's multiplier iteration, Algorithm 4.1 (iii), kept to reproduce the seed's figures
//! ([`crate::Solver::Paper`]): balls by the weight update w_i := w_i |p_{i_k} − q_i| / ε_i, planar
//! polygons by the slot iteration of Fig. 4.1 ([`crate::slots`]). Approximate; the exact
//! solver ([`crate::strategy`]) is the default.

use divdiff::Points;
use energy::Hessian;

use crate::constraint::{dist, Constraint};
use crate::operator;
use crate::stage::{FixedProblem, FixedSolution};
use crate::Error;

/// Kersey's multiplier iteration, Algorithm 4.1 (iii): start from w_i = 1, solve
/// (H + W)p = W q̃ (radius-0 points interpolated), update w_i := w_i |p_{i_k} − q_i| / ε_i, and
/// repeat `paper_iterations` times. The reported multipliers are the weights of the last solve,
/// so (H + W)p = W q̃ holds to rounding and the KKT residual measures the complementarity the
/// iteration has not reached.
pub(crate) fn paper(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    if fp.has_derivatives() {
        return Err(Error::Unsupported {
            field: "solver",
            reason: "the paper's iteration handles data constraints only; use the exact solver for tangents and end conditions",
        });
    }
    let n = fp.q.len();
    match fp.constraint {
        Constraint::Interpolate | Constraint::Smoothing(_) => crate::linear::solve(fp, 1),
        Constraint::Balls(r) => {
            let fixed: Vec<bool> = r.iter().map(|&e| e == 0.0).collect();
            if fixed.iter().all(|&f| f) {
                return crate::linear::interpolate(fp);
            }
            let h = Hessian::new(fp.knots);
            let floor =
                fp.options.paper.weight_floor * h.bands().0.iter().sum::<f64>() / h.len() as f64;
            let mut w: Vec<f64> = fixed.iter().map(|&f| if f { 0.0 } else { 1.0 }).collect();
            let d = fp.q.dim();
            let iters = fp.problem.paper_iterations.max(1);
            let mut p = crate::linear::linear(fp, &fixed, &w, 1)?;
            for _ in 1..iters {
                for i in 0..n {
                    if !fixed[i] {
                        let v = fp.data_vertex[i];
                        let gap = dist(p.point(v), fp.q.point(i));
                        w[i] = (w[i] * gap / r[i]).max(floor);
                    }
                }
                p = crate::linear::linear(fp, &fixed, &w, 1)?;
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
            Ok(FixedSolution::new(p, Some(multipliers), iters))
        }
        Constraint::HalfSpaces(sets) => paper_slots(fp, sets),
    }
}

/// The paper's slot iteration for polygonal constraints in the plane (Fig. 4.1; see
/// [`crate::slots`]): one d×d spring block per slot at its data vertex, weights updated by
/// w := w |u·p − m| / ε.
fn paper_slots(
    fp: &FixedProblem<'_>,
    sets: &[Vec<crate::constraint::HalfSpace>],
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
    let floor = fp.options.paper.weight_floor * h.bands().0.iter().sum::<f64>() / h.len() as f64;
    let mut w: Vec<Vec<f64>> = all.iter().map(|s| vec![1.0; s.len()]).collect();
    let solve = |w: &[Vec<f64>]| -> Result<Points, Error> {
        let mut sys = crate::linear::hessian_system(h.clone(), d)?;
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
    Ok(FixedSolution::new(p, Some(multipliers), iters))
}
