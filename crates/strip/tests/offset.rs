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
    natural_exact(t, y).0
}

/// A double as the rational it is.
fn q(x: f64) -> BigRational {
    BigRational::from_float(x).expect("finite")
}

/// ∫f''² and the moments f''(t_i) of the natural cubic spline through (t, y), exactly.
fn natural_exact(t: &[f64], y: &[f64]) -> (BigRational, Vec<BigRational>) {
    natural_exact_through(t, &y.iter().map(|&x| q(x)).collect::<Vec<_>>())
}

/// [`natural_exact`] through rational values.
fn natural_exact_through(t: &[f64], y: &[BigRational]) -> (BigRational, Vec<BigRational>) {
    let t: Vec<_> = t.iter().map(|&x| q(x)).collect();
    let moments = spline_exact(&t, y, [None, None]);
    let energy = energy_exact(&t, moments.windows(2).map(|m| [&m[0], &m[1]]));
    (energy, moments)
}

/// ∫f''² of pieces on the breaks x with f'' = \[a, b\] at each piece's ends (f'' is linear on
/// each piece: h/3 (a² + ab + b²)), exactly.
fn energy_exact<'a>(
    x: &[BigRational],
    second: impl Iterator<Item = [&'a BigRational; 2]>,
) -> BigRational {
    let three = BigRational::from_integer(3.into());
    second
        .enumerate()
        .map(|(i, [a, b])| (&x[i + 1] - &x[i]) / &three * (a * a + a * b + b * b))
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

/// 40 sites near t = 5·10⁵ with spans from 1e-8 to 1e-1 (a cluster of very short ones among
/// long ones), values a smooth wave plus a line, bounds far away: the natural spline, whose
/// moments at the short spans turn on the last digits of the values. The frame's
/// (y − a) − b(t − t₀) rounds each value by ~ε|y|, and over a span h that moves a slope by
/// ε|y|/h: on `xtask/sweeps/strip.py`'s seed 719, case 69 (5000 such sites), f'' came back 54 %
/// off at a span of 1e-7 and ∫f''² 6.7e-7 above the exact value, though scipy's `CubicSpline`
/// on the same doubles matched it to 12 digits.
fn clustered_far_problem() -> Problem {
    let spans = [
        3e-2, 1e-7, 4e-2, 2e-6, 5e-2, 1e-8, 3e-2, 6e-2, 3e-7, 2e-2, 8e-2, 5e-3, 1e-6, 4e-2, 7e-2,
        2e-8, 3e-2, 5e-2, 9e-7, 6e-2, 4e-2, 1e-1, 3e-6, 2e-2, 5e-2, 5e-8, 4e-2, 3e-2, 7e-2, 2e-7,
        5e-2, 6e-2, 4e-2, 8e-6, 3e-2, 5e-2, 2e-2, 1e-7, 4e-2,
    ];
    let mut t = vec![499_999.999_999_999_94_f64];
    for h in spans {
        let next = t[t.len() - 1] + h;
        t.push(next);
    }
    let (t0, span) = (t[0], t[t.len() - 1] - t[0]);
    let y: Vec<f64> = t
        .iter()
        .map(|&x| 0.3 + 0.7 * ((x - t0) / span) + 0.25 * (9.0 * (x - t0) / span).sin())
        .collect();
    let n = t.len();
    Problem {
        t,
        y,
        lower: Bound::Pieces(vec![[-10.0, 0.0, 0.0, 0.0]; n - 1]),
        upper: Bound::Pieces(vec![[10.0, 0.0, 0.0, 0.0]; n - 1]),
        end_slopes: [None, None],
    }
}

#[test]
fn clustered_sites_far_from_the_origin_leave_the_natural_spline_exact() {
    let p = clustered_far_problem();
    let s = solve(&p, &Options::default()).expect("the natural spline");
    assert!(s.extra_knots.is_empty(), "the bounds are far away");
    assert_through_exactly(&s, &p.t, &p.y.iter().map(|&y| q(y)).collect::<Vec<_>>());
}

/// `s` is the natural spline through (x, v) to 1e-12 of ∫f''² and 1e-9 of max |f''| at every
/// break (from the piece that starts there; the last from the one ending there), against exact
/// rationals.
fn assert_through_exactly(s: &strip::Solution, x: &[f64], v: &[BigRational]) {
    let (energy, moments) = natural_exact_through(x, v);
    let exact = energy.to_f64().unwrap();
    let rel = (s.energy - exact).abs() / exact;
    assert!(
        rel <= 1e-12,
        "∫f''² {} against {exact} exactly: {rel:e}",
        s.energy
    );
    let moments: Vec<f64> = moments.iter().map(|m| m.to_f64().unwrap()).collect();
    let largest = moments.iter().fold(0.0f64, |a, m| a.max(m.abs()));
    for (j, exact) in moments.iter().enumerate() {
        let ours = s.derivative(x[j], 2);
        assert!(
            (ours - exact).abs() <= 1e-9 * largest,
            "f''({}) {ours} against {exact} exactly (largest |f''| {largest})",
            x[j]
        );
    }
}

/// The same sites in a polyline band of ±1e-4 about the data polygon: the exchange's answer, a
/// spline through the data and the points it holds on the bounds, is formed through the same
/// points in the caller's frame. Its ∫f''² and f'' at every break are checked against the spline
/// through those points (the data, and each contact's bound value, the polyline's exact value at
/// the contact's abscissa) in exact rationals. Before, the same sites in a band of 0.3 % of the
/// range of `strip.py`'s seed 719, case 69 came back 6.0e-7 above it, with f'' 54 % off; with the
/// contacts' values rounded to doubles (item 49's re-solve), f'' came back 1.1e-9 of its size off
/// the exact bound's spline at a break 1e-8 from the next.
#[test]
fn contacts_on_clustered_sites_far_from_the_origin_are_exact() {
    let mut p = clustered_far_problem();
    let w = 1e-4;
    let band = |s: f64| {
        Bound::Polyline(
            p.t.iter()
                .zip(&p.y)
                .map(|(&t, &y)| [t, y + s * w])
                .collect(),
        )
    };
    (p.lower, p.upper) = (band(-1.0), band(1.0));
    let s = solve(&p, &Options::default()).expect("answered");
    assert!(
        !s.extra_knots.is_empty(),
        "the band is narrow enough to touch"
    );
    // the value at every break: the data at a site, the polygon ± w at a contact, exactly
    // (a + (b − a)(x − x₀)/(x₁ − x₀) between the bound's vertices, which are doubles)
    let values = values_at_breaks(&p, &s, |k, x| {
        let sign = match k.kind {
            strip::KnotKind::Touch(strip::Side::Lower) => -1.0,
            strip::KnotKind::Touch(strip::Side::Upper) => 1.0,
            other => panic!("the exchange's contacts are touching points: {other:?}"),
        };
        let i = k.interval;
        let (a, b) = (q(p.y[i] + sign * w), q(p.y[i + 1] + sign * w));
        let along = (q(x) - q(p.t[i])) / (q(p.t[i + 1]) - q(p.t[i]));
        &a + (b - &a) * along
    });
    assert_through_exactly(&s, &s.breaks, &values);
}

/// The same sites in bands of constant pieces, each interval's bound its larger (upper) or
/// smaller (lower) data value ± w: the wave overshoots its sites near its crests and troughs and
/// touches there. Newton on Φ answers (one sweep) with tangencies, where f' meets the bound's
/// slope; its answer is the spline through the data and the touching points, and is formed
/// through the same points in the caller's frame (`resolve`). Before, it came back 1.5e-11 (two
/// tangencies, w = 1e-3) and 1.3e-11 (one, w = 3e-3) of ∫f''² above the spline through those
/// points in exact rationals, with f'' 8.4e-9 and 1.6e-8 of its size off.
#[test]
fn tangencies_on_clustered_sites_far_from_the_origin_are_exact() {
    let mut p = clustered_far_problem();
    let n = p.t.len();
    for (w, touches) in [(1e-3, 2), (3e-3, 1)] {
        let bound = |side: f64| {
            let piece = |i: usize| {
                let (a, b) = (p.y[i], p.y[i + 1]);
                [
                    if side > 0.0 { a.max(b) } else { a.min(b) } + side * w,
                    0.0,
                    0.0,
                    0.0,
                ]
            };
            Bound::Pieces((0..n - 1).map(piece).collect())
        };
        (p.lower, p.upper) = (bound(-1.0), bound(1.0));
        let s = solve(&p, &Options::default()).expect("answered");
        assert_eq!(s.rounds, 1, "Newton on Φ's answer, not the exchange's");
        assert_eq!(s.extra_knots.len(), touches, "w = {w}: {:?}", s.extra_knots);
        // the value at every break: the data at a site, the bound's piece at a contact
        let values = values_at_breaks(&p, &s, |k, _| {
            let bound = match k.kind {
                strip::KnotKind::Touch(strip::Side::Lower) => &p.lower,
                strip::KnotKind::Touch(strip::Side::Upper) => &p.upper,
                other => panic!("the bands are touched at points: {other:?}"),
            };
            let Bound::Pieces(pieces) = bound else {
                unreachable!("constant pieces")
            };
            q(pieces[k.interval][0])
        });
        assert_through_exactly(&s, &s.breaks, &values);
    }
}

/// The value at every break of `s`, exactly: the data at a site, `contact(knot, x)` at a contact.
fn values_at_breaks(
    p: &Problem,
    s: &strip::Solution,
    contact: impl Fn(&strip::ExtraKnot, f64) -> BigRational,
) -> Vec<BigRational> {
    s.breaks
        .iter()
        .map(
            |&x| match p.t.iter().position(|t| t.to_bits() == x.to_bits()) {
                Some(i) => q(p.y[i]),
                None => {
                    let k = s.extra_knots.iter().find(|k| k.t.to_bits() == x.to_bits());
                    contact(k.expect("a contact"), x)
                }
            },
        )
        .collect()
}

/// The clamped (or natural, `None`) cubic spline through (x, y) in exact rationals: its moments
/// f''(x_k) (the tridiagonal system of `strip`'s spline module, by the Thomas algorithm).
fn spline_exact(
    x: &[BigRational],
    y: &[BigRational],
    ends: [Option<BigRational>; 2],
) -> Vec<BigRational> {
    let k = x.len();
    let (three, six) = (
        BigRational::from_integer(3.into()),
        BigRational::from_integer(6.into()),
    );
    let h: Vec<BigRational> = (0..k - 1).map(|i| &x[i + 1] - &x[i]).collect();
    let d: Vec<BigRational> = (0..k - 1).map(|i| (&y[i + 1] - &y[i]) / &h[i]).collect();
    let zero = BigRational::zero;
    // rows [sub, diagonal, super] and right-hand sides
    let mut rows = Vec::with_capacity(k);
    let mut r = Vec::with_capacity(k);
    for i in 0..k {
        let (row, rhs) = if i == 0 || i == k - 1 {
            let end = &ends[usize::from(i > 0)];
            match end {
                None => (
                    [zero(), BigRational::from_integer(1.into()), zero()],
                    zero(),
                ),
                Some(s) if i == 0 => ([zero(), &h[0] / &three, &h[0] / &six], &d[0] - s),
                Some(s) => (
                    [&h[k - 2] / &six, &h[k - 2] / &three, zero()],
                    s - &d[k - 2],
                ),
            }
        } else {
            (
                [&h[i - 1] / &six, (&h[i - 1] + &h[i]) / &three, &h[i] / &six],
                &d[i] - &d[i - 1],
            )
        };
        rows.push(row);
        r.push(rhs);
    }
    let (mut cp, mut dp) = (Vec::with_capacity(k), Vec::with_capacity(k));
    for i in 0..k {
        let [a, b, c] = &rows[i];
        let (den, num) = if i == 0 {
            (b.clone(), r[0].clone())
        } else {
            (b - a * &cp[i - 1], &r[i] - a * &dp[i - 1])
        };
        cp.push(c / &den);
        dp.push(num / den);
    }
    let mut m = vec![zero(); k];
    for i in (0..k).rev() {
        m[i] = if i + 1 < k {
            &dp[i] - &cp[i] * &m[i + 1]
        } else {
            dp[i].clone()
        };
    }
    m
}

/// Even sites near t = 5·10⁵ over a smooth wave, a lower bound on each interval 1e-6 below the
/// chord (linear pieces): the wave sags below its chords, so Newton on Φ answers with the curve on
/// its bound over subarcs (f straight there) and a touching point. Formed in the caller's frame
/// (`resolve`): between its subarcs the splines through its breaks (the data at a site, the
/// bound's exact value at a contact), clamped to the bound's slope at a subarc's ends, and the
/// bound itself on each subarc. Checked against that construction in exact rationals, through
/// the answer's own breaks: ∫f''² to 1e-12 and f'' on both sides of every break to 1e-9 of its
/// largest size (before: 2.3e-11 and 2.5e-8, Newton's pieces mapped back from the normalized
/// frame); and where f leaves its bound, that f'' joins the bound's there to the rounding of
/// the abscissa (the optimum's condition, which `resolve` places the subarcs' ends on).
#[test]
fn subarcs_far_from_the_origin_are_formed_exactly() {
    let (n, w) = (40usize, 1e-6);
    let t: Vec<f64> = (0..n).map(|i| 5e5 + 0.1 * i as f64).collect();
    let y: Vec<f64> = (0..n).map(|i| 1.0 + (0.15 * i as f64).sin()).collect();
    let pieces: Vec<[f64; 4]> = (0..n - 1)
        .map(|i| [y[i] - w, (y[i + 1] - y[i]) / (t[i + 1] - t[i]), 0.0, 0.0])
        .collect();
    let p = Problem {
        t,
        y,
        lower: Bound::Pieces(pieces.clone()),
        upper: Bound::None,
        end_slopes: [None, None],
    };
    let s = solve(&p, &Options::default()).expect("answered");
    assert_eq!(s.rounds, 1, "Newton on Φ's answer");
    let subarcs = s
        .extra_knots
        .iter()
        .filter(|k| matches!(k.kind, strip::KnotKind::SubarcStart(_)))
        .count();
    assert!(subarcs >= 10, "subarcs: {:?}", s.extra_knots);
    // the bound (g, g', g'') at x, exactly
    let bound = |x: f64| {
        let i = p.t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
        let c: Vec<BigRational> = pieces[i].iter().map(|&c| q(c)).collect();
        let u = q(x) - q(p.t[i]);
        let three = BigRational::from_integer(3.into());
        let two = BigRational::from_integer(2.into());
        (
            &c[0] + &u * (&c[1] + &u * (&c[2] + &u * &c[3])),
            &c[1] + &u * (&two * &c[2] + &three * &u * &c[3]),
            &two * &c[2] + BigRational::from_integer(6.into()) * &u * &c[3],
        )
    };
    let values = values_at_breaks(&p, &s, |_, x| bound(x).0);
    let x: Vec<BigRational> = s.breaks.iter().map(|&b| q(b)).collect();
    let kind = |j: usize| {
        s.extra_knots
            .iter()
            .find(|k| k.t.to_bits() == s.breaks[j].to_bits())
            .map(|k| k.kind)
    };
    // f'' at both ends of every piece, exactly: segments between the subarcs, the bound on each
    let k = x.len();
    let mut second: Vec<[BigRational; 2]> = Vec::with_capacity(k - 1);
    let (mut from, mut left) = (0, None);
    for j in 0..k {
        let start = matches!(kind(j), Some(strip::KnotKind::SubarcStart(_)));
        if start || j == k - 1 {
            let right = start.then(|| bound(s.breaks[j]).1);
            let m = spline_exact(&x[from..=j], &values[from..=j], [left.clone(), right]);
            second.extend(m.windows(2).map(|m| [m[0].clone(), m[1].clone()]));
            if start {
                second.push([bound(s.breaks[j]).2, bound(s.breaks[j + 1]).2]);
                (from, left) = (j + 1, Some(bound(s.breaks[j + 1]).1));
            }
        }
    }
    assert_eq!(second.len(), k - 1);
    let energy = energy_exact(&x, second.iter().map(|[a, b]| [a, b]))
        .to_f64()
        .unwrap();
    let rel = (s.energy - energy).abs() / energy;
    assert!(
        rel <= 1e-12,
        "∫f''² {} against {energy} exactly: {rel:e}",
        s.energy
    );
    let exact: Vec<[f64; 2]> = second
        .iter()
        .map(|[a, b]| [a.to_f64().unwrap(), b.to_f64().unwrap()])
        .collect();
    let largest = exact.iter().flatten().fold(0.0f64, |a, m| a.max(m.abs()));
    for (j, [a, b]) in exact.iter().enumerate() {
        let (x0, x1) = (s.breaks[j], s.breaks[j + 1]);
        let mid = 0.5 * (x0 + x1);
        // (the piece's own f'' at its ends, from its coefficients)
        let c = s.coefficients[j];
        let ours = [2.0 * c[2], 2.0 * c[2] + 6.0 * c[3] * (x1 - x0)];
        for (o, e) in ours.iter().zip([a, b]) {
            assert!(
                (o - e).abs() <= 1e-9 * largest,
                "f'' {o} against {e} exactly on the piece about {mid} (largest |f''| {largest})"
            );
        }
    }
    // where f leaves its bound, f'' joins the bound's to the rounding of the abscissa
    for j in 1..k - 1 {
        if !matches!(
            kind(j),
            Some(strip::KnotKind::SubarcStart(_) | strip::KnotKind::SubarcEnd(_))
        ) {
            continue;
        }
        let (l, r) = (exact[j - 1], exact[j]);
        let third = |i: usize| (exact[i][1] - exact[i][0]) / (s.breaks[i + 1] - s.breaks[i]);
        let abscissa =
            4.0 * f64::EPSILON * s.breaks[j].abs() * (third(j - 1).abs() + third(j).abs());
        assert!(
            (l[1] - r[0]).abs() <= abscissa,
            "f'' jumps by {:e} at {} (the abscissa's rounding moves it by {abscissa:e})",
            (l[1] - r[0]).abs(),
            s.breaks[j]
        );
    }
}
