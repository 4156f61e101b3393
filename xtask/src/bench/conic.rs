//! Benchmarks for `conic`: the exact fixed-knot solve of every problem class, the crate's own
//! interior-point method (through `refine::Problem::solve`, the path users call: the strategy
//! list, the condensed or full-vertex backend, the polish and the independent certificate)
//! against Clarabel on the same conic program (`Problem::conic_problem` →
//! `ConicProblem::solve_clarabel`: the full-vertex program with the energy factored, Clarabel's
//! tolerances 1e-10, its answer certified by `conic`'s residuals).
//!
//! Data: the noisy star of `crates/refine/tests/kersey_support/cases.rs` (jittered angles,
//! balls and boxes of 0.05–0.25 of the local chord; wedges at every 8th point; clamped ends),
//! k = 3, d = 2, no knot update (one fixed-knot solve), closed and open, n = 10²…10⁵ (Clarabel up
//! to where it finishes within its time limit).
//!
//! A second table takes balls beyond the plane star: the star in space (d = 3) and the smooth
//! wavy circle (a sparse active set), closed and open; a third, the default knot updates against
//! one solve. The last table times the full-vertex backend alone on issue 3's balls problem (a wavy closed
//! curve with radii 0.05–0.55 of the spacing) against Clarabel on the same SOCP as posed
//! (P = H ⊗ I), the table the `energy` group used to print.
//!
//! The first two tables' `cores` column is the process's CPU time over the wall time of our
//! timed solves (`super::time_median_cores`): how much of the machine a solve kept busy. The
//! interior-point method's iterations run on one thread; the parallel passes around them (the
//! certificate, the split) use the pool.
//!
//! Every ratio is measured in the same run; nothing is asserted.

#[allow(clippy::duplicate_mod)]
#[path = "../../../crates/refine/tests/kersey_support/mod.rs"]
mod kersey_support;

use std::time::{Duration, Instant};

use divdiff::Topology;
use kersey_support::cases::{problem, Class};
use refine::{ConicOptions, ConicProblem, ConvexSet};

use super::{time_median, Opts};

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Clarabel's time limit per solve (a run that hits it is reported, not compared).
const CLARABEL_LIMIT_S: f64 = 60.0;

/// Runs this group and prints its tables.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    println!("## conic — exact fixed-knot solves, ours vs Clarabel on the same conic program");
    println!();
    println!("noisy star, k = 3, d = 2, knot_iterations = 0; ours = Problem::solve (certified); Clarabel = the same program (ConicProblem::solve_clarabel, tolerance 1e-10), certified by the same residuals");
    println!();
    println!("| class | topology | n | N | ours | ns/vertex | cores | iterations | active | certificate | Clarabel | status | its certificate | energy rel. diff | Clarabel / ours |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|");
    let sizes: &[usize] = if opts.quick {
        &[100, 1_000]
    } else {
        &[100, 1_000, 10_000, 100_000]
    };
    let clarabel_max = if opts.quick { 1_000 } else { 100_000 };
    for class in [
        Class::Balls,
        Class::HalfSpaces,
        Class::Tangents,
        Class::Clamped,
    ] {
        for topology in [Topology::Closed, Topology::Open] {
            if class == Class::Clamped && topology == Topology::Closed {
                continue;
            }
            // Clarabel stops being worth waiting for once it has taken over a minute.
            let mut clarabel_gave_up = false;
            for &n in sizes {
                let p = problem(class, n, 2, topology, 3, 7);
                let run_clarabel = n <= clarabel_max && !clarabel_gave_up;
                clarabel_gave_up |= table_row(class.name(), topology, n, &p, run_clarabel)?;
            }
        }
    }
    println!();
    balls_beyond(opts)?;
    knot_updates(opts)?;
    full_vertex(opts)?;
    Ok(())
}

/// Times `p` through `Problem::solve` and, when `run_clarabel`, Clarabel on the same program, and
/// prints one row of the class table; returns whether Clarabel hit its time limit.
fn table_row(
    name: &str,
    topology: Topology,
    n: usize,
    p: &refine::Problem,
    run_clarabel: bool,
) -> anyhow::Result<bool> {
    let mut clarabel_gave_up = false;
    let nv = refine::Problem::refined_len(p.topology, n, p.k);
    let reps = (200_000 / n).clamp(1, 15);
    let (start, cpu) = (Instant::now(), super::cpu_time());
    let first = p.solve();
    let once = start.elapsed();
    let cores_once = super::cores_since(cpu, once);
    let sol = match first {
        Ok(s) => s,
        Err(e) => {
            println!(
                "| {name} | {topology:?} | {n} | {nv} | refused after {:.1} ms: {e} | | | | | | | | | | |",
                ms(once)
            );
            return Ok(false);
        }
    };
    let (t, cores) = if reps > 1 {
        super::time_median_cores(reps, || p.solve().expect("solved once"))
    } else {
        (once, cores_once)
    };
    let ours = format!(
        "{:.2} ms | {:.0} | {cores:.2} | {} | {} | {:.1e}",
        ms(t),
        t.as_secs_f64() * 1e9 / nv as f64,
        sol.iterations.solver,
        sol.active.iter().filter(|&&a| a).count(),
        sol.kkt_residual
    );
    let theirs = if !run_clarabel {
        "— | not run | | | ".to_string()
    } else {
        let cp = p.conic_problem()?;
        let copts = conic::clarabel::ClarabelOptions {
            time_limit: Some(CLARABEL_LIMIT_S),
            ..Default::default()
        };
        let start = Instant::now();
        let r = cp.solve_clarabel(&copts);
        let tc = start.elapsed();
        clarabel_gave_up = tc.as_secs_f64() >= CLARABEL_LIMIT_S;
        match r {
            Ok(c) => {
                let e = energy::energy(cp.knots(), &c.points)?;
                let status = if c.kkt.total <= 1e-9 {
                    "certified"
                } else {
                    "not certified"
                };
                format!(
                    "{:.2} ms | {status} ({} it.) | {:.1e} | {:.1e} | {:.1}×",
                    ms(tc),
                    c.iterations,
                    c.kkt.total,
                    (e - sol.energy).abs() / sol.energy,
                    tc.as_secs_f64() / t.as_secs_f64()
                )
            }
            Err(e) => format!("{:.2} ms | failed: {e} | | | ", ms(tc)),
        }
    };
    println!("| {name} | {topology:?} | {n} | {nv} | {ours} | {theirs} |");
    Ok(clarabel_gave_up)
}

/// Balls beyond the plane noisy star of the class table: the star in space (d = 3, dense active
/// set), the plane star with radii four times larger (about half active) and the bench's smooth
/// wavy circle with radii of 0.2–0.7 of the spacing (a sparse active set), closed and open,
/// k = 3; the plane star in axis-aligned boxes of half-width 0.3 of the local chord (a
/// tolerance per coordinate, every box active: the class ROBUSTNESS.md item 32 found ten times
/// slower than balls) and in balls of radii spread over five decades ([`spread_radii`], item 33);
/// Clarabel on the same program up to n = 10⁴ (10⁵ gives the scaling of ours).
fn balls_beyond(opts: Opts) -> anyhow::Result<()> {
    println!(
        "## conic — balls in space, half active and with a sparse active set, and boxes, ours vs Clarabel"
    );
    println!();
    println!("k = 3, knot_iterations = 0; noisy star d = 3 (radii 0.05–0.25 of the local chord), the plane star with radii 0.2–1.0 of the local chord (about half active: the working set's rounds), wavy circle d = 2 (radii 0.2–0.7 of the mean spacing), the plane star in axis-aligned boxes of half-width 0.3 of the local chord, the plane star in balls of radii 10^u local chords, u uniform in [-4, 1]");
    println!();
    println!("| data | topology | n | N | ours | ns/vertex | cores | iterations | active | certificate | Clarabel | status | its certificate | energy rel. diff | Clarabel / ours |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|");
    let sizes: &[usize] = if opts.quick {
        &[1_000]
    } else {
        &[10_000, 100_000]
    };
    for topology in [Topology::Closed, Topology::Open] {
        for &n in sizes {
            let star = problem(Class::Balls, n, 3, topology, 3, 7);
            let mid = wider_balls(problem(Class::Balls, n, 2, topology, 3, 7), 4.0);
            let wavy = wavy_balls(n, topology);
            let boxes = axis_boxes(problem(Class::Balls, n, 2, topology, 3, 7), 0.3);
            let spread = spread_radii(problem(Class::Balls, n, 2, topology, 3, 7));
            for (name, p) in [
                ("noisy star, d = 3", star),
                ("noisy star, radii × 4", mid),
                ("wavy circle", wavy),
                ("noisy star, axis-aligned boxes", boxes),
                ("noisy star, radii over five decades", spread),
            ] {
                table_row(name, topology, n, &p, n <= 10_000)?;
            }
        }
    }
    println!();
    Ok(())
}

/// `p` (balls) with every radius times `factor`: the noisy star's balls of 0.05–0.25 of the
/// local chord times 4 leave about half active (5138 of 10⁴, closed), between the dense star and
/// the sparse wavy circle, where the working set runs several rounds before it settles.
fn wider_balls(p: refine::Problem, factor: f64) -> refine::Problem {
    let radii = match &p.constraint {
        refine::Constraint::Balls(r) => r.iter().map(|x| x * factor).collect(),
        _ => return p,
    };
    p.with_constraint(refine::Constraint::Balls(radii))
}

/// `p`'s points each in an axis-aligned box of half-width `ratio` times its local chord (the
/// mean distance to its neighbours), in place of `p`'s constraint.
fn axis_boxes(p: refine::Problem, ratio: f64) -> refine::Problem {
    let chords = kersey_support::cases::local_chords(&p.points, p.topology);
    let boxes = kersey_support::cases::axis_boxes(&p.points, |i| ratio * chords[i]);
    p.with_constraint(boxes)
}

/// `p`'s points each in a ball of radius 10^u local chords, u uniform in [−4, 1] (a tolerance
/// that varies from point to point over five decades), in place of `p`'s constraint: the class
/// where a round's polish pulled points back onto the tiniest balls from hundreds of radii away
/// (ROBUSTNESS.md item 33).
fn spread_radii(p: refine::Problem) -> refine::Problem {
    let chords = kersey_support::cases::local_chords(&p.points, p.topology);
    let mut rng = kersey_support::cases::Rng::new(33);
    let radii = chords
        .iter()
        .map(|c| c * 10f64.powf(rng.range(-4.0, 1.0)))
        .collect();
    p.with_constraint(refine::Constraint::Balls(radii))
}

/// The bench's smooth wavy circle with balls of radii 0.2–0.7 of the spacing (a sparse active
/// set), k = 3, no knot update.
fn wavy_balls(n: usize, topology: Topology) -> refine::Problem {
    let q = super::refine::wavy_circle(n);
    let r = super::refine::radii(&q);
    refine::Problem::new(q)
        .with_topology(topology)
        .with_k(3)
        .with_knot_iterations(0)
        .with_constraint(refine::Constraint::Balls(r))
}

/// Algorithm 4.1 with the default three knot updates (four fixed-knot solves, each after the
/// first warm-started from the previous one's answer) against one solve of the same problem,
/// same run: the noisy star (dense active set) and the bench's wavy circle (sparse), closed,
/// k = 3, d = 2.
fn knot_updates(opts: Opts) -> anyhow::Result<()> {
    println!("## conic — knot updates: knot_iterations = 3 (default) against one solve, balls, closed, k = 3, d = 2");
    println!();
    println!("| data | n | one solve | iterations | knot_iterations 3 | iterations | ratio | certificate |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    let sizes: &[usize] = if opts.quick {
        &[1_000]
    } else {
        &[1_000, 10_000]
    };
    for &n in sizes {
        let star = problem(Class::Balls, n, 2, Topology::Closed, 3, 7);
        let wavy = wavy_balls(n, Topology::Closed);
        for (name, p) in [("noisy star", star), ("wavy circle", wavy)] {
            let once = p.clone().with_knot_iterations(0);
            let three = p.with_knot_iterations(3);
            let reps = (100_000 / n).clamp(3, 15);
            let t1 = time_median(reps, || once.solve().expect("one solve"));
            let t3 = time_median(reps, || three.solve().expect("knot updates"));
            let (s1, s3) = (once.solve()?, three.solve()?);
            println!(
                "| {name} | {n} | {:.2} ms | {} | {:.2} ms | {} | {:.1}× | {:.1e} |",
                ms(t1),
                s1.iterations.solver,
                ms(t3),
                s3.iterations.solver,
                t3.as_secs_f64() / t1.as_secs_f64(),
                s3.kkt_residual
            );
        }
    }
    println!();
    Ok(())
}

/// Points per span in issue 3's balls problem.
const BALLS_K: usize = 3;

/// The data of issue 3's balls problem: n points on a noisy closed curve and the refined knots
/// (centripetal data knots split uniformly into k + 1 pieces).
fn balls_data(n: usize) -> anyhow::Result<(Vec<[f64; 2]>, divdiff::Knots)> {
    let k = BALLS_K;
    let q: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let wobble = 1.0 + 0.2 * (7.0 * a).sin() + 0.01 * ((i * 7919 % 97) as f64 / 97.0 - 0.5);
            [wobble * a.cos(), 0.7 * wobble * a.sin()]
        })
        .collect();
    let mut t = vec![0.0];
    for i in 0..n {
        let (a, b) = (q[i], q[(i + 1) % n]);
        let span = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2))
            .sqrt()
            .sqrt();
        let t0 = *t.last().unwrap_or(&0.0);
        for j in 1..=k + 1 {
            t.push(t0 + span * j as f64 / (k + 1) as f64);
        }
    }
    Ok((q, divdiff::Knots::closed(t)?))
}

/// Issue 3's balls problem: n data points on a noisy closed curve, k = 3 (N = 4n vertices),
/// d = 2, centripetal data knots split uniformly, a ball of random radius about every data point.
fn balls_problem(n: usize) -> anyhow::Result<ConicProblem> {
    let k = BALLS_K;
    let (q, knots) = balls_data(n)?;
    let mut p = ConicProblem::new(&knots, 2)?;
    let spacing = std::f64::consts::TAU / n as f64;
    for (i, c) in q.iter().enumerate() {
        let r = spacing * (0.05 + 0.5 * ((i * 31 % 101) as f64 / 101.0));
        p.add_constraint(
            &[((k + 1) * i, 1.0)],
            ConvexSet::Ball {
                center: c.to_vec(),
                radius: r,
            },
        )?;
    }
    Ok(p)
}

/// The full-vertex backend alone on issue 3's balls problem, against Clarabel on the same SOCP
/// as posed (P = H ⊗ I).
fn full_vertex(opts: Opts) -> anyhow::Result<()> {
    println!("## conic — the full-vertex backend alone: issue 3's balls problem (closed, k = 3, d = 2), vs Clarabel as posed");
    println!();
    println!("| n | N | ours | iterations | certificate | Clarabel | Clarabel objective | rel. diff | ratio |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let sizes: &[usize] = if opts.quick {
        &[1_000]
    } else {
        &[1_000, 10_000, 100_000]
    };
    for &n in sizes {
        let p = balls_problem(n)?;
        let reps = if n >= 100_000 { 3 } else { 7 };
        let t = time_median(reps, || p.solve(&ConicOptions::default()));
        let sol = p.solve(&ConicOptions::default())?;
        let (tc, obj) = if n <= 10_000 {
            let (tc, obj) = clarabel_balls(&p)?;
            (Some(tc), Some(obj))
        } else {
            (None, None)
        };
        println!(
            "| {n} | {} | {:.2} ms | {} | {:.1e} | {} | {} | {} | {} |",
            4 * n,
            ms(t),
            sol.iterations,
            sol.kkt.total,
            tc.map(|d| format!("{:.2} ms", ms(d)))
                .unwrap_or_else(|| "—".into()),
            obj.map(|o| format!("{o:.10e}"))
                .unwrap_or_else(|| "—".into()),
            obj.map(|o| format!("{:.1e}", (o - sol.objective).abs() / sol.objective.abs()))
                .unwrap_or_else(|| "—".into()),
            tc.map(|c| format!("{:.0}×", c.as_secs_f64() / t.as_secs_f64()))
                .unwrap_or_else(|| "—".into()),
        );
    }
    println!();
    Ok(())
}

/// Clarabel's solve time (one run, setup excluded) and objective for a balls problem as posed,
/// built from the dense-free banded H.
fn clarabel_balls(p: &ConicProblem) -> anyhow::Result<(Duration, f64)> {
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SupportedConeT};
    let nv = p.len();
    let d = 2;
    let h = energy::Hessian::new(p.knots());
    let (dg, o1, o2) = h.bands();
    let (mut pi, mut pj, mut pv) = (vec![], vec![], vec![]);
    let mut push = |a: usize, b: usize, v: f64| {
        for c in 0..d {
            let (r, s) = (a * d + c, b * d + c);
            pi.push(r.min(s));
            pj.push(r.max(s));
            pv.push(v);
        }
    };
    for j in 0..nv {
        push(j, j, dg[j]);
        push(j, (j + 1) % nv, o1[j]);
        push(j, (j + 2) % nv, o2[j]);
    }
    let pm = CscMatrix::new_from_triplets(nv * d, nv * d, pi, pj, pv);
    let (mut ai, mut aj, mut av, mut b) = (vec![], vec![], vec![], vec![]);
    let mut cones = vec![];
    let mut row = 0;
    for (c, con) in p.constraints().iter().enumerate() {
        let ConvexSet::Ball { center, radius } = &con.set else {
            anyhow::bail!("constraint {c} is not a ball");
        };
        b.push(*radius);
        row += 1;
        for (comp, cc) in center.iter().enumerate() {
            ai.push(row);
            aj.push(con.stencil[0].0 * d + comp);
            av.push(1.0);
            b.push(*cc);
            row += 1;
        }
        cones.push(SupportedConeT::SecondOrderConeT(d + 1));
    }
    let am = CscMatrix::new_from_triplets(row, nv * d, ai, aj, av);
    let q = vec![0.0; nv * d];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut solver = DefaultSolver::new(&pm, &q, &am, &b, &cones, settings)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let t0 = Instant::now();
    solver.solve();
    Ok((t0.elapsed(), solver.solution.obj_val))
}
