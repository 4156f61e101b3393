//! Benchmarks for the uniform schemes: one level of the (2m+2)-point n-ary scheme on 10^6 points
//! in R^3, reported as memory throughput (bytes read + bytes written per second) next to a
//! plain `copy_from_slice` (memcpy) of the output-sized buffer measured in the same run.

use std::time::Duration;

use divdiff::{Points, Topology};
use refine::{NaryScheme, NaturalScheme};

use super::{time_median, Opts};

fn gbps(bytes: usize, t: Duration) -> f64 {
    bytes as f64 / t.as_secs_f64() / 1e9
}

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let n = if opts.quick { 100_000 } else { 1_000_000 };
    let reps = if opts.quick { 3 } else { 15 };
    let dim = 3;
    // A smooth closed curve (a trefoil), so the data is not trivially compressible by caches.
    let coords: Vec<f64> = (0..n)
        .flat_map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            [
                t.sin() + 2.0 * (2.0 * t).sin(),
                t.cos() - 2.0 * (2.0 * t).cos(),
                -(3.0 * t).sin(),
            ]
        })
        .collect();
    let points = Points::new(dim, coords)?;
    let f = std::mem::size_of::<f64>();

    // Baseline: memcpy of a buffer the size of a binary level's output (read + write counted).
    let src = vec![1.0f64; 2 * n * dim];
    let mut dst = vec![0.0f64; 2 * n * dim];
    let t_copy = time_median(reps, || {
        dst.copy_from_slice(&src);
        dst[0]
    });
    let copy_bytes = 2 * src.len() * f;
    let copy_rate = gbps(copy_bytes, t_copy);
    println!("\n## schemes: one level on {n} points in R^3 (median of {reps})");
    println!(
        "{:<44} {:>10} {:>10} {:>9} {:>12}",
        "case", "time ms", "MB moved", "GB/s", "vs memcpy"
    );
    println!(
        "{:<44} {:>10.3} {:>10.1} {:>9.2} {:>12}",
        "memcpy (output-sized, binary)",
        t_copy.as_secs_f64() * 1e3,
        copy_bytes as f64 / 1e6,
        copy_rate,
        "1.00"
    );
    // Second baseline: the same access pattern as a binary level without arithmetic (each input
    // point written twice with ordinary stores, so the output's write-allocate reads are paid
    // as in the schemes, unlike memcpy's non-temporal stores).
    let input = points.coords();
    let mut up = vec![0.0f64; 2 * input.len()];
    let t_up = time_median(reps, || {
        for (src, dst) in input.chunks_exact(3).zip(up.chunks_exact_mut(6)) {
            dst[..3].copy_from_slice(src);
            dst[3..].copy_from_slice(src);
        }
        up[1]
    });
    let up_bytes = (input.len() + up.len()) * f;
    println!(
        "{:<44} {:>10.3} {:>10.1} {:>9.2} {:>12.2}",
        "plain upsampling copy (binary pattern)",
        t_up.as_secs_f64() * 1e3,
        up_bytes as f64 / 1e6,
        gbps(up_bytes, t_up),
        gbps(up_bytes, t_up) / copy_rate
    );
    let mut out = Vec::new();
    for (p, arity, topology, label) in [
        (4, 2, Topology::Closed, "4-point binary (DD), closed"),
        (4, 2, Topology::Open, "4-point binary (DD), open"),
        (6, 2, Topology::Closed, "6-point binary, closed"),
        (4, 3, Topology::Closed, "4-point ternary, closed"),
        (6, 3, Topology::Closed, "6-point ternary, closed"),
        (8, 4, Topology::Closed, "8-point quaternary, closed"),
    ] {
        let s = NaryScheme::new(p, arity)?;
        s.subdivide_level_into(&points, topology, &mut out)?;
        let t = time_median(reps, || {
            s.subdivide_level_into(&points, topology, &mut out)
                .map(|_| out[1])
        });
        let bytes = (points.coords().len() + out.len()) * f;
        let rate = gbps(bytes, t);
        println!(
            "{:<44} {:>10.3} {:>10.1} {:>9.2} {:>12.2}",
            label,
            t.as_secs_f64() * 1e3,
            bytes as f64 / 1e6,
            rate,
            rate / copy_rate
        );
    }
    // Natural cubic subdivision (sparse rows, allocating its output each time).
    let natural = NaturalScheme::new()?;
    let level = natural.subdivide_once(&points)?;
    let t = time_median(reps, || natural.subdivide_once(&points).map(|p| p.len()));
    let bytes = (points.coords().len() + level.coords().len()) * f;
    let rate = gbps(bytes, t);
    println!(
        "{:<44} {:>10.3} {:>10.1} {:>9.2} {:>12.2}",
        "natural cubic (Warren–Weimer), one level",
        t.as_secs_f64() * 1e3,
        bytes as f64 / 1e6,
        rate,
        rate / copy_rate
    );
    Ok(())
}
