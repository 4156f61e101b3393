//! The answer solved again in the caller's frame, from the caller's own numbers.
//!
//! The solver works in the normalized frame ([`crate::frame`]), whose values (y − a) − b(t − t₀)
//! each round by ~ε|y|; over a span h that moves a slope by ε|y|/h, and on very short spans f''
//! with it. Measured on `xtask/sweeps/strip.py`'s seed 719, case 69 (5000 sites near t = 5·10⁵
//! with spans from 7.5e-9 to 28, values in [−1, 1]): the natural spline came back with f'' 54 %
//! of its size off at a span of 1e-7 and ∫f''² 6.7e-7 above its value in 60-digit arithmetic
//! (which scipy's `CubicSpline` on the same doubles matches to 12 digits), and the same sites in
//! a polyline band of 0.3 % of the range (10 contacts) 6.0e-7 above the spline through the same
//! points (ROBUSTNESS.md §4, item 46). Perturbing those values by one ulp moves the exact ∫f''² by
//! 1e-7 … 5e-6 of itself, so no frame that rounds the values can give these answers.
//!
//! The answer is solved again through the same abscissae — the data, its touching points (f
//! equal to its bound there: the exchange's contacts, and Newton on Φ's tangencies and touching
//! pairs, where f' meets the bound's slope too) and its subarcs' ends (below) — with the
//! caller's values: the data as given, a contact's value its bound's at that abscissa,
//! computed in the caller's frame with the error of its rounding ([`crate::compensated`]). The
//! slopes of the moment system are formed with the roundings of their differences, of their
//! quotient and of the contacts' values ([`Spline::through_exactly`]), so its right-hand sides
//! keep the accuracy of their own size even where the slopes nearly cancel, and the system is
//! diagonally dominant (condition ≤ 3): the moments are those of the caller's doubles and its
//! bounds' exact values, to rounding. (Without the compensation, on `strip.py` seed 1, sites near
//! 10⁶ with values 1e7 and slopes 3e4 lost four digits of their moments, ∫f''² 4.7e-13 of
//! itself off; a contact's value rounded to ε|g| moved f'' by 1.1e-9 of its size at a break 1e-8
//! from the next, `tests/offset.rs`.) Where that spline fails a test below, the spline through
//! the contacts' values rounded to doubles is tried next: a contact whose multiplier is at
//! rounding can change sign between the two (on `strip.py` seeds 3 and 727, by 4e-7 and 1.7e-7
//! of the largest |f'''|, on data where one ulp of the contacts' values moves f'' by 1e-7 of its
//! size). Either replaces the solver's answer only when
//! - its slopes join to their rounding ([`SLOPE_ROUNDING`]) and every number is finite (moments
//!   that underflow, values 1e-268 on spans of 1e34, leave a polygon that is no spline; on spans
//!   of 1e-79 f''² overflows);
//! - f'' joins the bound's at every subarc's end to its rounding (the test every answer of Newton
//!   on Φ passes, [`crate::C2_ROUNDING`]) and that of the abscissa ([`ABSCISSA_ROUNDING`];
//!   between them it joins by construction);
//! - every contact's f''' jump, its multiplier, has the sign of its side (up at a lower contact,
//!   down at an upper one; [`SIGN_TOLERANCE`] of the largest |f'''|): with the two tests above,
//!   these are the strip problem's optimality conditions (f in C², a multiplier of its side's
//!   sign on the contact set: point masses at the touching points and the subarcs' ends, none
//!   inside a subarc, where f'''' = g'''' = 0); with no contact, the natural or clamped spline
//!   (Holladay);
//! - it keeps to the strip by the test every answer passes ([`crate::solve()`]), and its gap — the
//!   exchange's estimate 2 Σ |jump| × excursion over ∫f''² — is at most the exchange's acceptance.
//!
//! Newton on Φ's answers have abscissae of their own, which its solver meets only to its
//! tolerance in the normalized frame: a tangency, where f' meets the bound's slope, and a
//! subarc's ends, where f leaves a cubic piece of its bound with f'' equal to the bound's. Each
//! is placed again ([`Breaks::place`]): Newton's method on those conditions, each abscissa on its
//! bound, within [`PLACE_REACH`] of the spans beside it. Between two subarcs the answer is the
//! spline through its points, clamped to the bound's slope at the subarcs' ends (so the
//! segments are independent, and each is placed alone); on a subarc it is the bound's own cubic.
//! Where an abscissa is within an ulp of its condition, nothing moves (the energy is stationary
//! in a tangency's abscissa, and moves to second order only). Measured: `tests/offset.rs`'s
//! clustered sites in bands of constant pieces (one and two tangencies) came back 1.3e-11 and
//! 1.5e-11 of ∫f''² above the spline through the same points, f'' 1.6e-8 and 8.4e-9 of its size
//! off; formed again, ∫f''² to the last bit and f'' to 2.2e-16 of its size. The same file's
//! 40 even sites near 5·10⁵ under a bound 1e-6 below their chords (17 subarcs) came back
//! 2.3e-11 of ∫f''² and f'' 2.5e-8 of its size off the construction above in exact rationals;
//! formed again, 1.6e-16 and 4.3e-16.

use crate::check::worst_violation;
use crate::linalg::solve_dense;
use crate::piece::{cubic3, shift};
use crate::spline::Spline;
use crate::strategy::ACCEPT_GAP;
use crate::types::{KnotKind, Problem, Side, Solution, C2_ROUNDING};
use banded::TridiagonalLu;

/// A spline's slopes join to this many ε times the size of the terms they are formed from.
const SLOPE_ROUNDING: f64 = 64.0;

/// f'' at a subarc's end may move by |f'''| times this many ε of the break's abscissa (the
/// rounding of the solver's abscissa).
const ABSCISSA_ROUNDING: f64 = 4.0;

/// A contact's f''' jump may have the wrong sign by this fraction of the largest |f'''|.
const SIGN_TOLERANCE: f64 = 1e-9;

/// `sol` solved again in the caller's frame (module docs), or `None` where its breaks are not
/// the sites and its contacts (a subarc's ends adjacent, on a cubic piece; no data moved by
/// Remark 4.2), an abscissa cannot be placed, or the new answer fails a test. `exchange`:
/// whether the exchange produced `sol` (it reports no gradient, and its contacts are not
/// tangencies); `tolerance`: the strip's, as [`crate::solve()`]
/// applies it. The answer carries its [`Solution::violation`], from the same exact test.
pub(crate) fn in_callers_frame(
    problem: &Problem,
    sol: &Solution,
    exchange: bool,
    tolerance: f64,
) -> Option<Solution> {
    if !sol.shifted_data.is_empty() || !sol.uncertified.is_empty() {
        return None;
    }
    let (t, n) = (&problem.t, problem.t.len());
    // The values at the breaks; where each data site is among them; the contacts' breaks.
    let mut values = Vec::with_capacity(sol.breaks.len());
    let mut low = vec![0.0; sol.breaks.len()];
    let mut at_site = Vec::with_capacity(n);
    let mut contacts = Vec::with_capacity(sol.extra_knots.len());
    let (mut subarcs, mut touches) = (Vec::new(), Vec::new());
    // (a subarc's start whose end has not come yet: nothing may lie between them)
    let mut open: Option<(usize, Side)> = None;
    let mut extra = sol.extra_knots.iter().peekable();
    for (j, &b) in sol.breaks.iter().enumerate() {
        let site = at_site.len();
        if open.is_none() && site < n && t[site].to_bits() == b.to_bits() {
            values.push(problem.y[site]);
            at_site.push(j);
        } else if let Some(k) = extra.next_if(|k| k.t.to_bits() == b.to_bits()) {
            let side = match (k.kind, open) {
                (KnotKind::Touch(side), None) => {
                    touches.push((j, side));
                    side
                }
                (KnotKind::SubarcStart(side), None) => {
                    open = Some((j, side));
                    side
                }
                (KnotKind::SubarcEnd(side), Some(start)) if start == (j - 1, side) => {
                    subarcs.push(start);
                    open = None;
                    side
                }
                _ => return None,
            };
            // (a subarc lies on a cubic piece: Newton on Φ's bounds)
            if open.is_some() && problem.bound_piece(side, b).is_none() {
                return None;
            }
            let (value, error) = problem.bound_at_compensated(side, b);
            values.push(value);
            low[j] = error;
            contacts.push((j, side));
        } else {
            return None;
        }
    }
    if at_site.len() != n || extra.next().is_some() || open.is_some() {
        return None;
    }
    let points = Points {
        values,
        at_site,
        contacts,
        touches,
        subarcs,
    };
    let through = |low: &[f64]| formed(problem, sol, exchange, tolerance, &points, low);
    // Through the bounds' exact values first; where that fails a test, through their doubles
    // (the module docs: a contact whose multiplier is at rounding can change sign between them).
    through(&low).or_else(|| {
        let rounded = vec![0.0; low.len()];
        low.iter()
            .any(|&l| l != 0.0)
            .then(|| through(&rounded))
            .flatten()
    })
}

/// The points an answer is formed through: the values at its breaks (the data at a site, a
/// contact's bound value rounded to a double), where each data site is among them, the
/// contacts' breaks with their sides (touching points and subarcs' ends), and the first break of
/// each subarc (its end is the next).
struct Points {
    values: Vec<f64>,
    at_site: Vec<usize>,
    contacts: Vec<(usize, Side)>,
    touches: Vec<(usize, Side)>,
    subarcs: Vec<(usize, Side)>,
}

/// An answer's pieces as they are formed: each piece's coefficients and f'' at its two ends,
/// and ∫f''².
#[derive(Default)]
struct Pieces {
    coefficients: Vec<[f64; 4]>,
    second: Vec<[f64; 2]>,
    energy: f64,
}

impl Pieces {
    /// The spline through breaks `from ..= to` ([`Spline::through_exactly`]) with the given end
    /// slopes.
    fn spline(&mut self, at: &Breaks, (from, to): (usize, usize), ends: [Option<f64>; 2]) {
        let spline = Spline::through_exactly(
            at.x[from..=to].to_vec(),
            at.v[from..=to].to_vec(),
            &at.low[from..=to],
            ends,
        );
        self.energy += spline.energy();
        self.coefficients.extend(spline.to_curve().coeffs);
        self.second
            .extend(spline.m.windows(2).map(|m| [m[0], m[1]]));
    }

    /// The bound's cubic `g` (about the piece's start) on a subarc of length h, with f'' = `end`
    /// at its end.
    fn subarc(&mut self, g: [f64; 4], h: f64, end: f64) {
        let start = 2.0 * g[2];
        self.energy += h / 3.0 * (start * start + start * end + end * end);
        self.coefficients.push(g);
        self.second.push([start, end]);
    }
}

/// The abscissae of an answer's breaks, with the values there (`v` plus the low parts `low`).
struct Breaks {
    x: Vec<f64>,
    v: Vec<f64>,
    low: Vec<f64>,
}

/// A spline between two subarcs (or a curve's end): its first and last break, each with the
/// side of the subarc that ends or starts there (`None` at a curve's end).
struct Segment {
    from: (usize, Option<Side>),
    to: (usize, Option<Side>),
}

/// Newton steps that place a segment's free abscissae ([`Breaks::place`]).
const PLACE_STEPS: usize = 4;

/// A free abscissa moves at most this fraction of the spans beside it (the solver's abscissa is
/// off by its tolerance, not by a fraction of a span; measured moves reach 4e-11 of the
/// abscissa).
const PLACE_REACH: f64 = 1e-6;

/// Up to this many free abscissae in a segment, its Jacobian is taken whole ([`Breaks::place`]).
const DENSE_PLACE: usize = 8;

/// Beyond [`DENSE_PLACE`], every this-many-th abscissa moves at a time for the tridiagonal
/// Jacobian's differences (what the others feel of it decays like 0.27⁵ or faster).
const COLOURS: usize = 5;

/// An abscissa that Newton on Φ's answer leaves to its solver's tolerance, placed again
/// ([`Breaks::place`]): break `j` on the bound of `side`, where f'' joins the bound's (a
/// subarc's end: `second`) or f' meets the bound's (a tangency).
#[derive(Clone, Copy, Debug)]
struct Free {
    j: usize,
    side: Side,
    second: bool,
}

impl Breaks {
    /// The bound of `side` at x: g, g', g'' (where it is a cubic piece).
    fn bound(problem: &Problem, side: Side, x: f64) -> Option<(f64, f64, f64)> {
        let (g, t0) = problem.bound_piece(side, x)?;
        Some(cubic3(&g, x - t0))
    }

    /// The slopes a segment is clamped to: its bound's at a subarc's end, the given end slope at
    /// the curve's.
    fn ends(&self, problem: &Problem, s: &Segment) -> Option<[Option<f64>; 2]> {
        let slope = |(j, side): (usize, Option<Side>), given: Option<f64>| match side {
            Some(side) => Some(Some(Self::bound(problem, side, self.x[j])?.1)),
            None => Some(given),
        };
        Some([
            slope(s.from, problem.end_slopes[0])?,
            slope(s.to, problem.end_slopes[1])?,
        ])
    }

    /// Break j at x on the bound of `side` (its value and the error of its rounding).
    fn set(&mut self, problem: &Problem, (j, side): (usize, Side), x: f64) {
        let (value, error) = problem.bound_at_compensated(side, x);
        (self.x[j], self.v[j], self.low[j]) = (x, value, error);
    }

    /// Each free abscissa's condition as it stands in segment `s`'s spline: f'' less its
    /// bound's at a subarc's end, f' less its bound's at a tangency.
    fn mismatch(&self, problem: &Problem, s: &Segment, free: &[Free]) -> Option<Vec<f64>> {
        let (from, to) = (s.from.0, s.to.0);
        let spline = Spline::through_exactly(
            self.x[from..=to].to_vec(),
            self.v[from..=to].to_vec(),
            &self.low[from..=to],
            self.ends(problem, s)?,
        );
        // (only the pieces the conditions read: the placement evaluates this many times)
        free.iter()
            .map(|f| {
                let (_, slope, second) = Self::bound(problem, f.side, self.x[f.j])?;
                Some(match f.second {
                    true => spline.m[f.j - from] - second,
                    false => spline.slope(f.j - from) - slope,
                })
            })
            .collect()
    }

    /// Places segment `s`'s free abscissae (in order; the segments are independent: each free
    /// abscissa lies in one, and its spline depends on its own breaks only) where their
    /// conditions hold — the optimum's, which the solver's abscissae meet only to its own
    /// tolerance: Newton's method on [`Breaks::mismatch`], each abscissa on its bound, with a
    /// Jacobian by differences — whole up to [`DENSE_PLACE`] abscissae, tridiagonal beyond (every
    /// [`COLOURS`]-th abscissa moved at a time); at most [`PLACE_STEPS`] steps, each abscissa
    /// within [`PLACE_REACH`] of the spans beside it and the breaks in order (else `None`). The
    /// steps end where none moves an abscissa by a unit in its last place: a condition can then
    /// be off by what one such unit of its own abscissa, or of a neighbour's, moves it (on
    /// `strip.py` seed 727, case 88, a subarc's end is 3400 units of its own from its condition
    /// but within one of the tangency beside it; the test of f'' there then refuses the answer,
    /// and the solver's stands).
    fn place(&mut self, problem: &Problem, s: &Segment, free: &[Free]) -> Option<()> {
        let m = free.len();
        if m == 0 {
            return Some(());
        }
        let origin: Vec<f64> = free.iter().map(|f| self.x[f.j]).collect();
        let limit: Vec<f64> = free
            .iter()
            .map(|f| {
                let (l, r) = (self.x[f.j] - self.x[f.j - 1], self.x[f.j + 1] - self.x[f.j]);
                PLACE_REACH * l.min(r)
            })
            .collect();
        // each difference's step: a thousandth of the reach, or 16 units in the last place of
        // the abscissa where that is larger (as the step is, exactly, in doubles)
        let delta: Vec<f64> = free
            .iter()
            .zip(&limit)
            .map(|(f, &l)| {
                let x = self.x[f.j];
                (x + (1e-3 * l).max(16.0 * f64::EPSILON * x.abs())) - x
            })
            .collect();
        let mut r = self.mismatch(problem, s, free)?;
        // the Jacobian: whole when there are few abscissae (a short segment's ends and the
        // tangencies between them can all be coupled); else tridiagonal, from differences with
        // every `stride`-th abscissa moved at a time (a condition depends on abscissae beyond its
        // neighbours only through the moments' decay, ~0.27 a break)
        let dense = m <= DENSE_PLACE;
        let (stride, width) = if dense { (m, m) } else { (COLOURS, 3) };
        let mut jac = vec![0.0; m * width];
        for _ in 0..PLACE_STEPS {
            for colour in 0..stride {
                let moved: Vec<usize> = (colour..m).step_by(stride).collect();
                let at: Vec<f64> = moved.iter().map(|&i| self.x[free[i].j]).collect();
                for (&i, &x) in moved.iter().zip(&at) {
                    self.set(problem, (free[i].j, free[i].side), x + delta[i]);
                }
                let after = self.mismatch(problem, s, free);
                for (&i, &x) in moved.iter().zip(&at) {
                    self.set(problem, (free[i].j, free[i].side), x);
                }
                let after = after?;
                for &i in &moved {
                    let rows = if dense {
                        0..m
                    } else {
                        i.saturating_sub(1)..(i + 2).min(m)
                    };
                    for row in rows {
                        // column i of `row`; tridiagonal rows are [sub, diagonal, super]
                        let column = if dense { i } else { i + 1 - row };
                        jac[row * width + column] = (after[row] - r[row]) / delta[i];
                    }
                }
            }
            // (solved in place: the step's right-hand side is the mismatch, measured again below)
            let mut step = std::mem::take(&mut r);
            if dense {
                // (the elimination overwrites `jac`: the next step measures all of it again)
                solve_dense(&mut jac, &mut step, m)?;
            } else {
                let lu = TridiagonalLu::factor(jac.as_chunks::<3>().0).ok()?;
                lu.solve_in_place(&mut step, 1).ok()?;
            }
            let mut moved = false;
            for (i, f) in free.iter().enumerate() {
                let x = self.x[f.j] - step[i];
                if !x.is_finite() || (x - origin[i]).abs() > limit[i] {
                    return None;
                }
                moved |= x.to_bits() != self.x[f.j].to_bits();
                self.set(problem, (f.j, f.side), x);
            }
            if !(s.from.0..s.to.0).all(|j| self.x[j] < self.x[j + 1])
                || free
                    .iter()
                    .any(|f| self.x[f.j - 1] >= self.x[f.j] || self.x[f.j] >= self.x[f.j + 1])
            {
                return None;
            }
            if !moved {
                break;
            }
            r = self.mismatch(problem, s, free)?;
        }
        Some(())
    }
}

/// The spline through `points` (their values plus the low parts `low`) as an answer in place of
/// `sol`, or `None` where it fails a test ([`in_callers_frame`]).
fn formed(
    problem: &Problem,
    sol: &Solution,
    exchange: bool,
    tolerance: f64,
    points: &Points,
    low: &[f64],
) -> Option<Solution> {
    let (t, n) = (&problem.t, problem.t.len());
    let (at_site, contacts) = (&points.at_site, &points.contacts);
    let k = sol.breaks.len();
    // The segments between the subarcs: each a spline clamped to its bound's slope at a
    // subarc's end (to the given end slopes at the curve's ends), whose ends are placed first.
    let mut segments = Vec::with_capacity(points.subarcs.len() + 1);
    let mut from = (0, None);
    for &(j, side) in &points.subarcs {
        segments.push(Segment {
            from,
            to: (j, Some(side)),
        });
        from = (j + 1, Some(side));
    }
    segments.push(Segment {
        from,
        to: (k - 1, None),
    });
    let mut at = Breaks {
        x: sol.breaks.clone(),
        v: points.values.clone(),
        low: low.to_vec(),
    };
    // Newton on Φ's abscissae placed: its subarcs' ends, and its tangencies (the exchange's
    // contacts are its polylines' points, not tangencies)
    for segment in &segments {
        let (from, to) = (segment.from.0, segment.to.0);
        let touches = &points.touches;
        let inside = match exchange {
            true => &[][..],
            false => {
                &touches[touches.partition_point(|c| c.0 <= from)
                    ..touches.partition_point(|c| c.0 < to)]
            }
        };
        let free: Vec<Free> = (segment.from.1.map(|side| (from, side, true)).into_iter())
            .chain(inside.iter().map(|&(j, side)| (j, side, false)))
            .chain(segment.to.1.map(|side| (to, side, true)))
            .map(|(j, side, second)| Free { j, side, second })
            .collect();
        at.place(problem, segment, &free)?;
    }
    // The segments' splines and the bound's own cubic on each subarc.
    let mut pieces = Pieces::default();
    for (i, segment) in segments.iter().enumerate() {
        let ends = at.ends(problem, segment)?;
        pieces.spline(&at, (segment.from.0, segment.to.0), ends);
        if let Some(&(j, side)) = points.subarcs.get(i) {
            let (g, t0) = problem.bound_piece(side, at.x[j])?;
            let second = cubic3(&g, at.x[j + 1] - t0).2;
            pieces.subarc(shift(&g, at.x[j] - t0), at.x[j + 1] - at.x[j], second);
        }
    }
    let (x, v) = (&at.x, &at.v);
    let Pieces {
        coefficients,
        second: m,
        energy,
    } = pieces;
    if !energy.is_finite() || !coefficients.iter().flatten().all(|c| c.is_finite()) {
        return None;
    }
    let h = |i: usize| x[i + 1] - x[i];
    // the size of the terms piece i's slope is formed from
    let slope_size =
        |i: usize| ((v[i + 1] - v[i]) / h(i)).abs() + h(i) * (m[i][0].abs() + m[i][1].abs());
    // the slopes join (and meet the given end slopes) to their rounding
    for i in 0..k {
        let left = match i {
            0 => problem.end_slopes[0],
            _ => Some(cubic3(&coefficients[i - 1], x[i] - x[i - 1]).1),
        };
        let right = if i + 1 == k {
            problem.end_slopes[1]
        } else {
            Some(coefficients[i][1])
        };
        let size = if i > 0 { slope_size(i - 1) } else { 0.0 }
            + if i + 1 < k { slope_size(i) } else { 0.0 };
        if let (Some(l), Some(r)) = (left, right) {
            let by = (l - r).abs();
            if by.is_nan() || by > SLOPE_ROUNDING * f64::EPSILON * size {
                return None;
            }
        }
    }
    let third = |i: usize| (m[i][1] - m[i][0]) / h(i);
    let f3max = (0..k - 1).fold(0.0f64, |a, j| a.max(third(j).abs()));
    // f'' joins at a subarc's ends (within a spline it joins by construction) to its rounding,
    // as every answer of Newton's does (`C2_ROUNDING`: R of a piece from its Hermite data), and
    // to that of the break's abscissa
    let f2max = m.iter().flatten().fold(0.0f64, |a, s| a.max(s.abs()));
    let hermite = |i: usize| {
        let (s0, s1) = (
            coefficients[i][1].abs(),
            cubic3(&coefficients[i], h(i)).1.abs(),
        );
        (6.0 * (v[i].abs() + v[i + 1].abs()) / h(i) + 4.0 * s0.max(s1) + 2.0 * s0.min(s1)) / h(i)
    };
    for &(j, _) in &points.subarcs {
        for i in [j, j + 1] {
            let by = (m[i - 1][1] - m[i][0]).abs();
            let abscissa = x[i].abs() * (third(i - 1).abs() + third(i).abs());
            let rounding = C2_ROUNDING * (f2max + hermite(i - 1) + hermite(i))
                + ABSCISSA_ROUNDING * f64::EPSILON * abscissa;
            if by.is_nan() || by > rounding {
                return None;
            }
        }
    }
    // each contact's multiplier, the f''' jump, on its side's sign
    let mut jumps = 0.0;
    for &(j, side) in contacts {
        let jump = third(j) - third(j - 1);
        let wrong = match side {
            Side::Lower => -jump,
            Side::Upper => jump,
        };
        if wrong > SIGN_TOLERANCE * f3max {
            return None;
        }
        jumps += jump.abs();
    }
    let last = coefficients[k - 2];
    let mut slopes: Vec<f64> = at_site
        .iter()
        .map(|&j| match coefficients.get(j) {
            Some(c) => c[1],
            None => cubic3(&last, x[k - 1] - x[k - 2]).1,
        })
        .collect();
    for (side, end) in [0, n - 1].into_iter().enumerate() {
        if let Some(s) = problem.end_slopes[side] {
            slopes[end] = s;
        }
    }
    // ∂Φ/∂z_i = 2(f''(t_i−) − f''(t_i+)) at the sites whose slope is free: the moments' rounding
    // (0 for the exchange's answers, as it reports them)
    let second = |j: usize, s: f64| cubic3(&coefficients[j], s).2;
    let gradient_norm = if exchange {
        0.0
    } else {
        (0..n)
            .filter(|&i| !(i == 0 && problem.end_slopes[0].is_some()))
            .filter(|&i| !(i == n - 1 && problem.end_slopes[1].is_some()))
            .map(|i| {
                let j = at_site[i];
                let left = if j > 0 {
                    second(j - 1, x[j] - x[j - 1])
                } else {
                    0.0
                };
                let right = if j + 1 < k { second(j, 0.0) } else { 0.0 };
                let g = 2.0 * (left - right);
                g * g
            })
            .sum::<f64>()
            .sqrt()
    };
    // (the subarcs' ends where they were placed)
    let mut extra_knots = sol.extra_knots.clone();
    for (knot, &(j, _)) in extra_knots.iter_mut().zip(contacts) {
        knot.t = x[j];
    }
    let mut out = Solution {
        breaks: x.clone(),
        extra_knots,
        coefficients,
        slopes,
        grid: t.clone(),
        grid_values: problem.y.clone(),
        energy,
        norm: energy.sqrt(),
        gradient_norm,
        newton_decrement: 0.0,
        gap: 0.0,
        ..sol.clone()
    };
    // (the strip's test, made here once: the caller takes `violation` from it)
    out.violation = match worst_violation(problem, &out) {
        Some((by, _, _)) if by.is_nan() || by > tolerance => return None,
        Some((by, _, _)) => by,
        None => 0.0,
    };
    out.newton_decrement = 2.0 * jumps * out.violation.max(0.0);
    out.gap = if energy > 0.0 {
        out.newton_decrement / energy
    } else {
        0.0
    };
    (out.gap <= ACCEPT_GAP).then_some(out)
}
