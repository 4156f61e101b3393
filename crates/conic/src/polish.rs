//! The active-set polish: Newton's method on the KKT system of the constraints an
//! interior-point iterate identifies as active.
//!
//! Off the central path an interior-point iterate approaches the optimum only like √μ in some
//! directions (the vector part of s ∘ z on a second-order cone, weakly active rows); its
//! certificate stalls at 1e-8…1e-6 on hard problems. The polish takes the active set from the
//! iterate and solves the equality-constrained problem it defines:
//!
//! - an orthant row k with z_k/s_k ≥ F/L (or a slack within [`crate::PolishOptions::active_rtol`]
//!   of 0) becomes the equality c(x) = s_k(x) = b_k − A_k x = 0 with multiplier y = z_k;
//! - a second-order block with |s||z| ≥ [`crate::PolishOptions::soc_ratio`] · sᵀz whose
//!   stiffness y/(s_0 − |s̄|), y = z_0|s|/s_0, competes with P's
//!   ([`crate::KktSystem::diagonal_scale`]) (or near its boundary) becomes
//!   c(x) = ½ J(s(x)) / |J s| = 0 (the boundary |s̄| = s_0, scaled to unit normal in row space)
//!   with z = y J s/|J s|;
//! - every zero-cone row stays an equality.
//!
//! With the unit row-space normals u_j (e_k, or J s/|J s|), G̃_j = u_jᵀA_b and the Lagrangian
//! L = f − Σ y_j c_j, whose Hessian is H_L = P − Σ_SOC (y_j/|J s|) A_bᵀJA_b, each step solves
//!
//!   [H_L  G̃ᵀ] [dx]   [−(Px + q + Aᵀz)]
//!   [G̃    0 ] [dy] = [ c(x)           ]
//!
//! by factoring H_L + G̃ᵀΔ⁻¹G̃ (Θ_b = −(y/|Js|)J + u uᵀ/δ on an active cone, e_k e_kᵀ/δ on an
//! active row: the *stiff penalty* that holds the normals; δ = [`crate::PolishOptions::penalty`]
//! relative to the block's diagonal scale) and refining against the system above, so the penalty
//! leaves no trace in the step. For a ball (b = (ε, q), rows (0; I)) the curvature term is y/ε I,
//! positive; for a direction wedge it is indefinite along the axis, and the penalty on the normal
//! makes the factored matrix definite where the problem's second-order condition holds (Finsler's
//! lemma). At the apex of a cone (s = 0) there is no normal and the polish declines.
//!
//! After each step a violated inactive constraint joins the set and an active one whose
//! multiplier turned negative leaves it (a primal active-set method started from the
//! interior-point iterate), the step being retried from the previous point, at most
//! [`crate::PolishOptions::active_changes`] times. Every step's point is certified
//! ([`crate::Residuals`]) and the best is kept. The steps go on (at most
//! [`crate::PolishOptions::steps`]) until the point is certified at the tolerance *and* its
//! stationarity residual is at the tolerance of the largest force it actually carries
//! ([`crate::Residuals::reaction`]) or at rounding: F's floor can exceed the reactions by orders
//! of magnitude, and one more Newton step costs less than a caller's refusal. (Nocedal & Wright, *Numerical Optimization*,
//! §18.1 for the Newton–KKT step; §16.5 for the active-set changes.)

use crate::cone::{distance_to_cone, soc_residual, Kind};
use crate::ipm::{certify, Point, Solution, Status};
use crate::residual::Residuals;
use crate::vector::{dot, inf_norm, norm};
use crate::{KktSystem, Options, Weights};

/// One constraint of the active set.
#[derive(Clone, Copy, Debug)]
struct Con {
    block: usize,
    /// The row for a zero or orthant row; `None` for a whole second-order block.
    row: Option<usize>,
    /// The multiplier y.
    y: f64,
}

/// The row-space normal u (unit), value c and |J s| of a constraint at slack s.
fn normal(con: &Con, s: &[f64], range: std::ops::Range<usize>, u: &mut Vec<f64>) -> (f64, f64) {
    u.clear();
    u.resize(range.len(), 0.0);
    match con.row {
        Some(k) => {
            u[k - range.start] = 1.0;
            (s[k], 1.0)
        }
        None => {
            let sb = &s[range];
            for (j, v) in sb.iter().enumerate() {
                u[j] = if j == 0 { *v } else { -*v };
            }
            let nj = norm(u).max(f64::MIN_POSITIVE);
            u.iter_mut().for_each(|v| *v /= nj);
            (0.5 * soc_residual(sb) / nj, nj)
        }
    }
}

/// Polishes a returned solution (its x, s and z; e.g. one the caller's own certificate does
/// not accept): the polish of [`crate::solve`] run on demand. `None` if the active set cannot be
/// formed or no step succeeds; otherwise the polished point with its certificate (keep it only
/// if that is better).
pub fn polish_solution<K: KktSystem + ?Sized>(
    kkt: &mut K,
    sol: &Solution,
    opts: &Options,
) -> Option<Solution> {
    let (n, m) = (kkt.num_vars(), kkt.cones().rows());
    if sol.x.len() != n || sol.s.len() != m || sol.z.len() != m {
        return None;
    }
    let floors = crate::ipm::floors(kkt);
    let pt = Point {
        x: sol.x.clone(),
        s: sol.s.clone(),
        z: sol.z.clone(),
    };
    let mut w = crate::ipm::Work::new(n, m);
    let (res, _) = crate::ipm::evaluate(kkt, &pt, &mut w, floors);
    let mut out = polish(kkt, &pt, &res, opts, sol.iterations, floors)?;
    out.status = sol.status;
    Some(out)
}

/// Polishes the interior-point iterate `pt` (with its residuals `res`); `None` if the active
/// set cannot be formed (a cone at its apex) or no step succeeds.
pub(crate) fn polish<K: KktSystem + ?Sized>(
    kkt: &mut K,
    pt: &Point,
    res: &Residuals,
    opts: &Options,
    iterations: usize,
    floors: crate::Scales,
) -> Option<Solution> {
    let po = opts.polish.as_ref()?;
    let cones = kkt.cones().clone();
    let (n, m) = (kkt.num_vars(), cones.rows());
    let (force, length) = (res.force, res.length);
    // The active set.
    let mut cons: Vec<Con> = Vec::new();
    let mut member = vec![false; m];
    for (bi, cone) in cones.blocks().iter().enumerate() {
        let r = cones.range(bi);
        let (s, z) = (&pt.s[r.clone()], &pt.z[r.clone()]);
        match cone.kind() {
            Kind::Zero => {
                for k in r {
                    cons.push(Con {
                        block: bi,
                        row: Some(k),
                        y: pt.z[k],
                    });
                    member[k] = true;
                }
            }
            Kind::Nonnegative => {
                let size = norm(s).max(f64::MIN_POSITIVE);
                for (j, k) in r.enumerate() {
                    if z[j] * length >= s[j] * force || s[j] <= po.active_rtol * size {
                        cons.push(Con {
                            block: bi,
                            row: Some(k),
                            y: z[j],
                        });
                        member[k] = true;
                    }
                }
            }
            Kind::SecondOrder => {
                let boundary = s[0] - norm(&s[1..]);
                // y, the multiplier on the unit row-space normal J s/|J s| (|J s| = |s|), over the
                // distance to the boundary is the stiffness with which the block holds the point;
                // it is engaged when that competes with P's (`diagonal_scale`, in the block's own
                // row units), as an orthant row's z/s against F/L. The ratio test alone is, on the
                // central path, only "within 1/ratio of the boundary", and it passes z = 0 (a
                // polished point's inactive block): pulling such a block onto its boundary moves
                // the point away from the optimum, which the steps left after dropping it again do
                // not recover (ROBUSTNESS.md, limit 10).
                let y = z[0] / s[0].max(f64::MIN_POSITIVE) * norm(s);
                let engaged = norm(s) * norm(z) >= po.soc_ratio * dot(s, z)
                    && y >= boundary * kkt.diagonal_scale(bi);
                if engaged || boundary <= po.active_rtol * s[0] {
                    if norm(s) <= 1e-9 * length {
                        // The apex: J s carries no direction.
                        return None;
                    }
                    cons.push(Con {
                        block: bi,
                        row: None,
                        y,
                    });
                    for k in r {
                        member[k] = true;
                    }
                }
            }
        }
    }
    let mut x = pt.x.clone();
    let mut best: Option<Solution> = None;
    let mut ax = vec![0.0; m];
    let mut g = vec![0.0; n];
    let mut u = Vec::new();
    let mut changes = 0;
    let mut taken = 0;
    let mut weights = Weights::zero(&cones);
    let mut dense = Vec::new();
    while taken < po.steps {
        taken += 1;
        // s(x), normals, values, z = Σ y u.
        kkt.apply_a(&x, &mut ax);
        let s: Vec<f64> = kkt.b().iter().zip(&ax).map(|(b, a)| b - a).collect();
        let mut normals: Vec<(Vec<f64>, f64, f64)> = Vec::with_capacity(cons.len());
        let mut z = vec![0.0; m];
        for con in &cons {
            let r = cones.range(con.block);
            let (c, js) = normal(con, &s, r.clone(), &mut u);
            for (j, k) in r.enumerate() {
                z[k] += con.y * u[j];
            }
            normals.push((u.clone(), c, js));
        }
        // Θ: curvature and penalties per block.
        weights.clear();
        let mut delta = vec![0.0; cons.len()];
        // The constraints of each block, in order (cons is kept sorted by block).
        let mut per_block: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
        for (ci, con) in cons.iter().enumerate() {
            delta[ci] = po.penalty / kkt.diagonal_scale(con.block).max(f64::MIN_POSITIVE);
            match per_block.last_mut() {
                Some((b, r)) if *b == con.block => r.end = ci + 1,
                _ => per_block.push((con.block, ci..ci + 1)),
            }
        }
        for (bi, members) in per_block {
            let mb = cones.blocks()[bi].dim();
            dense.clear();
            dense.resize(mb * mb, 0.0);
            for ci in members {
                let con = &cons[ci];
                let (uj, _, js) = &normals[ci];
                if con.row.is_none() {
                    // −(y/|Js|) J.
                    let w = con.y / js;
                    for j in 0..mb {
                        dense[j * mb + j] += if j == 0 { -w } else { w };
                    }
                }
                for a in 0..mb {
                    for b in 0..mb {
                        dense[a * mb + b] += uj[a] * uj[b] / delta[ci];
                    }
                }
            }
            weights.set_dense(bi, &dense);
        }
        if kkt.factor(&weights, 0.0).is_err() {
            return best;
        }
        // Stationarity R = g + Aᵀz.
        kkt.gradient(&x, &mut g);
        let mut atz = vec![0.0; n];
        kkt.apply_at(&z, &mut atz);
        let rhs1: Vec<f64> = g.iter().zip(&atz).map(|(a, b)| -(a + b)).collect();
        let cvals: Vec<f64> = normals.iter().map(|v| v.1).collect();
        // Inexact Newton: each solve is refined only to a hundredth of the current residual of
        // the system (stationarity over F, constraint values over L), which keeps the steps'
        // fast convergence and saves refinement solves early on.
        let current = (inf_norm(&rhs1) / force).max(inf_norm(&cvals) / length);
        let rtol = (1e-2 * current).clamp(1e-15, 1e-6);
        let (dx, dy) = saddle_solve(
            kkt,
            &cons,
            &normals,
            &delta,
            &rhs1,
            &cvals,
            po.refinement_steps,
            rtol,
        );
        if dx.iter().chain(&dy).any(|v| !v.is_finite()) {
            return best;
        }
        for (a, d) in x.iter_mut().zip(&dx) {
            *a += d;
        }
        for (c, d) in cons.iter_mut().zip(&dy) {
            c.y += d;
        }
        // Active-set changes.
        kkt.apply_a(&x, &mut ax);
        let s: Vec<f64> = kkt.b().iter().zip(&ax).map(|(b, a)| b - a).collect();
        let ymax = cons.iter().fold(0.0f64, |a, c| a.max(c.y.abs()));
        let mut drop = vec![false; cons.len()];
        let mut add: Vec<Con> = Vec::new();
        for (ci, con) in cons.iter().enumerate() {
            let kind = cones.blocks()[con.block].kind();
            if kind != Kind::Zero && con.y < -1e-12 * ymax {
                drop[ci] = true;
            }
        }
        let mut inactive_violation: f64 = 0.0;
        for (bi, cone) in cones.blocks().iter().enumerate() {
            let r = cones.range(bi);
            match cone.kind() {
                Kind::Zero => {}
                Kind::Nonnegative => {
                    for k in r {
                        if !member[k] && s[k] < 0.0 {
                            inactive_violation = inactive_violation.max(-s[k] / length);
                            if -s[k] > opts.tolerance * length {
                                add.push(Con {
                                    block: bi,
                                    row: Some(k),
                                    y: 0.0,
                                });
                            }
                        }
                    }
                }
                Kind::SecondOrder => {
                    if !member[r.start] {
                        let dist = distance_to_cone(Kind::SecondOrder, &s[r.clone()]) / length;
                        inactive_violation = inactive_violation.max(dist);
                        if dist > opts.tolerance {
                            add.push(Con {
                                block: bi,
                                row: None,
                                y: 0.0,
                            });
                        }
                    }
                }
            }
        }
        // Certificate of the new point: z from the multipliers at the new normals.
        let mut z = vec![0.0; m];
        let mut active_violation: f64 = 0.0;
        for con in &cons {
            let r = cones.range(con.block);
            let (c, _) = normal(con, &s, r.clone(), &mut u);
            active_violation = active_violation.max(c.abs() / length);
            for (j, k) in r.enumerate() {
                z[k] += con.y * u[j];
            }
        }
        let (cert, s_out, objective) = certify(kkt, &x, &z, floors);
        let done = cert.total <= opts.tolerance && settled(&cert, opts.tolerance);
        let hopeless = inactive_violation > opts.tolerance
            && inactive_violation > po.abandon_ratio * cert.stationarity.max(active_violation);
        if best
            .as_ref()
            .is_none_or(|b| cert.total < b.residuals.total || b.residuals.total.is_nan())
        {
            best = Some(Solution {
                x: x.clone(),
                s: s_out,
                z,
                residuals: cert,
                objective,
                iterations,
                status: Status::Converged,
                polished: true,
            });
        }
        let want_change = drop.iter().any(|&d| d) || !add.is_empty();
        if want_change && changes < po.active_changes && !done {
            // Continue from the new point with the corrected set (Newton pulls a joining
            // constraint onto its boundary and lets a leaving one go); the step is not counted.
            changes += 1;
            taken -= 1;
            let mut kept = Vec::with_capacity(cons.len());
            for (ci, con) in cons.iter().enumerate() {
                if drop[ci] {
                    let r = cones.range(con.block);
                    match con.row {
                        Some(k) => member[k] = false,
                        None => r.for_each(|k| member[k] = false),
                    }
                } else {
                    kept.push(*con);
                }
            }
            for con in add {
                let r = cones.range(con.block);
                if con.block < cones.len() && cones.blocks()[con.block].kind() == Kind::SecondOrder
                {
                    // A second-order block joining needs a normal: not at its apex.
                    let sb = &s[r.clone()];
                    if norm(sb) <= 1e-9 * length {
                        continue;
                    }
                }
                match con.row {
                    Some(k) => member[k] = true,
                    None => r.for_each(|k| member[k] = true),
                }
                kept.push(con);
            }
            kept.sort_by_key(|c| (c.block, c.row));
            cons = kept;
            continue;
        }
        if done || hopeless {
            break;
        }
    }
    best
}

/// The multiple of ε F that bounds the rounding in g + Aᵀz (F with its floor: the size of the
/// terms the residual is summed from).
const ROUNDING_MULTIPLE: f64 = 16.0;

/// Whether the stationarity residual is at `tolerance` of the forces the point actually carries
/// ([`Residuals::reaction`]), or is rounding: the polish's Newton steps go on until then.
/// [`Residuals::stationarity`] is relative to F, whose floor F₀ (the backend's force scale,
/// ‖q‖∞) can exceed the reactions of a finely refined curve by orders of magnitude — stopping
/// there left 1e-9 of the largest reaction unbalanced, which a certificate relative to that
/// reaction (refine's) refuses (ROBUSTNESS.md, limit 10). A residual of ROUNDING_MULTIPLE ε F
/// counts as `tolerance`.
fn settled(cert: &Residuals, tolerance: f64) -> bool {
    let scale = cert
        .reaction
        .max(ROUNDING_MULTIPLE * f64::EPSILON * cert.force / tolerance);
    cert.stationarity * cert.force <= tolerance * scale
}

/// Solves [H_L G̃ᵀ; G̃ 0][dx; dy] = [b1; c] with the factorization of H_L + G̃ᵀΔ⁻¹G̃ and
/// iterative refinement to `rtol` × the right-hand side (module docs).
#[allow(clippy::too_many_arguments)]
fn saddle_solve<K: KktSystem + ?Sized>(
    kkt: &mut K,
    cons: &[Con],
    normals: &[(Vec<f64>, f64, f64)],
    delta: &[f64],
    b1: &[f64],
    c: &[f64],
    steps: usize,
    rtol: f64,
) -> (Vec<f64>, Vec<f64>) {
    let cones = kkt.cones().clone();
    let (n, m) = (kkt.num_vars(), cones.rows());
    // G̃ v per constraint from A v; G̃ᵀ w as Aᵀ(Σ w_j u_j).
    let g_apply = |av: &[f64], ci: usize| -> f64 {
        let r = cones.range(cons[ci].block);
        dot(&normals[ci].0, &av[r])
    };
    let scatter = |w: &[f64], out: &mut [f64]| {
        out.fill(0.0);
        for (ci, con) in cons.iter().enumerate() {
            let r = cones.range(con.block);
            for (j, k) in r.enumerate() {
                out[k] += w[ci] * normals[ci].0[j];
            }
        }
    };
    // Curvature part of H_L: Aᵀ Θc A with Θc = −(y/|Js|) J on active cones.
    let curvature = |av: &[f64], out: &mut [f64]| {
        out.fill(0.0);
        for (ci, con) in cons.iter().enumerate() {
            if con.row.is_none() {
                let r = cones.range(con.block);
                let w = con.y / normals[ci].2;
                for (j, k) in r.enumerate() {
                    out[k] += if j == 0 { -w * av[k] } else { w * av[k] };
                }
            }
        }
    };
    let mut dx = vec![0.0; n];
    let mut dy = vec![0.0; cons.len()];
    let mut e1 = b1.to_vec();
    let mut e2 = c.to_vec();
    let bnorm = inf_norm(b1).max(inf_norm(c)).max(f64::MIN_POSITIVE);
    let mut row = vec![0.0; m];
    let mut tmp_n = vec![0.0; n];
    let mut av = vec![0.0; m];
    let mut last = f64::INFINITY;
    for step in 0..=steps {
        // ddx = K⁻¹(e1 + G̃ᵀΔ⁻¹e2), ddy = (G̃ ddx − e2)/δ.
        let w: Vec<f64> = e2.iter().zip(delta).map(|(e, d)| e / d).collect();
        scatter(&w, &mut row);
        kkt.apply_at(&row, &mut tmp_n);
        let mut r: Vec<f64> = e1.iter().zip(&tmp_n).map(|(a, b)| a + b).collect();
        kkt.solve(&mut r);
        kkt.apply_a(&r, &mut av);
        for (a, b) in dx.iter_mut().zip(&r) {
            *a += b;
        }
        for ci in 0..cons.len() {
            dy[ci] += (g_apply(&av, ci) - e2[ci]) / delta[ci];
        }
        if step == steps {
            break;
        }
        // e1 = b1 − H_L dx − G̃ᵀdy, e2 = c − G̃ dx.
        kkt.apply_p(&dx, &mut tmp_n);
        kkt.apply_a(&dx, &mut av);
        curvature(&av, &mut row);
        let mut extra = vec![0.0; m];
        scatter(&dy, &mut extra);
        for (a, b) in row.iter_mut().zip(&extra) {
            *a += b;
        }
        let mut at = vec![0.0; n];
        kkt.apply_at(&row, &mut at);
        for i in 0..n {
            e1[i] = b1[i] - tmp_n[i] - at[i];
        }
        for ci in 0..cons.len() {
            e2[ci] = c[ci] - g_apply(&av, ci);
        }
        let rn = inf_norm(&e1).max(inf_norm(&e2));
        // Stop at the target or when a step no longer halves the residual.
        if !rn.is_finite() || rn > 0.5 * last || rn <= rtol * bnorm {
            break;
        }
        last = rn;
    }
    (dx, dy)
}
