//! Any bytes as `curvefit strip`'s JSON problem: parsed, solved when small, checked by the
//! oracles (interpolation, C², within bounds).
#![no_main]
use curvefit::spec;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match spec::from_json::<spec::StripProblem>(text) {
        Err(e) => curvefit_fuzz::check_refusal(&e),
        Ok(p) => {
            if p.t.len() > 2000 {
                return;
            }
            match spec::strip(&p) {
                Ok(s) => curvefit_fuzz::check_strip(&p, &s),
                Err(e) => curvefit_fuzz::check_refusal(&e),
            }
        }
    }
});
