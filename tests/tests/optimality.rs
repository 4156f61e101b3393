//! A certified answer is the optimum, checked against a point of an independent solver.
//!
//! The first fixture is case 250 of `xtask/sweeps/refine.py` seed 5, found by
//! `xtask/sweeps/optimality.py`: 20 open points near (1001, 1000) with extent 1.3, half-spaces
//! at 11 of them, centripetal-like knots with exponent 1.99, so the refined spans run from
//! 1.5e-6 to 0.54. The binary once answered it with E = 5.37e6 and a certificate of 8.3e-10:
//! the rounding floor of its stationarity test, 16 ε ‖H‖_∞ max|p|, is set by the stiffest row
//! of H (the 1.5e-6 spans) and by coordinates near 1e3, and it covered residuals of 1.5e5 at
//! vertices whose own rows are 1e12 times softer. Clarabel (0.11, the program of docs/math.md
//! §2 posed on the answer's knots, points centred and scaled) finds a point inside every
//! half-space to 1.7e-13 of the extent with E = 0.325022575.
//!
//! The second is case 259 of seed 2: five points on a line (d = 1) in balls, near-clamped ends
//! of radius 0.05, exponent 1.59 and three knot updates, so the final spans run from 1.3e-8 to
//! 2.9 and the first seven vertices form one cluster. The binary once answered it with
//! E = 2.1537741 at a certificate of 4.8e-11: the cluster's balls were all inactive while it
//! carried a net force of 0.3, hidden vertex by vertex under rounding levels of ~1e4 (its rows
//! of H are ~1/h³). Clarabel's point on the answer's knots, projected into the balls, keeps
//! the ends' balls to 4e-13 and has E = 2.131559022. It is now refused naming
//! `knot_iterations` (spans 2.3e8 apart, beyond `refine::MAX_CERTIFIED_SPAN_RATIO`).
//!
//! The third is case 254 of seed 41: five open points near (10⁶, 10⁶), two of them 0.0026
//! apart and the others about 1 apart, chordal parameters, k = 2 (refined spans 8.7e-4 beside
//! 0.6), half-spaces at three points. The interior-point method stopped at 1e-11 of its force
//! floor (‖H‖ × the data's scale, set by the short spans) on curves 1.5e-4 of the extent away
//! from the optimum, which the certificate refused at 4.7e-5; the binary refused the problem
//! (ROBUSTNESS.md §4, item 38). It is now answered by the method's last attempt with the floor
//! at the rounding level. Clarabel's point on the answer's knots (centred) keeps the
//! half-spaces to 9e-12 and has E = 0.193735492847.
//!
//! Any answer must be refused or have an energy no higher than Clarabel's point's.

use curvefit_tests::run_cli;

#[test]
fn a_certified_answer_is_never_above_a_feasible_point_of_clarabel() {
    // (fixture, E of Clarabel's feasible point; module docs)
    for (name, clarabel) in [
        (
            "refine-unequal-spans-far-from-origin.json",
            0.325_022_575_374_6,
        ),
        (
            "refine-clustered-spans-near-clamped.json",
            2.131_559_021_790_139,
        ),
    ] {
        check(name, clarabel);
    }
}

#[test]
fn clustered_chordal_half_spaces_are_answered_at_the_optimum() {
    // (Module docs, the third fixture: refused before.)
    let name = "refine-clustered-chordal-halfspaces.json";
    assert_eq!(check(name, 0.193_735_492_847_437_55), 0, "{name}: refused");
}

/// Runs the fixture through the binary and checks its answer against Clarabel's energy;
/// returns the exit code.
fn check(name: &str, clarabel: f64) -> i32 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name);
    let doc = std::fs::read_to_string(path).unwrap();
    let (code, out, err) = run_cli(&["refine", "-"], &doc);
    match code {
        // A refusal must say why, in one line, and write nothing.
        2 => {
            assert!(out.is_empty(), "{name}: {out}");
            assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        }
        0 => {
            let v: serde_json::Value = serde_json::from_str(&out).unwrap();
            let e = v["energy"].as_f64().unwrap();
            assert!(
                e <= clarabel * (1.0 + 1e-6),
                "{name}: certified E = {e} (kkt {}) above Clarabel's feasible {clarabel}",
                v["kkt_residual"]
            );
        }
        c => panic!("{name}: exit code {c}: {err}"),
    }
    code
}
