//! Points held in boxes of half-spaces (a tolerance per coordinate, as a drawing gives it), most
//! of them on a face or a corner at the optimum: the active-set polish does not settle such sets
//! (weakly active faces join and leave at every step), so the condensed working set's answer is
//! certified only after the method goes on to the strict tolerance
//! (`SolveOptions::strict_tolerance`). It goes on from its last iterate; the strategy list's
//! strict entry started over, which doubled the solve.

mod kersey_support;
mod noisy;

use divdiff::{Points, Topology};
use refine::{Constraint, Problem};

/// An axis-aligned box around every point, of half-width `ratio` times the shorter of the point's
/// chords to its neighbours (wrapping around).
fn boxes(q: &Points, ratio: f64) -> Constraint {
    let n = q.len();
    let chord = |i: usize| banded::vector::dist(q.point(i), q.point((i + 1) % n));
    kersey_support::cases::axis_boxes(q, |i| ratio * chord(i).min(chord((i + n - 1) % n)))
}

/// The noisy star of n = 3000 in boxes of 0.3 of the local spacing, closed and open: certified,
/// with the strict tolerance reached in one pass of the method (35 interior-point iterations
/// each, working-set rounds included; starting over at the strict entry took 68).
#[test]
fn boxes_reach_the_strict_tolerance_without_starting_over() {
    let n = 3000;
    let q = noisy::noisy_star(n);
    for topology in [Topology::Closed, Topology::Open] {
        let problem = Problem::new(q.clone())
            .with_topology(topology)
            .with_k(3)
            .with_knot_iterations(0)
            .with_constraint(boxes(&q, 0.3));
        let r = problem.solve().expect("points in boxes are certified");
        assert!(r.kkt_residual <= 1e-9, "{topology:?}: {}", r.kkt_residual);
        let active = r.active.iter().filter(|&&a| a).count();
        assert!(active > n / 2, "{topology:?}: {active} of {n} boxes active");
        assert!(
            r.iterations.solver < 60,
            "{topology:?}: {} iterations: the strict entry started over",
            r.iterations.solver
        );
    }
}
