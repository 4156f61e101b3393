//! Conditioning study of Kersey refinement (issue 8): badly scaled data, extreme span-length
//! ratios, nearly collinear and nearly coincident points, radii from 0 to beyond the data, and
//! bounded iterations. Every case either meets the documented tolerances — the certified
//! relative KKT residual ([`refine::Refinement::kkt_residual`]) and the relative constraint
//! violation, recomputed here — or fails with a typed error. The limits asserted here are the
//! ones measured and tabulated in ROBUSTNESS.md (run with `--nocapture` to print the table).

mod kersey_support;
mod noisy;

use banded::vector::dist;
use divdiff::{Parametrization, Points, Topology};
use noisy::noisy_star;
use refine::{
    Boundary, ConicOptions, ConicProblem, Constraint, ConvexSet, Error, HalfSpace, Problem,
    Refinement, Tangent,
};

/// Certified KKT residual met by well-scaled problems (the exact solver's acceptance level).
const KKT_GOOD: f64 = 1e-9;
/// Smallest ball radius (relative to the data's extent) certified to [`KKT_GOOD`] (measured).
const RADIUS_CERTIFIED: f64 = 1e-9;

/// The largest coordinate distance from the data's centroid.
fn extent(q: &Points) -> f64 {
    let n = q.len() as f64;
    let d = q.dim();
    let c: Vec<f64> = (0..d)
        .map(|j| q.iter().map(|x| x[j]).sum::<f64>() / n)
        .collect();
    q.iter()
        .flat_map(|x| {
            x.iter()
                .zip(&c)
                .map(|(a, b)| (a - b).abs())
                .collect::<Vec<_>>()
        })
        .fold(0.0, f64::max)
}

/// `r` is certified to [`KKT_GOOD`] with the energy `reference` to 1e-9 relative: the optimum
/// of a problem known to have the same one.
fn assert_same_optimum(label: &str, r: &Refinement, reference: f64) {
    assert!(r.kkt_residual <= KKT_GOOD, "{label}: {}", r.kkt_residual);
    let rel = (r.energy - reference).abs() / reference;
    assert!(rel <= 1e-9, "{label}: E {} vs {reference}", r.energy);
}

/// Relative constraint violation: max over data points of the distance outside the constraint
/// set, over the data's extent.
fn violation(p: &Problem, r: &Refinement) -> f64 {
    let l = extent(&p.points);
    let mut worst: f64 = 0.0;
    for (i, &v) in r.data_vertex.iter().enumerate() {
        let (pv, qi) = (r.points.point(v), p.points.point(i));
        let dist = dist(pv, qi);
        let out = match &p.constraint {
            Constraint::Interpolate => dist,
            Constraint::Balls(radii) => dist - radii[i],
            Constraint::Smoothing(_) => 0.0,
            Constraint::HalfSpaces(sets) => sets[i]
                .iter()
                .map(|h| {
                    let len = h.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                    (h.normal.iter().zip(pv).map(|(a, b)| a * b).sum::<f64>() - h.offset) / len
                })
                .fold(0.0, f64::max),
        };
        worst = worst.max(out / l);
    }
    worst
}

/// One row of the table: (label, Ok(kkt, violation, energy) or the error).
type Row = (String, Result<(f64, f64, f64), Error>);

fn run(label: String, p: &Problem) -> Row {
    let r = p.solve().map(|r| {
        assert!(
            r.points.coords().iter().all(|x| x.is_finite()),
            "{label}: non-finite point"
        );
        assert!(
            r.energy.is_finite() && r.kkt_residual.is_finite(),
            "{label}"
        );
        (r.kkt_residual, violation(p, &r), r.energy)
    });
    match &r {
        Ok((k, v, e)) => eprintln!("| {label} | {k:.1e} | {v:.1e} | {e:.3e} |"),
        Err(e) => eprintln!("| {label} | error: {e} | | |"),
    }
    (label, r)
}

/// Eight points on a perturbed ellipse (closed) or an arc (open), scaled by `s` about `centre`.
fn data(n: usize, closed: bool, s: f64, centre: f64) -> Points {
    let mut c = Vec::new();
    for i in 0..n {
        let th = if closed {
            2.0 * std::f64::consts::PI * i as f64 / n as f64
        } else {
            0.9 * std::f64::consts::PI * i as f64 / (n - 1) as f64
        };
        let wobble = 0.1 * ((3 * i) as f64).sin();
        c.push(centre + s * (2.0 + wobble) * th.cos());
        c.push(centre + s * (1.0 - wobble) * th.sin());
    }
    Points::new(2, c).unwrap()
}

/// Every point in an axis-aligned box of half-width `w`.
fn boxes(q: &Points, w: f64) -> Constraint {
    kersey_support::cases::axis_boxes(q, |_| w)
}

fn kinds(q: &Points, s: f64) -> Vec<(&'static str, Constraint)> {
    let n = q.len();
    let radii: Vec<f64> = (0..n)
        .map(|i| if i % 3 == 0 { 0.0 } else { 0.2 * s })
        .collect();
    vec![
        ("interpolate", Constraint::Interpolate),
        ("balls", Constraint::Balls(radii)),
        ("smoothing", Constraint::Smoothing(vec![1.0; n])),
        ("half-spaces", boxes(q, 0.15 * s)),
    ]
}

/// Data scale from 1e-8 to 1e8 (and translated far from the origin): every kind stays
/// certified to [`KKT_GOOD`] with violation ≤ 1e-9, and E scales as s^{2−3e} (centripetal:
/// s^{1/2}). Smoothing weights are scaled by s^{−3e} to keep the problem the same.
#[test]
fn data_scale_1e_minus8_to_1e8() {
    eprintln!("| data scale s (centre) / kind | KKT | violation | E |");
    for closed in [true, false] {
        let base: Vec<f64> = kinds(&data(8, closed, 1.0, 0.0), 1.0)
            .iter()
            .map(|(_, c)| {
                Problem::new(data(8, closed, 1.0, 0.0))
                    .with_topology(if closed {
                        Topology::Closed
                    } else {
                        Topology::Open
                    })
                    .with_constraint(c.clone())
                    .solve()
                    .unwrap()
                    .energy
            })
            .collect();
        for (s, centre) in [
            (1e-8, 0.0),
            (1e-4, 0.0),
            (1.0, 0.0),
            (1e4, 0.0),
            (1e8, 0.0),
            (1.0, 1e6),
            (1e-3, 1e3),
        ] {
            let q = data(8, closed, s, centre);
            for (k, (name, c)) in kinds(&q, s).into_iter().enumerate() {
                let c = match c {
                    Constraint::Smoothing(w) => {
                        Constraint::Smoothing(w.iter().map(|x| x * s.powf(-1.5)).collect())
                    }
                    c => c,
                };
                let p = Problem::new(q.clone())
                    .with_topology(if closed {
                        Topology::Closed
                    } else {
                        Topology::Open
                    })
                    .with_constraint(c);
                let (label, row) = run(
                    format!(
                        "{} s = {s:e} (centre {centre:e}) {name}",
                        if closed { "closed" } else { "open" }
                    ),
                    &p,
                );
                let (kkt, viol, e) = row.unwrap_or_else(|e| panic!("{label}: {e}"));
                assert!(kkt <= KKT_GOOD, "{label}: kkt {kkt:e}");
                assert!(viol <= 1e-9, "{label}: violation {viol:e}");
                let want = base[k] * s.powf(0.5);
                assert!(
                    (e - want).abs() <= 1e-6 * want,
                    "{label}: E {e:e} vs {want:e}"
                );
            }
        }
    }
}

/// Open data whose consecutive spans differ by a ratio up to 1e6 (chordal knots: the knot
/// spans differ as much), constraint sets of size 0.01·L. Measured: interpolation stays
/// certified to ~1e-17 up to ratio 1e6, smoothing up to 1e4 (at 1e6 a typed
/// `Energy(Singular)` error); balls to ≤ 1e-13 and half-spaces to ≤ 2e-10 at every ratio
/// (earlier mains read up to 3.1e-3 and 8e-3 here): every kind is now required to certify to
/// [`KKT_GOOD`].
#[test]
fn span_ratios_up_to_1e6() {
    eprintln!("| span ratio / kind | KKT | violation | E |");
    let mut rows = Vec::new();
    for ratio in [1e2, 1e4, 1e6] {
        // Points on an arc with every other span shortened by `ratio`.
        let mut pts = Vec::new();
        let mut th = 0.0f64;
        for i in 0..8 {
            pts.push([2.0 * th.cos(), th.sin()]);
            th += if i % 2 == 0 { 0.4 } else { 0.4 / ratio };
        }
        let q = Points::from_rows(&pts).unwrap();
        let l = extent(&q);
        for (name, c) in kinds(&q, 0.05 * l) {
            let p = Problem::new(q.clone())
                .with_topology(Topology::Open)
                .with_parametrization(Parametrization::Chordal)
                .with_knot_iterations(0)
                .with_constraint(c);
            rows.push(run(format!("ratio {ratio:e} {name}"), &p));
        }
    }
    for (label, row) in rows {
        let ratio: f64 = label
            .split(' ')
            .nth(1)
            .and_then(|x| x.parse().ok())
            .unwrap_or(0.0);
        match row {
            Ok((kkt, viol, _)) => {
                assert!(viol <= KKT_GOOD, "{label}: violation {viol:e}");
                assert!(kkt <= KKT_GOOD, "{label}: kkt {kkt:e}");
            }
            // (Smoothing names its weights: `smoothing_weights_below_the_stiffness_name_the_weights`.)
            Err(e) => assert!(
                ratio >= 1e6
                    && matches!(
                        e,
                        Error::Energy(_)
                            | Error::InvalidParameter {
                                field: "weights",
                                ..
                            }
                    ),
                "{label}: {e}"
            ),
        }
    }
}

/// Nearly collinear data (a line bent by δ): E → 0 like δ², the certificate stays meaningful
/// for interpolation (the reactions are exact linear algebra) down to δ = 1e-12.
#[test]
fn nearly_collinear_points() {
    eprintln!("| collinear, bend δ / kind | KKT | violation | E |");
    for delta in [1e-2, 1e-6, 1e-9, 1e-12] {
        let rows: Vec<[f64; 2]> = (0..8)
            .map(|i| {
                let x = i as f64;
                [x, if i == 4 { delta } else { 0.0 }]
            })
            .collect();
        let q = Points::from_rows(&rows).unwrap();
        for (name, c) in [
            ("interpolate", Constraint::Interpolate),
            ("smoothing", Constraint::Smoothing(vec![1.0; 8])),
        ] {
            let p = Problem::new(q.clone())
                .with_topology(Topology::Open)
                .with_constraint(c);
            let (label, row) = run(format!("δ = {delta:e} {name}"), &p);
            let (kkt, viol, e) = row.unwrap_or_else(|e| panic!("{label}: {e}"));
            assert!(kkt <= KKT_GOOD, "{label}: kkt {kkt:e}");
            assert!(viol <= 1e-12, "{label}: violation {viol:e}");
            assert!(e <= 10.0 * delta * delta, "{label}: E {e:e}");
        }
    }
}

/// Nearly coincident consecutive points (distance δ against spans of ~1): exactly coincident
/// points are refused ([`Error::CoincidentPoints`]); every result returned is certified to
/// [`KKT_GOOD`] (measured ≤ 1.4e-15 down to δ = 1e-12); below δ = 1e-8 knot updates may meet
/// coincident refined vertices ([`Error::DegenerateRefinedSpan`]) or the system may be
/// numerically singular ([`Error::Energy`]; [`Error::InvalidParameter`] naming
/// `knot_iterations` after a knot update, or the smoothing weights) — typed errors, never NaN.
#[test]
fn nearly_coincident_points() {
    eprintln!("| coincident, gap δ / kind | KKT | violation | E |");
    for delta in [1e-4, 1e-8, 1e-12, 0.0] {
        let mut rows: Vec<[f64; 2]> = (0..7)
            .map(|i| {
                let th = 2.0 * std::f64::consts::PI * i as f64 / 7.0;
                [2.0 * th.cos(), th.sin()]
            })
            .collect();
        rows.insert(3, [rows[2][0] + delta, rows[2][1]]);
        let q = Points::from_rows(&rows).unwrap();
        for (name, c) in kinds(&q, 1.0) {
            let p = Problem::new(q.clone()).with_constraint(c);
            let (label, row) = run(format!("δ = {delta:e} {name}"), &p);
            match row {
                Ok((kkt, viol, _)) => {
                    assert!(delta > 0.0, "{label}: coincident points accepted");
                    assert!(kkt <= KKT_GOOD, "{label}: kkt {kkt:e}");
                    assert!(viol <= KKT_GOOD, "{label}: violation {viol:e}");
                }
                Err(e) => {
                    if delta == 0.0 {
                        assert!(
                            matches!(e, Error::CoincidentPoints { index: 2, next: 3 }),
                            "{label}: {e}"
                        );
                    } else {
                        assert!(delta < 1e-8, "{label}: {e}");
                        assert!(
                            matches!(
                                e,
                                Error::DegenerateRefinedSpan { .. }
                                    | Error::Energy(_)
                                    | Error::InvalidParameter {
                                        field: "knot_iterations" | "weights",
                                        ..
                                    }
                                    | Error::NotConverged { .. }
                                    | Error::NotConvergedAfterUpdate { .. }
                            ),
                            "{label}: {e}"
                        );
                    }
                }
            }
        }
    }
}

/// Ball radii from 0 to larger than the data: radius 0 interpolates; radii larger than the
/// data's extent make the balls share a point, and the constant curve (E = 0) is returned.
#[test]
fn radii_from_zero_to_beyond_the_data() {
    eprintln!("| radius / extent | KKT | violation | E |");
    for closed in [true, false] {
        let q = data(8, closed, 1.0, 0.0);
        let l = extent(&q);
        let topo = if closed {
            Topology::Closed
        } else {
            Topology::Open
        };
        let interp = Problem::new(q.clone()).with_topology(topo).solve().unwrap();
        let mut rows = Vec::new();
        for rel in [0.0, 1e-12, 1e-9, 1e-6, 1e-4, 1e-2, 0.3, 1.0, 10.0] {
            let p = Problem::new(q.clone())
                .with_topology(topo)
                .with_constraint(Constraint::Balls(vec![rel * l; 8]));
            let (label, row) = run(
                format!("{} ε/L = {rel:e}", if closed { "closed" } else { "open" }),
                &p,
            );
            rows.push((rel, label, row));
        }
        for (rel, label, row) in rows {
            // Radii ≤ 1e-10·L may certify only to ~1e-6…1e-5 (finding 8): then the exact solver
            // refuses with NotConverged (on the first knots or after an update) and the best
            // residual instead of returning the result.
            let (kkt, viol, e) = match row {
                Ok(r) => r,
                Err(
                    Error::NotConverged { residual, .. }
                    | Error::NotConvergedAfterUpdate { residual, .. },
                ) if rel <= 1e-10 => {
                    assert!(
                        residual > refine::EXACT_ACCEPT_KKT,
                        "{label}: refused at {residual:e}"
                    );
                    continue;
                }
                Err(e) => panic!("{label}: {e}"),
            };
            assert!(viol <= 1e-9, "{label}: violation {viol:e}");
            assert!(
                e <= interp.energy * (1.0 + 1e-9),
                "{label}: E {e} above interpolation's"
            );
            if rel >= 10.0 {
                // The balls share a point: the constant curve, E = 0 exactly.
                assert!(e.abs() <= 1e-12 * interp.energy, "{label}: E {e}");
            } else if e <= 1e-12 * interp.energy {
                // E* = 0 (a line or a point meets every ball): with multipliers projected onto
                // complementarity the certificate stays meaningful (ROBUSTNESS.md, finding 2).
                assert!(kkt <= KKT_GOOD, "{label}: E* = 0, kkt {kkt:e}");
            } else if rel == 0.0 || rel >= RADIUS_CERTIFIED {
                assert!(kkt <= KKT_GOOD, "{label}: kkt {kkt:e}");
            } else {
                // Tiny radii (ε = 1e-12 L): the certificate's complementarity w·slack with
                // w ~ force/ε reads 1.1e-7 (closed) / 7.7e-8 (open) although E equals
                // interpolation's (ROBUSTNESS.md, finding 8): NOT certified to KKT_GOOD; only
                // the level above which `Problem::solve` refuses is guaranteed.
                assert!(kkt <= refine::EXACT_ACCEPT_KKT, "{label}: kkt {kkt:e}");
            }
        }
    }
}

/// A radius far beyond the data is a point left free ("don't care"): 1e10·L and 1e300 solve as
/// a radius of 100·L does, where the optimum leaves that ball inactive — so both problems have
/// the same optimum, reached on different numerical paths (the solvers see the huge radius
/// capped at 100 times the largest distance from `points[0]`, `FAR_BOUND` in
/// `constraint/mod.rs`, 1.5 to 2 times this L on these data, so the reference radius is not; the
/// certificate sees the radii as given).
/// Before the cap a closed curve with one ball of 1e10·L stopped without a certificate, and
/// radii whose square overflows made the certificate NaN. Radii too small to represent against
/// the data are refused naming the radius, not an internal start.
#[test]
fn free_points_by_huge_radii_solve_as_with_moderate_ones() {
    for (name, q) in [
        ("ellipse", data(8, true, 1.0, 0.0)),
        ("noisy star", noisy_star(40)),
    ] {
        for topo in [Topology::Closed, Topology::Open] {
            let l = extent(&q);
            let n = q.len();
            let free = [2, n / 2 + 1];
            let balls = |big: f64| {
                let r: Vec<f64> = (0..n)
                    .map(|i| if free.contains(&i) { big } else { 0.02 * l })
                    .collect();
                Problem::new(q.clone())
                    .with_topology(topo)
                    .with_constraint(Constraint::Balls(r))
            };
            let label = format!("{name} {topo:?}");
            let reference = balls(100.0 * l).solve().unwrap();
            assert!(reference.kkt_residual <= KKT_GOOD, "{label}");
            for &i in &free {
                let gap = dist(reference.points.point(reference.data_vertex[i]), q.point(i));
                assert!(
                    gap < 50.0 * l,
                    "{label}: the reference's ball {i} is not inactive"
                );
            }
            for big in [1e10 * l, 1e300] {
                let r = balls(big)
                    .solve()
                    .unwrap_or_else(|e| panic!("{label}, radius {big:e}: {e}"));
                assert_same_optimum(&format!("{label}, {big:e}"), &r, reference.energy);
            }
            // Every ball huge: a common point, the constant curve, and a finite certificate.
            let all = Problem::new(q.clone())
                .with_topology(topo)
                .with_constraint(Constraint::Balls(vec![1e300; n]))
                .solve()
                .unwrap();
            assert!(all.energy.abs() <= 0.0, "{label}: E {}", all.energy);
            assert!(
                all.kkt_residual <= KKT_GOOD,
                "{label}: {}",
                all.kkt_residual
            );
        }
    }
    // Radii of 1e-260 on data of size 1e-100: refused (their multipliers, force over radius,
    // overflow), not as the start of the interior-point method (`Error::Conic`, "start.s[0] is
    // invalid").
    let q = data(8, true, 1e-100, 0.0);
    let mut r = vec![1e-260; 8];
    r[3] = 1e-101;
    match Problem::new(q)
        .with_topology(Topology::Closed)
        .with_constraint(Constraint::Balls(r))
        .solve()
    {
        Err(Error::Conic(e)) => panic!("an internal error: {e}"),
        Err(_) => {}
        Ok(r) => assert!(r.kkt_residual <= refine::EXACT_ACCEPT_KKT),
    }
}

/// Half-space offsets far beyond the data are open sides ("no bound", 1e20 as other solvers
/// spell infinity): a box with two such sides, and a point whose one half-space is 1e300 away,
/// solve as the same problem with those sides removed (an empty set leaves a point free): the
/// same optimum reached through other constraints. Before the solvers saw such offsets capped
/// (`FAR_BOUND` in `constraint/mod.rs`) they stopped uncertified from 1e20 and were refused as
/// "start.s[0] is invalid" from 1e200.
#[test]
fn open_sides_of_boxes_solve_as_removed_sides() {
    for (name, q) in [
        ("ellipse", data(8, true, 1.0, 0.0)),
        ("noisy star", noisy_star(40)),
    ] {
        let l = extent(&q);
        let Constraint::HalfSpaces(sets) = boxes(&q, 0.02 * l) else {
            unreachable!()
        };
        for topo in [Topology::Closed, Topology::Open] {
            let label = format!("{name} {topo:?}");
            let solve = |sets: Vec<Vec<HalfSpace>>| {
                Problem::new(q.clone())
                    .with_topology(topo)
                    .with_constraint(Constraint::HalfSpaces(sets))
                    .solve()
            };
            let (a, b) = (2, q.len() / 2 + 1);
            let mut removed = sets.clone();
            removed[a].truncate(2); // the box's y sides gone
            removed[b].clear();
            let reference = solve(removed).unwrap_or_else(|e| panic!("{label}: {e}"));
            assert!(reference.kkt_residual <= KKT_GOOD, "{label}");
            for far in [1e20, 1e300] {
                let mut open = sets.clone();
                open[a][2].offset = far;
                open[a][3].offset = far;
                open[b] = vec![HalfSpace {
                    normal: vec![1.0, 1.0],
                    offset: far,
                }];
                let r = solve(open).unwrap_or_else(|e| panic!("{label}, {far:e}: {e}"));
                assert_same_optimum(&format!("{label}, {far:e}"), &r, reference.energy);
            }
        }
    }
}

/// Derivative radii far beyond the data's slopes leave the derivative free: tension at every
/// point on top of balls, a tangent ball and near-clamped ends of radius 1e10 or 1e300 solve as
/// the problem without them. Before the solvers saw such radii capped, and then left them to the
/// certificate (`split_far_derivative_set` in `constraint/mod.rs`), tension of 1e10 with balls
/// was refused uncertified with the advice to take "a larger radius", and 1e300 was refused as
/// a singular system naming `points`.
#[test]
fn derivative_radii_far_beyond_the_slopes_leave_derivatives_free() {
    let q = noisy_star(30);
    let (l, n) = (extent(&q), q.len());
    let balls = Constraint::Balls(vec![0.02 * l; n]);
    for topo in [Topology::Closed, Topology::Open] {
        let base = || Problem::new(q.clone()).with_topology(topo);
        let solved = |p: Problem, label: &str| p.solve().unwrap_or_else(|e| panic!("{label}: {e}"));
        let certified = |p: Problem, label: &str| {
            let r = solved(p, label);
            assert!(r.kkt_residual <= KKT_GOOD, "{label}: {}", r.kkt_residual);
            r.energy
        };
        let with_balls = certified(
            base().with_constraint(balls.clone()),
            &format!("{topo:?} balls"),
        );
        let natural = certified(base(), &format!("{topo:?} natural"));
        for big in [1e10, 1e300] {
            let label = format!("{topo:?} radius {big:e}");
            let tension = vec![Some(Tangent::Tension { radius: big }); n];
            let r = solved(
                base().with_constraint(balls.clone()).with_tangents(tension),
                &label,
            );
            assert_same_optimum(&label, &r, with_balls);
            let mut one = vec![None; n];
            one[5] = Some(Tangent::Ball {
                center: vec![1.0, 0.0],
                radius: big,
            });
            assert_same_optimum(&label, &solved(base().with_tangents(one), &label), natural);
            if topo == Topology::Open {
                let ends = Boundary::NearClamped {
                    start: vec![1.0, 0.0],
                    end: vec![0.0, 1.0],
                    radius: big,
                };
                assert_same_optimum(&label, &solved(base().with_boundary(ends), &label), natural);
            }
        }
    }
}

/// Tangent half-spaces whose offsets lie far beyond the data's slopes leave the derivative free
/// on that side: at every third point, a side of offset 1e10, 1e50 or 1e300 beside an active
/// side solves as the active side alone, and a box of far sides alone as no tangent constraint.
/// Before the solvers left such offsets to the certificate (`split_far_derivative_set` in
/// `constraint/mod.rs`) 1e50 was refused as not converged (best residual 1) and 1e200 as a
/// singular system naming `points`.
#[test]
fn tangent_halfspaces_far_beyond_the_slopes_leave_derivatives_free() {
    let q = noisy_star(30);
    let n = q.len();
    let side = |normal: [f64; 2], offset: f64| HalfSpace {
        normal: normal.to_vec(),
        offset,
    };
    let tangents = |sides: &dyn Fn() -> Vec<HalfSpace>| -> Vec<Option<Tangent>> {
        (0..n)
            .map(|i| (i % 3 == 0).then(|| Tangent::HalfSpaces(sides())))
            .collect()
    };
    // Df · (0.3, 1) ≤ 0.2: active on the star's arms that run upward.
    let active = || vec![side([0.3, 1.0], 0.2)];
    for topo in [Topology::Closed, Topology::Open] {
        let base = || Problem::new(q.clone()).with_topology(topo);
        let solved = |p: Problem, label: &str| p.solve().unwrap_or_else(|e| panic!("{label}: {e}"));
        let natural = solved(base(), &format!("{topo:?} natural"));
        let pressed = solved(
            base().with_tangents(tangents(&active)),
            &format!("{topo:?} active side"),
        );
        assert!(pressed.kkt_residual <= KKT_GOOD, "{}", pressed.kkt_residual);
        // The active side changes the curve: the comparison below can tell the two apart.
        assert!(pressed.energy > natural.energy * (1.0 + 1e-6));
        for far in [1e10, 1e50, 1e300] {
            let label = format!("{topo:?} offset {far:e}");
            let beside = || {
                let mut s = active();
                s.push(side([1.0, -0.2], far));
                s
            };
            let r = solved(base().with_tangents(tangents(&beside)), &label);
            assert_same_optimum(&label, &r, pressed.energy);
            let boxed = || {
                vec![
                    side([1.0, 0.0], far),
                    side([0.0, 1.0], far),
                    side([-1.0, 0.0], far),
                    side([0.0, -1.0], far),
                ]
            };
            let r = solved(base().with_tangents(tangents(&boxed)), &label);
            assert_same_optimum(&label, &r, natural.energy);
        }
    }
}

/// Asserts `a` = `b` to 1e-9 of `scale` (`label` and `what` say where, for the message).
fn assert_close(label: &str, what: &str, a: f64, b: f64, scale: f64) {
    assert!(
        (a - b).abs() <= 1e-9 * scale,
        "{label} {what}: {a:e} vs {b:e}"
    );
}

/// Asserts that `r`, solved at scale `s` on centripetal knots, is certified and is `one` (the
/// scale-1 solve, data of extent `l`) scaled: points ∝ s to 1e-9 of `l`, E ∝ s^{1/2} to 1e-9.
fn assert_scaled(label: &str, r: &Refinement, one: &Refinement, s: f64, l: f64) {
    assert!(r.kkt_residual <= KKT_GOOD, "{label}: {}", r.kkt_residual);
    for (a, b) in r.points.coords().iter().zip(one.points.coords()) {
        assert_close(label, "points", a / s, *b, l);
    }
    assert_close(label, "energy", r.energy / s.sqrt(), one.energy, one.energy);
}

/// Interpolation and smoothing on chordal knots at the ends of the extent range (1e±140, spans
/// ~ the extent) give the solution at scale 1, scaled: points ∝ s, E ∝ s^{-1} (chordal: E scales
/// as s^{2−3e}), certified. Solved where they were, the rows of H (~1/h³ on spans of 1e−141)
/// overflowed: at 1e−140 the interpolant came back with 1800 times the optimal energy and a
/// certificate of 0 (ROBUSTNESS.md item 39); both are now rescaled by powers of two, and a
/// certificate whose force scale is not finite is NaN, never accepted.
#[test]
fn chordal_interpolation_and_smoothing_at_the_ends_of_the_extent_range_scale_exactly() {
    let base = noisy_star(30);
    let n = base.len();
    let l = extent(&base);
    for (topo, smoothing, updates) in [Topology::Closed, Topology::Open]
        .into_iter()
        .flat_map(|t| [(t, false), (t, true)])
        .flat_map(|(t, s)| [(t, s, 0), (t, s, 3)])
    {
        let solve = |s: f64| {
            let q = Points::new(2, base.coords().iter().map(|x| x * s).collect()).unwrap();
            let mut p = Problem::new(q)
                .with_topology(topo)
                .with_k(5)
                .with_knot_iterations(updates)
                .with_parametrization(Parametrization::Chordal);
            if smoothing {
                // Weights scale by s^{-3} (chordal) to keep the problem the same one.
                p = p.with_constraint(Constraint::Smoothing(vec![10.0 / (s * s * s); n]));
            }
            p.solve().unwrap_or_else(|e| {
                panic!("{topo:?} smoothing {smoothing} updates {updates} scale {s:e}: {e}")
            })
        };
        let one = solve(1.0);
        // (Smoothing's weights 10 s^{-3} are doubles only up to |log10 s| ≈ 102.)
        let scales: &[f64] = if smoothing {
            &[1e-100, 1e100]
        } else {
            &[1e-140, 1e-100, 1e100, 1e140]
        };
        for &s in scales {
            let label = format!("{topo:?} smoothing {smoothing} updates {updates} scale {s:e}");
            let r = solve(s);
            assert!(r.kkt_residual <= KKT_GOOD, "{label}: {}", r.kkt_residual);
            for (a, b) in r.points.coords().iter().zip(one.points.coords()) {
                assert_close(&label, "points", a / s, *b, l);
            }
            assert_close(&label, "energy", r.energy * s, one.energy, one.energy);
        }
    }
}

/// Balls at the ends of the extent range (1e±100, 1e±140) give the solution at scale 1,
/// scaled: points ∝ s, knots ∝ s^{1/2} (centripetal), E ∝ s^{1/2}, ball weights (force over
/// radius, ∝ 1/h³) ∝ s^{−3/2}, the reactions of radius-0 points ∝ s^{−1/2} — each compared
/// with the scale-1 solve to 1e-9. Before the solve rescaled such problems by powers of two
/// (`run_rescaled` in `solve.rs`) the interior-point method stopped after one or two iterations
/// from 1e±80 (half-spaces, rescaled the same way since, next test).
#[test]
fn balls_at_the_ends_of_the_extent_range_scale_exactly() {
    let base = noisy_star(40);
    let n = base.len();
    let radii = |s: f64| -> Vec<f64> {
        (0..n)
            .map(|i| match i % 5 {
                0 => 0.0,
                1 => 0.3 * s,
                _ => 1e-3 * s,
            })
            .collect()
    };
    for topo in [Topology::Closed, Topology::Open] {
        let solve = |s: f64| {
            let q = Points::new(2, base.coords().iter().map(|x| x * s).collect()).unwrap();
            Problem::new(q)
                .with_topology(topo)
                .with_constraint(Constraint::Balls(radii(s)))
                .solve()
                .unwrap_or_else(|e| panic!("{topo:?} scale {s:e}: {e}"))
        };
        let one = solve(1.0);
        let l = extent(&base);
        for s in [1e-140, 1e-100, 1e100, 1e140] {
            let label = format!("{topo:?} scale {s:e}");
            let r = solve(s);
            assert_scaled(&label, &r, &one, s, l);
            let span = one.knots.values().last().unwrap() - one.knots.values()[0];
            for (a, b) in r.knots.values().iter().zip(one.knots.values()) {
                assert_close(&label, "knots", a / s.sqrt(), *b, span);
            }
            for (i, (a, b)) in r.multipliers.iter().zip(one.multipliers.iter()).enumerate() {
                // (rows: [w] for a ball, the d reaction components at radius 0)
                let k = if i % 5 == 0 { s.sqrt() } else { s * s.sqrt() };
                let size = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let big = one
                    .multipliers
                    .iter()
                    .filter(|m| m.len() == b.len())
                    .flatten()
                    .fold(0.0f64, |m, x| m.max(x.abs()));
                for (x, y) in a.iter().zip(b) {
                    assert_close(&label, "multipliers", x * k, *y, big.max(size));
                }
            }
        }
    }
}

/// Boxes of half-spaces at the ends of the extent range, and far from the origin, give the
/// solution at scale 1, scaled: points ∝ s, E ∝ s^{1/2} (centripetal), the net forces of the
/// multipliers (per unit normal, ∝ s/h³) ∝ s^{−1/2}, each compared with the scale-1 solve to 1e-9. Every
/// fifth box has width 0 (the point pinned). Before the solve rescaled half-spaces as it does
/// balls (`run_rescaled`), the interior-point method stopped without converging from an extent
/// of ~1e30; the fuzz find of ROBUSTNESS.md item 34 (three points in boxes of width 0 at 2.5e37,
/// d = 3, closed, k = 1) was refused translated and solved at the origin.
#[test]
fn half_spaces_at_the_ends_of_the_extent_range_scale_exactly() {
    let base = noisy_star(40);
    let width = |i: usize| if i.is_multiple_of(5) { 0.0 } else { 0.1 };
    for topo in [Topology::Closed, Topology::Open] {
        let solve = |s: f64| {
            let q = Points::new(2, base.coords().iter().map(|x| x * s).collect()).unwrap();
            let boxes = kersey_support::cases::axis_boxes(&q, |i| width(i) * s);
            Problem::new(q)
                .with_topology(topo)
                .with_constraint(boxes)
                .solve()
                .unwrap_or_else(|e| panic!("{topo:?} scale {s:e}: {e}"))
        };
        let one = solve(1.0);
        let l = extent(&base);
        for s in [1e-140, 1e-100, 1e30, 1e37, 1e100, 1e140] {
            let label = format!("{topo:?} scale {s:e}");
            let r = solve(s);
            assert_scaled(&label, &r, &one, s, l);
            // (A pinned point's faces share its force in no unique way: compared is the net
            // force Σ_j w_j n_j, per coordinate the + face's multiplier less the − face's.)
            let net = |r: &Refinement| -> Vec<f64> {
                r.multipliers
                    .values()
                    .chunks_exact(2)
                    .map(|w| w[0] - w[1])
                    .collect()
            };
            let (got, want) = (net(&r), net(&one));
            let big = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (a, b) in got.iter().zip(&want) {
                assert_close(&label, "net forces", a * s.sqrt(), *b, big);
            }
        }
    }
    // The fuzz find, at the origin and translated by 2.7e37 (its data as the fuzzer gave them).
    let fuzz = |shift: f64| {
        let rows = [
            [-2e36, -2e36, 9e36],
            [-1e36, -1e36, -1e36],
            [-1e36, -3e36, -1e36],
        ];
        let q = Points::new(3, rows.iter().flatten().map(|x| x + shift).collect()).unwrap();
        let pinned = kersey_support::cases::axis_boxes(&q, |_| 0.0);
        Problem::new(q)
            .with_topology(Topology::Closed)
            .with_k(1)
            .with_knot_iterations(0)
            .with_parametrization(Parametrization::Uniform)
            .with_constraint(pinned)
            .solve()
            .unwrap_or_else(|e| panic!("fuzz find shifted by {shift:e}: {e}"))
    };
    let (at_origin, moved) = (fuzz(0.0), fuzz(2.7e37));
    assert!(moved.kkt_residual <= KKT_GOOD, "{}", moved.kkt_residual);
    for (a, b) in moved.points.coords().iter().zip(at_origin.points.coords()) {
        assert!(
            (a - 2.7e37 - b).abs() <= 1e-9 * 1e37,
            "{a:e} vs {b:e} + 2.7e37"
        );
    }
    let rel = (moved.energy - at_origin.energy).abs() / at_origin.energy;
    assert!(rel <= 1e-9, "E {} vs {}", moved.energy, at_origin.energy);
}

/// Derivative constraints — tension at every third point (not the ends) over balls (some of radius 0), wedges,
/// and for the open curve near-clamped ends — at scales from 1e−80 to 1e80 give the solution at
/// scale 1, scaled: points ∝ s, E ∝ s^{1/2} (centripetal knots ∝ s^{1/2}, derivatives ∝ s^{1/2}),
/// compared to 1e-9. Before `run_rescaled` took derivative constraints, these were refused from
/// 1e±15 on, and at 1e80 the wedges were certified (KKT 3e-32) at 1e73 times the optimal energy
/// (ROBUSTNESS.md item 35).
#[test]
fn derivative_constraints_at_extreme_scales_scale_exactly() {
    let base = noisy_star(40);
    let n = base.len();
    let chord = extent(&base) / n as f64;
    for topo in [Topology::Closed, Topology::Open] {
        for wedge in [false, true] {
            let solve = |s: f64| {
                let q = Points::new(2, base.coords().iter().map(|x| x * s).collect()).unwrap();
                let slope = chord.sqrt() * s.sqrt();
                let tangents = (0..n)
                    .map(|i| {
                        (i % 3 == 1).then(|| {
                            if wedge {
                                Tangent::Wedge {
                                    direction: vec![1.0, 0.5],
                                    half_angle: 0.3,
                                }
                            } else {
                                Tangent::Tension {
                                    radius: 0.5 * slope,
                                }
                            }
                        })
                    })
                    .collect();
                let radii = (0..n)
                    .map(|i| {
                        if i.is_multiple_of(4) {
                            0.0
                        } else {
                            0.2 * chord * s
                        }
                    })
                    .collect();
                let mut p = Problem::new(q)
                    .with_topology(topo)
                    .with_constraint(Constraint::Balls(radii))
                    .with_tangents(tangents);
                if topo == Topology::Open {
                    p = p.with_boundary(Boundary::NearClamped {
                        start: vec![0.0, 3.0 * slope],
                        end: vec![-3.0 * slope, 0.0],
                        radius: slope,
                    });
                }
                p.solve()
                    .unwrap_or_else(|e| panic!("{topo:?} wedge {wedge} scale {s:e}: {e}"))
            };
            let one = solve(1.0);
            let l = extent(&base);
            for s in [1e-80, 1e-15, 1e15, 1e80] {
                let label = format!("{topo:?} wedge {wedge} scale {s:e}");
                assert_scaled(&label, &solve(s), &one, s, l);
            }
        }
    }
}

/// Iterations are bounded: the interior-point method with an absurdly low iteration limit
/// returns [`Error::NotConverged`] carrying the best residual it reached (finite, positive).
#[test]
fn iteration_limit_gives_not_converged_with_the_best_residual() {
    let q = data(8, true, 1.0, 0.0);
    let knots = divdiff::parametrize(&q, Topology::Closed, Parametrization::Centripetal).unwrap();
    let mut cp = ConicProblem::new(&knots, 2).unwrap();
    for i in 0..8 {
        cp.add_constraint(
            &[(i, 1.0)],
            ConvexSet::Ball {
                center: q.point(i).to_vec(),
                radius: 0.2,
            },
        )
        .unwrap();
    }
    let full = cp.solve(&ConicOptions::default()).unwrap();
    let accept = ConicOptions::default().accept;
    assert!(full.kkt.total <= accept);
    for limit in [0, 1, 2] {
        let opts = ConicOptions::default().with_max_iterations(limit);
        match cp.solve(&opts) {
            Err(Error::NotConverged {
                iterations,
                residual,
                ..
            }) => {
                eprintln!(
                    "limit {limit}: NotConverged after {iterations}, best residual {residual:e}"
                );
                assert!(iterations <= limit.max(1));
                assert!(residual.is_finite() && residual > accept);
            }
            other => panic!("limit {limit}: expected NotConverged, got {other:?}"),
        }
    }
}

/// Interpolation of 10⁵ noisy points at k = 7 (N = 8·10⁵ vertices) is certified: the split's
/// sub-spans are equal to the last bit (`algorithm::split_knots`), so the closed form is the
/// optimum on the knots it reports. With the sub-knots computed as (1 − s)a + s·b their
/// rounding (relative ε·N in the spans) left free vertices 5·10⁻⁹ out of balance and the solve
/// was refused.
#[test]
#[allow(clippy::float_cmp)] // equal to the last bit is the claim
fn large_noisy_interpolation_is_certified() {
    let problem = Problem::new(noisy_star(100_000))
        .with_topology(Topology::Closed)
        .with_parametrization(Parametrization::Centripetal)
        .with_k(7)
        .with_knot_iterations(0);
    let r = problem.solve().expect("interpolation is certified");
    assert!(r.kkt_residual <= KKT_GOOD, "{}", r.kkt_residual);
    let t = r.knots.values();
    for span in t.chunks_exact(8).take(1000) {
        let h = span[1] - span[0];
        assert!(span.windows(2).all(|w| w[1] - w[0] == h), "{span:?}");
    }
}

/// A heavily smoothed 1-D curve (weights 1e-6 on a sine with a trend and ±0.015 of
/// deterministic noise, n = 2000) almost stops at a turning point: the knot update's span
/// |p_{j+1} − p_j|^e there is ~1e-4 of the others. Until the linear solves refined their answer
/// with a residual in difference form (`linear::Factored::refine`), the next solve's rounding
/// kept it from its certificate and the knot updates were refused naming `knot_iterations`
/// (ROBUSTNESS.md §4, 14, and item 27); it is now solved and certified, on knots whose spans
/// differ by a factor of about 500 (centripetal: the square roots of those distances).
#[test]
fn knot_updates_that_flatten_the_spans_are_solved_after_refinement() {
    let n = 2000;
    let rows: Vec<[f64; 1]> = (0..n)
        .map(|i| {
            let s = 10.0 * i as f64 / (n - 1) as f64;
            let noise = 0.03 * ((i as f64 * 0.618_033_988_749_894_9) % 1.0 - 0.5);
            [s.sin() + 0.05 * s + noise]
        })
        .collect();
    let q = Points::from_rows(&rows).unwrap();
    let p = Problem::new(q)
        .with_topology(Topology::Open)
        .with_k(3)
        .with_constraint(Constraint::Smoothing(vec![1e-6; n]));
    let r = p
        .clone()
        .with_knot_iterations(0)
        .solve()
        .expect("solves on the data's knots");
    assert!(r.kkt_residual <= KKT_GOOD, "{}", r.kkt_residual);
    let r = p
        .with_knot_iterations(3)
        .solve()
        .expect("solves after refinement");
    assert!(r.kkt_residual <= KKT_GOOD, "{}", r.kkt_residual);
    assert_eq!(r.iterations.knot_updates, 3);
    let h: Vec<f64> = r.knots.values().windows(2).map(|w| w[1] - w[0]).collect();
    let (lo, hi) = h
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, u), &x| (l.min(x), u.max(x)));
    assert!(
        lo < 1e-2 * hi,
        "spans {lo:e} … {hi:e}: not the flattened case"
    );
}

/// Smoothing weights too small against the stiffness of very unequal spans (a closed ellipse
/// whose angular steps grow geometrically by 10⁴ over n = 5000 points, every weight 1e-6): H + W
/// is singular to rounding (ROBUSTNESS.md §4, 5). The refusal names the weights, and the advice
/// holds: weights of 1e-4 solve the same points.
#[test]
fn smoothing_weights_below_the_stiffness_name_the_weights() {
    let n = 5000;
    let steps: Vec<f64> = (0..n)
        .map(|i| 1e4f64.powf(i as f64 / (n - 1) as f64))
        .collect();
    let total: f64 = steps[1..].iter().sum::<f64>() + steps[n - 1];
    let mut th = 0.0;
    let rows: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            if i > 0 {
                th += 2.0 * std::f64::consts::PI * steps[i] / total;
            }
            [th.cos(), 0.6 * th.sin()]
        })
        .collect();
    let q = Points::from_rows(&rows).unwrap();
    let p = |w: f64| {
        Problem::new(q.clone())
            .with_topology(Topology::Closed)
            .with_k(3)
            .with_knot_iterations(0)
            .with_constraint(Constraint::Smoothing(vec![w; n]))
    };
    match p(1e-6).solve() {
        Err(Error::InvalidParameter { field, value, .. }) => {
            assert_eq!((field, value), ("weights", 1e-6));
        }
        other => panic!("expected a refusal naming the weights, got {other:?}"),
    }
    let r = p(1e-4).solve().expect("larger weights solve");
    assert!(r.kkt_residual <= KKT_GOOD, "{}", r.kkt_residual);
}

/// A far derivative bound that the optimum would cross is never answered crossed: with the
/// start clamped to a derivative of 1e12, the curve without tension has |Df| ≈ 2e11 at the
/// second data point; tension there of a tenth of that (far beyond the data's slopes, so the
/// solvers leave it to the certificate, which reads its violation) is refused, or answered
/// within it.
#[test]
fn a_far_derivative_bound_the_optimum_crosses_is_never_answered_crossed() {
    let q = Points::new(
        2,
        (0..8).flat_map(|i| [i as f64, (i as f64).sin()]).collect(),
    )
    .unwrap();
    let ends = Boundary::Clamped {
        start: vec![1e12, 0.0],
        end: vec![1.0, 0.0],
    };
    let base = || {
        Problem::new(q.clone())
            .with_topology(Topology::Open)
            .with_boundary(ends.clone())
            .with_knot_iterations(0)
    };
    let df = |r: &Refinement, i: usize| {
        let v = r.data_vertex[i];
        let st = divdiff::derivative_stencil(&r.knots, v, refine::DerivativeRule::Bessel).unwrap();
        let mut y = [0.0; 2];
        for (u, c) in st {
            for (yk, pk) in y.iter_mut().zip(r.points.point(u)) {
                *yk += c * pk;
            }
        }
        (y[0] * y[0] + y[1] * y[1]).sqrt()
    };
    let free = base().solve().unwrap();
    let crossed = df(&free, 1);
    assert!(crossed > 1e11, "|Df| = {crossed:e} without the tension");
    let mut tension = vec![None; q.len()];
    tension[1] = Some(Tangent::Tension {
        radius: 0.1 * crossed,
    });
    match base().with_tangents(tension).solve() {
        Err(_) => {}
        Ok(r) => {
            assert!(r.kkt_residual <= KKT_GOOD, "{}", r.kkt_residual);
            assert!(
                df(&r, 1) <= 0.1 * crossed * (1.0 + 1e-9),
                "answered with |Df| = {:e} beyond the tension {:e}",
                df(&r, 1),
                0.1 * crossed
            );
        }
    }
}
