//! Integration tests of the strip solver: Holladay's theorem, Theorem 2.1's structure, each
//! candidate kind, gradients against finite differences, pruning, optimality against an
//! independent Clarabel lower bound, §4 convergence, Remark 4.2, and typed errors.

mod common;

use proptest::prelude::*;
use strip::interval::solve_interval;
use strip::{
    solve, Bound, Error, Infeasibility, KnotKind, Method, Options, Problem, Pruning, Shape, Side,
};
use strip_testkit::examples::{polygon_strip, Y16};

/// Natural cubic spline by the independent moment (second-derivative) formulation:
/// returns the second derivatives M_i at the sites.
fn natural_moments(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len();
    let h: Vec<f64> = (0..n - 1).map(|i| t[i + 1] - t[i]).collect();
    let mut a = vec![0.0; n];
    let mut b = vec![1.0; n];
    let mut c = vec![0.0; n];
    let mut r = vec![0.0; n];
    for i in 1..n - 1 {
        a[i] = h[i - 1] / 6.0;
        b[i] = (h[i - 1] + h[i]) / 3.0;
        c[i] = h[i] / 6.0;
        r[i] = (y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1];
    }
    for i in 1..n {
        let w = a[i] / b[i - 1];
        b[i] -= w * c[i - 1];
        r[i] -= w * r[i - 1];
    }
    let mut m = vec![0.0; n];
    m[n - 1] = r[n - 1] / b[n - 1];
    for i in (0..n - 1).rev() {
        m[i] = (r[i] - c[i] * m[i + 1]) / b[i];
    }
    m
}

fn natural_eval(t: &[f64], y: &[f64], m: &[f64], x: f64) -> f64 {
    let n = t.len();
    let i = t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
    let h = t[i + 1] - t[i];
    let (a, b) = ((t[i + 1] - x) / h, (x - t[i]) / h);
    a * y[i] + b * y[i + 1] + ((a * a * a - a) * m[i] + (b * b * b - b) * m[i + 1]) * h * h / 6.0
}

#[test]
fn inactive_strip_gives_the_natural_spline() {
    // Holladay: with a strip wide enough to stay inactive, the answer is the natural spline.
    let t: Vec<f64> = vec![0.0, 0.7, 1.9, 2.4, 3.8, 5.0, 5.3, 7.0];
    let y: Vec<f64> = vec![1.0, -0.4, 0.8, 1.7, 0.2, -1.0, -0.6, 0.9];
    let n = t.len();
    let p = Problem {
        t: t.clone(),
        y: y.clone(),
        lower: Bound::Pieces(vec![[-50.0, 0.0, 0.0, 0.0]; n - 1]),
        upper: Bound::Pieces(vec![[50.0, 0.0, 0.0, 0.0]; n - 1]),
        end_slopes: [None, None],
    };
    let s = solve(&p, &Options::default()).unwrap();
    assert!(s.extra_knots.is_empty());
    let m = natural_moments(&t, &y);
    let scale = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for k in 0..=700 {
        let x = 7.0 * k as f64 / 700.0;
        let d = (s.eval(x) - natural_eval(&t, &y, &m, x)).abs();
        assert!(d <= 1e-12 * scale, "at {x}: {d:e}");
    }
    for (i, mi) in m.iter().enumerate() {
        let d2 = s.derivative(t[i].min(6.999_999_999), 2);
        let d2 = if i == n - 1 {
            s.derivative(t[i] - 1e-300, 2)
        } else {
            d2
        };
        assert!((d2 - mi).abs() <= 1e-11 * (1.0 + mi.abs()), "M[{i}]");
    }
    // energy ∫ f''² of the natural spline from the moments: Σ h/3 (M_i² + M_i M_{i+1} + M_{i+1}²)
    let e: f64 = (0..n - 1)
        .map(|i| (t[i + 1] - t[i]) / 3.0 * (m[i] * m[i] + m[i] * m[i + 1] + m[i + 1] * m[i + 1]))
        .sum();
    assert!((s.energy - e).abs() <= 1e-12 * e);
}

fn assert_structure(p: &Problem, s: &strip::Solution) {
    let n = p.t.len();
    // at most two extra knots per interval; no subarc in the first or last interval
    for j in 0..n - 1 {
        let k = s.extra_knots.iter().filter(|k| k.interval == j).count();
        assert!(k <= 2, "interval {j} has {k} extra knots");
    }
    if p.end_slopes == [None, None] {
        assert!(!matches!(s.shapes[0], Shape::Subarc(_)));
        assert!(!matches!(s.shapes[n - 2], Shape::Subarc(_)));
        let scale =
            1.0 + (0..s.coefficients.len()).fold(0.0f64, |a, j| a.max(s.coefficients[j][2].abs()));
        assert!(
            s.derivative(p.t[0], 2).abs() <= 1e-8 * scale,
            "f''(t1) = {}",
            s.derivative(p.t[0], 2)
        );
        let last = s.coefficients.last().unwrap();
        let hl = p.t[n - 1] - s.breaks[s.breaks.len() - 2];
        let f2_end = 2.0 * last[2] + 6.0 * last[3] * hl;
        assert!(f2_end.abs() <= 1e-8 * scale, "f''(tn) = {f2_end}");
    }
    // C² at every break: compare the left piece's value/derivatives at its right end
    for j in 1..s.coefficients.len() {
        let c = s.coefficients[j - 1];
        let hh = s.breaks[j] - s.breaks[j - 1];
        let left = [
            c[0] + hh * (c[1] + hh * (c[2] + hh * c[3])),
            c[1] + hh * (2.0 * c[2] + 3.0 * hh * c[3]),
            2.0 * c[2] + 6.0 * hh * c[3],
        ];
        let r = s.coefficients[j];
        let right = [r[0], r[1], 2.0 * r[2]];
        for d in 0..3 {
            assert!(
                (left[d] - right[d]).abs() <= 1e-8 * (1.0 + right[d].abs()),
                "break {j} derivative {d}: {} vs {}",
                left[d],
                right[d]
            );
        }
    }
    // interpolation and bounds
    for i in 0..n {
        assert!((s.eval(p.t[i]) - p.y[i]).abs() <= 1e-12 * (1.0 + p.y[i].abs()));
    }
    assert!(common::max_violation(p, s, 20_000) <= 1e-10);
    assert!(s.uncertified.is_empty());
}

#[test]
fn theorem_2_1_structure_and_every_kind_active() {
    for w in [0.3, 0.2, 0.1] {
        let p = polygon_strip(&Y16, w);
        let s = solve(&p, &Options::default()).unwrap();
        assert_structure(&p, &s);
        assert!(s.gradient_norm <= 1e-6, "gradient {}", s.gradient_norm);
        assert!(
            s.newton_decrement <= 1e-13 * s.energy,
            "decrement {}",
            s.newton_decrement
        );
    }
    // w = 0.1 activates every kind (checked, not assumed)
    let s = solve(&polygon_strip(&Y16, 0.1), &Options::default()).unwrap();
    for shape in [
        Shape::Touch(Side::Lower),
        Shape::Touch(Side::Upper),
        Shape::Subarc(Side::Lower),
        Shape::Subarc(Side::Upper),
        Shape::Pair(Side::Lower),
        Shape::Pair(Side::Upper),
    ] {
        assert!(
            s.shapes.contains(&shape),
            "{shape:?} not active: {:?}",
            s.shapes
        );
    }
    assert!(s
        .extra_knots
        .iter()
        .any(|k| k.kind == KnotKind::SubarcStart(Side::Lower)));
}

#[test]
fn optimal_against_an_independent_clarabel_lower_bound() {
    for w in [0.2, 0.1] {
        let p = polygon_strip(&Y16, w);
        let s = solve(&p, &Options::default()).unwrap();
        let grid = common::qp_grid(&p, 16, Some(&s));
        let lb = common::qp_lower_bound(&p, &grid);
        let rel = (s.energy - lb) / s.energy;
        assert!(
            rel >= -1e-9,
            "energy {} below the lower bound {lb}",
            s.energy
        );
        assert!(
            rel <= 1e-6,
            "energy {} vs lower bound {lb}: gap {rel:e}",
            s.energy
        );
    }
}

#[test]
fn newton_and_bfgs_agree() {
    let p = polygon_strip(&Y16, 0.2);
    let a = solve(&p, &Options::default()).unwrap();
    let b = solve(
        &p,
        &Options {
            method: Method::Bfgs,
            ..Options::default()
        },
    )
    .unwrap();
    assert!((a.energy - b.energy).abs() <= 1e-9 * a.energy);
    for (x, y) in a.slopes.iter().zip(&b.slopes) {
        assert!((x - y).abs() <= 1e-5 * (1.0 + x.abs()), "{x} vs {y}");
    }
}

/// One interval: (θ, lower, upper, expected shape).
type Design = ([f64; 4], Option<[f64; 4]>, Option<[f64; 4]>, Shape);

fn designed_cells() -> Vec<Design> {
    let e = Some([0.0; 4]);
    let d = Some([1.0, 0.0, 0.0, 0.0]);
    vec![
        ([0.2, -1.0, 0.25, 1.0], e, d, Shape::Touch(Side::Lower)),
        ([0.8, 1.0, 0.75, -1.0], e, d, Shape::Touch(Side::Upper)),
        ([0.5, -6.0, 0.5, 6.0], e, None, Shape::Subarc(Side::Lower)),
        ([0.5, 6.0, 0.5, -6.0], None, d, Shape::Subarc(Side::Upper)),
        ([0.5, -8.0, 0.5, -8.0], e, d, Shape::Pair(Side::Lower)),
        ([0.5, 8.0, 0.5, 8.0], e, d, Shape::Pair(Side::Upper)),
        // sloped bounds and a non-unit interval
        (
            [0.5, -3.0, 0.6, -2.0],
            Some([0.0, 0.05, 0.0, 0.0]),
            Some([1.0, 0.025, 0.0, 0.0]),
            Shape::Touch(Side::Lower),
        ),
    ]
}

#[test]
fn each_candidate_kind_is_exact() {
    for (k, (th, lo, up, want)) in designed_cells().into_iter().enumerate() {
        let h = if k == 6 { 2.0 } else { 1.0 };
        let r = solve_interval(h, th, lo, up, Pruning::None).unwrap();
        assert_eq!(r.shape, want, "cell {k}");
        assert!(r.certified, "cell {k}");
        assert!(
            r.c2_residual <= 1e-9,
            "cell {k}: C² residual {}",
            r.c2_residual
        );
        assert!(r.margin >= -1e-12, "cell {k}: margin {}", r.margin);
        // Hermite data reproduced at both ends
        let (s0, c0) = r.pieces[0];
        assert!((c0[0] - th[0]).abs() < 1e-14 && (c0[1] - th[1]).abs() < 1e-13);
        let (sl, cl) = *r.pieces.last().unwrap();
        let l = h - sl;
        let f1 = cl[0] + l * (cl[1] + l * (cl[2] + l * cl[3]));
        let d1 = cl[1] + l * (2.0 * cl[2] + 3.0 * l * cl[3]);
        assert!(
            (f1 - th[2]).abs() < 1e-12 && (d1 - th[3]).abs() < 1e-10,
            "cell {k}"
        );
        assert!(s0.abs() < 1e-300);
        // contact: f = bound and f' = bound' at every extra knot (tangency)
        for (j, &x) in r.knots.iter().enumerate() {
            let side = match want {
                Shape::Touch(s) | Shape::Subarc(s) => s,
                Shape::Pair(s) if j == 0 => s,
                Shape::Pair(Side::Lower) => Side::Upper,
                Shape::Pair(Side::Upper) => Side::Lower,
                Shape::Free => unreachable!(),
            };
            let g = if side == Side::Lower {
                lo.unwrap()
            } else {
                up.unwrap()
            };
            let (_, c) = r.pieces[j + 1];
            let gv = g[0] + x * (g[1] + x * (g[2] + x * g[3]));
            let gd = g[1] + x * (2.0 * g[2] + 3.0 * x * g[3]);
            assert!(
                (c[0] - gv).abs() < 1e-12 && (c[1] - gd).abs() < 1e-10,
                "cell {k} knot {j}"
            );
        }
        // on a subarc of a linear bound f'' = 0
        if let Shape::Subarc(_) = want {
            let (_, c) = r.pieces[1];
            assert!(c[2].abs() < 1e-10 && c[3].abs() < 1e-9);
        }
    }
}

/// φ by re-solving the interval.
fn phi(h: f64, th: [f64; 4], lo: Option<[f64; 4]>, up: Option<[f64; 4]>) -> f64 {
    solve_interval(h, th, lo, up, Pruning::None).unwrap().energy
}

#[test]
fn gradient_and_hessian_match_finite_differences_in_every_kind() {
    for (k, (th, lo, up, _)) in designed_cells().into_iter().enumerate() {
        let h = if k == 6 { 2.0 } else { 1.0 };
        let r = solve_interval(h, th, lo, up, Pruning::None).unwrap();
        let d = 1e-6;
        for a in 0..4 {
            let mut tp = th;
            let mut tm = th;
            tp[a] += d;
            tm[a] -= d;
            let fd = (phi(h, tp, lo, up) - phi(h, tm, lo, up)) / (2.0 * d);
            assert!(
                (fd - r.grad[a]).abs() <= 1e-6 * (1.0 + r.grad[a].abs()),
                "cell {k} ∂φ/∂θ{a}: analytic {} fd {fd}",
                r.grad[a]
            );
            let gp = solve_interval(h, tp, lo, up, Pruning::None).unwrap().grad;
            let gm = solve_interval(h, tm, lo, up, Pruning::None).unwrap().grad;
            for b in 0..4 {
                let fdh = (gp[b] - gm[b]) / (2.0 * d);
                assert!(
                    (fdh - r.hess[b][a]).abs() <= 1e-4 * (1.0 + r.hess[b][a].abs()),
                    "cell {k} H[{b}][{a}]: implicit {} fd {fdh}",
                    r.hess[b][a]
                );
            }
        }
        // ∂φ/∂z0 = −2 f''(a+), ∂φ/∂z1 = 2 f''(b−) from the pieces themselves
        let c0 = r.pieces[0].1;
        assert!((r.grad[1] + 2.0 * 2.0 * c0[2]).abs() <= 1e-10 * (1.0 + r.grad[1].abs()));
        let (sl, cl) = *r.pieces.last().unwrap();
        let f2b = 2.0 * cl[2] + 6.0 * cl[3] * (h - sl);
        assert!((r.grad[3] - 2.0 * f2b).abs() <= 1e-10 * (1.0 + r.grad[3].abs()));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(192))]

    /// The seed's pruning rules and the certificate rule never change the answer.
    #[test]
    fn pruning_never_changes_the_answer(
        h in 0.2f64..3.0,
        lo0 in -1.0f64..0.0, lo1 in -1.0f64..0.0,
        up0 in 0.0f64..1.0, up1 in 0.0f64..1.0,
        a0 in 0.05f64..0.95, a1 in 0.05f64..0.95,
        z0 in -15.0f64..15.0, z1 in -15.0f64..15.0,
    ) {
        // bounds e: lo0 → lo1 − 0.2, d: up0 + 0.2 → up1 + 0.2 (width ≥ 0.2), data inside
        let e = [lo0 - 0.2, (lo1 - lo0) / h, 0.0, 0.0];
        let d = [up0 + 0.2, (up1 - up0) / h, 0.0, 0.0];
        let y0 = e[0] + a0 * (d[0] - e[0]);
        let (e1, d1) = (e[0] + e[1] * h, d[0] + d[1] * h);
        let y1 = e1 + a1 * (d1 - e1);
        let th = [y0, z0, y1, z1];
        let all = solve_interval(h, th, Some(e), Some(d), Pruning::None).unwrap();
        for pr in [Pruning::Seed, Pruning::Certificate] {
            let p = solve_interval(h, th, Some(e), Some(d), pr).unwrap();
            prop_assert!((p.energy - all.energy).abs() <= 1e-9 * all.energy.max(1e-12),
                "{pr:?}: {} vs {}", p.energy, all.energy);
            prop_assert!(p.candidates <= all.candidates);
        }
        prop_assert!(all.certified);
        prop_assert!(all.margin >= -1e-9);
    }

    /// The analytic gradient of φ matches central differences on random cells (Φ is C¹ even
    /// across candidate regions, so this holds everywhere up to O(δ)).
    #[test]
    fn gradient_matches_finite_differences(
        a0 in 0.05f64..0.95, a1 in 0.05f64..0.95,
        z0 in -12.0f64..12.0, z1 in -12.0f64..12.0,
    ) {
        let e = Some([0.0, 0.1, 0.0, 0.0]);
        let d = Some([1.0, -0.1, 0.0, 0.0]);
        let h = 1.3;
        let th = [a0, z0, 0.13 + a1 * (0.74), z1];
        let r = solve_interval(h, th, e, d, Pruning::Certificate).unwrap();
        let dl = 1e-6;
        for a in 0..4 {
            let mut tp = th;
            let mut tm = th;
            tp[a] += dl;
            tm[a] -= dl;
            let fd = (phi(h, tp, e, d) - phi(h, tm, e, d)) / (2.0 * dl);
            prop_assert!((fd - r.grad[a]).abs() <= 1e-5 * (1.0 + r.grad[a].abs()),
                "θ{a}: {} vs {fd} ({:?})", r.grad[a], r.shape);
        }
    }
}

#[test]
fn end_slopes_and_a_cubic_bound_piece() {
    // Example 5.2-like: bounds jump at data sites, the lower bound is cubic in the fourth
    // interval, end slopes −2 and −2.
    let t: Vec<f64> = (0..9).map(|i| 2.0 * i as f64).collect();
    let y = vec![1.0, 1.6, 0.8, 1.4, 1.0, 1.5, 0.7, 1.2, 0.9];
    let n = t.len();
    let mut lo: Vec<[f64; 4]> = (0..n - 1)
        .map(|i| [0.65 - 0.05 * (i % 2) as f64, 0.0, 0.0, 0.0])
        .collect();
    lo[3] = [1.35, -0.05, 0.0, -0.05]; // cubic: 1.35 − 0.05 s − 0.05 s³ on [6, 8]
    let up: Vec<[f64; 4]> = (0..n - 1)
        .map(|i| [1.72 - 0.1 * (i % 3) as f64, 0.0, 0.0, 0.0])
        .collect();
    let p = Problem {
        t,
        y,
        lower: Bound::Pieces(lo),
        upper: Bound::Pieces(up),
        end_slopes: [Some(-2.0), Some(-2.0)],
    };
    let s = solve(&p, &Options::default()).unwrap();
    assert!((s.slopes[0] + 2.0).abs() < 1e-14 && (s.slopes[n - 1] + 2.0).abs() < 1e-14);
    assert_structure(&p, &s);
    // the end slopes force contacts at both ends, and the cubic piece is touched
    assert_eq!(s.shapes[0], Shape::Touch(Side::Lower));
    assert_eq!(s.shapes[7], Shape::Touch(Side::Upper));
    assert_eq!(s.shapes[3], Shape::Touch(Side::Lower));
    let lb = common::qp_lower_bound(&p, &common::qp_grid(&p, 16, Some(&s)));
    let rel = (s.energy - lb) / s.energy;
    assert!((-1e-9..=1e-6).contains(&rel), "gap {rel:e}");
}

#[test]
fn polyline_bounds_converge_as_the_grid_refines() {
    // §4, Theorem 4.1: e(t) = −0.6 + 0.3 sin(2t), d(t) = 0.6 + 0.25 cos(3t) approximated by
    // polylines on m cells; the solutions converge as m grows.
    let t = vec![0.0, 1.0, 2.0, 3.0, 4.0];
    let y = vec![0.0, 0.2, -0.3, 0.3, 0.0];
    let e = |x: f64| -0.6 + 0.3 * (2.0 * x).sin();
    let d = |x: f64| 0.6 + 0.25 * (3.0 * x).cos();
    let mut energies = Vec::new();
    let mut sols = Vec::new();
    for m in [8, 16, 32, 64, 128] {
        let p = Problem {
            t: t.clone(),
            y: y.clone(),
            lower: Bound::from_fn(e, 0.0, 4.0, m),
            upper: Bound::from_fn(d, 0.0, 4.0, m),
            end_slopes: [Some(3.0), Some(3.0)],
        };
        let s = solve(&p, &Options::default()).unwrap();
        assert!(common::max_violation(&p, &s, 8000) <= 1e-9);
        // converged: the gap estimate is negligible
        assert!(s.gap <= 1e-10, "m = {m}: gap {}", s.gap);
        // optimal for the polyline problem: against the Clarabel lower bound of that problem
        let lb = common::qp_lower_bound(&p, &common::qp_grid(&p, 40, Some(&s)));
        let gap = (s.energy - lb) / s.energy;
        assert!(
            (-1e-9..=1e-6).contains(&gap),
            "m = {m}: energy {} lower bound {lb}",
            s.energy
        );
        energies.push(s.energy);
        sols.push(s);
    }
    // successive differences shrink (W^{2,2} convergence implies energy convergence)
    let diffs: Vec<f64> = energies.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    assert!(diffs[3] < diffs[0] * 0.25, "energies {energies:?}");
    // and the functions converge uniformly
    let last = sols.last().unwrap();
    let dist = |s: &strip::Solution| {
        (0..=400).fold(0.0f64, |a, k| {
            let x = 4.0 * k as f64 / 400.0;
            a.max((s.eval(x) - last.eval(x)).abs())
        })
    };
    assert!(dist(&sols[3]) < dist(&sols[0]), "no uniform convergence");
}

#[test]
fn data_on_a_bound_remark_4_2() {
    // y_2 = e(t_2) exactly: the point is moved inside by ε·width and the solutions converge as
    // ε → 0.
    // The lower bound peaks at the data point (a valley would make the problem infeasible:
    // f'(t_2) ≤ e'(t_2−) and f'(t_2) ≥ e'(t_2+) must both hold).
    let mut p = polygon_strip(&[0.0, 1.0, 0.0, 1.0, 0.0], 0.2);
    if let Bound::Pieces(lo) = &mut p.lower {
        lo[1] = [-0.5, 0.5, 0.0, 0.0]; // e on [1, 2] rises to y_2 = 0
        lo[2] = [0.0, -0.5, 0.0, 0.0]; // and falls after it
    }
    let mut prev = None;
    let mut gaps = Vec::new();
    for eps in [1e-2, 1e-3, 1e-4, 1e-5] {
        let s = solve(
            &p,
            &Options {
                boundary_margin: eps,
                ..Options::default()
            },
        )
        .unwrap();
        assert_eq!(s.shifted_data, vec![2]);
        assert!(common::max_violation(&p, &s, 4000) <= 1e-9);
        if let Some(e) = prev {
            gaps.push(((s.energy - e) as f64).abs());
        }
        prev = Some(s.energy);
    }
    assert!(gaps[2] < gaps[0], "no convergence: {gaps:?}");
}

#[test]
fn bad_input_is_a_typed_error() {
    let good = polygon_strip(&Y16, 0.2);
    let mut p = good.clone();
    p.y[4] += 0.5;
    assert!(matches!(
        solve(&p, &Options::default()),
        Err(Error::Infeasible {
            field: "y",
            index: 4,
            reason: Infeasibility::OutsideBound {
                side: Side::Upper,
                ..
            }
        })
    ));
    let mut p = good.clone();
    if let Bound::Pieces(up) = &mut p.upper {
        up[6] = [-5.0, 0.0, 0.0, 0.0];
    }
    assert!(matches!(
        solve(&p, &Options::default()),
        Err(Error::Infeasible {
            field: "lower.pieces",
            index: 6,
            reason: Infeasibility::Closed { .. }
        })
    ));
    let mut p = good.clone();
    p.t[3] = p.t[2];
    assert_eq!(
        solve(&p, &Options::default()),
        Err(Error::NonIncreasing {
            field: "t",
            index: 3
        })
    );
    let mut p = good.clone();
    p.y[7] = f64::NAN;
    assert_eq!(
        solve(&p, &Options::default()),
        Err(Error::NonFinite {
            field: "y",
            index: 7
        })
    );
    let mut p = good.clone();
    if let Bound::Pieces(lo) = &mut p.lower {
        lo[3][2] = f64::INFINITY;
    }
    assert_eq!(
        solve(&p, &Options::default()),
        Err(Error::NonFinite {
            field: "lower.pieces",
            index: 3
        })
    );
    let mut p = good.clone();
    if let Bound::Pieces(lo) = &mut p.lower {
        lo.pop();
    }
    assert!(matches!(
        solve(&p, &Options::default()),
        Err(Error::WrongLength {
            field: "lower.pieces",
            ..
        })
    ));
    let p = Problem {
        t: vec![0.0],
        y: vec![1.0],
        ..Problem::default()
    };
    assert_eq!(
        solve(&p, &Options::default()),
        Err(Error::TooFew {
            field: "t",
            minimum: 2,
            got: 1
        })
    );
    let mut p = good;
    p.lower = Bound::Polyline(vec![[1.0, -5.0], [15.0, -5.0]]);
    assert!(matches!(
        solve(&p, &Options::default()),
        Err(Error::InvalidValue {
            field: "lower.polyline",
            index: 0,
            ..
        })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random small problems (jumping linear bounds, optional end slopes): the solution is
    /// feasible, C², and its energy lies within 1e-6 above Clarabel's lower bound.
    #[test]
    fn random_problems_are_optimal(
        ys in proptest::collection::vec(-1.0f64..1.0, 6),
        hs in proptest::collection::vec(0.3f64..2.0, 5),
        below in proptest::collection::vec((0.05f64..0.6, -0.3f64..0.3), 5),
        above in proptest::collection::vec((0.05f64..0.6, -0.3f64..0.3), 5),
        s0 in proptest::option::of(-3.0f64..3.0),
        s1 in proptest::option::of(-3.0f64..3.0),
    ) {
        let mut t = vec![0.0];
        for h in &hs {
            t.push(t.last().unwrap() + h);
        }
        // bounds: through y_i − w and y_{i+1} − w' (kept below both data values), tilted
        let lo: Vec<[f64; 4]> = (0..5).map(|i| {
            let (w, tilt) = below[i];
            let a = ys[i] - w - tilt.max(0.0);
            let b = ys[i + 1] - w + tilt.min(0.0);
            [a, (b - a) / hs[i], 0.0, 0.0]
        }).collect();
        let up: Vec<[f64; 4]> = (0..5).map(|i| {
            let (w, tilt) = above[i];
            let a = ys[i] + w + tilt.max(0.0);
            let b = ys[i + 1] + w - tilt.min(0.0);
            [a, (b - a) / hs[i], 0.0, 0.0]
        }).collect();
        let p = Problem { t, y: ys, lower: Bound::Pieces(lo), upper: Bound::Pieces(up), end_slopes: [s0, s1] };
        let s = solve(&p, &Options::default()).unwrap();
        prop_assert!(common::max_violation(&p, &s, 5000) <= 1e-10);
        prop_assert!(s.uncertified.is_empty());
        let lb = common::qp_lower_bound(&p, &common::qp_grid(&p, 16, Some(&s)));
        let gap = (s.energy - lb) / s.energy.max(1e-12);
        prop_assert!((-1e-8..=1e-6).contains(&gap), "energy {} lower bound {lb}", s.energy);
    }
}

#[test]
fn two_points_without_bounds() {
    // natural ends: the straight line (∫f''² = 0); clamped: the Hermite cubic, whose energy is
    // the closed form (4/h)(z0² + z0z1 + z1²) − (12Δ/h)(z0 + z1) + 12Δ²/h (math.md §4)
    let p = Problem {
        t: vec![1.0, 3.0],
        y: vec![0.5, 1.5],
        ..Problem::default()
    };
    let s = solve(&p, &Options::default()).unwrap();
    assert!(s.energy.abs() < 1e-24 && (s.eval(2.0) - 1.0).abs() < 1e-15);
    let p = Problem {
        end_slopes: [Some(-1.0), Some(2.0)],
        ..p
    };
    let s = solve(&p, &Options::default()).unwrap();
    let (h, d, z0, z1) = (2.0, 0.5, -1.0, 2.0);
    let e = 4.0 / h * (z0 * z0 + z0 * z1 + z1 * z1) - 12.0 * d / h * (z0 + z1) + 12.0 * d * d / h;
    assert!((s.energy - e).abs() < 1e-13 * e);
    assert_eq!(s.iterations, 0);
}
