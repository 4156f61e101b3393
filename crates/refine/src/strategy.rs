//! The exact solver of one fixed-knot problem: an ordered list of strategies.
//!
//! Each entry of [`EXACT`] says what is tried, when it applies and why it stands where it does.
//! [`exact`] runs the entries that apply, in order: each attempt is certified independently
//! ([`crate::certify`]) and returned as soon as its certificate is at most
//! [`crate::SolveOptions::accept_kkt`]; otherwise the best attempt so far is handed to the next
//! entry (the full-vertex backend starts from its curve). When no entry is certified the solve
//! refuses with [`Error::NotConverged`] naming the entry that came closest and its certificate;
//! when none produced a curve at all, with the first error met (an empty polytope, a singular
//! system).
//!
//! | # | entry | applies to | why |
//! |---|---|---|---|
//! | 1 | linear solve | interpolation, smoothing, balls of radius 0; no derivative constraint | a linear system: one banded solve and a step of iterative refinement, exact to rounding where the spans are even (certified with the stage; a smoothing stage refused is solved again with refinement to rounding, `linear::CONVERGED_STEPS`) |
//! | 2 | linear solve with clamped ends | interpolation, smoothing, balls of radius 0 with clamped ends and no tangent set (`Problem::linear_clamped_ends`), first stage | an equality-constrained quadratic: a bordered system ([`crate::linear::clamped`]), one banded factorization and three solves refined in difference form, or for long interpolations interpolation's own solve and two on 64 spans at the ends — where the interior-point method took a solve per iteration and was held to its size limit |
//! | 3 | condensed working set | data-vertex sets alone (balls, half-spaces): no derivative constraint, enough constrained points | only the constrained data vertices are variables (O(n) per iteration), on a working set of the active ones; an answer not accepted goes on from its last iterate to the strict tolerance of 4 (starting 4 over took half of a solve with points in boxes of half-spaces) |
//! | 4 | condensed working set (strict) | as 3 | an active set read off at the default tolerance is sometimes not settled enough for the polish |
//! | 5 | full-vertex interior point | every kind, first stages up to [`crate::MAX_CONIC_COORDS`] coordinates | derivative stencils and end conditions act on free vertices; the fallback of 2–4; an answer refine's certificate refuses is polished once more, holding blocks at their apex, and as a last attempt solved again with the method's force floor at the rounding level where the certificate resolves the stiffest vertices (`ConicProblem::solve_judged`) |
//! | 6 | full-vertex interior point (strict) | as 5 | the method's gap measure is relative to the energy: many small balls need a stricter target |

use divdiff::Points;

use crate::backend::working_set;
use crate::certify::{certify, Certificate};
use crate::conic_problem::{ConicOptions, ConicSolution};
use crate::constraint::Rows;
use crate::operator::Stencil;
use crate::stage::{FixedProblem, FixedSolution};
use crate::Error;

/// One entry of the strategy list (module docs).
pub(crate) struct Strategy {
    /// What is tried.
    pub name: &'static str,
    /// When it applies.
    pub applies: fn(&FixedProblem<'_>) -> bool,
    /// Why it is there (the module docs' table says the same; a test keeps them together).
    #[cfg_attr(not(test), allow(dead_code))]
    pub why: &'static str,
    /// Whether its results are exact by construction (a linear solve): accepted without a
    /// certificate here; the stage's certificate judges the final one.
    pub exact_by_construction: bool,
    /// The attempt, given the best earlier attempt.
    pub run: fn(&FixedProblem<'_>, Option<&FixedSolution>) -> Result<FixedSolution, Error>,
}

/// The list, in order (module docs).
pub(crate) const EXACT: [Strategy; 6] = [
    Strategy {
        name: "linear solve",
        applies: |fp| fp.kinds().iter().all(|k| k.linear()),
        why: "interpolation and smoothing are linear systems: one banded solve, exact to rounding",
        exact_by_construction: true,
        run: |fp, _| crate::linear::solve(fp, 1),
    },
    Strategy {
        name: "linear solve with clamped ends",
        applies: |fp| fp.derivatives && fp.problem.linear_clamped_ends().is_some(),
        why: "interpolation and smoothing with clamped ends are an equality-constrained quadratic: one banded factorization, three solves",
        exact_by_construction: false,
        run: |fp, _| crate::linear::clamped(fp),
    },
    Strategy {
        name: "condensed working set",
        applies: |fp| condensed_sets(fp).is_some(),
        why: "data-vertex sets alone: only the constrained data vertices are variables, on a working set",
        exact_by_construction: false,
        run: |fp, _| condensed(fp, fp.options.conic.tolerance),
    },
    Strategy {
        name: "condensed working set (strict)",
        applies: |fp| condensed_sets(fp).is_some(),
        why: "an active set read off at the default tolerance is sometimes not settled enough for the polish",
        exact_by_construction: false,
        run: |fp, _| condensed(fp, fp.options.strict_tolerance),
    },
    Strategy {
        name: "full-vertex interior point",
        applies: full_applies,
        why: "every kind, derivative stencils included; the fallback of the condensed entries",
        exact_by_construction: false,
        run: |fp, from| full(fp, fp.options.conic.tolerance, from),
    },
    Strategy {
        name: "full-vertex interior point (strict)",
        applies: full_applies,
        why: "the duality gap is measured against the energy, which many small balls make tiny",
        exact_by_construction: false,
        run: |fp, from| full(fp, fp.options.strict_tolerance, from),
    },
];

/// The full-vertex entries apply up to the size limit of the first stage (beyond it one solve
/// takes minutes: `Problem::validate` refuses such problems when they need this backend).
fn full_applies(fp: &FixedProblem<'_>) -> bool {
    fp.knots.vertex_count().saturating_mul(fp.q.dim()) <= crate::MAX_CONIC_COORDS
}

/// The certificate of a solution (computed unless the solver already did).
pub(crate) fn certificate(
    fp: &FixedProblem<'_>,
    sol: &FixedSolution,
) -> (Certificate, crate::Multipliers) {
    if let Some(c) = &sol.certificate {
        return c.clone();
    }
    certify(
        fp.knots,
        &sol.points,
        fp.q,
        fp.data_vertex,
        &fp.kinds(),
        sol.multipliers.clone(),
        &sol.derivative,
        fp.problem.derivative,
        fp.options.active_rtol,
    )
}

/// Solves the fixed-knot problem exactly (module docs).
///
/// # Errors
/// [`Error::NotConverged`] with the best certificate when no entry reaches the acceptance level;
/// the first error met when no entry produced a curve.
pub(crate) fn exact(fp: &FixedProblem<'_>) -> Result<FixedSolution, Error> {
    let accept = fp.options.accept_kkt;
    let mut best: Option<(f64, FixedSolution, &'static str)> = None;
    let mut first_error: Option<Error> = None;
    let mut iterations = 0;
    for s in EXACT.iter().filter(|s| (s.applies)(fp)) {
        match (s.run)(fp, best.as_ref().map(|b| &b.1)) {
            Ok(mut sol) => {
                iterations += sol.iterations;
                if s.exact_by_construction {
                    sol.iterations = iterations;
                    return Ok(sol);
                }
                let (cert, mult) = certificate(fp, &sol);
                let k = cert.kkt_residual;
                sol.certificate = Some((cert, mult));
                if k <= accept {
                    sol.iterations = iterations;
                    return Ok(sol);
                }
                if best.as_ref().is_none_or(|b| k < b.0 || b.0.is_nan()) {
                    best = Some((k, sol, s.name));
                }
            }
            Err(e) => {
                // An entry that fails only hands over to the next; an infeasible constraint is
                // a fact about the data and ends the search.
                if matches!(e, Error::InfeasibleConstraint { .. }) {
                    return Err(e);
                }
                first_error.get_or_insert(e);
            }
        }
    }
    match (best, first_error) {
        // An attempt that got somewhere names the shortfall; one nowhere near a solution (a
        // residual of 1 or more) says less than the error an earlier entry met (a singular
        // system).
        (Some((residual, _, _)), Some(e)) if residual.is_nan() || residual >= 1.0 => Err(e),
        (Some((residual, _, solver)), _) => Err(Error::NotConverged {
            solver,
            iterations,
            residual,
        }),
        (None, Some(e)) => Err(e),
        (None, None) => Err(Error::Unsupported {
            field: "k",
            reason: "no exact solver applies to a problem of this size",
        }),
    }
}

/// The data kind's point sets for the condensed backend, when it applies: no derivative
/// constraint, a set at every point the condensation must start at (point 0, and the last of an
/// open curve), and enough constrained points for its data rows (two on a closed curve — one
/// would couple its row to itself — three on an open one, whose end rows are zero).
fn condensed_sets(
    fp: &FixedProblem<'_>,
) -> Option<Vec<Option<crate::backend::condensed::PointSet>>> {
    if fp.has_derivatives() {
        return None;
    }
    let sets = fp.constraint.kind().point_sets(fp)?;
    let n = sets.len();
    let constrained = sets.iter().filter(|s| s.is_some()).count();
    let enough = if fp.knots.is_closed() {
        constrained >= 2
    } else {
        constrained >= 3 && sets[n - 1].is_some()
    };
    (sets[0].is_some() && enough).then_some(sets)
}

/// The condensed working-set method at `tolerance`, certified inside (its judge).
fn condensed(fp: &FixedProblem<'_>, tolerance: f64) -> Result<FixedSolution, Error> {
    let sets = condensed_sets(fp).ok_or(Error::Unsupported {
        field: "constraint",
        reason: "the condensed method needs data-vertex sets alone",
    })?;
    let stencil = Stencil::new(fp.knots);
    let kinds = fp.kinds();
    let opts = fp.options.conic.clone().with_tolerance(tolerance);
    let mut judge = |p: &Points, m: &[Vec<f64>]| {
        let (cert, mult) = certify(
            fp.knots,
            p,
            fp.q,
            fp.data_vertex,
            &kinds,
            Some(m.to_vec()),
            &[],
            fp.problem.derivative,
            fp.options.active_rtol,
        );
        (cert.kkt_residual, (cert, mult))
    };
    let setting = working_set::Setting {
        knots: fp.knots,
        stencil: &stencil,
        q: fp.q,
        sets: &sets,
        stride: fp.stride,
        conic: &opts,
    };
    let sol = working_set::solve(
        &setting,
        &fp.options.working_set,
        fp.warm,
        &mut judge,
        working_set::Aim {
            target: fp.options.polish_above,
            accept: fp.options.accept_kkt,
            strict: Some(fp.options.strict_tolerance),
        },
        fp.options.progress.as_ref(),
    )?;
    Ok(FixedSolution {
        certificate: Some(sol.certificate),
        ..FixedSolution::new(sol.points, Some(sol.multipliers), sol.iterations)
    })
}

/// The full-vertex backend at `tolerance`, started from `from`'s curve when given.
fn full(
    fp: &FixedProblem<'_>,
    tolerance: f64,
    from: Option<&FixedSolution>,
) -> Result<FixedSolution, Error> {
    let mut rows = Rows::new(fp)?;
    for k in fp.kinds() {
        k.rows(fp, &mut rows)?;
    }
    let mut opts = ConicOptions {
        conic: fp.options.conic.clone().with_tolerance(tolerance),
        progress: fp.options.progress.clone(),
        ..ConicOptions::default()
    };
    if let Some(f) = from {
        opts.warm_start = Some(f.points.clone());
    }
    // The solution in this crate's terms, with its certificate (the judge of the method's
    // answer: `ConicProblem::solve_judged`).
    let fixed = |sol: &ConicSolution| {
        let hp = crate::operator::apply_h(fp.knots, &sol.points);
        let multipliers = fp.constraint.kind().multipliers(fp, sol, &rows, &hp);
        let derivative = rows
            .derivative
            .iter()
            .map(|(c, _)| (sol.cone_duals[*c].clone(), sol.forces[*c].clone()))
            .collect();
        let mut out = FixedSolution {
            derivative,
            ..FixedSolution::new(sol.points.clone(), Some(multipliers), sol.iterations)
        };
        out.certificate = Some(certificate(fp, &out));
        out
    };
    let (sol, fixed): (ConicSolution, FixedSolution) = rows
        .problem
        .solve_judged(&opts, |sol| {
            let f = fixed(sol);
            let accepted = f
                .certificate
                .as_ref()
                .is_some_and(|(c, _)| c.kkt_residual <= fp.options.accept_kkt);
            (accepted, f)
        })
        .map_err(|e| rows.user_error(e))?;
    if sol.kkt.total.is_nan() || sol.kkt.total > fp.options.accept_kkt {
        // Not converged: perhaps because nothing is feasible.
        if let Some(e) = rows.problem.diagnose(&sol) {
            return Err(rows.user_error(e));
        }
    }
    Ok(fixed)
}

#[cfg(test)]
mod tests {
    /// The module docs' table and the list agree: every entry's name is in it, in order.
    #[test]
    fn the_documented_table_is_the_list() {
        let docs = include_str!("strategy.rs");
        let mut at = 0;
        for s in &super::EXACT {
            let found = docs[at..].find(&format!("| {} |", s.name)).map(|i| i + at);
            assert!(
                found.is_some(),
                "{} not in the table after byte {at}",
                s.name
            );
            at = found.unwrap_or(at) + 1;
            assert!(!s.why.is_empty());
        }
    }
}
