//! Benchmarks for `refine` (Kersey §3–4).
//!
//! * interpolatory, closed, k = 7, d = 2: the library call from data to refined vertices
//!   (`Problem::refine_points`, closed form) and the certified `Problem::solve`, over a size
//!   sweep (time per vertex shows the O(N) scaling), against scipy's periodic
//!   `CubicSpline` fit + evaluation at the same (k+1)n parameters (peer script
//!   `xtask/peers/refine_peer.py`, run when python3 with scipy is importable);
//! * balls, closed, k = 3: the exact optimum against Clarabel's solve of the same SOCP on the
//!   same knots, twice: through its Rust crate in this process (the tight-tolerance ladder of
//!   the tests' reference), and through its Python package (peer script `refine_peer.py balls`,
//!   run when python3 with numpy, scipy and clarabel is importable) at Clarabel's default
//!   settings and at tolerances 1e-10, timing `solve()` alone. The Python peer gets the SOCP
//!   built by `clarabel_problem` (the tests' reference, P = H ⊗ I_d: from n = 10^4 on Clarabel
//!   stops there at `InsufficientProgress`, H's condition number growing like N⁴) and the same
//!   problem in factored form (`factored_energy`: z = (A ⊗ I_d)x, P = I on z), which it
//!   solves. Its answers are judged by the energy of its vertices (`energy::energy`) and their
//!   ball violations, not by its own objective value alone; no ratio is printed for a run that
//!   did not reach an optimum or hit its time limit (30 s per solve at n = 10^5).
//!
//! Every ratio is measured in the same run; nothing is asserted.

// The same reference file as verify's (xtask's shared modules are not ours to edit).
#[allow(clippy::duplicate_mod)]
#[path = "../../../crates/refine/tests/kersey_support/mod.rs"]
mod clarabel_ref;

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use divdiff::Points;
use refine::{Constraint, Problem};

use super::{time_median, time_median_idle, Opts};

/// The closed test curve shared with the peer script: a wavy circle
/// r(θ) = 1 + 0.3 sin 5θ + 0.1 cos 17θ sampled at θ_i = 2πi/n.
pub fn wavy_circle(n: usize) -> Points {
    let mut c = Vec::with_capacity(2 * n);
    for i in 0..n {
        let th = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        let r = 1.0 + 0.3 * (5.0 * th).sin() + 0.1 * (17.0 * th).cos();
        c.push(r * th.cos());
        c.push(r * th.sin());
    }
    Points::new(2, c).expect("finite")
}

/// Deterministic radii in [0.2, 0.7] × the mean data spacing (a small LCG, so the peer and
/// repeated runs see the same problem).
pub(super) fn radii(q: &Points) -> Vec<f64> {
    let n = q.len();
    let mut spacing = 0.0;
    for i in 0..n {
        let (a, b) = (q.point(i), q.point((i + 1) % n));
        spacing += ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() / n as f64;
    }
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            let u = (s >> 11) as f64 / (1u64 << 53) as f64;
            (0.2 + 0.5 * u) * spacing
        })
        .collect()
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn peer(n: usize, k: usize, reps: usize) -> Option<f64> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/peers/refine_peer.py");
    let out = Command::new("python3")
        .args([
            script,
            "interp",
            &n.to_string(),
            &k.to_string(),
            &reps.to_string(),
        ])
        .output();
    match out {
        Ok(o) if o.status.success() => {
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).ok()?;
            v["median_s"].as_f64()
        }
        Ok(o) => {
            println!(
                "  (peer skipped: python3 with scipy not importable: {})",
                String::from_utf8_lossy(&o.stdout).trim()
            );
            None
        }
        Err(e) => {
            println!("  (peer skipped: python3 not runnable: {e})");
            None
        }
    }
}

/// Writes the conic program in the format `refine_peer.py balls` reads (documented there): a JSON
/// header line padded to a multiple of 8 bytes, then little-endian int64/float64 arrays.
fn write_socp(path: &std::path::Path, s: &clarabel_ref::SocpData) -> anyhow::Result<()> {
    let mut header = serde_json::json!({
        "n_vars": s.n_vars,
        "m": s.b.len(),
        "p_nnz": s.p.vals.len(),
        "a_nnz": s.a.vals.len(),
        "n_cones": s.cones.len(),
        "constant": s.constant,
    })
    .to_string();
    while !(header.len() + 1).is_multiple_of(8) {
        header.push(' ');
    }
    header.push('\n');
    let mut buf: Vec<u8> = header.into_bytes();
    let ints = |buf: &mut Vec<u8>, v: &mut dyn Iterator<Item = usize>| -> anyhow::Result<()> {
        for x in v {
            buf.extend_from_slice(&i64::try_from(x)?.to_le_bytes());
        }
        Ok(())
    };
    let floats = |buf: &mut Vec<u8>, v: &[f64]| {
        for x in v {
            buf.extend_from_slice(&x.to_le_bytes());
        }
    };
    ints(&mut buf, &mut s.p.rows.iter().copied())?;
    ints(&mut buf, &mut s.p.cols.iter().copied())?;
    floats(&mut buf, &s.p.vals);
    floats(&mut buf, &s.q_lin);
    ints(&mut buf, &mut s.a.rows.iter().copied())?;
    ints(&mut buf, &mut s.a.cols.iter().copied())?;
    floats(&mut buf, &s.a.vals);
    floats(&mut buf, &s.b);
    ints(
        &mut buf,
        &mut s.cones.iter().map(|(kind, _)| match kind {
            clarabel_ref::ConeKind::Zero => 0,
            clarabel_ref::ConeKind::SecondOrder => 1,
            clarabel_ref::ConeKind::Nonnegative => 2,
        }),
    )?;
    ints(&mut buf, &mut s.cones.iter().map(|&(_, dim)| dim))?;
    std::fs::File::create(path)?.write_all(&buf)?;
    Ok(())
}

/// Clarabel's `time_limit` (seconds, per solve) for the Python peer at n = 10^5; a run that hits
/// it reports status `MaxTime` instead of a ratio.
const BALLS_PEER_LARGE_LIMIT_S: f64 = 30.0;

/// Wall-clock backstop for one run of the balls peer (both settings, all repetitions) beyond
/// Clarabel's own `time_limit`: the child is killed and the comparison skipped.
const BALLS_PEER_WALL_LIMIT: Duration = Duration::from_secs(300);

/// Runs `refine_peer.py balls` on `socp` (`reps` repetitions, Clarabel `time_limit` seconds if
/// given) and returns its JSON; `None` (after a one-line message) when python3, numpy, scipy or
/// clarabel is missing or the peer fails.
fn balls_peer(
    n: usize,
    tag: &str,
    socp: &clarabel_ref::SocpData,
    reps: usize,
    time_limit: Option<f64>,
) -> Option<serde_json::Value> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/peers/refine_peer.py");
    let path = std::env::temp_dir().join(format!(
        "curvefit-bench-balls-{}-{n}-{tag}.socp",
        std::process::id()
    ));
    if let Err(e) = write_socp(&path, socp) {
        println!(
            "  n = {n}: (peer skipped: cannot write {}: {e})",
            path.display()
        );
        return None;
    }
    let mut args = vec![
        script.to_string(),
        "balls".to_string(),
        path.display().to_string(),
        reps.to_string(),
    ];
    if let Some(t) = time_limit {
        args.push(t.to_string());
    }
    let result = run_with_limit(&args, BALLS_PEER_WALL_LIMIT);
    let _ = std::fs::remove_file(&path);
    let skipped = |why: String| {
        // The solution files the script may have left (read and deleted on success).
        for settings in ["default", "tol_1e-10"] {
            let _ = std::fs::remove_file(format!("{}.x.{settings}", path.display()));
        }
        println!("  n = {n}: (peer skipped: {why})");
        None
    };
    match result.map(|o| (o.status.code(), o.stdout, o.stderr)) {
        Ok((Some(0), stdout, _)) => match serde_json::from_slice(&stdout) {
            Ok(v) => Some(v),
            Err(e) => skipped(format!("unreadable output: {e}")),
        },
        // Exit code 3: the script's "module not importable".
        Ok((Some(3), stdout, _)) => skipped(format!(
            "python3 with numpy, scipy and clarabel not importable: {}",
            String::from_utf8_lossy(&stdout).trim()
        )),
        Ok((code, _, stderr)) => skipped(format!(
            "refine_peer.py failed (exit {code:?}): {}",
            String::from_utf8_lossy(&stderr)
                .lines()
                .last()
                .unwrap_or("")
        )),
        Err(e) => skipped(e),
    }
}

/// Runs python3 with `args`, killing it after `limit`.
fn run_with_limit(args: &[String], limit: Duration) -> Result<std::process::Output, String> {
    let mut child = Command::new("python3")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("python3 not runnable: {e}"))?;
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "python3 peer still running after {:.0} s, killed",
                    limit.as_secs_f64()
                ));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(format!("waiting for python3: {e}")),
        }
    }
    child
        .wait_with_output()
        .map_err(|e| format!("reading python3 output: {e}"))
}

/// What the bench needs to judge a peer's answer independently of Clarabel's own objective.
struct BallsCase<'a> {
    n: usize,
    knots: &'a divdiff::Knots,
    q: &'a Points,
    radii: &'a [f64],
    data_vertex: &'a [usize],
    /// Our optimum's energy.
    e_ours: f64,
    /// Our solve time.
    ours: Duration,
    /// Clarabel's `time_limit` for the peer, seconds.
    time_limit: Option<f64>,
}

/// Reads the peer's x (little-endian float64, vertex-major) and deletes the file; returns the
/// energy of those vertices by `energy::energy` (the divided-difference form, free of the
/// cancellation in ½xᵀPx) and the largest ball violation max_i(|p_{i_k} − q_i| − ε_i).
fn peer_points(case: &BallsCase, file: &str) -> anyhow::Result<(f64, f64)> {
    let bytes = std::fs::read(file)?;
    let _ = std::fs::remove_file(file);
    let mut x: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    // The vertices come first (the factored form appends its auxiliary z).
    let nx = case.knots.vertex_count() * case.q.dim();
    anyhow::ensure!(x.len() >= nx, "{} values, expected at least {nx}", x.len());
    x.truncate(nx);
    let p = Points::new(case.q.dim(), x)?;
    let e = energy::energy(case.knots, &p)?;
    let mut worst = f64::NEG_INFINITY;
    for (i, &v) in case.data_vertex.iter().enumerate() {
        let dist = p
            .point(v)
            .iter()
            .zip(case.q.point(i))
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        worst = worst.max(dist - case.radii[i]);
    }
    Ok((e, worst.max(0.0)))
}

/// Prints one settings run of the balls peer against our energy and time.
fn print_balls_peer(case: &BallsCase, label: &str, run: &serde_json::Value) {
    let n = case.n;
    if let Some(why) = run["skipped"].as_str() {
        println!("  n = {n}: python clarabel {label}: skipped ({why})");
        return;
    }
    let f = |key: &str| run[key].as_f64().unwrap_or(f64::NAN);
    let solve = f("solve_s");
    let rel = |e: f64| (case.e_ours - e).abs() / case.e_ours;
    let from_x = match run["x_file"].as_str().map(|file| peer_points(case, file)) {
        Some(Ok((e, viol))) => format!(
            "E(x) = {e:.9e} (rel diff {:.1e}, max ball violation {viol:.1e})",
            rel(e)
        ),
        Some(Err(e)) => format!("x not evaluated: {e}"),
        None => "no x".to_string(),
    };
    let status = run["status"].as_str().unwrap_or("?");
    // A ratio against a run that did not reach an optimum would compare unlike things.
    let ratio = if run["hit_time_limit"].as_bool() == Some(true) {
        format!(
            "did not finish within its time_limit: comparison skipped (ratio solve/ours would be > {:.1}x)",
            solve / case.ours.as_secs_f64()
        )
    } else if matches!(status, "Solved" | "AlmostSolved") {
        let at_limit = match case.time_limit {
            Some(l) if f("clarabel_solve_time_s") >= 0.99 * l => {
                " (converged in the iteration that reached its time_limit)"
            }
            _ => "",
        };
        format!(
            "ratio solve/ours {:.1}x, (setup+solve)/ours {:.1}x (target >= 50x){at_limit}",
            solve / case.ours.as_secs_f64(),
            (solve + f("setup_s")) / case.ours.as_secs_f64()
        )
    } else {
        "no ratio (not solved)".to_string()
    };
    println!(
        "  n = {n}: python clarabel {label}: {status} in {} iterations, solve {:.2} ms (+ setup {:.2} ms): {ratio}",
        run["iterations"],
        solve * 1e3,
        f("setup_s") * 1e3,
    );
    println!(
        "      objective + const = {:.9e} (rel diff to ours {:.1e}); {from_x}",
        f("energy"),
        rel(f("energy")),
    );
}

/// The same problem in factored form, for the balls SOCP (whose objective is ½xᵀ(H ⊗ I_d)x with
/// no linear term): with H = AᵀA (`energy::alphas`, row i on vertices i − 1, i, i + 1) and new
/// variables z = (A ⊗ I_d)x, minimize ½|z|² subject to the original rows plus the equalities
/// (A ⊗ I_d)x − z = 0 (a zero cone appended). Equivalent optimum, but Clarabel's KKT system no
/// longer carries H, whose condition number (~N⁴ on a closed curve) is what stops it at
/// `InsufficientProgress` as posed at n = 10^4. Vertices come first in x, then z.
fn factored_energy(
    socp: &clarabel_ref::SocpData,
    knots: &divdiff::Knots,
    d: usize,
) -> clarabel_ref::SocpData {
    let nv = knots.vertex_count();
    let nx = nv * d;
    assert_eq!(socp.n_vars, nx, "one variable per vertex coordinate");
    assert!(
        socp.q_lin.iter().all(|&v| v == 0.0) && socp.constant == 0.0,
        "the factored form is for objectives ½xᵀ(H ⊗ I_d)x (balls, interpolation, half-spaces)"
    );
    let alphas = energy::alphas(knots);
    let mut out = socp.clone();
    out.n_vars = nx + nx;
    out.q_lin = vec![0.0; nx + nx];
    out.p = clarabel_ref::Triplets {
        rows: (nx..nx + nx).collect(),
        cols: (nx..nx + nx).collect(),
        vals: vec![1.0; nx],
    };
    let m = socp.b.len();
    for (i, row) in alphas.iter().enumerate() {
        for c in 0..d {
            let r = m + i * d + c;
            for (j, &a) in row.iter().enumerate() {
                // Row i of A acts on vertices i − 1, i, i + 1 (periodic for closed curves; the
                // end rows of an open curve are zero).
                if a == 0.0 {
                    continue;
                }
                let v = (i + nv + j - 1) % nv;
                out.a.rows.push(r);
                out.a.cols.push(v * d + c);
                out.a.vals.push(a);
            }
            out.a.rows.push(r);
            out.a.cols.push(nx + i * d + c);
            out.a.vals.push(-1.0);
            out.b.push(0.0);
        }
    }
    out.cones.push((clarabel_ref::ConeKind::Zero, nx));
    out
}

/// A peer's median in ms for a table cell ("-" when the peer could not run).
fn peer_ms(peer_s: Option<f64>) -> String {
    peer_s.map_or("-".into(), |s| format!("{:.2}", s * 1e3))
}

/// The ratio peer / ours for a table cell ("-" when the peer could not run).
fn peer_ratio(peer_s: Option<f64>, ours: Duration) -> String {
    peer_s.map_or("-".into(), |s| format!("{:.2}x", s / ours.as_secs_f64()))
}

/// How long the "after idle" columns of [`hard`] sleep before each timed call. (On the 2-core
/// development machine, 2026-12-04, the closed d = 2 solve at n = 10⁵ took 13.2–15.5 ms after
/// 50 ms asleep against 9.4–9.7 ms back to back; scipy 54–57 ms against 49–50.)
const IDLE: Duration = Duration::from_millis(50);

/// The `hard` group: interpolation on the noisy star of the `cli` group (jittered angles,
/// alternating radii with noise; k = 7, centripetal) — closed in the plane, open (an arc), and
/// closed in space (d = 3) — through `Problem::solve` (points, energy, reactions and the
/// independent certificate) against scipy's `CubicSpline` (periodic for the closed curves,
/// natural for the open one) fit + evaluation at the same parameters on the same points (the
/// `cli` group's peer, in memory), measured in the same run (issue 14 §1: target ≥ 5×); the same
/// solve on a one-thread pool; and Algorithm 4.1's default three knot updates against one solve
/// (§4: target ≤ 2×). Every time is the median of repeated calls in one process (the allocator
/// reuses the freed arrays); `bench cli` times a fresh process per solve. Back to back, a call
/// finds its memory and the processor as the previous call left them; a user's single call finds
/// them after other work or none, so the solve and scipy are also timed each after [`IDLE`]
/// asleep ("after idle"), and their ratio printed beside the back-to-back one.
pub fn hard(opts: Opts) -> anyhow::Result<()> {
    let k = 7;
    let reps = if opts.quick { 3 } else { 7 };
    let sizes: &[usize] = if opts.quick {
        &[10_000]
    } else {
        &[10_000, 100_000]
    };
    let dir = std::env::temp_dir().join(format!("curvefit-bench-hard-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    println!("hard: interpolation, noisy star, k = {k}, centripetal; Problem::solve (certified); medians of {reps}");
    println!(
        "  {:>6} {:>2} {:>8} {:>9} {:>10} {:>10} {:>12} {:>10} {:>12} {:>14} {:>12} {:>11} {:>11} {:>11}",
        "curve",
        "d",
        "n",
        "N",
        "solve ms",
        "ns/vertex",
        "1 thread ms",
        "scipy ms",
        "scipy/solve",
        "3 updates ms",
        "updates/solve",
        "idle solve",
        "idle scipy",
        "idle ratio"
    );
    for (closed, d) in [(true, 2), (false, 2), (true, 3)] {
        for &n in sizes {
            let json = super::cli::star_case(n, k, closed, d);
            let file = dir.join(format!("star-{n}-{closed}-{d}.json"));
            std::fs::write(&file, serde_json::to_vec(&json)?)?;
            let coords: Vec<f64> = json["points"]
                .as_array()
                .ok_or_else(|| anyhow::anyhow!("points"))?
                .iter()
                .flat_map(|p| {
                    p.as_array()
                        .into_iter()
                        .flatten()
                        .filter_map(|x| x.as_f64())
                })
                .collect();
            let q = Points::new(d, coords)?;
            let topology = if closed {
                divdiff::Topology::Closed
            } else {
                divdiff::Topology::Open
            };
            let problem = Problem::new(q)
                .with_topology(topology)
                .with_parametrization(divdiff::Parametrization::Centripetal)
                .with_k(k)
                .with_knot_iterations(0);
            let solve = || problem.solve().expect("interpolation solves");
            let one = time_median(reps, solve);
            // The same solve on one thread: what the parallel passes (refine's `par`) give.
            let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
            let single = pool.install(|| time_median(reps, solve));
            let updates = problem.clone().with_knot_iterations(3);
            let three = time_median(reps.min(3), || {
                updates
                    .solve()
                    .expect("interpolation with knot updates solves")
            });
            let scipy = super::cli::peer(&file, reps, Duration::ZERO);
            let idle = time_median_idle(reps, IDLE, solve);
            let idle_scipy = super::cli::peer(&file, reps, IDLE);
            let nv = Problem::refined_len(topology, n, k);
            println!(
                "  {:>6} {:>2} {:>8} {:>9} {:>10.2} {:>10.1} {:>12.2} {:>10} {:>12} {:>14.2} {:>12.2} {:>11.2} {:>11} {:>11}",
                if closed { "closed" } else { "open" },
                d,
                n,
                nv,
                ms(one),
                one.as_secs_f64() * 1e9 / nv as f64,
                ms(single),
                peer_ms(scipy),
                peer_ratio(scipy, one),
                ms(three),
                three.as_secs_f64() / one.as_secs_f64(),
                ms(idle),
                peer_ms(idle_scipy),
                peer_ratio(idle_scipy, idle)
            );
        }
    }
    println!(
        "  (targets: scipy/solve >= 5x; updates/solve <= 2x; idle: each call after {} ms asleep)",
        IDLE.as_millis()
    );
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let k = 7;
    let reps = if opts.quick { 3 } else { 7 };
    println!("refine: interpolatory, closed, d = 2, k = {k}, knot_iterations = 0 (one solve)");
    println!("  refine_points: closed form, data to refined vertices, no certificate;");
    println!("  solve: the same points plus energy, reactions and the independent KKT certificate");
    println!(
        "  {:>8} {:>9} {:>14} {:>12} {:>10} {:>12}",
        "n", "N", "points ms", "ns/vertex", "solve ms", "ns/vertex"
    );
    let sizes: &[usize] = if opts.quick {
        &[1_000, 10_000]
    } else {
        &[10_000, 30_000, 100_000, 300_000]
    };
    let mut at_1e5 = None;
    for &n in sizes {
        let q = wavy_circle(n);
        let problem = Problem::new(q).with_k(k).with_knot_iterations(0);
        let lean = time_median(reps, || {
            problem.refine_points().expect("interpolation refines")
        });
        let t = time_median(reps, || problem.solve().expect("interpolation solves"));
        let nv = (k + 1) * n;
        let per = |t: Duration| t.as_secs_f64() * 1e9 / nv as f64;
        println!(
            "  {:>8} {:>9} {:>14.2} {:>12.1} {:>10.2} {:>12.1}",
            n,
            nv,
            ms(lean),
            per(lean),
            ms(t),
            per(t)
        );
        if n == 100_000 {
            at_1e5 = Some((lean, t));
        }
    }
    let n_peer = if opts.quick { 10_000 } else { 100_000 };
    let (lean, ours) = match at_1e5 {
        Some(t) => t,
        None => {
            let problem = Problem::new(wavy_circle(n_peer))
                .with_k(k)
                .with_knot_iterations(0);
            (
                time_median(reps, || {
                    problem.refine_points().expect("interpolation refines")
                }),
                time_median(reps, || problem.solve().expect("interpolation solves")),
            )
        }
    };
    if let Some(scipy) = peer(n_peer, k, reps) {
        println!(
            "  n = {n_peer}: scipy CubicSpline(periodic) fit+eval {:.2} ms; curvefit refine_points {:.2} ms: ratio {:.1}x (target >= 5x); certified solve {:.2} ms: ratio {:.1}x",
            scipy * 1e3,
            ms(lean),
            scipy / lean.as_secs_f64(),
            ms(ours),
            scipy / ours.as_secs_f64()
        );
    }
    // With the default three knot updates (four solves).
    let problem = Problem::new(wavy_circle(n_peer)).with_k(k);
    let t = time_median(reps.min(3), || {
        problem.solve().expect("interpolation solves")
    });
    println!(
        "  n = {n_peer}, default knot_iterations = 3 (four solves + updates): {:.2} ms",
        ms(t)
    );

    println!("refine: balls, closed, d = 2, k = 3, knot_iterations = 0");
    let n_balls: &[usize] = if opts.quick {
        &[1_000, 10_000]
    } else {
        &[1_000, 10_000, 100_000]
    };
    for &n in n_balls {
        let q = wavy_circle(n);
        let r = radii(&q);
        let c = Constraint::Balls(r.clone());
        let problem = Problem::new(q.clone())
            .with_k(3)
            .with_knot_iterations(0)
            .with_constraint(c.clone());
        // The first solve is timed directly; smaller sizes repeat for a median.
        let start = std::time::Instant::now();
        let sol = match problem.solve() {
            Ok(s) => s,
            Err(e) => {
                println!("  n = {n}: exact solver failed: {e}");
                continue;
            }
        };
        let first = start.elapsed();
        let t = time_median(reps.min(5), || problem.solve().expect("balls solve"));
        println!(
            "  n = {n}: exact {:.2} ms (median; first solve in the process {:.2} ms), kkt {:.1e}, {} solver iterations, {} of {n} active, E = {:.9e}",
            ms(t),
            ms(first),
            sol.kkt_residual,
            sol.iterations.solver,
            sol.active.iter().filter(|&&a| a).count(),
            sol.energy
        );
        if n <= 10_000 {
            let start = Instant::now();
            match clarabel_ref::clarabel_solve(&sol.knots, &q, &sol.data_vertex, &c) {
                Ok(reference) => {
                    let tc = start.elapsed();
                    let e_ref = energy::energy(&sol.knots, &reference.points)?;
                    println!(
                        "  n = {n}: clarabel (Rust crate, tolerance ladder {:?}) {:.2} ms ({} iterations), E = {:.9e}, rel diff {:.1e}: ratio {:.1}x (target >= 50x)",
                        clarabel_ref::CLARABEL_LADDER,
                        ms(tc),
                        reference.iterations,
                        e_ref,
                        (sol.energy - e_ref).abs() / e_ref,
                        tc.as_secs_f64() / t.as_secs_f64()
                    );
                }
                Err(e) => println!(
                    "  n = {n}: clarabel (Rust crate, tolerance ladder {:?}) gave no reference ({e}) after {:.2} ms",
                    clarabel_ref::CLARABEL_LADDER,
                    ms(start.elapsed())
                ),
            }
        }
        // The Python peer: every size up to 10^4 (median of `reps`), 10^5 once with Clarabel's
        // time limit BALLS_PEER_LARGE_LIMIT_S per solve.
        let (peer_reps, limit) = if n <= 10_000 {
            (reps.min(3), None)
        } else {
            (1, Some(BALLS_PEER_LARGE_LIMIT_S))
        };
        let socp = clarabel_ref::clarabel_problem(&sol.knots, &q, &sol.data_vertex, &c);
        let factored = factored_energy(&socp, &sol.knots, q.dim());
        let case = BallsCase {
            n,
            knots: &sol.knots,
            q: &q,
            radii: &r,
            data_vertex: &sol.data_vertex,
            e_ours: sol.energy,
            ours: t,
            time_limit: limit,
        };
        for (tag, form, program) in [
            (
                "posed",
                "as posed (P = H ⊗ I_d, the tests' reference)",
                &socp,
            ),
            (
                "factored",
                "factored (P = I on z = (A ⊗ I_d) x, H = AᵀA)",
                &factored,
            ),
        ] {
            let Some(v) = balls_peer(n, tag, program, peer_reps, limit) else {
                break;
            };
            println!(
                "  n = {n}: SOCP {form}: {} variables, {} rows; ours {:.2} ms; Python clarabel {}{}:",
                v["n_vars"],
                v["m"],
                ms(t),
                v["clarabel"].as_str().unwrap_or("?"),
                limit.map_or(String::new(), |l| format!(", time_limit {l} s"))
            );
            print_balls_peer(&case, "default settings (tol 1e-8)", &v["default"]);
            print_balls_peer(&case, "tol 1e-10", &v["tol_1e-10"]);
        }
    }
    Ok(())
}
