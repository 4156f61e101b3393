//! Divided differences: recurrence vs the explicit formula, polynomial reproduction, slopes,
//! second differences and jumps against their definitions.

use divdiff::{
    divided_difference, divided_difference_explicit, jumps, second_differences, slopes, Error,
    Knots, Points, Topology,
};
use proptest::prelude::*;

/// Random knots with gaps in [0.2, 2.0] and random data in [−3, 3]^d, d = 1..4.
fn problem() -> impl Strategy<Value = (Knots, Points)> {
    (
        prop_oneof![Just(Topology::Open), Just(Topology::Closed)],
        3usize..=10,
        1usize..=4,
    )
        .prop_flat_map(|(top, n, d)| {
            let m = if top == Topology::Closed { n + 1 } else { n };
            (
                -4.0f64..4.0,
                prop::collection::vec(0.2f64..2.0, m - 1),
                prop::collection::vec(-3.0f64..3.0, n * d),
            )
                .prop_map(move |(t0, gaps, c)| {
                    let t = std::iter::once(t0)
                        .chain(gaps.iter().scan(t0, |s, g| {
                            *s += g;
                            Some(*s)
                        }))
                        .collect();
                    (Knots::new(top, t).unwrap(), Points::new(d, c).unwrap())
                })
        })
}

/// The magnitude of the explicit formula's terms, Σ_k |p_{i+k}|_∞ / |π'(t_{i+k})|: the scale of
/// the rounding error of both formulas.
fn term_scale(knots: &Knots, points: &Points, i: isize, order: usize) -> f64 {
    let n = knots.vertex_count() as isize;
    (0..=order as isize)
        .map(|k| {
            let tk = knots.t(i + k);
            let dpi: f64 = (0..=order as isize)
                .filter(|&j| j != k)
                .map(|j| tk - knots.t(i + j))
                .product();
            let p = points.point((i + k).rem_euclid(n) as usize);
            p.iter().fold(0.0f64, |m, x| m.max(x.abs())) / dpi.abs()
        })
        .sum()
}

/// Relative round-off budget for a divided difference of order ≤ 5.
const REL_TOL: f64 = 1e-11;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn recurrence_matches_explicit_formula((knots, p) in problem(), order in 0usize..=5, shift in -3isize..=3) {
        let n = knots.vertex_count();
        let indices: Vec<isize> = if knots.is_closed() {
            // Any index, including negative ones and ones past N (periodic extension).
            (0..n as isize).map(|i| i + shift * n as isize / 2).collect()
        } else {
            (0..n.saturating_sub(order) as isize).collect()
        };
        for i in indices {
            let a = divided_difference(&knots, &p, i, order).unwrap();
            let b = divided_difference_explicit(&knots, &p, i, order).unwrap();
            let tol = REL_TOL * term_scale(&knots, &p, i, order);
            for (x, y) in a.iter().zip(&b) {
                prop_assert!((x - y).abs() <= tol, "i={i} order={order}: {x} vs {y}");
            }
        }
    }

    /// Δ_{i,m} of a polynomial of degree m is its leading coefficient; Δ_{i,m+1} vanishes.
    #[test]
    fn polynomials_are_reproduced(
        (knots, _) in problem(),
        coeffs in prop::collection::vec(-2.0f64..2.0, 1..=4),
    ) {
        let knots = Knots::open(knots.values().to_vec()).unwrap();
        let m = coeffs.len() - 1;
        let f = |t: f64| coeffs.iter().rev().fold(0.0, |acc, c| acc * t + c);
        let p = Points::new(1, knots.values().iter().map(|&t| f(t)).collect()).unwrap();
        for i in 0..knots.vertex_count().saturating_sub(m + 1) as isize {
            let lead = divided_difference(&knots, &p, i, m).unwrap()[0];
            let next = divided_difference(&knots, &p, i, m + 1).unwrap()[0];
            let scale = REL_TOL * term_scale(&knots, &p, i, m + 1).max(1.0);
            prop_assert!((lead - coeffs[m]).abs() <= scale, "{lead} vs {}", coeffs[m]);
            prop_assert!(next.abs() <= scale, "Δ_(m+1) = {next}");
        }
    }

    #[test]
    fn slopes_and_second_differences_are_the_first_and_second_divided_differences((knots, p) in problem()) {
        let n = knots.vertex_count();
        let s = slopes(&knots, &p).unwrap();
        prop_assert_eq!(s.len(), knots.span_count());
        for j in 0..knots.span_count() {
            let want = divided_difference(&knots, &p, j as isize, 1).unwrap();
            for (x, y) in s.point(j).iter().zip(&want) {
                prop_assert!((x - y).abs() <= REL_TOL * term_scale(&knots, &p, j as isize, 1));
            }
        }
        let c = second_differences(&knots, &p).unwrap();
        for i in 0..n {
            let exists = knots.is_closed() || (i >= 1 && i + 1 < n);
            for k in 0..p.dim() {
                let want = if exists {
                    divided_difference(&knots, &p, i as isize - 1, 2).unwrap()[k]
                } else {
                    0.0
                };
                let tol = if exists { REL_TOL * term_scale(&knots, &p, i as isize - 1, 2) } else { 0.0 };
                prop_assert!((c.point(i)[k] - want).abs() <= tol);
            }
        }
    }

    /// The two forms of the jump: (h_{i−1,3}/h_i)Δ_{i−1,3} − (h_{i−2,3}/h_{i−1})Δ_{i−2,3} (the
    /// definition, Kersey §2.2) against the second-difference form used by `jumps`.
    #[test]
    fn jump_matches_third_difference_definition((knots, p) in problem()) {
        let n = knots.vertex_count();
        let j = jumps(&knots, &p).unwrap();
        // Open curves: the third-difference form needs t_{i−2}..t_{i+2}.
        let range = if knots.is_closed() { 0..n } else { 2..n.saturating_sub(2) };
        for i in range {
            let ii = i as isize;
            let d_right = divided_difference(&knots, &p, ii - 1, 3).unwrap();
            let d_left = divided_difference(&knots, &p, ii - 2, 3).unwrap();
            let h13 = knots.t(ii + 2) - knots.t(ii - 1);
            let h23 = knots.t(ii + 1) - knots.t(ii - 2);
            let (hi, hl) = (knots.t(ii + 1) - knots.t(ii), knots.t(ii) - knots.t(ii - 1));
            let scale = h13 / hi * term_scale(&knots, &p, ii - 1, 3)
                + h23 / hl * term_scale(&knots, &p, ii - 2, 3);
            for k in 0..p.dim() {
                let want = h13 / hi * d_right[k] - h23 / hl * d_left[k];
                prop_assert!((j.point(i)[k] - want).abs() <= REL_TOL * scale, "i={i}");
            }
        }
    }

    /// Theorem 2.1 at the level of divided differences: Σ p_i · jmp_i = Σ |Δ_{i−1,2} f|² h_{i−1,2}.
    #[test]
    fn summation_by_parts((knots, p) in problem()) {
        let n = knots.vertex_count();
        let j = jumps(&knots, &p).unwrap();
        let c = second_differences(&knots, &p).unwrap();
        let lhs: f64 = p.coords().iter().zip(j.coords()).map(|(a, b)| a * b).sum();
        let mut rhs = 0.0;
        let mut scale = 0.0;
        for i in 0..n {
            let h2 = if knots.is_closed() || (i >= 1 && i + 1 < n) {
                knots.h(i as isize - 1) + knots.h(i as isize)
            } else {
                0.0
            };
            rhs += c.point(i).iter().map(|x| x * x).sum::<f64>() * h2;
        }
        for (a, b) in p.coords().iter().zip(j.coords()) {
            scale += (a * b).abs();
        }
        prop_assert!((lhs - rhs).abs() <= REL_TOL * scale.max(rhs), "{lhs} vs {rhs}");
    }
}

#[test]
fn open_curves_reject_missing_knots() {
    let knots = Knots::open(vec![0.0, 1.0, 2.5, 3.0]).unwrap();
    let p = Points::zeros(4, 2);
    assert_eq!(
        divided_difference(&knots, &p, 2, 2),
        Err(Error::DifferenceOutOfRange {
            index: 2,
            order: 2,
            len: 4
        })
    );
    assert_eq!(
        divided_difference_explicit(&knots, &p, -1, 1),
        Err(Error::DifferenceOutOfRange {
            index: -1,
            order: 1,
            len: 4
        })
    );
    assert!(divided_difference(&knots, &p, 0, 3).is_ok());
}

#[test]
fn sizes_must_agree() {
    let knots = Knots::closed(vec![0.0, 1.0, 2.5, 3.0]).unwrap();
    let p = Points::zeros(4, 2);
    let want = Err(Error::LengthMismatch {
        field: "points",
        expected: 3,
        got: 4,
    });
    assert_eq!(slopes(&knots, &p), want);
    assert_eq!(jumps(&knots, &p), want);
    assert_eq!(
        divided_difference(&knots, &p, 0, 1).map(|_| ()),
        want.map(|_: Points| ())
    );
}

/// A closed curve wraps: Δ_{N−1,1} is the slope of the closing span, over the period's end.
#[test]
fn closed_differences_wrap() {
    let knots = Knots::closed(vec![0.0, 1.0, 3.0, 7.0]).unwrap();
    let p = Points::from_rows(&[[1.0], [2.0], [5.0]]).unwrap();
    // Closing span: from p_2 = 5 at t = 3 to p_0 = 1 at t = 7: slope −1.
    let s = divided_difference(&knots, &p, 2, 1).unwrap()[0];
    assert!((s + 1.0).abs() <= 1e-15);
    let s_prev = divided_difference(&knots, &p, -1, 1).unwrap()[0];
    assert!(
        (s_prev + 1.0).abs() <= 1e-15,
        "index −1 is the closing span again"
    );
    let sl = slopes(&knots, &p).unwrap();
    assert!((sl.point(2)[0] + 1.0).abs() <= 1e-15);
}
