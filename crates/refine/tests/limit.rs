//! The limit curve (`limit_curve`, `CubicSpline`): it interpolates the constrained vertices, it is
//! C² at its breaks (around a closed curve too), the refined polygon converges to it at O(h²) as k
//! grows, and its natural and clamped forms agree with an independent construction (the
//! truncated-power basis, solved densely).

use divdiff::{Knots, Points, Topology};
use refine::{limit_curve, Boundary, Constraint, CubicSpline, Problem, Tangent};

/// A small deterministic generator (no dependency): uniform in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Jittered data on a wobbly loop (closed) or an S-curve (open), d = 2 or 3, very unequal spans.
fn data(n: usize, d: usize, closed: bool, seed: u64) -> Points {
    let mut g = Lcg(seed);
    let mut rows = Vec::new();
    let mut s = 0.0;
    for i in 0..n {
        // Spans between 0.2 and 2.2 times the mean.
        s += 0.2 + 2.0 * g.next();
        let a = if closed {
            std::f64::consts::TAU * i as f64 / n as f64
        } else {
            0.35 * s
        };
        let mut p = vec![
            (2.0 + 0.3 * g.next()) * a.cos() + if closed { 0.0 } else { a },
            (1.0 + 0.3 * g.next()) * (2.0 * a).sin(),
        ];
        if d == 3 {
            p.push(0.5 * a.sin() + 0.2 * g.next());
        }
        rows.push(p);
    }
    Points::from_rows(&rows).unwrap()
}

fn topo(closed: bool) -> Topology {
    if closed {
        Topology::Closed
    } else {
        Topology::Open
    }
}

fn scale(p: &Points) -> f64 {
    p.coords()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(1.0)
}

/// Value, first and second derivative of piece `i` at its left (s = 0) or right (s = 1) end,
/// from the Bézier control points alone (not through `derivative`).
fn end_jet(s: &CubicSpline, i: usize, right: bool) -> [Vec<f64>; 3] {
    let d = s.dim();
    let b = s.bezier(i).unwrap();
    let h = s.breaks()[i + 1] - s.breaks()[i];
    let c = |r: usize, k: usize| b[r * d + k];
    let (v, d1, d2): (Vec<f64>, Vec<f64>, Vec<f64>) = if right {
        (
            (0..d).map(|k| c(3, k)).collect(),
            (0..d).map(|k| 3.0 * (c(3, k) - c(2, k)) / h).collect(),
            (0..d)
                .map(|k| 6.0 * (c(3, k) - 2.0 * c(2, k) + c(1, k)) / (h * h))
                .collect(),
        )
    } else {
        (
            (0..d).map(|k| c(0, k)).collect(),
            (0..d).map(|k| 3.0 * (c(1, k) - c(0, k)) / h).collect(),
            (0..d)
                .map(|k| 6.0 * (c(2, k) - 2.0 * c(1, k) + c(0, k)) / (h * h))
                .collect(),
        )
    };
    [v, d1, d2]
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The largest jump of value, f' and f'' over the interior breaks (and the closing break of a
/// closed curve), each relative to the size of that quantity.
fn c2_jumps(s: &CubicSpline) -> [f64; 3] {
    let p = s.pieces();
    let mut worst = [0.0f64; 3];
    let mut size = [0.0f64; 3];
    let joins: Vec<(usize, usize)> = (1..p)
        .map(|i| (i - 1, i))
        .chain(s.is_closed().then_some((p - 1, 0)))
        .collect();
    for (a, b) in joins {
        let l = end_jet(s, a, true);
        let r = end_jet(s, b, false);
        for o in 0..3 {
            worst[o] = worst[o].max(max_diff(&l[o], &r[o]));
            size[o] = size[o].max(l[o].iter().fold(0.0f64, |m, x| m.max(x.abs())));
        }
    }
    [0, 1, 2].map(|o| worst[o] / size[o].max(1.0))
}

fn problems() -> Vec<(&'static str, Problem)> {
    let mut v = Vec::new();
    for (closed, d, seed) in [(false, 2, 1), (true, 2, 2), (false, 3, 3), (true, 3, 4)] {
        let n = 9;
        let q = data(n, d, closed, seed);
        let base = Problem::new(q).with_topology(topo(closed)).with_k(5);
        v.push(("interpolate", base.clone()));
        v.push((
            "balls",
            base.clone()
                .with_constraint(Constraint::Balls(vec![0.15; n])),
        ));
        v.push((
            "smoothing",
            base.clone()
                .with_constraint(Constraint::Smoothing(vec![3.0; n])),
        ));
        if !closed {
            let mut start = vec![1.0; d];
            start[1] = 0.5;
            let end = vec![-0.5; d];
            v.push((
                "clamped",
                base.clone().with_boundary(Boundary::Clamped { start, end }),
            ));
        }
        v.push(("levels", base.with_levels(2, 1)));
    }
    v
}

/// (a) The limit curve passes through the constrained vertices (data vertices; every vertex of
/// the level before the last after interpolatory levels) at their knots, and (b) it is C² at
/// every break, around the closing break of a closed curve too.
#[test]
fn interpolates_the_constrained_vertices_and_is_c2() {
    for (name, problem) in problems() {
        let r = problem.solve().unwrap();
        let s = limit_curve(&problem, &r).unwrap();
        let stride = if r.stages.len() > 1 {
            r.stages.last().unwrap().k + 1
        } else {
            0
        };
        let vertices: Vec<usize> = if stride > 0 {
            (0..r.points.len()).step_by(stride).collect()
        } else {
            r.data_vertex.clone()
        };
        assert_eq!(s.pieces() + usize::from(!s.is_closed()), vertices.len());
        let sc = scale(&r.points);
        for &v in &vertices {
            let e = max_diff(&s.eval(r.knots.values()[v]), r.points.point(v));
            assert!(e <= 1e-12 * sc, "{name}: vertex {v} off by {e:e}");
        }
        let jumps = c2_jumps(&s);
        assert!(jumps.iter().all(|&j| j <= 1e-11), "{name}: jumps {jumps:?}");
        // `derivative` agrees with the control points at the breaks (right piece).
        for i in 0..s.pieces() {
            let jet = end_jet(&s, i, false);
            for (o, want) in jet.iter().enumerate() {
                let got = s.derivative(s.breaks()[i], o);
                assert!(
                    max_diff(&got, want) <= 1e-9 * scale_of(want),
                    "{name}: order {o}"
                );
            }
        }
    }
}

fn scale_of(v: &[f64]) -> f64 {
    v.iter().fold(1.0f64, |m, x| m.max(x.abs()))
}

/// Clamped ends: f'(t_0) = start and f'(t_last) = end exactly.
#[test]
fn clamped_ends_have_the_prescribed_derivatives() {
    let q = data(7, 2, false, 11);
    let problem = Problem::new(q)
        .with_topology(Topology::Open)
        .with_boundary(Boundary::Clamped {
            start: vec![2.0, -1.0],
            end: vec![0.5, 3.0],
        });
    let r = problem.solve().unwrap();
    let s = limit_curve(&problem, &r).unwrap();
    let (a, b) = s.domain();
    assert!(max_diff(&s.derivative(a, 1), &[2.0, -1.0]) <= 1e-12);
    assert!(max_diff(&s.derivative(b - 1e-300, 1), &[0.5, 3.0]) <= 1e-11);
    assert!(max_diff(&s.derivative(b, 1), &[0.5, 3.0]) <= 1e-11);
}

/// Interior tangent constraints: the curve takes the returned discrete derivative Df(t_{i_k}) at
/// those vertices and is C¹ (not C²) there; it still interpolates the data vertices.
#[test]
fn tangent_vertices_take_the_returned_derivative() {
    let q = data(8, 2, true, 5);
    let mut tangents = vec![None; 8];
    tangents[3] = Some(Tangent::Ball {
        center: vec![0.0, 1.0],
        radius: 0.1,
    });
    let problem = Problem::new(q)
        .with_topology(Topology::Closed)
        .with_tangents(tangents);
    let r = problem.solve().unwrap();
    let s = limit_curve(&problem, &r).unwrap();
    let v = r.data_vertex[3];
    let df = divdiff::vertex_derivative(&r.knots, &r.points, v, problem.derivative).unwrap();
    let t = r.knots.values()[v];
    assert!(max_diff(&s.derivative(t, 1), &df) <= 1e-11 * scale_of(&df));
    // C¹ from the left as well.
    let left = end_jet(&s, 2, true);
    assert!(max_diff(&left[1], &df) <= 1e-11 * scale_of(&df));
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let e = max_diff(&s.eval(r.knots.values()[v]), r.points.point(v));
        assert!(e <= 1e-12 * scale(&r.points), "vertex {i}");
    }
}

/// (c) On fixed knots the data-vertex values are the data for every k, so the limit curve is one
/// spline; the refined vertices approach it at their knots (h ∝ 1/(k + 1)). Natural and closed:
/// the measured order log₂(e_k / e_{2k+1}) is at least 1.9 on every step from k = 3 to k = 127
/// (measured 1.92–2.00). Clamped ends converge at first order only (measured orders −0.6, 0.41,
/// 0.72, 0.86, 0.93 → 1): the discrete energy has no second difference at an open curve's end vertex,
/// which costs nothing when f'' = 0 there (natural) but drops an O(h) share ¼|f''(t_0)|²h of
/// ½∫|f''|² when an end slope forces f''(t_0) ≠ 0; the test asserts order ≥ 0.8 on the last
/// two steps.
#[test]
fn refined_polygon_converges_to_the_limit_at_second_order() {
    let cases: Vec<(&str, Problem)> = vec![
        (
            "open natural",
            Problem::new(data(8, 2, false, 7)).with_topology(Topology::Open),
        ),
        (
            "closed",
            Problem::new(data(8, 2, true, 8)).with_topology(Topology::Closed),
        ),
        (
            "open clamped d = 3",
            Problem::new(data(8, 3, false, 9))
                .with_topology(Topology::Open)
                .with_boundary(Boundary::Clamped {
                    start: vec![1.0, 0.0, 0.5],
                    end: vec![0.0, -1.0, 0.5],
                }),
        ),
    ];
    for (name, base) in cases {
        let clamped = name.contains("clamped");
        let mut errors = Vec::new();
        let mut first: Option<CubicSpline> = None;
        for k in [3usize, 7, 15, 31, 63, 127] {
            let problem = base.clone().with_k(k).with_knot_iterations(0);
            let r = problem.solve().unwrap();
            let s = limit_curve(&problem, &r).unwrap();
            match &first {
                None => first = Some(s.clone()),
                Some(f) => {
                    // The same spline at every k (same data knots, same values, same ends).
                    for u in [0.1, 0.37, 0.81].map(|x| {
                        let (a, b) = f.domain();
                        a + x * (b - a)
                    }) {
                        assert!(max_diff(&s.eval(u), &f.eval(u)) <= 1e-12 * scale(&r.points));
                    }
                }
            }
            let e = (0..r.points.len())
                .map(|j| max_diff(&s.eval(r.knots.values()[j]), r.points.point(j)))
                .fold(0.0f64, f64::max);
            errors.push(e);
        }
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        eprintln!("{name}: errors {errors:.3?}, orders {orders:.3?}");
        let ok = if clamped {
            orders[3..].iter().all(|&o| o >= 0.8)
        } else {
            orders.iter().all(|&o| o >= 1.9)
        };
        assert!(ok, "{name}: errors {errors:?}, orders {orders:?}");
    }
}

/// Dense Gaussian elimination with partial pivoting (the independent solve of (d)).
fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            let pivot = a[c].clone();
            for (x, y) in a[r][c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * y;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// Truncated-power representation f(t) = Σ_{j<4} a_j (t − u_0)^j + Σ_i c_i (t − u_i)_+³, its value
/// or derivative of order `o`.
fn power_basis(t: f64, u: &[f64], o: usize, coef: &[f64], interior: &[usize]) -> f64 {
    let fall = |p: i32, o: usize| -> f64 { (0..o).map(|m| (p - m as i32) as f64).product() };
    let x = t - u[0];
    let mut v = 0.0;
    for (j, &a) in coef.iter().enumerate().take(4).skip(o) {
        v += a * fall(j as i32, o) * x.powi(j as i32 - o as i32);
    }
    for (c, &i) in interior.iter().enumerate() {
        let y = t - u[i];
        if y > 0.0 && o <= 3 {
            v += coef[4 + c] * fall(3, o) * y.powi(3 - o as i32);
        }
    }
    v
}

/// (d) Natural and clamped splines against the truncated-power basis solved densely: natural
/// with a, b only (a_2 = a_3 = 0) and the conditions Σc_i = Σc_i u_i = 0 (f'' = 0 beyond the last
/// knot) over all knots; clamped with a full cubic and c_i on interior knots, end slopes as rows.
#[test]
fn natural_and_clamped_match_the_truncated_power_construction() {
    let mut g = Lcg(42);
    for trial in 0..6 {
        let n = 4 + trial;
        let mut u = vec![0.0];
        for _ in 1..n {
            let last = *u.last().unwrap();
            u.push(last + 0.05 + 3.0 * g.next());
        }
        let y: Vec<f64> = (0..n).map(|_| 4.0 * g.next() - 2.0).collect();
        let knots = Knots::open(u.clone()).unwrap();
        let pts = Points::new(1, y.clone()).unwrap();
        let probe: Vec<f64> = (0..40).map(|_| u[n - 1] * g.next()).collect();

        // Natural: unknowns a_0, a_1 (a_2 = a_3 = 0), c_0..c_{n−1} on every knot.
        let all: Vec<usize> = (0..n).collect();
        let m = n + 2;
        let mut a = vec![vec![0.0; m]; m];
        let mut b = vec![0.0; m];
        for i in 0..n {
            a[i][0] = 1.0;
            a[i][1] = u[i] - u[0];
            for j in 0..i {
                a[i][2 + j] = (u[i] - u[j]).powi(3);
            }
            b[i] = y[i];
        }
        for j in 0..n {
            a[n][2 + j] = 1.0;
            a[n + 1][2 + j] = u[j];
        }
        let x = dense_solve(a, b);
        let coef: Vec<f64> = [x[0], x[1], 0.0, 0.0]
            .into_iter()
            .chain(x[2..].iter().copied())
            .collect();
        let s = CubicSpline::through(&knots, &pts, &vec![None; n]).unwrap();
        for &t in &probe {
            for o in 0..3 {
                let want = power_basis(t, &u, o, &coef, &all);
                let got = s.derivative(t, o)[0];
                assert!(
                    (got - want).abs() <= 1e-10 * want.abs().max(1.0),
                    "natural n = {n}, order {o}: {got} vs {want}"
                );
            }
        }

        // Clamped: a_0..a_3 and c_i on interior knots; rows: n values, 2 end slopes.
        let (s0, s1) = (4.0 * g.next() - 2.0, 4.0 * g.next() - 2.0);
        let interior: Vec<usize> = (1..n - 1).collect();
        let m = n + 2;
        let mut a = vec![vec![0.0; m]; m];
        let mut b = vec![0.0; m];
        for i in 0..n {
            let x = u[i] - u[0];
            a[i][..4].copy_from_slice(&[1.0, x, x * x, x * x * x]);
            for (c, &j) in interior.iter().enumerate() {
                a[i][4 + c] = if u[i] > u[j] {
                    (u[i] - u[j]).powi(3)
                } else {
                    0.0
                };
            }
            b[i] = y[i];
        }
        a[n][1] = 1.0;
        b[n] = s0;
        let x = u[n - 1] - u[0];
        a[n + 1][..4].copy_from_slice(&[0.0, 1.0, 2.0 * x, 3.0 * x * x]);
        for (c, &j) in interior.iter().enumerate() {
            a[n + 1][4 + c] = 3.0 * (u[n - 1] - u[j]).powi(2);
        }
        b[n + 1] = s1;
        let coef = dense_solve(a, b);
        let mut slopes = vec![None; n];
        slopes[0] = Some(vec![s0]);
        slopes[n - 1] = Some(vec![s1]);
        let s = CubicSpline::through(&knots, &pts, &slopes).unwrap();
        for &t in &probe {
            for o in 0..4 {
                let want = power_basis(t, &u, o, &coef, &interior);
                let got = s.derivative(t, o)[0];
                assert!(
                    (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                    "clamped n = {n}, order {o}: {got} vs {want}"
                );
            }
        }
    }
}

/// A closed curve is periodic: f(u + T) = f(u), derivatives too.
#[test]
fn closed_curves_are_periodic() {
    let q = data(6, 3, true, 13);
    let problem = Problem::new(q).with_topology(Topology::Closed);
    let r = problem.solve().unwrap();
    let s = limit_curve(&problem, &r).unwrap();
    let (a, b) = s.domain();
    let period = b - a;
    let mut g = Lcg(3);
    for _ in 0..20 {
        let u = a + period * g.next();
        for o in 0..3 {
            let x = s.derivative(u, o);
            let y = s.derivative(u + 2.0 * period, o);
            let z = s.derivative(u - period, o);
            assert!(max_diff(&x, &y) <= 1e-9 * scale_of(&x));
            assert!(max_diff(&x, &z) <= 1e-9 * scale_of(&x));
        }
    }
}

/// Wrong sizes are typed errors naming the field.
#[test]
fn bad_input_is_a_typed_error() {
    let knots = Knots::open(vec![0.0, 1.0, 2.0]).unwrap();
    let y = Points::new(2, vec![0.0, 0.0, 1.0, 1.0, 2.0, 0.0]).unwrap();
    let e = CubicSpline::through(&knots, &y, &[None, None]).unwrap_err();
    assert!(matches!(
        e,
        refine::Error::WrongLength {
            field: "slopes",
            ..
        }
    ));
    let e = CubicSpline::through(&knots, &y, &[Some(vec![1.0]), None, None]).unwrap_err();
    assert!(matches!(
        e,
        refine::Error::WrongDimension {
            field: "slopes",
            index: 0,
            ..
        }
    ));
    let e = CubicSpline::through(&knots, &y, &[None, Some(vec![f64::NAN, 0.0]), None]).unwrap_err();
    assert!(matches!(
        e,
        refine::Error::NonFiniteInput {
            field: "slopes",
            index: 1
        }
    ));
}
