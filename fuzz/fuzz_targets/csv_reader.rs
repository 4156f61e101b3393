//! Any bytes as a CSV of points (`--points FILE.csv`): read with a small coordinate limit; a
//! table read is rectangular and finite, a refusal names a field.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match curvefit::cli::input::read_csv_limited(data, "points", 10_000) {
        Ok(csv) => {
            let p = &csv.points;
            assert!(
                p.coords().iter().all(|x| x.is_finite()),
                "non-finite coordinate read"
            );
            assert_eq!(p.coords().len(), p.len() * p.dim(), "ragged table");
            assert!(p.coords().len() <= 10_000, "limit not enforced");
        }
        Err(e) => {
            curvefit_fuzz::check_refusal(&e);
            assert!(
                !e.field.is_empty(),
                "a CSV refusal without a field: {}",
                e.message
            );
        }
    }
});
