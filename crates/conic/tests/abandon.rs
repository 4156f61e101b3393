//! [`PolishOptions::abandon_first`]: the polish gives up when its first Newton step leaves the
//! residual above the limit, and is unchanged when the limit is never reached.

use conic::{Cone, Cones, DenseProblem, Options, PolishOptions};

/// minimize ½|x − c|² s.t. (r, x − o) ∈ Q³ for three balls (x ∈ R², one block each; c lies
/// outside every ball, so the answer is on the boundary of their intersection).
/// A = −[0 0; I] per block, b = (r, −o).
fn balls() -> DenseProblem {
    let centres = [[0.0, 0.0], [0.3, 0.1], [0.1, 0.4]];
    let radii = [1.0, 1.1, 0.9];
    let mut a = Vec::new();
    let mut b = Vec::new();
    for (o, r) in centres.iter().zip(radii) {
        a.extend([0.0, 0.0, -1.0, 0.0, 0.0, -1.0]);
        b.extend([r, -o[0], -o[1]]);
    }
    DenseProblem::new(
        vec![1.0, 0.0, 0.0, 1.0],
        vec![-3.0, -2.0],
        a,
        b,
        Cones::new(vec![Cone::SecondOrder(3); 3]).unwrap(),
    )
    .unwrap()
}

fn with_limit(limit: Option<f64>) -> Options {
    Options {
        polish: Some(PolishOptions {
            abandon_first: limit,
            ..PolishOptions::default()
        }),
        ..Options::default()
    }
}

#[test]
fn the_polish_gives_up_after_a_first_step_above_the_limit() {
    let mut p = balls();
    let loose = Options {
        tolerance: 1e-1,
        polish: None,
        ..Options::default()
    };
    let sol = conic::solve(&mut p, &loose).unwrap();
    assert!(sol.residuals.total > 1e-6, "{:?}", sol.residuals);
    let free = conic::polish::polish_solution(&mut p, &sol, &with_limit(None))
        .expect("the polish from the loose point");
    assert!(free.residuals.total <= 1e-10, "{:?}", free.residuals);
    // A limit no step reaches changes nothing, bit for bit.
    let never = conic::polish::polish_solution(&mut p, &sol, &with_limit(Some(f64::INFINITY)))
        .expect("the same polish");
    assert_eq!(
        free.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        never.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    // A first step from a loose point does not land exactly: a limit of 0 gives up.
    assert!(conic::polish::polish_solution(&mut p, &sol, &with_limit(Some(0.0))).is_none());
}
