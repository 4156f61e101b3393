//! Values with a large common offset on clustered sites, bounds far away: the answer is the
//! natural spline, and its ∫f''² is checked against the natural spline's computed in exact
//! rational arithmetic from the same floating-point data (the moments of the tridiagonal
//! system, then ∫f''² = Σ h/3 (M_i² + M_i M_{i+1} + M_{i+1}²)). The solver's frame subtracted
//! the line ℓ(t) = a + b(t − t₀) from each value with a rounding of ulp(a); on values
//! 1e5 ± 0.1 with spans of 2e-4 that moved f'' by ~1e-4 of its size and ∫f''² by 1.5e-9 of
//! itself (found by `xtask/sweeps/strip.py`, seed 5, case 115, on 5000 sites). The offset now
//! comes out first, (y − a) − b(t − t₀), exact for values within a factor two of a. Here: 2.3e-16
//! of ∫f''² off the exact value (7.3e-10 with the old frame, which fails this test).

use num_rational::BigRational;
use num_traits::{ToPrimitive, Zero};
use strip::{solve, Bound, Options, Problem};

/// 40 sites, spans alternating 2e-4 (growing by a tenth) and 0.05; values 1e5 + 0.1 sin.
fn offset_problem() -> Problem {
    let mut t = vec![0.0f64];
    for k in 0..39 {
        let h = if k % 2 == 0 {
            2e-4 * (1.0 + 0.1 * k as f64)
        } else {
            0.05
        };
        t.push(t[k] + h);
    }
    let span = t[39];
    let y: Vec<f64> = t
        .iter()
        .map(|&x| 1e5 + 0.1 * (6.0 * x / span).sin())
        .collect();
    let (lo, hi) = (1e5 - 1.0, 1e5 + 1.0);
    Problem {
        t,
        y,
        lower: Bound::Pieces(vec![[lo, 0.0, 0.0, 0.0]; 39]),
        upper: Bound::Pieces(vec![[hi, 0.0, 0.0, 0.0]; 39]),
        end_slopes: [None, None],
    }
}

/// ∫f''² of the natural cubic spline through (t, y), exactly.
fn natural_energy_exact(t: &[f64], y: &[f64]) -> BigRational {
    let q = |x: f64| BigRational::from_float(x).expect("finite");
    let (t, y): (Vec<_>, Vec<_>) = (
        t.iter().map(|&x| q(x)).collect(),
        y.iter().map(|&x| q(x)).collect(),
    );
    let n = t.len();
    let h: Vec<BigRational> = (0..n - 1).map(|i| &t[i + 1] - &t[i]).collect();
    let s: Vec<BigRational> = (0..n - 1).map(|i| (&y[i + 1] - &y[i]) / &h[i]).collect();
    // h_{i−1} M_{i−1} + 2(h_{i−1} + h_i) M_i + h_i M_{i+1} = 6(s_i − s_{i−1}), M_0 = M_{n−1} = 0
    let m = n - 2;
    let two = BigRational::from_integer(2.into());
    let six = BigRational::from_integer(6.into());
    let (mut cp, mut dp) = (Vec::with_capacity(m), Vec::with_capacity(m));
    for i in 0..m {
        let (a, b, c) = (&h[i], &two * (&h[i] + &h[i + 1]), &h[i + 1]);
        let d = &six * (&s[i + 1] - &s[i]);
        let (den, num) = if i == 0 {
            (b, d)
        } else {
            (b - a * &cp[i - 1], d - a * &dp[i - 1])
        };
        cp.push(c / &den);
        dp.push(num / den);
    }
    let mut moments = vec![BigRational::zero(); n];
    for i in (0..m).rev() {
        let next = &moments[i + 2];
        moments[i + 1] = &dp[i] - &cp[i] * next;
    }
    let three = BigRational::from_integer(3.into());
    (0..n - 1)
        .map(|i| {
            let (a, b) = (&moments[i], &moments[i + 1]);
            &h[i] / &three * (a * a + a * b + b * b)
        })
        .fold(BigRational::zero(), |acc, e| acc + e)
}

#[test]
fn an_offset_of_the_values_leaves_the_natural_spline_exact() {
    let p = offset_problem();
    let s = solve(&p, &Options::default()).expect("the natural spline");
    assert!(s.extra_knots.is_empty(), "the bounds are far away");
    let exact = natural_energy_exact(&p.t, &p.y).to_f64().unwrap();
    let rel = (s.energy - exact).abs() / exact;
    assert!(
        rel <= 1e-12,
        "∫f''² {} against {exact} exactly: {rel:e}",
        s.energy
    );
}
