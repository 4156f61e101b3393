//! Benchmarks for `energy`: O(N) solves of (H ⊗ I_d + M) x = b against a dense nalgebra solve.
//!
//! Every row times factor + solve for all d coordinate columns (median of several runs). The
//! claim checked here is that the time per unknown (N·d) stays flat from N = 10^3 to 10^6, and
//! how far the banded solve is from a dense LU of the same matrix (N ≤ 2000).
use super::{time_median, Opts};
use divdiff::{Points, Topology};
use energy::System;
use nalgebra::{DMatrix, DVector};

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
    Ok(())
}
