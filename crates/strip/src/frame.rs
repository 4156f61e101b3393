//! The normalized frame in which [`crate::solve()`] works (ROBUSTNESS.md, finding 7).
//!
//! The strip problem is exactly equivariant: f solves (t, y, e, d) if and only if
//! t ↦ ℓ(t) + c·f((t − t₀)/λ) solves the problem with sites t₀ + λt, values ℓ + c·y and bounds
//! ℓ + c·e, ℓ + c·d for every line ℓ, c > 0 and λ > 0, and ∫f''² scales by c²/λ³. The solver's
//! stopping and feasibility tests are therefore applied to a normalized problem: sites shifted to
//! start at 0 and divided by λ (the power of two at or below the site range), the line ℓ through
//! the first and the last data point subtracted from values, bounds and end slopes, and values
//! divided by c (the power of two at or below the value scale V). Powers of two make the scalings
//! exact; only the subtraction of ℓ rounds (at the level of the input's own rounding).
//!
//! The value scale V is the largest of
//! * max |y_i − ℓ(t_i)| (how far the data are from the line),
//! * (t_n − t_1)·max |s − ℓ'| over prescribed end slopes s,
//! * max(e − ℓ, ℓ − d, 0) at the ends of every bound piece and at polyline vertices (how far the
//!   bounds force f away from the line);
//!
//! when all three vanish (data on a line that the strip contains at every site), the largest
//! distance |e − ℓ|, |d − ℓ| at those points, and 1 when there are no bounds either (the answer is
//! then ℓ itself). Every tolerance of the solver is relative to V (values), the site range
//! (sites) and the derived scales, so the answer is the same for every equivalent problem up to
//! rounding.

use crate::error::{bound_field, Error, BADLY_SCALED};
use crate::types::{polyline_at, Bound, Problem, Side, MAX_MAGNITUDE};

/// The change of frame t = t₀ + λ·u, value = ℓ(t) + c·ṽ with ℓ(t) = a + b·(t − t₀).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    /// First site.
    pub t0: f64,
    /// Site scale (a power of two).
    pub lam: f64,
    /// ℓ(t₀) = y₁.
    pub a: f64,
    /// Slope of ℓ.
    pub b: f64,
    /// Value scale used for the division (a power of two, V/2 < c ≤ V).
    pub c: f64,
    /// The value scale V.
    pub scale: f64,
    /// Magnitude of the values in the caller's frame (max |y_i| + |b|·(t_n − t_1) + V): the
    /// rounding of the returned coefficients is relative to it.
    pub magnitude: f64,
}

/// The largest power of two ≤ x (x > 0 finite), from the bits (exact, subnormals included).
fn pow2_at_or_below(x: f64) -> f64 {
    let bits = x.to_bits();
    if x >= f64::MIN_POSITIVE {
        f64::from_bits(bits & 0xFFF0_0000_0000_0000)
    } else {
        let m = bits & 0x000F_FFFF_FFFF_FFFF;
        f64::from_bits(1u64 << (63 - m.leading_zeros()))
    }
}

/// Value of a cubic piece c0 + c1 s + c2 s² + c3 s³.
fn cubic(c: &[f64; 4], s: f64) -> f64 {
    c[0] + s * (c[1] + s * (c[2] + s * c[3]))
}

/// (t, bound value) at the ends of every piece and at every polyline vertex inside the range.
fn bound_points(b: &Bound, t: &[f64]) -> Vec<(f64, f64)> {
    let n = t.len();
    match b {
        Bound::None => Vec::new(),
        Bound::Pieces(p) => p
            .iter()
            .enumerate()
            .flat_map(|(i, c)| [(t[i], c[0]), (t[i + 1], cubic(c, t[i + 1] - t[i]))])
            .collect(),
        Bound::Polyline(v) => {
            let mut out: Vec<(f64, f64)> = v
                .iter()
                .filter(|p| p[0] >= t[0] && p[0] <= t[n - 1])
                .map(|p| (p[0], p[1]))
                .collect();
            for &x in [t[0], t[n - 1]].iter() {
                out.push((x, polyline_at(v, x)));
            }
            out
        }
    }
}

/// The error for `field[index]` when its normalized value overflows.
pub(crate) fn scaled(field: &'static str, index: usize) -> Error {
    Error::InvalidValue {
        field,
        index,
        reason: BADLY_SCALED,
    }
}

impl Frame {
    /// y − ℓ(t), as (y − a) − b·(t − t₀): the offset a common to the values (y − a is exact for
    /// y within a factor two of a, Sterbenz) is taken out before anything rounds, so the result
    /// errs by a rounding of the deviations, not of the offset. Computed as y − ℓ(t) it erred
    /// by ulp(a): on 5000 clustered sites (spans 2e-4) with values 1e5 ± 0.1 (`strip.py` sweep,
    /// seed 5, case 115) the natural spline then came back with ∫f''² 1.5e-9 above its value
    /// (extended precision), f'' off by ~1e-4 of its size.
    pub fn above(&self, t: f64, y: f64) -> f64 {
        (y - self.a) - self.b * (t - self.t0)
    }

    /// The frame of a validated problem.
    pub fn of(p: &Problem) -> Result<Frame, Error> {
        let n = p.t.len();
        let t0 = p.t[0];
        let range = p.t[n - 1] - t0;
        if !(range.is_finite() && range > 0.0) {
            return Err(scaled("t", n - 1));
        }
        let a = p.y[0];
        let b = (p.y[n - 1] - p.y[0]) / range;
        if !b.is_finite() {
            return Err(scaled("y", n - 1));
        }
        let mut frame = Frame {
            t0,
            lam: pow2_at_or_below(range),
            a,
            b,
            c: 1.0,
            scale: 1.0,
            magnitude: 0.0,
        };
        let l = |t: f64, y: f64| frame.above(t, y);
        // deviations within the rounding of y − ℓ(t) are none: data on a line (two points, say)
        // must not get a value scale of 1e-16 (its bounds then normalize to 1e16); others count
        // in full (subtracting the rounding from every deviation moved V = 1 to just below it,
        // halved c, and Newton on a hair-thin cell then stalled where it had converged)
        let data = p.t.iter().zip(&p.y).fold(0.0f64, |m, (t, y)| {
            let rounding = 8.0 * f64::EPSILON * (y.abs() + a.abs() + (b * (t - t0)).abs());
            let d = l(*t, *y).abs();
            m.max(if d <= rounding { 0.0 } else { d })
        });
        let slopes = p
            .end_slopes
            .iter()
            .flatten()
            .fold(0.0f64, |m, s| m.max(range * (s - b).abs()));
        let lower = bound_points(&p.lower, &p.t);
        let upper = bound_points(&p.upper, &p.t);
        let forcing = lower
            .iter()
            .map(|(t, e)| l(*t, *e))
            .chain(upper.iter().map(|(t, d)| -l(*t, *d)))
            .fold(0.0f64, f64::max);
        let mut v = data.max(slopes).max(forcing);
        if !v.is_finite() {
            return Err(frame.blame(p));
        }
        if v <= 0.0 {
            v = lower
                .iter()
                .chain(&upper)
                .fold(0.0f64, |m, (t, g)| m.max(l(*t, *g).abs()));
        }
        if !v.is_finite() {
            return Err(frame.blame(p));
        }
        if v <= 0.0 {
            v = 1.0;
        }
        frame.scale = v;
        frame.c = pow2_at_or_below(v);
        frame.magnitude = p.y.iter().fold(0.0f64, |m, y| m.max(y.abs())) + b.abs() * range + v;
        if !frame.magnitude.is_finite() {
            return Err(scaled("y", 0));
        }
        Ok(frame)
    }

    /// The first input number whose distance from the line ℓ overflows (for the error).
    fn blame(&self, p: &Problem) -> Error {
        if let Some(i) = (0..p.t.len()).find(|&i| !self.above(p.t[i], p.y[i]).is_finite()) {
            return scaled("y", i);
        }
        let range = p.t[p.t.len() - 1] - p.t[0];
        if let Some(k) =
            (0..2).find(|&k| p.end_slopes[k].is_some_and(|s| !(range * (s - self.b)).is_finite()))
        {
            return scaled("end_slopes", k);
        }
        for (side, b) in [(Side::Lower, &p.lower), (Side::Upper, &p.upper)] {
            let index = match b {
                Bound::None => None,
                Bound::Pieces(pc) => (0..pc.len()).find(|&i| {
                    !self.above(p.t[i], pc[i][0]).is_finite()
                        || !self
                            .above(p.t[i + 1], cubic(&pc[i], p.t[i + 1] - p.t[i]))
                            .is_finite()
                }),
                Bound::Polyline(v) => v.iter().position(|q| !self.above(q[0], q[1]).is_finite()),
            };
            if let Some(index) = index {
                return scaled(bound_field(b, side), index);
            }
        }
        scaled("y", 0)
    }

    /// The normalized problem. Errors: `InvalidValue` (badly scaled) when a normalized number is not finite or
    /// exceeds [`MAX_MAGNITUDE`] (bounds enormous compared with V), `NonIncreasing`
    /// when two abscissae closer than the rounding of t − t₁ merge.
    pub fn forward(&self, p: &Problem) -> Result<Problem, Error> {
        let (lam, c) = (self.lam, self.c);
        let u = |t: f64| (t - self.t0) / lam;
        let v = |t: f64, y: f64| self.above(t, y) / c;
        let map_bound = |bd: &Bound| match bd {
            Bound::None => Bound::None,
            Bound::Pieces(pc) => Bound::Pieces(
                pc.iter()
                    .enumerate()
                    .map(|(i, k)| {
                        [
                            v(p.t[i], k[0]),
                            (k[1] - self.b) * lam / c,
                            k[2] * lam * lam / c,
                            k[3] * lam * lam * lam / c,
                        ]
                    })
                    .collect(),
            ),
            Bound::Polyline(pl) => {
                Bound::Polyline(pl.iter().map(|q| [u(q[0]), v(q[0], q[1])]).collect())
            }
        };
        let q = Problem {
            t: p.t.iter().map(|t| u(*t)).collect(),
            y: p.t.iter().zip(&p.y).map(|(t, y)| v(*t, *y)).collect(),
            lower: map_bound(&p.lower),
            upper: map_bound(&p.upper),
            end_slopes: p.end_slopes.map(|s| s.map(|s| (s - self.b) * lam / c)),
        };
        let ok = |x: &f64| x.is_finite() && x.abs() <= MAX_MAGNITUDE;
        let bad_bound = |bd: &Bound| match bd {
            Bound::None => None,
            Bound::Pieces(pc) => pc.iter().position(|x| !x.iter().all(ok)),
            Bound::Polyline(pl) => pl.iter().position(|x| !x.iter().all(ok)),
        };
        if let Some(i) = q.t.iter().position(|x| !ok(x)) {
            return Err(scaled("t", i));
        }
        if let Some(i) = q.y.iter().position(|x| !ok(x)) {
            return Err(scaled("y", i));
        }
        if let Some(k) = (0..2).find(|&k| q.end_slopes[k].is_some_and(|s| !ok(&s))) {
            return Err(scaled("end_slopes", k));
        }
        for (side, b, bq) in [
            (Side::Lower, &p.lower, &q.lower),
            (Side::Upper, &p.upper, &q.upper),
        ] {
            if let Some(i) = bad_bound(bq) {
                return Err(scaled(bound_field(b, side), i));
            }
        }
        Ok(q)
    }

    /// The caller's abscissa of a normalized one.
    pub fn time(&self, u: f64) -> f64 {
        self.t0 + self.lam * u
    }

    /// The caller's value at t of a normalized value.
    pub fn value(&self, t: f64, v: f64) -> f64 {
        // the deviations first, then the offset: one rounding at the offset's ulp, not two
        self.a + (self.b * (t - self.t0) + self.c * v)
    }

    /// The caller's slope of a normalized slope.
    pub fn slope(&self, z: f64) -> f64 {
        self.b + self.c * z / self.lam
    }

    /// ∫f''² in the caller's frame per unit of the normalized one: c²/λ³.
    pub fn energy_factor(&self) -> f64 {
        let r = self.c / self.lam;
        r * r / self.lam
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powers_of_two() {
        for x in [5e-324, 1e-310, 1e-300, 3e-9, 0.7, 1.0, 5.0, 1e8, 1.7e300] {
            let p = pow2_at_or_below(x);
            assert!(p <= x && 2.0 * p > x, "{x}: {p}");
            assert!((p.log2() - p.log2().round()).abs() < 1e-12);
        }
    }
}
