//! Balls and direction wedges at every data point of a noisy closed star (ROBUSTNESS.md §4,
//! 13): the wedges about the chords q_{i+1} − q_{i−1} fight the star's zigzag, and at some
//! points the optimum stops — its derivative vanishes, the apex of the wedge's cone, which the
//! wedge allows (a cusp). Before the polish held such blocks at their apex these problems were
//! refused with `NotConverged` (this instance at 2.0e-8).

use divdiff::{DerivativeRule, Topology};
use refine::{Constraint, Problem, Tangent};

mod noisy;

#[test]
fn balls_and_wedges_with_cusps_are_certified() {
    let (n, half_angle) = (1000, 0.2);
    // The noisy star of the robustness note: radii alternating 1 and 1.5 with ±0.03 noise.
    let q = noisy::star(n, 15, 0.5, 0.03);
    let p = |i: usize| q.point(i % n).to_vec();
    let mut radii = Vec::new();
    let mut axes = Vec::new();
    for i in 0..n {
        let (a, b, c) = (p(i + n - 1), p(i), p(i + 1));
        radii.push(0.1 * (c[0] - b[0]).hypot(c[1] - b[1]));
        axes.push([c[0] - a[0], c[1] - a[1]]);
    }
    let tangents = axes
        .iter()
        .map(|a| {
            Some(Tangent::Wedge {
                direction: a.to_vec(),
                half_angle,
            })
        })
        .collect();
    let r = Problem::new(q.clone())
        .with_topology(Topology::Closed)
        .with_k(3)
        .with_knot_iterations(0)
        .with_constraint(Constraint::Balls(radii.clone()))
        .with_tangents(tangents)
        .solve()
        .expect("certified");
    assert!(r.kkt_residual <= 1e-9, "{}", r.kkt_residual);
    // Feasibility, recomputed: every ball, and every wedge through the Bessel derivative (the
    // problem's rule) on the returned knots; the cusps counted.
    let mut cusps = 0;
    let mut speed: f64 = 0.0;
    let mut derivatives = Vec::new();
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let (pv, qi) = (r.points.point(v), q.point(i));
        let dist = (pv[0] - qi[0]).hypot(pv[1] - qi[1]);
        assert!(
            dist <= radii[i] * (1.0 + 1e-9),
            "ball {i}: {dist} > {}",
            radii[i]
        );
        let stencil = divdiff::derivative_stencil(&r.knots, v, DerivativeRule::Bessel).unwrap();
        let mut df = [0.0; 2];
        for &(u, c) in stencil.iter() {
            for k in 0..2 {
                df[k] += c * (r.points.point(u)[k] - pv[k]);
            }
        }
        speed = speed.max(df[0].hypot(df[1]));
        derivatives.push(df);
    }
    for (i, (df, a)) in derivatives.iter().zip(&axes).enumerate() {
        let len = df[0].hypot(df[1]);
        if len <= 1e-9 * speed {
            cusps += 1;
            continue;
        }
        let cos = (df[0] * a[0] + df[1] * a[1]) / (len * a[0].hypot(a[1]));
        assert!(
            cos >= half_angle.cos() - 1e-9,
            "wedge {i}: angle {} > {half_angle}",
            cos.acos()
        );
    }
    let least = derivatives
        .iter()
        .map(|d| d[0].hypot(d[1]))
        .fold(f64::INFINITY, f64::min);
    assert!(cusps > 0, "no wedge at its apex (least |Df| {least:e} of {speed:e}): the case does not test what it is for");
}
