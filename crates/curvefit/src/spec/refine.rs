//! `refine`: validation of the JSON problem, its mapping onto [`refine::Problem`] and the JSON
//! result ([`solve`]).

pub use super::refine_types::*;
use super::InputError;

/// Largest refined problem accepted: vertices × dimension of the final curve. A problem beyond it
/// is refused before any allocation (it would need gigabytes of memory and output).
pub const MAX_REFINED_COORDS: usize = 50_000_000;

/// Largest `knot_iterations` accepted: Algorithm 4.1's knot updates settle within a few
/// iterations (the seed uses "a few"); more is almost certainly a mistake and would only burn time.
pub const MAX_KNOT_ITERATIONS: usize = 100;

/// Number of vertices after a `k`-level split of `n` data points (open or closed), or `None` on
/// overflow.
pub fn split_count(n: usize, k: usize, closed: bool) -> Option<usize> {
    let spans = if closed { n } else { n.checked_sub(1)? };
    let v = spans.checked_mul(k.checked_add(1)?)?;
    if closed {
        Some(v)
    } else {
        v.checked_add(1)
    }
}

// The field names are built only for an error (a format! per coordinate cost more than the
// solve on large inputs).

fn finite(field: impl Fn() -> String, x: f64) -> Result<f64, InputError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(InputError::new(field(), "must be a finite number"))
    }
}

fn nonneg(field: impl Fn() -> String, x: f64) -> Result<f64, InputError> {
    let x = finite(&field, x)?;
    if x < 0.0 {
        return Err(InputError::new(
            field(),
            format!("must be ≥ 0, got {}", super::messages::num(x)),
        ));
    }
    Ok(x)
}

fn vector(field: impl Fn() -> String, v: &[f64], d: usize) -> Result<(), InputError> {
    if v.len() != d {
        return Err(InputError::new(
            field(),
            format!("has {} coordinates, expected {d}", v.len()),
        ));
    }
    for (j, &x) in v.iter().enumerate() {
        finite(|| format!("{}[{j}]", field()), x)?;
    }
    Ok(())
}

fn nonzero_vector(field: impl Fn() -> String, v: &[f64], d: usize) -> Result<(), InputError> {
    vector(&field, v, d)?;
    if v.iter().all(|&x| x == 0.0) {
        return Err(InputError::new(field(), "must be a non-zero vector"));
    }
    Ok(())
}

fn halfspace(field: String, h: &HalfSpaceSpec, d: usize) -> Result<(), InputError> {
    nonzero_vector(|| format!("{field}.normal"), &h.normal, d)?;
    finite(|| format!("{field}.offset"), h.offset)?;
    Ok(())
}

fn per_point_len(field: &str, got: usize, n: usize) -> Result<(), InputError> {
    if got != n {
        return Err(InputError::new(
            field,
            format!("has {got} entries, expected one per point ({n})"),
        ));
    }
    Ok(())
}

/// Checks everything that can be checked without solving; returns the dimension d.
///
/// # Errors
/// An [`InputError`] naming the first offending field and index.
pub fn validate(p: &RefineProblem) -> Result<usize, InputError> {
    let n = p.points.len();
    let min_n = if p.closed { 3 } else { 2 };
    if n < min_n {
        return Err(InputError::new(
            "points",
            format!(
                "{} curves need at least {min_n} points, got {n}",
                if p.closed { "closed" } else { "open" }
            ),
        ));
    }
    // Rows guarantee one dimension d ≥ 1 and finite coordinates.
    let d = p.points.dim();
    if let Some((i, j)) = p.points.coincident_span(p.closed) {
        return Err(InputError::new(
            format!("points[{j}]"),
            format!(
                "coincides with points[{i}] (consecutive points must differ: zero-length span)"
            ),
        ));
    }
    if let Some(t) = &p.knots {
        let want = if p.closed { n + 1 } else { n };
        if t.len() != want {
            return Err(InputError::new(
                "knots",
                format!("has {} values, expected {want}", t.len()),
            ));
        }
        for (i, &x) in t.iter().enumerate() {
            finite(|| format!("knots[{i}]"), x)?;
            if i > 0 && x <= t[i - 1] {
                return Err(InputError::new(
                    format!("knots[{i}]"),
                    "knots must be strictly increasing",
                ));
            }
        }
    }
    if let ParamSpec::Exponent(e) = p.parametrization {
        nonneg(|| "parametrization.exponent".into(), e)?;
    }
    if p.k == 0 {
        return Err(InputError::new("k", "must be at least 1"));
    }
    if p.knot_iterations > MAX_KNOT_ITERATIONS {
        return Err(InputError::new(
            "knot_iterations",
            format!(
                "must be at most {MAX_KNOT_ITERATIONS}, got {}",
                p.knot_iterations
            ),
        ));
    }
    if p.level_k == 0 {
        return Err(InputError::new("level_k", "must be at least 1"));
    }
    let too_large = |v: Option<usize>| v.is_none_or(|m| m.saturating_mul(d) > MAX_REFINED_COORDS);
    let mut vertices = split_count(n, p.k, p.closed);
    // (k alone past the limit names k: the levels are not to blame.)
    if too_large(vertices) {
        return Err(InputError::new(
            "k",
            format!(
                "{n} points with k = {} give a refined curve of more than {MAX_REFINED_COORDS} coordinates; lower k",
                p.k
            ),
        ));
    }
    for _ in 0..p.levels {
        vertices = vertices.and_then(|m| split_count(m, p.level_k, p.closed));
        if too_large(vertices) {
            break;
        }
    }
    if too_large(vertices) {
        return Err(InputError::new(
            "levels",
            format!("the refined curve would exceed {MAX_REFINED_COORDS} coordinates; lower k, levels or level_k"),
        ));
    }
    match &p.constraint {
        ConstraintSpec::Interpolate => {}
        ConstraintSpec::Balls { radii } => {
            per_point_len("constraint.radii", radii.len(), n)?;
            for (i, &r) in radii.iter().enumerate() {
                nonneg(|| format!("constraint.radii[{i}]"), r)?;
            }
        }
        ConstraintSpec::Smoothing { weights } => {
            per_point_len("constraint.weights", weights.len(), n)?;
            for (i, &w) in weights.iter().enumerate() {
                nonneg(|| format!("constraint.weights[{i}]"), w)?;
            }
        }
        ConstraintSpec::Halfspaces { sets } => {
            per_point_len("constraint.sets", sets.len(), n)?;
            for (i, set) in sets.iter().enumerate() {
                for (j, h) in set.iter().enumerate() {
                    halfspace(format!("constraint.sets[{i}][{j}]"), h, d)?;
                }
            }
        }
    }
    if let Some(tangents) = &p.tangents {
        per_point_len("tangents", tangents.len(), n)?;
        for (i, t) in tangents.iter().enumerate() {
            let f = format!("tangents[{i}]");
            match t {
                None => {}
                Some(TangentSpec::Ball { center, radius }) => {
                    vector(|| format!("{f}.center"), center, d)?;
                    nonneg(|| format!("{f}.radius"), *radius)?;
                }
                Some(TangentSpec::Wedge {
                    direction,
                    half_angle,
                }) => {
                    nonzero_vector(|| format!("{f}.direction"), direction, d)?;
                    let a = nonneg(|| format!("{f}.half_angle"), *half_angle)?;
                    if a >= std::f64::consts::FRAC_PI_2 {
                        return Err(InputError::new(
                            format!("{f}.half_angle"),
                            format!(
                                "must be below π/2 (a convex wedge), got {}",
                                super::messages::num(a)
                            ),
                        ));
                    }
                }
                Some(TangentSpec::Tension { radius }) => {
                    nonneg(|| format!("{f}.radius"), *radius)?;
                }
                Some(TangentSpec::Halfspaces { halfspaces }) => {
                    for (j, h) in halfspaces.iter().enumerate() {
                        halfspace(format!("{f}.halfspaces[{j}]"), h, d)?;
                    }
                }
            }
        }
    }
    match &p.boundary {
        BoundarySpec::Natural => {}
        _ if p.closed => {
            return Err(InputError::new(
                "boundary",
                "end conditions apply to open curves only (set \"closed\": false)",
            ))
        }
        BoundarySpec::Clamped { start, end } => {
            vector(|| "boundary.start".into(), start, d)?;
            vector(|| "boundary.end".into(), end, d)?;
        }
        BoundarySpec::NearClamped { start, end, radius } => {
            vector(|| "boundary.start".into(), start, d)?;
            vector(|| "boundary.end".into(), end, d)?;
            nonneg(|| "boundary.radius".into(), *radius)?;
        }
    }
    Ok(d)
}

/// Builds the library problem from the (validated) JSON problem.
///
/// # Errors
/// An [`InputError`] for points the library rejects.
pub fn to_library(p: &RefineProblem) -> Result<refine::Problem, InputError> {
    library(p.points.0.clone(), constraint(p.constraint.clone()), p)
}

/// [`to_library`] for a problem that is not needed afterwards: its points and the constraint's
/// arrays move into the library problem instead of being copied.
///
/// # Errors
/// As [`to_library`].
pub fn into_library(mut p: RefineProblem) -> Result<refine::Problem, InputError> {
    let points = std::mem::take(&mut p.points.0);
    let c = std::mem::replace(&mut p.constraint, ConstraintSpec::Interpolate);
    library(points, constraint(c), &p)
}

/// The library's constraint for the JSON's.
fn constraint(c: ConstraintSpec) -> refine::Constraint {
    match c {
        ConstraintSpec::Interpolate => refine::Constraint::Interpolate,
        ConstraintSpec::Balls { radii } => refine::Constraint::Balls(radii),
        ConstraintSpec::Smoothing { weights } => refine::Constraint::Smoothing(weights),
        ConstraintSpec::Halfspaces { sets } => refine::Constraint::HalfSpaces(
            sets.into_iter()
                .map(|set| set.iter().map(half_space).collect())
                .collect(),
        ),
    }
}

fn half_space(h: &HalfSpaceSpec) -> refine::HalfSpace {
    refine::HalfSpace {
        normal: h.normal.clone(),
        offset: h.offset,
    }
}

/// The library problem of `points` and `constraint` with every other field of `p`.
fn library(
    points: divdiff::Points,
    constraint: refine::Constraint,
    p: &RefineProblem,
) -> Result<refine::Problem, InputError> {
    use divdiff::{DerivativeRule, Parametrization, Topology};
    let mut prob = refine::Problem::new(points)
        .with_topology(if p.closed {
            Topology::Closed
        } else {
            Topology::Open
        })
        .with_parametrization(match p.parametrization {
            ParamSpec::Uniform => Parametrization::Uniform,
            ParamSpec::Centripetal => Parametrization::Centripetal,
            ParamSpec::Chordal => Parametrization::Chordal,
            ParamSpec::Exponent(e) => Parametrization::Exponent(e),
        })
        .with_k(p.k)
        .with_knot_iterations(p.knot_iterations)
        .with_levels(p.levels, p.level_k)
        .with_constraint(constraint)
        .with_derivative(match p.derivative {
            DerivativeSpec::Average => DerivativeRule::Average,
            DerivativeSpec::Bessel => DerivativeRule::Bessel,
        })
        .with_boundary(match &p.boundary {
            BoundarySpec::Natural => refine::Boundary::Natural,
            BoundarySpec::Clamped { start, end } => refine::Boundary::Clamped {
                start: start.clone(),
                end: end.clone(),
            },
            BoundarySpec::NearClamped { start, end, radius } => refine::Boundary::NearClamped {
                start: start.clone(),
                end: end.clone(),
                radius: *radius,
            },
        })
        .with_solver(match p.solver {
            SolverSpec::Exact => refine::Solver::Exact,
            SolverSpec::Paper => refine::Solver::Paper,
        });
    if let Some(t) = &p.knots {
        prob = prob.with_knots(t.clone());
    }
    if let Some(tangents) = &p.tangents {
        prob = prob.with_tangents(
            tangents
                .iter()
                .map(|t| {
                    t.as_ref().map(|t| match t {
                        TangentSpec::Ball { center, radius } => refine::Tangent::Ball {
                            center: center.clone(),
                            radius: *radius,
                        },
                        TangentSpec::Wedge {
                            direction,
                            half_angle,
                        } => refine::Tangent::Wedge {
                            direction: direction.clone(),
                            half_angle: *half_angle,
                        },
                        TangentSpec::Tension { radius } => {
                            refine::Tangent::Tension { radius: *radius }
                        }
                        TangentSpec::Halfspaces { halfspaces } => {
                            refine::Tangent::HalfSpaces(halfspaces.iter().map(half_space).collect())
                        }
                    })
                })
                .collect(),
        );
    }
    Ok(prob)
}

/// Converts the library's refinement into the JSON result.
pub fn to_result(r: refine::Refinement) -> RefineResult {
    RefineResult {
        points: Rows(r.points),
        knots: r.knots.into_values(),
        data_vertex: r.data_vertex,
        energy: r.energy,
        multipliers: r.multipliers,
        active: r.active,
        kkt_residual: r.kkt_residual,
        iterations: RefineIterations {
            knot_updates: r.iterations.knot_updates,
            solver: r.iterations.solver,
            solves: r.iterations.solves,
        },
    }
}

/// `curvefit refine`: validates the problem, solves it with [`refine::Problem::solve`] and returns
/// the JSON result.
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn solve(problem: &RefineProblem) -> Result<RefineResult, InputError> {
    solve_observed(problem, None)
}

/// [`solve`], telling `progress` (when given) of each fixed-knot solve and solver iteration.
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn solve_observed(
    problem: &RefineProblem,
    progress: Option<refine::Observer>,
) -> Result<RefineResult, InputError> {
    validate(problem)?;
    let mut prob = to_library(problem)?;
    prob.options.progress = progress;
    run(prob)
}

/// [`solve`] for a problem that is not needed afterwards: its arrays move into the solve
/// instead of being copied (the Python package's calls).
///
/// # Errors
/// As [`solve`].
pub fn solve_owned(problem: RefineProblem) -> Result<RefineResult, InputError> {
    validate(&problem)?;
    run(into_library(problem)?)
}

/// Solves a validated problem's library form and words the result (or the error) as the JSON's.
fn run(prob: refine::Problem) -> Result<RefineResult, InputError> {
    use super::messages::num;
    prob.solve().map(to_result).map_err(|e| match e {
        refine::Error::NotConverged {
            solver,
            iterations,
            residual,
        } => match tiny_ball(&prob) {
            Some(ball) => tiny_ball_refusal(ball, "", solver, iterations, residual),
            None => match derivative_field(&prob) {
                Some(field) => InputError::new(
                    field,
                    format!(
                        "{solver} did not converge in {iterations} iterations (best residual {}, accepted at most {}): derivative constraints are not always certified on very unequal spacing, nor a narrow wedge where the optimal derivative vanishes (the wedge's apex); loosen them (a wider half_angle, a larger radius, a near_clamped end instead of a clamped one) or constrain fewer points",
                        num(residual),
                        num(prob.options.accept_kkt)
                    ),
                ),
                None => data_constraint_refusal(solver, iterations, residual, prob.options.accept_kkt),
            },
        },
        // The solve before the update was certified; a tiny ball is still the likelier cause
        // than the spans (a sweep's case of ROBUSTNESS.md §4, item 20, whose first solve the
        // polish of item 33 certifies and whose first update it does not), and radius 0
        // removes it at every update.
        e @ refine::Error::NotConvergedAfterUpdate {
            update,
            solver,
            iterations,
            residual,
            ..
        } => match tiny_ball(&prob) {
            Some(ball) => tiny_ball_refusal(
                ball,
                &format!(
                    "after knot update {update} (the solve before it was certified: knot_iterations {} stops there), ",
                    update - 1
                ),
                solver,
                iterations,
                residual,
            ),
            None => user_error(e),
        },
        // The spread of the spans comes from the knot updates, the given knots, or the points'
        // spacing under the parametrization: the field the user can change.
        e @ refine::Error::SpansTooUnequal { .. } => {
            let (field, advice) = if prob.knot_iterations > 0 {
                ("knot_iterations", "each knot update makes the spans more unequal where the points cluster or the curve nearly stops: use fewer knot updates")
            } else if prob.knots.is_some() {
                ("knots", "give knots whose spans are less unequal")
            } else {
                ("points", "points far closer together than their neighbours make such spans: thin the cluster, or use a parametrization with a smaller exponent (uniform)")
            };
            InputError::new(field, format!("{e}; {advice}"))
        }
        e => user_error(e),
    })
}

/// The field of the derivative constraints that send a problem to the general interior-point
/// method (`tangents` when any point has a tangent set, else `boundary` for end conditions),
/// named when that method does not certify it: every such refusal of the sweeps had them
/// (ROBUSTNESS.md §4, items 14, 15 and 22), and loosening them is what the user can do.
fn derivative_field(prob: &refine::Problem) -> Option<&'static str> {
    if prob
        .tangents
        .as_ref()
        .is_some_and(|t| t.iter().any(Option::is_some))
    {
        Some("tangents")
    } else if prob.boundary != refine::Boundary::Natural {
        Some("boundary")
    } else {
        None
    }
}

/// The refusal of a first solve with data constraints alone (no derivative constraint, no
/// tiny ball) that no entry of the exact solver certified. It was the library's line with no
/// field and the residual in full ("full-vertex interior point (strict) did not converge in 21
/// iterations (best residual 4.708806638834959e-5)", ROBUSTNESS.md §4, item 38).
fn data_constraint_refusal(
    solver: &str,
    iterations: usize,
    residual: f64,
    accept: f64,
) -> InputError {
    use super::messages::num;
    InputError::new(
        "constraint",
        format!(
            "{solver} did not converge in {iterations} iterations (best residual {}, accepted at most {}): not a statement that the constraints contradict each other; very unequal spacing of the points (or of their parameter spans) can cause it: another parametrization, fewer intermediate points (k) or fewer knot updates may help",
            num(residual),
            num(accept)
        ),
    )
}

/// Radii below this fraction of the data's extent are named when a ball problem is not
/// certified ([`run`]): a known cause of such refusals (ROBUSTNESS.md §4, items 3 and 20: one
/// radius of 1e-8 among radii of 0.3 on points 5 apart is refused, radius 0 solves).
const TINY_RADIUS: f64 = 1e-6;

/// The refusal naming a tiny ball ([`tiny_ball`]: its index, radius and the data's extent) after
/// `when` (where the solve failed; empty for the first solve) and the solver's report.
fn tiny_ball_refusal(
    (i, r, extent): (usize, f64, f64),
    when: &str,
    solver: &str,
    iterations: usize,
    residual: f64,
) -> InputError {
    use super::messages::num;
    InputError::new(
        format!("constraint.radii[{i}]"),
        format!(
            "{when}{solver} did not converge in {iterations} iterations (best residual {}); this radius, {}, is {} of the data's extent, and a ball that small is a stiff spring (its force over its radius) that the solver may not balance to its certificate: give that point radius 0 to interpolate it exactly, or a larger radius",
            num(residual),
            num(r),
            num(r / extent)
        ),
    )
}

/// The smallest positive ball radius, its index and the data's extent (the largest side of their
/// bounding box), when that radius is below [`TINY_RADIUS`] of the extent.
fn tiny_ball(prob: &refine::Problem) -> Option<(usize, f64, f64)> {
    let refine::Constraint::Balls(radii) = &prob.constraint else {
        return None;
    };
    let (i, &r) = radii
        .iter()
        .enumerate()
        .filter(|(_, r)| **r > 0.0)
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    let p = &prob.points;
    let extent = (0..p.dim())
        .map(|c| {
            let (lo, hi) = p
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                    (lo.min(x[c]), hi.max(x[c]))
                });
            hi - lo
        })
        .fold(0.0f64, f64::max);
    (r < TINY_RADIUS * extent).then_some((i, r, extent))
}

/// A library field and index as the JSON's path: `tangents.direction` at 1 is
/// `tangents[1].direction`, `radii` at 2 `constraint.radii[2]`.
fn path(field: &str, index: usize) -> String {
    match field.split_once('.') {
        Some(("tangents", rest)) => format!("tangents[{index}].{rest}"),
        Some(("boundary", _)) => field.to_string(),
        _ => match field {
            "radii" | "weights" | "sets" => format!("constraint.{field}[{index}]"),
            _ => format!("{field}[{index}]"),
        },
    }
}

/// A half-space set's JSON path: `tangents[i].halfspaces` or `constraint.sets[i]`.
fn set_path(field: &str, point: usize) -> String {
    if field.starts_with("tangents") {
        format!("tangents[{point}].halfspaces")
    } else {
        format!("constraint.sets[{point}]")
    }
}

/// The user's view of a library error: the JSON field and index it concerns (module docs of
/// `refine::Error` for the variants), and what is wrong in words.
fn user_error(e: refine::Error) -> InputError {
    use refine::Error as E;
    let whole = |field: &str| match field {
        "radii" | "weights" | "sets" => format!("constraint.{field}"),
        f => f.to_string(),
    };
    match e {
        E::TooLarge { field, limit } => InputError::new(
            field,
            format!("the first stage would exceed {limit} coordinates, the limit of the general interior-point solver (tangents, end conditions, half-spaces); lower k"),
        ),
        E::TooFewPoints { .. } => InputError::new("points", e),
        E::CoincidentPoints { next, .. } => InputError::new(format!("points[{next}]"), e),
        E::WrongLength {
            field,
            expected,
            got,
        } => InputError::new(
            whole(field),
            format!("has {got} entries, expected {expected}"),
        ),
        E::WrongDimension {
            field,
            index,
            expected,
            got,
        } => InputError::new(
            path(field, index),
            format!("has {got} coordinates, expected {expected}"),
        ),
        E::InvalidValue {
            field,
            index,
            reason,
            ..
        } => InputError::new(path(field, index), reason),
        E::InvalidParameter { field, reason, .. } => InputError::new(whole(field), reason),
        E::InvalidHalfSpace {
            field,
            point,
            index,
            reason,
        } => InputError::new(format!("{}[{index}]", set_path(field, point)), reason),
        E::EmptySet {
            field,
            point,
            half_spaces,
        } => {
            let list: Vec<String> = half_spaces.iter().map(usize::to_string).collect();
            InputError::new(
                set_path(field, point),
                format!("is empty: its half-spaces {} have no common point (an exact Farkas certificate: positive multiples of their normals sum to zero while the same multiples of their offsets sum below zero); each normal points out of the set: check their orientation", list.join(", ")),
            )
        }
        E::InvalidKnots { index, reason } => InputError::new(format!("knots[{index}]"), reason),
        E::TooFewWeights { needed, got } => InputError::new(
            "constraint.weights",
            format!("at least {needed} weights must be positive, got {got}"),
        ),
        E::DegenerateRefinedSpan { .. } => InputError::new(
            "knot_iterations",
            format!("{e}; the refined curve doubles back on itself: use knot_iterations 0"),
        ),
        // Certified before the update, not after it: fewer updates solve (stage 0 with
        // `update` − 1 of them is the same computation up to the certified solve).
        E::NotConvergedAfterUpdate { stage, update, .. } => {
            let advice = if stage == 0 && update > 1 {
                format!("use knot_iterations {} or fewer", update - 1)
            } else if stage == 0 {
                "use knot_iterations 0".to_string()
            } else {
                "use fewer knot updates, or knot_iterations 0".to_string()
            };
            InputError::new(
                "knot_iterations",
                format!("{e}: each knot update makes the refined spans more unequal where the points cluster or the curve nearly stops; {advice}"),
            )
        }
        E::InfeasibleConstraint { field, point } => InputError::new(
            constraint_field(field, point),
            "cannot be satisfied together with the other constraints",
        ),
        E::EndConflict { end, point, gap } => {
            let (side, vertex) = if end == 0 {
                ("start", "first")
            } else {
                ("end", "last")
            };
            InputError::new(
                format!("tangents[{point}]"),
                format!("cannot hold together with boundary.{side}: both constrain the derivative Df at the curve's {vertex} vertex, and their sets are {gap:.3e} apart, so no curve meets both; loosen one of them (a near_clamped end with a larger radius, a larger tangent radius, a wider half_angle) or drop it"),
            )
        }
        E::NoFeasiblePointFound {
            field,
            point,
            violation,
            iterations,
        } => InputError::new(
            constraint_field(field, point),
            format!("the exact solver found no point meeting every constraint in {iterations} iterations, and this one was the most violated where it stopped (relative violation {violation:.2e}); this is not a proof that the constraints contradict each other: check this constraint against its neighbours' (a tangent set against an end condition at the same point, say), or loosen it"),
        ),
        E::Unsupported { field, reason } => InputError::new(whole(field), reason),
        // The linear algebra failed on valid input: the data's scale (or the spread of the
        // spans) is beyond what the floating-point solve resolves.
        E::Energy(_) | E::Divdiff(_) | E::NonFiniteInput { .. } => InputError::new(
            "points",
            format!("{e}: the points (or their parameter spans) are too badly scaled for a floating-point solve; rescale the points or use fewer intermediate points (k)"),
        ),
        e => InputError::new("", e),
    }
}

/// The problem's field of a constraint named by the library (`"sets"`, `"radii"`, `"tangents"`,
/// `"boundary"`, …) at data point `point` (for `"boundary"`: 0 = start, 1 = end).
fn constraint_field(field: &str, point: usize) -> String {
    match field {
        "boundary" => ["boundary.start", "boundary.end"][point.min(1)].to_string(),
        "tangents" => format!("tangents[{point}]"),
        f => format!("constraint.{f}[{point}]"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(json: &str) -> RefineProblem {
        super::super::from_json(json).unwrap()
    }

    #[test]
    fn a_data_constraint_refusal_names_the_constraint_and_reads_its_numbers() {
        let e =
            data_constraint_refusal("full-vertex interior point", 21, 4.708806638834959e-5, 1e-9);
        assert_eq!(e.field, "constraint");
        assert!(
            e.message.starts_with(
                "full-vertex interior point did not converge in 21 iterations (best residual 4.70881e-5, accepted at most 1e-9): "
            ),
            "{}",
            e.message
        );
    }

    /// A problem solved by value (its arrays moved) and by reference (copied) gives the same
    /// result and the same errors, for every kind of constraint.
    #[test]
    fn solving_a_moved_problem_equals_solving_a_borrowed_one() {
        let texts = [
            r#"{"points": [[0,0],[1,0.2],[2,1],[1,2],[0,1.5]], "closed": true, "k": 3}"#,
            r#"{"points": [[0,0],[1,0.2],[2,1],[1,2],[0,1.5]], "k": 2, "constraint": {"type": "balls", "radii": [0.1, 0.3, 0, 0.2, 0.05]}}"#,
            r#"{"points": [[0,0],[1,0.2],[2,1],[1,2],[0,1.5]], "k": 2, "constraint": {"type": "smoothing", "weights": [1, 10, 100, 5, 2]}}"#,
            r#"{"points": [[0,0],[1,0.2],[2,1]], "k": 2, "constraint": {"type": "halfspaces", "sets": [[], [{"normal": [0, 1], "offset": 0.1}], []]}}"#,
            r#"{"points": [[0,0],[1,0.2],[2,1],[1,2]], "k": 2, "constraint": {"type": "balls", "radii": [0.1, -1, 0, 0.2]}}"#,
        ];
        for text in texts {
            let p = problem(text);
            let json = |r: Result<RefineResult, InputError>| match r {
                Ok(r) => serde_json::to_string(&r).unwrap(),
                Err(e) => format!("{e}"),
            };
            let borrowed = json(solve(&p));
            assert_eq!(json(solve_owned(p)), borrowed, "{text}");
        }
    }

    #[test]
    fn split_counts_match_3_1() {
        assert_eq!(split_count(5, 3, true), Some(20));
        assert_eq!(split_count(5, 3, false), Some(17));
        assert_eq!(split_count(usize::MAX, 3, true), None);
    }

    #[test]
    fn validation_names_fields_and_indices() {
        let cases = [
            (r#"{"points": [[0,0],[1,0]], "closed": true}"#, "points"),
            (r#"{"points": [[0,0]]}"#, "points"),
            (r#"{"points": [[0,0],[1,0],[1,0]]}"#, "points[2]"),
            (r#"{"points": [[0,0],[1,0],[0]]}"#, "points[2]"),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "closed": true, "knots": [0,1,1,2]}"#,
                "knots[2]",
            ),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "closed": true, "knots": [0,1,2]}"#,
                "knots",
            ),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "knots": [0,1,2,3]}"#,
                "knots",
            ),
            (r#"{"points": [[0,0],[1,0],[0,1]], "k": 0}"#, "k"),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "constraint": {"type": "balls", "radii": [1,-1,1]}}"#,
                "constraint.radii[1]",
            ),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "constraint": {"type": "balls", "radii": [1,1]}}"#,
                "constraint.radii",
            ),
            (r#"{"points": [[0,0],[1,0],[0,1]], "levels": 40}"#, "levels"),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "tangents": [null, {"type": "wedge", "direction": [0,0], "half_angle": 0.1}, null]}"#,
                "tangents[1].direction",
            ),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "closed": true, "boundary": {"type": "clamped", "start": [1,0], "end": [1,0]}}"#,
                "boundary",
            ),
            (
                r#"{"points": [[0,0],[1,0],[0,1]], "closed": false, "boundary": {"type": "clamped", "start": [1], "end": [1,0]}}"#,
                "boundary.start",
            ),
        ];
        for (json, field) in cases {
            let e = match super::super::from_json::<RefineProblem>(json) {
                Ok(p) => validate(&p).unwrap_err(),
                Err(e) => e,
            };
            assert_eq!(e.field, field, "{json}: {e}");
        }
        assert_eq!(
            validate(&problem(r#"{"points": [[0,0],[1,0],[0,1]]}"#)),
            Ok(2)
        );
    }
}
