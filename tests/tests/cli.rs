//! End-to-end tests of the `curvefit` command line: help, bad-input catalogue, atomic output.

use curvefit_tests::{problem_path, run_cli, scratch_dir};

#[test]
fn help_runs_for_every_subcommand() {
    let (code, out, _) = run_cli(&["--help"], "");
    assert_eq!(code, 0);
    for sub in ["refine", "strip", "natural"] {
        assert!(out.contains(sub), "--help lists {sub}");
        let (code, out, err) = run_cli(&[sub, "--help"], "");
        assert_eq!(code, 0, "{sub} --help: {err}");
        assert!(out.contains("Usage"), "{sub} --help prints usage");
    }
}

/// Each bad input: exit code 2, one stderr line naming the field, and no output file written.
fn assert_refused(args: &[&str], stdin: &str, field: &str) {
    let dir = scratch_dir("refused");
    let out = dir.join("out.json");
    let svg = dir.join("out.svg");
    let mut argv: Vec<&str> = args.to_vec();
    let (o, s) = (
        out.to_string_lossy().into_owned(),
        svg.to_string_lossy().into_owned(),
    );
    argv.extend(["-o", &o, "--svg", &s]);
    let (code, stdout, stderr) = run_cli(&argv, stdin);
    assert_eq!(code, 2, "args {args:?} stdin {stdin:?}: stderr {stderr}");
    assert!(stdout.is_empty(), "nothing on stdout: {stdout}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains(field), "stderr names `{field}`: {stderr}");
    assert!(
        !out.exists() && !svg.exists(),
        "no output file for {args:?}"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(
        leftovers.is_empty(),
        "no temporary files left: {leftovers:?}"
    );
}

#[test]
fn malformed_json_is_refused() {
    assert_refused(&["refine", "-"], "{\"points\": [[0, 0], [1,", "problem");
    assert_refused(&["refine", "-"], "[1, 2, 3]", "");
    assert_refused(
        &["refine", "-"],
        "{\"points\": [[0, 0], [1, NaN]]}",
        "problem",
    );
}

#[test]
fn unknown_fields_are_refused_with_their_path() {
    assert_refused(
        &["refine", "-"],
        r#"{"points": [[0,0],[1,0],[0,1]], "colsed": true}"#,
        "colsed",
    );
    assert_refused(
        &["refine", "-"],
        r#"{"points": [[0,0],[1,0],[0,1]], "constraint": {"type": "balls", "radii": [1,1,1], "radius": 2}}"#,
        "radius",
    );
}

#[test]
fn wrong_types_name_the_index() {
    assert_refused(
        &["refine", "-"],
        r#"{"points": [[0,0],[1,"a"],[0,1]]}"#,
        "points[1][1]",
    );
}

#[test]
fn missing_problem_file_is_refused() {
    let p = problem_path("does-not-exist.json");
    assert_refused(&["refine", &p.to_string_lossy()], "", "problem");
}

#[test]
fn csv_points_and_json_points_conflict() {
    let dir = scratch_dir("csv");
    let csv = dir.join("pts.csv");
    std::fs::write(&csv, "0,0\n1,0\n0,1\n").unwrap();
    let c = csv.to_string_lossy().into_owned();
    assert_refused(
        &["refine", "-", "--points", &c],
        r#"{"points": [[0,0],[1,0],[0,1]]}"#,
        "points",
    );
    std::fs::write(&csv, "0,0\n1,x\n").unwrap();
    assert_refused(&["refine", "--points", &c], "", "points[1]");
    std::fs::write(&csv, "0,0\n1,0,2\n").unwrap();
    assert_refused(&["refine", "--points", &c], "", "points[1]");
}
