//! Feasible means solved (issue 17 §4): random problems with the features that used to be
//! refused — zero and tiny end derivatives, near-clamped radius 0, stiff and mixed smoothing
//! weights — are solved through `Problem::solve()` with the independent certificate ≤ 1e-9, and
//! their energy agrees with Clarabel's optimum of the same fixed-knot program on the returned
//! knots (an independent conic solver, `kersey_support`).

mod kersey_support;

use divdiff::{DerivativeRule, Points, Topology};
use kersey_support::{
    clarabel_problem, clarabel_problem_with_derivatives, clarabel_solve_socp, ConeKind,
};
use proptest::prelude::*;
use refine::{Boundary, Constraint, Problem};

/// n points in the plane or in space along a wavy open arc (x increasing, so consecutive points
/// differ), with noise.
fn arc() -> impl Strategy<Value = Points> {
    (3usize..8, 2usize..4).prop_flat_map(|(n, d)| {
        proptest::collection::vec(-0.4f64..0.4, n * d).prop_map(move |noise| {
            let mut c = Vec::with_capacity(n * d);
            for i in 0..n {
                let x = i as f64;
                c.push(x + 0.3 * noise[i * d]);
                c.push((1.3 * x).sin() + noise[i * d + 1]);
                if d == 3 {
                    c.push(0.5 * (0.7 * x).cos() + noise[i * d + 2]);
                }
            }
            Points::new(d, c).unwrap()
        })
    })
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

/// An end derivative: zero, tiny (1e-9 scale) or zero in some coordinates only.
fn end_derivative(d: usize) -> impl Strategy<Value = Vec<f64>> {
    (0usize..3, proptest::collection::vec(-1.0f64..1.0, d)).prop_map(|(kind, v)| match kind {
        0 => vec![0.0; v.len()],
        1 => v.iter().map(|x| 1e-9 * x).collect(),
        _ => v
            .iter()
            .enumerate()
            .map(|(i, &x)| if i == 0 { 0.0 } else { x })
            .collect(),
    })
}

/// Clarabel's energy for the problem `r` was solved as, on `r`'s knots.
fn clarabel_energy(
    q: &Points,
    r: &refine::Refinement,
    constraint: &Constraint,
    boundary: &Boundary,
) -> Option<f64> {
    let data = clarabel_problem_with_derivatives(
        &r.knots,
        q,
        &r.data_vertex,
        constraint,
        None,
        boundary,
        DerivativeRule::Bessel,
    )
    .unwrap();
    let reference = clarabel_solve_socp(&data, q.dim()).ok()?;
    Some(energy::energy(&r.knots, &reference.points).unwrap())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Clamped ends with zero or tiny derivatives (with and without knot updates, k = 1…5).
    #[test]
    fn clamped_zero_and_tiny_end_derivatives(
        q in arc(),
        k in 1usize..6,
        iters in 0usize..3,
        (start, end) in (2usize..4).prop_flat_map(|_| (end_derivative(3), end_derivative(3))),
    ) {
        let d = q.dim();
        let boundary = Boundary::Clamped { start: start[..d].to_vec(), end: end[..d].to_vec() };
        let r = Problem::new(q.clone()).with_topology(Topology::Open).with_k(k)
            .with_knot_iterations(iters).with_boundary(boundary.clone()).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        let e = clarabel_energy(&q, &r, &Constraint::Interpolate, &boundary);
        prop_assume!(e.is_some());
        let e = e.unwrap();
        prop_assert!(rel(r.energy, e) <= 1e-8, "{} vs Clarabel {}", r.energy, e);
    }

    /// Near-clamped ends of radius 0 (the clamped limit) about zero or tiny derivatives.
    #[test]
    fn near_clamped_radius_zero(
        q in arc(),
        k in 1usize..5,
        iters in 0usize..3,
        (start, end) in (2usize..4).prop_flat_map(|_| (end_derivative(3), end_derivative(3))),
    ) {
        let d = q.dim();
        let (start, end) = (start[..d].to_vec(), end[..d].to_vec());
        let boundary = Boundary::NearClamped { start: start.clone(), end: end.clone(), radius: 0.0 };
        let r = Problem::new(q.clone()).with_topology(Topology::Open).with_k(k)
            .with_knot_iterations(iters).with_boundary(boundary).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        // Radius 0 is clamped: the reference is the zero-cone program.
        let e = clarabel_energy(&q, &r, &Constraint::Interpolate, &Boundary::Clamped { start, end });
        prop_assume!(e.is_some());
        let e = e.unwrap();
        prop_assert!(rel(r.energy, e) <= 1e-8, "{} vs Clarabel {}", r.energy, e);
    }

    /// Stiff smoothing weights (1e12 … 1e300 at some points, ordinary or tiny (1e-300) at the
    /// others, the two ends stiff): solved, the stiff points met to rounding, and the energy that
    /// of the limit w → ∞ — interpolation at the stiff points, smoothing at the others — as
    /// Clarabel solves it (the two differ by O(‖H‖/w) ≤ 1e-10 relative here).
    #[test]
    fn stiff_and_mixed_smoothing_weights(
        q in arc(),
        k in 1usize..5,
        iters in 0usize..3,
        exponent in 12i32..301,
        pattern in proptest::collection::vec(0usize..3, 8),
        tiny_others in any::<bool>(),
    ) {
        let n = q.len();
        let stiff = 10f64.powi(exponent);
        // Points 0 and n − 1 always stiff (an open curve needs two weights), the rest by pattern.
        let is_stiff: Vec<bool> = (0..n).map(|i| i == 0 || i + 1 == n || pattern[i] == 0).collect();
        let other = if tiny_others { 1e-300 } else { 1.0 };
        let w: Vec<f64> = is_stiff.iter().map(|&s| if s { stiff } else { other }).collect();
        let c = Constraint::Smoothing(w.clone());
        let r = Problem::new(q.clone()).with_topology(Topology::Open).with_k(k)
            .with_knot_iterations(iters).with_constraint(c).solve().unwrap();
        prop_assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        for (i, &s) in is_stiff.iter().enumerate() {
            if s {
                let p = r.points.point(r.data_vertex[i]);
                for (a, b) in p.iter().zip(q.point(i)) {
                    // Within rounding of the data: |p − q| ≤ ‖H‖ L / w (module docs of linear).
                    prop_assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "point {i}: {a} vs {b}");
                }
            }
        }
        // The limit program: the other weights as they are, the stiff points interpolated
        // (zero-cone rows p_{i_k} = q_i added to Clarabel's smoothing program).
        let d = q.dim();
        let others: Vec<f64> = w.iter().zip(&is_stiff).map(|(&x, &s)| if s { 0.0 } else { x }).collect();
        let mut data = clarabel_problem(&r.knots, &q, &r.data_vertex, &Constraint::Smoothing(others));
        for (i, &s) in is_stiff.iter().enumerate() {
            if s {
                for c in 0..d {
                    let row = data.b.len();
                    data.a.rows.push(row);
                    data.a.cols.push(r.data_vertex[i] * d + c);
                    data.a.vals.push(1.0);
                    data.b.push(q.point(i)[c]);
                }
                data.cones.push((ConeKind::Zero, d));
            }
        }
        let reference = clarabel_solve_socp(&data, d);
        prop_assume!(reference.is_ok());
        let e = energy::energy(&r.knots, &reference.unwrap().points).unwrap();
        prop_assert!(rel(r.energy, e) <= 1e-8 || (r.energy - e).abs() <= 1e-12, "{} vs Clarabel {}", r.energy, e);
    }
}
