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
        match spec::scheme(&p) {
            Ok(r) => {
                let v = serde_json::to_value(&r).expect("a result serializes");
                assert!(
                    !v.to_string().contains("null"),
                    "a non-finite number in {v}"
                );
            }
            Err(e) => curvefit_fuzz::check_refusal(&e),
        }
    }
    if let Ok(p) = spec::from_json::<spec::NaturalProblem>(text) {
        match spec::natural(&p) {
            Ok(r) => {
                let v = serde_json::to_value(&r).expect("a result serializes");
                assert!(
                    !v.to_string().contains("null"),
                    "a non-finite number in {v}"
                );
            }
            Err(e) => curvefit_fuzz::check_refusal(&e),
        }
    }
});
