//! The parallel passes (`src/par.rs`) give the same answer bit for bit on one thread and on
//! many: the chunks are fixed by the problem, not by the pool, and combined in order. Each solve
//! below spans several chunks (N ≥ 4·10⁴ vertices against chunks of 16 Ki) and goes through
//! the paths that run in parallel: the closed form and the k-level split (no knot update), the
//! streaming interpolation on updated knots (knot updates), and the certificate's pass; open and
//! closed, d = 2 and 3, on jittered data.
//!
//! That the chunked answer is the right one is checked elsewhere, independently of the chunking:
//! the pass against divdiff's jumps across chunk boundaries (`certify` unit tests), the points
//! by the certificate, which is computed from divided differences (every solve here must be
//! certified), and the large noisy case in `conditioning.rs`.

mod noisy;

use divdiff::{Parametrization, Points, Topology};
use noisy::noisy_star;
use refine::{Problem, Refinement};

/// The shared noisy star in d = 2, or lifted to d = 3 by z = 0.3 sin 3θ (θ its angle).
fn noisy_points(n: usize, d: usize) -> Points {
    let star = noisy_star(n);
    if d == 2 {
        return star;
    }
    let c = star
        .iter()
        .flat_map(|x| [x[0], x[1], 0.3 * (3.0 * x[1].atan2(x[0])).sin()])
        .collect();
    Points::new(3, c).expect("finite points")
}

fn solve_on(threads: usize, problem: &Problem) -> Refinement {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| problem.solve())
        .expect("the problem solves")
}

#[test]
fn one_thread_and_many_give_the_same_bits() {
    for (n, d, topology, updates) in [
        (6_000, 2, Topology::Closed, 0),
        (6_000, 3, Topology::Open, 0),
        (5_000, 2, Topology::Closed, 2),
        (5_000, 3, Topology::Open, 1),
    ] {
        let problem = Problem::new(noisy_points(n, d))
            .with_topology(topology)
            .with_parametrization(Parametrization::Centripetal)
            .with_k(7)
            .with_knot_iterations(updates);
        let one = solve_on(1, &problem);
        let many = solve_on(4, &problem);
        let case = format!("n = {n}, d = {d}, {topology:?}, {updates} updates");
        assert!(one.kkt_residual <= 1e-9, "{case}: kkt {}", one.kkt_residual);
        assert!(
            one.points.len() > 2 * (1 << 14),
            "{case}: spans several chunks"
        );
        let bits = |r: &Refinement| -> Vec<u64> {
            let mut b: Vec<u64> = r.points.coords().iter().map(|x| x.to_bits()).collect();
            b.extend(r.knots.values().iter().map(|x| x.to_bits()));
            b.extend(r.multipliers.iter().flatten().map(|x| x.to_bits()));
            b.extend([r.energy.to_bits(), r.kkt_residual.to_bits()]);
            b
        };
        assert!(
            bits(&one) == bits(&many),
            "{case}: one thread and four differ"
        );
    }
}
