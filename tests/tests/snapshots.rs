//! Insta snapshot tests of `curvefit` results for a fixed set of small problems: every
//! subcommand, open and closed curves, each constraint type. Floats are printed at 6 significant
//! digits (values below 1e-9 in magnitude print as 0) so the snapshots are stable across
//! machines; certificates that depend on rounding (KKT residuals, gradient norms, iteration
//! counts) are checked against their bounds and left out of the snapshot.

use curvefit_tests::{problem_path, round_json, run_cli};
use serde_json::Value;

/// Fields whose exact values depend on floating-point rounding paths.
const VOLATILE: &[&str] = &["kkt_residual", "gradient_norm", "iterations"];

fn snapshot_of(args: &[&str]) -> String {
    let (code, out, err) = run_cli(args, "");
    assert_eq!(code, 0, "{args:?}: {err}");
    let mut v: Value = serde_json::from_str(&out).expect("JSON result");
    if let Value::Object(o) = &mut v {
        if let Some(k) = o.get("kkt_residual").and_then(Value::as_f64) {
            assert!(k <= 1e-9, "{args:?}: KKT residual {k} ≤ 1e-9");
        }
        for f in VOLATILE {
            o.remove(*f);
        }
    }
    serde_json::to_string_pretty(&round_json(&v, 6, 1e-9)).unwrap()
}

fn json_problem(command: &str, file: &str) -> String {
    let p = problem_path(file);
    snapshot_of(&[command, &p.to_string_lossy()])
}

macro_rules! snap {
    ($name:ident, $cmd:expr, $file:expr) => {
        #[test]
        fn $name() {
            insta::assert_snapshot!(json_problem($cmd, $file));
        }
    };
}

snap!(
    refine_interpolate_closed,
    "refine",
    "refine-interpolate-closed.json"
);
snap!(
    refine_interpolate_open_3d,
    "refine",
    "refine-interpolate-open-3d.json"
);
snap!(
    refine_interpolate_levels_1d,
    "refine",
    "refine-interpolate-levels-1d.json"
);
snap!(
    refine_smoothing_closed,
    "refine",
    "refine-smoothing-closed.json"
);
snap!(refine_balls_closed, "refine", "refine-balls-closed.json");
snap!(refine_balls_open, "refine", "refine-balls-open.json");
snap!(
    refine_halfspaces_closed,
    "refine",
    "refine-halfspaces-closed.json"
);
snap!(refine_tangents_open, "refine", "refine-tangents-open.json");
snap!(refine_clamped_open, "refine", "refine-clamped-open.json");
snap!(strip_small, "strip", "strip-small.json");
snap!(strip_end_slopes, "strip", "strip-end-slopes.json");
snap!(strip_polyline, "strip", "strip-polyline.json");
snap!(natural_small, "natural", "natural-small.json");
snap!(surface_small, "surface", "surface-small.json");

#[test]
fn scheme_rules_binary_4_point() {
    insta::assert_snapshot!(snapshot_of(&["scheme", "--stencil", "4", "--arity", "2"]));
}

#[test]
fn scheme_rules_ternary_6_point_with_surface() {
    insta::assert_snapshot!(snapshot_of(&[
        "scheme",
        "--stencil",
        "6",
        "--arity",
        "3",
        "--surface"
    ]));
}

#[test]
fn scheme_applied_to_a_square() {
    let p = problem_path("polygon-square.json");
    insta::assert_snapshot!(snapshot_of(&[
        "scheme",
        "--stencil",
        "4",
        "--arity",
        "3",
        "--apply",
        &p.to_string_lossy(),
        "--levels",
        "1"
    ]));
}
