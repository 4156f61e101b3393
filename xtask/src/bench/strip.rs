//! Benchmarks for `strip`: the 16-point example, a size sweep with many active intervals, and
//! the exact solver against Clarabel's fine-grid QP (M = 10^4 grid points) in the same run.

use super::{time_median, Opts};
use strip::{solve, Method, Options, Shape};
use strip_testkit::examples::{example_5_1, large};

/// Solves the lower-bound QP on `m` uniform grid points; returns its optimal value.
fn clarabel_qp(p: &strip::Problem, m: usize) -> anyhow::Result<f64> {
    let (a, b) = (p.t[0], p.t[p.t.len() - 1]);
    let grid: Vec<f64> = (1..m).map(|k| a + (b - a) * k as f64 / m as f64).collect();
    let lb = strip_testkit::lower_bound(p, &grid, false).map_err(|e| anyhow::anyhow!(e))?;
    Ok(lb.primal)
}

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let reps = if opts.quick { 3 } else { 11 };
    println!("## strip");
    let p16 = example_5_1();
    let s16 = solve(&p16, &Options::default())?;
    let t16 = time_median(reps * 5, || solve(&p16, &Options::default()));
    let tb = time_median(reps, || {
        solve(
            &p16,
            &Options {
                method: Method::Bfgs,
                ..Options::default()
            },
        )
    });
    println!(
        "16-point example (5.1-like): Newton {:.3} ms ({} iterations, {} extra knots), argmin BFGS {:.3} ms (×{:.1})",
        t16.as_secs_f64() * 1e3,
        s16.iterations,
        s16.extra_knots.len(),
        tb.as_secs_f64() * 1e3,
        tb.as_secs_f64() / t16.as_secs_f64()
    );
    let m = if opts.quick { 2_000 } else { 10_000 };
    let tq = time_median(if opts.quick { 1 } else { 3 }, || clarabel_qp(&p16, m));
    let lb = clarabel_qp(&p16, m)?;
    println!(
        "Clarabel fine-grid QP (M = {m}) on the same problem: {:.1} ms, value {:.9} (exact {:.9}); exact solver is {:.0}× faster",
        tq.as_secs_f64() * 1e3,
        lb,
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
    let mut base: Option<(usize, f64)> = None;
    for &n in sizes {
        let p = large(n);
        let s = solve(&p, &Options::default())?;
        let t = time_median(if opts.quick { 1 } else { 3 }, || {
            solve(&p, &Options::default())
        });
        let active = s.shapes.iter().filter(|x| **x != Shape::Free).count();
        let per = t.as_secs_f64() * 1e6 / n as f64;
        println!(
            "{n:>8} {:>12.2} {:>10} {:>8} {:>14.2}",
            t.as_secs_f64() * 1e3,
            active,
            s.iterations,
            per
        );
        if let Some((n0, p0)) = base {
            println!(
                "         growth vs n = {n0}: time per point ×{:.2}",
                per / p0
            );
        } else {
            base = Some((n, per));
        }
    }
    Ok(())
}
