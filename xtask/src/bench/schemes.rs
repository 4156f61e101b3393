//! Benchmarks for the uniform schemes: one level of the (2m+2)-point n-ary scheme on 10^6 points
//! in R^3, reported as memory throughput (bytes read + bytes written per second) next to two
//! baselines measured in the same run, interleaved with the kernel so that both see the same
//! machine load (the machine is shared): a plain `copy_from_slice` (memcpy) of a buffer of the
//! output's size, and a "pattern copy" that writes every input point n times into the output
//! (the scheme's access pattern without its arithmetic).

use std::time::{Duration, Instant};

use divdiff::{Points, Topology};
use subdivision::{NaryScheme, NaturalScheme};

use super::{time_median, Opts};

fn gbps(bytes: usize, t: Duration) -> f64 {
    bytes as f64 / t.as_secs_f64() / 1e9
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn timed(mut f: impl FnMut() -> f64) -> (Duration, f64) {
    let t = Instant::now();
    let x = f();
    (t.elapsed(), x)
}

/// Interleaved runs of (memcpy, pattern copy, kernel): median times and median per-round ratios.
struct Row {
    kernel: Duration,
    copy: Duration,
    pattern: Duration,
    vs_copy: f64,
    vs_pattern: f64,
}

fn interleaved(
    reps: usize,
    mut copy: impl FnMut() -> f64,
    mut pattern: impl FnMut() -> f64,
    mut kernel: impl FnMut() -> f64,
) -> Row {
    let (mut tk, mut tc, mut tp, mut rc, mut rp) = (vec![], vec![], vec![], vec![], vec![]);
    // One warm-up round (page faults, caches).
    std::hint::black_box((copy(), pattern(), kernel()));
    for _ in 0..reps {
        let (c, x) = timed(&mut copy);
        let (p, y) = timed(&mut pattern);
        let (k, z) = timed(&mut kernel);
        std::hint::black_box((x, y, z));
        tk.push(k.as_secs_f64());
        tc.push(c.as_secs_f64());
        tp.push(p.as_secs_f64());
        rc.push(c.as_secs_f64() / k.as_secs_f64());
        rp.push(p.as_secs_f64() / k.as_secs_f64());
    }
    Row {
        kernel: Duration::from_secs_f64(median(tk)),
        copy: Duration::from_secs_f64(median(tc)),
        pattern: Duration::from_secs_f64(median(tp)),
        vs_copy: median(rc),
        vs_pattern: median(rp),
    }
}

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let n = if opts.quick { 100_000 } else { 1_000_000 };
    let reps = if opts.quick { 5 } else { 21 };
    let dim = 3;
    // A smooth closed curve (a trefoil).
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
    let input = points.coords();
    let f = std::mem::size_of::<f64>();
    println!("\n## schemes: one level on {n} points in R^3 (median of {reps} interleaved rounds)");
    println!("GB/s = (bytes read + bytes written) / time; memcpy moves 2 × output bytes.");
    println!(
        "{:<36} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>10} {:>10}",
        "case", "ms", "MB", "GB/s", "copy ms", "copy GB/s", "pat. ms", "÷ memcpy", "÷ pattern"
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
        let src = vec![1.0f64; out.len()];
        let mut dst = vec![0.0f64; out.len()];
        let mut pat = vec![0.0f64; out.len()];
        let row = interleaved(
            reps,
            || {
                dst.copy_from_slice(&src);
                dst[1]
            },
            || {
                for (q, block) in input.chunks_exact(3).zip(pat.chunks_exact_mut(3 * arity)) {
                    for d in block.chunks_exact_mut(3) {
                        d.copy_from_slice(q);
                    }
                }
                pat[1]
            },
            || {
                let ok = s.subdivide_level_into(&points, topology, &mut out).is_ok();
                if ok {
                    out[1]
                } else {
                    f64::NAN
                }
            },
        );
        let bytes = (input.len() + out.len()) * f;
        let copy_bytes = 2 * out.len() * f;
        let rate = gbps(bytes, row.kernel);
        let copy_rate = gbps(copy_bytes, row.copy);
        println!(
            "{:<36} {:>8.3} {:>8.1} {:>8.2} {:>9.3} {:>9.2} {:>9.3} {:>10.2} {:>10.2}",
            label,
            row.kernel.as_secs_f64() * 1e3,
            bytes as f64 / 1e6,
            rate,
            row.copy.as_secs_f64() * 1e3,
            copy_rate,
            row.pattern.as_secs_f64() * 1e3,
            // Throughput ratio kernel/memcpy = (bytes/copy_bytes) · (t_copy/t_kernel).
            row.vs_copy * bytes as f64 / copy_bytes as f64,
            row.vs_pattern,
        );
    }
    // Natural cubic subdivision (sparse rows from the exactly derived S), into a reused buffer.
    let natural = NaturalScheme::new()?;
    let mut level = Vec::new();
    natural.subdivide_once_into(&points, &mut level)?;
    let runs = reps.min(9);
    let t = time_median(runs, || {
        natural
            .subdivide_once_into(&points, &mut level)
            .map_or(f64::NAN, |_| level[1])
    });
    let bytes = (input.len() + level.len()) * f;
    println!(
        "{:<36} {:>8.3} {:>8.1} {:>8.2}   (median of {runs}, not interleaved)",
        "natural cubic (Warren–Weimer)",
        t.as_secs_f64() * 1e3,
        bytes as f64 / 1e6,
        gbps(bytes, t)
    );
    Ok(())
}
