//! Any bytes as `curvefit refine`'s JSON problem: parsed by `spec::from_json`, solved by
//! `spec::refine` when small enough to solve quickly, the result checked by the oracles.
#![no_main]
use curvefit::spec;
use libfuzzer_sys::fuzz_target;

/// Refined vertices above which a parsed problem is not solved (keeps executions fast; sizes
/// are refused or bounded by the library's own limits, tested elsewhere).
const MAX_VERTICES: usize = 4000;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match spec::from_json::<spec::RefineProblem>(text) {
        Err(e) => curvefit_fuzz::check_refusal(&e),
        Ok(p) => {
            let n = p.points.len();
            // each further level multiplies the vertices by level_k + 1
            let growth = (p.level_k + 1).saturating_pow(p.levels.min(8) as u32);
            let small = spec::refine::split_count(n, p.k, p.closed)
                .is_some_and(|v| v.saturating_mul(growth) <= MAX_VERTICES)
                && p.levels <= 2
                && p.knot_iterations <= 3;
            if !small {
                return;
            }
            match spec::refine(&p) {
                Ok(r) => curvefit_fuzz::check_refine(&p, &r),
                Err(e) => curvefit_fuzz::check_refusal(&e),
            }
        }
    }
});
