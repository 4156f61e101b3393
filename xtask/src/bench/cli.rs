//! `cargo xtask bench cli`: the `curvefit` binary end to end, as a user calls it.
//!
//! Interpolation, closed, a noisy star (n points at jittered angles θ_i = 2π(i + u_i)/n,
//! u_i ∈ [−0.4, 0.4], radii alternating 1 and 1.5 with ±0.03 noise; a deterministic LCG), k = 7,
//! centripetal, `knot_iterations: 0`: (k + 1)n = 8·10⁵ output vertices at n = 10⁵. The binary
//! (`target/release/curvefit`, built first) runs `refine FILE --timings -o OUT --format F` for
//! F = json, csv, npy; the table shows the medians of its own `parse_s`, `solve_s`, `write_s`,
//! their sum, the process's wall time, and the output's size. The peer, measured in the same
//! run: scipy's `CubicSpline(u, q, bc_type="periodic")` fit + evaluation at the same (k + 1)n
//! parameters (u the centripetal parameters of the same points, closing span included), in
//! memory, median of the same number of repetitions; the ratio is (parse + solve + write) /
//! scipy (issue 14's target: ≤ 1.5). `python3` on PATH with numpy and scipy (e.g.
//! `PATH=/work/venv/bin:$PATH`); without it the ratio is skipped with a message.
//!
//! Each run replaces the previous run's output, as a user re-running a command does; the starred
//! row of each format (`json*`, `csv*`, `npy*`) writes to a file that does not exist yet (removed
//! before each run). The difference is the filesystem's: replacing a file by a rename on ext4
//! (`auto_da_alloc`, the default) starts writing the new file back to disk inside the rename, to
//! keep the old or the new contents across a crash — ~0.7 ms per MB of output on the development
//! machine.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use super::Opts;

/// The scipy peer: reads the problem's points, times fit + evaluation in memory: a closed curve
/// by the periodic `CubicSpline` through the points and the first again, an open one by the
/// natural `CubicSpline` (curvefit's default ends), on the centripetal parameters, evaluated at
/// the (k + 1)·spans parameters of the split (and the last one of an open curve). An optional
/// third argument, in milliseconds, sleeps that long before each timed call (see [`peer`]).
const PEER: &str = r#"
import json, sys, time
try:
    import numpy as np
    from scipy.interpolate import CubicSpline
except ImportError as e:
    print(json.dumps({"skipped": str(e)})); sys.exit(3)
p = json.load(open(sys.argv[1])); reps = int(sys.argv[2]); k = p["k"]
idle = float(sys.argv[3]) / 1e3 if len(sys.argv) > 3 else 0.0
closed = p.get("closed", False)
q = np.array(p["points"]); qc = np.vstack([q, q[:1]]) if closed else q
u = np.concatenate([[0.0], np.cumsum(np.sqrt(np.linalg.norm(np.diff(qc, axis=0), axis=1)))])
s = np.arange(k + 1) / (k + 1)
t = (u[:-1, None] * (1.0 - s) + u[1:, None] * s).ravel()
if not closed:
    t = np.append(t, u[-1])
bc = "periodic" if closed else "natural"
def run():
    return CubicSpline(u, qc, bc_type=bc)(t)
run()
ts = []
for _ in range(reps):
    time.sleep(idle)
    t0 = time.perf_counter(); out = run(); ts.append(time.perf_counter() - t0)
ts.sort()
print(json.dumps({"median_s": ts[len(ts) // 2], "evaluations": int(out.shape[0])}))
"#;

/// The noisy star of the module docs, as a `refine` problem (also the `hard` group's data).
pub(super) fn star_problem(n: usize, k: usize) -> serde_json::Value {
    star_case(n, k, true, 2)
}

/// The noisy star, closed or open (an arc of nine tenths of the turn), in the plane or lifted
/// to d = 3 by z = 0.3 sin 3θ.
pub(super) fn star_case(n: usize, k: usize, closed: bool, d: usize) -> serde_json::Value {
    let mut unif = super::uniform(0x2545_F491_4F6C_DD1D);
    let turn = if closed { 1.0 } else { 0.9 };
    let points: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let th = turn * 2.0 * std::f64::consts::PI * (i as f64 + 0.8 * unif() - 0.4) / n as f64;
            let r = 1.0 + 0.5 * (i % 2) as f64 + 0.06 * unif() - 0.03;
            let mut p = vec![r * th.cos(), r * th.sin()];
            if d == 3 {
                p.push(0.3 * (3.0 * th).sin());
            }
            p
        })
        .collect();
    serde_json::json!({
        "points": points, "closed": closed, "k": k,
        "parametrization": "centripetal", "knot_iterations": 0
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Builds the release binary and returns its path (next to this xtask binary).
fn binary() -> anyhow::Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args([
            "build",
            "--release",
            "--quiet",
            "-p",
            "curvefit",
            "--bin",
            "curvefit",
        ])
        .status()?;
    anyhow::ensure!(status.success(), "building the curvefit binary failed");
    let exe = std::env::current_exe()?;
    let dir = exe
        .parent()
        .ok_or_else(|| anyhow::anyhow!("no directory"))?;
    Ok(dir.join(format!("curvefit{}", std::env::consts::EXE_SUFFIX)))
}

/// One run: (parse_s, solve_s, write_s, wall_s, output bytes).
fn run_once(bin: &Path, problem: &Path, out: &Path, format: &str) -> anyhow::Result<[f64; 5]> {
    let t = Instant::now();
    let o = Command::new(bin)
        .arg("refine")
        .arg(problem)
        .args(["--timings", "--format", format, "-o"])
        .arg(out)
        .output()?;
    let wall = t.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&o.stderr);
    anyhow::ensure!(o.status.success(), "curvefit refine failed: {err}");
    let v: serde_json::Value = serde_json::from_str(err.lines().last().unwrap_or(""))?;
    let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let size = std::fs::metadata(out)?.len() as f64;
    Ok([f("parse_s"), f("solve_s"), f("write_s"), wall, size])
}

/// The median seconds of [`PEER`]'s fit + evaluation on `problem`, `reps` calls after a warm-up,
/// each call after `idle` asleep (zero: back to back, the loop a warm cache favours most), or
/// `None` with the reason printed when python3 with numpy and scipy cannot run it.
pub(super) fn peer(problem: &Path, reps: usize, idle: Duration) -> Option<f64> {
    match Command::new("python3")
        .args(["-c", PEER])
        .arg(problem)
        .arg(reps.to_string())
        .arg(idle.as_millis().to_string())
        .output()
    {
        Ok(o) if o.status.success() => {
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).ok()?;
            v["median_s"].as_f64()
        }
        Ok(o) => {
            println!(
                "  (ratio skipped: python3 with numpy and scipy not importable: {})",
                String::from_utf8_lossy(&o.stdout).trim()
            );
            None
        }
        Err(e) => {
            println!("  (ratio skipped: python3 not runnable: {e})");
            None
        }
    }
}

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let (n, k) = (if opts.quick { 10_000 } else { 100_000 }, 7);
    let reps = if opts.quick { 3 } else { 7 };
    let bin = binary()?;
    let dir = std::env::temp_dir().join(format!("curvefit-bench-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let problem = dir.join("star.json");
    std::fs::write(&problem, serde_json::to_vec(&star_problem(n, k))?)?;
    let input_mb = std::fs::metadata(&problem)?.len() as f64 / 1e6;
    println!(
        "cli: curvefit refine, closed noisy star, n = {n}, k = {k}, centripetal, knot_iterations = 0 ({} vertices; input {input_mb:.1} MB); medians of {reps}",
        (k + 1) * n
    );
    let scipy = peer(&problem, reps, Duration::ZERO);
    println!(
        "  {:>6} {:>9} {:>9} {:>9} {:>11} {:>9} {:>9} {:>14}",
        "format",
        "parse ms",
        "solve ms",
        "write ms",
        "p+s+w ms",
        "wall ms",
        "out MB",
        "(p+s+w)/scipy"
    );
    for (format, fresh) in ["json", "csv", "npy"]
        .into_iter()
        .flat_map(|f| [(f, false), (f, true)])
    {
        let out = dir.join(format!("out.{format}"));
        run_once(&bin, &problem, &out, format)?; // warm-up (page cache, allocator)
        let runs: Vec<[f64; 5]> = (0..reps)
            .map(|_| {
                if fresh {
                    std::fs::remove_file(&out)?;
                }
                run_once(&bin, &problem, &out, format)
            })
            .collect::<anyhow::Result<_>>()?;
        let col = |i: usize| median(runs.iter().map(|r| r[i]).collect());
        let total = median(runs.iter().map(|r| r[0] + r[1] + r[2]).collect());
        let ratio = scipy.map_or("-".to_string(), |s| format!("{:.2}x", total / s));
        println!(
            "  {:>6} {:>9.1} {:>9.1} {:>9.1} {:>11.1} {:>9.1} {:>9.1} {:>14}",
            format!("{format}{}", if fresh { "*" } else { "" }),
            col(0) * 1e3,
            col(1) * 1e3,
            col(2) * 1e3,
            total * 1e3,
            col(3) * 1e3,
            col(4) / 1e6,
            ratio
        );
    }
    println!("  (F*: to a new file each run; the others replace the previous run's output)");
    if let Some(s) = scipy {
        println!(
            "  scipy CubicSpline(bc_type=\"periodic\") fit + evaluation of the same {} points, in memory: {:.1} ms (target: p+s+w <= 1.5x)",
            (k + 1) * n,
            s * 1e3
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
