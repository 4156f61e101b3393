//! Verification cases for `strip` (Dontchev–Kolmanovsky, seed 002; math.md §4).

use super::{Case, Outcome};
use strip::interval::solve_interval;
use strip::{solve, Bound, Method, Options, Problem, Pruning, Shape, Side, Solution};
use strip_testkit::examples::{example_5_1, example_5_2, example_5_3, polygon_strip, Y16};

/// min(primal, dual) of the lower-bound QP (see `strip_testkit::lower_bound_qp`) solved by
/// Clarabel.
fn qp_lower_bound(p: &Problem, extra: &[f64]) -> anyhow::Result<f64> {
    let lb = strip_testkit::lower_bound(p, extra, true).map_err(|e| anyhow::anyhow!(e))?;
    anyhow::ensure!(
        lb.solved || lb.status == "AlmostSolved",
        "clarabel: {}",
        lb.status
    );
    Ok(lb.value)
}

/// QP grid: `per` uniform points per data interval plus points clustered at every break.
fn qp_grid(p: &Problem, per: usize, s: &Solution) -> Vec<f64> {
    let t = &p.t;
    let mut g = Vec::new();
    for w in t.windows(2) {
        for k in 1..per {
            g.push(w[0] + (w[1] - w[0]) * k as f64 / per as f64);
        }
    }
    let span = t[t.len() - 1] - t[0];
    for b in s.breaks.iter().chain(s.extra_knots.iter().map(|k| &k.t)) {
        g.push(*b);
        for e in 1..8 {
            let d = span * 1e-2 * 0.5f64.powi(e);
            g.push(b - d);
            g.push(b + d);
        }
    }
    g.retain(|x| *x > t[0] && *x < t[t.len() - 1]);
    g.sort_by(f64::total_cmp);
    g.dedup_by(|a, b| (*a - *b).abs() < 1e-13);
    g
}

fn bound_at(b: &Bound, i: usize, ti: f64, x: f64) -> Option<f64> {
    match b {
        Bound::Pieces(p) => {
            let (c, s) = (p[i], x - ti);
            Some(c[0] + s * (c[1] + s * (c[2] + s * c[3])))
        }
        Bound::Polyline(p) => {
            let k = p.partition_point(|v| v[0] <= x).clamp(1, p.len() - 1);
            let (a, b) = (p[k - 1], p[k]);
            Some(a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]))
        }
        _ => None,
    }
}

/// Largest bound violation over a dense sample plus the breaks.
fn violation(p: &Problem, s: &Solution) -> f64 {
    let t = &p.t;
    let n = t.len();
    let mut xs: Vec<f64> = (0..=20_000)
        .map(|k| t[0] + (t[n - 1] - t[0]) * k as f64 / 20_000.0)
        .collect();
    xs.extend(&s.breaks);
    xs.iter().fold(0.0f64, |w, &x| {
        let i = t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
        let f = s.eval(x);
        let lo = bound_at(&p.lower, i, t[i], x).map_or(0.0, |e| e - f);
        let up = bound_at(&p.upper, i, t[i], x).map_or(0.0, |d| f - d);
        w.max(lo).max(up)
    })
}

/// Largest relative jump of f, f', f'' across the breaks.
fn c2_residual(s: &Solution) -> f64 {
    let mut r = 0.0f64;
    for j in 1..s.coefficients.len() {
        let c = s.coefficients[j - 1];
        let h = s.breaks[j] - s.breaks[j - 1];
        let left = [
            c[0] + h * (c[1] + h * (c[2] + h * c[3])),
            c[1] + h * (2.0 * c[2] + 3.0 * h * c[3]),
            2.0 * c[2] + 6.0 * h * c[3],
        ];
        let q = s.coefficients[j];
        let right = [q[0], q[1], 2.0 * q[2]];
        for d in 0..3 {
            r = r.max((left[d] - right[d]).abs() / (1.0 + right[d].abs()));
        }
    }
    r
}

fn optimality_gap(p: &Problem, per: usize) -> anyhow::Result<Outcome> {
    let s = solve(p, &Options::default())?;
    let lb = qp_lower_bound(p, &qp_grid(p, per, &s))?;
    let gap = (s.energy - lb) / s.energy;
    // the energy must not be below the lower bound (beyond solver accuracy) and within 1e-6 of it
    let residual = if gap < -1e-9 {
        f64::INFINITY
    } else {
        gap.abs()
    };
    Ok(Outcome::check(
        residual,
        1e-6,
        format!(
            "∫f''² = {:.12} vs Clarabel lower bound {:.12} (grid of {} points)",
            s.energy,
            lb,
            qp_grid(p, per, &s).len() + p.t.len()
        ),
    ))
}

/// Natural spline by the moment formulation (independent of the solver's slope formulation).
fn natural_spline(t: &[f64], y: &[f64], x: f64) -> f64 {
    let n = t.len();
    let h: Vec<f64> = (0..n - 1).map(|i| t[i + 1] - t[i]).collect();
    let (mut b, mut c, mut r) = (vec![1.0; n], vec![0.0; n], vec![0.0; n]);
    let mut a = vec![0.0; n];
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
    let i = t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
    let (p, q) = ((t[i + 1] - x) / h[i], (x - t[i]) / h[i]);
    p * y[i]
        + q * y[i + 1]
        + ((p * p * p - p) * m[i] + (q * q * q - q) * m[i + 1]) * h[i] * h[i] / 6.0
}

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    vec![
        Case::holds("strip/holladay/inactive-strip-is-natural-spline", || {
            let p = polygon_strip(&Y16, 3.0);
            let s = solve(&p, &Options::default())?;
            let r = (0..=3000).fold(0.0f64, |m, k| {
                let x = 15.0 * k as f64 / 3000.0;
                m.max((s.eval(x) - natural_spline(&p.t, &p.y, x)).abs() / 3.0)
            });
            Ok(Outcome::check(
                r,
                1e-12,
                format!(
                    "max |f − natural spline| / max|y|; {} extra knots",
                    s.extra_knots.len()
                ),
            ))
        }),
        Case::holds("strip/thm2.1/structure-example-5.1", || {
            let p = example_5_1();
            let s = solve(&p, &Options::default())?;
            let per_interval_ok = (0..p.t.len() - 1)
                .all(|j| s.extra_knots.iter().filter(|k| k.interval == j).count() <= 2);
            let ends_ok = !matches!(s.shapes[0], Shape::Subarc(_))
                && !matches!(s.shapes[s.shapes.len() - 1], Shape::Subarc(_));
            let f2 = s
                .derivative(p.t[0], 2)
                .abs()
                .max(s.derivative(p.t[15] - 1e-12, 2).abs());
            let r = c2_residual(&s).max(violation(&p, &s)).max(f2);
            anyhow::ensure!(per_interval_ok && ends_ok, "structure: {:?}", s.shapes);
            // as in the paper's Figure 2: five single touching points, a subarc in the 12th
            // interval and a touching pair in the 14th (nine extra knots)
            let touches = s
                .shapes
                .iter()
                .filter(|x| matches!(x, Shape::Touch(_)))
                .count();
            anyhow::ensure!(
                s.extra_knots.len() == 9
                    && touches == 5
                    && matches!(s.shapes[11], Shape::Subarc(_))
                    && matches!(s.shapes[13], Shape::Pair(_)),
                "not the paper's structure: {:?}",
                s.shapes
            );
            Ok(Outcome::check(r, 1e-8, format!(
                "max(C² jump, bound violation, |f''(t1)|, |f''(tn)|); ≤2 knots/interval, no end subarc; 9 extra knots: 5 touches, subarc in interval 12, pair in 14 (as Fig. 2); ‖f''‖ = {:.4}", s.norm)))
        }),
        Case::holds("strip/thm2.1/every-kind-active", || {
            let s = solve(&polygon_strip(&Y16, 0.1), &Options::default())?;
            let kinds = [
                Shape::Touch(Side::Lower),
                Shape::Touch(Side::Upper),
                Shape::Subarc(Side::Lower),
                Shape::Subarc(Side::Upper),
                Shape::Pair(Side::Lower),
                Shape::Pair(Side::Upper),
            ];
            let missing: Vec<_> = kinds.iter().filter(|k| !s.shapes.contains(k)).collect();
            Ok(Outcome::flag(
                missing.is_empty(),
                format!("16 points, strip ±0.1: all six contact kinds active; missing {missing:?}"),
            ))
        }),
        Case::holds("strip/sec3/gradient-vs-finite-differences", || {
            let e = Some([0.0, 0.1, 0.0, 0.0]);
            let d = Some([1.0, -0.1, 0.0, 0.0]);
            let mut worst = 0.0f64;
            let mut kinds = std::collections::BTreeSet::new();
            for k in 0..60 {
                let z0 = -12.0 + 24.0 * ((k * 37) % 60) as f64 / 60.0;
                let z1 = -12.0 + 24.0 * ((k * 17 + 5) % 60) as f64 / 60.0;
                let th = [0.3 + 0.01 * k as f64, z0, 0.5 - 0.005 * k as f64, z1];
                let r = solve_interval(1.3, th, e, d, Pruning::None)
                    .ok_or_else(|| anyhow::anyhow!("no candidate"))?;
                kinds.insert(format!("{:?}", r.shape));
                for a in 0..4 {
                    let dl = 1e-6;
                    let (mut tp, mut tm) = (th, th);
                    tp[a] += dl;
                    tm[a] -= dl;
                    let f =
                        |t: [f64; 4]| solve_interval(1.3, t, e, d, Pruning::None).map(|r| r.energy);
                    let (Some(fp), Some(fm)) = (f(tp), f(tm)) else {
                        continue;
                    };
                    let fd = (fp - fm) / (2.0 * dl);
                    worst = worst.max((fd - r.grad[a]).abs() / (1.0 + r.grad[a].abs()));
                }
            }
            Ok(Outcome::check(worst, 1e-5, format!(
                "∂φ/∂(y0,z0,y1,z1) = (2f'''(a+), −2f''(a+), −2f'''(b−), 2f''(b−)) vs central differences, 60 cells, kinds {kinds:?}")))
        }),
        Case::holds("strip/sec3/pruning-never-changes-the-answer", || {
            let mut worst = 0.0f64;
            let (mut all, mut seed, mut cert) = (0, 0, 0);
            for k in 0..400 {
                let u = |m: usize| ((k * m + 7) % 101) as f64 / 101.0;
                let h = 0.3 + 2.0 * u(13);
                let e = [-0.2 - 0.8 * u(3), (0.8 * u(5) - 0.4) / h, 0.0, 0.0];
                let d = [0.2 + 0.8 * u(7), (0.8 * u(11) - 0.4) / h, 0.0, 0.0];
                let (e1, d1) = (e[0] + e[1] * h, d[0] + d[1] * h);
                let th = [
                    e[0] + (0.05 + 0.9 * u(17)) * (d[0] - e[0]),
                    30.0 * u(19) - 15.0,
                    e1 + (0.05 + 0.9 * u(23)) * (d1 - e1),
                    30.0 * u(29) - 15.0,
                ];
                let r = |pr| {
                    solve_interval(h, th, Some(e), Some(d), pr)
                        .ok_or_else(|| anyhow::anyhow!("cell {k}: no candidate"))
                };
                let (a, b, c) = (
                    r(Pruning::None)?,
                    r(Pruning::Seed)?,
                    r(Pruning::Certificate)?,
                );
                all += a.candidates;
                seed += b.candidates;
                cert += c.candidates;
                worst = worst.max(
                    (a.energy - b.energy).abs().max((a.energy - c.energy).abs())
                        / a.energy.max(1e-12),
                );
            }
            Ok(Outcome::check(worst, 1e-9, format!(
                "400 random cells: max relative energy difference; candidates examined: all {all}, seed rules {seed}, certificate {cert}")))
        }),
        Case::holds("strip/sec3/newton-equals-argmin-bfgs", || {
            let p = example_5_1();
            let a = solve(&p, &Options::default())?;
            let b = solve(
                &p,
                &Options {
                    method: Method::Bfgs,
                    ..Options::default()
                },
            )?;
            Ok(Outcome::check(
                (a.energy - b.energy).abs() / a.energy,
                1e-9,
                format!(
                    "Newton {} iterations, BFGS {} iterations; energies {:.12} / {:.12}",
                    a.iterations, b.iterations, a.energy, b.energy
                ),
            ))
        }),
        Case::holds("strip/optimality/example-5.1-vs-clarabel", || {
            optimality_gap(&example_5_1(), 16)
        }),
        Case::holds("strip/optimality/strip-0.1-vs-clarabel", || {
            optimality_gap(&polygon_strip(&Y16, 0.1), 16)
        }),
        Case::holds("strip/ex5.2/end-slopes-cubic-piece-vs-clarabel", || {
            optimality_gap(&example_5_2(), 16)
        }),
        Case::holds("strip/ex5.3/remark4.2-polyline-vs-clarabel", || {
            optimality_gap(&example_5_3(), 400)
        }),
        Case::holds("strip/sec4/thm4.1-refining-grids-converge", || {
            let t = vec![0.0, 1.0, 2.0, 3.0, 4.0];
            let y = vec![0.0, 0.2, -0.3, 0.3, 0.0];
            let e = |x: f64| -0.6 + 0.3 * (2.0 * x).sin();
            let d = |x: f64| 0.6 + 0.25 * (3.0 * x).cos();
            let mut en = Vec::new();
            for m in [8, 16, 32, 64, 128, 256] {
                let p = Problem {
                    t: t.clone(),
                    y: y.clone(),
                    lower: Bound::from_fn(e, 0.0, 4.0, m),
                    upper: Bound::from_fn(d, 0.0, 4.0, m),
                    end_slopes: [Some(3.0), Some(3.0)],
                };
                en.push(solve(&p, &Options::default())?.energy);
            }
            let diffs: Vec<f64> = en.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
            let last = diffs[diffs.len() - 1] / en[en.len() - 1];
            anyhow::ensure!(diffs[4] < diffs[0], "energies do not settle: {en:?}");
            Ok(Outcome::check(
                last,
                1e-3,
                format!(
                    "∫f''² on m = 8..256 cells: {:?}; relative change of the last refinement",
                    en.iter().map(|v| format!("{v:.6}")).collect::<Vec<_>>()
                ),
            ))
        }),
        Case::holds("strip/remark4.2/data-on-bound-converges", || {
            let mut p = polygon_strip(&[0.0, 1.0, 0.0, 1.0, 0.0], 0.2);
            if let Bound::Pieces(lo) = &mut p.lower {
                lo[1] = [-0.5, 0.5, 0.0, 0.0];
                lo[2] = [0.0, -0.5, 0.0, 0.0];
            }
            let mut en = Vec::new();
            for eps in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
                en.push(
                    solve(
                        &p,
                        &Options {
                            boundary_margin: eps,
                            ..Options::default()
                        },
                    )?
                    .energy,
                );
            }
            let r = (en[4] - en[3]).abs() / en[4];
            Ok(Outcome::check(
                r,
                1e-4,
                format!("y_2 on e: ∫f''² for ε = 1e-2..1e-6: {en:?}"),
            ))
        }),
        Case::holds("strip/errors/typed-and-named", || {
            let mut p = polygon_strip(&Y16, 0.2);
            p.y[4] += 0.5;
            let e1 = solve(&p, &Options::default()).err();
            let mut p = polygon_strip(&Y16, 0.2);
            if let Bound::Pieces(up) = &mut p.upper {
                up[6] = [-5.0, 0.0, 0.0, 0.0];
            }
            let e2 = solve(&p, &Options::default()).err();
            let ok = matches!(
                e1,
                Some(strip::Error::Infeasible {
                    field: "y",
                    index: 4,
                    ..
                })
            ) && matches!(
                e2,
                Some(strip::Error::Infeasible {
                    field: "upper.pieces" | "lower.pieces",
                    index: 6,
                    ..
                })
            );
            Ok(Outcome::flag(ok, format!("{e1:?}; {e2:?}")))
        }),
    ]
}
