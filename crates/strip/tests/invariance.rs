//! Invariance properties of best interpolation in a strip (issue 8).
//!
//! ∫f''² and the constraints f(t_i) = y_i, e ≤ f ≤ d are unchanged when the same line a + bt is
//! added to y, e and d (a line has f'' = 0), so the optimum f̃ satisfies f̃ − (a + bt) = f.
//! Scaling values by c scales f by c and ∫f''² by c²; the change of variable t ↦ λt + s maps
//! f to f((t − s)/λ), whose ∫f''² is λ⁻³ times the original. Bound pieces are cubics in
//! s = t − t_i: adding a + bt adds a + bt_i to c0 and b to c1; t ↦ λt + s divides c_j by λ^j;
//! prescribed end slopes gain b, scale by c, or divide by λ.
//!
//! Each property runs [`CASES`] random problems (jumping linear bounds as in `tests/strip.rs`,
//! optional prescribed end slopes) over the whole range of the conditioning study
//! (tests/conditioning.rs, ROBUSTNESS.md §2): values ×c with c ∈ [1e-8, 1e8], sites ×λ with
//! λ ∈ [1e-4, 1e4] (so slope scales c/λ from 1e-12 to 1e12), lines with slopes up to 1e8 (in
//! units of the value scale over the site range) and all of them at once. `solve` works in a
//! normalized frame (ROBUSTNESS.md, finding 7, fixed), so every transformed problem is the same
//! normalized problem up to the rounding of its input; before that fix, c/λ < 1e-4 stopped the
//! solver after 0–3 iterations (deviation up to 8e-2, the strip violated by 9.3e-4).
//!
//! Besides the agreement, every transformed solution is checked against its own strip by
//! sampling (independently of the solver's exact check): violation ≤ [`VIOLATION_RTOL`] of the
//! value scale plus the rounding of the added line's magnitude.

use proptest::prelude::*;
use strip::{solve, Bound, Options, Problem, Solution};

/// Cases per invariance property.
const CASES: u32 = 64;
/// Relative tolerance on f at sample points, relative to the value scale c·(1 + max|y|) of the
/// transformed problem. Measured over 3 × 5 × 64 cases (ROBUSTNESS.md §1): worst 1.9e-14 for
/// pure scalings; with input rounding, worst 0.02 × (1e-11 + the allowance below).
const VALUE_RTOL: f64 = 1e-11;
/// Relative tolerance on ∫f''². Measured: worst 1.1e-14 for pure scalings; with input
/// rounding, worst 0.05 × (1e-11 + the allowance below).
const ENERGY_RTOL: f64 = 1e-11;
/// Relative tolerance on extra-knot positions, relative to the site range.
const KNOT_RTOL: f64 = 1e-6;
/// Strip violation of a transformed solution (sampled), relative to its value scale: the
/// documented guarantee [`strip::RESULT_FEASIBILITY_TOL`] (candidates are feasible to
/// [`strip::FEASIBILITY_TOL`] = 1e-10 of the value scale).
const VIOLATION_RTOL: f64 = strip::RESULT_FEASIBILITY_TOL;
/// Input rounding allowance (≈ 450 ε): the transformed input is itself rounded. Values of
/// magnitude L (an added line) carry errors ~ε·L, sites shifted by s carry errors ~ε·|s|; relative
/// to the value scale V and the site range R these are ε·L/V and ε·|s|/(λR), and the answer can
/// be no more accurate than that (measured: ~10 ε times these ratios). Tolerances add
/// `INPUT_ROUNDING`·(L/V + |s|/(λR)) to their relative part.
const INPUT_ROUNDING: f64 = 1e-13;

fn problem() -> impl Strategy<Value = Problem> {
    (
        proptest::collection::vec(-1.0f64..1.0, 6),
        proptest::collection::vec(0.3f64..2.0, 5),
        proptest::collection::vec((0.05f64..0.6, -0.3f64..0.3), 5),
        proptest::collection::vec((0.05f64..0.6, -0.3f64..0.3), 5),
        proptest::option::of(-3.0f64..3.0),
        proptest::option::of(-3.0f64..3.0),
    )
        .prop_map(|(ys, hs, below, above, s0, s1)| {
            let mut t = vec![0.0];
            for h in &hs {
                t.push(t.last().unwrap_or(&0.0) + h);
            }
            let lo = (0..5)
                .map(|i| {
                    let (w, tilt) = below[i];
                    let a = ys[i] - w - tilt.max(0.0);
                    let b = ys[i + 1] - w + tilt.min(0.0);
                    [a, (b - a) / hs[i], 0.0, 0.0]
                })
                .collect();
            let up = (0..5)
                .map(|i| {
                    let (w, tilt) = above[i];
                    let a = ys[i] + w + tilt.max(0.0);
                    let b = ys[i + 1] + w - tilt.min(0.0);
                    [a, (b - a) / hs[i], 0.0, 0.0]
                })
                .collect();
            Problem {
                t,
                y: ys,
                lower: Bound::Pieces(lo),
                upper: Bound::Pieces(up),
                end_slopes: [s0, s1],
            }
        })
}

fn map_bound(b: &Bound, f: impl Fn(usize, &[f64; 4]) -> [f64; 4]) -> Bound {
    match b {
        Bound::Pieces(p) => Bound::Pieces(p.iter().enumerate().map(|(i, c)| f(i, c)).collect()),
        other => other.clone(),
    }
}

/// The problem transformed to values ℓ(T) + c·v at sites T = λt + s, with ℓ(T) = a + bT.
fn transform(p: &Problem, c: f64, lam: f64, s: f64, a: f64, b: f64) -> Problem {
    let tt: Vec<f64> = p.t.iter().map(|t| lam * t + s).collect();
    let line = |x: f64| a + b * x;
    let tr = |i: usize, k: &[f64; 4]| {
        [
            c * k[0] + line(tt[i]),
            c * k[1] / lam + b,
            c * k[2] / (lam * lam),
            c * k[3] / (lam * lam * lam),
        ]
    };
    let slope = |z: Option<f64>| z.map(|z| c * z / lam + b);
    Problem {
        y: tt.iter().zip(&p.y).map(|(x, y)| c * y + line(*x)).collect(),
        lower: map_bound(&p.lower, tr),
        upper: map_bound(&p.upper, tr),
        end_slopes: [slope(p.end_slopes[0]), slope(p.end_slopes[1])],
        t: tt,
    }
}

/// 1 + max|y|: the base problem's value scale.
fn scale_of(p: &Problem) -> f64 {
    1.0 + p.y.iter().fold(0.0f64, |m, y| m.max(y.abs()))
}

/// Largest |value| of the line a + bT over the transformed sites.
fn line_magnitude(q: &Problem, a: f64, b: f64) -> f64 {
    q.t.iter().fold(0.0f64, |m, x| m.max((a + b * x).abs()))
}

/// Largest strip violation of `g` over 200 samples per interval of `q` (bound pieces).
fn sampled_violation(q: &Problem, g: &Solution) -> f64 {
    let at = |b: &Bound, i: usize, x: f64| match b {
        Bound::Pieces(v) => {
            let k = v[i];
            let u = x - q.t[i];
            Some(k[0] + u * (k[1] + u * (k[2] + u * k[3])))
        }
        _ => None,
    };
    let mut worst: f64 = 0.0;
    for i in 0..q.t.len() - 1 {
        for j in 0..=200 {
            let x = q.t[i] + (q.t[i + 1] - q.t[i]) * j as f64 / 200.0;
            let v = g.eval(x);
            if let Some(lo) = at(&q.lower, i, x) {
                worst = worst.max(lo - v);
            }
            if let Some(hi) = at(&q.upper, i, x) {
                worst = worst.max(v - hi);
            }
        }
    }
    worst
}

/// Solves p and its transform and checks the equivariance: g(λt + s) = ℓ + c·f(t) at 2000
/// samples, ∫g''² = c²/λ³ ∫f''², the same extra knots mapped, and g inside its strip.
/// Returns the worst relative value deviation, the relative energy deviation and the input
/// rounding allowance (for the measurements).
fn check(
    p: &Problem,
    c: f64,
    lam: f64,
    s: f64,
    a: f64,
    b: f64,
) -> Result<(f64, f64, f64), TestCaseError> {
    let f = solve(p, &Options::default()).unwrap();
    let q = transform(p, c, lam, s, a, b);
    let g = match solve(&q, &Options::default()) {
        Ok(g) => g,
        Err(e) => {
            return Err(TestCaseError::fail(format!(
                "c {c:e} λ {lam:e} s {s} a {a:e} b {b:e}: {e}"
            )))
        }
    };
    let lmag = line_magnitude(&q, a, b);
    let vscale = c * scale_of(p);
    let (t0, t1) = (p.t[0], p.t[p.t.len() - 1]);
    let input = INPUT_ROUNDING * (lmag / vscale + s.abs() / (lam * (t1 - t0)));
    let tol = (VALUE_RTOL + input) * vscale;
    let mut dev: f64 = 0.0;
    for k in 0..=2000 {
        let t = t0 + (t1 - t0) * k as f64 / 2000.0;
        let x = lam * t + s;
        let want = a + b * x + c * f.eval(t);
        let got = g.eval(x);
        prop_assert!(
            (want - got).abs() <= tol,
            "c {c:e} λ {lam:e} s {s} a {a:e} b {b:e}, t = {t}: {want} vs {got}"
        );
        dev = dev.max((want - got).abs() / vscale);
    }
    let e = f.energy * (c / lam) * (c / lam) / lam;
    let edev = (e - g.energy).abs() / e.max(1e-300);
    prop_assert!(
        (e - g.energy).abs() <= (ENERGY_RTOL + input) * e.max(1e-12 * c * c / (lam * lam * lam)),
        "c {c:e} λ {lam:e}: energy {e} vs {}",
        g.energy
    );
    prop_assert_eq!(f.extra_knots.len(), g.extra_knots.len());
    for (x, y) in f.extra_knots.iter().zip(&g.extra_knots) {
        prop_assert_eq!(x.kind, y.kind);
        prop_assert!(
            (lam * x.t + s - y.t).abs() <= (KNOT_RTOL + input) * lam * (t1 - t0),
            "{} vs {}",
            x.t,
            y.t
        );
    }
    let viol = sampled_violation(&q, &g);
    prop_assert!(
        viol <= (VIOLATION_RTOL + input) * vscale,
        "c {c:e} λ {lam:e} a {a:e} b {b:e}: violation {viol:e} (value scale {vscale:e})"
    );
    // the solver's own exact check agrees with the samples (the samples cannot see more)
    prop_assert!(
        viol <= g.violation.max(0.0) + input * vscale + 1e-15 * vscale,
        "sampled {viol:e} > exact {:e}",
        g.violation
    );
    Ok((dev, edev, input))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// Adding a + bt to y, e, d (and b to prescribed end slopes) leaves f − (a + bt) unchanged,
    /// with the same energy and extra knots; slopes b up to 1e8 (the data's slopes are ~1).
    #[test]
    fn adding_a_line(p in problem(), a in -1e8f64..1e8, logb in -2.0f64..8.0, sign in proptest::bool::ANY) {
        let b = if sign { 10f64.powf(logb) } else { -(10f64.powf(logb)) };
        check(&p, 1.0, 1.0, 0.0, a, b)?;
    }

    /// Scaling y, e, d (and end slopes) by c ∈ [1e-8, 1e8] scales f by c and ∫f''² by c².
    #[test]
    fn scaling_values(p in problem(), logc in -8.0f64..8.0) {
        check(&p, 10f64.powf(logc), 1.0, 0.0, 0.0, 0.0)?;
    }

    /// t ↦ λt + s with λ ∈ [1e-4, 1e4]: f ↦ f((t − s)/λ), ∫f''² ↦ λ⁻³ ∫f''².
    #[test]
    fn shifting_and_scaling_sites(p in problem(), loglam in -4.0f64..4.0, s in -1e3f64..1e3) {
        check(&p, 1.0, 10f64.powf(loglam), s, 0.0, 0.0)?;
    }

    /// Everything at once: values ×c, sites ×λ and shifted, a line added (slope up to 1e4 times
    /// the slope scale c/λ), including slope scales c/λ < 1e-4 (finding 7's failing range).
    #[test]
    fn all_at_once(
        p in problem(),
        logc in -8.0f64..8.0,
        loglam in -4.0f64..4.0,
        s in -1e3f64..1e3,
        a in -1e3f64..1e3,
        logb in -4.0f64..4.0,
    ) {
        let (c, lam) = (10f64.powf(logc), 10f64.powf(loglam));
        check(&p, c, lam, s * lam, a * c, 10f64.powf(logb) * c / lam)?;
    }
}

/// The extreme corners of the ranges above (lines of slope ±1e4 times the slope scale c/λ), and
/// finding 7's own case (values ×1e-8, sites ×10: before the fix it stopped after one iteration
/// and left the strip by 9.3e-4 of the value scale, returned as Ok).
#[test]
fn corners_of_the_ranges() {
    let p = problem_fixed();
    eprintln!(
        "| c | λ | line slope | value deviation | energy deviation | input rounding allowance |"
    );
    let mut cases = vec![(1e-8, 10.0, 0.0)];
    for c in [1e-8, 1e8] {
        for lam in [1e-4, 1e4] {
            for b in [0.0, 1e4 * c / lam, -1e4 * c / lam] {
                cases.push((c, lam, b));
            }
        }
    }
    for (c, lam, b) in cases {
        let (dev, edev, input) = check(&p, c, lam, 0.0, 0.0, b).unwrap_or_else(|e| panic!("{e}"));
        eprintln!("| {c:e} | {lam:e} | {b:e} | {dev:.1e} | {edev:.1e} | {input:.1e} |");
    }
}

/// A fixed problem of the generator's family: six points with jumping linear bounds, one
/// prescribed end slope.
fn problem_fixed() -> Problem {
    let ys = [0.0, 1.0, -0.5, 0.8, 0.2, 1.0];
    let t = [0.0, 1.0, 2.5, 3.0, 4.2, 5.0];
    let piece = |i: usize, off: f64| {
        let sl = (ys[i + 1] - ys[i]) / (t[i + 1] - t[i]);
        [ys[i] + off, sl, 0.0, 0.0]
    };
    Problem {
        lower: Bound::Pieces((0..5).map(|i| piece(i, -0.1 - 0.02 * i as f64)).collect()),
        upper: Bound::Pieces((0..5).map(|i| piece(i, 0.1)).collect()),
        t: t.to_vec(),
        y: ys.to_vec(),
        end_slopes: [Some(0.5), None],
    }
}
