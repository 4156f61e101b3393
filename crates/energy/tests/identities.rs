//! Kersey §2 identities over random non-uniform knots, d = 1..4, open and closed:
//! Theorem 2.1 (three ways to E), Corollary 2.2, Lemma 2.3, positive semidefiniteness and the
//! kernel of H; the exact knot gradient against finite differences, and the printed Lemma 2.4.

mod common;

use common::{max_abs, norm2, problem, Problem};
use divdiff::{jumps, second_differences, DerivativeRule, Knots, Points};
use energy::{
    energy, energy_by_jumps, knot_gradient, knot_gradient_printed, orthogonality_residuals,
    vertex_knot_gradient, Hessian,
};
use proptest::prelude::*;

/// Round-off budget relative to the scale |H|_max·|p|² of the energy's terms.
const REL_TOL: f64 = 1e-11;

/// Tolerance for central finite differences of the (non-quadratic) knot dependence: step
/// δ = FD_STEP·min h gives truncation O(δ²) and rounding O(ε/δ) relative to the scale E/min h.
const FD_STEP: f64 = 1e-5;
const FD_TOL: f64 = 1e-6;

fn scale(pr: &Problem) -> f64 {
    Hessian::new(&pr.knots).max_abs() * norm2(pr.points.coords()) + f64::MIN_POSITIVE
}

fn min_span(k: &Knots) -> f64 {
    (0..k.span_count())
        .map(|j| k.h(j as isize))
        .fold(f64::INFINITY, f64::min)
}

/// Central finite differences of E in each knot value.
fn fd_knot_gradient(pr: &Problem) -> Vec<f64> {
    let d = FD_STEP * min_span(&pr.knots);
    let e = |k: usize, dt: f64| {
        let mut t = pr.knots.values().to_vec();
        t[k] += dt;
        energy(&Knots::new(pr.knots.topology(), t).unwrap(), &pr.points).unwrap()
    };
    (0..pr.knots.values().len())
        .map(|k| (e(k, d) - e(k, -d)) / (2.0 * d))
        .collect()
}

/// Collapses per-knot values to per-vertex values (closed: vertex 0 moves t_0 and t_N).
fn per_vertex(knots: &Knots, mut g: Vec<f64>) -> Vec<f64> {
    if knots.is_closed() {
        let last = g.pop().unwrap();
        g[0] += last;
    }
    g
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Theorem 2.1 and (2.1): the direct sum, ½pᵀHp and pᵀ·jmp agree.
    #[test]
    fn energy_three_ways(pr in problem(2..=12)) {
        let e1 = energy(&pr.knots, &pr.points).unwrap();
        let e2 = Hessian::new(&pr.knots).energy(&pr.points).unwrap();
        let e3 = energy_by_jumps(&pr.knots, &pr.points).unwrap();
        let tol = REL_TOL * scale(&pr);
        prop_assert!((e1 - e2).abs() <= tol && (e1 - e3).abs() <= tol, "{e1} {e2} {e3}");
    }

    /// Corollary 2.2: jmp = ½Hp, vertex by vertex and coordinate by coordinate.
    #[test]
    fn jumps_are_half_hp(pr in problem(2..=12)) {
        let hp = Hessian::new(&pr.knots).apply(&pr.points);
        let j = jumps(&pr.knots, &pr.points).unwrap();
        let tol = REL_TOL * Hessian::new(&pr.knots).max_abs() * max_abs(pr.points.coords());
        for (a, b) in j.coords().iter().zip(hp.coords()) {
            prop_assert!((a - 0.5 * b).abs() <= tol, "{a} vs {}", 0.5 * b);
        }
    }

    /// Lemma 2.3: ∂E/∂p = Hp. E is quadratic in p, so central differences are exact up to
    /// rounding, O(ε·scale/δ) with δ = 1e-3.
    #[test]
    fn point_gradient_is_hp(pr in problem(2..=10)) {
        let hp = Hessian::new(&pr.knots).apply(&pr.points);
        let delta = 1e-3;
        let tol = 1e-9 * (scale(&pr) + Hessian::new(&pr.knots).max_abs());
        for idx in 0..pr.points.coords().len() {
            let e = |dx: f64| {
                let mut p = pr.points.clone();
                p.coords_mut()[idx] += dx;
                energy(&pr.knots, &p).unwrap()
            };
            let fd = (e(delta) - e(-delta)) / (2.0 * delta);
            prop_assert!((fd - hp.coords()[idx]).abs() <= tol, "{fd} vs {}", hp.coords()[idx]);
        }
    }

    /// H is symmetric positive semidefinite with kernel of dimension 1 (closed: constants) or
    /// 2 (open: linear polynomials in t).
    #[test]
    fn psd_and_kernel_dimension(pr in problem(2..=12)) {
        let hess = Hessian::new(&pr.knots);
        let h = hess.to_dense();
        let ev = h.clone().symmetric_eigenvalues();
        let lmax = ev.amax();
        // Smallest non-zero eigenvalue here is ≳ 1e-7 λmax (N ≤ 12, gap ratio ≤ 10); round-off is
        // ≲ 1e-14 λmax: the threshold separates them with margin on both sides.
        let zero = 1e-10 * lmax;
        prop_assert!(ev.iter().all(|&l| l >= -zero), "negative eigenvalue in {ev}");
        let kernel = ev.iter().filter(|&&l| l.abs() <= zero).count();
        let want = if pr.knots.is_closed() { 1 } else { 2 };
        prop_assert_eq!(kernel, want, "eigenvalues {}", ev);
        // The kernel vectors themselves: constants, and for open curves t.
        let ones = Points::new(1, vec![1.0; hess.len()]).unwrap();
        prop_assert!(max_abs(hess.apply(&ones).coords()) <= 1e-12 * lmax);
        if !pr.knots.is_closed() {
            let t = Points::new(1, pr.knots.values().to_vec()).unwrap();
            let tscale = max_abs(pr.knots.values()).max(1.0);
            prop_assert!(max_abs(hess.apply(&t).coords()) <= 1e-12 * lmax * tscale);
        }
    }

    /// The exact knot gradient against central finite differences of (2.1).
    #[test]
    fn knot_gradient_matches_finite_differences(pr in problem(2..=9)) {
        let g = knot_gradient(&pr.knots, &pr.points).unwrap();
        let fd = fd_knot_gradient(&pr);
        let e = energy(&pr.knots, &pr.points).unwrap();
        let tol = FD_TOL * (e / min_span(&pr.knots) + max_abs(&g)) + 1e-12;
        for (k, (a, b)) in g.iter().zip(&fd).enumerate() {
            prop_assert!((a - b).abs() <= tol, "knot {k}: exact {a} vs fd {b} (tol {tol})");
        }
    }

    /// Translation invariance Σ ∂E/∂t_k = 0 and homogeneity Σ t_k ∂E/∂t_k = −3E.
    #[test]
    fn knot_gradient_euler_identities(pr in problem(2..=12)) {
        let g = knot_gradient(&pr.knots, &pr.points).unwrap();
        let e = energy(&pr.knots, &pr.points).unwrap();
        let t = pr.knots.values();
        let gs: f64 = g.iter().sum();
        let tg: f64 = g.iter().zip(t).map(|(a, b)| a * b).sum();
        let sc = g.iter().zip(t).map(|(a, b)| (a * b).abs() + a.abs()).sum::<f64>() + e;
        prop_assert!(gs.abs() <= REL_TOL * sc);
        prop_assert!((tg + 3.0 * e).abs() <= REL_TOL * sc, "{tg} vs {}", -3.0 * e);
    }

    /// The per-vertex gradient equals the closed form (corrected Lemma 2.4):
    /// 2[s_{i−1}·(c_i − c_{i−1})/h_{i−1} − s_i·(c_{i+1} − c_i)/h_i] + |c_{i+1}|² − |c_{i−1}|²,
    /// which is 2·printed + |c_{i+1}|² − |c_{i−1}|².
    #[test]
    fn corrected_lemma_2_4_closed_form(pr in problem(3..=12)) {
        let v = vertex_knot_gradient(&pr.knots, &pr.points).unwrap();
        let printed = knot_gradient_printed(&pr.knots, &pr.points).unwrap();
        let c = second_differences(&pr.knots, &pr.points).unwrap();
        let n = pr.knots.vertex_count();
        let tol = REL_TOL * (scale(&pr) / min_span(&pr.knots));
        for i in 0..n {
            let (prev, next) = ((i + n - 1) % n, (i + 1) % n);
            let (cp, cn) = (
                if pr.knots.is_closed() || i >= 1 { norm2(c.point(prev)) } else { 0.0 },
                if pr.knots.is_closed() || i + 1 < n { norm2(c.point(next)) } else { 0.0 },
            );
            let want = 2.0 * printed[i] + cn - cp;
            prop_assert!((v[i] - want).abs() <= tol, "vertex {i}: {} vs {want}", v[i]);
        }
    }

    /// Orthogonality residuals are Df(t_i)·(Hp)_i = 2 Df(t_i)·jmp_i.
    #[test]
    fn orthogonality_residuals_are_df_dot_hp(pr in problem(3..=10)) {
        for rule in [DerivativeRule::Average, DerivativeRule::Bessel] {
            let r = orthogonality_residuals(&pr.knots, &pr.points, rule).unwrap();
            let j = jumps(&pr.knots, &pr.points).unwrap();
            let df = divdiff::vertex_derivatives(&pr.knots, &pr.points, rule).unwrap();
            for (i, ri) in r.iter().enumerate() {
                let want: f64 = 2.0 * df.point(i).iter().zip(j.point(i)).map(|(a, b)| a * b).sum::<f64>();
                let sc = norm2(df.point(i)).sqrt() * Hessian::new(&pr.knots).max_abs() * max_abs(pr.points.coords());
                prop_assert!((ri - want).abs() <= REL_TOL * sc + 1e-300);
            }
        }
    }
}

/// A fixed non-uniform closed problem (seeded LCG, reproducible).
fn seeded(n: usize, d: usize, closed: bool, seed: u64) -> Problem {
    let mut s = seed;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let m = if closed { n + 1 } else { n };
    let mut t = vec![0.0];
    for _ in 1..m {
        let last = t[t.len() - 1];
        t.push(last + 0.2 + 1.8 * next());
    }
    let coords = (0..n * d).map(|_| 6.0 * next() - 3.0).collect();
    Problem {
        knots: if closed {
            Knots::closed(t)
        } else {
            Knots::open(t)
        }
        .unwrap(),
        points: Points::new(d, coords).unwrap(),
    }
}

/// The printed Lemma 2.4 disagrees with finite differences (relative error ≥ 10%) while the
/// corrected gradient agrees (relative error ≤ 1e-6), on seeded non-uniform problems.
#[test]
fn printed_lemma_2_4_fails_where_corrected_gradient_holds() {
    for (seed, closed, d) in [(1, true, 2), (2, true, 3), (3, false, 2), (4, false, 1)] {
        let pr = seeded(9, d, closed, seed);
        let fd = per_vertex(&pr.knots, fd_knot_gradient(&pr));
        let exact = vertex_knot_gradient(&pr.knots, &pr.points).unwrap();
        let printed = knot_gradient_printed(&pr.knots, &pr.points).unwrap();
        let rel = |g: &[f64]| {
            let diff: Vec<f64> = g.iter().zip(&fd).map(|(a, b)| a - b).collect();
            max_abs(&diff) / max_abs(&fd)
        };
        assert!(
            rel(&exact) <= 1e-6,
            "seed {seed}: corrected {}",
            rel(&exact)
        );
        assert!(
            rel(&printed) >= 0.1,
            "seed {seed}: printed {}",
            rel(&printed)
        );
    }
}

/// A regular polygon inscribed in a circle, on uniform knots: by symmetry Hp_i is radial and
/// Df(t_i) tangential, so the orthogonality residuals vanish, and so does the knot gradient.
#[test]
fn regular_polygon_is_knot_stationary() {
    let n = 7;
    let rows: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let a = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let p = Points::from_rows(&rows).unwrap();
    let knots = Knots::closed((0..=n).map(|i| 0.5 * i as f64).collect()).unwrap();
    let e = energy(&knots, &p).unwrap();
    for rule in [DerivativeRule::Average, DerivativeRule::Bessel] {
        let r = orthogonality_residuals(&knots, &p, rule).unwrap();
        assert!(max_abs(&r) <= 1e-12 * e, "{r:?}");
    }
    let g = vertex_knot_gradient(&knots, &p).unwrap();
    assert!(max_abs(&g) <= 1e-12 * e, "{g:?}");
    // Moving one vertex off the circle breaks both.
    let mut q = p.clone();
    q.point_mut(3)[0] *= 1.3;
    let g = vertex_knot_gradient(&knots, &q).unwrap();
    assert!(max_abs(&g) > 1e-3 * e);
}

#[test]
fn size_mismatch_is_an_error() {
    let knots = Knots::open(vec![0.0, 1.0, 3.0]).unwrap();
    let p = Points::zeros(2, 2);
    let want = energy::Error::WrongLength {
        field: "points",
        expected: 3,
        got: 2,
    };
    assert_eq!(energy(&knots, &p), Err(want.clone()));
    assert_eq!(energy_by_jumps(&knots, &p), Err(want.clone()));
    assert_eq!(knot_gradient(&knots, &p), Err(want.clone()));
    assert_eq!(knot_gradient_printed(&knots, &p), Err(want.clone()));
    assert_eq!(
        orthogonality_residuals(&knots, &p, DerivativeRule::Bessel),
        Err(want)
    );
}
