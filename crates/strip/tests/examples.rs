//! The worked examples solve and show what they are designed to show.

mod common;

use strip::{solve, Options, Shape, Side};
use strip_testkit::examples::{example_5_1, example_5_2, example_5_3, large};

#[test]
fn example_5_1_has_touches_a_subarc_and_a_pair() {
    let p = example_5_1();
    let s = solve(&p, &Options::default()).unwrap();
    assert!(
        s.shapes.iter().any(|x| matches!(x, Shape::Touch(_))),
        "{:?}",
        s.shapes
    );
    assert!(
        s.shapes.iter().any(|x| matches!(x, Shape::Subarc(_))),
        "{:?}",
        s.shapes
    );
    assert!(
        s.shapes.iter().any(|x| matches!(x, Shape::Pair(_))),
        "{:?}",
        s.shapes
    );
    assert!(common::max_violation(&p, &s, 10_000) <= 1e-10);
    // the same structure as the paper's Figure 2: nine extra knots — five single touching
    // points, one subarc in the 12th interval, one touching pair in the 14th
    assert_eq!(s.extra_knots.len(), 9);
    assert_eq!(
        s.shapes
            .iter()
            .filter(|x| matches!(x, Shape::Touch(_)))
            .count(),
        5
    );
    assert!(matches!(s.shapes[11], Shape::Subarc(_)));
    assert!(matches!(s.shapes[13], Shape::Pair(_)));
    // the unconstrained spline leaves the strip
    let free = strip::Problem {
        lower: strip::Bound::None,
        upper: strip::Bound::None,
        ..p.clone()
    };
    let f = solve(&free, &Options::default()).unwrap();
    assert!(common::max_violation(&p, &f, 10_000) > 0.05);
    assert!(s.norm > f.norm);
}

#[test]
fn example_5_2_and_5_3_solve() {
    let p = example_5_2();
    let s = solve(&p, &Options::default()).unwrap();
    assert!(s.shapes.contains(&Shape::Touch(Side::Lower)));
    let p = example_5_3();
    let s = solve(&p, &Options::default()).unwrap();
    // f(0) = 0 lies on the upper bound: kept there exactly (polyline problems need no margin)
    assert!(s.shifted_data.is_empty());
    assert!(s.eval(0.0).abs() <= 1e-15);
    assert!(
        s.extra_knots.len() >= 6,
        "{} extra knots",
        s.extra_knots.len()
    );
    assert!(common::max_violation(&p, &s, 10_000) <= 1e-9);
    let lb = common::qp_lower_bound(&p, &common::qp_grid(&p, 400, Some(&s)));
    let gap = (s.energy - lb) / s.energy;
    assert!(gap.abs() <= 1e-9, "energy {} lower bound {lb}", s.energy);
}

#[test]
fn large_problem_has_many_active_intervals() {
    let p = large(300);
    let s = solve(&p, &Options::default()).unwrap();
    let active = s.shapes.iter().filter(|x| **x != Shape::Free).count();
    assert!(
        active * 2 > s.shapes.len(),
        "{active} of {}",
        s.shapes.len()
    );
    assert!(common::max_violation(&p, &s, 30_000) <= 1e-10);
    assert!(s.newton_decrement <= 1e-13 * s.energy);
}
