//! The working set: the one method with the condensed backend, run on a growing set W of data
//! constraints.
//!
//! At the optimum most data constraints are usually inactive (the bench's closed curves: 3.6 %
//! of the balls at n = 10⁴, 0.9 % at n = 10⁵), and a constraint that is inactive at the
//! optimum can be dropped without changing it. So the method runs on a working set W: the
//! condensation is taken onto the data vertices of W only
//! ([`Condensation::at_vertices_reusing`]; the other data vertices become free vertices of longer
//! spans), and the optimum of the relaxed problem is accepted when its curve respects every
//! constraint outside W with a margin ([`WorkingSetOptions::margin`], measured by each kind's
//! [`PointSet::closeness`]) — then it is feasible for all constraints and optimal among a
//! superset of curves, so optimal. Otherwise constraints join W and the round repeats: all the
//! violated (and nearly violated, [`WorkingSetOptions::near`]) ones when they are few, else the
//! local maxima of the closeness ([`WorkingSetOptions::window`], a window that narrows every
//! [`WorkingSetOptions::window_halving`] rounds). W only grows, so this ends (at
//! worst with every constraint, taken at once after [`WorkingSetOptions::max_rounds`], or from
//! round [`WorkingSetOptions::dense_round`] when most constraints outside W are violated,
//! [`WorkingSetOptions::dense`], or earlier when nearly all are,
//! [`WorkingSetOptions::dense_early`]); it starts from the interpolated points, the ends of an open
//! curve and every [`WorkingSetOptions::start_step`]-th constraint (and, in Algorithm 4.1, the
//! constraints active in the previous knot iteration) — or, when the data of a problem of balls
//! turn more than their balls can straighten at many points ([`WorkingSetOptions::turn_start`],
//! a sign that most balls end active), with every constraint in a single round. A round is
//! judged as soon as its residual reaches [`WorkingSetOptions::round_tolerance`] (the method is
//! stopped there and resumed from the same iterate if the round is accepted), and judged again
//! at its end. An accepted round on a dense W ([`WorkingSetOptions::early_polish`]) is polished
//! right at the round tolerance (Newton's method on the active set, on W's condensation or, when
//! a fifth of W or more is inactive, on a condensation onto its active points), and the method
//! resumes only when that polish does not get the caller's certificate to its aim. An answer
//! the judge accepts but the caller's certificate does not goes on from the round's last iterate
//! to the stricter tolerance the caller gives ([`Aim::strict`]), and the better answer is
//! kept. Each round's condensation reuses the spans of the previous one that no new point
//! splits. The multipliers of the constraints outside W are 0.

use banded::vector::dot;
use conic::{Start, Status};
use divdiff::{Knots, Points};

use super::condensed::{Condensed, PointSet};
use super::round_polish::{multipliers, polish_rounds, ActivePolish, Certified, Polished};
use crate::fast::Condensation;
use crate::operator::Stencil;
use crate::Error;

/// Tuning of the working set, with documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkingSetOptions {
    /// The working set runs with at least this many data points (fewer: one round on all;
    /// default 64).
    pub min_points: usize,
    /// …and with at most this many vertices per span, k + 1 (more: the O(N) passes of each
    /// round outweigh the interior-point work saved; default 32).
    pub max_stride: usize,
    /// W starts with about this many constraints (every n/this-th; default 4)…
    pub start_points: usize,
    /// …and at least every this-many-th (default 64).
    pub start_step: usize,
    /// A constraint outside W whose closeness is at least 1 − this counts as violated: the round
    /// is not accepted (default 1e-9).
    pub margin: f64,
    /// Constraints outside W within this of their boundary are "near" and join with the
    /// violated ones when those are few (default 0.02).
    pub near: f64,
    /// When the near constraints number at most 1/this of W, all of them join; otherwise only
    /// the local maxima of the closeness within [`WorkingSetOptions::window`] points
    /// (default 2).
    pub add_all: usize,
    /// After this many rounds W becomes every constraint (one more round ends the method;
    /// default 16).
    pub max_rounds: usize,
    /// From round [`WorkingSetOptions::dense_round`] on, when more than this fraction of the
    /// constraints outside W are (nearly) violated, the next round takes all: most are active and
    /// the rounds would add them a few at a time. A start set holding more than this fraction
    /// also means one round on all (default 0.5).
    pub dense: f64,
    /// The round from which [`WorkingSetOptions::dense`] applies (default 2). The first round,
    /// from a small start, leaves about half the constraints violated whether or not most are
    /// active; the second tells them apart. Measured after round 2 at n = 10⁴, closed, balls of
    /// 0.2–0.7 × the mean spacing (`crates/curvefit-py/bench`'s data): the noisy star, 83 %
    /// active at the optimum, leaves 64 % violated; the same star with radii twice as large, 17 %
    /// active, 24 %; the smooth wavy circle, 3.6 % active, 14 %. (After round 1 they leave 53 %,
    /// 48 % and 59 %.) From round 4, the earlier default, the star took 48 iterations where it
    /// now takes 32.
    pub dense_round: usize,
    /// Before [`WorkingSetOptions::dense_round`], the next round takes all when more than this
    /// fraction of the constraints outside W are (nearly) violated (default 0.9: the first round
    /// of the bench's noisy star leaves 95–98 % violated, 89 % of its balls are active at the
    /// optimum; the smooth wavy circle's leaves 58 %, 3.6 % active).
    pub dense_early: f64,
    /// Half-width, in data points, of the window of the local-maximum rule in the first rounds
    /// (default 16)…
    pub window: usize,
    /// …halved every this many rounds, down to 1 (default 2; 0 keeps it fixed): a window of w adds
    /// at most one constraint in 2w + 1, so a fixed window adds W's active constraints at a
    /// fixed pace. With 16 fixed, the star with 17 % active took 9 rounds (117 iterations); with
    /// the window halved every second round, 7 (97 iterations; the wavy circle 54 → 45).
    pub window_halving: usize,
    /// A round is judged when its residual first reaches this (default 1e-6): only an accepted
    /// round goes on to the full tolerance.
    pub round_tolerance: f64,
    /// A round on at least this fraction of the constrained points is polished as soon as the
    /// judge accepts it at [`WorkingSetOptions::round_tolerance`] (the method resumes only if the
    /// polish does not get there; default 0.5): on a dense working set an interior-point
    /// iteration costs as much as a polish step, and the polish needs three or four where the
    /// method needs six more. A sparse working set's iterations cost O(|W|), the polish's steps
    /// O(N).
    pub early_polish: f64,
    /// W starts with every constraint (one round) when more than this fraction of the balls
    /// have their data point farther from the segment between its two neighbours than the
    /// ball's radius (default 0.15; a first solve of balls alone, not after a knot update):
    /// there the data turn more than the ball lets the curve straighten, and the energy presses
    /// the curve against it. Measured at
    /// n = 10⁴, closed unless said, k = 3, in process, rounds against one round on all: the
    /// Python bench's noisy star (radii 0.2–0.7 of the mean spacing; 98 % of the balls turn past
    /// their radii, 83 % end active) 54.5 → 48.2 ms, open 61.2 → 54.0, radii × 0.5 39.5 → 33.8,
    /// × 2 (52 % turn past, 17 % active) 59.6 → 48.2; a random walk with unit steps and radius 1
    /// (20 %, 43 % active) 78.6 → 56.6, radius 0.3 (73 %, 87 %) 48.4 → 46.7. Below it, where one
    /// round on all costs more: the star with radii × 4 (7 % turn past, 0.1 % active; one round
    /// would take 136 ms against 10.7), the smooth wavy circle (0 %, 3.6 % active; 58 against
    /// 19 ms), the same with noise of 0.3 of the mean radius (3.5 %, 5.3 %; 67 against 27), the
    /// random walk with radius 3 (0 %, 10 %; 61 against 52). Greater than 1 turns the test off.
    pub turn_start: f64,
}

impl Default for WorkingSetOptions {
    fn default() -> Self {
        WorkingSetOptions {
            min_points: 64,
            max_stride: 32,
            start_points: 4,
            start_step: 64,
            margin: 1e-9,
            near: 0.02,
            add_all: 2,
            max_rounds: 16,
            dense: 0.5,
            dense_round: 2,
            dense_early: 0.9,
            window: 16,
            window_halving: 2,
            round_tolerance: 1e-6,
            early_polish: 0.5,
            turn_start: 0.15,
        }
    }
}

impl PointSet {
    /// How close p is to leaving the set, relative to the set's size: 0 at its centre (the
    /// data point, for a ball), 1 on its boundary, above 1 outside. A ball: |p − q|/ε; a
    /// polytope: 1 + max_k (n̂_k·p − ĉ_k)/ℓ with ℓ the depth of q inside it (or `spacing`, the
    /// local data spacing, when q is not inside); an interpolated point: 0.
    pub(crate) fn closeness(&self, p: &[f64], q: &[f64], spacing: f64) -> f64 {
        match self {
            PointSet::Fixed => 0.0,
            PointSet::Ball(r) => {
                p.iter()
                    .zip(q)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
                    / r
            }
            PointSet::Faces(faces) => {
                let depth = faces
                    .iter()
                    .map(|f| f.offset - dot(&f.normal, q))
                    .fold(f64::INFINITY, f64::min);
                let scale = if depth > 0.0 { depth } else { spacing };
                let worst = faces
                    .iter()
                    .map(|f| dot(&f.normal, p) - f.offset)
                    .fold(f64::NEG_INFINITY, f64::max);
                1.0 + worst / scale.max(f64::MIN_POSITIVE)
            }
        }
    }
}

/// The result of the working-set method.
pub(crate) struct WorkingSetSolution<C> {
    /// The refined vertices.
    pub points: Points,
    /// Per data point, in the conventions of [`crate::Refinement::multipliers`].
    pub multipliers: Vec<Vec<f64>>,
    /// Interior-point iterations over all rounds.
    pub iterations: usize,
    /// The caller's certificate of the returned curve and multipliers.
    pub certificate: C,
}

/// The caller's independent certificate of a curve and the multipliers of every data point:
/// its relative KKT residual and whatever the caller keeps of it.
pub(crate) type Certify<'c, C> = &'c mut dyn FnMut(&Points, &[Vec<f64>]) -> (f64, C);

/// The round's judge: whether a curve respects every constraint outside W with the margin
/// (filling in the near and violated ones).
type Judge<'j> = &'j mut dyn FnMut(&Points, &mut Vec<(usize, f64)>) -> bool;

/// The fixed-knot data-vertex problem the working set solves: the knots and their stencil, the
/// data and each data point's set (`None` for no constraint), attached at the vertices 0,
/// stride, 2·stride, …, and the cone solver's options.
#[derive(Clone, Copy)]
pub(crate) struct Setting<'a> {
    pub knots: &'a Knots,
    pub stencil: &'a Stencil,
    pub q: &'a Points,
    pub sets: &'a [Option<PointSet>],
    pub stride: usize,
    pub conic: &'a conic::Options,
}

/// What the caller's certificate is asked for: the level a round's curve is polished to
/// (`target`) and the level at which a curve is accepted at all (`accept`); and a stricter
/// tolerance of the method (below `Setting::conic`'s), to which a round whose answer is not
/// accepted goes on from its last iterate (`strict`; `None`: it stops).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Aim {
    pub target: f64,
    pub accept: f64,
    pub strict: Option<f64>,
}

/// Solves the data-vertex problem (each data point i in `sets[i]`, `None` for no constraint)
/// at the data vertices 0, stride, 2·stride, … of `knots` by the working-set method, first from
/// `warm` (the previous knot iteration's answer) when given ([`polish_from_warm`]). An
/// accepted round whose curve `certify` puts above `aim.target` is polished
/// ([`conic::polish::polish_solution`]) and judged again; the better of the two is returned.
///
/// # Errors
/// [`Error::Energy`] if a factorization fails; [`Error::NotConverged`] with the best certificate
/// when the last round (all constraints) does not reach `conic.tolerance`'s neighbourhood
/// (its certificate above 1e-6: the caller certifies anything better independently).
pub(crate) fn solve<C>(
    setting: &Setting<'_>,
    options: &WorkingSetOptions,
    warm: Option<(&Points, &[Vec<f64>])>,
    certify: Certify<'_, C>,
    aim: Aim,
    progress: Option<&crate::Observer>,
) -> Result<WorkingSetSolution<C>, Error> {
    if let Some(warm) = warm {
        if let Some(sol) = polish_from_warm(setting, warm, certify, aim.accept)? {
            return Ok(sol);
        }
    }
    let (q, sets, stride) = (setting.q, setting.sets, setting.stride);
    // Otherwise the constraints active in the previous answer (a positive multiplier) start W.
    let active: Option<Vec<bool>> =
        warm.map(|(_, m)| m.iter().map(|w| w.iter().any(|&w| w > 0.0)).collect());
    let start = active.as_deref();
    let n = q.len();
    let constrained = sets.iter().filter(|s| s.is_some()).count();
    let dense_start = start.is_some_and(|s| {
        s.iter().filter(|&&a| a).count() as f64 > options.dense * constrained as f64
    });
    // (The previous answer's active set, when there is one, says more than the data's turns.)
    let turning = start.is_none()
        && turns_past_radii(q, sets, setting.knots.is_closed())
            .is_some_and(|f| f > options.turn_start);
    let step = if n < options.min_points || stride > options.max_stride || dense_start || turning {
        1
    } else {
        (n / options.start_points).clamp(1, options.start_step)
    };
    solve_from(setting, options, step, start, certify, aim, progress)
}

/// The fraction of the balls whose data point q_i lies farther than the radius from the segment
/// between its neighbours q_{i−1} and q_{i+1} (the interior points of an open curve; `None` when
/// there are none, or when a constraint other than a ball or an interpolated point is present).
/// A curve through the balls can straighten such a turn only by leaving q_i by more than the ball
/// allows, so the energy presses it against the ball: a cheap forecast, from the data alone, of
/// a dense active set ([`WorkingSetOptions::turn_start`]).
pub(crate) fn turns_past_radii(q: &Points, sets: &[Option<PointSet>], closed: bool) -> Option<f64> {
    let n = q.len();
    if n < 3
        || sets
            .iter()
            .any(|s| !matches!(s, None | Some(PointSet::Ball(_) | PointSet::Fixed)))
    {
        return None;
    }
    let (mut balls, mut past) = (0usize, 0usize);
    let interior = if closed { 0..n } else { 1..n - 1 };
    for i in interior {
        let Some(PointSet::Ball(r)) = sets[i] else {
            continue;
        };
        let (a, p, b) = (q.point((i + n - 1) % n), q.point(i), q.point((i + 1) % n));
        // The nearest point of the segment a + t(b − a), t in [0, 1].
        let (mut ab2, mut apab) = (0.0, 0.0);
        for ((&a, &p), &b) in a.iter().zip(p).zip(b) {
            ab2 += (b - a) * (b - a);
            apab += (p - a) * (b - a);
        }
        let t = if ab2 > 0.0 {
            (apab / ab2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let dist2: f64 = a
            .iter()
            .zip(p)
            .zip(b)
            .map(|((&a, &p), &b)| {
                let e = p - (a + t * (b - a));
                e * e
            })
            .sum();
        balls += 1;
        past += usize::from(dist2 > r * r);
    }
    (balls > 0).then(|| past as f64 / balls as f64)
}

/// The knot iterations of Algorithm 4.1 move the knots a little and the active set rarely: the
/// previous iteration's answer (`warm`: its points and data multipliers), put on the new knots
/// with every data point in W, is polished ([`conic::polish::polish_solution`]: Newton steps on
/// the active set read off its complementary s and z, with active-set changes) and returned when
/// `certify` accepts it (≤ `accept`) — a few banded factorizations instead of an interior-point
/// solve from the centre. Anything else (a polytope, a point without a set, a polish that does
/// not get there, or whose first Newton step leaves its residual above [`WARM_ABANDON`]) returns
/// `None` and the method runs as usual.
fn polish_from_warm<C>(
    &Setting {
        knots,
        stencil,
        q,
        sets,
        stride,
        conic: conic_opts,
    }: &Setting<'_>,
    (points, wmult): (&Points, &[Vec<f64>]),
    certify: Certify<'_, C>,
    accept: f64,
) -> Result<Option<WorkingSetSolution<C>>, Error> {
    let (n, d) = (q.len(), q.dim());
    if conic_opts.polish.is_none()
        || points.len() != knots.vertex_count()
        || points.dim() != d
        || wmult.len() != n
    {
        return Ok(None);
    }
    let Some(wsets) = sets
        .iter()
        .map(|s| match s {
            Some(s @ (PointSet::Ball(_) | PointSet::Fixed)) => Some(s.clone()),
            _ => None,
        })
        .collect::<Option<Vec<PointSet>>>()
    else {
        return Ok(None);
    };
    let need = if knots.is_closed() { 2 } else { 3 };
    if n < need {
        return Ok(None);
    }
    let vertices: Vec<usize> = (0..n).map(|i| i * stride).collect();
    let cond = Condensation::at_vertices_reusing(knots, stencil, vertices, None)?;
    let mut be = Condensed::new(&cond, knots, q.coords().to_vec(), wsets.clone(), d)?;
    let x: Vec<f64> = (0..n)
        .filter(|&i| matches!(wsets[i], PointSet::Ball(_)))
        .flat_map(|i| points.point(i * stride).to_vec())
        .collect();
    let w: Vec<f64> = wmult
        .iter()
        .map(|m| m.first().copied().unwrap_or(0.0))
        .collect();
    let Some(from) = be.warm_solution(x, &w) else {
        return Ok(None);
    };
    // W holds every constraint: nothing outside it to judge. The polish stops once accepted; it
    // runs on the points active in the previous answer when a fifth or more are not
    // (`ActivePolish`: a condensation onto them, joined by any point its curve leaves).
    let qw = q.coords().to_vec();
    let mut opts = conic_opts.clone();
    if let Some(po) = opts.polish.as_mut() {
        po.abandon_first = Some(WARM_ABANDON);
    }
    let mut polish = ActivePolish {
        be: &mut be,
        cond: &cond,
        knots,
        stencil,
        qw: &qw,
        wsets: &wsets,
        d,
        conic_opts: &opts,
        margin: WorkingSetOptions::default().margin,
        target: accept,
    };
    let start = polish.start(&from);
    let polished = polish.run(&start, &mut |_| true, certify)?;
    Ok(match polished {
        Some(Polished {
            best: Some(best),
            calls,
            ..
        }) if best.k <= accept => Some(WorkingSetSolution {
            points: best.points,
            multipliers: best.multipliers,
            iterations: calls,
            certificate: best.certificate,
        }),
        _ => None,
    })
}

/// A knot update's warm polish gives up when its first Newton step leaves the method's relative
/// residual above this ([`conic::PolishOptions::abandon_first`]): the start is too far off for
/// Newton's quadratic regime, and the cold solve is cheaper than the steps and active-set changes
/// it would take. Measured on fifteen data sets at n = 10⁴, k = 3, three updates each
/// (ROBUSTNESS.md item 26): of the ten warm polishes that failed after 35–112 ms, seven had a
/// first step above 1e-2 (1.2e-2 … 3.3e-2), the other three 1.3e-4 … 9.5e-3; of the 35 that
/// succeeded, four had (1.3e-2 … 3.1e-2), three of them slower than a cold solve (52–97 ms
/// against 44–52) and one faster (16 against 47 ms); the rest 1.6e-6 … 6.4e-3.
const WARM_ABANDON: f64 = 1e-2;

/// [`solve`] with W started from every `step`-th constraint (1: all, a single round) and the
/// ones marked in `start`.
pub(crate) fn solve_from<C>(
    &Setting {
        knots,
        stencil,
        q,
        sets,
        stride,
        conic: conic_opts,
    }: &Setting<'_>,
    options: &WorkingSetOptions,
    step: usize,
    start: Option<&[bool]>,
    certify: Certify<'_, C>,
    aim: Aim,
    progress: Option<&crate::Observer>,
) -> Result<WorkingSetSolution<C>, Error> {
    let n = q.len();
    let d = q.dim();
    let closed = knots.is_closed();
    let constrained = sets.iter().filter(|s| s.is_some()).count();
    // The local data spacing (the closeness scale of a polytope its point is not inside).
    let spacing: Vec<f64> = (0..n)
        .map(|i| {
            let j = if i + 1 < n {
                i + 1
            } else if closed {
                0
            } else {
                i - 1
            };
            dot_dist(q.point(i), q.point(j))
        })
        .collect();
    // The interpolated points and the ends of an open curve are always in W (the condensation
    // needs the first data vertex, and the last of an open curve); of the others, every
    // `step`-th to start with.
    let mut work: Vec<bool> = (0..n)
        .map(|i| {
            matches!(sets[i], Some(PointSet::Fixed))
                || i == 0
                || (!closed && i + 1 == n)
                || (sets[i].is_some()
                    && (i % step == 0 || start.is_some_and(|s| s.get(i) == Some(&true))))
        })
        .collect();
    // The condensation needs data rows (see `fixed::condensed_sets`): the first constrained
    // interior points join until it has them.
    let need = if closed { 2 } else { 3 };
    for i in 1..n {
        if work.iter().filter(|&&w| w).count() >= need {
            break;
        }
        if sets[i].is_some() {
            work[i] = true;
        }
    }
    if work.iter().filter(|&&w| w).count() < need || sets[0].is_none() {
        return Err(Error::Unsupported {
            field: "constraint",
            reason: "the condensed method needs the first data point (and the last of an open curve) constrained, and two (closed) or three (open) constraints in all",
        });
    }
    let mut iterations = 0;
    let mut near: Vec<(usize, f64)> = Vec::new();
    let mut ratio = vec![0.0; n];
    let mut prev: Option<Condensation> = None;
    let mut rounds = 0;
    loop {
        let idx: Vec<usize> = (0..n).filter(|&i| work[i]).collect();
        let everything = idx.iter().filter(|&&i| sets[i].is_some()).count()
            == sets.iter().filter(|s| s.is_some()).count();
        let vertices: Vec<usize> = idx.iter().map(|&i| i * stride).collect();
        let cond = Condensation::at_vertices_reusing(knots, stencil, vertices, prev.take())?;
        let mut qw = Vec::with_capacity(idx.len() * d);
        for &i in &idx {
            qw.extend_from_slice(q.point(i));
        }
        let wsets: Vec<PointSet> = idx
            .iter()
            .map(|&i| sets[i].clone().unwrap_or(PointSet::Fixed))
            .collect();
        // The judge: the curve respects every constraint outside W with the margin.
        let mut judge = |p: &Points, near: &mut Vec<(usize, f64)>| {
            near.clear();
            for i in (0..n).filter(|&i| !work[i]) {
                let Some(set) = &sets[i] else { continue };
                let r = set.closeness(p.point(i * stride), q.point(i), spacing[i]);
                if r >= 1.0 - options.near {
                    near.push((i, r));
                }
            }
            !near.iter().any(|v| v.1 >= 1.0 - options.margin)
        };
        let round = run_round(
            &cond,
            knots,
            stencil,
            qw,
            wsets,
            d,
            conic_opts,
            options,
            &mut judge,
            &mut near,
            &mut |p: &Points, wmult: &[Vec<f64>]| {
                // The multipliers of all data points for the caller's certificate.
                let mut all = empty_multipliers(sets, d);
                for (m, &i) in wmult.iter().zip(&idx) {
                    all[i].clone_from(m);
                }
                let (k, c) = certify(p, &all);
                (k, (c, all))
            },
            aim,
            idx.len() as f64 >= options.early_polish * constrained as f64,
            progress,
        );
        prev = Some(cond);
        let round = match round {
            Ok(r) => r,
            // A round that fails on a subset is repeated on every constraint.
            Err(_) if !everything => {
                for i in 0..n {
                    work[i] = work[i] || sets[i].is_some();
                }
                continue;
            }
            Err(e) => return Err(e),
        };
        iterations += round.iterations;
        if let Some((points, (certificate, multipliers))) = round.accepted {
            return Ok(WorkingSetSolution {
                points,
                multipliers,
                iterations,
                certificate,
            });
        }
        rounds += 1;
        let outside = (0..n).filter(|&i| !work[i] && sets[i].is_some()).count();
        let dense = if rounds >= options.dense_round {
            options.dense
        } else {
            options.dense_early
        };
        if rounds >= options.max_rounds || near.len() as f64 > dense * outside as f64 {
            // (A bound on the work: the next round takes every constraint. So does a later
            // round that still leaves most constraints outside W violated: most are active.)
            for i in 0..n {
                work[i] = work[i] || sets[i].is_some();
            }
        } else if near.len() * options.add_all <= idx.len() {
            // Few left: all of them (and the near ones) join.
            for &(i, _) in &near {
                work[i] = true;
            }
        } else {
            // Many: only those leaving their sets farthest within the window on either side (the
            // curve moves near them, which settles most of the others).
            // (Halved down to 1, not to 0: a window of 0, every near constraint a maximum, is
            // only what the caller asks for.)
            let window = match options.window_halving {
                0 => options.window,
                h => (options.window >> ((rounds - 1) / h).min(usize::BITS as usize - 1))
                    .max(options.window.min(1)),
            };
            for &(i, r) in &near {
                ratio[i] = r;
            }
            for &(i, r) in &near {
                let top = r >= 1.0 - options.margin
                    && (1..=window.min(n / 2)).all(|o| {
                        let right = (closed || i + o < n).then(|| (i + o) % n);
                        let left = (closed || i >= o).then(|| (i + n - o) % n);
                        [right, left]
                            .into_iter()
                            .flatten()
                            .all(|j| match ratio[j].total_cmp(&r) {
                                std::cmp::Ordering::Less => true,
                                std::cmp::Ordering::Equal => j > i,
                                std::cmp::Ordering::Greater => false,
                            })
                    });
                if top {
                    work[i] = true;
                }
            }
            for &(i, _) in &near {
                ratio[i] = 0.0;
            }
        }
    }
}

/// Zero multipliers of every data point, in the shapes of [`crate::Refinement::multipliers`].
fn empty_multipliers(sets: &[Option<PointSet>], d: usize) -> Vec<Vec<f64>> {
    sets.iter()
        .map(|s| match s {
            Some(PointSet::Faces(f)) => vec![0.0; f.len()],
            Some(PointSet::Fixed) => vec![0.0; d],
            None => Vec::new(),
            Some(PointSet::Ball(_)) => vec![0.0],
        })
        .collect()
}

fn dot_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// One round's outcome: the curve and its certificate if the judge accepted it.
struct Round<C> {
    accepted: Option<(Points, C)>,
    iterations: usize,
}

/// One round: the method on W, judged at the round tolerance and at the end, and polished when
/// the caller's certificate asks for it.
#[allow(clippy::too_many_arguments)]
fn run_round<C>(
    cond: &Condensation,
    knots: &Knots,
    stencil: &Stencil,
    qw: Vec<f64>,
    wsets: Vec<PointSet>,
    d: usize,
    conic_opts: &conic::Options,
    options: &WorkingSetOptions,
    judge: Judge<'_>,
    near: &mut Vec<(usize, f64)>,
    certify: Certify<'_, C>,
    aim: Aim,
    early: bool,
    progress: Option<&crate::Observer>,
) -> Result<Round<C>, Error> {
    let mut be = Condensed::new(cond, knots, qw.clone(), wsets.clone(), d)?;
    let mut start = be.ball_start();
    let mut iterations = 0;
    // The polish runs on demand below, not inside the method: the condensed iterations are
    // cheap, the polish's systems are O(N).
    let ipm_opts = conic::Options {
        polish: None,
        ..conic_opts.clone()
    };
    // Stop once at the round tolerance to judge.
    let mut judged = false;
    let sol = loop {
        let tol = options.round_tolerance;
        let mut monitor = |it: &conic::Iterate<'_>| {
            report_iteration(progress, it);
            judged || it.residuals.total > tol
        };
        let sol = conic::solve_with(&mut be, &ipm_opts, start.take(), &mut monitor)?;
        iterations += sol.iterations;
        if sol.status != Status::Stopped {
            break sol;
        }
        judged = true;
        let (points, _) = be.curve(&sol.x, stencil)?;
        if !judge(&points, near) {
            return Ok(Round {
                accepted: None,
                iterations,
            });
        }
        // Accepted so far: the active-set polish from this iterate (Newton's method on the
        // constraints it identifies as active, with active-set changes) usually finishes the
        // round in a few O(N) steps where the method would take several more iterations. When
        // it does not get there (or its curve leaves a constraint outside W), the method
        // resumes from the iterate.
        if early && conic_opts.polish.is_some() {
            let mut on_active = ActivePolish {
                be: &mut be,
                cond,
                knots,
                stencil,
                qw: &qw,
                wsets: &wsets,
                d,
                conic_opts,
                margin: options.margin,
                target: aim.target,
            };
            let start = on_active.start(&sol);
            if let Some(Polished {
                best: Some(b),
                settled,
                ..
            }) = on_active.run(&start, &mut |p| judge(p, near), certify)?
            {
                if b.k <= aim.target || (settled && b.k <= aim.accept) {
                    return Ok(Round {
                        accepted: Some((b.points, b.certificate)),
                        iterations,
                    });
                }
            }
        }
        start = Some(Start {
            x: sol.x,
            sz: Some((sol.s, sol.z)),
        });
    };
    // The round's answer from the method's last iterate (`None`: the judge refused a curve),
    // at the method's tolerance `tol`.
    let mut finish = |be: &mut Condensed<'_>,
                      sol: &conic::Solution,
                      tol: &conic::Options,
                      iterations: usize|
     -> Result<Option<Certified<C>>, Error> {
        let round = ActivePolish {
            be,
            cond,
            knots,
            stencil,
            qw: &qw,
            wsets: &wsets,
            d,
            conic_opts: tol,
            margin: options.margin,
            target: aim.target,
        };
        finish_round(round, judge, near, certify, sol, iterations)
    };
    let strict = aim.strict.filter(|&s| s < conic_opts.tolerance);
    let mut best = finish(&mut be, &sol, conic_opts, iterations)?;
    // An answer the caller's certificate does not accept goes on at the stricter tolerance
    // from the same iterate (the strict entry of the strategy list would start over: on
    // points in boxes of half-spaces, where the polish does not settle the active set, that
    // was half of the solve), and the better answer is kept.
    if let (Some(tol), Some(b)) = (strict, best.as_ref()) {
        // (NaN is not accepted either.)
        if b.k > aim.accept || b.k.is_nan() {
            let strict_opts = conic_opts.clone().with_tolerance(tol);
            let ipm_opts = ipm_opts.clone().with_tolerance(tol);
            let mut monitor = |it: &conic::Iterate<'_>| {
                report_iteration(progress, it);
                true
            };
            // On a new backend: the polish leaves this one factoring more exactly
            // (`KktSystem::escalate`), which is slower and, at n = 10^5, stopped short of the
            // certificate a fresh start at the strict tolerance reaches. (Any failure here
            // keeps the answer the round has.)
            let fresh = Condensed::new(cond, knots, qw.clone(), wsets.clone(), d).ok();
            if let Some(mut fresh) = fresh {
                let start = Start {
                    x: sol.x,
                    sz: Some((sol.s, sol.z)),
                };
                let sol = conic::solve_with(&mut fresh, &ipm_opts, Some(start), &mut monitor);
                if let Ok(sol) = sol {
                    iterations += sol.iterations;
                    if let Ok(Some(c)) = finish(&mut fresh, &sol, &strict_opts, iterations) {
                        if best.as_ref().is_some_and(|b| c.k < b.k || b.k.is_nan()) {
                            best = Some(c);
                        }
                    }
                }
            }
        }
    }
    Ok(Round {
        accepted: best.map(|b| (b.points, b.certificate)),
        iterations,
    })
}

/// Reports one iteration of the method on the condensed working set to the progress observer.
fn report_iteration(progress: Option<&crate::Observer>, it: &conic::Iterate<'_>) {
    crate::progress::report(
        progress,
        crate::Progress::Iteration {
            solver: "condensed working set",
            iteration: it.iteration,
            residual: it.residuals.total,
        },
    );
}

/// The end of a round ([`run_round`]) from the method's last iterate `sol`, after `iterations`
/// of the round: its curve judged, certified, and polished to the aim (`round`: W's backend,
/// condensation and sets, the method's options and the target, as the polish on the active
/// points takes them). `None` when the judge refuses a curve.
fn finish_round<C>(
    mut round: ActivePolish<'_, '_>,
    judge: Judge<'_>,
    near: &mut Vec<(usize, f64)>,
    certify: Certify<'_, C>,
    sol: &conic::Solution,
    iterations: usize,
) -> Result<Option<Certified<C>>, Error> {
    // (NaN is not converged either.)
    if sol.residuals.total.is_nan() || sol.residuals.total > 1e-6 {
        return Err(Error::NotConverged {
            solver: "condensed interior-point method",
            iterations,
            residual: sol.residuals.total,
        });
    }
    let (points, g) = round.be.curve(&sol.x, round.stencil)?;
    if !judge(&points, near) {
        return Ok(None);
    }
    let mult = multipliers(round.be, round.wsets, &sol.z, &g, round.d);
    let (k, certificate) = certify(&points, &mult);
    let certified = Certified {
        k,
        certificate,
        points,
        multipliers: mult,
    };
    // Polish to the aim: each call takes Newton steps on the active set until the method's
    // stationarity is at its tolerance of the reactions (`conic::Residuals::reaction`, not only
    // of its force floor ‖Q‖ times the largest step, `Condensed::new`, far above the forces of
    // a finely refined curve) or at rounding, at most `PolishOptions::steps`. The calls repeat
    // from the polished point while the caller's certificate is above `target` and falls (F(t)
    // of the free-knot optimizer and its envelope gradient are only as accurate as this curve;
    // a call that ran out of steps after an active-set change goes on from its best point).
    // Each polished curve is judged again (it moves a little). On the active points of W when
    // a fifth of W or more is inactive (`ActivePolish`); on W when that polish leaves a point of
    // W it dropped.
    let polish = round.conic_opts.polish.is_some();
    // (Evaluated once for the choice of route and the first polish call on either.)
    let start = (certified.k > round.target && polish).then(|| round.start(sol));
    if let Some(start) = start.as_ref().filter(|s| s.subset) {
        if let Some(p) = round
            .reborrow()
            .run(start, &mut |p| judge(p, near), certify)?
        {
            return Ok(Some(match p.best {
                Some(b) if b.k < certified.k => b,
                _ => certified,
            }));
        }
    }
    let polished = polish_rounds(
        round.be,
        round.stencil,
        round.wsets,
        round.d,
        round.conic_opts,
        // (a copy: the round goes on from `sol` when the certificate refuses the answer)
        sol.clone(),
        Some(certified),
        round.target,
        &mut |p| judge(p, near),
        certify,
        None,
        start.as_ref().and_then(|s| s.ev.as_ref()),
    )?;
    Ok(polished.and_then(|p| p.best))
}

#[cfg(test)]
mod tests;
