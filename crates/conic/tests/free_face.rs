//! The active-set polish on a face of optimal points: when P's null space is orthogonal to every
//! active normal, the optimum is a segment, and the polish's matrix P + AᵀΘA is singular along
//! it. Asked to ([`PolishOptions::shift_singular`]), the polish factors it with the method's
//! static regularization and refines against the exact system (`conic::polish`; refine's ROBUSTNESS.md item 41, where a curve free to slide
//! between two faces of its boxes left the condensed working set at a certificate of 3e-6).

use conic::{Cone, Cones, DenseProblem, Options, PolishOptions};

/// minimize ½(x₁ + x₂)² − 3(x₁ + x₂) subject to x₁ + x₂ ≤ 1: the optimum is the line
/// x₁ + x₂ = 1 (z = 2), and P = [[1, 1], [1, 1]] does not see (1, −1).
fn on_a_line() -> DenseProblem {
    DenseProblem::new(
        vec![1.0, 1.0, 1.0, 1.0],
        vec![-3.0, -3.0],
        vec![1.0, 1.0],
        vec![1.0],
        Cones::new(vec![Cone::Nonnegative(1)]).unwrap(),
    )
    .unwrap()
}

#[test]
fn a_face_of_optimal_points_is_polished() {
    let mut p = on_a_line();
    let loose = Options::default().with_tolerance(1e-5).with_polish(None);
    let sol = conic::solve(&mut p, &loose).unwrap();
    let off = (sol.x[0] + sol.x[1] - 1.0).abs();
    assert!(
        off > 1e-12,
        "the loose answer is not already on the line: {off:e}"
    );
    // Without the shift the polish gives up on the singular matrix.
    assert!(conic::polish::polish_solution(&mut p, &sol, &Options::default()).is_none());
    let shifted = Options::default().with_polish(Some(PolishOptions {
        shift_singular: true,
        ..PolishOptions::default()
    }));
    let polished = conic::polish::polish_solution(&mut p, &sol, &shifted)
        .expect("a polished point on the singular system");
    let (x, z) = (&polished.x, &polished.z);
    assert!((x[0] + x[1] - 1.0).abs() <= 1e-12, "x = {x:?}");
    assert!((z[0] - 2.0).abs() <= 1e-12, "z = {z:?}");
    assert!(
        polished.residuals.total <= 1e-12,
        "{:?}",
        polished.residuals
    );
    // Along the free direction the steps leave the point where the method put it, but for
    // rounding amplified by the regularization's inverse (a 1e-12 shift).
    let slide = (x[0] - x[1]) - (sol.x[0] - sol.x[1]);
    assert!(slide.abs() <= 1e-3, "slid by {slide:e}");
}
