//! A certified answer is the optimum, checked against a point of an independent solver.
//!
//! The fixture is case 250 of `xtask/sweeps/refine.py` seed 5, found by
//! `xtask/sweeps/optimality.py`: 20 open points near (1001, 1000) with extent 1.3, half-spaces
//! at 11 of them, centripetal-like knots with exponent 1.99, so the refined spans run from
//! 1.5e-6 to 0.54. The binary once answered it with E = 5.37e6 and a certificate of 8.3e-10:
//! the rounding floor of its stationarity test, 16 ε ‖H‖_∞ max|p|, is set by the stiffest row
//! of H (the 1.5e-6 spans) and by coordinates near 1e3, and it covered residuals of 1.5e5 at
//! vertices whose own rows are 1e12 times softer. Clarabel (0.11, the program of docs/math.md
//! §2 posed on the answer's knots, points centred and scaled) finds a point inside every
//! half-space to 1.7e-13 of the extent with E = 0.325022575. Any answer must be refused or
//! have an energy no higher.

use curvefit_tests::run_cli;

/// E of Clarabel's feasible point (module docs).
const CLARABEL_ENERGY: f64 = 0.325_022_575_374_6;

#[test]
fn a_certified_answer_is_never_above_a_feasible_point_of_clarabel() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join("refine-unequal-spans-far-from-origin.json");
    let doc = std::fs::read_to_string(path).unwrap();
    let (code, out, err) = run_cli(&["refine", "-"], &doc);
    match code {
        // A refusal must say why, in one line, and write nothing.
        2 => {
            assert!(out.is_empty(), "{out}");
            assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        }
        0 => {
            let v: serde_json::Value = serde_json::from_str(&out).unwrap();
            let e = v["energy"].as_f64().unwrap();
            assert!(
                e <= CLARABEL_ENERGY * (1.0 + 1e-6),
                "certified E = {e} (kkt {}) above Clarabel's feasible {CLARABEL_ENERGY}",
                v["kkt_residual"]
            );
        }
        c => panic!("exit code {c}: {err}"),
    }
}
