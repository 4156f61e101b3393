//! The primal–dual interior-point method: Mehrotra's predictor–corrector with Nesterov–Todd
//! scaling (crate docs for the math and sources).

use crate::cone::{soc_residual, Kind};
use crate::product;
use crate::residual::{self, Parts, Residuals};
use crate::vector::{inf_norm, norm};
use crate::{Error, KktSystem, Options, Weights};

/// A starting point: x alone (the slacks are derived from it and shifted into the interior, the
/// duals centred), or x, s and z all given (s and z strictly inside their cones on every
/// non-zero block).
#[derive(Clone, Debug, PartialEq)]
pub struct Start {
    /// x.
    pub x: Vec<f64>,
    /// s and z, or `None` to derive them.
    pub sz: Option<(Vec<f64>, Vec<f64>)>,
}

/// What a [`Monitor`] sees after each iterate's residuals are computed.
#[derive(Clone, Copy, Debug)]
pub struct Iterate<'a> {
    /// The iteration (0 = the start).
    pub iteration: usize,
    /// x, s, z.
    pub x: &'a [f64],
    /// s.
    pub s: &'a [f64],
    /// z.
    pub z: &'a [f64],
    /// The iterate's relative residuals.
    pub residuals: Residuals,
}

/// Watches the iterates; returning `false` from [`Monitor::iterate`] stops the method with
/// [`Status::Stopped`] and the current iterate (e.g. a working set that judges a round as soon
/// as its iterate is good enough to tell).
pub trait Monitor {
    /// Called after each iterate's residuals are computed.
    fn iterate(&mut self, it: &Iterate<'_>) -> bool;
}

/// A monitor that never stops the method.
pub struct NoMonitor;

impl Monitor for NoMonitor {
    fn iterate(&mut self, _: &Iterate<'_>) -> bool {
        true
    }
}

impl<F: FnMut(&Iterate<'_>) -> bool> Monitor for F {
    fn iterate(&mut self, it: &Iterate<'_>) -> bool {
        self(it)
    }
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The residual reached [`Options::tolerance`] (the returned point's certificate may still
    /// be above it; the caller's acceptance test decides).
    Converged,
    /// The iteration limit was reached; the best iterate is returned.
    MaxIterations,
    /// A Newton matrix did not factor or a step was not finite; the best iterate is returned.
    Stalled,
    /// The [`Monitor`] stopped the method; the current iterate is returned, unpolished.
    Stopped,
}

/// The result of [`crate::solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// x.
    pub x: Vec<f64>,
    /// s: b − Ax, except after [`Status::Stopped`], where it is the iterate's own slack (with
    /// x and z a valid [`Start`] to resume from).
    pub s: Vec<f64>,
    /// The dual z.
    pub z: Vec<f64>,
    /// The certificate of (x, z) (module [`crate::residual`]).
    pub residuals: Residuals,
    /// The objective ½xᵀPx + qᵀx + c.
    pub objective: f64,
    /// Interior-point iterations.
    pub iterations: usize,
    /// How the method ended.
    pub status: Status,
    /// Whether the returned point comes from the active-set polish.
    pub polished: bool,
}

impl Solution {
    /// `Ok(self)` if the certificate is at most `accept`, else [`Error::NotConverged`] with the
    /// certificate (NaN refuses too).
    ///
    /// # Errors
    /// As described.
    pub fn accepted(self, accept: f64) -> Result<Self, Error> {
        if self.residuals.total <= accept {
            Ok(self)
        } else {
            Err(Error::NotConverged {
                solver: "conic interior-point method",
                iterations: self.iterations,
                residual: self.residuals.total,
            })
        }
    }
}

/// Work vectors of one run.
pub(crate) struct Work {
    g: Vec<f64>,
    atz: Vec<f64>,
    ax: Vec<f64>,
    rx: Vec<f64>,
    rs: Vec<f64>,
}

/// The iterate.
#[derive(Clone)]
pub(crate) struct Point {
    pub x: Vec<f64>,
    pub s: Vec<f64>,
    pub z: Vec<f64>,
}

/// The scales below which the residuals do not divide: the backend's [`crate::Scales`], raised
/// to ‖q‖∞ (the force of the linear term, from P·0 + q) and ‖b‖∞.
pub(crate) fn floors<K: KktSystem + ?Sized>(kkt: &mut K) -> crate::Scales {
    let n = kkt.num_vars();
    let mut q = vec![0.0; n];
    kkt.gradient(&vec![0.0; n], &mut q);
    let given = kkt.scales();
    crate::Scales {
        force: given.force.max(inf_norm(&q)),
        length: given.length.max(inf_norm(kkt.b())),
    }
}

/// Evaluates g, Aᵀz, Ax, the residual vectors and the iterate's residuals.
pub(crate) fn evaluate<K: KktSystem + ?Sized>(
    kkt: &mut K,
    pt: &Point,
    w: &mut Work,
    floors: crate::Scales,
) -> (Residuals, f64) {
    let objective = kkt.gradient(&pt.x, &mut w.g);
    kkt.apply_at(&pt.z, &mut w.atz);
    kkt.apply_a(&pt.x, &mut w.ax);
    let b = kkt.b();
    for ((r, g), a) in w.rx.iter_mut().zip(&w.g).zip(&w.atz) {
        *r = g + a;
    }
    for (((r, a), s), bb) in w.rs.iter_mut().zip(&w.ax).zip(&pt.s).zip(b) {
        *r = a + s - bb;
    }
    let res = residual::iterate(
        &Parts {
            g: &w.g,
            atz: &w.atz,
            ax: &w.ax,
            b,
            s: &pt.s,
            z: &pt.z,
            objective,
            floors,
        },
        kkt.cones(),
    );
    (res, objective)
}

/// The certificate of (x, z) with s = b − Ax.
pub(crate) fn certify<K: KktSystem + ?Sized>(
    kkt: &mut K,
    x: &[f64],
    z: &[f64],
    floors: crate::Scales,
) -> (Residuals, Vec<f64>, f64) {
    let (n, m) = (kkt.num_vars(), kkt.cones().rows());
    let mut g = vec![0.0; n];
    let mut atz = vec![0.0; n];
    let mut ax = vec![0.0; m];
    let objective = kkt.gradient(x, &mut g);
    kkt.apply_at(z, &mut atz);
    kkt.apply_a(x, &mut ax);
    let s: Vec<f64> = kkt.b().iter().zip(&ax).map(|(b, a)| b - a).collect();
    let res = residual::certificate(
        &Parts {
            g: &g,
            atz: &atz,
            ax: &ax,
            b: kkt.b(),
            s: &s,
            z,
            objective,
            floors,
        },
        kkt.cones(),
    );
    (res, s, objective)
}

/// The largest diagonal scale over the blocks (the start's weight ω), 1 without blocks.
fn omega<K: KktSystem + ?Sized>(kkt: &K) -> f64 {
    let w = (0..kkt.cones().len())
        .map(|b| kkt.diagonal_scale(b))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    if w > 0.0 {
        w
    } else {
        1.0
    }
}

/// The default start: x minimizing ½xᵀPx + qᵀx + (ω/2)|b − Ax|² (one factorization with
/// Θ = ωI; x = 0 if it does not factor), s = b − Ax shifted into the interior by its
/// violation plus a tenth of its size, z = μ s⁻¹ (the centre for s) with μ = ω|s|².
fn default_start<K: KktSystem + ?Sized>(kkt: &mut K, x0: Option<Vec<f64>>) -> Point {
    let (n, m) = (kkt.num_vars(), kkt.cones().rows());
    let w = omega(kkt);
    let x = match x0 {
        Some(x) => x,
        None => {
            let weights = Weights::uniform(kkt.cones(), w);
            let mut rhs = vec![0.0; n];
            let mut g = vec![0.0; n];
            // −q = −(P·0 + q).
            kkt.gradient(&vec![0.0; n], &mut g);
            let wb: Vec<f64> = kkt.b().iter().map(|v| w * v).collect();
            kkt.apply_at(&wb, &mut rhs);
            for (r, gi) in rhs.iter_mut().zip(&g) {
                *r -= gi;
            }
            match kkt.factor(&weights, 0.0) {
                Ok(()) => {
                    kkt.solve(&mut rhs);
                    if rhs.iter().all(|v| v.is_finite()) {
                        rhs
                    } else {
                        vec![0.0; n]
                    }
                }
                Err(_) => vec![0.0; n],
            }
        }
    };
    let mut ax = vec![0.0; m];
    kkt.apply_a(&x, &mut ax);
    let cones = kkt.cones().clone();
    let scale_x = inf_norm(kkt.b()).max(inf_norm(&x));
    let mut s = vec![0.0; m];
    let mut z = vec![0.0; m];
    for (bi, cone) in cones.blocks().iter().enumerate() {
        let r = cones.range(bi);
        let sb = &mut s[r.clone()];
        for ((sv, bv), av) in sb.iter_mut().zip(&kkt.b()[r.clone()]).zip(&ax[r.clone()]) {
            *sv = bv - av;
        }
        let size = norm(sb).max(scale_x * 1e-3).max(f64::MIN_POSITIVE);
        match cone.kind() {
            Kind::Zero => {
                sb.fill(0.0);
                continue;
            }
            Kind::Nonnegative => {
                let lo = sb.iter().fold(f64::INFINITY, |a, &v| a.min(v));
                let shift = (-lo).max(0.0) + 0.1 * size;
                sb.iter_mut().for_each(|v| *v += shift);
            }
            Kind::SecondOrder => {
                let gap = norm(&sb[1..]) - sb[0];
                sb[0] += gap.max(0.0) + 0.1 * size;
            }
        }
        let mu = w * norm(sb).powi(2);
        let zb = &mut z[r];
        match cone.kind() {
            Kind::Zero => {}
            Kind::Nonnegative => {
                for (zv, sv) in zb.iter_mut().zip(sb.iter()) {
                    *zv = mu / sv;
                }
            }
            Kind::SecondOrder => {
                let js = soc_residual(sb);
                zb[0] = mu * sb[0] / js;
                for k in 1..zb.len() {
                    zb[k] = -mu * sb[k] / js;
                }
            }
        }
    }
    Point { x, s, z }
}

/// Checks a given start.
fn given_start<K: KktSystem + ?Sized>(kkt: &K, start: Start) -> Result<Point, Error> {
    let (n, m) = (kkt.num_vars(), kkt.cones().rows());
    if start.x.len() != n {
        return Err(Error::WrongLength {
            field: "start.x",
            expected: n,
            got: start.x.len(),
        });
    }
    if let Some(i) = start.x.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            field: "start.x",
            index: i,
        });
    }
    let Some((s, z)) = start.sz else {
        return Ok(Point {
            x: start.x,
            s: Vec::new(),
            z: Vec::new(),
        });
    };
    for (field, v) in [("start.s", &s), ("start.z", &z)] {
        if v.len() != m {
            return Err(Error::WrongLength {
                field,
                expected: m,
                got: v.len(),
            });
        }
    }
    let cones = kkt.cones();
    for (bi, cone) in cones.blocks().iter().enumerate() {
        let r = cones.range(bi);
        for (field, v) in [("start.s", &s[r.clone()]), ("start.z", &z[r.clone()])] {
            let inside = match cone.kind() {
                Kind::Zero => v.iter().all(|x| x.is_finite()),
                Kind::Nonnegative => v.iter().all(|&x| x > 0.0 && x.is_finite()),
                Kind::SecondOrder => {
                    v.iter().all(|x| x.is_finite()) && v[0] > 0.0 && soc_residual(v) > 0.0
                }
            };
            if !inside {
                return Err(Error::InvalidValue {
                    field,
                    index: bi,
                    reason: "not strictly inside its cone",
                });
            }
        }
    }
    Ok(Point { x: start.x, s, z })
}

/// One factorization of the Newton matrix with its scalings, and solves with iterative
/// refinement.
pub(crate) struct Newton {
    /// Start of block b's NT scaling in the weights' data ([`Weights::nt_layout`]).
    sc_off: Vec<usize>,
    scratch: Vec<f64>,
    /// λ = V z.
    pub lambda: Vec<f64>,
    /// δ per zero block (0 elsewhere).
    pub delta: Vec<f64>,
    /// Θ: the NT scalings of the iterate (written in place each iteration) and 1/δ on zero
    /// blocks.
    pub weights: Weights,
    pub shifted: bool,
    ws: SolveWork,
}

impl Newton {
    fn new(cones: &crate::Cones, n: usize) -> Self {
        let (weights, sc_off) = Weights::nt_layout(cones);
        Newton {
            sc_off,
            scratch: Vec::new(),
            lambda: vec![0.0; cones.rows()],
            delta: vec![0.0; cones.len()],
            weights,
            shifted: false,
            ws: SolveWork::new(n, cones.rows()),
        }
    }

    /// The NT scaling data of every block (block b from `sc_off[b]`).
    fn sc(&self) -> &[f64] {
        self.weights.nt_data()
    }

    /// Scalings at (s, z) and the factorization, with the retries of
    /// [`crate::Regularization`].
    fn factor<K: KktSystem + ?Sized>(
        &mut self,
        kkt: &mut K,
        cones: &crate::Cones,
        pt: &Point,
        opts: &Options,
    ) -> Result<(), Error> {
        product::scalings(
            cones,
            &pt.s,
            &pt.z,
            self.weights.nt_data_mut(),
            &self.sc_off,
            &mut self.lambda,
            &mut self.scratch,
        );
        let reg = &opts.regularization;
        let eq_attempts = if cones.has_equalities() {
            reg.equality_attempts.max(1)
        } else {
            1
        };
        let mut last = Error::Singular { index: 0 };
        for attempt in 0..eq_attempts + reg.static_attempts {
            let eq = attempt.min(eq_attempts - 1);
            let rel = reg.equality * reg.equality_growth.powi(eq as i32);
            if cones.has_equalities() {
                for (bi, cone) in cones.blocks().iter().enumerate() {
                    if cone.kind() == Kind::Zero {
                        let scale = kkt.diagonal_scale(bi).max(f64::MIN_POSITIVE);
                        self.delta[bi] = rel / scale;
                        self.weights.set_scalar(bi, 1.0 / self.delta[bi]);
                    }
                }
            }
            let shift_attempt = attempt - eq;
            let sigma = if shift_attempt > 0 {
                reg.static_shift * reg.static_growth.powi(shift_attempt as i32 - 1)
            } else {
                0.0
            };
            self.shifted = sigma > 0.0;
            match kkt.factor(&self.weights, sigma) {
                Ok(()) => return Ok(()),
                Err(e) => last = e,
            }
        }
        Err(last)
    }

    /// Solves for (dx, ds, dz) given r_x, r_s and ξ (the scaled complementarity right-hand
    /// side: V⁻¹ds + V dz = ξ), refining up to `steps` times to `rtol` × the right-hand side.
    #[allow(clippy::too_many_arguments)]
    fn solve<K: KktSystem + ?Sized>(
        &mut self,
        kkt: &mut K,
        cones: &crate::Cones,
        rx: &[f64],
        rs: &[f64],
        xi: &[f64],
        steps: usize,
        rtol: f64,
        out: &mut Direction,
    ) -> bool {
        let ws = &mut self.ws;
        let sc = self.weights.nt_data();
        let sc_off = &self.sc_off[..];
        let has_eq = cones.has_equalities();
        // rhs1 = −r_x − A_iᵀ(V⁻¹ξ + V⁻² r_s) over inequality blocks; e2 = −r_s on zero blocks.
        // V⁻¹ξ + V⁻² r_s = V⁻¹(ξ + V⁻¹ r_s).
        product::scaled_sum(cones, sc, sc_off, rs, xi, &mut ws.t);
        if has_eq {
            ws.e2.fill(0.0);
            for (bi, cone) in cones.blocks().iter().enumerate() {
                if cone.kind() == Kind::Zero {
                    for k in cones.range(bi) {
                        ws.e2[k] = -rs[k];
                        ws.t[k] = 0.0;
                    }
                }
            }
        }
        kkt.apply_at(&ws.t, &mut ws.rhs1);
        for (a, r) in ws.rhs1.iter_mut().zip(rx) {
            *a = -*a - r;
        }
        // [K A_eᵀ; A_e 0][dx; dz_e] = [rhs1; e2], K = P + A_iᵀV⁻²A_i: regularized solves
        // dx = K_δ⁻¹(e1 + A_eᵀe2/δ), dz_e = (A_e dx − e2)/δ, refined against the exact system.
        // (Without zero blocks e2 and res2 stay 0 and dz is set by the recovery below.)
        out.dx.fill(0.0);
        if has_eq {
            out.dz.fill(0.0);
            ws.res2.copy_from_slice(&ws.e2);
        }
        ws.e1.copy_from_slice(&ws.rhs1);
        let bnorm = inf_norm(&ws.rhs1)
            .max(if has_eq { inf_norm(&ws.e2) } else { 0.0 })
            .max(f64::MIN_POSITIVE);
        let mut last = f64::INFINITY;
        for step in 0..=steps {
            // Correction from the residuals (e1, res2).
            ws.r.copy_from_slice(&ws.e1);
            if has_eq {
                for (bi, cone) in cones.blocks().iter().enumerate() {
                    for k in cones.range(bi) {
                        ws.u[k] = if cone.kind() == Kind::Zero {
                            ws.res2[k] / self.delta[bi]
                        } else {
                            0.0
                        };
                    }
                }
                kkt.apply_at(&ws.u, &mut ws.atu);
                for (a, c) in ws.r.iter_mut().zip(&ws.atu) {
                    *a += c;
                }
            }
            kkt.solve(&mut ws.r);
            if step > 0 {
                // (Kept to undo a diverging correction; before the first, dx = dz = 0.)
                ws.prev_dx.copy_from_slice(&out.dx);
                if has_eq {
                    ws.prev_dz.copy_from_slice(&out.dz);
                }
            }
            for (a, c) in out.dx.iter_mut().zip(&ws.r) {
                *a += c;
            }
            if has_eq {
                kkt.apply_a(&ws.r, &mut ws.ax);
                for (bi, cone) in cones.blocks().iter().enumerate() {
                    if cone.kind() == Kind::Zero {
                        for k in cones.range(bi) {
                            out.dz[k] += (ws.ax[k] - ws.res2[k]) / self.delta[bi];
                        }
                    }
                }
            }
            if step == steps {
                break;
            }
            // Residuals of the exact system: e1 = rhs1 − K dx − A_eᵀ dz_e, res2 = e2 − A_e dx.
            if !has_eq && kkt.apply_newton(&out.dx, &mut ws.kdx) {
                for ((e, a), k) in ws.e1.iter_mut().zip(&ws.rhs1).zip(&ws.kdx) {
                    *e = a - k;
                }
            } else {
                kkt.apply_p(&out.dx, &mut ws.kdx);
                kkt.apply_a(&out.dx, &mut ws.ax);
                product::theta(cones, sc, sc_off, &ws.ax, &mut ws.u);
                if has_eq {
                    for (bi, cone) in cones.blocks().iter().enumerate() {
                        if cone.kind() == Kind::Zero {
                            for k in cones.range(bi) {
                                ws.u[k] = out.dz[k];
                                ws.res2[k] = ws.e2[k] - ws.ax[k];
                            }
                        }
                    }
                }
                kkt.apply_at(&ws.u, &mut ws.atu);
                for ((e, a), (k, c)) in ws
                    .e1
                    .iter_mut()
                    .zip(&ws.rhs1)
                    .zip(ws.kdx.iter().zip(&ws.atu))
                {
                    *e = a - k - c;
                }
            }
            let rn = inf_norm(&ws.e1).max(if has_eq { inf_norm(&ws.res2) } else { 0.0 });
            if !rn.is_finite() || rn > last {
                // Diverging (the regularized factor is too far from the exact matrix): undo
                // the last correction (never the first: `last` starts at ∞).
                out.dx.copy_from_slice(&ws.prev_dx);
                if has_eq {
                    out.dz.copy_from_slice(&ws.prev_dz);
                }
                break;
            }
            last = rn;
            if rn <= rtol * bnorm {
                break;
            }
        }
        // Far from its target after the refinement — and not even accurate to 1e-4 — the
        // factorization is too far from the exact matrix for this direction. (A direction a few
        // digits short of a tight target still makes progress; escalating costs more.)
        let accurate = steps == 0 || last <= (1e2 * rtol).max(1e-4) * bnorm;
        // ds = −r_s − A dx, dz = V⁻¹(ξ + V⁻¹(r_s + A dx)) on inequality blocks (zero blocks:
        // ds = 0, dz_e from the refinement).
        kkt.apply_a(&out.dx, &mut ws.ax);
        for ((u, a), r) in ws.u.iter_mut().zip(&ws.ax).zip(rs) {
            *u = r + a;
        }
        product::scaled_sum(cones, sc, sc_off, &ws.u, xi, &mut out.dz);
        for (d, u) in out.ds.iter_mut().zip(&ws.u) {
            *d = -u;
        }
        if has_eq {
            for (bi, cone) in cones.blocks().iter().enumerate() {
                if cone.kind() == Kind::Zero {
                    out.ds[cones.range(bi)].fill(0.0);
                }
            }
        }
        accurate
    }
}

/// Work vectors of the Newton solves (allocated once per run).
pub(crate) struct SolveWork {
    t: Vec<f64>,
    e2: Vec<f64>,
    u: Vec<f64>,
    rhs1: Vec<f64>,
    e1: Vec<f64>,
    res2: Vec<f64>,
    r: Vec<f64>,
    atu: Vec<f64>,
    ax: Vec<f64>,
    kdx: Vec<f64>,
    prev_dx: Vec<f64>,
    prev_dz: Vec<f64>,
}

impl SolveWork {
    fn new(n: usize, m: usize) -> Self {
        SolveWork {
            t: vec![0.0; m],
            e2: vec![0.0; m],
            u: vec![0.0; m],
            rhs1: vec![0.0; n],
            e1: vec![0.0; n],
            res2: vec![0.0; m],
            r: vec![0.0; n],
            atu: vec![0.0; n],
            ax: vec![0.0; m],
            kdx: vec![0.0; n],
            prev_dx: vec![0.0; n],
            prev_dz: vec![0.0; m],
        }
    }
}

/// A search direction.
pub(crate) struct Direction {
    pub dx: Vec<f64>,
    pub ds: Vec<f64>,
    pub dz: Vec<f64>,
}

impl Work {
    pub(crate) fn new(n: usize, m: usize) -> Self {
        Work {
            g: vec![0.0; n],
            atz: vec![0.0; n],
            ax: vec![0.0; m],
            rx: vec![0.0; n],
            rs: vec![0.0; m],
        }
    }
}

impl Direction {
    fn new(n: usize, m: usize) -> Self {
        Direction {
            dx: vec![0.0; n],
            ds: vec![0.0; m],
            dz: vec![0.0; m],
        }
    }
}

/// The largest step in [0, cap] keeping s + α ds and z + α dz in their cones.
fn max_step(cones: &crate::Cones, pt: &Point, d: &Direction, cap: f64) -> f64 {
    product::max_step(cones, &pt.s, &d.ds, &pt.z, &d.dz, cap)
}

/// The interior-point method, then the polish (see [`crate::solve_with`]).
pub(crate) fn run<K: KktSystem + ?Sized>(
    kkt: &mut K,
    opts: &Options,
    start: Option<Start>,
    monitor: &mut dyn Monitor,
) -> Result<Solution, Error> {
    let cones = kkt.cones().clone();
    let (n, m) = (kkt.num_vars(), cones.rows());
    if kkt.b().len() != m {
        return Err(Error::WrongLength {
            field: "b",
            expected: m,
            got: kkt.b().len(),
        });
    }
    if let Some(i) = kkt.b().iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            field: "b",
            index: i,
        });
    }
    let mut pt = match start {
        None => default_start(kkt, None),
        Some(st) => {
            let p = given_start(kkt, st)?;
            if p.s.is_empty() {
                default_start(kkt, Some(p.x))
            } else {
                p
            }
        }
    };
    let degree = cones.degree() as f64;
    let floors = floors(kkt);
    let mut w = Work {
        g: vec![0.0; n],
        atz: vec![0.0; n],
        ax: vec![0.0; m],
        rx: vec![0.0; n],
        rs: vec![0.0; m],
    };
    let mut newton = Newton::new(&cones, n);
    let mut aff = Direction::new(n, m);
    let mut dir = Direction::new(n, m);
    let mut xi = vec![0.0; m];
    let mut corrector_work: [Vec<f64>; 4] = Default::default();
    // The best iterate so far: the current one (`best_is_current`) or, once the current one
    // has moved on from it, `best` (the update swaps the two and writes the new point from it,
    // so the best point is never copied).
    let mut best_total = f64::INFINITY;
    let mut best = pt.clone();
    let mut best_is_current = false;
    let mut polished_best: Option<Solution> = None;
    let mut polish_tried = false;
    let mut iterations = 0;
    let status = loop {
        let (res, _) = evaluate(kkt, &pt, &mut w, floors);
        if iterations == 0 || res.total < best_total {
            best_total = res.total;
            best_is_current = true;
        }
        if !monitor.iterate(&Iterate {
            iteration: iterations,
            x: &pt.x,
            s: &pt.s,
            z: &pt.z,
            residuals: res,
        }) {
            // The iterate itself (s included), so that the caller can resume from it.
            let (cert, _, objective) = certify(kkt, &pt.x, &pt.z, floors);
            return Ok(Solution {
                x: pt.x,
                s: pt.s,
                z: pt.z,
                residuals: cert,
                objective,
                iterations,
                status: Status::Stopped,
                polished: false,
            });
        }
        // The polish, once the iterate is close: a polished point at the tolerance ends the
        // method early.
        if let Some(po) = &opts.polish {
            if !polish_tried && res.total <= po.from && degree > 0.0 {
                polish_tried = true;
                if let Some(p) = crate::polish::polish(kkt, &pt, &res, opts, iterations, floors) {
                    let done = p.residuals.total <= opts.tolerance;
                    keep_better(&mut polished_best, p);
                    if done {
                        break Status::Converged;
                    }
                }
            }
        }
        if res.total <= opts.tolerance {
            break Status::Converged;
        }
        if iterations >= opts.max_iterations {
            break Status::MaxIterations;
        }
        iterations += 1;
        if let Err(e) = newton.factor(kkt, &cones, &pt, opts) {
            if iterations == 1 {
                return Err(e);
            }
            break Status::Stalled;
        }
        let gap = product::gap(&cones, &pt.s, &pt.z);
        let mu = if degree > 0.0 { gap / degree } else { 0.0 };
        // Predictor: ξ = −λ.
        for (x, l) in xi.iter_mut().zip(&newton.lambda) {
            *x = -l;
        }
        let pred_steps = if cones.has_equalities() || newton.shifted {
            opts.refinement.max_steps
        } else {
            0
        };
        // (Without cones there is no central path to follow: an equality-constrained QP is
        // solved by one direction, refined all the way.)
        let rtol = if degree > 0.0 {
            (opts.refinement.accuracy * res.total).max(opts.refinement.floor)
        } else {
            opts.refinement.floor
        };
        let pred_ok = newton.solve(kkt, &cones, &w.rx, &w.rs, &xi, pred_steps, rtol, &mut aff);
        let alpha_a = max_step(&cones, &pt, &aff, 1.0);
        let mut sigma = 0.0;
        if gap > 0.0 {
            let gap_a = product::gap_along(&cones, &pt.s, &aff.ds, &pt.z, &aff.dz, alpha_a);
            sigma = (gap_a / gap).clamp(0.0, 1.0).powi(3);
        }
        // Corrector: ξ = λ⁻¹ ∘ (σμe − λ∘λ − (V⁻¹ds_a)∘(V dz_a)).
        product::corrector(
            &cones,
            newton.sc(),
            &newton.sc_off,
            &newton.lambda,
            &aff.ds,
            &aff.dz,
            sigma * mu,
            &mut xi,
            &mut corrector_work,
        );
        let steps = if cones.has_equalities() || newton.shifted || !kkt.factor_is_exact() {
            opts.refinement.max_steps
        } else if res.total <= opts.refinement.exact_from {
            opts.refinement.exact_steps
        } else {
            0
        };
        let corr_ok = newton.solve(kkt, &cones, &w.rx, &w.rs, &xi, steps, rtol, &mut dir);
        if !(pred_ok && corr_ok) && kkt.escalate() {
            // The backend now factors more exactly: repeat the iteration from the same point.
            continue;
        }
        let alpha =
            (opts.step_fraction * max_step(&cones, &pt, &dir, 1.0 / opts.step_fraction)).min(1.0);
        if !(alpha.is_finite() && alpha > 0.0)
            || dir.dx.iter().chain(&dir.dz).any(|v| !v.is_finite())
        {
            break Status::Stalled;
        }
        // (ds is 0 on zero blocks: their s stays.)
        if best_is_current {
            std::mem::swap(&mut pt, &mut best);
            best_is_current = false;
            for (v, (b, d)) in [
                (&mut pt.x, (&best.x, &dir.dx)),
                (&mut pt.s, (&best.s, &dir.ds)),
                (&mut pt.z, (&best.z, &dir.dz)),
            ] {
                for (a, (b, d)) in v.iter_mut().zip(b.iter().zip(d)) {
                    *a = b + alpha * d;
                }
            }
        } else {
            for (v, d) in [
                (&mut pt.x, &dir.dx),
                (&mut pt.s, &dir.ds),
                (&mut pt.z, &dir.dz),
            ] {
                for (a, d) in v.iter_mut().zip(d) {
                    *a += alpha * d;
                }
            }
        }
    };
    // The point returned: the polished one if it met the tolerance; else the last (converged)
    // or best iterate, polished once more when that helps.
    if status == Status::Converged {
        if let Some(p) = &polished_best {
            if p.residuals.total <= opts.tolerance {
                let mut p = polished_best.expect("checked");
                p.iterations = iterations;
                p.status = status;
                return Ok(p);
            }
        }
    }
    let from = if status == Status::Converged || best_is_current {
        pt
    } else {
        best
    };
    let (cert, s, objective) = certify(kkt, &from.x, &from.z, floors);
    let mut out = Solution {
        x: from.x.clone(),
        s,
        z: from.z.clone(),
        residuals: cert,
        objective,
        iterations,
        status,
        polished: false,
    };
    if let Some(po) = &opts.polish {
        let skip = cert.total <= po.skip_below;
        if !skip && degree > 0.0 {
            let (res, _) = evaluate(kkt, &from, &mut w, floors);
            if let Some(p) = crate::polish::polish(kkt, &from, &res, opts, iterations, floors) {
                keep_better(&mut polished_best, p);
            }
        }
    }
    if let Some(mut p) = polished_best {
        if p.residuals.total < out.residuals.total || out.residuals.total.is_nan() {
            p.iterations = iterations;
            p.status = status;
            out = p;
        }
    }
    Ok(out)
}

fn keep_better(slot: &mut Option<Solution>, p: Solution) {
    if slot
        .as_ref()
        .is_none_or(|b| p.residuals.total < b.residuals.total || b.residuals.total.is_nan())
    {
        *slot = Some(p);
    }
}
