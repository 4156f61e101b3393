//! `cargo xtask bench [--quick] [FILTER]`: benchmark tables. Every speed claim is a ratio against
//! a baseline measured in the same run; nothing here is asserted as a wall-clock limit.

mod cli;
mod conic;
mod energy;
mod refine;
mod schemes;
mod strip;

use std::time::{Duration, Instant};

/// Options shared by all benchmark groups.
#[derive(Clone, Copy, Debug)]
pub struct Opts {
    /// Smaller sizes and fewer repetitions (for smoke runs).
    pub quick: bool,
}

/// The benches' uniform numbers in \[0, 1): a 64-bit LCG (Knuth's MMIX constants) from `seed`,
/// its top 53 bits. The noisy star and the noisy strip channel are drawn from it, so a table's
/// data are reproduced from the seed.
pub(super) fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The process's CPU time so far: every thread's, user and system (`CLOCK_PROCESS_CPUTIME_ID`).
pub fn cpu_time() -> Duration {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ProcessCPUTime);
    Duration::new(
        u64::try_from(t.tv_sec).unwrap_or(0),
        u32::try_from(t.tv_nsec).unwrap_or(0),
    )
}

/// The cores kept busy since `cpu` (a [`cpu_time`] reading taken `wall` ago): the process's CPU
/// time since then over the wall time. A pool's worker spinning while it waits for work counts
/// as busy, as it does for the machine.
pub fn cores_since(cpu: Duration, wall: Duration) -> f64 {
    (cpu_time() - cpu).as_secs_f64() / wall.as_secs_f64()
}

/// [`time_median`] and the cores its runs kept busy ([`cores_since`]), the warm-up included.
pub fn time_median_cores<T>(reps: usize, f: impl FnMut() -> T) -> (Duration, f64) {
    let (cpu, wall) = (cpu_time(), Instant::now());
    let t = time_median(reps, f);
    (t, cores_since(cpu, wall.elapsed()))
}

/// Median wall time of `reps` runs of `f` (after one warm-up run), back to back.
pub fn time_median<T>(reps: usize, f: impl FnMut() -> T) -> Duration {
    time_median_idle(reps, Duration::ZERO, f)
}

/// Median wall time of `reps` runs of `f` (after one warm-up run), each after `idle` asleep
/// (outside the time): a call that finds the machine idle, as a user's single call does, instead
/// of one right after the same call with its memory in cache.
pub fn time_median_idle<T>(reps: usize, idle: Duration, mut f: impl FnMut() -> T) -> Duration {
    std::hint::black_box(f());
    let mut v: Vec<Duration> = (0..reps.max(1))
        .map(|_| {
            if !idle.is_zero() {
                std::thread::sleep(idle);
            }
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed()
        })
        .collect();
    v.sort();
    v[v.len() / 2]
}

/// Runs the benchmark groups whose name contains the filter.
pub fn run(args: &[String]) -> anyhow::Result<bool> {
    let quick = args.iter().any(|a| a == "--quick");
    let filter = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .map(String::as_str)
        .unwrap_or("");
    let opts = Opts { quick };
    // The binary's and the Python module's pool: each worker on its own processor.
    curvefit::threads::install_global();
    println!("(allocator: mimalloc, as in the curvefit binary and the Python module; threads: rayon's pool, {} here, as the binary's and the Python module's: curvefit::threads, each worker on its own processor unless CURVEFIT_PIN_THREADS=0)", rayon::current_num_threads());
    if "energy".contains(filter) || filter.is_empty() {
        energy::run(opts)?;
    }
    if "refine".contains(filter) || filter.is_empty() {
        refine::run(opts)?;
    }
    if "hard".contains(filter) || filter.is_empty() {
        refine::hard(opts)?;
    }
    if "conic".contains(filter) || filter.is_empty() {
        conic::run(opts)?;
    }
    if "schemes".contains(filter) || filter.is_empty() {
        schemes::run(opts)?;
    }
    if "strip".contains(filter) || filter.is_empty() {
        strip::run(opts)?;
    }
    if "cli".contains(filter) || filter.is_empty() {
        cli::run(opts)?;
    }
    Ok(true)
}
