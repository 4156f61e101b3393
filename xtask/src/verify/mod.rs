//! The verification suite: each identity, theorem and worked example of the seeds is a named
//! [`Case`]. A case either is expected to hold ([`Expect::Holds`]) or is a documented expected
//! failure ([`Expect::Fails`]) — e.g. the printed Lemma 2.4, which must *disagree* with finite
//! differences. The run ends with `N passed, N failed`, where "failed" counts unexpected outcomes,
//! and exits non-zero on any unexpected outcome or when no case ran.
//!
//! What counts as a pass (see `judge`): an error or a panic fails the case, expected failures
//! included; a NaN residual or tolerance fails it (cases fold their residuals with [`worst`],
//! which keeps NaN where `f64::max` would drop it); an expected failure must be *measured* — a
//! finite residual above a finite tolerance, or a flag — so an infinite residual (a case's way of
//! saying its precondition did not hold) fails it too. Every case names the independent
//! reference it compared with ([`Oracle`], printed in the table), and a passing case with a
//! tolerance ≥ [`LOOSE_TOLERANCE`] says why in [`Outcome::derived`]; both are enforced
//! (`REQUIRE_ORACLE`).

mod energy;
mod kersey_defs;
mod refine;
mod schemes;
mod strip;

/// What a case is expected to show.
#[derive(Clone, Copy, Debug)]
pub enum Expect {
    /// The check holds (residual within tolerance).
    Holds,
    /// The check is expected to fail, for the documented reason (e.g. a misprint in a seed). The
    /// run must *measure* the failure: an error, a panic or a NaN residual is a failure of the
    /// case, never an expected failure.
    Fails(&'static str),
}

/// The independent reference a case compares with. Every case names one (printed in the
/// table); a case whose reference is the code under test itself cannot fail and is not a check.
#[derive(Clone, Debug, PartialEq)]
pub enum Oracle {
    /// A closed form (the formula is in the detail line or the case's docs).
    ClosedForm,
    /// A number printed in the seed (table, example, figure caption).
    Seed,
    /// Finite differences of an independently evaluated function.
    FiniteDifferences,
    /// An independent solver (Clarabel, a dense solve, scipy).
    IndependentSolver(&'static str),
    /// Exact rational arithmetic.
    ExactRational,
    /// A structural or algebraic property checked directly (e.g. H = AᵀA entry by entry from
    /// the definitions); the detail line says which.
    Property(&'static str),
}

impl std::fmt::Display for Oracle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Oracle::ClosedForm => write!(f, "closed form"),
            Oracle::Seed => write!(f, "seed's printed value"),
            Oracle::FiniteDifferences => write!(f, "finite differences"),
            Oracle::IndependentSolver(s) => write!(f, "independent solver ({s})"),
            Oracle::ExactRational => write!(f, "exact rationals"),
            Oracle::Property(s) => write!(f, "property ({s})"),
        }
    }
}

/// Tolerances at or above this need a derivation in the outcome ([`Outcome::derived`]).
pub const LOOSE_TOLERANCE: f64 = 1e-4;

/// The measured outcome of one case.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Whether the check held.
    pub held: bool,
    /// The residual (or error) that decided it.
    pub residual: f64,
    /// The tolerance it was compared with.
    pub tol: f64,
    /// One line of context (what was compared with what).
    pub detail: String,
    /// The independent reference (required: see [`Oracle`]).
    pub oracle: Option<Oracle>,
    /// Why a tolerance ≥ [`LOOSE_TOLERANCE`] is the right one (a discretization bound, say).
    pub derivation: Option<String>,
}

impl Outcome {
    /// `held = residual <= tol` (NaN never holds).
    pub fn check(residual: f64, tol: f64, detail: impl Into<String>) -> Self {
        Outcome {
            held: residual <= tol,
            residual,
            tol,
            detail: detail.into(),
            oracle: None,
            derivation: None,
        }
    }
    /// An outcome decided by a boolean condition rather than a residual.
    pub fn flag(held: bool, detail: impl Into<String>) -> Self {
        Outcome {
            held,
            residual: if held { 0.0 } else { 1.0 },
            tol: 0.0,
            detail: detail.into(),
            oracle: None,
            derivation: None,
        }
    }
    /// Names the independent reference this outcome was compared with.
    pub fn against(mut self, oracle: Oracle) -> Self {
        self.oracle = Some(oracle);
        self
    }
    /// Says why a tolerance ≥ [`LOOSE_TOLERANCE`] is right (printed with the detail).
    pub fn derived(mut self, why: impl Into<String>) -> Self {
        self.derivation = Some(why.into());
        self
    }
}

/// The largest of `values`, NaN if any is NaN (unlike `f64::max`, which drops NaN), and 0 for
/// none. Use it for every residual fold so that a NaN anywhere fails the case.
pub fn worst(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut m: f64 = 0.0;
    for v in values {
        if v.is_nan() {
            return f64::NAN;
        }
        m = m.max(v);
    }
    m
}

/// A named verification case: `id` is stable (e.g. `kersey/thm2.1/energy-three-ways`).
pub struct Case {
    /// Stable identifier: `<seed>/<section>/<what>`.
    pub id: &'static str,
    /// Expected outcome.
    pub expect: Expect,
    /// The check itself. Errors and panics are failures of the case (also of expected failures).
    pub run: Box<dyn Fn() -> anyhow::Result<Outcome>>,
}

impl Case {
    /// A case expected to hold.
    pub fn holds(id: &'static str, run: impl Fn() -> anyhow::Result<Outcome> + 'static) -> Self {
        Case {
            id,
            expect: Expect::Holds,
            run: Box::new(run),
        }
    }
    /// A documented expected failure.
    pub fn fails(
        id: &'static str,
        reason: &'static str,
        run: impl Fn() -> anyhow::Result<Outcome> + 'static,
    ) -> Self {
        Case {
            id,
            expect: Expect::Fails(reason),
            run: Box::new(run),
        }
    }
}

/// Whether a case passed, and the label printed for it. A case passes when its outcome is the
/// expected one *and* it is a real check: it names its oracle, its residual is not NaN, and a
/// tolerance ≥ [`LOOSE_TOLERANCE`] comes with a derivation. An expected failure must be measured
/// (a finite residual above a finite tolerance, or a flag), not an error.
fn judge(expect: Expect, o: &Outcome, errored: bool) -> (bool, &'static str) {
    if errored {
        return (false, "ERROR");
    }
    if o.residual.is_nan() || o.tol.is_nan() {
        return (false, "NAN");
    }
    if o.oracle.is_none() && REQUIRE_ORACLE {
        return (false, "NO-ORACLE");
    }
    match expect {
        Expect::Holds => {
            if !o.held {
                (false, "FAIL")
            } else if o.tol >= LOOSE_TOLERANCE && o.derivation.is_none() && REQUIRE_ORACLE {
                (false, "LOOSE-TOL")
            } else {
                (true, "pass")
            }
        }
        Expect::Fails(_) => {
            if o.held {
                (false, "UNEXPECTED-PASS")
            } else if !(o.residual.is_finite() && o.tol.is_finite()) {
                // An infinite residual is how a case reports that its precondition failed (no
                // data point of the kind it needs): that is not a measured failure.
                (false, "UNMEASURED")
            } else {
                (true, "xfail")
            }
        }
    }
}

/// Whether a missing oracle or an underived loose tolerance fails a case: every case of the
/// suite complies, so it is on.
const REQUIRE_ORACLE: bool = true;

fn all_cases() -> Vec<Case> {
    let mut v = Vec::new();
    v.extend(energy::cases());
    v.extend(refine::cases());
    v.extend(schemes::cases());
    v.extend(strip::cases());
    v
}

/// Runs every case whose id contains `filter` (all when no filter is given).
pub fn run(args: &[String]) -> anyhow::Result<bool> {
    let filter = args.first().map(String::as_str).unwrap_or("");
    let cases: Vec<Case> = all_cases()
        .into_iter()
        .filter(|c| c.id.contains(filter))
        .collect();
    let (mut passed, mut failed) = (0usize, 0usize);
    println!(
        "{:<58} {:>11} {:>9}  {:<8} detail",
        "case", "residual", "tol", "outcome"
    );
    for case in &cases {
        let (outcome, errored) =
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (case.run)())) {
                Ok(Ok(o)) => (o, false),
                Ok(Err(e)) => (Outcome::check(f64::NAN, 0.0, format!("error: {e:#}")), true),
                Err(_) => (Outcome::check(f64::NAN, 0.0, "panicked"), true),
            };
        let (ok, label) = judge(case.expect, &outcome, errored);
        if ok {
            passed += 1;
        } else {
            failed += 1;
        }
        let mut detail = outcome.detail.clone();
        match &outcome.oracle {
            Some(o) => detail = format!("{detail} [oracle: {o}]"),
            None => detail = format!("{detail} [oracle: none named]"),
        }
        if let Some(why) = &outcome.derivation {
            detail = format!("{detail} [tolerance: {why}]");
        }
        if let Expect::Fails(reason) = case.expect {
            detail = format!("{detail} [expected failure: {reason}]");
        }
        println!(
            "{:<58} {:>11.3e} {:>9.1e}  {:<8} {}",
            case.id, outcome.residual, outcome.tol, label, detail
        );
    }
    println!("{passed} passed, {failed} failed");
    if cases.is_empty() {
        eprintln!("no verification case ran (filter {filter:?})");
        return Ok(false);
    }
    Ok(failed == 0)
}
