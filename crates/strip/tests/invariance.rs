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
//! optional prescribed end slopes).

use proptest::prelude::*;
use strip::{solve, Bound, Options, Problem, Solution};

/// Cases per invariance property.
const CASES: u32 = 64;
/// Relative tolerance on f at sample points (relative to the value scale max|y| + 1 of the
/// transformed problem). Adding a line is exact to ~1e-12; scalings are not exactly invariant,
/// because the solver's stopping and feasibility tests mix absolute and relative scales
/// (`tol · (1 + |x|)`, [`strip::FEASIBILITY_TOL`] relative to 1 + max|y|): measured worst
/// ~2e-7 for values scaled by 1e-4 or sites by 10^2, but 1e-3 for values scaled by 1e-6 and
/// 5e-5 for sites scaled by 10^3.3 (ROBUSTNESS.md, finding 7). The properties therefore draw
/// c ∈ [10^-2, 10^2] and λ ∈ [10^-1.5, 10^1.5]; tests/conditioning.rs measures the extremes.
const VALUE_RTOL: f64 = 1e-6;
/// Relative tolerance on ∫f''².
const ENERGY_RTOL: f64 = 1e-6;

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

/// Compares g(x) with `want(x)` at 400 points per interval of `p`'s sites, mapped by `x_of`.
fn compare(
    f: &Solution,
    g: &Solution,
    p: &Problem,
    x_of: impl Fn(f64) -> f64,
    want: impl Fn(f64, f64) -> f64,
    scale: f64,
) -> Result<(), TestCaseError> {
    let (t0, t1) = (p.t[0], p.t[p.t.len() - 1]);
    for k in 0..=2000 {
        let t = t0 + (t1 - t0) * k as f64 / 2000.0;
        let (a, b) = (want(t, f.eval(t)), g.eval(x_of(t)));
        prop_assert!(
            (a - b).abs() <= VALUE_RTOL * scale,
            "t = {}: {} vs {}",
            t,
            a,
            b
        );
    }
    Ok(())
}

fn scale_of(p: &Problem) -> f64 {
    1.0 + p.y.iter().fold(0.0f64, |m, y| m.max(y.abs()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// Adding a + bt to y, e, d (and b to prescribed end slopes) leaves f − (a + bt) unchanged,
    /// with the same energy and extra knots.
    #[test]
    fn adding_a_line(p in problem(), a in -100.0f64..100.0, b in -100.0f64..100.0) {
        let f = solve(&p, &Options::default()).unwrap();
        let line = |t: f64| a + b * t;
        let shifted = |i: usize, c: &[f64; 4]| [c[0] + line(p.t[i]), c[1] + b, c[2], c[3]];
        let q = Problem {
            t: p.t.clone(),
            y: p.t.iter().zip(&p.y).map(|(t, y)| y + line(*t)).collect(),
            lower: map_bound(&p.lower, shifted),
            upper: map_bound(&p.upper, shifted),
            end_slopes: [p.end_slopes[0].map(|s| s + b), p.end_slopes[1].map(|s| s + b)],
        };
        let g = solve(&q, &Options::default()).unwrap();
        compare(&f, &g, &p, |t| t, |t, v| v + line(t), scale_of(&q))?;
        prop_assert!((f.energy - g.energy).abs() <= ENERGY_RTOL * f.energy.max(1e-12), "{} vs {}", f.energy, g.energy);
        prop_assert_eq!(f.extra_knots.len(), g.extra_knots.len());
        for (x, y) in f.extra_knots.iter().zip(&g.extra_knots) {
            prop_assert_eq!(x.kind, y.kind);
            prop_assert!((x.t - y.t).abs() <= 1e-6 * (1.0 + x.t.abs()), "{} vs {}", x.t, y.t);
        }
    }

    /// Scaling y, e, d (and end slopes) by c scales f by c and ∫f''² by c².
    #[test]
    fn scaling_values(p in problem(), logc in -2.0f64..2.0) {
        let c = 10f64.powf(logc);
        let f = solve(&p, &Options::default()).unwrap();
        let sc = |_: usize, k: &[f64; 4]| [c * k[0], c * k[1], c * k[2], c * k[3]];
        let q = Problem {
            t: p.t.clone(),
            y: p.y.iter().map(|y| c * y).collect(),
            lower: map_bound(&p.lower, sc),
            upper: map_bound(&p.upper, sc),
            end_slopes: [p.end_slopes[0].map(|s| c * s), p.end_slopes[1].map(|s| c * s)],
        };
        let g = solve(&q, &Options::default()).unwrap();
        compare(&f, &g, &p, |t| t, |_, v| c * v, c * scale_of(&p))?;
        let e = c * c * f.energy;
        prop_assert!((e - g.energy).abs() <= ENERGY_RTOL * e.max(1e-12 * c * c), "{} vs {}", e, g.energy);
    }

    /// t ↦ λt + s (sites, bound pieces, end slopes): f ↦ f((t − s)/λ), ∫f''² ↦ λ⁻³ ∫f''².
    #[test]
    fn shifting_and_scaling_sites(p in problem(), loglam in -1.5f64..1.5, s in -1e3f64..1e3) {
        let lam = 10f64.powf(loglam);
        let f = solve(&p, &Options::default()).unwrap();
        let sc = |_: usize, k: &[f64; 4]| [k[0], k[1] / lam, k[2] / (lam * lam), k[3] / (lam * lam * lam)];
        let q = Problem {
            t: p.t.iter().map(|t| lam * t + s).collect(),
            y: p.y.clone(),
            lower: map_bound(&p.lower, sc),
            upper: map_bound(&p.upper, sc),
            end_slopes: [p.end_slopes[0].map(|z| z / lam), p.end_slopes[1].map(|z| z / lam)],
        };
        let g = solve(&q, &Options::default()).unwrap();
        compare(&f, &g, &p, |t| lam * t + s, |_, v| v, scale_of(&p))?;
        let e = f.energy / (lam * lam * lam);
        prop_assert!((e - g.energy).abs() <= ENERGY_RTOL * e.max(1e-12 / (lam * lam * lam)), "{} vs {}", e, g.energy);
    }
}
