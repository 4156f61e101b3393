//! Hard channels (issue 15): random steep fronts, narrow bumps, jittered sites and vertices,
//! polyline and piecewise-cubic bounds. Every answer is checked independently of the solver
//! (strip-testkit): the strip exactly on every piece, interpolation, C², Lemma 1.1's conditions
//! (which with feasibility are sufficient for optimality), the gap, and — where Clarabel solves
//! the fine-grid QP on a grid holding our knots (its interior point gives up at fronts of slope
//! ~10³) — the energy against Clarabel's. Infeasible channels are refused with the typed error
//! naming where.

use proptest::prelude::*;
use strip::{solve, Bound, Error, Infeasibility, Options, Problem, Side, Solution};
use strip_testkit::{BoundKind, Channel};

/// The value scale for relative checks: the largest |y|, or 1.
fn scale(p: &Problem) -> f64 {
    p.y.iter().fold(0.0f64, |m, y| m.max(y.abs())).max(1.0)
}

/// Every independent check of an answer; returns whether Clarabel could be compared.
fn check(p: &Problem, s: &Solution, clarabel: bool) -> Result<bool, TestCaseError> {
    let v = scale(p);
    strip_testkit::strip_violation(p, s)
        .at_most(1e-9 * v)
        .map_err(TestCaseError::fail)?;
    let interp = strip_testkit::interpolation_error(p, s);
    prop_assert!(interp <= 1e-12 * v, "interpolation {interp:e}");
    let c2 = strip_testkit::c2_jump(s);
    prop_assert!(c2.iter().all(|j| *j <= 1e-9), "C² jumps {c2:?}");
    let l = strip_testkit::lemma_1_1(p, s, 1e-9 * v);
    prop_assert!(
        l.f2_jump <= 1e-9 && l.end_f2 <= 1e-9 && l.stray_jump <= 1e-8 && l.wrong_sign <= 1e-8,
        "Lemma 1.1: {l:?}"
    );
    prop_assert!(s.gap <= 1e-9, "gap {:e}", s.gap);
    if !clarabel {
        return Ok(false);
    }
    let grid = strip_testkit::fine_grid(p, 2, Some(s));
    let Ok(lb) = strip_testkit::lower_bound(p, &grid, true) else {
        return Ok(false);
    };
    if !lb.solved {
        return Ok(false);
    }
    let rel = (s.energy - lb.value).abs() / s.energy;
    prop_assert!(
        rel <= 1e-8,
        "∫f''² {} vs Clarabel {} (relative {rel:e})",
        s.energy,
        lb.value
    );
    Ok(true)
}

fn channel() -> impl Strategy<Value = Channel> {
    (
        any::<u64>(),
        50usize..1500,
        2usize..120,
        0usize..7,
        1.0f64..3.2,
        0usize..4,
        (0.002f64..0.03, 0.005f64..0.05, 1.0f64..3.0),
        0.0f64..0.45,
    )
        .prop_map(
            |(seed, m, n, fronts, logslope, bumps, (bw, wmin, wratio), jitter)| Channel {
                seed,
                breakpoints: m,
                sites: n,
                fronts,
                front_slope: 10f64.powf(logslope),
                bumps,
                bump_width: bw,
                w_min: wmin,
                w_max: wmin * wratio,
                jitter,
                bounds: BoundKind::Polyline,
                shared_vertices: true,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random steep channels with polyline bounds (the exchange): feasible, interpolating, C²,
    /// Lemma 1.1, gap ≤ 1e-9; against Clarabel where its interior point converges.
    #[test]
    fn random_polyline_channels_are_solved_exactly(c in channel()) {
        let p = c.problem();
        let s = solve(&p, &Options::default());
        prop_assert!(s.is_ok(), "{c:?}: {:?}", s.err());
        let s = s.unwrap();
        check(&p, &s, c.breakpoints <= 600)?;
    }

    /// The same channels with bounds given as one cubic per data interval (Newton on Φ, the
    /// exchange when Newton stalls).
    #[test]
    fn random_piecewise_cubic_channels_are_solved_exactly(c in channel()) {
        let p = Channel { bounds: BoundKind::Pieces, ..c }.problem();
        let s = solve(&p, &Options::default());
        prop_assert!(s.is_ok(), "{c:?}: {:?}", s.err());
        let s = s.unwrap();
        check(&p, &s, true)?;
    }

    /// Independent vertices may make the polylines cross where M is coarse against a front: then
    /// the refusal names the lower polyline and a place where the strip really closes (checked
    /// independently: d ≤ e there); otherwise the answer passes every check.
    #[test]
    fn crossing_polylines_are_refused_where_they_cross(c in channel()) {
        let p = Channel { shared_vertices: false, ..c }.problem();
        match solve(&p, &Options::default()) {
            Ok(s) => {
                check(&p, &s, false)?;
            }
            Err(Error::Infeasible { field: "lower.polyline", reason: Infeasibility::Closed { at }, .. }) => {
                let e = strip_testkit::bound_at(&p.lower, &p.t, at).unwrap();
                let d = strip_testkit::bound_at(&p.upper, &p.t, at).unwrap();
                prop_assert!(d - e <= 1e-12 * scale(&p), "not closed at {at}: width {}", d - e);
            }
            Err(e) => prop_assert!(false, "{c:?}: {e}"),
        }
    }
}

/// The issue-15 channels (M = 10⁴; 16 and 200 sites; seeds 1..4): every check, Lemma 1.1 as the
/// optimality certificate (Clarabel does not converge on them).
#[test]
fn issue_15_channels() {
    for seed in 1..=4 {
        for n in [16, 200] {
            let p = Channel {
                seed,
                sites: n,
                ..Channel::default()
            }
            .problem();
            let s = solve(&p, &Options::default()).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            check(&p, &s, false).unwrap();
            assert!(!s.extra_knots.is_empty());
        }
    }
}

/// A lower polyline with an upper bound given as cubic pieces (the exchange handles both).
#[test]
fn mixed_polyline_and_pieces() {
    let p = Channel {
        seed: 9,
        breakpoints: 800,
        sites: 12,
        ..Channel::default()
    }
    .problem();
    let top = match &p.upper {
        Bound::Polyline(v) => v.iter().fold(f64::NEG_INFINITY, |m, q| m.max(q[1])),
        _ => unreachable!(),
    };
    // the upper bound: a parabola dipping to 0.03 above the highest vertex of the old one
    let upper: Vec<[f64; 4]> =
        p.t.windows(2)
            .map(|w| {
                // (t − ½)² + top + 0.03 as a cubic in s = t − w[0]
                let c = w[0] - 0.5;
                [c * c + top + 0.03, 2.0 * c, 1.0, 0.0]
            })
            .collect();
    let q = Problem {
        upper: Bound::Pieces(upper),
        ..p
    };
    let s = solve(&q, &Options::default()).unwrap();
    check(&q, &s, false).unwrap();
}

/// Refusals within the input check, naming the field, index and place.
#[test]
fn infeasible_channels_are_refused_with_the_place() {
    let base = Channel {
        seed: 4,
        breakpoints: 2_000,
        sites: 30,
        ..Channel::default()
    }
    .problem();
    // a site outside its bounds
    let mut p = base.clone();
    p.y[7] += 1.0;
    assert!(matches!(
        solve(&p, &Options::default()),
        Err(Error::Infeasible {
            field: "y",
            index: 7,
            reason: Infeasibility::OutsideBound {
                side: Side::Upper,
                ..
            }
        })
    ));
    // a pinch between two sites: one upper vertex pulled below the lower polyline
    let mut p = base.clone();
    let (k, x) = match (&mut p.upper, &p.lower) {
        (Bound::Polyline(u), Bound::Polyline(l)) => {
            // a vertex between sites 11 and 12
            let mid = 0.5 * (p.t[11] + p.t[12]);
            let k = u.partition_point(|q| q[0] < mid);
            u[k][1] = l[k][1] - 0.01;
            (k, u[k][0])
        }
        _ => unreachable!(),
    };
    match solve(&p, &Options::default()) {
        Err(Error::Infeasible {
            field: "lower.polyline",
            index,
            reason: Infeasibility::Closed { at },
        }) => {
            assert!(index.abs_diff(k) <= 1, "vertex {index}, pulled {k}");
            assert!((at - x).abs() <= 1e-3, "at {at}, vertex at {x}");
        }
        other => panic!("{other:?}"),
    }
    // a pinch of cubic pieces strictly between two sites (the ends of the piece open)
    let mut p = Channel {
        bounds: BoundKind::Pieces,
        ..Channel::default()
    }
    .problem();
    if let (Bound::Pieces(u), Bound::Pieces(l)) = (&mut p.upper, &p.lower) {
        let h = p.t[6] - p.t[5];
        // d − e at the piece's ends unchanged, its middle pushed below zero
        let mid_width = {
            let s = 0.5 * h;
            let ev = |c: &[f64; 4]| c[0] + s * (c[1] + s * (c[2] + s * c[3]));
            ev(&u[5]) - ev(&l[5])
        };
        // d − k·s(h − s): lower by k h²/4 = 2·(the width) in the middle, unchanged at the ends
        let k = 8.0 * mid_width / (h * h);
        u[5][1] -= k * h;
        u[5][2] += k;
    }
    match solve(&p, &Options::default()) {
        Err(Error::Infeasible {
            field: "lower.pieces",
            index: 5,
            reason: Infeasibility::Closed { at },
        }) => assert!(at > p.t[5] && at < p.t[6]),
        other => panic!("{other:?}"),
    }
}

/// A zigzag y = ±1 at t = 0, 1, …, n − 1 with the lower bound 0.05 below the data (a polyline
/// through (t_i, y_i − 0.05)): the natural spline dips through the bound in every data interval,
/// and the dips are apart — at every site f is 0.05 inside. The sweeps once took the violated
/// sub-intervals of the whole curve as one run and added one contact per sweep (n + 21 sweeps:
/// refused at n = 400 with the sweep limit of 400); each dip is now its own candidate. A second
/// case closes it in a two-sided channel 0.05 wide about the zigzag's polyline.
#[test]
fn a_zigzag_dipping_through_the_bound_in_every_interval() {
    for (n, upper) in [(1000, false), (3000, true)] {
        let t: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let y: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let line =
            |off: f64| Bound::Polyline(t.iter().zip(&y).map(|(&t, &y)| [t, y + off]).collect());
        let p = Problem {
            t: t.clone(),
            y: y.clone(),
            lower: line(-0.05),
            upper: if upper { line(0.05) } else { Bound::None },
            end_slopes: [None, None],
        };
        let s = solve(&p, &Options::default()).unwrap_or_else(|e| panic!("n = {n}: {e}"));
        check(&p, &s, false).unwrap();
        assert!(
            s.extra_knots.len() >= n - 2,
            "n = {n}: {} contacts",
            s.extra_knots.len()
        );
        assert!(s.rounds < 100, "n = {n}: {} sweeps", s.rounds);
    }
}

/// `solve_observed` tells of every sweep of the exchange in order, the last one being the
/// answer's: its number is `rounds`, its excursion within the exchange's tolerance, its
/// contacts the answer's extra knots; and the answer is `solve`'s, bit for bit.
#[test]
fn the_observer_is_told_of_every_sweep() {
    let n = 400;
    let t: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let y: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let line = |off: f64| Bound::Polyline(t.iter().zip(&y).map(|(&t, &y)| [t, y + off]).collect());
    let p = Problem {
        t: t.clone(),
        y: y.clone(),
        lower: line(-0.05),
        upper: line(0.05),
        end_slopes: [None, None],
    };
    let events = std::sync::Mutex::new(Vec::new());
    let s = strip::solve_observed(&p, &Options::default(), &|e| {
        events.lock().unwrap().push(*e)
    })
    .unwrap();
    let events = events.into_inner().unwrap();
    let sweeps: Vec<(usize, f64, usize)> = events
        .iter()
        .map(|e| match *e {
            strip::Progress::Sweep {
                sweep,
                excursion,
                contacts,
            } => (sweep, excursion, contacts),
            _ => unreachable!("only sweeps are reported"),
        })
        .collect();
    assert_eq!(
        sweeps.iter().map(|s| s.0).collect::<Vec<_>>(),
        (1..=s.rounds).collect::<Vec<_>>()
    );
    let (_, excursion, contacts) = *sweeps.last().unwrap();
    assert!(sweeps[0].1 > 1e-3, "first excursion {:e}", sweeps[0].1);
    assert!(excursion <= 1e-12, "last excursion {excursion:e}");
    assert_eq!(contacts, s.extra_knots.len());
    let plain = solve(&p, &Options::default()).unwrap();
    assert_eq!(plain.energy.to_bits(), s.energy.to_bits());
    assert_eq!(plain.breaks, s.breaks);
}
