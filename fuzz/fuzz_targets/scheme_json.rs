//! Any bytes as the JSON problems of `curvefit scheme` and `natural`: parsed and applied; every
//! returned coordinate must be finite.
#![no_main]
use curvefit::spec;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(p) = spec::from_json::<spec::SchemeProblem>(text) {
        curvefit_fuzz::check_finite_or_refused(&spec::scheme(&p));
    }
    if let Ok(p) = spec::from_json::<spec::NaturalProblem>(text) {
        curvefit_fuzz::check_finite_or_refused(&spec::natural(&p));
    }
});
