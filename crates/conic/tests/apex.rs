//! The active-set polish at a second-order cone's apex: the projection of a point onto a
//! direction wedge {x : (x − o)·a ≥ |x − o| cos θ} whose answer is the wedge's apex x = o (the
//! point lies in the polar cone, (c − o)·a ≤ −|c − o| sin θ). At the apex J s has no direction
//! a boundary constraint could hold: with [`PolishOptions::apex`] the block is held at s = 0,
//! its multiplier anywhere in the dual cone — here not unique, the wedge's three rows
//! (x·a / cos θ, x) being dependent.

use conic::{Cone, Cones, DenseProblem, Options, PolishOptions};

/// The wedge's apex.
const O: [f64; 2] = [1.0, -2.0];

/// minimize ½|x − c|² s.t. s = ((x − o)·a / cos θ, x − o) ∈ Q³: A = −[aᵀ / cos θ; I]
/// (row-major), b = A o.
fn wedge_projection(c: [f64; 2], a: [f64; 2], theta: f64) -> DenseProblem {
    let k = 1.0 / theta.cos();
    let rows = vec![-a[0] * k, -a[1] * k, -1.0, 0.0, 0.0, -1.0];
    let b = (0..3)
        .map(|r| rows[2 * r] * O[0] + rows[2 * r + 1] * O[1])
        .collect();
    DenseProblem::new(
        vec![1.0, 0.0, 0.0, 1.0],
        vec![-c[0], -c[1]],
        rows,
        b,
        Cones::new(vec![Cone::SecondOrder(3)]).unwrap(),
    )
    .unwrap()
}

/// |x − o|.
fn from_apex(x: &[f64]) -> f64 {
    (x[0] - O[0]).hypot(x[1] - O[1])
}

/// Cases: (c, a, θ) with c in the polar cone of the wedge, so that the projection is 0.
fn cases() -> Vec<([f64; 2], [f64; 2], f64)> {
    let unit = |t: f64| [t.cos(), t.sin()];
    let mut out = Vec::new();
    for (i, theta) in [0.05, 0.2, 0.7].into_iter().enumerate() {
        let a = unit(0.3 + i as f64);
        // c at angles from π (straight back) to just inside the polar cone's edge, π/2 + θ.
        for off in [0.0, 0.5, 0.9] {
            let phi =
                0.3 + i as f64 + std::f64::consts::PI - off * (std::f64::consts::FRAC_PI_2 - theta);
            let r = 0.5 + i as f64;
            out.push(([O[0] + r * phi.cos(), O[1] + r * phi.sin()], a, theta));
        }
    }
    out
}

/// The default options with the polish holding blocks at their apex
/// ([`PolishOptions::apex`]).
fn with_apex() -> Options {
    Options {
        polish: Some(PolishOptions {
            apex: true,
            ..PolishOptions::default()
        }),
        ..Options::default()
    }
}

fn dual_margin(z: &[f64]) -> f64 {
    z[0] - z[1].hypot(z[2])
}

#[test]
fn a_loose_answer_at_the_apex_is_polished_onto_it() {
    for (c, a, theta) in cases() {
        let mut p = wedge_projection(c, a, theta);
        let loose = Options {
            tolerance: 1e-5,
            polish: None,
            ..Options::default()
        };
        let sol = conic::solve(&mut p, &loose).unwrap();
        let x0 = from_apex(&sol.x);
        assert!(
            x0 > 1e-9,
            "the loose answer is not already at the apex: {x0:e}"
        );
        let polished = conic::polish::polish_solution(&mut p, &sol, &with_apex())
            .unwrap_or_else(|| panic!("no polished point for c = {c:?}, θ = {theta}"));
        let x = from_apex(&polished.x);
        assert!(x <= 1e-12, "c = {c:?}, θ = {theta}: |x − o| = {x:e}");
        assert!(
            polished.residuals.total <= 1e-12,
            "{:?}",
            polished.residuals
        );
        // The multiplier balances the pull of c (Aᵀz = −(x − c)) from inside the dual cone.
        assert!(dual_margin(&polished.z) >= 0.0, "z = {:?}", polished.z);
    }
}

#[test]
fn the_method_returns_the_apex_itself() {
    for (c, a, theta) in cases() {
        let mut p = wedge_projection(c, a, theta);
        let sol = conic::solve(&mut p, &with_apex()).unwrap();
        let x = from_apex(&sol.x);
        assert!(
            sol.polished,
            "c = {c:?}, θ = {theta}: returned unpolished, |x − o| = {x:e}"
        );
        assert!(x <= 1e-12, "c = {c:?}, θ = {theta}: |x − o| = {x:e}");
        assert!(sol.residuals.total <= 1e-12, "{:?}", sol.residuals);
    }
}
