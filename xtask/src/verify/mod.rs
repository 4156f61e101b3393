//! The verification suite: each identity, theorem and worked example of the seeds is a named
//! [`Case`]. A case either is expected to hold ([`Expect::Holds`]) or is a documented expected
//! failure ([`Expect::Fails`]) — e.g. the printed Lemma 2.4, which must *disagree* with finite
//! differences. The run ends with `N passed, N failed`, where "failed" counts unexpected outcomes,
//! and exits non-zero on any unexpected outcome or when no case ran.

mod energy;
mod refine;
mod schemes;
mod strip;

/// What a case is expected to show.
#[derive(Clone, Copy, Debug)]
pub enum Expect {
    /// The check holds (residual within tolerance).
    Holds,
    /// The check is expected to fail, for the documented reason (e.g. a misprint in a seed).
    Fails(&'static str),
}

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
}

impl Outcome {
    /// `held = residual <= tol` (NaN never holds).
    pub fn check(residual: f64, tol: f64, detail: impl Into<String>) -> Self {
        Outcome {
            held: residual <= tol,
            residual,
            tol,
            detail: detail.into(),
        }
    }
    /// An outcome decided by a boolean condition rather than a residual.
    pub fn flag(held: bool, detail: impl Into<String>) -> Self {
        Outcome {
            held,
            residual: if held { 0.0 } else { 1.0 },
            tol: 0.0,
            detail: detail.into(),
        }
    }
}

/// A named verification case: `id` is stable (e.g. `kersey/thm2.1/energy-three-ways`).
pub struct Case {
    /// Stable identifier: `<seed>/<section>/<what>`.
    pub id: &'static str,
    /// Expected outcome.
    pub expect: Expect,
    /// The check itself. Errors count as "did not hold".
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

fn all_cases() -> Vec<Case> {
    let mut v = Vec::new();
    v.extend(energy::cases());
    v.extend(refine::cases());
    v.extend(refine::free_knot_cases());
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
        let outcome = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (case.run)()))
        {
            Ok(Ok(o)) => o,
            Ok(Err(e)) => Outcome {
                held: false,
                residual: f64::NAN,
                tol: 0.0,
                detail: format!("error: {e:#}"),
            },
            Err(_) => Outcome {
                held: false,
                residual: f64::NAN,
                tol: 0.0,
                detail: "panicked".into(),
            },
        };
        let (ok, label) = match case.expect {
            Expect::Holds => (outcome.held, if outcome.held { "pass" } else { "FAIL" }),
            Expect::Fails(_) => (
                !outcome.held,
                if outcome.held {
                    "UNEXPECTED-PASS"
                } else {
                    "xfail"
                },
            ),
        };
        if ok {
            passed += 1;
        } else {
            failed += 1;
        }
        let mut detail = outcome.detail.clone();
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
