//! Fixed-knot optimality (Kersey §3.1–3.4): Theorems 3.1, 3.2, 3.4, 3.5 and Corollaries 3.3,
//! 3.6, each checked twice — the KKT conditions recomputed from the returned points and
//! multipliers ([`super::kkt`]), and the optimal objective of an independent solver (Clarabel).

use divdiff::{jumps, Points, Topology};
use refine::{Constraint, HalfSpace, Problem, Refinement};

use super::kkt::{self, extent, Kkt};
use super::{clarabel_gap, ellipse, jittered, lcg, radii, weights, ENERGY_RTOL, KKT_TOL};
use crate::verify::kersey_defs::{dist, dot, norm2};
use crate::verify::{worst, Case, Oracle, Outcome};

/// The seeded problem set: (n, d, topology, seed, very unequal spans?).
fn shapes() -> Vec<(usize, usize, Topology, u64, bool)> {
    vec![
        (5, 2, Topology::Closed, 1, false),
        (7, 3, Topology::Closed, 2, true),
        (6, 1, Topology::Closed, 3, false),
        (6, 2, Topology::Open, 4, true),
        (9, 3, Topology::Open, 5, true),
        (5, 1, Topology::Open, 6, false),
        (9, 2, Topology::Closed, 7, true),
    ]
}

fn data(n: usize, d: usize, topo: Topology, seed: u64, unequal: bool) -> Points {
    if unequal {
        jittered(n, d, topo, seed)
    } else {
        ellipse(n, d, seed)
    }
}

/// Solves `make` on every shape; returns the problems and their refinements.
fn solve_all(
    make: impl Fn(Points, Topology, u64) -> Problem,
) -> anyhow::Result<Vec<(String, Problem, Refinement)>> {
    let mut out = Vec::new();
    for (n, d, topo, seed, unequal) in shapes() {
        let p = make(data(n, d, topo, seed, unequal), topo, seed);
        let r = p
            .solve()
            .map_err(|e| anyhow::anyhow!("n={n} d={d} {topo:?}: {e}"))?;
        out.push((format!("n={n} d={d} {topo:?}"), p, r));
    }
    Ok(out)
}

/// The recomputed KKT certificate, worst over the set.
fn kkt_case(
    make: impl Fn(Points, Topology, u64) -> Problem,
    what: &str,
) -> anyhow::Result<Outcome> {
    let mut k = Kkt::default();
    let (mut which, mut reported) = (String::new(), 0.0f64);
    for (name, p, r) in solve_all(make)? {
        let c = kkt::recompute(&p, &r).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        if c.worst().is_nan() || c.worst() > k.worst() {
            which = name;
        }
        k = k.max(c);
        reported = worst([reported, r.kkt_residual]);
    }
    Ok(Outcome::check(
        k.worst(),
        KKT_TOL,
        format!("{what}, recomputed from the returned points and multipliers (7 shapes, d = 1..3, open and closed, 4 with very unequal spans): {} (worst: {which}; the solver's own residual, scaled by ‖H‖·max step, reads ≤ {reported:.1e})", k.show()),
    )
    .against(Oracle::Property(
        "KKT conditions recomputed with divdiff (Hp = 2 jmp), not the solver's residual",
    )))
}

/// Relative objective difference to Clarabel, worst over the set.
fn clarabel_case(
    make: impl Fn(Points, Topology, u64) -> Problem,
    what: &str,
) -> anyhow::Result<Outcome> {
    let (mut w, mut feasibility) = (0.0f64, 0.0f64);
    for (name, p, r) in solve_all(make)? {
        w = worst([
            w,
            clarabel_gap(&p, &r).map_err(|e| anyhow::anyhow!("{name}: {e}"))?,
        ]);
        // A lower objective than the optimum's would only mean an infeasible answer.
        feasibility = worst([feasibility, kkt::recompute(&p, &r)?.feasibility]);
    }
    Ok(Outcome::check(
        worst([w, feasibility]),
        ENERGY_RTOL,
        format!("{what}: relative objective difference to Clarabel on the same knots ({w:.1e}) and relative constraint violation of the returned points ({feasibility:.1e}), 7 seeded random shapes"),
    )
    .against(Oracle::IndependentSolver(
        "Clarabel, conic program of kersey_support",
    )))
}

fn interpolation(q: Points, t: Topology, _: u64) -> Problem {
    Problem::new(q).with_topology(t).with_k(3)
}

fn smoothing(q: Points, t: Topology, s: u64) -> Problem {
    let n = q.len();
    Problem::new(q)
        .with_topology(t)
        .with_constraint(Constraint::Smoothing(weights(n, s)))
}

fn balls(q: Points, t: Topology, s: u64) -> Problem {
    let n = q.len();
    Problem::new(q)
        .with_topology(t)
        .with_k(4)
        .with_constraint(Constraint::Balls(radii(n, s)))
}

/// Balls twice as large: some are inactive (Corollary 3.3).
fn big_balls(q: Points, t: Topology, s: u64) -> Problem {
    let n = q.len();
    let big: Vec<f64> = radii(n, s).iter().map(|e| 2.0 * e).collect();
    Problem::new(q)
        .with_topology(t)
        .with_constraint(Constraint::Balls(big))
}

/// A convex set about each data point (3.7): in the plane a polygon of 3–5 half-planes with
/// random normals spread around the circle, in R³ a randomly rotated box, in R a segment; the
/// offsets put q_i inside at distances 0.03..0.3 from each face (0.15..1.5 for every third
/// point), normals of random length.
fn polytopes(q: &Points, seed: u64) -> Vec<Vec<HalfSpace>> {
    let mut next = lcg(seed + 300);
    let d = q.dim();
    q.iter()
        .enumerate()
        .map(|(i, c)| {
            // Every third set is five times larger, so that some data vertices are inside.
            let size = if i % 3 == 1 { 30.0 } else { 1.0 };
            let normals: Vec<Vec<f64>> = match d {
                1 => vec![vec![1.0], vec![-1.0]],
                2 => {
                    let m = 3 + (next() * 3.0) as usize;
                    let a0 = next() * std::f64::consts::TAU;
                    (0..m)
                        .map(|j| {
                            let a = a0
                                + (j as f64 + 0.3 * (next() - 0.5)) * std::f64::consts::TAU
                                    / m as f64;
                            vec![a.cos(), a.sin()]
                        })
                        .collect()
                }
                _ => {
                    // A random rotation from two random angles, the box's six faces.
                    let (a, b) = (next() * 3.0, next() * 3.0);
                    let (ca, sa, cb, sb) = (a.cos(), a.sin(), b.cos(), b.sin());
                    let axes = [
                        vec![ca * cb, sa * cb, sb],
                        vec![-sa, ca, 0.0],
                        vec![-ca * sb, -sa * sb, cb],
                    ];
                    axes.iter()
                        .flat_map(|u| [u.clone(), u.iter().map(|x| -x).collect()])
                        .collect()
                }
            };
            normals
                .into_iter()
                .map(|u| {
                    let scale = 0.5 + 2.0 * next();
                    let normal: Vec<f64> = u.iter().map(|x| scale * x).collect();
                    let offset = dot(&normal, c) + scale * size * (0.03 + 0.27 * next());
                    HalfSpace { normal, offset }
                })
                .collect()
        })
        .collect()
}

fn halfspaces(q: Points, t: Topology, s: u64) -> Problem {
    let sets = polytopes(&q, s);
    Problem::new(q)
        .with_topology(t)
        .with_constraint(Constraint::HalfSpaces(sets))
}

/// Corollaries 3.3 and 3.6: at a data vertex strictly inside its set (a margin of 1e-6·L from
/// the boundary, so that weakly active constraints do not count) jmp = ½(Hp) vanishes; jmp from
/// `divdiff::jumps`, relative to the largest |jmp| of the curve (at least the rounding level
/// over 1e-9, as in [`kkt`]). At least one inactive and one
/// active data vertex must exist over the set, or the case fails.
fn inactive_jmp_case(
    make: impl Fn(Points, Topology, u64) -> Problem,
    corollary: &str,
) -> anyhow::Result<Outcome> {
    let (mut inactive, mut active, mut w) = (0usize, 0usize, 0.0f64);
    for (name, p, r) in solve_all(make)? {
        let l = extent(&p.points);
        let j = jumps(&r.knots, &r.points)?;
        // The force scale of the recomputed KKT conditions, halved (jmp = ½Hp).
        let scale = worst(j.coords().iter().map(|x| x.abs()))
            .max(0.5 * kkt::rounding_level(&r.knots, &r.points) / KKT_TOL)
            .max(f64::MIN_POSITIVE);
        for (i, &v) in r.data_vertex.iter().enumerate() {
            let x = r.points.point(v);
            // The largest scaled constraint value g/|∇g| (< 0 inside).
            let g = match &p.constraint {
                Constraint::Balls(eps) => dist(x, p.points.point(i)) - eps[i],
                // The signed maximum (worst() floors at 0); NaN propagates through the
                // comparison below as "not inactive", and an empty set counts as inactive.
                Constraint::HalfSpaces(sets) => sets[i]
                    .iter()
                    .map(|h| (dot(&h.normal, x) - h.offset) / norm2(&h.normal).sqrt())
                    .fold(f64::NEG_INFINITY, |a, b| {
                        if a.is_nan() || b.is_nan() {
                            f64::NAN
                        } else {
                            a.max(b)
                        }
                    }),
                _ => anyhow::bail!("{name}: not a set constraint"),
            };
            if g < -1e-6 * l {
                inactive += 1;
                w = worst([w, worst(j.point(v).iter().map(|x| x.abs())) / scale]);
            } else {
                active += 1;
            }
        }
    }
    let ok = inactive > 0 && active > 0;
    Ok(Outcome::check(
        if ok { w } else { f64::INFINITY },
        KKT_TOL,
        format!("{corollary}: max |jmp_(i_k)| / max|jmp| at {inactive} data vertices strictly inside their set ({active} on the boundary), jmp by divdiff::jumps"),
    )
    .against(Oracle::Property(
        "jmp = 0 at inactive vertices, jmp from divdiff's divided differences",
    )))
}

/// The condensed solver's working-set rounds (n ≥ 64: balls outside the set checked, not
/// solved), open and closed, d = 2 and 3, fixed knots and Algorithm 4.1's knot updates.
fn working_set() -> anyhow::Result<Outcome> {
    let mut gap = 0.0f64;
    let mut k = Kkt::default();
    let mut detail = Vec::new();
    for (n, d, topo, seed, ki) in [
        (120, 2, Topology::Closed, 11, 0),
        (96, 3, Topology::Closed, 12, 0),
        (110, 2, Topology::Open, 13, 0),
        (100, 2, Topology::Closed, 14, 3),
    ] {
        let q = if seed % 2 == 0 {
            jittered(n, d, topo, seed)
        } else {
            ellipse(n, d, seed)
        };
        let p = Problem::new(q)
            .with_topology(topo)
            .with_k(3)
            .with_knot_iterations(ki)
            .with_constraint(Constraint::Balls(radii(n, seed)));
        let r = p.solve()?;
        let g = clarabel_gap(&p, &r).map_err(|e| anyhow::anyhow!("n = {n}: {e}"))?;
        let c = kkt::recompute(&p, &r)?;
        gap = worst([gap, g]);
        k = k.max(c);
        let active = r.active.iter().filter(|&&a| a).count();
        detail.push(format!(
            "n={n}: {active} active, gap {g:.1e}, kkt {:.1e}",
            c.worst()
        ));
    }
    Ok(Outcome::check(
        worst([gap, k.worst() * ENERGY_RTOL / KKT_TOL]),
        ENERGY_RTOL,
        format!(
            "relative energy difference to Clarabel, and the recomputed KKT residual × 10 (KKT ≤ 1e-9): {}",
            detail.join("; ")
        ),
    )
    .against(Oracle::IndependentSolver(
        "Clarabel, and the KKT conditions recomputed with divdiff",
    )))
}

fn common_point() -> anyhow::Result<Outcome> {
    let q = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])?;
    let r = Problem::new(q)
        .with_constraint(Constraint::Balls(vec![0.75; 4]))
        .solve()?;
    let e = energy::energy(&r.knots, &r.points)?;
    let spread = worst(
        r.points
            .iter()
            .map(|p| (p[0] - r.points.point(0)[0]).abs() + (p[1] - r.points.point(0)[1]).abs()),
    );
    let feasible = r.data_vertex.iter().enumerate().all(|(i, &v)| {
        let (a, b) = (
            r.points.point(v),
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]][i],
        );
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() <= 0.75
    });
    Ok(Outcome::check(
        if feasible { worst([e.abs(), r.energy.abs(), spread]) } else { f64::INFINITY },
        1e-14,
        format!("balls of radius 0.75 about a unit square's corners share its centre: a feasible constant curve, E = 0 (recomputed E {e:.1e}, spread {spread:.1e}, feasible {feasible})"),
    )
    .against(Oracle::ClosedForm))
}

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    vec![
        Case::holds("kersey/thm3.1/interpolation-kkt", || {
            kkt_case(interpolation, "(3.3): p_(i_k) = q_i, (Hp)_j = 0 at free j")
        }),
        Case::holds("kersey/thm3.1/interpolation-vs-clarabel", || {
            clarabel_case(interpolation, "(3.2) interpolation")
        }),
        Case::holds("kersey/thm3.2/balls-kkt", || {
            kkt_case(
                balls,
                "(3.5): (H + W)p = W q~, w ≥ 0, |p − q| ≤ ε, w(|p − q| − ε) = 0",
            )
        }),
        Case::holds("kersey/thm3.2/balls-vs-clarabel", || {
            clarabel_case(balls, "(3.4) balls (second-order cones)")
        }),
        Case::holds("kersey/thm3.2/balls-working-set-vs-clarabel", working_set),
        Case::holds("kersey/cor3.3/jmp-vanishes-at-inactive-vertices", || {
            inactive_jmp_case(big_balls, "Corollary 3.3 (balls)")
        }),
        Case::holds("kersey/thm3.4/smoothing-kkt", || {
            kkt_case(smoothing, "(3.6): (H + W)p = W q~ with the given weights")
        }),
        Case::holds("kersey/thm3.4/smoothing-vs-clarabel", || {
            clarabel_case(smoothing, "(3.6) smoothing")
        }),
        Case::holds("kersey/thm3.5/halfspaces-kkt", || {
            kkt_case(
                halfspaces,
                "(3.8): (Hp)_(i_k) + Σ w_ij n_ij = 0, (Hp)_j = 0 free, w ≥ 0, n·p ≤ c, w(c − n·p) = 0",
            )
        }),
        Case::holds("kersey/thm3.5/halfspaces-vs-clarabel", || {
            clarabel_case(halfspaces, "(3.7) polygons / rotated boxes (half-spaces)")
        }),
        Case::holds("kersey/cor3.6/jmp-vanishes-inside-the-sets", || {
            inactive_jmp_case(halfspaces, "Corollary 3.6 (half-spaces)")
        }),
        Case::holds(
            "kersey/degenerate/common-point-constant-curve",
            common_point,
        ),
    ]
}
