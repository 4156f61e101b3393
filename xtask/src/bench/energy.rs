//! Benchmarks for `energy`: O(N) solves of (H ⊗ I_d + M) x = b against a dense nalgebra solve.
//!
//! Every row times factor + solve for all d coordinate columns (median of several runs). The
//! claim checked here is that the time per unknown (N·d) stays flat from N = 10^3 to 10^6, and
//! how far the banded solve is from a dense LU of the same matrix (N ≤ 2000).
use super::{time_median, Opts};
use divdiff::{Points, Topology};
use energy::System;
use nalgebra::{DMatrix, DVector};
use refine::{ConicOptions, ConicProblem, ConvexSet};

/// Bands of Kersey's H = AᵀA (math.md §1) on knots with spans 1 + 0.5 sin(j).
fn bands(top: Topology, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let h: Vec<f64> = (0..n).map(|j| 1.0 + 0.5 * (j as f64).sin()).collect();
    let mut dg = vec![0.0; n];
    let mut o1 = vec![0.0; n];
    let mut o2 = vec![0.0; n];
    let rows = match top {
        Topology::Closed => 0..n,
        Topology::Open => 1..n - 1,
    };
    for i in rows {
        let (hm, hp) = (h[(i + n - 1) % n], h[i]);
        let s = (hm + hp).sqrt();
        let a1 = std::f64::consts::SQRT_2 / (hm * s);
        let a3 = std::f64::consts::SQRT_2 / (hp * s);
        let r = [a1, -a1 - a3, a3];
        let c = [(i + n - 1) % n, i, (i + 1) % n];
        for a in 0..3 {
            dg[c[a]] += r[a] * r[a];
        }
        o1[c[0]] += r[0] * r[1];
        o1[c[1]] += r[1] * r[2];
        o2[c[0]] += r[0] * r[2];
    }
    (dg, o1, o2)
}

/// The smoothing-type system: H ⊗ I_d plus unit weights at every 8th vertex (and, with
/// `blocks`, a 2×2 PSD block at every 4th vertex, which forces the block path).
fn system(top: Topology, n: usize, d: usize, blocks: bool) -> anyhow::Result<System> {
    let (dg, o1, o2) = bands(top, n);
    let mut s = System::from_bands(top, dg, o1, o2, d)?;
    for j in (0..n).step_by(8) {
        s.add_weight(j, 1.0)?;
    }
    if blocks {
        let mut b = vec![0.0; d * d];
        for c in 0..d {
            b[c * d + c] = 0.5;
        }
        b[0] += 0.25;
        for j in (0..n).step_by(4) {
            s.add_block(j, &b)?;
        }
    }
    Ok(s)
}

fn rhs(n: usize, d: usize) -> anyhow::Result<Points> {
    Ok(Points::new(
        d,
        (0..n * d)
            .map(|k| ((k * 7919) % 1000) as f64 / 500.0 - 1.0)
            .collect(),
    )?)
}

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    // Profiling hook: `CONIC_ONLY=n[,reps]` times only the conic balls problem of size n.
    if let Ok(spec) = std::env::var("CONIC_ONLY") {
        return conic_only(&spec);
    }
    println!("## energy: O(N) solves of (H ⊗ I_d + M) x = b (factor + solve, median)");
    println!();
    println!("| path | topology | N | d | time | ns / unknown |");
    println!("|---|---|---:|---:|---:|---:|");
    let sizes: &[usize] = if opts.quick {
        &[1_000, 10_000, 100_000]
    } else {
        &[1_000, 10_000, 100_000, 1_000_000]
    };
    let d = 2;
    for (path, blocks) in [("scalar", false), ("block", true)] {
        for top in [Topology::Open, Topology::Closed] {
            for &n in sizes {
                let s = system(top, n, d, blocks)?;
                let b = rhs(n, d)?;
                let reps = (2_000_000 / n).clamp(5, 200);
                let t = time_median(reps, || {
                    let f = s.factor().expect("nonsingular benchmark system");
                    f.solve(&b).expect("sizes match")
                });
                println!(
                    "| {path} | {top:?} | {n} | {d} | {:.3} ms | {:.2} |",
                    t.as_secs_f64() * 1e3,
                    t.as_secs_f64() * 1e9 / (n * d) as f64
                );
            }
        }
    }
    println!();
    println!(
        "Dense contrast (d = 1, closed): nalgebra LU of the same K vs the cyclic banded solve."
    );
    println!();
    println!("| N | dense LU | banded | ratio |");
    println!("|---:|---:|---:|---:|");
    let dense_sizes: &[usize] = if opts.quick {
        &[250, 500]
    } else {
        &[250, 500, 1000, 2000]
    };
    for &n in dense_sizes {
        let s = system(Topology::Closed, n, 1, false)?;
        let b = rhs(n, 1)?;
        // Dense K column by column through the banded operator (K e_j).
        let mut k = DMatrix::<f64>::zeros(n, n);
        for j in 0..n {
            let mut e = Points::zeros(n, 1);
            e.point_mut(j)[0] = 1.0;
            let col = s.apply(&e)?;
            for i in 0..n {
                k[(i, j)] = col.point(i)[0];
            }
        }
        let bv = DVector::from_column_slice(b.coords());
        let reps = if n >= 1000 { 3 } else { 10 };
        let td = time_median(reps, || k.clone().lu().solve(&bv));
        let tb = time_median(200, || {
            s.factor()
                .expect("nonsingular benchmark system")
                .solve(&b)
                .expect("sizes match")
        });
        // Same answer?
        let xd = k
            .clone()
            .lu()
            .solve(&bv)
            .unwrap_or_else(|| DVector::zeros(n));
        let xb = s.factor()?.solve(&b)?;
        let diff = (DVector::from_column_slice(xb.coords()) - &xd).norm() / xd.norm();
        println!(
            "| {n} | {:.3} ms | {:.4} ms | {:.0}× (solutions agree to {diff:.1e}) |",
            td.as_secs_f64() * 1e3,
            tb.as_secs_f64() * 1e3,
            td.as_secs_f64() / tb.as_secs_f64()
        );
    }
    println!();
    conic(opts)?;
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

/// The exact conic solver (refine::conic) on issue 3's balls problem, against Clarabel on the
/// same SOCP (built from the dense-free banded H: P = H ⊗ I as CSC).
fn conic(opts: Opts) -> anyhow::Result<()> {
    println!("## refine::conic — exact balls problem (closed, k = 3, d = 2), vs Clarabel");
    println!();
    println!("| n | N | conic time | iterations | KKT | Clarabel time | Clarabel objective | rel. diff | ratio |");
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
            let (tc, obj) = clarabel_balls(n)?;
            (Some(tc), Some(obj))
        } else {
            (None, None)
        };
        let fmt_ms = |d: std::time::Duration| format!("{:.2} ms", d.as_secs_f64() * 1e3);
        println!(
            "| {n} | {} | {} | {} | {:.1e} | {} | {} | {} | {} |",
            4 * n,
            fmt_ms(t),
            sol.iterations,
            sol.kkt.total,
            tc.map(fmt_ms).unwrap_or_else(|| "—".into()),
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

/// `CONIC_ONLY=n[,reps]`: the conic solver alone on `balls_problem(n)` (for profilers).
fn conic_only(spec: &str) -> anyhow::Result<()> {
    let mut it = spec.split(',');
    let n: usize = it.next().unwrap_or("10000").trim().parse()?;
    let reps: usize = it
        .next()
        .map(|r| r.trim().parse())
        .transpose()?
        .unwrap_or(5);
    let p = balls_problem(n)?;
    let t = time_median(reps, || p.solve(&ConicOptions::default()));
    // The minimum is the robust statistic on a loaded machine.
    let tmin = (0..reps.max(1))
        .map(|_| {
            let t0 = std::time::Instant::now();
            std::hint::black_box(p.solve(&ConicOptions::default()).is_ok());
            t0.elapsed()
        })
        .min()
        .unwrap_or_default();
    let sol = p.solve(&ConicOptions::default())?;
    // The Newton-system kernel alone: closed, N = 4n, d = 2, a 2×2 block at every 4th vertex.
    let s = system(Topology::Closed, 4 * n, 2, true)?;
    let b = rhs(4 * n, 2)?;
    let f = s.factor()?;
    let tf = time_median(reps, || s.factor().expect("nonsingular benchmark system"));
    let ts = time_median(reps, || f.solve(&b).expect("sizes match"));
    println!(
        "block system N = {}: factor {:.3} ms ({:.0} ns/vertex), solve {:.3} ms",
        4 * n,
        tf.as_secs_f64() * 1e3,
        tf.as_secs_f64() * 1e9 / (4 * n) as f64,
        ts.as_secs_f64() * 1e3
    );
    println!(
        "conic balls n = {n}: median {:.3} ms, min {:.3} ms, {} iterations, KKT {:.2e}, polished {}, objective {:.15e}",
        t.as_secs_f64() * 1e3,
        tmin.as_secs_f64() * 1e3,
        sol.iterations,
        sol.kkt.total,
        sol.polished,
        sol.objective
    );
    Ok(())
}

/// Clarabel's solve time (one run, setup excluded) and objective for `balls_problem(n)`.
fn clarabel_balls(n: usize) -> anyhow::Result<(std::time::Duration, f64)> {
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SupportedConeT};
    let p = balls_problem(n)?;
    let nv = p.len();
    let d = 2;
    // Rebuild H from the same knots through the problem's own definition: ½ pᵀ H p.
    let (_, knots) = balls_data(n)?;
    let h = energy::Hessian::new(&knots);
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
    let qv = vec![0.0; nv * d];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut solver = DefaultSolver::new(&pm, &qv, &am, &b, &cones, settings)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let start = std::time::Instant::now();
    solver.solve();
    Ok((start.elapsed(), solver.solution.obj_val))
}
