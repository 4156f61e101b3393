//! Shared generators: random non-uniform knots and R^d data, open and closed.
#![allow(dead_code)]

use divdiff::{Knots, Points, Topology};
use proptest::prelude::*;

/// A random problem: knots with gaps in [0.2, 2.0] (ratio up to 10 between neighbours), points
/// with coordinates in [−3, 3], N vertices, dimension d.
#[derive(Clone, Debug)]
pub struct Problem {
    pub knots: Knots,
    pub points: Points,
}

pub fn topology() -> impl Strategy<Value = Topology> {
    prop_oneof![Just(Topology::Open), Just(Topology::Closed)]
}

/// N in `n_range` (at least 3 for closed curves), d in 1..=4.
pub fn problem(n_range: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Problem> {
    (topology(), n_range, 1usize..=4).prop_flat_map(|(top, n, d)| {
        let n = if top == Topology::Closed { n.max(3) } else { n };
        let m = if top == Topology::Closed { n + 1 } else { n };
        (
            -5.0f64..5.0,
            prop::collection::vec(0.2f64..2.0, m - 1),
            prop::collection::vec(-3.0f64..3.0, n * d),
        )
            .prop_map(move |(t0, gaps, coords)| {
                let mut t = vec![t0];
                for g in gaps {
                    let last = t[t.len() - 1];
                    t.push(last + g);
                }
                Problem {
                    knots: Knots::new(top, t).unwrap(),
                    points: Points::new(d, coords).unwrap(),
                }
            })
    })
}

/// |x|_∞ of a slice.
pub fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Σ x².
pub fn norm2(x: &[f64]) -> f64 {
    banded::vector::dot(x, x)
}
