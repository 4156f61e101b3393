//! The polish of the working set's rounds: calls of [`conic::polish::polish_solution`] on the
//! condensed backend, each polished curve judged (the constraints it does not hold) and certified
//! by the caller; on W's condensation, or on a condensation onto W's active points alone when a
//! fifth or more of W is inactive ([`ActivePolish`]).

use divdiff::{Knots, Points};

use super::condensed::{Condensed, PointSet};
use super::working_set::Certify;
use crate::fast::Condensation;
use crate::operator::Stencil;
use crate::Error;

/// A curve with the caller's certificate of it: its residual `k`, what the caller keeps, and
/// the multipliers it was certified with.
pub(super) struct Certified<C> {
    pub(super) k: f64,
    pub(super) certificate: C,
    pub(super) points: Points,
    pub(super) multipliers: Vec<Vec<f64>>,
}

/// The polish calls ([`conic::polish::polish_solution`]) from `sol`, whose curve is `best`
/// (`None`: not certified yet): each polished curve is judged (`judge`: the constraints outside
/// W) and certified, and the calls go on from the polished point while the certificate is above
/// `target` and falls, and the method's residual fell in the call, at most [`POLISH_ROUNDS`].
/// `None` when a polished curve left a constraint outside W. `first`: `sol` already evaluated
/// on `be` ([`conic::polish::evaluate`]), for the first call.
#[allow(clippy::too_many_arguments)]
pub(super) fn polish_rounds<C>(
    be: &mut Condensed<'_>,
    stencil: &Stencil,
    wsets: &[PointSet],
    d: usize,
    conic_opts: &conic::Options,
    mut sol: conic::Solution,
    mut best: Option<Certified<C>>,
    target: f64,
    judge: &mut dyn FnMut(&Points) -> bool,
    certify: Certify<'_, C>,
    left: Option<&mut Option<(conic::Solution, Points)>>,
    mut first: Option<&conic::polish::Evaluated>,
) -> Result<Option<Polished<C>>, Error> {
    let mut calls = 0;
    let mut settled = false;
    let mut opts = conic_opts.clone();
    if let Some(po) = opts.polish.as_mut() {
        po.penalty = po.penalty.max(CONDENSED_PENALTY);
        // A singular polish matrix is a face of optimal points (ROBUSTNESS.md item 41).
        po.shift_singular = true;
    }
    let conic_opts = &opts;
    while calls < POLISH_ROUNDS {
        if best.as_ref().is_some_and(|b| b.k <= target) || conic_opts.polish.is_none() {
            break;
        }
        let polished = match first.take() {
            Some(ev) => conic::polish::polish_evaluated(be, ev, conic_opts),
            None => conic::polish::polish_solution(be, &sol, conic_opts),
        };
        let Some(p) = polished else {
            break;
        };
        calls += 1;
        let (points, g) = be.curve(&p.x, stencil)?;
        if !judge(&points) {
            if let Some(left) = left {
                *left = Some((p, points));
            }
            return Ok(None);
        }
        let multipliers = multipliers(be, wsets, &p.z, &g, d);
        let (k, certificate) = certify(&points, &multipliers);
        // (NaN is never better.)
        if k.is_nan() || best.as_ref().is_some_and(|b| k >= b.k) {
            // A call whose point the method certifies at its tolerance without lowering `k`:
            // the caller's certificate is at its floor.
            settled = p.residuals.total <= conic_opts.tolerance;
            break;
        }
        best = Some(Certified {
            k,
            certificate,
            points,
            multipliers,
        });
        // A call that left the method's residual no lower than at the point it started from
        // ran its Newton steps outside their quadratic regime, and another call from its point
        // repeats them: the calls end ([`POLISH_ROUNDS`]).
        if no_lower(&p, &sol) {
            break;
        }
        if p.residuals.total <= ROUNDING_LEVEL * conic_opts.tolerance {
            // The method certifies the point at its rounding: another call would take its
            // Newton steps again from a converged point; the caller's certificate is at its
            // floor.
            settled = true;
            break;
        }
        sol = p;
    }
    Ok(Some(Polished {
        best,
        calls,
        settled,
    }))
}

/// Whether the polished point `p` is no better than the point `from` it started from by the
/// method's residual, when that is known (an interior-point iterate, an earlier call's point;
/// not a warm start's, whose residual is 0: unknown). NaN is never better.
fn no_lower(p: &conic::Solution, from: &conic::Solution) -> bool {
    let lowered = p.residuals.total < from.residuals.total;
    from.residuals.total > 0.0 && !lowered
}

/// What [`polish_rounds`] ends with: the best certified curve (if any), the calls made, and
/// whether they ended settled (a call certified by the method at its tolerance did not lower
/// the caller's certificate: that is at its floor).
pub(super) struct Polished<C> {
    pub(super) best: Option<Certified<C>>,
    pub(super) calls: usize,
    pub(super) settled: bool,
}

/// The polish of a round from an interior-point iterate that the judge accepted at the round
/// tolerance (`run_round`): on W's backend when W is mostly active (or holds polytopes), else on
/// a backend over the active points of W alone. The polish's systems on W's condensation leave
/// its inactive points free with no weight, which the condensed route regularizes (a run of them
/// makes its solves inexact, and the polish then takes the full-vertex route over every vertex of
/// the curve); condensed onto the active points, the inactive ones are free vertices of the
/// energy, as outside W, and every condensed point carries its constraint's curvature and
/// penalty. The polished curve is judged against every constraint it left out.
pub(super) struct ActivePolish<'e, 'c> {
    pub(super) be: &'e mut Condensed<'c>,
    pub(super) cond: &'e Condensation,
    pub(super) knots: &'e Knots,
    pub(super) stencil: &'e Stencil,
    pub(super) qw: &'e [f64],
    pub(super) wsets: &'e [PointSet],
    pub(super) d: usize,
    pub(super) conic_opts: &'e conic::Options,
    pub(super) margin: f64,
    pub(super) target: f64,
}

/// At most this fraction of W's variables inactive: the polish runs on W's own backend.
const POLISH_ON_W: f64 = 0.2;

/// A solution as the polish of a round starts from it ([`ActivePolish::start`]).
pub(super) struct PolishStart<'s> {
    /// The interior-point iterate (or warm point) polished.
    sol: &'s conic::Solution,
    /// `sol` evaluated on W's backend ([`conic::polish::evaluate`]; `None`: its vectors do not
    /// fit), for the first polish call.
    pub(super) ev: Option<conic::polish::Evaluated>,
    /// W's variables in the active set the polish starts from ([`conic::polish::active_blocks`];
    /// `None`: it cannot be formed).
    active: Option<Vec<bool>>,
    /// Whether the polish runs on a condensation onto W's active points: W of balls alone, more
    /// than [`POLISH_ON_W`] of it inactive.
    pub(super) subset: bool,
}

impl<'c> ActivePolish<'_, 'c> {
    /// The same polish borrowing this one's backend for a shorter while ([`ActivePolish::run`]
    /// consumes it; the caller goes on with the backend afterwards).
    pub(super) fn reborrow(&mut self) -> ActivePolish<'_, 'c> {
        ActivePolish {
            be: &mut *self.be,
            cond: self.cond,
            knots: self.knots,
            stencil: self.stencil,
            qw: self.qw,
            wsets: self.wsets,
            d: self.d,
            conic_opts: self.conic_opts,
            margin: self.margin,
            target: self.target,
        }
    }

    /// `sol` as the polish starts from it ([`PolishStart`]): evaluated on W's backend, its
    /// active set read off and the route chosen, once for the choice and the calls on either.
    pub(super) fn start<'s>(&mut self, sol: &'s conic::Solution) -> PolishStart<'s> {
        let ev = conic::polish::evaluate(self.be, sol);
        let active = ev
            .as_ref()
            .and_then(|ev| conic::polish::active_blocks(self.be, ev, self.conic_opts));
        let balls = !self.wsets.iter().any(|s| matches!(s, PointSet::Faces(_)));
        let subset = balls
            && active.as_ref().is_some_and(|active| {
                let inactive = active.iter().filter(|a| !**a).count();
                inactive as f64 > POLISH_ON_W * active.len() as f64
            });
        PolishStart {
            sol,
            ev,
            active,
            subset,
        }
    }

    /// The polish calls from `start` ([`polish_rounds`], none certified yet), on W or on its
    /// active points ([`PolishStart::subset`]); `None` when a polished curve left a constraint
    /// it does not hold.
    pub(super) fn run<C>(
        self,
        start: &PolishStart<'_>,
        judge: &mut dyn FnMut(&Points) -> bool,
        certify: Certify<'_, C>,
    ) -> Result<Option<Polished<C>>, Error> {
        let ActivePolish {
            be,
            cond,
            knots,
            stencil,
            qw,
            wsets,
            d,
            conic_opts,
            margin,
            target,
        } = self;
        let sol = start.sol;
        let vars = be.variables().to_vec();
        let n_w = wsets.len();
        // W's positions kept: the interpolated and active points, and the ends the
        // condensation starts at.
        let mut keep = vec![false; n_w];
        for (j, set) in wsets.iter().enumerate() {
            keep[j] = *set == PointSet::Fixed;
        }
        keep[0] = true;
        if !cond.closed {
            keep[n_w - 1] = true;
        }
        if let Some(active) = &start.active {
            for (v, &j) in vars.iter().enumerate() {
                if active[v] {
                    keep[j] = true;
                } else {
                    // A point the iterate does not count as active but that nearly leaves its
                    // set is kept too (the polish decides; see SUBSET_NEAR).
                    let near = wsets[j].closeness(
                        &sol.x[v * d..(v + 1) * d],
                        &qw[j * d..(j + 1) * d],
                        0.0,
                    );
                    keep[j] |= near >= 1.0 - SUBSET_NEAR;
                }
            }
        }
        let need = if cond.closed { 2 } else { 3 };
        if !start.subset || keep.iter().filter(|&&k| k).count() < need {
            return polish_rounds(
                be,
                stencil,
                wsets,
                d,
                conic_opts,
                sol.clone(),
                None,
                target,
                judge,
                certify,
                None,
                start.ev.as_ref(),
            );
        }
        let mut var_of = vec![usize::MAX; n_w];
        for (v, &j) in vars.iter().enumerate() {
            var_of[j] = v;
        }
        // The points of W left out that a polished curve violates join, and the polish is
        // repeated on the larger set from that curve (the points joining on their boundary
        // side, where the polish takes them as active), a few times at most.
        // The start: the iterate on W's variables (x, its slack and dual per variable).
        let mut from: Vec<Option<VariableStart>> = vec![None; n_w];
        for (v, &j) in vars.iter().enumerate() {
            let r = be.rows(v);
            from[j] = Some((
                sol.x[v * d..(v + 1) * d].to_vec(),
                sol.s[r.clone()].to_vec(),
                sol.z[r].to_vec(),
            ));
        }
        for attempt in 1..=SUBSET_ATTEMPTS {
            let pos: Vec<usize> = (0..n_w).filter(|&j| keep[j]).collect();
            let sub_cond = Condensation::at_vertices_reusing(
                knots,
                stencil,
                pos.iter().map(|&j| cond.vertices[j]).collect(),
                None,
            )?;
            let qs: Vec<f64> = pos
                .iter()
                .flat_map(|&j| qw[j * d..(j + 1) * d].iter().copied())
                .collect();
            let ss: Vec<PointSet> = pos.iter().map(|&j| wsets[j].clone()).collect();
            let mut sub = Condensed::new(&sub_cond, knots, qs, ss.clone(), d)?;
            let (mut x, mut s, mut z) = (Vec::new(), Vec::new(), Vec::new());
            for &j in &pos {
                if let Some((xj, sj, zj)) = &from[j] {
                    x.extend_from_slice(xj);
                    s.extend_from_slice(sj);
                    z.extend_from_slice(zj);
                }
            }
            let sub_sol = conic::Solution {
                x,
                s,
                z,
                // Where the round's method stood (on W): a call on the subset that ends no lower
                // ends the calls (`polish_rounds`).
                residuals: sol.residuals,
                objective: 0.0,
                iterations: sol.iterations,
                status: sol.status,
                polished: false,
            };
            // The judge: the points of W left out (with the margin), then those outside W.
            let dropped: Vec<usize> = (0..n_w).filter(|&j| !keep[j]).collect();
            let mut violated: Vec<usize> = Vec::new();
            let mut judge_sub = |p: &Points| {
                violated.clear();
                violated.extend(dropped.iter().copied().filter(|&j| {
                    wsets[j].closeness(p.point(cond.vertices[j]), &qw[j * d..(j + 1) * d], 0.0)
                        >= 1.0 - margin
                }));
                violated.is_empty() && judge(p)
            };
            // The certificate: W's multipliers, 0 on the points left out.
            let mut certify_sub = |p: &Points, m: &[Vec<f64>]| certify(p, &on_w(m, &pos, wsets, d));
            let mut left = None;
            let polished = polish_rounds(
                &mut sub,
                stencil,
                &ss,
                d,
                conic_opts,
                sub_sol,
                None,
                target,
                &mut judge_sub,
                &mut certify_sub,
                Some(&mut left),
                None,
            )?;
            if polished.is_some() || violated.is_empty() || attempt == SUBSET_ATTEMPTS {
                // The multipliers returned are W's, as on W's own backend: a knot update's warm
                // start reads one per data point (`working_set::polish_from_warm`).
                return Ok(polished.map(|mut p| {
                    if let Some(b) = p.best.as_mut() {
                        b.multipliers = on_w(&b.multipliers, &pos, wsets, d);
                    }
                    p
                }));
            }
            // A polished point no better than where the round's method stood is not worth
            // another attempt on a larger subset (whose polish starts from it): the method
            // resumes from its iterate instead (SUBSET_ATTEMPTS).
            if left.as_ref().is_some_and(|(p, _)| no_lower(p, sol)) {
                return Ok(None);
            }
            // The next start: the polished point, and the violated points where its curve put
            // them (outside their balls: the polish takes them as active, with multiplier 0).
            if let Some((p, points)) = left {
                let sub_vars = sub.variables();
                for (v, &sj) in sub_vars.iter().enumerate() {
                    let r = sub.rows(v);
                    from[pos[sj]] = Some((
                        p.x[v * d..(v + 1) * d].to_vec(),
                        p.s[r.clone()].to_vec(),
                        p.z[r].to_vec(),
                    ));
                }
                for &j in &violated {
                    let PointSet::Ball(radius) = wsets[j] else {
                        continue;
                    };
                    let xj = points.point(cond.vertices[j]).to_vec();
                    let mut sj = vec![radius];
                    sj.extend(qw[j * d..(j + 1) * d].iter().zip(&xj).map(|(q, x)| q - x));
                    from[j] = Some((xj, sj, vec![0.0; d + 1]));
                }
            }
            for &j in &violated {
                keep[j] = true;
            }
        }
        Ok(None)
    }
}

/// The multipliers `m` of the points of W at positions `pos` (a subset's), spread over all of
/// W: 0 (of each set's shape) on the points left out.
fn on_w(m: &[Vec<f64>], pos: &[usize], wsets: &[PointSet], d: usize) -> Vec<Vec<f64>> {
    let mut wm: Vec<Vec<f64>> = wsets
        .iter()
        .map(|set| match set {
            PointSet::Fixed => vec![0.0; d],
            PointSet::Ball(_) => vec![0.0],
            PointSet::Faces(f) => vec![0.0; f.len()],
        })
        .collect();
    for (mm, &j) in m.iter().zip(pos) {
        wm[j].clone_from(mm);
    }
    wm
}

/// A variable's part of a start: its x, s and z.
type VariableStart = (Vec<f64>, Vec<f64>, Vec<f64>);

/// Polishes on a condensation onto W's active points, each with the points of W the previous
/// one's curve left, at most this many — and none after one whose polished point the method
/// certifies no better than the round's iterate: the bench's noisy star in balls of radii over
/// five decades at n = 10⁵ (a quarter of the balls inactive) made all three attempts, six
/// Newton steps each at about 47 ms, every one ending near 1.5e-4 from an iterate at 7e-7,
/// before the method resumed: 1.99 → 1.00 s (ROBUSTNESS.md item 33).
const SUBSET_ATTEMPTS: usize = 3;

/// A point of W that the interior-point iterate does not count as active (its relative slack
/// above `PolishOptions::active_rtol`) but whose closeness ([`PointSet::closeness`], the
/// judge's measure) at the iterate is at least 1 − this — a ball its curve fills to 0.99 of
/// the radius — stays in the subset the polish runs on, where the polish decides whether it is
/// active. Left out, such a ball was the one the polished curve then left (the noisy star of
/// `cargo xtask bench conic` with radii ×2 and ×4, n = 10⁴: one and two balls at 0.998 and
/// 0.999 of their radius, with multipliers as large as the active ones' — the iterate's slack
/// at its tolerance was not yet 1e-6), and the whole polish ran again on the larger subset.
const SUBSET_NEAR: f64 = 1e-2;

/// The polish's penalty on the normals of active constraints on the condensed backend, relative
/// to each point's Q_jj (as [`conic::PolishOptions::penalty`], whose default of 1e-9 a caller's
/// larger value overrides): the condensed route inverts the polish's weight cI + pūūᵀ per point,
/// and the penalty's right-hand side along the normals, 1/δ times the constraint values, leaves
/// the rounding of its cancellation across them multiplied by 1/c. At 1e-6 the first solve of
/// a polish step is accurate to ~1e-4 where 1e-9 left it at 10³–10⁴ relative and the refinement
/// took five or six solves (noisy star, n = 10⁴); the penalty's own error, δ times the
/// multipliers' change, is refined away at a rate of about δ per solve.
const CONDENSED_PENALTY: f64 = 1e-6;

/// A polished point the method certifies at this fraction of its tolerance is converged: no
/// further polish call is made from it.
const ROUNDING_LEVEL: f64 = 1e-2;

/// Most polish calls per accepted round (each one or more Newton steps on the active set; the
/// steps converge quadratically, so a call that does not lower the certificate ends them). A
/// call that leaves the method's residual no lower than at its start ends them too: balls with
/// radii spread over five decades (n = 10⁴) took four calls and thirteen steps pulling points
/// back onto the tiniest balls from hundreds of radii away, boxes of half-spaces three calls
/// ending near 1e-2, before the method resumed (ROBUSTNESS.md item 33).
pub(super) const POLISH_ROUNDS: usize = 4;

/// Multipliers of W's points: balls w = z₀/ε (Kersey (3.5)); faces w_k = z_k/|n_k| ((3.8) for
/// the original normals); interpolated points the reaction −(Hp)_v = −(Qy)_j (`g`).
pub(super) fn multipliers(
    be: &Condensed<'_>,
    wsets: &[PointSet],
    z: &[f64],
    g: &[f64],
    d: usize,
) -> Vec<Vec<f64>> {
    let mut var = 0;
    let mut mult = Vec::with_capacity(wsets.len());
    for (j, set) in wsets.iter().enumerate() {
        match set {
            PointSet::Fixed => mult.push(g[j * d..(j + 1) * d].iter().map(|v| -v).collect()),
            PointSet::Ball(r) => {
                let rows = be.rows(var);
                mult.push(vec![z[rows.start] / r]);
                var += 1;
            }
            PointSet::Faces(faces) => {
                let rows = be.rows(var);
                mult.push(
                    faces
                        .iter()
                        .zip(&z[rows])
                        .map(|(f, z)| z / f.norm)
                        .collect(),
                );
                var += 1;
            }
        }
    }
    mult
}

#[cfg(test)]
mod tests {
    use super::{polish_rounds, POLISH_ROUNDS};
    use crate::backend::condensed::{Condensed, PointSet};
    use crate::fast::Condensation;
    use crate::operator::Stencil;
    use divdiff::{Knots, Points, Topology};

    /// The polish calls of a round from its interior-point iterate: a call that leaves the
    /// method's residual no lower than at the point it started from ends them; from a start
    /// whose residual is unknown (0, as a knot update's warm start) they go on. Each call here
    /// takes one Newton step towards a tolerance no call reaches, and the caller's certificate
    /// falls at every call, so nothing else ends the calls before [`POLISH_ROUNDS`].
    #[test]
    fn calls_end_when_one_leaves_the_residual_no_lower_than_its_start() {
        let (n, m, d) = (16usize, 4usize, 2usize);
        let t: Vec<f64> = (0..=n * m)
            .map(|j| j as f64 * 0.7 + 0.1 * ((j * 7) % 5) as f64)
            .collect();
        let kn = Knots::new(Topology::Closed, t).unwrap();
        let stencil = Stencil::new(&kn);
        let cond = Condensation::new(&kn, &stencil, n, m).unwrap();
        // A star of alternating radii: the balls hold the curve's turns.
        let q: Vec<f64> = (0..n)
            .flat_map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                let r = 1.0 + 0.3 * (i % 2) as f64;
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let sets = vec![PointSet::Ball(0.05); n];
        let mut be = Condensed::new(&cond, &kn, q, sets.clone(), d).unwrap();
        // The iterate at 1e-6, where a round stops to judge it.
        let ipm = conic::Options {
            polish: None,
            ..conic::Options::default()
        };
        let start = be.ball_start();
        let mut judge_at = |it: &conic::Iterate<'_>| it.residuals.total > 1e-6;
        let sol = conic::solve_with(&mut be, &ipm, start, &mut judge_at).unwrap();
        assert_eq!(sol.status, conic::Status::Stopped);
        let opts = conic::Options {
            tolerance: 1e-300,
            polish: Some(conic::PolishOptions {
                steps: 1,
                ..conic::PolishOptions::default()
            }),
            ..conic::Options::default()
        };
        let mut calls = |start_residual: f64| {
            let mut from = sol.clone();
            from.residuals.total = start_residual;
            let mut k = 1.0;
            let mut certify = |_: &Points, _: &[Vec<f64>]| {
                k *= 0.5;
                (k, ())
            };
            polish_rounds(
                &mut be,
                &stencil,
                &sets,
                d,
                &opts,
                from,
                None,
                0.0,
                &mut |_| true,
                &mut certify,
                None,
                None,
            )
            .unwrap()
            .unwrap()
            .calls
        };
        // A start no Newton step can improve on: one call.
        assert_eq!(calls(f64::MIN_POSITIVE), 1);
        // The iterate itself: the calls go on while they lower the residual.
        let from_iterate = calls(sol.residuals.total);
        assert!(from_iterate > 1, "{from_iterate}");
        // An unknown start: the first call is not judged.
        let unknown = calls(0.0);
        assert!((2..=POLISH_ROUNDS).contains(&unknown), "{unknown}");
    }
}
