//! Constraints on the approximate derivative (Kersey §3.5, Figs. 3.5–3.8) and the ends of open
//! curves (§3.6): optimality against Clarabel on the conic program of `kersey_support` (the
//! derivative stencils from `divdiff::derivative_stencil`), feasibility of the returned points
//! with Df evaluated from its definition ([`crate::verify::kersey_defs`]), and the natural end
//! condition printed in §3.6 with its correction.

use divdiff::{DerivativeRule, Points, Topology};
use refine::{Boundary, Constraint, HalfSpace, Problem, Refinement, Tangent};

use super::clarabel_ref::{clarabel_problem_with_derivatives, clarabel_solve_socp};
use super::{ellipse, jittered, rel, ENERGY_RTOL};
use crate::verify::kersey_defs::{dist, dot, norm2, sub, Curve, Df};
use crate::verify::{worst, Case, Oracle, Outcome};

/// A derivative-constrained problem family: name, data, topology, position constraint, rule.
struct Shape {
    name: &'static str,
    q: Points,
    topology: Topology,
    constraint: Constraint,
    rule: DerivativeRule,
}

fn shapes() -> Vec<Shape> {
    let q1 = jittered(6, 2, Topology::Closed, 31);
    let q2 = jittered(6, 3, Topology::Open, 32);
    let q3 = ellipse(5, 2, 33);
    vec![
        Shape {
            name: "closed d=2 balls Bessel",
            constraint: Constraint::Balls(vec![0.1, 0.05, 0.15, 0.08, 0.12, 0.06]),
            q: q1,
            topology: Topology::Closed,
            rule: DerivativeRule::Bessel,
        },
        Shape {
            name: "open d=3 interpolation Bessel",
            q: q2,
            topology: Topology::Open,
            constraint: Constraint::Interpolate,
            rule: DerivativeRule::Bessel,
        },
        Shape {
            name: "open d=2 balls Average",
            constraint: Constraint::Balls(vec![0.1; 5]),
            q: q3,
            topology: Topology::Open,
            rule: DerivativeRule::Average,
        },
    ]
}

fn rule_df(rule: DerivativeRule) -> Df {
    match rule {
        DerivativeRule::Average => Df::Average,
        DerivativeRule::Bessel => Df::Bessel,
    }
}

/// Df at the data vertices of the unconstrained-derivative solve: the reference vectors the
/// tangent constraints are built around (so that they are active).
fn reference_tangents(s: &Shape) -> anyhow::Result<Vec<Vec<f64>>> {
    let r = Problem::new(s.q.clone())
        .with_topology(s.topology)
        .with_constraint(s.constraint.clone())
        .with_derivative(s.rule)
        .solve()?;
    let c = Curve::from_lib(&r.knots, &r.points);
    Ok(r.data_vertex
        .iter()
        .map(|&v| c.df(v, rule_df(s.rule)))
        .collect())
}

/// Rotates v by `angle` in the plane of its first two coordinates and scales it.
fn turn(v: &[f64], angle: f64, scale: f64) -> Vec<f64> {
    let mut w: Vec<f64> = v.iter().map(|x| scale * x).collect();
    if w.len() >= 2 {
        let (c, s) = (angle.cos(), angle.sin());
        let (a, b) = (w[0], w[1]);
        w[0] = c * a - s * b;
        w[1] = s * a + c * b;
    }
    w
}

/// The tangent constraints of one kind about the reference tangents D_i (every other point
/// left free, so free and constrained data vertices mix).
fn tangents(kind: &str, d: &[Vec<f64>]) -> Vec<Option<Tangent>> {
    d.iter()
        .enumerate()
        .map(|(i, v)| {
            if i % 3 == 2 {
                return None;
            }
            let len = norm2(v).sqrt();
            Some(match kind {
                // Fig. 3.5a: a ball about a turned and stretched prescribed vector.
                "ball" => Tangent::Ball {
                    center: turn(v, 0.5, 1.3),
                    radius: 0.2 * len,
                },
                // Fig. 3.5b: only the direction, within ±0.15 rad of a turned direction.
                "wedge" => Tangent::Wedge {
                    direction: turn(v, 0.4, 1.0),
                    half_angle: 0.15,
                },
                // Fig. 3.5c: tension, |Df| at most 60 % of the free length.
                "tension" => Tangent::Tension { radius: 0.6 * len },
                // (3.10) with piecewise-linear boundaries: two half-spaces cutting the
                // reference tangent's component along itself and along a turned direction.
                _ => Tangent::HalfSpaces(vec![
                    HalfSpace {
                        normal: v.clone(),
                        offset: 0.8 * len * len,
                    },
                    HalfSpace {
                        normal: turn(v, 1.2, 2.0),
                        offset: 0.1 * len * len,
                    },
                ]),
            })
        })
        .collect()
}

/// max over the constraints of the scaled violation, with Df from its definition.
fn tangent_violation(
    r: &Refinement,
    t: &[Option<Tangent>],
    rule: DerivativeRule,
) -> anyhow::Result<f64> {
    let c = Curve::from_lib(&r.knots, &r.points);
    let mut w = 0.0f64;
    for (i, t) in t.iter().enumerate() {
        let Some(t) = t else { continue };
        let df = c.df(r.data_vertex[i], rule_df(rule));
        let len = norm2(&df).sqrt();
        let v = match t {
            Tangent::Ball { center, radius } => {
                (dist(&df, center) - radius) / norm2(center).sqrt().max(*radius)
            }
            Tangent::Tension { radius } => (len - radius) / radius.max(f64::MIN_POSITIVE),
            Tangent::Wedge {
                direction,
                half_angle,
            } => {
                let u = norm2(direction).sqrt();
                (half_angle.cos() * len - dot(&df, direction) / u) / len.max(f64::MIN_POSITIVE)
            }
            Tangent::HalfSpaces(hs) => worst(hs.iter().map(|h| {
                (dot(&h.normal, &df) - h.offset) / (norm2(&h.normal).sqrt() * len.max(1e-300))
            })),
        };
        w = worst([w, v]);
    }
    Ok(w)
}

/// Ball violation of the data constraint, relative to the radius (interpolation: |p − q|).
fn position_violation(p: &Problem, r: &Refinement) -> f64 {
    worst(r.data_vertex.iter().enumerate().map(|(i, &v)| {
        let d = dist(r.points.point(v), p.points.point(i));
        match &p.constraint {
            Constraint::Balls(eps) => (d - eps[i]) / eps[i].max(1e-300),
            _ => d,
        }
    }))
}

/// E of ours vs Clarabel's optimum of the same problem on the returned knots.
fn clarabel_energy_gap(p: &Problem, r: &Refinement) -> anyhow::Result<f64> {
    let socp = clarabel_problem_with_derivatives(
        &r.knots,
        &p.points,
        &r.data_vertex,
        &p.constraint,
        p.tangents.as_deref(),
        &p.boundary,
        p.derivative,
    )
    .map_err(anyhow::Error::msg)?;
    let reference = clarabel_solve_socp(&socp, p.points.dim()).map_err(anyhow::Error::msg)?;
    Ok(rel(
        energy::energy(&r.knots, &r.points)?,
        energy::energy(&r.knots, &reference.points)?,
    ))
}

fn tangent_case(kind: &'static str, what: &str) -> anyhow::Result<Outcome> {
    let (mut gap, mut viol) = (0.0f64, 0.0f64);
    let mut detail = Vec::new();
    for s in shapes() {
        let d = reference_tangents(&s)?;
        let t = tangents(kind, &d);
        let p = Problem::new(s.q.clone())
            .with_topology(s.topology)
            .with_constraint(s.constraint.clone())
            .with_derivative(s.rule)
            .with_tangents(t.clone());
        let r = p.solve().map_err(|e| anyhow::anyhow!("{}: {e}", s.name))?;
        let free = Problem::new(s.q.clone())
            .with_topology(s.topology)
            .with_constraint(s.constraint.clone())
            .with_knots(data_knots(&r))
            .with_knot_iterations(0)
            .solve()?;
        let g = clarabel_energy_gap(&p, &r).map_err(|e| anyhow::anyhow!("{}: {e}", s.name))?;
        let v = worst([
            tangent_violation(&r, &t, s.rule)?,
            position_violation(&p, &r),
        ]);
        gap = worst([gap, g]);
        viol = worst([viol, v]);
        detail.push(format!(
            "{}: E {:.4} (without tangents {:.4}), gap {g:.1e}, violation {v:.1e}",
            s.name, r.energy, free.energy
        ));
    }
    Ok(Outcome::check(
        worst([gap, viol]),
        ENERGY_RTOL,
        format!(
            "{what}; the data of Figs. 3.6–3.8 are not printed: seeded random data, tangent sets built about each problem's own free tangents so that they are active; relative energy difference to Clarabel on the returned knots and the largest relative violation (Df from its definition): {}",
            detail.join("; ")
        ),
    )
    .against(Oracle::IndependentSolver(
        "Clarabel on the conic program with derivative rows (kersey_support)",
    )))
}

/// The data knots of a refinement (its knots at the data vertices, plus T for a closed curve).
fn data_knots(r: &Refinement) -> Vec<f64> {
    let t = r.knots.values();
    let mut u: Vec<f64> = r.data_vertex.iter().map(|&v| t[v]).collect();
    if r.knots.is_closed() {
        u.push(t[t.len() - 1]);
    }
    u
}

fn ends_case(near: bool) -> anyhow::Result<Outcome> {
    let (mut gap, mut viol) = (0.0f64, 0.0f64);
    let mut detail = Vec::new();
    for (name, q, c, rule) in [
        (
            "d=2 interpolation Bessel",
            jittered(6, 2, Topology::Open, 41),
            Constraint::Interpolate,
            DerivativeRule::Bessel,
        ),
        (
            "d=3 balls Bessel",
            jittered(7, 3, Topology::Open, 42),
            Constraint::Balls(vec![0.05, 0.1, 0.2, 0.1, 0.05, 0.15, 0.1]),
            DerivativeRule::Bessel,
        ),
        (
            "d=2 balls Average",
            ellipse(5, 2, 43),
            Constraint::Balls(vec![0.1; 5]),
            DerivativeRule::Average,
        ),
    ] {
        let d = q.dim();
        let start: Vec<f64> = (0..d).map(|c| if c == 1 { 2.0 } else { 0.3 }).collect();
        let end: Vec<f64> = (0..d).map(|c| if c == 0 { -1.5 } else { 0.5 }).collect();
        let boundary = if near {
            Boundary::NearClamped {
                start: start.clone(),
                end: end.clone(),
                radius: 0.3,
            }
        } else {
            Boundary::Clamped {
                start: start.clone(),
                end: end.clone(),
            }
        };
        let p = Problem::new(q)
            .with_topology(Topology::Open)
            .with_constraint(c)
            .with_derivative(rule)
            .with_boundary(boundary);
        let r = p.solve().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        let g = clarabel_energy_gap(&p, &r).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        let cur = Curve::from_lib(&r.knots, &r.points);
        let n = cur.n();
        let mut v = position_violation(&p, &r);
        let mut gaps = Vec::new();
        for (vertex, want) in [(0, &start), (n - 1, &end)] {
            let df = cur.df(vertex, rule_df(rule));
            let e = dist(&df, want);
            gaps.push(e);
            v = worst([
                v,
                if near {
                    (e - 0.3) / 0.3
                } else {
                    e / norm2(want).sqrt()
                },
            ]);
        }
        gap = worst([gap, g]);
        viol = worst([viol, v]);
        detail.push(format!(
            "{name}: |Df − v| at the ends {:.2e}, {:.2e}, gap {g:.1e}",
            gaps[0], gaps[1]
        ));
    }
    Ok(Outcome::check(
        worst([gap, viol]),
        ENERGY_RTOL,
        format!(
            "{}, seeded random data (Fig. 3.9's data are not printed): relative energy difference to Clarabel and the relative violation of the end condition (Df from its definition): {}",
            if near { "near-clamped |Df(t_1) − v_1| ≤ 0.3, |Df(t_N) − v_n| ≤ 0.3" } else { "clamped Df(t_1) = v_1, Df(t_N) = v_n" },
            detail.join("; ")
        ),
    )
    .against(Oracle::IndependentSolver(
        "Clarabel on the conic program with derivative rows (kersey_support)",
    )))
}

/// §3.6's end condition of an open curve with balls: ∂L/∂p_1 = c·Δ_{1,2}p/h_1 + w_1(p_1 − q_1) = 0
/// (printed with c = 1; with the multipliers of (3.5), c = 2), and the right end likewise with
/// (2/h_{N−1})Δ_{N−2,2}p. Returns (worst residual with factor `c` at the active ends, the worst
/// |Δ| at inactive ends relative to the force scale, number of active ends, of inactive ends).
fn end_condition(c: f64) -> anyhow::Result<(f64, f64, usize, usize)> {
    let (mut res, mut natural, mut act, mut inact) = (0.0f64, 0.0f64, 0usize, 0usize);
    for (q, eps) in [
        (
            jittered(6, 2, Topology::Open, 51),
            vec![0.02, 0.1, 0.1, 0.1, 0.1, 0.9],
        ),
        (
            jittered(7, 3, Topology::Open, 52),
            vec![0.9, 0.1, 0.05, 0.1, 0.1, 0.05, 0.03],
        ),
        (ellipse(6, 2, 53), vec![0.05, 0.1, 0.1, 0.1, 0.1, 0.05]),
    ] {
        let p = Problem::new(q.clone())
            .with_topology(Topology::Open)
            .with_constraint(Constraint::Balls(eps.clone()));
        let r = p.solve()?;
        let cur = Curve::from_lib(&r.knots, &r.points);
        let n = cur.n();
        let force = worst((0..n).flat_map(|i| cur.jmp(i).into_iter().map(|x| 2.0 * x.abs())));
        for (i, vertex, dd, h) in [
            (0, 0, cur.dd(0, 2), cur.h(0)),
            (
                q.len() - 1,
                n - 1,
                cur.dd(n as isize - 3, 2),
                cur.h(n as isize - 2),
            ),
        ] {
            let w = r.multipliers[i][0];
            let diff = sub(r.points.point(vertex), q.point(i));
            if norm2(&diff).sqrt() < eps[i] * (1.0 - 1e-6) {
                inact += 1;
                natural = worst([natural, worst(dd.iter().map(|x| 2.0 * x.abs() / h)) / force]);
            } else {
                act += 1;
                let r: Vec<f64> = dd
                    .iter()
                    .zip(&diff)
                    .map(|(a, b)| c * a / h + w * b)
                    .collect();
                res = worst([res, worst(r.iter().map(|x| x.abs())) / force]);
            }
        }
    }
    Ok((res, natural, act, inact))
}

fn end_condition_corrected() -> anyhow::Result<Outcome> {
    let (res, natural, act, inact) = end_condition(2.0)?;
    let ok = act > 0 && inact > 0;
    Ok(Outcome::check(
        if ok { worst([res, natural]) } else { f64::INFINITY },
        super::KKT_TOL,
        format!("(2/h_1)Δ_(1,2)p + w_1(p_1 − q_1) = 0 at {act} active ends: {res:.1e}; natural Δ_(1,2)p = 0 at {inact} inactive ends: {natural:.1e} (relative to max|Hp|; three open curves, d = 2, 3)"),
    )
    .against(Oracle::Property(
        "the end rows of ∂E/∂p from the definition of E (Δ_(1,2) by explicit divided differences), with the returned multipliers",
    )))
}

fn end_condition_printed() -> anyhow::Result<Outcome> {
    let (res, _, act, _) = end_condition(1.0)?;
    Ok(Outcome::check(
        if act > 0 { res } else { f64::NAN },
        super::KKT_TOL,
        format!("printed (1/h_1)Δ_(1,2)p + w_1(p_1 − q_1) with the multipliers of (3.5), relative to max|Hp|, worst over {act} active ends: {res:.3e}"),
    )
    .against(Oracle::Property(
        "the end rows of ∂E/∂p from the definition of E, with the returned multipliers",
    )))
}

/// The cases of this area.
pub fn cases() -> Vec<Case> {
    vec![
        Case::holds("kersey/3.5/tangent-balls-vs-clarabel", || {
            tangent_case("ball", "(3.9), Fig. 3.5a: |Df(t_(i_k)) − v_i| ≤ ε¹_i")
        }),
        Case::holds("kersey/3.5/tangent-wedges-vs-clarabel", || {
            tangent_case("wedge", "Fig. 3.5b: angle(Df, v_i) ≤ 0.15")
        }),
        Case::holds("kersey/3.5/tangent-tension-vs-clarabel", || {
            tangent_case("tension", "Fig. 3.5c: |Df| ≤ ε¹_i (tension)")
        }),
        Case::holds("kersey/3.5/tangent-halfspaces-vs-clarabel", || {
            tangent_case("halfspaces", "(3.10): n·Df ≤ c, piecewise-linear")
        }),
        Case::holds("kersey/3.6/clamped-vs-clarabel", || ends_case(false)),
        Case::holds("kersey/3.6/near-clamped-vs-clarabel", || ends_case(true)),
        Case::holds("kersey/3.6/natural-end-condition", end_condition_corrected),
        Case::fails(
            "kersey/3.6/printed-end-condition",
            "§3.6 prints ∂L = (1/h_1)Δ_(1,2)p + w_1(p_1 − q_1); with E of (2.1) and the multipliers of (3.5) the first term is (2/h_1)Δ_(1,2)p",
            end_condition_printed,
        ),
    ]
}
