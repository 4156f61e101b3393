//! Exact checks of a solution, written independently of the solver's own checks.
//!
//! The strip is checked on every sub-interval between consecutive breaks of the solution and
//! vertices (or data sites, for cubic pieces) of the bound: there f − e (or d − f) is one cubic,
//! whose minimum is taken at an end or at a real root of its derivative (a quadratic, solved by
//! the cancellation-free formula). No sampling: a dip between two samples cannot hide.
//! Polyline vertices and solution breaks are merged in one pass, so the check is O(M + pieces).

use strip::{Bound, Problem, Solution};

/// The largest excursion of a solution outside the strip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Violation {
    /// By how much f leaves the strip (≤ 0: inside; NaN propagates).
    pub by: f64,
    /// Where.
    pub at: f64,
    /// Whether the upper bound (else the lower).
    pub upper: bool,
}

impl Violation {
    /// `Ok` when the strip is left by at most `tol` (NaN is not), else the message the tests
    /// report: by how much and where.
    pub fn at_most(&self, tol: f64) -> Result<(), String> {
        if self.by <= tol {
            Ok(())
        } else {
            Err(format!("strip left by {:e} at {}", self.by, self.at))
        }
    }
}

/// Taylor coefficients at s of the cubic c (in its own variable).
fn taylor(c: &[f64; 4], s: f64) -> [f64; 4] {
    [
        c[0] + s * (c[1] + s * (c[2] + s * c[3])),
        c[1] + s * (2.0 * c[2] + 3.0 * s * c[3]),
        c[2] + 3.0 * s * c[3],
        c[3],
    ]
}

/// The smallest value of c0 + c1 u + c2 u² + c3 u³ on \[0, l\] and where it is taken.
fn cubic_min(c: &[f64; 4], l: f64) -> (f64, f64) {
    let at = |u: f64| c[0] + u * (c[1] + u * (c[2] + u * c[3]));
    let mut best = (c[0], 0.0);
    let mut consider = |u: f64| {
        if (0.0..=l).contains(&u) {
            let v = at(u);
            if v < best.0 || v.is_nan() {
                best = (v, u);
            }
        }
    };
    consider(l);
    // derivative 3c3 u² + 2c2 u + c1
    let (a, b, cc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    if a == 0.0 {
        if b != 0.0 {
            consider(-cc / b);
        }
    } else {
        let disc = b * b - 4.0 * a * cc;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            if q != 0.0 {
                consider(q / a);
                consider(cc / q);
            } else {
                consider(0.0);
            }
        }
    }
    best
}

/// Breakpoints of a bound (polyline vertices, or the data sites for cubic pieces).
fn breakpoints(b: &Bound, t: &[f64]) -> Vec<f64> {
    match b {
        Bound::None => Vec::new(),
        Bound::Pieces(_) => t.to_vec(),
        Bound::Polyline(v) => v.iter().map(|q| q[0]).collect(),
    }
}

/// The bound as a cubic in u = x − a on a sub-interval \[a, b\] that no breakpoint splits.
fn bound_cubic(bd: &Bound, t: &[f64], a: f64, b: f64) -> Option<[f64; 4]> {
    match bd {
        Bound::None => None,
        Bound::Pieces(p) => {
            let n = t.len();
            let mid = 0.5 * (a + b);
            let i = t.partition_point(|v| *v <= mid).clamp(1, n - 1) - 1;
            Some(taylor(&p[i], a - t[i]))
        }
        Bound::Polyline(v) => {
            let mid = 0.5 * (a + b);
            let k = v.partition_point(|q| q[0] <= mid).clamp(1, v.len() - 1);
            let (p, q) = (v[k - 1], v[k]);
            let slope = (q[1] - p[1]) / (q[0] - p[0]);
            Some([p[1] + slope * (a - p[0]), slope, 0.0, 0.0])
        }
    }
}

/// The largest violation of the strip by `s` (exact, see the module docs).
pub fn strip_violation(p: &Problem, s: &Solution) -> Violation {
    let mut worst = Violation {
        by: f64::NEG_INFINITY,
        at: p.t[0],
        upper: false,
    };
    for (bd, upper) in [(&p.lower, false), (&p.upper, true)] {
        if matches!(bd, Bound::None) {
            continue;
        }
        let cuts = breakpoints(bd, &p.t);
        let mut k = 0;
        for j in 0..s.coefficients.len() {
            let (x0, x1) = (s.breaks[j], s.breaks[j + 1]);
            if x1 <= x0 {
                continue;
            }
            while k < cuts.len() && cuts[k] <= x0 {
                k += 1;
            }
            let mut a = x0;
            let mut kk = k;
            loop {
                let b = if kk < cuts.len() && cuts[kk] < x1 {
                    cuts[kk]
                } else {
                    x1
                };
                let f = taylor(&s.coefficients[j], a - x0);
                if let Some(g) = bound_cubic(bd, &p.t, a, b) {
                    let d: [f64; 4] =
                        std::array::from_fn(|i| if upper { g[i] - f[i] } else { f[i] - g[i] });
                    let (m, u) = cubic_min(&d, b - a);
                    if -m > worst.by || m.is_nan() {
                        worst = Violation {
                            by: -m,
                            at: a + u,
                            upper,
                        };
                    }
                }
                if b >= x1 {
                    break;
                }
                a = b;
                kk += 1;
            }
        }
    }
    if worst.by == f64::NEG_INFINITY {
        worst.by = 0.0;
    }
    worst
}

/// The data the solution `s` of `p` interpolates: `p` with the values Remark 4.2 moved inside
/// their bounds (`s.shifted_data`) replaced by the solution's (`s.grid_values`).
pub fn moved_data(p: &Problem, s: &Solution) -> Problem {
    let mut q = p.clone();
    for &i in &s.shifted_data {
        q.y[i] = s.grid_values[i];
    }
    q
}

/// The largest |f(t_i±) − y_i| over the data, from the pieces on both sides of each site.
pub fn interpolation_error(p: &Problem, s: &Solution) -> f64 {
    let mut worst: f64 = 0.0;
    for (i, (&x, &y)) in p.t.iter().zip(&p.y).enumerate() {
        let j = s.breaks.partition_point(|b| *b <= x);
        let mut vals = Vec::new();
        if j >= 1 && j - 1 < s.coefficients.len() {
            vals.push(taylor(&s.coefficients[j - 1], x - s.breaks[j - 1])[0]);
        }
        if j >= 2 {
            vals.push(taylor(&s.coefficients[j - 2], x - s.breaks[j - 2])[0]);
        }
        if vals.is_empty() {
            return f64::NAN;
        }
        for v in vals {
            let e = (v - y).abs();
            if e.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(e);
        }
        let _ = i;
    }
    worst
}

/// The largest jumps of f, f' and f'' across the interior breaks, each relative to the largest
/// |f|, |f'|, |f''| at the breaks (one number per derivative).
pub fn c2_jump(s: &Solution) -> [f64; 3] {
    let mut jump = [0.0f64; 3];
    let mut scale = [0.0f64; 3];
    for j in 0..s.coefficients.len() {
        let c = &s.coefficients[j];
        let r = taylor(c, s.breaks[j + 1] - s.breaks[j]);
        let ends = [[c[0], c[1], 2.0 * c[2]], [r[0], r[1], 2.0 * r[2]]];
        for e in ends {
            for d in 0..3 {
                scale[d] = scale[d].max(e[d].abs());
            }
        }
        if j + 1 < s.coefficients.len() {
            let q = &s.coefficients[j + 1];
            let right = [q[0], q[1], 2.0 * q[2]];
            for d in 0..3 {
                let e = (ends[1][d] - right[d]).abs();
                jump[d] = if e.is_nan() { f64::NAN } else { jump[d].max(e) };
            }
        }
    }
    std::array::from_fn(|d| jump[d] / scale[d].max(f64::MIN_POSITIVE))
}

/// The f'' jumps of a solution at its interior breaks against their rounding level, from the
/// returned pieces alone (caller's frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C2Rounding {
    /// The largest |f''(b−) − f''(b+)| over max|f''|.
    pub relative: f64,
    /// The largest jump over its rounding level (≤ 1: C² to rounding; NaN propagates).
    pub rounding: f64,
    /// Where the largest ratio is.
    pub at: f64,
}

/// [`C2Rounding`] of `s`. The rounding level of the jump at a break b, derived from how the
/// returned pieces can represent a C² function (not from the solver's code):
/// * b is a double: the exact knot lies within ulp(b) of it, and pieces expanded about the
///   rounded abscissa differ there by |Δf'''|·ulp(b) (Δf''' the jump of f''' at b);
/// * f'' from each side is computed from a cubic whose coefficients are themselves computed from
///   Hermite data (values and slopes at the piece's ends, length h): that carries a few u times
///   T = (6|f(end) − f(start)|/h + 4|f'(b)| + 2|f'(other end)|)/h, and evaluating 2c₂ + 6c₃h a
///   few u of max|f''|;
/// * at a contact (a break that is not a data site) the value f(b) is a bound's value, computed
///   from its polynomial's terms: u·E, E = Σ|c_k|(b − t_i)^k, moves f'' on each side by 6u·E/h².
///
/// So the level is 16u·(max|f''| + T₋ + T₊) + |Δf'''|·ulp(b) (u = 2⁻⁵³; 16u leaves a factor of
/// two over the ~8u the operations count), with 6E/h added to each side's 6|Δf|/h in T.
pub fn c2_rounding(p: &Problem, s: &Solution) -> C2Rounding {
    let u = f64::EPSILON / 2.0;
    let k = s.coefficients.len();
    let mut f2 = 0.0f64;
    for j in 0..k {
        let c = &s.coefficients[j];
        let r = taylor(c, s.breaks[j + 1] - s.breaks[j]);
        f2 = f2.max((2.0 * c[2]).abs()).max((2.0 * r[2]).abs());
    }
    let mut out = C2Rounding {
        relative: 0.0,
        rounding: 0.0,
        at: s.breaks[0],
    };
    // E at break j (0 at the data sites and the ends)
    let magnitude = |j: usize| {
        let b = s.breaks[j];
        if j == 0 || j == k || p.t.iter().any(|t| t.total_cmp(&b).is_eq()) {
            return 0.0;
        }
        let n = p.t.len();
        let i = p.t.partition_point(|v| *v <= b).clamp(1, n - 1) - 1;
        [&p.lower, &p.upper]
            .iter()
            .map(|bd| match bd {
                Bound::None => 0.0,
                Bound::Pieces(c) => {
                    let (c, x) = (c[i], (b - p.t[i]).abs());
                    c[0].abs() + x * (c[1].abs() + x * (c[2].abs() + x * c[3].abs()))
                }
                Bound::Polyline(v) => {
                    let q = v.partition_point(|q| q[0] <= b).clamp(1, v.len() - 1);
                    v[q - 1][1].abs().max(v[q][1].abs())
                }
            })
            .fold(0.0, f64::max)
    };
    // (T at the left end, T at the right end) of piece j
    let terms = |j: usize| {
        let c = &s.coefficients[j];
        let h = s.breaks[j + 1] - s.breaks[j];
        let r = taylor(c, h);
        let dv = 6.0 * ((r[0] - c[0]).abs() + magnitude(j) + magnitude(j + 1)) / h;
        (
            (dv + 4.0 * c[1].abs() + 2.0 * r[1].abs()) / h,
            (dv + 2.0 * c[1].abs() + 4.0 * r[1].abs()) / h,
        )
    };
    for j in 1..k {
        let (a, b) = (&s.coefficients[j - 1], &s.coefficients[j]);
        let h = s.breaks[j] - s.breaks[j - 1];
        let jump = (2.0 * a[2] + 6.0 * a[3] * h - 2.0 * b[2]).abs();
        let ulp = s.breaks[j].abs() * f64::EPSILON;
        let level = 16.0 * u * (f2 + terms(j - 1).1 + terms(j).0) + 6.0 * (b[3] - a[3]).abs() * ulp;
        let ratio = if jump == 0.0 { 0.0 } else { jump / level };
        if ratio.is_nan() {
            out.rounding = f64::NAN;
            out.relative = f64::NAN;
            out.at = s.breaks[j];
            return out;
        }
        out.relative = out.relative.max(jump / f2.max(f64::MIN_POSITIVE));
        if ratio > out.rounding {
            out.rounding = ratio;
            out.at = s.breaks[j];
        }
    }
    out
}

/// The necessary conditions of Lemma 1.1 of the seed, evaluated on the returned pieces (with
/// Theorem 2.1 they are also sufficient): f'' continuous, f''(t_1) = f''(t_n) = 0 at natural
/// ends, and f''' = l_i + ∫d(μ₁ − μ₂) with μ₁, μ₂ ≥ 0 supported on the contacts — so between data
/// sites f''' jumps only where f touches a bound, up at the lower and down at the upper one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lemma11 {
    /// Largest jump of f'' at a break, relative to max |f''|.
    pub f2_jump: f64,
    /// Largest |f''| at a natural end, relative to max |f''|.
    pub end_f2: f64,
    /// Largest |jump of f'''| at a break that is neither a data site nor a contact, relative to
    /// max |f'''|.
    pub stray_jump: f64,
    /// Largest jump of f''' with the wrong sign at a contact, relative to max |f'''|.
    pub wrong_sign: f64,
    /// Contacts found.
    pub contacts: usize,
}

/// Lemma 1.1 on `s`; a break is a contact when f is within `contact_tol` of a bound there.
pub fn lemma_1_1(p: &Problem, s: &Solution, contact_tol: f64) -> Lemma11 {
    let k = s.coefficients.len();
    let (mut f2max, mut f3max) = (0.0f64, 0.0f64);
    for (j, c) in s.coefficients.iter().enumerate() {
        let h = s.breaks[j + 1] - s.breaks[j];
        f2max = f2max
            .max((2.0 * c[2]).abs())
            .max((2.0 * c[2] + 6.0 * c[3] * h).abs());
        f3max = f3max.max((6.0 * c[3]).abs());
    }
    let f2max = f2max.max(f64::MIN_POSITIVE);
    let f3max = f3max.max(f64::MIN_POSITIVE);
    let mut out = Lemma11 {
        f2_jump: 0.0,
        end_f2: 0.0,
        stray_jump: 0.0,
        wrong_sign: 0.0,
        contacts: 0,
    };
    let nan_max = |a: f64, b: f64| {
        if b.is_nan() || a.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    };
    for j in 1..k {
        let (c0, c1) = (&s.coefficients[j - 1], &s.coefficients[j]);
        let h = s.breaks[j] - s.breaks[j - 1];
        let b = s.breaks[j];
        out.f2_jump = nan_max(
            out.f2_jump,
            ((2.0 * c0[2] + 6.0 * c0[3] * h) - 2.0 * c1[2]).abs() / f2max,
        );
        let jump = 6.0 * (c1[3] - c0[3]);
        if p.t.iter().any(|t| t.total_cmp(&b).is_eq()) {
            continue;
        }
        let f = c1[0];
        let lower = crate::bound_at(&p.lower, &p.t, b).is_some_and(|e| f - e <= contact_tol);
        let upper = crate::bound_at(&p.upper, &p.t, b).is_some_and(|d| d - f <= contact_tol);
        if lower || upper {
            out.contacts += 1;
            // where the strip is narrower than the tolerance both bounds touch, and the
            // multiplier may take either sign
            let wrong = match (lower, upper) {
                (true, false) => -jump,
                (false, true) => jump,
                _ => 0.0,
            };
            out.wrong_sign = nan_max(out.wrong_sign, wrong.max(0.0) / f3max);
        } else {
            out.stray_jump = nan_max(out.stray_jump, jump.abs() / f3max);
        }
    }
    if p.end_slopes[0].is_none() {
        out.end_f2 = (2.0 * s.coefficients[0][2]).abs() / f2max;
    }
    if p.end_slopes[1].is_none() {
        let c = &s.coefficients[k - 1];
        let h = s.breaks[k] - s.breaks[k - 1];
        out.end_f2 = out.end_f2.max((2.0 * c[2] + 6.0 * c[3] * h).abs() / f2max);
    }
    out
}
