//! Benchmarks for `refine` (Kersey §3–4).
//!
//! * interpolatory, closed, k = 7, d = 2: the library call from data to refined vertices
//!   (`Problem::refine_points`, closed form) and the certified `Problem::solve`, over a size
//!   sweep (time per vertex shows the O(N) scaling), against scipy's periodic
//!   `CubicSpline` fit + evaluation at the same (k+1)n parameters (peer script
//!   `xtask/peers/refine_peer.py`, run when python3 with scipy is importable);
//! * balls, closed, k = 3: the exact optimum against Clarabel's solve of the same SOCP on the
//!   same knots (Clarabel through its Rust crate, in this process).
//!
//! Every ratio is measured in the same run; nothing is asserted.

// The same reference file as verify's (xtask's shared modules are not ours to edit).
#[allow(clippy::duplicate_mod)]
#[path = "../../../crates/refine/tests/kersey_support/mod.rs"]
mod clarabel_ref;

use std::process::Command;
use std::time::Duration;

use divdiff::Points;
use refine::{Constraint, Problem};

use super::{time_median, Opts};

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
fn radii(q: &Points) -> Vec<f64> {
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
        let t = if n <= 10_000 {
            time_median(reps.min(3), || problem.solve().expect("balls solve"))
        } else {
            first
        };
        println!(
            "  n = {n}: exact {:.2} ms, kkt {:.1e}, {} solver iterations, {} of {n} active, E = {:.9e}",
            ms(t),
            sol.kkt_residual,
            sol.iterations.solver,
            sol.active.iter().filter(|&&a| a).count(),
            sol.energy
        );
        if n <= 10_000 {
            let start = std::time::Instant::now();
            let reference = match clarabel_ref::clarabel_solve(&sol.knots, &q, &sol.data_vertex, &c)
            {
                Ok(r) => r,
                Err(e) => {
                    println!(
                        "  n = {n}: Clarabel gave no reference ({e}) after {:.2} ms",
                        ms(start.elapsed())
                    );
                    continue;
                }
            };
            let tc = start.elapsed();
            let e_ref = energy::energy(&sol.knots, &reference.points)?;
            println!(
                "  n = {n}: clarabel {:.2} ms ({} iterations), E = {:.9e}, rel diff {:.1e}: ratio {:.1}x (target >= 50x)",
                ms(tc),
                reference.iterations,
                e_ref,
                (sol.energy - e_ref).abs() / e_ref,
                tc.as_secs_f64() / t.as_secs_f64()
            );
        }
    }
    Ok(())
}
