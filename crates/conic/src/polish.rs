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
//! lemma). At the apex of a cone (s = 0) there is no normal and the polish declines. The backend
//! sees Θ_b with its structure ([`crate::BlockWeight::Active`], [`crate::BlockWeight::Diagonal`]);
//! when a step's refinement stalls far from its target the backend is asked to factor more
//! exactly ([`crate::KktSystem::escalate`]) and the step is repeated.
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

/// The row-space normal u (unit, into `u`: the block's rows), value c and |J s| of a
/// constraint at slack s.
#[inline]
fn normal(con: &Con, s: &[f64], range: std::ops::Range<usize>, u: &mut [f64]) -> (f64, f64) {
    match con.row {
        Some(k) => {
            u.fill(0.0);
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

/// The normals of the active constraints at one slack, flat: constraint ci's normal over its
/// block's rows at `u[off[ci]..off[ci + 1]]`, its value c and |J s|.
#[derive(Default)]
struct Normals {
    u: Vec<f64>,
    off: Vec<usize>,
    c: Vec<f64>,
    js: Vec<f64>,
}

impl Normals {
    /// The normals of `cons` at slack `s`.
    fn at(&mut self, cons: &[Con], cones: &crate::Cones, s: &[f64]) {
        self.off.clear();
        self.off.push(0);
        self.c.clear();
        self.js.clear();
        let total: usize = cons.iter().map(|c| cones.range(c.block).len()).sum();
        self.u.resize(total, 0.0);
        for con in cons {
            let r = cones.range(con.block);
            let start = self.off[self.off.len() - 1];
            let end = start + r.len();
            let (c, js) = normal(con, s, r, &mut self.u[start..end]);
            self.off.push(end);
            self.c.push(c);
            self.js.push(js);
        }
    }

    /// Constraint ci's normal.
    #[inline]
    fn of(&self, ci: usize) -> &[f64] {
        &self.u[self.off[ci]..self.off[ci + 1]]
    }

    /// z = Σ y_ci u_ci over the rows (z zeroed first).
    #[inline]
    fn scatter(&self, cons: &[Con], cones: &crate::Cones, w: impl Fn(usize) -> f64, z: &mut [f64]) {
        z.fill(0.0);
        for (ci, con) in cons.iter().enumerate() {
            let r = cones.range(con.block);
            let wi = w(ci);
            for (zk, uj) in z[r].iter_mut().zip(self.of(ci)) {
                *zk += wi * uj;
            }
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
    let (pt, res, floors) = evaluated(kkt, sol)?;
    let mut out = polish(kkt, &pt, &res, opts, sol.iterations, floors)?;
    out.status = sol.status;
    Some(out)
}

/// `sol` as an iterate of `kkt` with its residuals and the backend's floors; `None` when its
/// vectors do not fit the program.
fn evaluated<K: KktSystem + ?Sized>(
    kkt: &mut K,
    sol: &Solution,
) -> Option<(Point, Residuals, crate::Scales)> {
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
    Some((pt, res, floors))
}

/// The active set the polish starts from (module docs): the constraints, sorted by block and
/// row, and which rows they hold; `None` when an active second-order block is at its apex.
fn active_set<K: KktSystem + ?Sized>(
    kkt: &K,
    pt: &Point,
    res: &Residuals,
    po: &crate::PolishOptions,
) -> Option<(Vec<Con>, Vec<bool>)> {
    let cones = kkt.cones();
    let m = cones.rows();
    let (force, length) = (res.force, res.length);
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
    Some((cons, member))
}

/// Which blocks hold a constraint of the active set the polish would start from at `sol`
/// (its x, s and z; module docs), `None` when it cannot be formed (a second-order block at its
/// apex, a malformed solution, no polish options). A caller may pose the polish's problem on
/// those blocks alone.
pub fn active_blocks<K: KktSystem + ?Sized>(
    kkt: &mut K,
    sol: &Solution,
    opts: &Options,
) -> Option<Vec<bool>> {
    let po = opts.polish.as_ref()?;
    let (pt, res, _) = evaluated(kkt, sol)?;
    let (cons, _) = active_set(kkt, &pt, &res, po)?;
    let mut blocks = vec![false; kkt.cones().len()];
    for c in &cons {
        blocks[c.block] = true;
    }
    Some(blocks)
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
    let (mut cons, mut member) = active_set(kkt, pt, res, po)?;
    let mut x = pt.x.clone();
    let mut best: Option<Solution> = None;
    let mut ax = vec![0.0; m];
    let mut s = vec![0.0; m];
    let mut z = vec![0.0; m];
    let mut g = vec![0.0; n];
    let mut atz = vec![0.0; n];
    let mut rhs1 = vec![0.0; n];
    let mut normals = Normals::default();
    let mut changes = 0;
    let mut taken = 0;
    let mut weights = Weights::zero(&cones);
    let mut theta = Vec::new();
    let mut delta = Vec::new();
    let mut work = SaddleWork::new(n, m);
    let slack = |kkt: &K, ax: &[f64], s: &mut [f64]| {
        for ((sv, b), a) in s.iter_mut().zip(kkt.b()).zip(ax) {
            *sv = b - a;
        }
    };
    while taken < po.steps {
        taken += 1;
        // s(x), normals, values, z = Σ y u.
        kkt.apply_a(&x, &mut ax);
        slack(kkt, &ax, &mut s);
        normals.at(&cons, &cones, &s);
        normals.scatter(&cons, &cones, |ci| cons[ci].y, &mut z);
        // Θ per block: curvature and penalty of an active second-order constraint, the
        // penalties of a block's active rows.
        weights.clear();
        delta.clear();
        let mut ci = 0;
        while ci < cons.len() {
            let bi = cons[ci].block;
            let dl = po.penalty / kkt.diagonal_scale(bi).max(f64::MIN_POSITIVE);
            if cons[ci].row.is_none() {
                delta.push(dl);
                weights.set_active(bi, cons[ci].y / normals.js[ci], 1.0 / dl, normals.of(ci));
                ci += 1;
                continue;
            }
            // The block's active rows (cons is sorted by block and row).
            let r = cones.range(bi);
            theta.clear();
            theta.resize(r.len(), 0.0);
            while ci < cons.len() && cons[ci].block == bi {
                let k = cons[ci].row.expect("a row constraint");
                theta[k - r.start] += 1.0 / dl;
                delta.push(dl);
                ci += 1;
            }
            weights.set_diagonal(bi, &theta);
        }
        if kkt.factor(&weights, 0.0).is_err() {
            return best;
        }
        // Stationarity R = g + Aᵀz.
        kkt.gradient(&x, &mut g);
        kkt.apply_at(&z, &mut atz);
        for ((r, a), b) in rhs1.iter_mut().zip(&g).zip(&atz) {
            *r = -(a + b);
        }
        // Inexact Newton: each solve is refined only to a hundredth of the current residual of
        // the system (stationarity over F, constraint values over L), which keeps the steps'
        // fast convergence and saves refinement solves early on.
        let current = (inf_norm(&rhs1) / force).max(inf_norm(&normals.c) / length);
        let rtol = (1e-2 * current).clamp(1e-15, 1e-6);
        let accurate = saddle_solve(
            kkt,
            &cones,
            &cons,
            &normals,
            &delta,
            &rhs1,
            po.refinement_steps,
            rtol,
            &mut work,
        );
        if !accurate && kkt.escalate() {
            // The backend's factorization was too far from the system for this step (e.g. a
            // condensation regularized where the polish leaves points free); it now factors
            // exactly: the same step again.
            taken -= 1;
            continue;
        }
        let (dx, dy) = (&work.dx, &work.dy);
        if dx.iter().chain(dy).any(|v| !v.is_finite()) {
            return best;
        }
        for (a, d) in x.iter_mut().zip(dx) {
            *a += d;
        }
        for (c, d) in cons.iter_mut().zip(dy) {
            c.y += d;
        }
        // Active-set changes.
        kkt.apply_a(&x, &mut ax);
        slack(kkt, &ax, &mut s);
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
        normals.at(&cons, &cones, &s);
        normals.scatter(&cons, &cones, |ci| cons[ci].y, &mut z);
        let active_violation = normals
            .c
            .iter()
            .fold(0.0f64, |a, c| a.max(c.abs() / length));
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
                z: z.clone(),
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

/// Work vectors of [`saddle_solve`] (allocated once per polish): the step (dx, dy) and the
/// buffers of its refinement.
struct SaddleWork {
    dx: Vec<f64>,
    dy: Vec<f64>,
    e1: Vec<f64>,
    e2: Vec<f64>,
    w: Vec<f64>,
    row: Vec<f64>,
    extra: Vec<f64>,
    tmp_n: Vec<f64>,
    at: Vec<f64>,
    r: Vec<f64>,
    av: Vec<f64>,
}

impl SaddleWork {
    fn new(n: usize, m: usize) -> Self {
        SaddleWork {
            dx: vec![0.0; n],
            dy: Vec::new(),
            e1: vec![0.0; n],
            e2: Vec::new(),
            w: Vec::new(),
            row: vec![0.0; m],
            extra: vec![0.0; m],
            tmp_n: vec![0.0; n],
            at: vec![0.0; n],
            r: vec![0.0; n],
            av: vec![0.0; m],
        }
    }
}

/// Solves [H_L G̃ᵀ; G̃ 0][dx; dy] = [b1; c] (c the normals' values) with the factorization of
/// H_L + G̃ᵀΔ⁻¹G̃ and iterative refinement to `rtol` × the right-hand side (module docs), into
/// `ws.dx`, `ws.dy`. Returns whether the refinement got within a hundred times `rtol` (and at
/// least 1e-4) of its target, as the method's directions ([`crate::KktSystem::escalate`]).
#[allow(clippy::too_many_arguments)]
fn saddle_solve<K: KktSystem + ?Sized>(
    kkt: &mut K,
    cones: &crate::Cones,
    cons: &[Con],
    normals: &Normals,
    delta: &[f64],
    b1: &[f64],
    steps: usize,
    rtol: f64,
    ws: &mut SaddleWork,
) -> bool {
    let c = &normals.c;
    let nc = cons.len();
    // G̃ v per constraint from A v; G̃ᵀ w as Aᵀ(Σ w_j u_j).
    let g_apply = |av: &[f64], ci: usize| -> f64 {
        let r = cones.range(cons[ci].block);
        dot(normals.of(ci), &av[r])
    };
    // Curvature part of H_L: Aᵀ Θc A with Θc = −(y/|Js|) J on active cones.
    let curvature = |av: &[f64], out: &mut [f64]| {
        out.fill(0.0);
        for (ci, con) in cons.iter().enumerate() {
            if con.row.is_none() {
                let r = cones.range(con.block);
                let w = con.y / normals.js[ci];
                for (j, k) in r.enumerate() {
                    out[k] += if j == 0 { -w * av[k] } else { w * av[k] };
                }
            }
        }
    };
    ws.dx.fill(0.0);
    ws.dy.clear();
    ws.dy.resize(nc, 0.0);
    ws.e1.copy_from_slice(b1);
    ws.e2.clear();
    ws.e2.extend_from_slice(c);
    let bnorm = inf_norm(b1).max(inf_norm(c)).max(f64::MIN_POSITIVE);
    let mut last = f64::INFINITY;
    let mut reached = steps == 0;
    for step in 0..=steps {
        // ddx = K⁻¹(e1 + G̃ᵀΔ⁻¹e2), ddy = (G̃ ddx − e2)/δ.
        ws.w.clear();
        ws.w.extend(ws.e2.iter().zip(delta).map(|(e, d)| e / d));
        let w = &ws.w;
        normals.scatter(cons, cones, |ci| w[ci], &mut ws.row);
        kkt.apply_at(&ws.row, &mut ws.tmp_n);
        for ((r, a), b) in ws.r.iter_mut().zip(&ws.e1).zip(&ws.tmp_n) {
            *r = a + b;
        }
        kkt.solve(&mut ws.r);
        kkt.apply_a(&ws.r, &mut ws.av);
        for (a, b) in ws.dx.iter_mut().zip(&ws.r) {
            *a += b;
        }
        for (ci, (dy, (e, dl))) in ws.dy.iter_mut().zip(ws.e2.iter().zip(delta)).enumerate() {
            *dy += (g_apply(&ws.av, ci) - e) / dl;
        }
        if step == steps {
            break;
        }
        // e1 = b1 − H_L dx − G̃ᵀdy, e2 = c − G̃ dx.
        kkt.apply_p(&ws.dx, &mut ws.tmp_n);
        kkt.apply_a(&ws.dx, &mut ws.av);
        curvature(&ws.av, &mut ws.row);
        let dy = &ws.dy;
        normals.scatter(cons, cones, |ci| dy[ci], &mut ws.extra);
        for (a, b) in ws.row.iter_mut().zip(&ws.extra) {
            *a += b;
        }
        kkt.apply_at(&ws.row, &mut ws.at);
        for ((e, b), (t, a)) in ws.e1.iter_mut().zip(b1).zip(ws.tmp_n.iter().zip(&ws.at)) {
            *e = b - t - a;
        }
        for (ci, (e, cv)) in ws.e2.iter_mut().zip(c).enumerate() {
            *e = cv - g_apply(&ws.av, ci);
        }
        let rn = inf_norm(&ws.e1).max(inf_norm(&ws.e2));
        reached = rn <= (1e2 * rtol).max(1e-4) * bnorm;
        // Stop at the target or when a step no longer halves the residual.
        if !rn.is_finite() || rn > 0.5 * last || rn <= rtol * bnorm {
            break;
        }
        last = rn;
    }
    reached
}
