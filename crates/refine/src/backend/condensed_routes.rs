//! Both routes of the condensed backend solve the same systems (tests).

use divdiff::{Knots, Topology};

/// The closed test curve: n data points m vertices apart on unequal knots, and their data (n × d).
fn closed_case(n: usize, m: usize, d: usize) -> (Knots, Vec<f64>) {
    let t: Vec<f64> = (0..=n * m)
        .map(|j| j as f64 * 0.7 + 0.1 * ((j * 7) % 5) as f64)
        .collect();
    let kn = Knots::new(Topology::Closed, t).unwrap();
    let q = (0..n * d)
        .map(|k| ((k * 13) % 7) as f64 * 0.3 - 1.0)
        .collect();
    (kn, q)
}

mod route_tests {
    use super::super::{Condensed, Face, PointSet};
    use crate::fast::Condensation;
    use crate::operator::Stencil;
    use conic::{KktSystem, Weights};

    /// The condensed elimination and the full-vertex one solve the same Newton system
    /// (Q + D)Δy = r for polytopes with orthant NT weights of widely spread size.
    #[test]
    fn both_routes_solve_the_same_system() {
        let (n, m, d) = (6usize, 3usize, 2usize);
        let (kn, q) = super::closed_case(n, m, d);
        let stencil = Stencil::new(&kn);
        let cond = Condensation::new(&kn, &stencil, n, m).unwrap();
        let face = |nx: f64, ny: f64, c: f64| {
            let l = (nx * nx + ny * ny).sqrt();
            Face {
                normal: vec![nx / l, ny / l],
                offset: c / l,
                norm: l,
            }
        };
        let sets: Vec<PointSet> = (0..n)
            .map(|i| {
                PointSet::Faces(vec![
                    face(1.0, 0.0, 1.0 + i as f64),
                    face(-1.0, 0.2, 1.0),
                    face(0.3, -1.0, 2.0),
                ])
            })
            .collect();
        let mut be = Condensed::new(&cond, &kn, q, sets, d).unwrap();
        let cones = be.cones().clone();
        // NT weights with θ spread over 1e-8 … 1e8.
        let mut w = Weights::zero(&cones);
        for b in 0..cones.len() {
            let v: Vec<f64> = (0..3)
                .map(|k| 10f64.powf(((b * 3 + k) % 9) as f64 - 4.0))
                .collect();
            w.set_nt(b, conic::Kind::Nonnegative, &v);
        }
        let r: Vec<f64> = (0..n * d).map(|k| ((k * 5) % 11) as f64 - 5.0).collect();
        be.factor(&w, 0.0).unwrap();
        let mut a = r.clone();
        be.solve(&mut a);
        be.route = super::super::Route::Full;
        be.factor_full(&w, 0.0).unwrap();
        let mut b = r.clone();
        be.solve(&mut b);
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-6 * scale, "{a:?}\n{b:?}");
        }
    }
}

mod polish_route_tests {
    use super::super::{Condensed, PointSet};
    use crate::fast::Condensation;
    use crate::operator::Stencil;
    use conic::{KktSystem, Weights};
    use divdiff::{Knots, Topology};

    /// The condensed route and the full-vertex one solve the same system for the polish's
    /// weights (an active ball's c(−J) + p uuᵀ with a stiff p, an inactive ball's 0): to
    /// rounding when every ball is active; with an inactive ball to about the floor of its
    /// weight (POLISH_FLOOR), which refinement against the exact Q + D removes in a few steps.
    #[test]
    fn both_routes_solve_the_polish_system() {
        for (closed, inactive) in [(true, false), (false, false), (true, true), (false, true)] {
            let (n, m, d) = (12usize, 4usize, 2usize);
            let topo = if closed {
                Topology::Closed
            } else {
                Topology::Open
            };
            let spans = if closed { n * m } else { (n - 1) * m };
            let t: Vec<f64> = (0..=spans)
                .map(|j| j as f64 * 0.7 + 0.1 * ((j * 7) % 5) as f64)
                .collect();
            let kn = Knots::new(topo, t).unwrap();
            let stencil = Stencil::new(&kn);
            let cond = Condensation::new(&kn, &stencil, n, m).unwrap();
            let q: Vec<f64> = (0..n * d)
                .map(|k| ((k * 13) % 7) as f64 * 0.3 - 1.0)
                .collect();
            let sets = vec![PointSet::Ball(0.1); n];
            let mut be = Condensed::new(&cond, &kn, q, sets, d).unwrap();
            let cones = be.cones().clone();
            let mut w = Weights::zero(&cones);
            for b in 0..cones.len() {
                if inactive && b == 3 {
                    // An inactive ball: Θ = 0.
                    continue;
                }
                let a = 0.3 + b as f64;
                let u = [
                    0.5f64.sqrt(),
                    -0.5f64.sqrt() * a.cos(),
                    -0.5f64.sqrt() * a.sin(),
                ];
                let scale = be.diagonal_scale(b);
                // (p = 1/δ with the condensed backend's polish penalty δ = 1e-6 relative.)
                w.set_active(b, scale * (0.01 + 0.1 * (b % 3) as f64), scale * 1e6, &u);
            }
            let r: Vec<f64> = (0..n * d).map(|k| ((k * 5) % 11) as f64 - 5.0).collect();
            // (Q + D) v, D = AᵀΘA: the lower-right d × d block of Θ per ball.
            let newton = |be: &mut Condensed<'_>, v: &[f64]| {
                let mut out = vec![0.0; v.len()];
                be.apply_p(v, &mut out);
                for b in 0..n {
                    let mut u = vec![0.0; d + 1];
                    u[1..].copy_from_slice(&v[b * d..(b + 1) * d]);
                    w.apply(b, &mut u);
                    for c in 0..d {
                        out[b * d + c] += u[1 + c];
                    }
                }
                out
            };
            be.route = super::super::Route::Full;
            be.factor_full(&w, 0.0).unwrap();
            let mut exact = r.clone();
            be.solve(&mut exact);
            let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            be.factor(&w, 0.0).unwrap();
            assert_eq!(be.route, super::super::Route::Condensed);
            let mut x = r.clone();
            be.solve(&mut x);
            let first = x
                .iter()
                .zip(&exact)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
                / scale;
            let bound = if inactive { 1e-3 } else { 1e-9 };
            assert!(
                first <= bound,
                "closed {closed} inactive {inactive}: {first:e}"
            );
            for _ in 0..3 {
                let kx = newton(&mut be, &x);
                let mut e: Vec<f64> = r.iter().zip(&kx).map(|(a, b)| a - b).collect();
                be.solve(&mut e);
                for (a, b) in x.iter_mut().zip(&e) {
                    *a += b;
                }
            }
            for (a, b) in x.iter().zip(&exact) {
                assert!(
                    (a - b).abs() <= 1e-9 * scale,
                    "closed {closed} inactive {inactive}: {a} vs {b}"
                );
            }
        }
    }
}

mod escalation_tests {
    use super::super::{Condensed, Face, PointSet, Route};
    use crate::fast::Condensation;
    use crate::operator::Stencil;
    use conic::{KktSystem, Weights};

    /// Route of each of `k` factorizations of `w`, with an escalation after the ones marked.
    fn routes(be: &mut Condensed<'_>, w: &Weights, escalate_after: &[bool]) -> Vec<Route> {
        escalate_after
            .iter()
            .map(|&esc| {
                be.factor(w, 0.0).unwrap();
                let route = be.route;
                if esc {
                    be.escalate();
                }
                route
            })
            .collect()
    }

    /// Balls: the first escalation sends the repeated step alone to the full-vertex route, the
    /// second every later system; polytopes: the first already does. A full-route factor is not
    /// escalated again (`escalate` is false: nothing more exact to offer).
    #[test]
    fn escalation_is_once_then_for_good_on_balls_and_for_good_on_polytopes() {
        let (n, m, d) = (6usize, 3usize, 2usize);
        let (kn, q) = super::closed_case(n, m, d);
        let stencil = Stencil::new(&kn);
        let cond = Condensation::new(&kn, &stencil, n, m).unwrap();
        let (c, f) = (Route::Condensed, Route::Full);

        let mut be =
            Condensed::new(&cond, &kn, q.clone(), vec![PointSet::Ball(0.2); n], d).unwrap();
        let mut w = Weights::zero(&be.cones().clone());
        for b in 0..n {
            // (η, w̄) with w̄₀² − |w̄₁|² = 1.
            w.set_nt(b, conic::Kind::SecondOrder, &[1.0, 1.25, 0.45, 0.6]);
        }
        assert_eq!(
            routes(
                &mut be,
                &w,
                &[false, true, false, false, true, false, false]
            ),
            [c, c, f, c, c, f, f]
        );
        assert!(!be.escalate(), "already exact");

        let face = Face {
            normal: vec![1.0, 0.0],
            offset: 1.0,
            norm: 1.0,
        };
        let sets = vec![PointSet::Faces(vec![face]); n];
        let mut be = Condensed::new(&cond, &kn, q, sets, d).unwrap();
        let mut w = Weights::zero(&be.cones().clone());
        for b in 0..n {
            w.set_nt(b, conic::Kind::Nonnegative, &[1.0]);
        }
        assert_eq!(routes(&mut be, &w, &[true, false, false]), [c, f, f]);
    }
}
