//! The exact solver for polyline bounds: a dual active-set (Goldfarb–Idnani) method on point
//! constraints, driven by an exact sweep of the strip (an exchange method for the
//! semi-infinite QP).
//!
//! **The point problem.** For a finite set of points P with sides, minimize ∫f''² subject to
//! f(t_i) = y_i and f(p) ≥ e(p) (lower points), f(p) ≤ d(p) (upper points). Its solution is the
//! cubic spline through the data and the *active* points held on their bound (Holladay), with
//! natural (or the prescribed clamped) ends; the multiplier of an active point is the jump of
//! f''' there (∂∫f''²/∂f(p) = 2·jump), which must be ≥ 0 at a lower point and ≤ 0 at an upper
//! one. It is a relaxation of the strip problem, so its optimum is a **lower bound** on the strip
//! optimum, and when its spline satisfies the strip everywhere (to the tolerance), it **is** the
//! strip optimum: a function is optimal for the strip exactly when it is C² (every spline is),
//! interpolates, stays in the strip, and f''' jumps only at contacts, up at lower and down at
//! upper ones (for any feasible g, ∫g''² − ∫f''² ≥ 2 Σ jump·(g − f)(τ) ≥ 0).
//!
//! **Dual active set** (Goldfarb & Idnani, *A numerically stable dual method for solving strictly
//! convex quadratic programs*, Math. Programming 27, 1983). The iterate is always dual feasible
//! (every multiplier has the right sign); a violated point q is added by moving its value from
//! f(q) to its bound. Along that move everything is linear in the value (the spline is linear in
//! its data), so the multipliers of the active points move linearly: when one reaches zero
//! first, the move stops there and that point leaves the active set (its jump is zero, so the
//! spline does not change), and the move continues; otherwise q joins. Each step is one or two
//! tridiagonal solves (diagonally dominant: well conditioned however uneven the spacing), over
//! the [`SHORT_REACH`] knots on each side of the point, or the [`RESPONSE_REACH`] where the
//! response has not fallen below rounding at the first: beyond them it is below rounding, and a
//! step costs the same at M = 10² and 10⁵ knots. The dual objective increases strictly, so the
//! method cannot cycle.
//!
//! **Exchange.** An O(M) sweep ([`crate::check::excursions`]) finds, on every sub-interval
//! between consecutive knots and bound breakpoints, where f leaves the strip most (the real roots
//! of the derivative of the cubic minus the bound). In every run of consecutive violated
//! sub-intervals with f outside at their common ends (one dip of f through the bound) the worst
//! point is a candidate (one per run: adding every violated point
//! activates nearly every vertex of a narrow channel at once, far from the answer); candidates
//! still violated when their turn comes are added. Points at vertices fix contacts at kinks of
//! the polyline; points inside segments converge to the tangent contacts (the added point lands
//! where f dips deepest, and the previous one leaves the active set as its multiplier falls to
//! zero), quadratically in the measured runs. The sweeps stop when f leaves the strip nowhere
//! by more than the tolerance.
//!
//! Measured on the issue-15 channels (M = 10³ … 10⁴, 16 and 200 sites): 16–34 sweeps, 500–2600
//! spline solves; the energies agree with the Φ-based exact stage where that one converged
//! (6.5·10⁻⁹ relative, from below, as they must) and showed it 1.1·10⁻⁵ too high where it
//! stopped at a vertex contact with f'' jumping (see [`crate::strategy`]).

use crate::check::excursions;
use crate::spline::{moments, Curve, Spline, Work};
use crate::types::{Bound, Problem, Side};
use crate::Progress;

/// The sweeps stop when f leaves the strip nowhere by more than this fraction of the value scale
/// (normalized frame). Its first-order effect on the energy (holding every contact up by this
/// much, [`crate::Solution::gap`]) was ≤ 2·10⁻¹⁰ relative on the generator's channels; the
/// rounding of the spline's values there is ~10⁻¹³.
pub(crate) const EXCHANGE_TOL: f64 = 1e-12;
/// The sweeps go on with a tolerance 100 times smaller while the first-order gap estimate
/// ([`Exchanged::gap`]) exceeds this (a hair-thin strip turns sharply, so its multipliers are
/// large and a tolerance relative to the value scale alone is too coarse) …
pub(crate) const GAP_TARGET: f64 = 1e-11;
/// … down to this fraction of the value scale (the rounding of the spline's values).
const TOL_FLOOR: f64 = 1e-15;
/// Sweeps before giving up.
pub(crate) const MAX_SWEEPS: usize = 400;
/// Dual steps (additions and removals) before giving up: this many, or [`STEPS_PER_KNOT`] per
/// site and polyline vertex if more.
const MAX_STEPS: usize = 2_000_000;
/// Noisy sites in a channel ±0.02 (`cargo xtask bench strip`'s hard table) take about 22 steps
/// a site (2.2·10⁵ at n = 10⁴): with the fixed limit alone, n = 10⁵ ran out of steps.
const STEPS_PER_KNOT: usize = 50;

/// When the exchange gives up (sweeps, dual steps).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    pub sweeps: usize,
    pub steps: usize,
}

impl Limits {
    /// [`MAX_SWEEPS`], and [`MAX_STEPS`] or [`STEPS_PER_KNOT`] per site and vertex of `q`.
    fn of(q: &Problem) -> Self {
        let vertices = |b: &Bound| match b {
            Bound::Polyline(v) => v.len(),
            _ => 0,
        };
        let knots = q.t.len() + vertices(&q.lower) + vertices(&q.upper);
        Limits {
            sweeps: MAX_SWEEPS,
            steps: MAX_STEPS.max(STEPS_PER_KNOT.saturating_mul(knots)),
        }
    }
}

/// An active point: abscissa, side, and its bound value there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Contact {
    pub x: f64,
    pub side: Side,
    pub value: f64,
}

/// The exchange's answer.
pub(crate) struct Exchanged {
    /// The spline through the data and the active points.
    pub spline: Spline,
    /// The active points.
    pub active: Vec<Contact>,
    /// The largest excursion of the spline outside the strip (normalized frame).
    pub violation: f64,
    /// Whether the sweeps ended with no excursion above the tolerance.
    pub converged: bool,
    /// First-order estimate of how far the energy lies below the strip optimum, relative: what
    /// holding every contact up by the remaining excursion would cost (∂∫f''²/∂f(τ) = 2·jump),
    /// over the energy.
    pub gap: f64,
    /// Sweeps, dual steps, spline solves.
    pub sweeps: usize,
    pub steps: usize,
    pub solves: usize,
}

/// What a knot of the current spline is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Knot {
    /// A data site.
    Data,
    /// An active point on the bound of this side.
    Active(Side),
    /// The point being added (its value on the way to its bound).
    Adding,
}

/// The state of the method: the current spline on its knots, and what each knot is.
///
/// While a sweep's candidates are added, the knots are split at the point being added
/// ([`State::seek`]): `cur` and `kind` hold them up to [`AHEAD`] knots past it, `tail` the rest.
/// An insertion or removal then moves O([`RESPONSE_REACH`]) knots instead of all the knots after
/// it: with every knot in one vector, a channel with 8·10⁴ contacts spent 79 % of its time
/// moving them (quadratic in M: 65 s at n = 2·10⁴).
struct State<'a> {
    q: &'a Problem,
    cur: Spline,
    kind: Vec<Knot>,
    tail: Tail,
    work: Work,
    unit: Vec<f64>,
    response: Vec<f64>,
    /// Abscissae of the knots added and removed since the last sweep.
    touched: Vec<f64>,
    steps: usize,
    /// The dual steps allowed ([`Limits`]).
    max_steps: usize,
    solves: usize,
}

impl<'a> State<'a> {
    /// The natural (or clamped) spline through the data.
    fn new(q: &'a Problem) -> Self {
        let mut st = State {
            q,
            cur: Spline {
                x: q.t.clone(),
                v: q.y.clone(),
                m: Vec::new(),
                low: Vec::new(),
            },
            kind: vec![Knot::Data; q.t.len()],
            tail: Tail::default(),
            work: Work::default(),
            unit: Vec::new(),
            response: Vec::new(),
            touched: Vec::new(),
            steps: 0,
            max_steps: MAX_STEPS,
            solves: 0,
        };
        st.resolve();
        st
    }

    /// Splits the knots at x: `cur` ends [`AHEAD`] knots past the first knot at or after x (or
    /// at the last knot), `tail` holds the rest. Moves as many knots as lie between the last
    /// split and this one: O(M) a sweep when the candidates come in order of x.
    fn seek(&mut self, x: f64) {
        while self.tail.x.last().is_some_and(|&u| u < x) {
            self.pull();
        }
        let want = self.cur.x.partition_point(|u| *u < x) + AHEAD + 1;
        self.ahead(want);
        while self.cur.x.len() > want {
            self.tail.x.extend(self.cur.x.pop());
            self.tail.v.extend(self.cur.v.pop());
            self.tail.m.extend(self.cur.m.pop());
            self.tail.kind.extend(self.kind.pop());
        }
    }

    /// Moves knots from `tail` into `cur` until `cur` holds `len` knots or `tail` is empty.
    fn ahead(&mut self, len: usize) {
        while self.cur.x.len() < len && !self.tail.x.is_empty() {
            self.pull();
        }
    }

    /// All the knots back in `cur`.
    fn join(&mut self) {
        self.ahead(usize::MAX);
    }

    /// The first knot of `tail` to the end of `cur`.
    fn pull(&mut self) {
        self.cur.x.extend(self.tail.x.pop());
        self.cur.v.extend(self.tail.v.pop());
        self.cur.m.extend(self.tail.m.pop());
        self.kind.extend(self.tail.kind.pop());
    }

    /// Solves for the moments afresh (the updates of `add` accumulate rounding).
    fn resolve(&mut self) {
        debug_assert!(self.tail.x.is_empty(), "resolve on split knots");
        moments(
            &self.cur.x,
            &self.cur.v,
            self.q.end_slopes,
            &mut self.cur.m,
            &mut self.work,
        );
        self.solves += 1;
    }

    /// The active points.
    fn active(&self) -> Vec<Contact> {
        self.cur
            .x
            .iter()
            .zip(&self.cur.v)
            .zip(&self.kind)
            .filter_map(|((&x, &value), k)| match k {
                Knot::Active(side) => Some(Contact {
                    x,
                    side: *side,
                    value,
                }),
                _ => None,
            })
            .collect()
    }

    /// Removes active points whose multiplier has the wrong sign, the worst first, one at a
    /// time (each removal changes the others).
    ///
    /// The dual steps keep every multiplier ≥ 0 up to the rounding of their incremental updates,
    /// but the fresh solve of [`State::resolve`] can disagree in sign where two active points
    /// lie very close: next to a tangent contact inside a segment, the GI steps converge to the
    /// tangent point with pairs of active points δ apart, and the multipliers of such a pair
    /// carry rounding of order ε·V/δ³ (values rounded to ε·V, moments to that over δ², jumps to
    /// that over δ once more). In a crossing-channel property test a pair 2.6·10⁻⁹ apart came
    /// out with f''' jumping 1.6·10⁵ the wrong way (6·10⁻⁴ of the largest f'''), and the answer
    /// failed the Lemma 1.1 sign check. Removing such a point lowers the energy and moves f
    /// back into the strip (that is what a wrong-sign multiplier means) or, where it is
    /// rounding, changes f by rounding (its partner holds the contact); the sweep that follows
    /// decides either way. Moving the contact instead (replacing the nearer point of a pair by
    /// the new one) was tried: it converged linearly, oscillating about the tangent point, and
    /// ran out of sweeps on the same channel.
    fn release(&mut self) {
        loop {
            let worst = self
                .kind
                .iter()
                .enumerate()
                .filter_map(|(i, k)| match k {
                    Knot::Active(s) => {
                        let sign = if *s == Side::Lower { 1.0 } else { -1.0 };
                        let m = sign * jump(&self.cur.x, &self.cur.m, i);
                        (m < 0.0).then_some((m, i))
                    }
                    _ => None,
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((_, i)) = worst else {
                return;
            };
            self.touched.push(self.cur.x[i]);
            self.cur.x.remove(i);
            self.cur.v.remove(i);
            self.cur.m.remove(i);
            self.kind.remove(i);
            self.resolve();
        }
    }

    /// Adds the point x on `side` (violated by the current spline): the dual step. The value at
    /// x moves from f(x) to the bound; the spline is linear in its values, so the multipliers
    /// move linearly too, along the response g to a unit value at x (every other value and the
    /// end conditions homogeneous): one solve per step. The knots are split at x
    /// ([`State::seek`]).
    fn add(&mut self, x: f64, side: Side) {
        let target = self.q.bound_at(side, x);
        // x becomes a knot with the spline's own value and second derivative (same function)
        let (value, second) = self.cur.at(x);
        let mut p = self.cur.x.partition_point(|u| *u < x);
        self.cur.x.insert(p, x);
        self.cur.v.insert(p, value);
        self.cur.m.insert(p, second);
        self.kind.insert(p, Knot::Adding);
        self.touched.push(x);
        loop {
            self.steps += 1;
            // (Removals in the window shorten `cur`: the window's far edge stays short of its
            // end unless that is the last knot.)
            self.ahead(p + AHEAD + 1);
            // The response to a unit value at p, in the window lo ..= hi around it (zero
            // outside: see RESPONSE_REACH).
            let (lo, hi) = response(
                &self.cur.x,
                p,
                self.q.end_slopes,
                &mut self.unit,
                &mut self.response,
                &mut self.work,
            );
            self.solves += 1;
            let delta = target - self.cur.v[p];
            // the first active multiplier to reach zero along the move (beyond the window the
            // multipliers do not move; one already below zero there is the release's)
            let mut block: Option<(f64, usize)> = None;
            for i in lo + 1..hi {
                let Knot::Active(s) = self.kind[i] else {
                    continue;
                };
                let sign = if s == Side::Lower { 1.0 } else { -1.0 };
                let m0 = sign * jump(&self.cur.x, &self.cur.m, i);
                let m1 = m0 + delta * sign * jump(&self.cur.x[lo..=hi], &self.response, i - lo);
                // (a multiplier already below zero, by rounding or after a move, leaves at
                // once unless the move brings it back)
                if m1 < 0.0 && (m1 < m0 || m0 < 0.0) {
                    let theta = if m0 > 0.0 { m0 / (m0 - m1) } else { 0.0 };
                    if theta < 1.0 && block.is_none_or(|(t, _)| theta < t) {
                        block = Some((theta, i));
                    }
                }
            }
            let theta = block.map_or(1.0, |b| b.0);
            self.cur.v[p] += theta * delta;
            for (m, r) in self.cur.m[lo..=hi].iter_mut().zip(&self.response) {
                *m += theta * delta * r;
            }
            match block {
                None => {
                    self.cur.v[p] = target;
                    self.kind[p] = Knot::Active(side);
                    return;
                }
                Some((_, i)) => {
                    // its jump is zero now: removing the knot leaves the function unchanged
                    self.touched.push(self.cur.x[i]);
                    self.cur.x.remove(i);
                    self.cur.v.remove(i);
                    self.cur.m.remove(i);
                    self.kind.remove(i);
                    if i < p {
                        p -= 1;
                    }
                }
            }
            if self.steps >= self.max_steps {
                // the point stays short of its bound: the next sweep sees the excursion, and
                // the caller stops at the step limit
                self.kind[p] = Knot::Active(side);
                return;
            }
        }
    }
}

/// Knots on each side of an added point within which [`response`] solves when [`SHORT_REACH`]
/// is not enough (and within which it always suffices). The moments' system
/// is tridiagonal with its diagonal twice the sum of its off-diagonal entries in every row
/// (whatever the spacing), so A = D(I − N) with ‖N‖_∞ ≤ ½ and an entry of A⁻¹ at distance j
/// from the diagonal is at most 2·2⁻ʲ of the diagonal's scale: the response to a unit value at
/// p is below 2⁻⁶⁰ ≈ 10⁻¹⁸ of its size 64 knots away, so truncating it there changes the
/// moments by less than their rounding. (Solving all M knots at every dual step made a step
/// O(M): 69 s for 1.5·10⁵ steps at M ≈ 1.2·10⁴.) Every sweep starts from a fresh full solve
/// ([`State::resolve`]), which is what the answer is checked on.
const RESPONSE_REACH: usize = 64;

/// Knots [`State::seek`] keeps in `cur` after the one being added: the response window and the
/// knot after it (a multiplier at the window's edge reads its right neighbour).
const AHEAD: usize = RESPONSE_REACH + 2;

/// The knots after `cur`'s while the knots are split ([`State`]), the last knot first.
#[derive(Default)]
struct Tail {
    x: Vec<f64>,
    v: Vec<f64>,
    m: Vec<f64>,
    kind: Vec<Knot>,
}

/// The window [`response`] tries first, knots on each side of the added point: the response
/// decays by 2 − √3 ≈ 0.27 a knot on equal spacing (faster on unequal), to ~2·10⁻¹⁸ of its size
/// at 31 knots. Measured on jittered noisy sites in a channel ±0.02 (n = 10⁴, 2·10⁵ steps): the
/// steps' solves were 61 % of the time with [`RESPONSE_REACH`] alone.
const SHORT_REACH: usize = 32;

/// The short window is kept when the response next to a cut edge is at most this fraction of
/// its largest value (below rounding: the moments it would move are rounded more than that).
const CUT_EDGE: f64 = f64::EPSILON / 2.0;

/// The moments of the spline on `x` with the unit value at knot p and homogeneous end
/// conditions (natural, or zero slope where `ends` prescribes one), in a window lo ..= hi around
/// p: into `response[..=hi − lo]`, with the moments at a window edge that is not an end of the
/// spline held at zero. The window is [`SHORT_REACH`] knots each side when the response next to
/// each cut edge is below [`CUT_EDGE`] of its largest value, else [`RESPONSE_REACH`] (where the
/// bound guarantees it). Returns (lo, hi).
fn response(
    x: &[f64],
    p: usize,
    ends: [Option<f64>; 2],
    unit: &mut Vec<f64>,
    out: &mut Vec<f64>,
    work: &mut Work,
) -> (usize, usize) {
    let last = x.len() - 1;
    let mut reach = SHORT_REACH;
    loop {
        let lo = p.saturating_sub(reach);
        let hi = (p + reach).min(last);
        unit.clear();
        unit.resize(hi - lo + 1, 0.0);
        unit[p - lo] = 1.0;
        let homogeneous = [
            ends[0].filter(|_| lo == 0).map(|_| 0.0),
            ends[1].filter(|_| hi == last).map(|_| 0.0),
        ];
        moments(&x[lo..=hi], unit, homogeneous, out, work);
        if reach == RESPONSE_REACH {
            return (lo, hi);
        }
        let size = out.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // (NaN moments fail the test and are solved again on the long window, NaN again.)
        let cut = |i: usize| out[i].abs() <= CUT_EDGE * size;
        if (lo == 0 || cut(1)) && (hi == last || cut(hi - lo - 1)) {
            return (lo, hi);
        }
        reach = RESPONSE_REACH;
    }
}

/// The jump of f''' at interior knot k of the spline on `x` with moments `m` (0 at the ends).
fn jump(x: &[f64], m: &[f64], k: usize) -> f64 {
    if k == 0 || k + 1 >= x.len() {
        return 0.0;
    }
    (m[k + 1] - m[k]) / (x[k + 1] - x[k]) - (m[k] - m[k - 1]) / (x[k] - x[k - 1])
}

/// The largest excursion of `curve` (or of its pieces `range`) outside the strip of `q`, and one
/// candidate (where, side, excursion) per run of sub-intervals where it exceeds `tol`.
fn sweep(
    q: &Problem,
    curve: &Curve,
    range: std::ops::Range<usize>,
    tol: f64,
) -> (f64, Vec<(f64, Side, f64)>) {
    // per side, the excursions in order of the sub-intervals; runs are merged across sides by
    // position (a run on the lower bound and one on the upper bound are separate candidates)
    let mut worst = f64::NEG_INFINITY;
    let mut out = Vec::new();
    for side in [Side::Lower, Side::Upper] {
        let b = if side == Side::Lower {
            &q.lower
        } else {
            &q.upper
        };
        let mut run: Option<(f64, f64)> = None;
        excursions(
            b,
            &q.t,
            side,
            &curve.breaks[range.start..=range.end],
            &curve.coeffs[range.clone()],
            &mut |_, _, by, at, start| {
                if by > worst || by.is_nan() {
                    worst = by;
                }
                if by > tol || by.is_nan() {
                    // a run goes on into this sub-interval only if f is outside at their common
                    // end: separate dips are separate candidates (else a zigzag's dips, one per
                    // data interval, were one run, and the sweeps added them one at a time)
                    if start <= tol {
                        if let Some((w, at)) = run.take() {
                            out.push((at, side, w));
                        }
                    }
                    if run.is_none_or(|(w, _)| by > w) {
                        run = Some((by, at));
                    }
                } else if let Some((w, at)) = run.take() {
                    out.push((at, side, w));
                }
            },
        );
        if let Some((w, at)) = run {
            out.push((at, side, w));
        }
    }
    (worst, out)
}

/// A sweep with more candidates than this adds them in order of abscissa on split knots
/// ([`State`]); one with fewer adds the worst first on whole vectors. The worst first took
/// 10–20 % fewer dual steps on the issue-15 channels (a few to a hundred candidates a sweep,
/// 10² … 10³ knots), where moving the knots costs nothing; in order, a channel of 2·10⁴ sites
/// and 8·10⁴ contacts took 6.5 s instead of 65 s.
const IN_ORDER: usize = 64;

/// Knots on each side of a changed knot whose pieces a local sweep checks. A change of the
/// spline at one knot decays by about 2 − √3 ≈ 0.27 per knot, so new excursions appear next to
/// the changes; anything farther is found by the full sweep that follows every local sweep
/// without candidates, and only a full sweep without candidates ends the method. Measured at
/// M = 10⁴, 16 sites: 12 knots 22 ms, 4 knots 18 ms, 2 knots 20 ms (more sweeps), same answer.
const LOCAL: usize = 4;

/// The first-order gap estimate of a spline with its active points and excursion.
fn gap_of(s: &Spline, active: &[Contact], violation: f64) -> f64 {
    let mut a = 0;
    let mut jumps = 0.0;
    for (k, &u) in s.x.iter().enumerate() {
        if a < active.len() && active[a].x.to_bits() == u.to_bits() {
            jumps += s.jump(k).0.abs();
            a += 1;
        }
    }
    let e = s.energy();
    if e > 0.0 {
        2.0 * jumps * violation.max(0.0) / e
    } else {
        0.0
    }
}

/// Solves the strip problem `q` (normalized, data strictly inside) to the excursion tolerance
/// `tol` (`vscale` the value scale), tightened while the gap estimate exceeds [`GAP_TARGET`].
pub(crate) fn exchange(
    q: &Problem,
    tol: f64,
    vscale: f64,
    progress: &dyn Fn(&Progress),
) -> Exchanged {
    exchange_within(q, tol, vscale, progress, Limits::of(q))
}

/// The knots, their kinds, the excursion and the gap estimate of a converged iterate, kept while
/// the sweeps go on with a tighter tolerance: if those run out of sweeps or steps, or end with a
/// larger gap, the answer is this one (the caller decides whether its gap is certified).
struct Converged {
    spline: Spline,
    kind: Vec<Knot>,
    violation: f64,
    gap: f64,
}

/// [`exchange`] within `limits`.
pub(crate) fn exchange_within(
    q: &Problem,
    tol: f64,
    vscale: f64,
    progress: &dyn Fn(&Progress),
    limits: Limits,
) -> Exchanged {
    let mut tol = tol;
    let range = q.t[q.t.len() - 1] - q.t[0];
    let mut st = State::new(q);
    st.max_steps = limits.steps;
    let mut sweeps = 0;
    let mut violation;
    let mut converged = false;
    let mut kept: Option<Converged> = None;
    loop {
        st.resolve();
        st.release();
        // abscissae where the last sweep's additions (and the releases) changed the knots
        // (none: a full sweep)
        let mut changed = std::mem::take(&mut st.touched);
        let local = !changed.is_empty();
        let curve = st.cur.to_curve();
        let pieces = curve.coeffs.len();
        let (mut worst, mut candidates) = (f64::NEG_INFINITY, Vec::new());
        if !local {
            (worst, candidates) = sweep(q, &curve, 0..pieces, tol);
        } else {
            // local: the pieces within LOCAL knots of every change, merged into stretches
            changed.sort_by(f64::total_cmp);
            let mut stretches: Vec<(usize, usize)> = Vec::new();
            for x in &changed {
                let k = curve.breaks.partition_point(|b| b < x);
                let (a, b) = (k.saturating_sub(LOCAL), (k + LOCAL).min(pieces));
                match stretches.last_mut() {
                    Some(last) if a <= last.1 => last.1 = last.1.max(b),
                    _ => stretches.push((a, b)),
                }
            }
            for (a, b) in stretches {
                let (w, c) = sweep(q, &curve, a..b, tol);
                worst = worst.max(w);
                candidates.extend(c);
            }
            if candidates.is_empty() {
                // nothing near the changes: the full sweep decides
                continue;
            }
        }
        // The worst first; many in order of x instead, so that the split of the knots moves
        // forward only ([`State::seek`]).
        let in_order = candidates.len() > IN_ORDER;
        if in_order {
            candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
        } else {
            candidates.sort_by(|a, b| b.2.total_cmp(&a.2));
        }
        sweeps += 1;
        violation = worst.max(0.0);
        progress(&Progress::Sweep {
            sweep: sweeps,
            excursion: violation / vscale,
            contacts: st
                .kind
                .iter()
                .filter(|k| matches!(k, Knot::Active(_)))
                .count(),
        });
        if candidates.is_empty() {
            converged = !worst.is_nan();
            let gap = gap_of(&st.cur, &st.active(), violation);
            if converged && gap > GAP_TARGET && tol > TOL_FLOOR * vscale {
                tol = (tol * 1e-2).max(TOL_FLOOR * vscale);
                // (the moments are fresh: nothing was added since the resolve above)
                kept = Some(Converged {
                    spline: st.cur.clone(),
                    kind: st.kind.clone(),
                    violation,
                    gap,
                });
                converged = false;
                continue;
            }
            break;
        }
        if sweeps >= limits.sweeps || st.steps >= limits.steps {
            break;
        }
        let mut added = false;
        for (x, side, _) in candidates {
            if in_order {
                st.seek(x);
            }
            // not on a knot (a data site or an active point: there the excursion is rounding)
            let k = st.cur.x.partition_point(|u| *u < x);
            let near = |k: usize| k < st.cur.x.len() && (st.cur.x[k] - x).abs() <= 1e-12 * range;
            if near(k) || (k > 0 && near(k - 1)) {
                continue;
            }
            let f = st.cur.at(x).0;
            let by = match side {
                Side::Lower => q.bound_at(side, x) - f,
                Side::Upper => f - q.bound_at(side, x),
            };
            if by > tol {
                st.add(x, side);
                added = true;
            }
        }
        st.join();
        if !added {
            if local {
                // the full sweep decides
                continue;
            }
            // every candidate sits on a knot, or no longer leaves the strip by more than the
            // tolerance when its turn comes: the excursions are rounding
            converged = violation <= 1e2 * tol;
            break;
        }
    }
    st.resolve();
    let mut gap = gap_of(&st.cur, &st.active(), violation);
    if let Some(c) = kept.filter(|c| !converged || c.gap < gap) {
        // the tighter tolerance ran out of sweeps or steps, or did worse: the last converged
        // iterate (its moments as they were solved)
        (st.cur, st.kind, violation, gap, converged) = (c.spline, c.kind, c.violation, c.gap, true);
    }
    let active = st.active();
    Exchanged {
        gap,
        active,
        violation,
        converged,
        sweeps,
        steps: st.steps,
        solves: st.solves,
        spline: st.cur,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jittered noisy sites in a channel ±0.02 (as `cargo xtask bench strip`'s hard table).
    fn noisy_channel(n: usize) -> Problem {
        let mut s: u64 = 0x2545_F491_4F6C_DD1D;
        let mut unif = move || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut t = vec![0.0];
        for _ in 1..n {
            let last = t[t.len() - 1];
            t.push(last + 0.2 + unif());
        }
        let y: Vec<f64> = t.iter().map(|x| (0.7 * x).sin() + 0.3 * unif()).collect();
        let line =
            |off: f64| Bound::Polyline(t.iter().zip(&y).map(|(&t, &y)| [t, y + off]).collect());
        Problem {
            lower: line(-0.02),
            upper: line(0.02),
            t: t.clone(),
            y: y.clone(),
            end_slopes: [None, None],
        }
    }

    /// When the sweeps with a tightened tolerance run out (here of sweeps: the limit is the
    /// second sweep after the first convergence), the answer is the converged iterate before them —
    /// its excursion and contacts as that sweep reported them, converged — not the half-done
    /// iterate the limit stopped, which was once returned as converged with its excursion (at
    /// n = 10⁵ the step limit did this, and the solve was refused with a gap of 4e-8).
    #[test]
    fn a_tightening_cut_short_returns_the_converged_iterate() {
        let q = noisy_channel(300);
        let events = std::cell::RefCell::new(Vec::new());
        let full = exchange(&q, EXCHANGE_TOL, 1.0, &|e| {
            if let Progress::Sweep {
                sweep,
                excursion,
                contacts,
            } = *e
            {
                events.borrow_mut().push((sweep, excursion, contacts));
            }
        });
        assert!(
            full.converged && full.gap <= GAP_TARGET,
            "gap {:e}",
            full.gap
        );
        let events = events.into_inner();
        let first = events
            .iter()
            .position(|e| e.1 <= EXCHANGE_TOL)
            .expect("a converged sweep");
        // (sweep + 1 sees the same curve with the tighter tolerance and adds; sweep + 2 is the
        // first after additions)
        assert!(first + 2 < events.len(), "no tightening: {events:?}");
        let (sweep, excursion, contacts) = events[first];
        assert_ne!(events[first + 2], events[first]);
        let limits = Limits {
            sweeps: sweep + 2,
            steps: usize::MAX,
        };
        let cut = exchange_within(&q, EXCHANGE_TOL, 1.0, &|_| {}, limits);
        assert!(cut.converged);
        assert_eq!(cut.violation.to_bits(), excursion.to_bits());
        assert_eq!(cut.active.len(), contacts);
        assert!(cut.gap > GAP_TARGET, "gap {:e}", cut.gap);
    }

    /// Dual steps on split knots ([`State::seek`]) against the same steps on whole vectors: the
    /// same knots, values, moments and kinds, bit for bit (every step reads only its window,
    /// which the split keeps whole). Clamped ends, so that a window cut short at a false end
    /// changes the bits (keeping 3 knots ahead instead of [`AHEAD`] fails it). A zigzag in a channel: every data interval dips through both
    /// bounds, several hundred candidates a sweep, and steps that remove active points.
    #[test]
    fn steps_on_split_knots_are_the_steps_on_whole_ones() {
        let n = 600;
        let t: Vec<f64> = (0..n)
            .map(|i| i as f64 + 0.3 * ((i * 7 % 11) as f64) / 11.0)
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let line =
            |off: f64| Bound::Polyline(t.iter().zip(&y).map(|(&t, &y)| [t, y + off]).collect());
        let q = Problem {
            t: t.clone(),
            y: y.clone(),
            lower: line(-0.05),
            upper: line(0.05),
            end_slopes: [Some(0.5), Some(-2.0)],
        };
        let (mut split, mut whole) = (State::new(&q), State::new(&q));
        let mut split_seen = 0;
        for _ in 0..3 {
            let curve = whole.cur.to_curve();
            let (_, mut candidates) = sweep(&q, &curve, 0..curve.coeffs.len(), 1e-12);
            assert!(
                candidates.len() > IN_ORDER,
                "{} candidates",
                candidates.len()
            );
            candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
            for (x, side, _) in candidates {
                split.seek(x);
                split_seen = split_seen.max(split.tail.x.len());
                split.add(x, side);
                whole.add(x, side);
            }
            split.join();
            assert!(split.tail.x.is_empty());
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&split.cur.x), bits(&whole.cur.x));
            assert_eq!(bits(&split.cur.v), bits(&whole.cur.v));
            assert_eq!(bits(&split.cur.m), bits(&whole.cur.m));
            assert_eq!(split.kind, whole.kind);
            assert_eq!(split.steps, whole.steps);
            split.resolve();
            whole.resolve();
        }
        assert!(
            split_seen > 500,
            "the knots were never split far: {split_seen}"
        );
    }

    /// The windowed response against the full solve it truncates, on knots whose spacing varies
    /// by ten orders of magnitude, with natural and clamped ends, at the ends and in the middle.
    #[test]
    fn windowed_response_is_the_full_one() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let knots = |h: &dyn Fn(usize) -> f64| {
            let mut x = vec![0.0];
            for i in 0..999 {
                x.push(x[x.len() - 1] + h(i));
            }
            x
        };
        let random: Vec<f64> = (0..999).map(|_| 10f64.powf(-10.0 * rnd())).collect();
        let sets = [
            knots(&|i| random[i]),
            // equal spacing: the slowest decay, 2 − √3 a knot
            knots(&|_| 1.0),
            // spacing shrinking a hundredfold a knot from knot 30 down to knot 0 (1e-60): there
            // the moments grow as 1/√h faster than the response decays, and a window cut short
            // among them is wrong by far more than rounding
            knots(&|i| 100f64.powi(i.min(30) as i32 - 30)),
        ];
        let (mut work, mut unit, mut out, mut full) =
            (Work::default(), Vec::new(), Vec::new(), Vec::new());
        let mut reaches = std::collections::BTreeSet::new();
        for x in &sets {
            let k = x.len();
            for ends in [[None, None], [Some(1.0), Some(-2.0)], [Some(3.0), None]] {
                for p in [
                    0,
                    1,
                    5,
                    31,
                    32,
                    33,
                    63,
                    64,
                    65,
                    470,
                    500,
                    k - 66,
                    k - 33,
                    k - 2,
                    k - 1,
                ] {
                    let homogeneous = ends.map(|e: Option<f64>| e.map(|_| 0.0));
                    let mut e = vec![0.0; k];
                    e[p] = 1.0;
                    moments(x, &e, homogeneous, &mut full, &mut work);
                    let (lo, hi) = response(x, p, ends, &mut unit, &mut out, &mut work);
                    reaches.insert((hi - p).max(p - lo));
                    let scale = full.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                    for (i, f) in full.iter().enumerate() {
                        let w = if (lo..=hi).contains(&i) {
                            out[i - lo]
                        } else {
                            0.0
                        };
                        assert!(
                            (w - f).abs() <= 1e-14 * scale,
                            "ends {ends:?}, p {p}, knot {i}: window {w:e}, full {f:e}"
                        );
                    }
                }
            }
        }
        // both windows were taken
        assert!(
            reaches.contains(&SHORT_REACH) && reaches.contains(&RESPONSE_REACH),
            "{reaches:?}"
        );
    }
}
