//! Tests of the working set: the condensed energy and backends against the full-vertex
//! ones, the rounds against one round on everything, and the options that grow W.

#![allow(clippy::needless_range_loop)]

use divdiff::{Knots, Points, Topology};
use proptest::prelude::*;

use super::super::condensed::{Face, PointSet};
use super::super::round_polish::POLISH_ROUNDS;
use super::{solve, solve_from, turns_past_radii, Setting, WorkingSetOptions, WorkingSetSolution};
use crate::certify::{certify, Certificate};
use crate::conic_problem::{ConicProblem, ConvexSet};
use crate::fast::{interpolate_condensed as interpolate, Condensation};
use crate::operator::Stencil;
use crate::{Constraint, HalfSpace};

/// The exact acceptance level of the refinement (the independent certificate).
const EXACT: f64 = 1e-9;

/// Energies below this times the interpolation energy count as E* = 0.
const ZERO_ENERGY_RTOL: f64 = 1e-12;

/// Knots with spacings `h` (closed: one span per vertex; open: one fewer).
fn knots(h: &[f64], topo: Topology) -> Knots {
    let mut t = vec![0.0];
    for x in h {
        t.push(t.last().unwrap() + x);
    }
    Knots::new(topo, t).unwrap()
}

/// (knots, n, stride, data, dimension) with n data points, k free vertices per span.
fn case() -> impl Strategy<Value = (Knots, usize, usize, Vec<f64>, usize)> {
    (3usize..9, 1usize..5, 1usize..4, any::<bool>()).prop_flat_map(|(n, k, d, closed)| {
        let m = k + 1;
        let topo = if closed {
            Topology::Closed
        } else {
            Topology::Open
        };
        let spans = if closed { m * n } else { m * (n - 1) };
        (
            proptest::collection::vec(0.2f64..2.0, spans),
            proptest::collection::vec(-1.0f64..1.0, n * d),
        )
            .prop_map(move |(h, y)| (knots(&h, topo), n, m, y, d))
    })
}

/// refine's independent certificate of a curve on `kn` with data `q` every `m` vertices
/// under `constraint` and the given multipliers: (its residual, the certificate).
fn judged(
    kn: &Knots,
    q: &Points,
    m: usize,
    constraint: &Constraint,
    p: &Points,
    mult: &[Vec<f64>],
) -> (f64, Certificate) {
    let dv: Vec<usize> = (0..q.len()).map(|i| i * m).collect();
    let (c, _) = certify(
        kn,
        p,
        q,
        &dv,
        &[constraint.kind()],
        Some(mult.to_vec()),
        &[],
        divdiff::DerivativeRule::Bessel,
        1e-7,
    );
    (c.kkt_residual, c)
}

/// The working-set method on `sets` (W started from every `step`-th point), certified
/// independently.
fn run(
    kn: &Knots,
    q: &Points,
    sets: &[Option<PointSet>],
    constraint: &Constraint,
    m: usize,
    step: usize,
    start: Option<&[bool]>,
) -> (Points, Certificate) {
    let (p, c, _) = run_with(
        kn,
        q,
        sets,
        constraint,
        m,
        step,
        start,
        &WorkingSetOptions::default(),
    );
    (p, c)
}

/// [`run`] with these options; also returns the method's iterations.
#[allow(clippy::too_many_arguments)]
fn run_with(
    kn: &Knots,
    q: &Points,
    sets: &[Option<PointSet>],
    constraint: &Constraint,
    m: usize,
    step: usize,
    start: Option<&[bool]>,
    options: &WorkingSetOptions,
) -> (Points, Certificate, usize) {
    let stencil = Stencil::new(kn);
    let mut judge = |p: &Points, mult: &[Vec<f64>]| judged(kn, q, m, constraint, p, mult);
    let setting = Setting {
        knots: kn,
        stencil: &stencil,
        q,
        sets,
        stride: m,
        conic: &conic::Options::default(),
    };
    let sol = solve_from(
        &setting,
        options,
        step,
        start,
        &mut judge,
        super::Aim {
            target: EXACT,
            accept: EXACT,
            strict: None,
        },
        None,
    )
    .unwrap();
    (sol.points, sol.certificate, sol.iterations)
}

fn ball_sets(radii: &[f64]) -> Vec<Option<PointSet>> {
    radii
        .iter()
        .map(|&r| {
            Some(if r == 0.0 {
                PointSet::Fixed
            } else {
                PointSet::Ball(r)
            })
        })
        .collect()
}

/// Data points `q` in balls (`sets`, `constraint`), attached every `m` vertices: what the tests
/// below solve on one set of knots or on several.
struct Balls {
    q: Points,
    m: usize,
    sets: Vec<Option<PointSet>>,
    constraint: Constraint,
}

impl Balls {
    fn new(q: Points, m: usize, radii: Vec<f64>) -> Self {
        Balls {
            q,
            m,
            sets: ball_sets(&radii),
            constraint: Constraint::Balls(radii),
        }
    }

    /// [`solve`] on the knots `kn` (from `warm` when given), certified independently
    /// ([`judged`]) and polished to `target`.
    fn solve_on(
        &self,
        kn: &Knots,
        options: &WorkingSetOptions,
        warm: Option<(&Points, &[Vec<f64>])>,
        target: f64,
    ) -> WorkingSetSolution<Certificate> {
        let stencil = Stencil::new(kn);
        let mut judge =
            |p: &Points, mult: &[Vec<f64>]| judged(kn, &self.q, self.m, &self.constraint, p, mult);
        let setting = Setting {
            knots: kn,
            stencil: &stencil,
            q: &self.q,
            sets: &self.sets,
            stride: self.m,
            conic: &conic::Options::default(),
        };
        let aim = super::Aim {
            target,
            accept: EXACT,
            strict: None,
        };
        solve(&setting, options, warm, &mut judge, aim, None).unwrap()
    }
}

/// A noisy closed star of 600 points (d = 2: radii alternating 1 and 1.35, jittered angles),
/// from the stream `seed`, on its centripetal split knots with m = 4, in balls of
/// (lo + span·u)·spacing (u uniform, the mean spacing).
fn noisy_star(seed: u64, lo: f64, span: f64) -> (Knots, Balls) {
    let (n, m, d) = (600, 4, 2);
    let mut uniform = crate::par::uniform_stream(seed);
    let mut y = Vec::with_capacity(n * d);
    for i in 0..n {
        let a = std::f64::consts::TAU * (i as f64 + 0.8 * uniform() - 0.4) / n as f64;
        let r = 1.0 + 0.35 * (i % 2) as f64 + 0.05 * (uniform() - 0.5);
        y.extend([r * a.cos(), r * a.sin()]);
    }
    let q = Points::new(d, y).unwrap();
    let u =
        divdiff::parametrize(&q, Topology::Closed, divdiff::Parametrization::Centripetal).unwrap();
    let kn = crate::algorithm::split_knots(&u, m - 1).unwrap();
    let spacing = (0..n)
        .map(|i| super::dot_dist(q.point(i), q.point((i + 1) % n)))
        .sum::<f64>()
        / n as f64;
    let radii: Vec<f64> = (0..n).map(|_| (lo + span * uniform()) * spacing).collect();
    (kn, Balls::new(q, m, radii))
}

/// The knot updates' tests' data: n points of a closed curve at the angles
/// t_i = 2π(i + 0.3 sin 1.7i)/n and radii `radius(i, t_i)`, in balls of 0.2–0.7 of the angular
/// spacing, every m = 4 vertices.
fn warm_curve(n: usize, radius: impl Fn(usize, f64) -> f64) -> Balls {
    let q = Points::new(
        2,
        (0..n)
            .flat_map(|i| {
                let t =
                    std::f64::consts::TAU * (i as f64 + 0.3 * (i as f64 * 1.7).sin()) / n as f64;
                let r = radius(i, t);
                [r * t.cos(), r * t.sin()]
            })
            .collect(),
    )
    .unwrap();
    let spacing = std::f64::consts::TAU / n as f64;
    let radii: Vec<f64> = (0..n)
        .map(|i| spacing * (0.2 + 0.5 * (0.5 + 0.5 * (i as f64 * 0.9).sin())))
        .collect();
    Balls::new(q, 4, radii)
}

/// Knots for [`warm_curve`]'s data: sub-spans of uneven data spans, each scaled by up to
/// ±`wobble` (as a knot iteration moves them).
fn wobbled_knots(b: &Balls, wobble: f64) -> Knots {
    let (n, m) = (b.q.len(), b.m);
    let mut t = vec![0.0];
    for j in 0..n * m {
        let h = (1.0 + 0.2 * ((j / m) as f64 * 0.7).cos()) / m as f64;
        t.push(t[j] + h * (1.0 + wobble * (j as f64 * 0.37).sin()));
    }
    Knots::new(Topology::Closed, t).unwrap()
}

/// The full-vertex optimum of the same problem (the reference backend).
fn full_vertex(kn: &Knots, q: &Points, m: usize, set: impl Fn(usize) -> ConvexSet) -> f64 {
    let mut cp = ConicProblem::new(kn, q.dim()).unwrap();
    for i in 0..q.len() {
        cp.add_constraint(&[(i * m, 1.0)], set(i)).unwrap();
    }
    cp.solve(&crate::ConicOptions::default()).unwrap().energy
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// E(y) = ½ (Ky)ᵀ T⁻¹ (Ky) is the energy (2.1) of the reconstructed curve (computed
    /// by `energy::energy`), that curve is stationary at its free vertices, and Kᵀs is
    /// its gradient (Hp) at the data vertices.
    #[test]
    fn condensed_energy_is_the_minimal_energy((kn, n, m, y, d) in case()) {
        let stencil = Stencil::new(&kn);
        let cond = Condensation::new(&kn, &stencil, n, m).unwrap();
        let q = Points::new(d, y.clone()).unwrap();
        let mut be = super::super::condensed::Condensed::new(
            &cond, &kn, y.clone(), vec![PointSet::Ball(1.0); n], d,
        ).unwrap();
        let mut g = vec![0.0; n * d];
        use conic::KktSystem;
        let e = be.gradient(&y, &mut g);
        let (p, _) = be.curve(&y, &stencil).unwrap();
        let e_full = energy::energy(&kn, &p).unwrap();
        prop_assert!((e - e_full).abs() <= 1e-11 * e_full.max(1.0), "{e} vs {e_full}");
        let (hp, _) = stencil.apply_h(&p);
        let scale = hp.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        for v in 0..p.len() {
            for c in 0..d {
                let want = if v % m == 0 { g[(v / m) * d + c] } else { 0.0 };
                prop_assert!((hp[v * d + c] - want).abs() <= 1e-10 * scale,
                    "vertex {v}: Hp {} vs {want}", hp[v * d + c]);
            }
        }
        let _ = q;
    }

    /// The condensed optimum of balls (radius-0 points mixed in) is certified at the exact
    /// level and agrees with the full-vertex backend's optimum (energies to 1e-8 relative).
    #[test]
    fn condensed_balls_match_the_full_vertex_backend(
        (kn, n, m, y, d) in case(),
        r in proptest::collection::vec(0.0f64..0.6, 9),
        fixed in proptest::collection::vec(any::<bool>(), 9),
    ) {
        let q = Points::new(d, y).unwrap();
        let radii: Vec<f64> = (0..n).map(|i| if fixed[i] { 0.0 } else { r[i] + 0.01 }).collect();
        prop_assume!(radii.iter().any(|&e| e > 0.0));
        // Valid problems have distinct consecutive data points (Problem::validate).
        prop_assume!((0..n - 1).all(|i| super::dot_dist(q.point(i), q.point(i + 1)) > 0.05));
        let c = Constraint::Balls(radii.clone());
        let (p, cert) = run(&kn, &q, &ball_sets(&radii), &c, m, 1, None);
        let stencil = Stencil::new(&kn);
        let e_interp = energy::energy(&kn, &interpolate(&kn, &stencil, &q, m).unwrap()).unwrap();
        let e_full = full_vertex(&kn, &q, m, |i| ConvexSet::Ball { center: q.point(i).to_vec(), radius: radii[i] });
        let e = energy::energy(&kn, &p).unwrap();
        if e_full <= ZERO_ENERGY_RTOL * e_interp {
            // E* = 0 (data within reach of a straight open curve): both at rounding level.
            prop_assert!(e <= ZERO_ENERGY_RTOL * e_interp, "condensed {e} vs full {e_full} (E* = 0)");
        } else {
            prop_assert!(cert.kkt_residual <= EXACT, "kkt {:e}", cert.kkt_residual);
            prop_assert!((e - e_full).abs() <= 1e-8 * e_full, "condensed {e} vs full {e_full}");
        }
    }

    /// Half-space sets (boxes with an oblique cut, some points without a set) condensed onto
    /// the data vertices agree with the full-vertex backend (energies to 1e-8) and certify.
    #[test]
    fn condensed_half_spaces_match_the_full_vertex_backend(
        (kn, n, m, y, d) in case(),
        w in proptest::collection::vec(0.02f64..0.4, 9),
        cut in proptest::collection::vec(-1.0f64..1.0, 9),
        empty in proptest::collection::vec(0.0f64..1.0, 9),
    ) {
        let q = Points::new(d, y).unwrap();
        prop_assume!((0..n - 1).all(|i| super::dot_dist(q.point(i), q.point(i + 1)) > 0.05));
        // A box of half-width w_i about q_i, shifted by a fraction of w along an oblique
        // normal (so q_i need not be inside), and no set at a few interior points.
        let closed = kn.is_closed();
        let sets: Vec<Vec<HalfSpace>> = (0..n).map(|i| {
            let interior = i > 0 && (closed || i + 1 < n);
            if interior && empty[i] < 0.2 {
                return Vec::new();
            }
            let qi = q.point(i);
            let mut hs = Vec::new();
            for c in 0..d {
                let mut e = vec![0.0; d];
                e[c] = 1.0;
                hs.push(HalfSpace { normal: e.clone(), offset: qi[c] + w[i] });
                e[c] = -2.0;
                hs.push(HalfSpace { normal: e, offset: -2.0 * (qi[c] - w[i]) });
            }
            let nrm: Vec<f64> = (0..d).map(|c| if c == 0 { 1.0 } else { cut[i] }).collect();
            let off = nrm.iter().zip(qi).map(|(a, b)| a * b).sum::<f64>() + 0.5 * cut[i] * w[i];
            hs.push(HalfSpace { normal: nrm, offset: off });
            hs
        }).collect();
        let psets: Vec<Option<PointSet>> = sets.iter().map(|s| (!s.is_empty()).then(|| {
            PointSet::Faces(s.iter().map(|h| {
                let norm = h.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                Face { normal: h.normal.iter().map(|x| x / norm).collect(), offset: h.offset / norm, norm }
            }).collect())
        })).collect();
        // (The condensed method needs enough constrained points: `fixed::condensed_sets`.)
        prop_assume!(psets.iter().filter(|s| s.is_some()).count() >= if closed { 2 } else { 3 });
        let c = Constraint::HalfSpaces(sets.clone());
        let (p, cert) = run(&kn, &q, &psets, &c, m, 1, None);
        let mut cp = ConicProblem::new(&kn, d).unwrap();
        for (i, s) in sets.iter().enumerate() {
            if !s.is_empty() {
                cp.add_constraint(&[(i * m, 1.0)], ConvexSet::HalfSpaces(
                    s.iter().map(|h| (h.normal.clone(), h.offset)).collect())).unwrap();
            }
        }
        let Ok(full) = cp.solve(&crate::ConicOptions::default()) else {
            // The reference could not certify this instance: nothing to compare with.
            return Ok(());
        };
        let e = energy::energy(&kn, &p).unwrap();
        let e_interp = energy::energy(&kn, &interpolate(&kn, &Stencil::new(&kn), &q, m).unwrap()).unwrap();
        if full.energy <= ZERO_ENERGY_RTOL * e_interp {
            prop_assert!(e <= ZERO_ENERGY_RTOL * e_interp, "condensed {e} vs full {} (E* = 0)", full.energy);
        } else {
            prop_assert!(cert.kkt_residual <= EXACT, "kkt {:e}", cert.kkt_residual);
            prop_assert!((e - full.energy).abs() <= 1e-8 * full.energy, "condensed {e} vs full {}", full.energy);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The working set (started from every 2nd…9th ball, and also with a random start set)
    /// reaches the optimum of the single round on all balls: energies to 1e-9 relative, all
    /// certified at the exact level, every ball respected.
    #[test]
    fn the_working_set_reaches_the_optimum_of_all_balls(
        n in 8usize..40,
        k in 1usize..4,
        d in 1usize..4,
        closed in any::<bool>(),
        step in 2usize..10,
        seed in any::<u64>(),
    ) {
        let m = k + 1;
        let spans = if closed { m * n } else { m * (n - 1) };
        let mut state = seed | 1;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let h: Vec<f64> = (0..spans).map(|_| 0.2 + 1.8 * uniform()).collect();
        let topo = if closed { Topology::Closed } else { Topology::Open };
        let kn = knots(&h, topo);
        // A wiggly curve with noise, so some balls are active and most are not.
        let mut y = Vec::with_capacity(n * d);
        for i in 0..n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            for c in 0..d {
                let v = if c % 2 == 0 { a.cos() } else { a.sin() };
                y.push(v * (1.0 + 0.2 * (3.0 * a).sin()) + 0.1 * (uniform() - 0.5));
            }
        }
        let q = Points::new(d, y).unwrap();
        prop_assume!((0..n - 1).all(|i| super::dot_dist(q.point(i), q.point(i + 1)) > 1e-3));
        let radii: Vec<f64> = (0..n)
            .map(|i| if i % 11 == 5 { 0.0 } else { (0.02 + 0.3 * uniform()) * std::f64::consts::TAU / n as f64 })
            .collect();
        let c = Constraint::Balls(radii.clone());
        let sets = ball_sets(&radii);
        let (_, ca) = run(&kn, &q, &sets, &c, m, 1, None);
        let (pw, cw) = run(&kn, &q, &sets, &c, m, step, None);
        prop_assert!(ca.kkt_residual <= EXACT, "all: kkt {:e}", ca.kkt_residual);
        prop_assert!(cw.kkt_residual <= EXACT, "working set: kkt {:e}", cw.kkt_residual);
        prop_assert!((ca.energy - cw.energy).abs() <= 1e-9 * ca.energy,
            "all {} vs working set {}", ca.energy, cw.energy);
        // A start set (as the previous knot iteration's active balls give it): any set works.
        let start: Vec<bool> = (0..n).map(|_| uniform() < 0.2).collect();
        let (_, ch) = run(&kn, &q, &sets, &c, m, step, Some(&start));
        prop_assert!(ch.kkt_residual <= EXACT, "started: kkt {:e}", ch.kkt_residual);
        prop_assert!((ca.energy - ch.energy).abs() <= 1e-9 * ca.energy,
            "all {} vs started working set {}", ca.energy, ch.energy);
        // Every ball respected to the certificate's primal level: 1e-9 of the data's extent
        // L (the certificate's length scale; here L ≤ 1.2).
        let l = (0..n).flat_map(|i| q.point(i).iter().map(|v| v.abs())).fold(0.0f64, f64::max);
        for i in 0..n {
            let g = super::dot_dist(pw.point(i * m), q.point(i));
            prop_assert!(g <= radii[i] + 1e-9 * l, "ball {i}: {g} > {}", radii[i]);
        }
    }
}

/// The rules that decide how W grows — the window of the local-maximum rule, its halving,
/// the round from which a mostly violated remainder makes W everything — change the path,
/// not the answer: on a noisy closed star (n = 600, d = 2, a fifth to a half of the balls
/// active, so rounds add local maxima for a while) every setting reaches the single round
/// on all balls (energy to 1e-9 relative, certified), and the settings do take different
/// paths (their iteration counts are not all equal: an option that was ignored would fail).
#[test]
fn how_w_grows_changes_the_path_not_the_optimum() {
    let (kn, balls) = noisy_star(0x9E37_79B9_7F4A_7C15, 0.3, 0.7);
    let Balls {
        q,
        m,
        sets,
        constraint: c,
    } = &balls;
    let (n, m) = (q.len(), *m);
    let (_, all) = run(&kn, q, sets, c, m, 1, None);
    assert!(all.kkt_residual <= EXACT, "all: kkt {:e}", all.kkt_residual);
    let active = all.active.iter().filter(|&&a| a).count();
    assert!(
        (n / 5..n / 2).contains(&active),
        "the case is meant to be moderately dense: {active} of {n} active"
    );
    let default = WorkingSetOptions::default();
    let settings = [
        default.clone(),
        WorkingSetOptions {
            window_halving: 0,
            dense_round: 4,
            ..default.clone()
        },
        WorkingSetOptions {
            window_halving: 1,
            ..default.clone()
        },
        WorkingSetOptions {
            window: 0,
            ..default.clone()
        },
        WorkingSetOptions {
            dense_round: 1,
            dense: 0.1,
            ..default.clone()
        },
    ];
    let mut iterations = Vec::new();
    for (s, options) in settings.iter().enumerate() {
        let (_, cert, it) = run_with(&kn, q, sets, c, m, 64, None, options);
        assert!(
            cert.kkt_residual <= EXACT,
            "setting {s}: kkt {:e}",
            cert.kkt_residual
        );
        assert!(
            (cert.energy - all.energy).abs() <= 1e-9 * all.energy,
            "setting {s}: {} vs all {}",
            cert.energy,
            all.energy
        );
        iterations.push(it);
    }
    assert!(
        iterations.iter().any(|&i| i != iterations[0]),
        "every setting took the same path: {iterations:?}"
    );
}

/// The turn forecast on points placed by hand: q_2 = (2, 1) sits 1 above the chord from (1, 0)
/// to (3, 0); q_1 = (1, 0) sits 1/√5 from the chord from (0, 0) to (2, 1), and so does q_3; the
/// ends of an open curve have no chord. A point past the end of its chord is measured from that
/// end, not from the chord's line. A polytope leaves the forecast to the rounds.
#[test]
fn turns_past_radii_measures_from_the_neighbours_chord() {
    let q = Points::new(2, vec![0., 0., 1., 0., 2., 1., 3., 0., 4., 0.]).unwrap();
    let balls = |r: f64| vec![Some(PointSet::Ball(r)); 5];
    // How many of `of` balls turn past their radii (the fraction is a count over `of`).
    let past = |q: &Points, sets: &[Option<PointSet>], closed: bool, of: usize| {
        let f = turns_past_radii(q, sets, closed).unwrap();
        let count = (f * of as f64).round();
        assert!(
            (f * of as f64 - count).abs() < 1e-12,
            "{f} is not a count of {of}"
        );
        count as usize
    };
    let open = |r: f64| past(&q, &balls(r), false, 3);
    assert_eq!(open(0.4), 3, "1 and 1/√5 ≈ 0.447 both exceed 0.4");
    assert_eq!(open(0.5), 1, "only q_2 turns by more than 0.5");
    assert_eq!(open(1.0 / 5f64.sqrt() - 1e-12), 3);
    assert_eq!(open(1.0 / 5f64.sqrt() + 1e-12), 1);
    assert_eq!(open(1.0), 0, "a turn of exactly the radius is not past it");
    // Interpolated points are not counted. Closed, the ends count too: (0, 0) lies beyond the
    // end (1, 0) of the chord from (4, 0), 1 from it, and (4, 0) beyond the end (3, 0) of the
    // chord to (0, 0): with q_2, three of five turn by more than 0.5.
    let mut sets = balls(0.5);
    sets[2] = Some(PointSet::Fixed);
    assert_eq!(past(&q, &sets, false, 2), 0);
    assert_eq!(past(&q, &balls(0.5), true, 5), 3);
    // (2, 0) between (0, 0) and (1, 0) lies beyond its chord's end, 1 from it.
    let back = Points::new(2, vec![0., 0., 2., 0., 1., 0.]).unwrap();
    let b3 = vec![Some(PointSet::Ball(0.9)); 3];
    assert_eq!(past(&back, &b3, false, 1), 1);
    let face = Face {
        normal: vec![0.0, 1.0],
        offset: 1.0,
        norm: 1.0,
    };
    let mut mixed = balls(0.5);
    mixed[1] = Some(PointSet::Faces(vec![face]));
    assert_eq!(turns_past_radii(&q, &mixed, false), None);
}

/// On data whose balls are mostly active (the noisy star, radii 0.2–0.7 of the spacing, most of
/// them turning past their radii), `solve` starts with every ball and takes one round: the iterations of
/// a single round on all, not of the rounds from every 64th (the turn test switched off), and the
/// same optimum as the rounds (energy to 1e-9 relative, both certified).
#[test]
fn data_turning_past_their_balls_start_with_every_ball() {
    let (kn, balls) = noisy_star(0x2545_F491_4F6C_DD1D, 0.2, 0.5);
    let turning = turns_past_radii(&balls.q, &balls.sets, true).unwrap();
    assert!(turning > 0.5, "the star turns past most balls: {turning}");
    let solved = |options: &WorkingSetOptions| {
        let sol = balls.solve_on(&kn, options, None, EXACT);
        assert!(sol.certificate.kkt_residual <= EXACT);
        (sol.certificate.energy, sol.iterations)
    };
    let (e, it) = solved(&WorkingSetOptions::default());
    let (e_rounds, it_rounds) = solved(&WorkingSetOptions {
        turn_start: 2.0,
        ..WorkingSetOptions::default()
    });
    let (_, _, it_all) = run_with(
        &kn,
        &balls.q,
        &balls.sets,
        &balls.constraint,
        balls.m,
        1,
        None,
        &WorkingSetOptions::default(),
    );
    assert_eq!(it, it_all, "one round on every ball");
    assert_ne!(it, it_rounds, "the rounds take another path");
    assert!((e - e_rounds).abs() <= 1e-9 * e_rounds, "{e} vs {e_rounds}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// All radii 0: no cone, and the interpolating curve of `fast::interpolate`; radii far
    /// larger than the data: a constant curve is feasible, so E* = 0 and the optimum found has
    /// E at the rounding level of the interpolation energy.
    #[test]
    fn zero_radii_interpolate_and_huge_radii_give_zero_energy((kn, n, m, y, d) in case()) {
        let q = Points::new(d, y).unwrap();
        let stencil = Stencil::new(&kn);
        let (fixed, _) = run(&kn, &q, &ball_sets(&vec![0.0; n]), &Constraint::Balls(vec![0.0; n]), m, 1, None);
        let interp = interpolate(&kn, &stencil, &q, m).unwrap();
        let scale = interp.coords().iter().fold(1.0f64, |a, v| a.max(v.abs()));
        for (a, b) in fixed.coords().iter().zip(interp.coords()) {
            prop_assert!((a - b).abs() <= 1e-13 * scale, "{a} vs {b}");
        }
        let e_interp = energy::energy(&kn, &interp).unwrap();
        let (p, _) = run(&kn, &q, &ball_sets(&vec![10.0; n]), &Constraint::Balls(vec![10.0; n]), m, 1, None);
        let e = energy::energy(&kn, &p).unwrap();
        prop_assert!(e <= ZERO_ENERGY_RTOL * e_interp.max(f64::MIN_POSITIVE), "E = {e} (interpolation {e_interp})");
    }
}

/// A knot update's warm start: the answer on knots A, polished on knots B (sub-spans scaled
/// by up to ±4 %, as a knot iteration moves them), is the answer a cold solve on B finds —
/// same energy to 1e-9, both certified — and it took the polish path (at most
/// POLISH_ROUNDS calls, where the interior-point method takes tens of iterations).
#[test]
fn a_warm_polish_finds_the_cold_answer_on_moved_knots() {
    let balls = warm_curve(60, |i, _| {
        1.0 + 0.3 * (i % 2) as f64 + 0.04 * (i as f64 * 2.3).cos()
    });
    let solve_on = |kn: &Knots, warm: Option<(&Points, &[Vec<f64>])>| {
        balls.solve_on(kn, &WorkingSetOptions::default(), warm, 1e-11)
    };
    let (a, b) = (wobbled_knots(&balls, 0.0), wobbled_knots(&balls, 0.04));
    let first = solve_on(&a, None);
    let cold = solve_on(&b, None);
    let warm = solve_on(&b, Some((&first.points, &first.multipliers)));
    assert!(cold.certificate.kkt_residual <= EXACT && warm.certificate.kkt_residual <= EXACT);
    let (ec, ew) = (cold.certificate.energy, warm.certificate.energy);
    assert!(
        (ec - ew).abs() <= 1e-9 * ec,
        "energies {ec} (cold) vs {ew} (warm)"
    );
    assert!(
        warm.iterations <= POLISH_ROUNDS && cold.iterations > POLISH_ROUNDS,
        "warm {} and cold {} iterations",
        warm.iterations,
        cold.iterations
    );
    let active = first.multipliers.iter().filter(|w| w[0] > 0.0).count();
    assert!(active > 5, "{active} balls active: a test of nothing");
}

/// Knot updates in a row: a warm polish that ran on the active points alone (a fifth or more of
/// the balls inactive, `ActivePolish`) returns one multiplier per data point, as the next
/// update's warm start reads them — it returned the subset's, so the next update's warm start
/// was refused and the method ran cold (the wavy circle of `cargo xtask bench conic`, n = 10⁴,
/// three updates: 126 iterations where 68 do). Each warm answer is the cold one on its knots.
#[test]
fn a_warm_polish_on_the_active_points_starts_the_next_update() {
    let n = 80;
    let balls = warm_curve(n, |i, t| {
        1.0 + 0.3 * (5.0 * t).sin() + 0.03 * (i as f64 * 2.3).cos()
    });
    let solve_on = |kn: &Knots, warm: Option<(&Points, &[Vec<f64>])>| {
        balls.solve_on(kn, &WorkingSetOptions::default(), warm, 1e-11)
    };
    let first = solve_on(&wobbled_knots(&balls, 0.0), None);
    let active = first.multipliers.iter().filter(|w| w[0] > 0.0).count();
    assert!(
        active > 5 && active < n * 4 / 5,
        "{active} of {n} balls active: the polish would not run on a subset"
    );
    let mut prev = first;
    for wobble in [0.02, 0.03] {
        let kn = wobbled_knots(&balls, wobble);
        let warm = solve_on(&kn, Some((&prev.points, &prev.multipliers)));
        let cold = solve_on(&kn, None);
        assert_eq!(warm.multipliers.len(), n, "one multiplier per data point");
        assert!(
            warm.iterations <= POLISH_ROUNDS,
            "wobble {wobble}: {} iterations, not the warm polish",
            warm.iterations
        );
        assert!(warm.certificate.kkt_residual <= EXACT);
        let (ec, ew) = (cold.certificate.energy, warm.certificate.energy);
        assert!(
            (ec - ew).abs() <= 1e-9 * ec,
            "energies {ec} (cold) vs {ew} (warm)"
        );
        prev = warm;
    }
}
