//! `refine::ConicProblem` against an independent Clarabel solve of the same conic program.
//!
//! The Clarabel formulation is built here from the definitions (P = H ⊗ I_d + W from the dense
//! Hessian, fixed vertices as zero cones, balls and wedges as second-order cones, half-spaces as
//! the nonnegative orthant), without any code of the solver under test.
#![allow(non_snake_case)]
// Assembling rows coordinate by coordinate reads more clearly with index loops.
#![allow(clippy::needless_range_loop)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use divdiff::{Knots, Points, Topology};
use energy::Hessian;
use refine::{ConicOptions, ConicProblem, ConicSolution, ConvexSet, Error};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// Knots with random spans in [0.5, 1.5] for N vertices.
fn knots(top: Topology, n: usize, rng: &mut Rng) -> Knots {
    let count = if top == Topology::Closed { n + 1 } else { n };
    let mut t = vec![0.0];
    for _ in 1..count {
        let last = *t.last().unwrap();
        t.push(last + rng.range(0.5, 1.5));
    }
    Knots::new(top, t).unwrap()
}

/// A problem description kept alongside the solver's, for the Clarabel formulation.
struct Spec {
    knots: Knots,
    d: usize,
    fixed: Vec<(usize, Vec<f64>)>,
    smoothing: Vec<(usize, f64, Vec<f64>)>,
    constraints: Vec<(Vec<(usize, f64)>, ConvexSet)>,
}

impl Spec {
    fn new(top: Topology, n: usize, d: usize, rng: &mut Rng) -> Self {
        Spec {
            knots: knots(top, n, rng),
            d,
            fixed: vec![],
            smoothing: vec![],
            constraints: vec![],
        }
    }
    fn n(&self) -> usize {
        self.knots.vertex_count()
    }
    /// Derivative stencil (2.2): ½(s_{i−1} + s_i) at an interior vertex (cyclic for closed).
    fn df(&self, i: usize) -> Vec<(usize, f64)> {
        let n = self.n();
        let (hm, hp) = (self.knots.h(i as isize - 1), self.knots.h(i as isize));
        let (a, c) = ((i + n - 1) % n, (i + 1) % n);
        vec![(a, -0.5 / hm), (i, 0.5 / hm - 0.5 / hp), (c, 0.5 / hp)]
    }

    fn problem(&self) -> ConicProblem {
        let mut p = ConicProblem::new(&self.knots, self.d).unwrap();
        for (v, a) in &self.fixed {
            p.fix(*v, a).unwrap();
        }
        for (v, w, q) in &self.smoothing {
            p.add_smoothing(*v, *w, q).unwrap();
        }
        for (st, set) in &self.constraints {
            p.add_constraint(st, set.clone()).unwrap();
        }
        p
    }

    /// Clarabel's optimal objective of the same problem, plus the constant ½Σw|q|².
    fn clarabel(&self) -> f64 {
        let (n, d) = (self.n(), self.d);
        let nv = n * d;
        let hd = Hessian::new(&self.knots).to_dense();
        // P (upper triangle) and q.
        let mut P = vec![vec![0.0; nv]; nv];
        for i in 0..n {
            for j in 0..n {
                for c in 0..d {
                    P[i * d + c][j * d + c] = hd[(i, j)];
                }
            }
        }
        let mut q = vec![0.0; nv];
        let mut constant = 0.0;
        for (v, w, t) in &self.smoothing {
            for c in 0..d {
                P[v * d + c][v * d + c] += w;
                q[v * d + c] -= w * t[c];
                constant += 0.5 * w * t[c] * t[c];
            }
        }
        let mut A: Vec<Vec<f64>> = Vec::new();
        let mut b = Vec::new();
        let mut cones = Vec::new();
        let lrow = |st: &[(usize, f64)], comp: usize, scale: f64| {
            let mut r = vec![0.0; nv];
            for &(v, c) in st {
                r[v * d + comp] += scale * c;
            }
            r
        };
        for (v, a) in &self.fixed {
            for c in 0..d {
                A.push(lrow(&[(*v, 1.0)], c, 1.0));
                b.push(a[c]);
            }
            cones.push(SupportedConeT::ZeroConeT(d));
        }
        for (st, set) in &self.constraints {
            match set {
                ConvexSet::Ball { center, radius } if *radius > 0.0 => {
                    A.push(vec![0.0; nv]);
                    b.push(*radius);
                    for c in 0..d {
                        A.push(lrow(st, c, 1.0));
                        b.push(center[c]);
                    }
                    cones.push(SupportedConeT::SecondOrderConeT(d + 1));
                }
                ConvexSet::Ball { center: v, .. } | ConvexSet::Point(v) => {
                    for c in 0..d {
                        A.push(lrow(st, c, 1.0));
                        b.push(v[c]);
                    }
                    cones.push(SupportedConeT::ZeroConeT(d));
                }
                ConvexSet::HalfSpaces(hs) => {
                    for (nr, o) in hs {
                        let mut r = vec![0.0; nv];
                        for c in 0..d {
                            let rc = lrow(st, c, nr[c]);
                            for k in 0..nv {
                                r[k] += rc[k];
                            }
                        }
                        A.push(r);
                        b.push(*o);
                    }
                    cones.push(SupportedConeT::NonnegativeConeT(hs.len()));
                }
                ConvexSet::Cone { axis, half_angle } => {
                    // s = (a·y / cos θ, y) ∈ Q with s = b − A x.
                    let mut r = vec![0.0; nv];
                    for c in 0..d {
                        let rc = lrow(st, c, -axis[c] / half_angle.cos());
                        for k in 0..nv {
                            r[k] += rc[k];
                        }
                    }
                    A.push(r);
                    b.push(0.0);
                    for c in 0..d {
                        A.push(lrow(st, c, -1.0));
                        b.push(0.0);
                    }
                    cones.push(SupportedConeT::SecondOrderConeT(d + 1));
                }
            }
        }
        let csc = |rows: &[Vec<f64>], ncols: usize, upper: bool| {
            let (mut I, mut J, mut V) = (vec![], vec![], vec![]);
            for (i, r) in rows.iter().enumerate() {
                for (j, &v) in r.iter().enumerate() {
                    if v != 0.0 && (!upper || j >= i) {
                        I.push(i);
                        J.push(j);
                        V.push(v);
                    }
                }
            }
            CscMatrix::new_from_triplets(rows.len(), ncols, I, J, V)
        };
        let Pm = csc(&P, nv, true);
        let Am = csc(&A, nv, false);
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(1e-11)
            .tol_gap_rel(1e-11)
            .tol_feas(1e-11)
            .max_iter(200)
            .build()
            .unwrap();
        let mut solver = DefaultSolver::new(&Pm, &q, &Am, &b, &cones, settings).unwrap();
        solver.solve();
        assert!(
            matches!(solver.solution.status, SolverStatus::Solved),
            "clarabel status {:?}",
            solver.solution.status
        );
        solver.solution.obj_val + constant
    }
}

/// Solves with both solvers and checks the certificate and the agreement of the optima.
fn check(spec: &Spec) -> ConicSolution {
    let sol = spec.problem().solve(&ConicOptions::default()).unwrap();
    let reference = spec.clarabel();
    assert!(
        sol.kkt.total <= 1e-9,
        "KKT {:?} after {} iterations",
        sol.kkt,
        sol.iterations
    );
    // Relative agreement. Problems whose optimum has E = 0 are compared on the energy scale
    // of the data, max|H| · max|p|², times 1e-4 (so a zero optimum must agree to 1e-12 of it).
    let h = Hessian::new(&spec.knots);
    let xmax = sol
        .points
        .coords()
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let floor = 1e-4 * h.max_abs() * xmax * xmax;
    let scale = sol.objective.abs().max(reference.abs()).max(floor);
    assert!(
        (sol.objective - reference).abs() <= 1e-8 * scale,
        "objective {} vs clarabel {} (rel {:e}), {:?}, {} iterations",
        sol.objective,
        reference,
        (sol.objective - reference).abs() / scale,
        sol.kkt,
        sol.iterations
    );
    // The reported energy is E of (2.1) for the reported points (the divided-difference form,
    // as accurate as the solver's difference form; ½pᵀHp would cancel to ~ε max|H| max|p|² when
    // E ≈ 0).
    let e = energy::energy(&spec.knots, &sol.points).unwrap();
    assert!(
        (e - sol.energy).abs() <= 1e-12 * e + 1e-14 * h.max_abs() * xmax * xmax,
        "{e} vs {}",
        sol.energy
    );
    sol
}

/// n data points on a noisy circle (d ≥ 2: first two coordinates; others random small).
fn data(n: usize, d: usize, rng: &mut Rng) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            (0..d)
                .map(|c| match c {
                    0 => 3.0 * a.cos() + rng.range(-0.3, 0.3),
                    1 => 2.0 * a.sin() + rng.range(-0.3, 0.3),
                    _ => rng.range(-0.5, 0.5),
                })
                .collect()
        })
        .collect()
}

fn balls_spec(top: Topology, n: usize, k: usize, d: usize, seed: u64) -> Spec {
    let mut rng = Rng(seed);
    let nv = if top == Topology::Closed {
        (k + 1) * n
    } else {
        (k + 1) * (n - 1) + 1
    };
    let mut spec = Spec::new(top, nv, d, &mut rng);
    for (i, q) in data(n, d, &mut rng).into_iter().enumerate() {
        let r = if i % 4 == 3 {
            0.0
        } else {
            rng.range(0.05, 0.8)
        };
        spec.constraints.push((
            vec![((k + 1) * i, 1.0)],
            ConvexSet::Ball {
                center: q,
                radius: r,
            },
        ));
    }
    spec
}

#[test]
fn balls_closed_and_open_in_1_2_3_dimensions() {
    for (top, d, seed) in [
        (Topology::Closed, 2, 1),
        (Topology::Closed, 3, 2),
        (Topology::Closed, 1, 3),
        (Topology::Open, 2, 4),
        (Topology::Open, 1, 5),
        (Topology::Open, 3, 6),
    ] {
        let spec = balls_spec(top, 7, 2, d, seed);
        let sol = check(&spec);
        assert!(
            sol.polished,
            "{top:?} d={d}: the active-set polish should succeed here"
        );
        // Kersey (3.5): z_c = w_c (p − q) with w_c ≥ 0 for balls of positive radius, and
        // inactive balls carry no force.
        for (c, (st, set)) in spec.constraints.iter().enumerate() {
            if let (ConvexSet::Ball { center, radius }, Some(w)) = (set, sol.ball_weights[c]) {
                assert!(*radius > 0.0 && w >= -1e-9);
                let p = sol.points.point(st[0].0);
                for k in 0..d {
                    let want = w * (p[k] - center[k]);
                    assert!(
                        (sol.forces[c][k] - want).abs() <= 1e-6 * (1.0 + want.abs()),
                        "{top:?} d={d} c={c}: force {:?} vs w(p − q) = {want} (w = {w}, active {})",
                        sol.forces[c],
                        sol.active[c]
                    );
                }
                if !sol.active[c] {
                    assert!(w.abs() <= 1e-6, "inactive ball {c} has weight {w}");
                }
            }
        }
    }
}

#[test]
fn balls_with_smoothing_terms_and_fixed_vertices() {
    let mut spec = balls_spec(Topology::Closed, 6, 1, 2, 11);
    let mut rng = Rng(12);
    spec.fixed.push((3, vec![0.5, 1.5]));
    for v in [5, 7] {
        spec.smoothing.push((
            v,
            rng.range(0.5, 5.0),
            vec![rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)],
        ));
    }
    check(&spec);
}

#[test]
fn polygons_and_polytopes() {
    for (top, d, seed) in [
        (Topology::Closed, 2, 21),
        (Topology::Open, 3, 22),
        (Topology::Open, 1, 23),
    ] {
        let mut rng = Rng(seed);
        let n = 6;
        let k = 2;
        let nv = if top == Topology::Closed {
            (k + 1) * n
        } else {
            (k + 1) * (n - 1) + 1
        };
        let mut spec = Spec::new(top, nv, d, &mut rng);
        for (i, q) in data(n, d, &mut rng).into_iter().enumerate() {
            // A random polytope containing q: 2d + 1 half-spaces at random distances.
            let hs: Vec<(Vec<f64>, f64)> = (0..2 * d + 1)
                .map(|_| {
                    let nr: Vec<f64> = (0..d).map(|_| rng.range(-1.0, 1.0)).collect();
                    let o =
                        nr.iter().zip(&q).map(|(a, b)| a * b).sum::<f64>() + rng.range(0.05, 0.5);
                    (nr, o)
                })
                .collect();
            spec.constraints
                .push((vec![((k + 1) * i, 1.0)], ConvexSet::HalfSpaces(hs)));
        }
        if top == Topology::Open {
            // Smoothing terms toward the data make the solution unique even where the
            // polytopes are unbounded.
            for (i, q) in data(n, d, &mut rng).into_iter().enumerate() {
                spec.smoothing.push(((k + 1) * i, 0.5, q));
            }
        }
        check(&spec);
    }
}

#[test]
fn wedges_and_balls_on_derivative_stencils() {
    let mut spec = balls_spec(Topology::Closed, 6, 2, 2, 31);
    // Direction wedges on Df at data vertices 1 and 4, a ball on Df at 2 (Fig. 3.5a) and a
    // ball about the origin on Df at 5 (Fig. 3.5c, tension).
    let ax = |a: f64| vec![a.cos(), a.sin()];
    let df1 = spec.df(3);
    let df2 = spec.df(6);
    let df4 = spec.df(12);
    let df5 = spec.df(15);
    spec.constraints.push((
        df1,
        ConvexSet::Cone {
            axis: ax(2.0),
            half_angle: 0.2,
        },
    ));
    spec.constraints.push((
        df4,
        ConvexSet::Cone {
            axis: ax(-1.0),
            half_angle: 0.4,
        },
    ));
    spec.constraints.push((
        df2,
        ConvexSet::Ball {
            center: vec![-1.0, 1.0],
            radius: 0.3,
        },
    ));
    spec.constraints.push((
        df5,
        ConvexSet::Ball {
            center: vec![0.0, 0.0],
            radius: 0.2,
        },
    ));
    let sol = check(&spec);
    assert!(
        sol.active[spec.constraints.len() - 1],
        "tension ball should be active"
    );
}

#[test]
fn clamped_ends_are_derivative_equalities() {
    // Open curve, d = 2 and d = 3: end derivative stencils (one-sided) fixed to given vectors,
    // a derivative equality in the interior, balls elsewhere.
    for (d, seed) in [(2, 41), (3, 42)] {
        let mut spec = balls_spec(Topology::Open, 5, 2, d, seed);
        let n = spec.n();
        let h0 = spec.knots.h(0);
        let hl = spec.knots.h(n as isize - 2);
        let v0: Vec<f64> = (0..d).map(|c| if c == 0 { 1.0 } else { 0.5 }).collect();
        let v1: Vec<f64> = (0..d).map(|c| if c == 1 { -1.0 } else { 0.2 }).collect();
        spec.constraints
            .push((vec![(0, -1.0 / h0), (1, 1.0 / h0)], ConvexSet::Point(v0)));
        spec.constraints.push((
            vec![(n - 2, -1.0 / hl), (n - 1, 1.0 / hl)],
            ConvexSet::Point(v1),
        ));
        let dfm = spec.df(4);
        spec.constraints.push((
            dfm,
            ConvexSet::Ball {
                center: vec![0.3; d],
                radius: 0.0,
            },
        ));
        let sol = check(&spec);
        assert!(sol.active.iter().rev().take(3).all(|&a| a));
    }
}

#[test]
fn balls_sharing_a_point_give_a_constant_curve() {
    // Every ball contains the point (1, −2): the optimum is a constant curve with E = 0.
    for top in [Topology::Closed, Topology::Open] {
        let mut rng = Rng(51);
        let nv = 12;
        let mut spec = Spec::new(top, nv, 2, &mut rng);
        for v in (0..nv).step_by(3) {
            let dir = rng.range(0.0, 6.0);
            let r = rng.range(0.5, 1.0);
            // Center at distance 0.9 r from the common point.
            let center = vec![1.0 + 0.9 * r * dir.cos(), -2.0 + 0.9 * r * dir.sin()];
            spec.constraints
                .push((vec![(v, 1.0)], ConvexSet::Ball { center, radius: r }));
        }
        let sol = spec.problem().solve(&ConicOptions::default()).unwrap();
        assert!(sol.kkt.total <= 1e-9, "{:?}", sol.kkt);
        assert!(sol.energy <= 1e-12, "E = {}", sol.energy);
        if top == Topology::Closed {
            // ker H = constants: the curve is a single point.
            let p0 = sol.points.point(0).to_vec();
            for p in sol.points.iter() {
                assert!((p[0] - p0[0]).abs() + (p[1] - p0[1]).abs() <= 1e-6);
            }
        } else {
            // ker H = linear polynomials: Hp = 0.
            let h = Hessian::new(&spec.knots);
            let hp = h.apply(&sol.points);
            assert!(hp.coords().iter().all(|v| v.abs() <= 1e-8 * h.max_abs()));
        }
        let reference = spec.clarabel();
        assert!(reference.abs() <= 1e-8, "clarabel {reference}");
    }
}

#[test]
fn collinear_data_and_smallest_sizes() {
    // Collinear data in R^2 (the optimum is a straight line through the balls).
    let mut rng = Rng(61);
    let mut spec = Spec::new(Topology::Open, 9, 2, &mut rng);
    for (i, v) in [0usize, 4, 8].into_iter().enumerate() {
        let x = i as f64;
        spec.constraints.push((
            vec![(v, 1.0)],
            ConvexSet::Ball {
                center: vec![x, 2.0 * x],
                radius: 0.1,
            },
        ));
    }
    check(&spec);
    // Closed curve with the smallest N = 3 (bands alias), d = 1 and d = 2.
    for d in [1, 2] {
        let mut spec = Spec::new(Topology::Closed, 3, d, &mut rng);
        for v in 0..3 {
            let c: Vec<f64> = (0..d).map(|_| rng.range(-3.0, 3.0)).collect();
            spec.constraints.push((
                vec![(v, 1.0)],
                ConvexSet::Ball {
                    center: c,
                    radius: 0.3,
                },
            ));
        }
        check(&spec);
    }
}

#[test]
fn infeasible_and_malformed_input_are_typed_errors() {
    let mut rng = Rng(71);
    let mut spec = balls_spec(Topology::Closed, 5, 1, 2, 72);
    // An empty polygon: x ≤ 0 and x ≥ 1.
    spec.constraints.push((
        vec![(3, 1.0)],
        ConvexSet::HalfSpaces(vec![(vec![1.0, 0.0], 0.0), (vec![-1.0, 0.0], -1.0)]),
    ));
    let idx = spec.constraints.len() - 1;
    assert_eq!(
        spec.problem().solve(&ConicOptions::default()).unwrap_err(),
        Error::Infeasible { constraint: idx }
    );
    // A fixed vertex outside its own ball.
    let mut spec = Spec::new(Topology::Closed, 6, 2, &mut rng);
    spec.fixed.push((2, vec![5.0, 5.0]));
    spec.constraints.push((
        vec![(0, 1.0)],
        ConvexSet::Ball {
            center: vec![0.0, 0.0],
            radius: 1.0,
        },
    ));
    spec.constraints.push((
        vec![(2, 1.0)],
        ConvexSet::Ball {
            center: vec![0.0, 0.0],
            radius: 1.0,
        },
    ));
    assert_eq!(
        spec.problem().solve(&ConicOptions::default()).unwrap_err(),
        Error::Infeasible { constraint: 1 }
    );
    // Malformed constraints.
    let mut p = ConicProblem::new(&knots(Topology::Closed, 6, &mut rng), 2).unwrap();
    let ball = |r: f64| ConvexSet::Ball {
        center: vec![0.0, 0.0],
        radius: r,
    };
    assert!(matches!(
        p.add_constraint(&[(9, 1.0)], ball(1.0)),
        Err(Error::VertexOutOfRange { .. })
    ));
    assert!(matches!(
        p.add_constraint(&[(0, 1.0)], ball(-1.0)),
        Err(Error::InvalidConstraint { .. })
    ));
    assert!(matches!(
        p.add_constraint(&[(0, 1.0), (3, 1.0)], ball(1.0)),
        Err(Error::InvalidConstraint { .. })
    ));
    assert!(matches!(
        p.add_constraint(
            &[(0, 1.0)],
            ConvexSet::Ball {
                center: vec![0.0],
                radius: 1.0
            }
        ),
        Err(Error::WrongDimension { .. })
    ));
    assert!(matches!(
        p.add_constraint(
            &[(0, 1.0)],
            ConvexSet::Cone {
                axis: vec![2.0, 0.0],
                half_angle: 0.1
            }
        ),
        Err(Error::InvalidConstraint { .. })
    ));
    assert!(matches!(
        p.add_constraint(
            &[(0, 1.0)],
            ConvexSet::HalfSpaces(vec![(vec![0.0, 0.0], 1.0)])
        ),
        Err(Error::InvalidConstraint { .. })
    ));
    assert!(matches!(
        p.fix(0, &[f64::NAN, 0.0]),
        Err(Error::NonFiniteInput { .. })
    ));
    let bad_warm = ConicOptions::default().with_warm_start(Points::zeros(3, 2));
    p.add_constraint(&[(0, 1.0)], ball(1.0)).unwrap();
    assert!(matches!(
        p.solve(&bad_warm),
        Err(Error::WrongDimension { .. })
    ));
}

#[test]
fn warm_start_from_the_optimum_converges_quickly() {
    let spec = balls_spec(Topology::Closed, 8, 2, 2, 81);
    let p = spec.problem();
    let cold = p.solve(&ConicOptions::default()).unwrap();
    let warm = p
        .solve(&ConicOptions::default().with_warm_start(cold.points.clone()))
        .unwrap();
    assert!(warm.kkt.total <= 1e-9);
    assert!((warm.objective - cold.objective).abs() <= 1e-9 * cold.objective);
}

/// The Clarabel backend (feature `clarabel`) solves the same program: on balls, polytopes and
/// derivative wedges its certified answer has the energy of the method's to 1e-8.
#[cfg(feature = "clarabel")]
#[test]
fn the_clarabel_backend_solves_the_same_program() {
    for (top, seed) in [(Topology::Closed, 5u64), (Topology::Open, 6)] {
        let spec = balls_spec(top, 9, 2, 2, seed);
        let p = spec.problem();
        let ours = p.solve(&ConicOptions::default()).unwrap();
        let theirs = p
            .solve_clarabel(&conic::clarabel::ClarabelOptions::default())
            .unwrap();
        assert!(theirs.kkt.total <= 1e-7, "{:?}", theirs.kkt);
        assert!(
            (ours.energy - theirs.energy).abs() <= 1e-8 * ours.energy,
            "{} vs {}",
            ours.energy,
            theirs.energy
        );
    }
}
