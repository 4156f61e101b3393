//! Benchmarks for `strip`: the seed-like 16-point example (Newton on Φ and the seed's BFGS), a
//! size sweep of cubic-piece strips with many active intervals, and the hard channels of issue 15
//! (steep tanh fronts, narrow bumps, polyline bounds with M vertices) against Clarabel's
//! fine-grid QP on the same vertices, measured in the same run through `strip::solve` (the
//! library entry point) and, for one row, through the `curvefit` binary end to end; and hard
//! data as users bring it: jittered noisy sites in a narrow channel, a contact in nearly every
//! interval.

use std::time::Duration;

use super::{time_median, Opts};
use strip::{solve, Bound, Method, Options, Problem, Shape};
use strip_testkit::examples::{example_5_1, large};
use strip_testkit::{BoundKind, Channel};

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The issue-15 channel with M polyline vertices and n sites (seed 1).
fn channel(m: usize, n: usize) -> Problem {
    Channel {
        breakpoints: m,
        sites: n,
        ..Channel::default()
    }
    .problem()
}

/// n jittered noisy sites in a narrow channel: spacing 0.2–1.2, y = sin(0.7 t) + 0.3·u (u
/// uniform in [0, 1), a fixed LCG), polyline bounds ±0.02 about the data — the natural spline
/// leaves the channel in nearly every interval, and the answer has about 1.5 contacts a site.
fn noisy_channel(n: usize) -> Problem {
    let mut unif = super::uniform(0x2545_F491_4F6C_DD1D);
    let mut t = vec![0.0];
    for _ in 1..n {
        let last = t[t.len() - 1];
        t.push(last + 0.2 + unif());
    }
    let y: Vec<f64> = t.iter().map(|x| (0.7 * x).sin() + 0.3 * unif()).collect();
    let line = |off: f64| Bound::Polyline(t.iter().zip(&y).map(|(&t, &y)| [t, y + off]).collect());
    Problem {
        lower: line(-0.02),
        upper: line(0.02),
        t: t.clone(),
        y: y.clone(),
        end_slopes: [None, None],
    }
}

/// Clarabel on the lower-bound QP whose grid is every polyline vertex (the fine-grid QP a user
/// would hand to a conic solver), default settings: (time, status).
fn clarabel(p: &Problem) -> anyhow::Result<(Duration, String)> {
    let grid = strip_testkit::fine_grid(p, 1, None);
    let t = std::time::Instant::now();
    let lb = strip_testkit::lower_bound(p, &grid, false).map_err(|e| anyhow::anyhow!(e))?;
    Ok((t.elapsed(), lb.status))
}

/// Writes `p` as a `curvefit strip` problem to `path`.
fn write_problem(p: &Problem, path: &std::path::Path) -> anyhow::Result<()> {
    let bound = |b: &strip::Bound| match b {
        strip::Bound::None => serde_json::Value::Null,
        strip::Bound::Pieces(v) => serde_json::json!({ "pieces": v }),
        strip::Bound::Polyline(v) => serde_json::json!({ "polyline": v }),
    };
    let v = serde_json::json!({
        "t": p.t,
        "y": p.y,
        "lower": bound(&p.lower),
        "upper": bound(&p.upper),
    });
    std::fs::write(path, serde_json::to_vec(&v)?)?;
    Ok(())
}

/// Median wall time of the release `curvefit strip` on `p` (the binary next to this xtask), or
/// why not.
fn binary(p: &Problem, reps: usize) -> Result<Duration, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let bin = exe.with_file_name(format!("curvefit{}", std::env::consts::EXE_SUFFIX));
    if !bin.exists() {
        return Err(format!(
            "{} not built (cargo build --release -p curvefit)",
            bin.display()
        ));
    }
    let dir = exe
        .parent()
        .ok_or("no target directory")?
        .join("bench-strip");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let input = dir.join("channel.json");
    let output = dir.join("solution.json");
    write_problem(p, &input).map_err(|e| e.to_string())?;
    let mut failed = None;
    let t = time_median(reps, || {
        let st = std::process::Command::new(&bin)
            .arg("strip")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .status();
        if !matches!(st, Ok(s) if s.success()) {
            failed = Some(format!("{st:?}"));
        }
    });
    match failed {
        Some(e) => Err(format!("curvefit strip failed: {e}")),
        None => Ok(t),
    }
}

/// Runs this group and prints its tables.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let reps = if opts.quick { 3 } else { 11 };
    println!("## strip");
    let p16 = example_5_1();
    let s16 = solve(&p16, &Options::default())?;
    let t16 = time_median(reps * 5, || solve(&p16, &Options::default()));
    let bfgs = Options {
        method: Method::Bfgs,
        ..Options::default()
    };
    let tb = time_median(reps, || solve(&p16, &bfgs));
    println!(
        "16-point example (5.1-like, cubic pieces): Newton {:.3} ms ({} iterations, {} extra knots), argmin BFGS {:.3} ms (×{:.1})",
        ms(t16),
        s16.iterations,
        s16.extra_knots.len(),
        ms(tb),
        tb.as_secs_f64() / t16.as_secs_f64()
    );
    // the fine-grid QP of the same example (uniform grid of 10^4 points), as a user would solve it
    let m = if opts.quick { 2_000 } else { 10_000 };
    let (a, b) = (p16.t[0], p16.t[p16.t.len() - 1]);
    let grid: Vec<f64> = (1..m).map(|k| a + (b - a) * k as f64 / m as f64).collect();
    let qp = || strip_testkit::lower_bound(&p16, &grid, false);
    let tq = time_median(if opts.quick { 1 } else { 3 }, qp);
    let lb = qp().map_err(|e| anyhow::anyhow!(e))?;
    println!(
        "Clarabel fine-grid QP (M = {m}) on the same problem: {:.1} ms, {}, value {:.9} (exact {:.9}); exact solver {:.0}× faster",
        ms(tq),
        lb.status,
        lb.value,
        s16.energy,
        tq.as_secs_f64() / t16.as_secs_f64()
    );
    println!(
        "{:>8} {:>12} {:>10} {:>8} {:>14}",
        "n", "time [ms]", "active", "iters", "µs per point"
    );
    let sizes: &[usize] = if opts.quick {
        &[1_000, 3_000]
    } else {
        &[1_000, 3_000, 10_000, 30_000]
    };
    for &n in sizes {
        let p = large(n);
        let s = solve(&p, &Options::default())?;
        let t = time_median(if opts.quick { 1 } else { 3 }, || {
            solve(&p, &Options::default())
        });
        let active = s.shapes.iter().filter(|x| **x != Shape::Free).count();
        println!(
            "{n:>8} {:>12.2} {:>10} {:>8} {:>14.2}",
            ms(t),
            active,
            s.iterations,
            t.as_secs_f64() * 1e6 / n as f64
        );
    }

    println!();
    println!("issue-15 channels (5 tanh fronts of slope ~1e3, 3 bumps of width 0.004, half-width 0.01-0.04, seed 1): polyline bounds with M vertices, n sites; the exact exchange through strip::solve against Clarabel's QP on every vertex (default settings), same run");
    println!(
        "{:>9} {:>6} {:>10} {:>7} {:>7} {:>7} {:>10} {:>14} {:>12} {:>9}",
        "M",
        "n",
        "time [ms]",
        "sweeps",
        "steps",
        "knots",
        "gap",
        "Clarabel [ms]",
        "status",
        "ratio"
    );
    let rows: &[(usize, usize, bool)] = if opts.quick {
        &[
            (100, 16, true),
            (1_000, 16, true),
            (1_000, 200, true),
            (10_000, 16, false),
            (100_000, 16, false),
        ]
    } else {
        &[
            (100, 16, true),
            (1_000, 16, true),
            (1_000, 200, true),
            (10_000, 16, true),
            (10_000, 200, true),
            (10_000, 10_000, false),
            (100_000, 16, false),
            (100_000, 200, false),
            (1_000_000, 16, false),
        ]
    };
    for &(m, n, peer) in rows {
        let p = channel(m, n);
        let s = solve(&p, &Options::default())?;
        let r = if m >= 1_000_000 { 1 } else { reps.min(5) };
        let t = time_median(r, || solve(&p, &Options::default()));
        let (ct, status, ratio) = if peer {
            let (ct, status) = clarabel(&p)?;
            (
                format!("{:.1}", ms(ct)),
                status,
                format!("{:.0}×", ct.as_secs_f64() / t.as_secs_f64()),
            )
        } else {
            ("-".into(), "-".into(), "-".into())
        };
        println!(
            "{m:>9} {n:>6} {:>10.2} {:>7} {:>7} {:>7} {:>10.1e} {:>14} {:>12} {:>9}   {:.0} ns per breakpoint",
            ms(t),
            s.rounds,
            s.iterations,
            s.extra_knots.len(),
            s.gap,
            ct,
            status,
            ratio,
            t.as_secs_f64() * 1e9 / m as f64
        );
    }
    // 10^4 sites with piecewise-cubic bounds (Hermite cubics of the channel's bounds)
    let n = if opts.quick { 2_000 } else { 10_000 };
    let pc = Channel {
        sites: n,
        bounds: BoundKind::Pieces,
        ..Channel::default()
    }
    .problem();
    let s = solve(&pc, &Options::default())?;
    let t = time_median(reps.min(5), || solve(&pc, &Options::default()));
    println!(
        "{n} sites, piecewise-cubic bounds (the channel's Hermite cubics): {:.2} ms ({} Newton iterations, {} extra knots, gap {:.1e})",
        ms(t),
        s.iterations,
        s.extra_knots.len(),
        s.gap
    );
    // hard data: noisy sites in a narrow channel; Clarabel on the QP with 4 grid points per
    // interval (a relaxation of the strip, which it cannot state exactly), same run
    println!();
    println!("hard: jittered noisy sites in a channel ±0.02 (spacing 0.2-1.2, sin(0.7 t) + 0.3 noise), polyline bounds; strip::solve against Clarabel's QP on 4 grid points per interval (a relaxation), same run");
    println!(
        "{:>8} {:>10} {:>7} {:>9} {:>9} {:>9} {:>12} {:>14} {:>8}",
        "n",
        "time [ms]",
        "sweeps",
        "steps",
        "contacts",
        "gap",
        "µs per site",
        "Clarabel [ms]",
        "ratio"
    );
    let sizes: &[(usize, bool)] = if opts.quick {
        &[(1_000, true), (10_000, false)]
    } else {
        &[(1_000, true), (10_000, true), (100_000, false)]
    };
    for &(n, peer) in sizes {
        let p = noisy_channel(n);
        let t0 = std::time::Instant::now();
        let first = solve(&p, &Options::default());
        let once = t0.elapsed();
        let s = match first {
            Ok(s) => s,
            Err(e) => {
                println!("{n:>8} {:>10.0} refused: {e}", ms(once));
                continue;
            }
        };
        let t = if n >= 100_000 {
            once
        } else {
            time_median(reps.min(3), || solve(&p, &Options::default()))
        };
        let (ct, ratio) = if peer {
            let grid = strip_testkit::fine_grid(&p, 4, None);
            let t1 = std::time::Instant::now();
            let lb =
                strip_testkit::lower_bound(&p, &grid, false).map_err(|e| anyhow::anyhow!(e))?;
            let ct = t1.elapsed();
            (
                format!("{:.0} ({})", ms(ct), lb.status),
                format!("{:.0}×", ct.as_secs_f64() / t.as_secs_f64()),
            )
        } else {
            ("-".into(), "-".into())
        };
        println!(
            "{n:>8} {:>10.1} {:>7} {:>9} {:>9} {:>9.1e} {:>12.1} {:>14} {:>8}",
            ms(t),
            s.rounds,
            s.iterations,
            s.extra_knots.len(),
            s.gap,
            t.as_secs_f64() * 1e6 / n as f64,
            ct,
            ratio
        );
    }
    // end to end through the binary (JSON in and out, one process per solve)
    let p = channel(10_000, 16);
    let lib = time_median(reps.min(5), || solve(&p, &Options::default()));
    match binary(&p, if opts.quick { 1 } else { 3 }) {
        Ok(b) => println!(
            "curvefit strip, M = 10000, n = 16, end to end (process start, JSON read, solve, JSON write): {:.1} ms; strip::solve alone {:.1} ms",
            ms(b),
            ms(lib)
        ),
        Err(e) => println!("curvefit strip end to end: skipped ({e})"),
    }
    Ok(())
}
