//! Oracles shared by the fuzz targets: they check what a result says, not only that a call
//! returned. Each panics (libFuzzer records the input) when a result breaks a guarantee the
//! README makes:
//!
//! - every number in a result is finite;
//! - an exact refinement carries a relative KKT certificate ≤ [`EXACT_ACCEPT`] (ROBUSTNESS.md:
//!   "exact means exact"), its data vertices satisfy their constraint (interpolation, balls,
//!   half-spaces) to [`FEASIBILITY_RTOL`] of the data's extent, its energy is ≥ 0;
//! - a strip solution interpolates the data and stays within its bounds at the breaks and data
//!   sites, to [`FEASIBILITY_RTOL`] of the data's scale, and is C² at every break (data sites and
//!   extra knots) to the rounding level of its pieces;
//! - an input refused is refused with a field (never an empty message).
//!
//! Translation invariance (a refinement of q + c has the energy of q's and its points moved by
//! c) is checked by `refine_structured`.

use curvefit::spec::refine::{ConstraintSpec, SolverSpec};
use curvefit::spec::{self, InputError, RefineResult, StripResult};

/// What constrains data point i.
enum At<'a> {
    Exact,
    Ball(f64),
    HalfSpaces(Vec<(&'a [f64], f64)>),
    Free,
}

fn constraint_at(problem: &spec::RefineProblem, i: usize) -> At<'_> {
    match &problem.constraint {
        ConstraintSpec::Interpolate => At::Exact,
        ConstraintSpec::Balls { radii } if radii[i] == 0.0 => At::Exact,
        ConstraintSpec::Balls { radii } => At::Ball(radii[i]),
        ConstraintSpec::Halfspaces { sets } => At::HalfSpaces(
            sets[i]
                .iter()
                .map(|h| (h.normal.as_slice(), h.offset))
                .collect(),
        ),
        _ => At::Free,
    }
}

/// The exact solver's acceptance level (refine::EXACT_ACCEPT_KKT).
pub const EXACT_ACCEPT: f64 = 1e-9;
/// Feasibility is checked relative to the data's extent (rounding of the returned points).
pub const FEASIBILITY_RTOL: f64 = 1e-7;

/// The largest absolute coordinate of `rows` (at least the smallest normal number).
fn extent(coords: &[f64]) -> f64 {
    coords.iter().fold(f64::MIN_POSITIVE, |m, x| m.max(x.abs()))
}

/// With `CURVEFIT_FUZZ_SHOW=1` in the environment, prints each checked problem as the command
/// line's JSON (to replay a crash artifact through `curvefit refine -` or `curvefit strip -`;
/// libFuzzer aborts inside the panic hook, so nothing can be printed after a failed check).
fn show(problem: &impl serde::Serialize) {
    if std::env::var_os("CURVEFIT_FUZZ_SHOW").is_some() {
        eprintln!(
            "problem: {}",
            serde_json::to_string(problem).unwrap_or_default()
        );
    }
}

/// A refusal must say what is wrong.
pub fn check_refusal(e: &InputError) {
    assert!(
        !e.message.is_empty(),
        "empty error message for field {:?}",
        e.field
    );
}

/// A result whose JSON has no null (a non-finite number), or a refusal that says what is wrong.
pub fn check_finite_or_refused<T: serde::Serialize>(out: &Result<T, InputError>) {
    match out {
        Ok(r) => {
            let v = serde_json::to_value(r).expect("a result serializes");
            assert!(
                !v.to_string().contains("null"),
                "a non-finite number in {v}"
            );
        }
        Err(e) => check_refusal(e),
    }
}

/// Checks a refinement of `problem`.
pub fn check_refine(problem: &spec::RefineProblem, r: &RefineResult) {
    show(problem);
    let p = &r.points;
    assert!(p.coords().iter().all(|x| x.is_finite()), "non-finite point");
    assert!(r.knots.iter().all(|x| x.is_finite()), "non-finite knot");
    assert!(
        r.knots.windows(2).all(|w| w[0] < w[1]),
        "knots not increasing"
    );
    assert!(
        r.energy.is_finite() && r.energy >= 0.0,
        "energy {}",
        r.energy
    );
    assert!(r.kkt_residual.is_finite(), "kkt {}", r.kkt_residual);
    assert!(
        r.multipliers.iter().flatten().all(|x| x.is_finite()),
        "non-finite multiplier"
    );
    let q = &problem.points;
    assert_eq!(
        r.data_vertex.len(),
        q.len(),
        "one data vertex per data point"
    );
    assert!(
        r.data_vertex.windows(2).all(|w| w[0] < w[1]) && r.data_vertex.iter().all(|&v| v < p.len()),
        "data vertices out of order or range"
    );
    if problem.solver == SolverSpec::Paper {
        return; // the paper's iteration is approximate by design
    }
    assert!(
        r.kkt_residual <= EXACT_ACCEPT,
        "exact result with certificate {:e}",
        r.kkt_residual
    );
    let scale = extent(q.coords()).max(extent(p.coords()));
    let tol = FEASIBILITY_RTOL * scale;
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let (a, b) = (p.point(v), q.point(i));
        let dist = a
            .iter()
            .zip(b)
            .map(|(x, y)| ((x - y) / scale).powi(2))
            .sum::<f64>()
            .sqrt()
            * scale;
        match constraint_at(problem, i) {
            At::Exact => assert!(dist <= tol, "point {i} off its data point by {dist:e}"),
            At::Ball(r) => assert!(
                dist <= r + tol,
                "point {i} outside its ball ({dist:e} > {r:e})"
            ),
            At::HalfSpaces(sets) => {
                for (normal, offset) in sets {
                    let n = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                    let g = normal.iter().zip(a).map(|(x, y)| x * y).sum::<f64>() - offset;
                    assert!(
                        g <= tol * n,
                        "point {i} outside a half-space by {:e}",
                        g / n
                    );
                }
            }
            At::Free => {}
        }
    }
}

/// Checks a strip solution of `problem`.
pub fn check_strip(problem: &spec::StripProblem, s: &StripResult) {
    show(problem);
    assert!(s.breaks.iter().all(|x| x.is_finite()), "non-finite break");
    assert!(
        s.breaks.windows(2).all(|w| w[0] < w[1]),
        "breaks not increasing"
    );
    assert!(
        s.coefficients.iter().flatten().all(|x| x.is_finite()),
        "non-finite coefficient"
    );
    assert!(
        s.energy.is_finite() && s.energy >= 0.0,
        "energy {}",
        s.energy
    );
    assert_eq!(
        s.coefficients.len() + 1,
        s.breaks.len(),
        "one cubic per break interval"
    );
    let (t, y) = (&problem.t, &problem.y);
    // the value scale: the data and the solution's values at its breaks
    let scale = y
        .iter()
        .chain(s.coefficients.iter().map(|c| &c[0]))
        .fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()));
    let eval = |x: f64, nu: usize| -> f64 {
        let j = match s.breaks.binary_search_by(|b| b.total_cmp(&x)) {
            Ok(j) => j.min(s.coefficients.len() - 1),
            Err(j) => j.saturating_sub(1).min(s.coefficients.len() - 1),
        };
        let c = s.coefficients[j];
        let h = x - s.breaks[j];
        match nu {
            0 => c[0] + h * (c[1] + h * (c[2] + h * c[3])),
            1 => c[1] + h * (2.0 * c[2] + 3.0 * h * c[3]),
            _ => 2.0 * c[2] + 6.0 * h * c[3],
        }
    };
    for (i, (&ti, &yi)) in t.iter().zip(y.iter()).enumerate() {
        let f = eval(ti, 0);
        // Remark 4.2: a value on a cubic-piece bound is moved inside by 1e-7 of the strip width
        // (reported in `shifted_data`)
        let moved = if s.shifted_data.contains(&i) {
            // ε = 1e-7 of the strip width there, or of the value scale V where one bound is
            // missing (V: data, bounds and end slopes × span about the chord; bounded here by
            // their magnitudes)
            let span = t[t.len() - 1] - t[0];
            let slopes = problem
                .end_slopes
                .iter()
                .flatten()
                .flatten()
                .fold(0.0f64, |m, v| m.max(v.abs() * span));
            let bounds = (0..t.len())
                .flat_map(|j| {
                    [
                        bound_at(&problem.lower, t, j),
                        bound_at(&problem.upper, t, j),
                    ]
                })
                .flatten()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            2e-7 * (scale.max(bounds).max(slopes) * 2.0)
        } else {
            0.0
        };
        assert!(
            (f - yi).abs() <= moved + FEASIBILITY_RTOL * scale.max(f.abs()),
            "f(t[{i}]) = {f} but y[{i}] = {yi}"
        );
    }
    // within the bounds at every break and data site
    for (j, &x) in s.breaks.iter().enumerate() {
        let f = eval(x, 0);
        let Some(i) = t.iter().rposition(|&ti| ti <= x) else {
            continue;
        };
        if t[i] != x {
            continue; // the bounds are checked at the data sites, where they are known exactly
        }
        if let Some(lo) = bound_at(&problem.lower, t, i) {
            assert!(
                f >= lo - FEASIBILITY_RTOL * scale,
                "f({x}) = {f} below the lower bound {lo} (break {j})"
            );
        }
        if let Some(hi) = bound_at(&problem.upper, t, i) {
            assert!(
                f <= hi + FEASIBILITY_RTOL * scale,
                "f({x}) = {f} above the upper bound {hi} (break {j})"
            );
        }
    }
    // C² at every inner break (data sites and extra knots): the second derivative from both sides
    // agrees to its rounding level, derived from how the returned pieces represent f (as
    // strip-testkit's `c2_rounding`): a break is a double, so pieces expanded about it differ by
    // |Δf'''|·ulp(b); each side's f'' comes from a cubic computed from the Hermite data of its
    // piece (length h, values and slopes at its ends), which carries a few u times
    // T = (6|Δf|/h + 4|f'(b)| + 2|f'(other end)|)/h, and evaluating 2c₂ + 6c₃h a few u of
    // max|f''|. Level: 16u·(max|f''| + T₋ + T₊) + |Δf'''|·ulp(b), u = 2⁻⁵³.
    let u = f64::EPSILON / 2.0;
    let end = |c: &[f64; 4], h: f64| {
        (
            c[0] + h * (c[1] + h * (c[2] + h * c[3])),
            c[1] + h * (2.0 * c[2] + 3.0 * h * c[3]),
            2.0 * c[2] + 6.0 * h * c[3],
        )
    };
    let f2max = (0..s.coefficients.len()).fold(0.0f64, |m, j| {
        let c = &s.coefficients[j];
        let (_, _, f2) = end(c, s.breaks[j + 1] - s.breaks[j]);
        m.max((2.0 * c[2]).abs()).max(f2.abs())
    });
    // (T at the left end, T at the right end) of piece j
    let terms = |j: usize| {
        let c = &s.coefficients[j];
        let h = s.breaks[j + 1] - s.breaks[j];
        let (f, d, _) = end(c, h);
        let dv = 6.0 * (f - c[0]).abs() / h;
        (
            (dv + 4.0 * c[1].abs() + 2.0 * d.abs()) / h,
            (dv + 2.0 * c[1].abs() + 4.0 * d.abs()) / h,
        )
    };
    for j in 1..s.coefficients.len() {
        let h = s.breaks[j] - s.breaks[j - 1];
        let (a, b) = (&s.coefficients[j - 1], &s.coefficients[j]);
        let (_, _, left) = end(a, h);
        let right = 2.0 * b[2];
        let level = 16.0 * u * (f2max + terms(j - 1).1 + terms(j).0)
            + 6.0 * (b[3] - a[3]).abs() * s.breaks[j].abs() * f64::EPSILON;
        assert!(
            (left - right).abs() <= level,
            "f'' jumps at break {j} (t = {}): {left} vs {right}, {:e} of max|f''|, rounding level {level:e}",
            s.breaks[j],
            (left - right).abs() / f2max
        );
    }
}

/// A bound's value at data site `i` (the piece of the interval starting there, the last piece at
/// the last site; the polyline's segment containing t_i).
fn bound_at(b: &Option<spec::strip::BoundSpec>, t: &[f64], i: usize) -> Option<f64> {
    match b.as_ref()? {
        spec::strip::BoundSpec::Pieces(p) => {
            if i < p.len() {
                Some(p[i][0])
            } else {
                let c = p.last()?;
                let h = t[i] - t[i - 1];
                Some(c[0] + h * (c[1] + h * (c[2] + h * c[3])))
            }
        }
        spec::strip::BoundSpec::Polyline(v) => {
            let x = t[i];
            let k = v.windows(2).position(|w| w[0][0] <= x && x <= w[1][0])?;
            let (a, b) = (v[k], v[k + 1]);
            Some(a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]))
        }
    }
}
