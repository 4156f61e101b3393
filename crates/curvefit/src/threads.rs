//! The worker threads of the binary and the Python module: rayon's, each kept on a processor of
//! its own (Linux).
//!
//! # Why
//!
//! A solve alternates parallel passes with serial steps (a band solve, the certificate's
//! reductions), and rayon puts a worker that finds nothing to do to sleep within a fraction of a
//! millisecond. On Linux a thread that is woken is placed near the thread that woke it, and on
//! the 2-core development VM (2026-12-04) the woken worker waited there while the waker kept its
//! processor busy: after 50 ms idle, `rayon::join` of two 2 ms tasks took 4.0 ms (medians of
//! 20, the second task never moved to the idle processor), and 2.1 ms with each worker on a
//! processor of its own, where a wake costs 0.1–0.2 ms. A user's single call finds the workers
//! asleep, and so does each pass after a serial step: the certified interpolation of 10⁵ noisy
//! points at k = 7, closed, took 19.9–22.0 ms after 50 ms idle (medians of 21, three runs) and
//! 14.7–16.4 ms with the workers kept on their processors; back to back, where the workers are
//! still awake, the same within the machine's noise.
//!
//! # What
//!
//! [`builder`] is rayon's `ThreadPoolBuilder` whose worker i is restricted to the i-th processor
//! (modulo their number) of those the calling thread may run on — so a process started with
//! `taskset`, or in a container's cpuset, keeps to its processors. Nothing is restricted for a
//! pool of one worker, when fewer than two processors are allowed, on systems other than Linux,
//! or when the environment variable `CURVEFIT_PIN_THREADS` is `0`. [`install_global`] makes it
//! rayon's global pool (the binary at start, the Python module at import); the library crates
//! leave their pool to the caller (`refine::par`: the global one, or the one a caller
//! installs). Not on wasm32, which has no threads.

/// Rayon's pool builder for `threads` workers (`None`: rayon's default, `RAYON_NUM_THREADS` or
/// one per processor), each kept on a processor of its own when there are two or more (module
/// docs; one worker has no other to wait for, and stays free to move).
pub fn builder(threads: Option<usize>) -> rayon::ThreadPoolBuilder {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    match allowed_processors() {
        // (In the start handler the worker already belongs to its pool: rayon's own count.)
        Some(cpus) => builder.start_handler(move |i| {
            if rayon::current_num_threads() >= 2 {
                pin_to(cpus[i % cpus.len()]);
            }
        }),
        None => builder,
    }
}

/// Makes [`builder`]`(None)`'s pool rayon's global pool, unless that pool already exists (then
/// nothing changes: the first configuration stays).
pub fn install_global() {
    let _ = builder(None).build_global();
}

/// The processors the calling thread may run on, when the workers are to be kept on them: at
/// least two, on Linux, `CURVEFIT_PIN_THREADS` not `0`.
fn allowed_processors() -> Option<Vec<usize>> {
    if std::env::var_os("CURVEFIT_PIN_THREADS").is_some_and(|v| v == "0") {
        return None;
    }
    #[cfg(target_os = "linux")]
    {
        use rustix::thread::{sched_getaffinity, CpuSet};
        let set = sched_getaffinity(None).ok()?;
        let cpus: Vec<usize> = (0..CpuSet::MAX_CPU).filter(|&c| set.is_set(c)).collect();
        (cpus.len() >= 2).then_some(cpus)
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// Restricts the calling thread to processor `cpu` (a failure leaves it unrestricted).
#[cfg(target_os = "linux")]
fn pin_to(cpu: usize) {
    use rustix::thread::{sched_setaffinity, CpuSet};
    let mut set = CpuSet::new();
    set.set(cpu);
    let _ = sched_setaffinity(None, &set);
}

#[cfg(not(target_os = "linux"))]
fn pin_to(_: usize) {}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    /// A pool from [`super::builder`] runs worker i on the i-th allowed processor; a pool of one
    /// worker is left free.
    #[test]
    fn workers_keep_to_their_processors() {
        let Some(cpus) = super::allowed_processors() else {
            return; // one processor (or pinning switched off): nothing to check
        };
        let pool = super::builder(Some(cpus.len())).build().unwrap();
        let seen = pool.broadcast(|ctx| {
            let set = rustix::thread::sched_getaffinity(None).unwrap();
            (
                ctx.index(),
                set.count(),
                set.is_set(cpus[ctx.index() % cpus.len()]),
            )
        });
        for (i, count, on_own) in seen {
            assert_eq!(count, 1, "worker {i} may run on {count} processors");
            assert!(on_own, "worker {i} is not on processor {}", cpus[i]);
        }
        let one = super::builder(Some(1)).build().unwrap();
        let free = one.install(|| rustix::thread::sched_getaffinity(None).unwrap().count());
        assert_eq!(free as usize, cpus.len());
    }
}
