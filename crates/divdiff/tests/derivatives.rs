//! Vertex derivatives: exactness on quadratics (Bessel) and lines (Average), the printed (2.3)
//! misprint, the §3.6 end rules, and the parametrizations of Algorithm 4.1 step (iv).

use divdiff::{
    derivative_stencil, parametrize, vertex_derivative, vertex_derivatives, DerivativeRule, Error,
    Knots, Parametrization, Points, Topology,
};
use proptest::prelude::*;

const TOL: f64 = 1e-10;

fn knots_strategy(closed: bool) -> impl Strategy<Value = Knots> {
    (3usize..=9, -3.0f64..3.0).prop_flat_map(move |(n, t0)| {
        prop::collection::vec(0.2f64..2.0, if closed { n } else { n - 1 }).prop_map(move |g| {
            let mut t = vec![t0];
            for x in g {
                let last = t[t.len() - 1];
                t.push(last + x);
            }
            if closed {
                Knots::closed(t).unwrap()
            } else {
                Knots::open(t).unwrap()
            }
        })
    })
}

/// A quadratic curve in R^d: q(t) = a + b t + c t², with its derivative.
#[derive(Clone, Debug)]
struct Quadratic {
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
}

impl Quadratic {
    fn at(&self, t: f64) -> Vec<f64> {
        (0..self.a.len())
            .map(|k| self.a[k] + self.b[k] * t + self.c[k] * t * t)
            .collect()
    }
    fn slope(&self, t: f64) -> Vec<f64> {
        (0..self.a.len())
            .map(|k| self.b[k] + 2.0 * self.c[k] * t)
            .collect()
    }
}

fn quadratic() -> impl Strategy<Value = Quadratic> {
    (1usize..=4).prop_flat_map(|d| {
        (
            prop::collection::vec(-2.0f64..2.0, d),
            prop::collection::vec(-2.0f64..2.0, d),
            prop::collection::vec(-2.0f64..2.0, d),
        )
            .prop_map(|(a, b, c)| Quadratic { a, b, c })
    })
}

/// Points sampling `q` so that vertex `i`'s stencil sees q at t_{i−1}, t_i, t_{i+1} of the
/// (periodic) knot sequence: for a closed curve the neighbours of vertex i are placed at the
/// extended knots t(i − 1), t(i + 1) even when they wrap.
fn samples_around(knots: &Knots, q: &Quadratic, i: usize) -> Points {
    let n = knots.vertex_count();
    let mut rows: Vec<Vec<f64>> = (0..n).map(|j| q.at(knots.t(j as isize))).collect();
    if knots.is_closed() {
        rows[(i + n - 1) % n] = q.at(knots.t(i as isize - 1));
        rows[(i + 1) % n] = q.at(knots.t(i as isize + 1));
    }
    Points::from_rows(&rows).unwrap()
}

fn assert_close(a: &[f64], b: &[f64], tol: f64) -> Result<(), TestCaseError> {
    for (x, y) in a.iter().zip(b) {
        prop_assert!((x - y).abs() <= tol, "{a:?} vs {b:?}");
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Bessel is exact on quadratics at every vertex (interior, wrapped, and the §3.6 ends).
    #[test]
    fn bessel_is_exact_on_quadratics(
        closed in any::<bool>(),
        knots_o in knots_strategy(false),
        knots_c in knots_strategy(true),
        q in quadratic(),
    ) {
        let knots = if closed { knots_c } else { knots_o };
        for i in 0..knots.vertex_count() {
            let p = samples_around(&knots, &q, i);
            let df = vertex_derivative(&knots, &p, i, DerivativeRule::Bessel).unwrap();
            assert_close(&df, &q.slope(knots.t(i as isize)), TOL)?;
        }
    }

    /// Average (2.2) and the one-sided end differences are exact on lines.
    #[test]
    fn average_is_exact_on_lines(knots in knots_strategy(false), mut q in quadratic()) {
        q.c.iter_mut().for_each(|c| *c = 0.0);
        let p = samples_around(&knots, &q, 0);
        let all = vertex_derivatives(&knots, &p, DerivativeRule::Average).unwrap();
        for i in 0..knots.vertex_count() {
            assert_close(all.point(i), &q.b, TOL)?;
        }
    }

    /// The average is NOT exact on quadratics when h_{i−1} ≠ h_i: its error is c (h_i − h_{i−1}) / 2.
    #[test]
    fn average_error_on_quadratics(knots in knots_strategy(false), q in quadratic()) {
        let p = samples_around(&knots, &q, 0);
        for i in 1..knots.vertex_count() - 1 {
            let df = vertex_derivative(&knots, &p, i, DerivativeRule::Average).unwrap();
            let (a, b) = (knots.h(i as isize - 1), knots.h(i as isize));
            let want: Vec<f64> = q.slope(knots.t(i as isize)).iter().zip(&q.c)
                .map(|(s, c)| s + c * (b - a) / 2.0).collect();
            assert_close(&df, &want, TOL)?;
        }
    }

    /// Every stencil's coefficients sum to zero (constants have zero derivative).
    #[test]
    fn stencils_annihilate_constants(closed in any::<bool>(), knots_o in knots_strategy(false), knots_c in knots_strategy(true)) {
        let knots = if closed { knots_c } else { knots_o };
        for rule in [DerivativeRule::Average, DerivativeRule::Bessel] {
            for i in 0..knots.vertex_count() {
                let s = derivative_stencil(&knots, i, rule).unwrap();
                let scale: f64 = s.iter().map(|x| x.1.abs()).sum();
                prop_assert!(s.iter().map(|x| x.1).sum::<f64>().abs() <= 1e-13 * scale);
            }
        }
    }
}

/// Kersey (2.3) as printed, with a = h_{i−1}, b = h_i:
/// −(a + (a+b))/(a(a+b)) p_{i−1} + (a+b)/(ab) p_i − a/((a+b)b) p_{i+1}.
/// These are the coefficients of the quadratic's derivative at t_{i−1}, not at t_i.
#[test]
fn printed_bessel_is_the_derivative_at_the_left_neighbour() {
    let knots = Knots::open(vec![0.0, 0.5, 2.0]).unwrap();
    let (a, b) = (0.5, 1.5);
    let printed = [
        -(2.0 * a + b) / (a * (a + b)),
        (a + b) / (a * b),
        -a / ((a + b) * b),
    ];
    let q = Quadratic {
        a: vec![1.0],
        b: vec![-1.0],
        c: vec![3.0],
    };
    let f: Vec<f64> = knots.values().iter().map(|&t| q.at(t)[0]).collect();
    let df_printed: f64 = printed.iter().zip(&f).map(|(c, x)| c * x).sum();
    // Exact at t_{i−1} = 0 ...
    assert!((df_printed - q.slope(0.0)[0]).abs() <= TOL);
    // ... and wrong at t_i = 0.5 by 2c·a = 3.
    assert!((df_printed - q.slope(0.5)[0]).abs() > 1.0);
    let p = Points::new(1, f).unwrap();
    let df = vertex_derivative(&knots, &p, 1, DerivativeRule::Bessel).unwrap()[0];
    assert!((df - q.slope(0.5)[0]).abs() <= TOL);
}

/// On uniform knots Bessel and Average coincide at interior vertices (the central difference).
#[test]
fn rules_agree_on_uniform_knots() {
    let knots = Knots::closed(vec![0.0, 1.0, 2.0, 3.0, 4.0]).unwrap();
    for i in 0..4 {
        let a = derivative_stencil(&knots, i, DerivativeRule::Average).unwrap();
        let b = derivative_stencil(&knots, i, DerivativeRule::Bessel).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.0, y.0);
            assert!((x.1 - y.1).abs() <= 1e-15);
        }
    }
}

#[test]
fn derivative_errors_and_two_point_curves() {
    let knots = Knots::open(vec![0.0, 2.0]).unwrap();
    assert_eq!(
        derivative_stencil(&knots, 2, DerivativeRule::Bessel),
        Err(Error::IndexOutOfRange {
            field: "vertex",
            index: 2,
            len: 2
        })
    );
    let p = Points::from_rows(&[[1.0, 0.0], [3.0, 4.0]]).unwrap();
    for rule in [DerivativeRule::Average, DerivativeRule::Bessel] {
        for i in 0..2 {
            let df = vertex_derivative(&knots, &p, i, rule).unwrap();
            assert!(
                (df[0] - 1.0).abs() <= 1e-15 && (df[1] - 2.0).abs() <= 1e-15,
                "the secant"
            );
        }
    }
    assert_eq!(
        vertex_derivative(&knots, &Points::zeros(3, 2), 0, DerivativeRule::Average),
        Err(Error::LengthMismatch {
            field: "points",
            expected: 2,
            got: 3
        })
    );
}

fn close_slices(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12)
}

#[test]
fn parametrizations_follow_algorithm_4_1() {
    // Chords 5, 1, 4 (open); the closing chord from (4,4) back to (0,0) is √32.
    let q = Points::from_rows(&[[0.0, 0.0], [3.0, 4.0], [4.0, 4.0], [4.0, 0.0]]).unwrap();
    let open = |p| parametrize(&q, Topology::Open, p).unwrap();
    assert!(close_slices(
        open(Parametrization::Uniform).values(),
        &[0.0, 1.0, 2.0, 3.0]
    ));
    assert!(close_slices(
        open(Parametrization::Chordal).values(),
        &[0.0, 5.0, 6.0, 10.0]
    ));
    let s5 = 5f64.sqrt();
    assert!(close_slices(
        open(Parametrization::Centripetal).values(),
        &[0.0, s5, s5 + 1.0, s5 + 3.0]
    ));
    assert!(close_slices(
        open(Parametrization::Exponent(2.0)).values(),
        &[0.0, 25.0, 26.0, 42.0]
    ));
    let closed = parametrize(&q, Topology::Closed, Parametrization::Chordal).unwrap();
    assert_eq!(closed.vertex_count(), 4);
    assert!(close_slices(closed.values(), &[0.0, 5.0, 6.0, 10.0, 14.0]));
    let closed = parametrize(&q, Topology::Closed, Parametrization::Centripetal).unwrap();
    assert!(
        (closed.h(3) - 2.0).abs() <= 1e-12,
        "closing span |(4,0) − (0,0)|^½ = 2"
    );
}

#[test]
fn parametrization_errors() {
    let q = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    for p in [Parametrization::Uniform, Parametrization::Centripetal] {
        assert_eq!(
            parametrize(&q, Topology::Open, p),
            Err(Error::ZeroLengthSpan { index: 1, next: 2 })
        );
    }
    // The closing pair of a closed curve.
    let q = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]).unwrap();
    assert!(parametrize(&q, Topology::Open, Parametrization::Chordal).is_ok());
    assert_eq!(
        parametrize(&q, Topology::Closed, Parametrization::Chordal),
        Err(Error::ZeroLengthSpan { index: 3, next: 0 })
    );
    for e in [-0.5, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            parametrize(&q, Topology::Open, Parametrization::Exponent(e)),
            Err(Error::OutOfRange {
                field: "exponent",
                ..
            })
        ));
    }
    let two = Points::from_rows(&[[0.0], [1.0]]).unwrap();
    assert!(parametrize(&two, Topology::Open, Parametrization::Chordal).is_ok());
    assert_eq!(
        parametrize(&two, Topology::Closed, Parametrization::Chordal),
        Err(Error::TooFew {
            field: "points",
            needed: 3,
            got: 2
        })
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Every span is |q_{i+1} − q_i|^e, the first knot is 0, and a closed curve's last span is the
    /// closing chord (Algorithm 4.1 step (iv), not normalized).
    #[test]
    fn parametrize_spans_are_powers_of_chords(
        closed in any::<bool>(),
        d in 1usize..=4,
        e in 0.0f64..2.0,
        coords in prop::collection::vec(-3.0f64..3.0, 3 * 4..=10 * 4),
    ) {
        let n = coords.len() / 4;
        let q = Points::new(d, coords[..n * d].to_vec()).unwrap();
        let top = if closed { Topology::Closed } else { Topology::Open };
        let knots = parametrize(&q, top, Parametrization::Exponent(e)).unwrap();
        prop_assert_eq!(knots.vertex_count(), n);
        prop_assert!(knots.values()[0].abs() <= 0.0);
        for j in 0..knots.span_count() {
            let (a, b) = (q.point(j), q.point((j + 1) % n));
            let chord = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
            let want = chord.powf(e);
            prop_assert!((knots.h(j as isize) - want).abs() <= 1e-12 * (1.0 + knots.length()));
        }
    }
}
