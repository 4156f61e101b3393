//! End-to-end tests of the `curvefit` command line: help, bad-input catalogue, atomic output.

use curvefit_tests::{problem_path, run_cli, scratch_dir};

#[test]
fn help_runs_for_every_subcommand() {
    let (code, out, _) = run_cli(&["--help"], "");
    assert_eq!(code, 0);
    for sub in ["refine", "strip", "natural", "scheme", "surface", "demo"] {
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

/// Every `curvefit …` command line in the README's shell blocks runs and succeeds (output files
/// redirected to a scratch directory; input paths are relative to the repository root).
#[test]
fn every_readme_example_runs() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let dir = scratch_dir("readme");
    let mut in_sh = false;
    let mut ran = 0;
    for line in readme.lines() {
        if line.starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        let Some(cmd) = line.trim().strip_prefix("curvefit ") else {
            continue;
        };
        if !in_sh {
            continue;
        }
        let mut args: Vec<String> = Vec::new();
        let mut redirect = false;
        for tok in cmd.split_whitespace() {
            if redirect {
                args.push(dir.join(tok).to_string_lossy().into_owned());
                redirect = false;
                continue;
            }
            redirect = matches!(tok, "-o" | "--svg" | "--obj");
            let path = root.join(tok);
            if tok.ends_with(".json") && path.exists() {
                args.push(path.to_string_lossy().into_owned());
            } else {
                args.push(tok.to_string());
            }
        }
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, out, err) = run_cli(&argv, "");
        assert_eq!(code, 0, "README example `curvefit {cmd}` failed: {err}");
        let csv = cmd.contains("--format csv");
        assert!(
            out.is_empty() || csv || serde_json::from_str::<serde_json::Value>(&out).is_ok(),
            "JSON output"
        );
        assert!(!csv || out.starts_with("x,y\n"), "CSV output: {out}");
        ran += 1;
    }
    assert!(ran >= 6, "found the README's examples ({ran})");
}

#[test]
fn catalogue_of_bad_inputs() {
    let cases: &[(&str, &str, &str)] = &[
        // (subcommand, problem, field the message must name)
        (
            "refine",
            r#"{"points": [[0, 0], [1, 1e999], [0, 1]]}"#,
            "problem",
        ),
        (
            "refine",
            r#"{"points": [[0, 0], [1, 0], [0, 1, 2]]}"#,
            "points[2]",
        ),
        (
            "refine",
            r#"{"points": [[0, 0], [1, 0], [0, 1]], "closed": true, "knots": [0, 2, 1, 3]}"#,
            "knots[2]",
        ),
        (
            "refine",
            r#"{"points": [[0, 0], [1, 0], [1, 0], [0, 1]]}"#,
            "points[2]",
        ),
        (
            "refine",
            r#"{"points": [[0, 0], [1, 0], [0, 1]], "constraint": {"type": "balls", "radii": [0.1, -0.1, 0.1]}}"#,
            "constraint.radii[1]",
        ),
        ("refine", r#"{"points": []}"#, "points"),
        (
            "refine",
            r#"{"points": [[0, 0], [1, 0], [0, 1]], "k": 1000000000}"#,
            "k",
        ),
        (
            "refine",
            r#"{"points": [[0, 0], [1, 0], [0, 1]], "constraint": {"type": "smoothing", "weights": []}}"#,
            "constraint.weights",
        ),
        (
            "strip",
            r#"{"t": [0, 1, 2], "y": [0, 5, 0], "lower": null, "upper": {"pieces": [[1, 0, 0, 0], [1, 0, 0, 0]]}}"#,
            "y[1]",
        ),
        (
            "strip",
            r#"{"t": [0, 1, 1], "y": [0, 0, 0], "lower": null, "upper": null}"#,
            "t[2]",
        ),
        (
            "strip",
            r#"{"t": [], "y": [], "lower": null, "upper": null}"#,
            "t",
        ),
        (
            "strip",
            r#"{"t": [0, 1], "y": [0, 0], "lower": {"pieces": [[1, 0, 0, 0]]}, "upper": {"pieces": [[-1, 0, 0, 0]]}}"#,
            "pieces[0]",
        ),
        ("natural", r#"{"points": [], "levels": 2}"#, "points"),
        (
            "natural",
            r#"{"points": [[0], [1], [2]], "levels": 200}"#,
            "levels",
        ),
        (
            "surface",
            r#"{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1]]}"#,
            "points",
        ),
    ];
    for (cmd, problem, field) in cases {
        assert_refused(&[cmd, "-"], problem, field);
    }
}

#[test]
fn scheme_flags_are_validated() {
    for (args, field) in [
        (
            &["scheme", "--stencil", "3", "--arity", "2"][..],
            "--stencil",
        ),
        (&["scheme", "--stencil", "4", "--arity", "1"][..], "--arity"),
        (&["scheme", "--stencil", "4"][..], "arity"),
    ] {
        let (code, _, err) = run_cli(args, "");
        assert_eq!(code, 2, "{args:?}");
        assert!(err.contains(field), "{args:?}: {err}");
    }
}

/// Writing the result to a device (here /dev/null) writes in place: the atomic
/// temporary-and-rename path must never replace a device or FIFO with a regular file.
#[cfg(unix)]
#[test]
fn writing_to_a_device_keeps_the_device() {
    use std::os::unix::fs::FileTypeExt;
    let dev = std::path::Path::new("/dev/null");
    if !std::fs::metadata(dev).is_ok_and(|m| m.file_type().is_char_device()) {
        return; // not a character device on this system: nothing to protect
    }
    let p = problem_path("refine-interpolate-closed.json");
    let (code, _, err) = run_cli(
        &[
            "refine",
            &p.to_string_lossy(),
            "-o",
            "/dev/null",
            "--svg",
            "/dev/null",
        ],
        "",
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        std::fs::metadata(dev).unwrap().file_type().is_char_device(),
        "/dev/null is still a device"
    );
}

/// `--format csv|npy` (and the `-o` extension) write the refined points; their numbers are
/// exactly the JSON result's.
#[test]
fn csv_and_npy_outputs_hold_the_json_points() {
    let dir = scratch_dir("formats");
    let p = problem_path("refine-interpolate-open-3d.json");
    let p = p.to_string_lossy();
    let (code, json, err) = run_cli(&["refine", &p], "");
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let want: Vec<f64> = v["points"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
        .collect();
    let n = v["points"].as_array().unwrap().len();
    // CSV on standard output, with a header.
    let (code, csv, err) = run_cli(&["refine", &p, "--format", "csv"], "");
    assert_eq!(code, 0, "{err}");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x,y,z"));
    let got: Vec<f64> = lines
        .flat_map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()))
        .collect();
    assert_eq!(got, want);
    // .npy chosen by the extension.
    let npy = dir.join("points.npy");
    let (code, _, err) = run_cli(&["refine", &p, "-o", &npy.to_string_lossy()], "");
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(&npy).unwrap();
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    assert!(header.contains(&format!("'shape': ({n}, 3)")), "{header}");
    let got: Vec<f64> = bytes[10 + hlen..]
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    assert_eq!(got, want);
    // `scheme` has no array format; strip's rows are its pieces.
    let s = problem_path("strip-small.json");
    let (code, csv, err) = run_cli(&["strip", &s.to_string_lossy(), "--format", "csv"], "");
    assert_eq!(code, 0, "{err}");
    assert!(csv.starts_with("start,end,c0,c1,c2,c3\n"), "{csv}");
}

/// A bare `curvefit` prints the usage and every subcommand (on standard error, exit 2).
#[test]
fn bare_curvefit_prints_usage_and_subcommands() {
    let (code, out, err) = run_cli(&[], "");
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(err.contains("Usage: curvefit <COMMAND>"), "{err}");
    for sub in [
        "refine", "strip", "natural", "scheme", "surface", "schema", "demo",
    ] {
        assert!(err.contains(&format!("  {sub} ")), "lists {sub}: {err}");
    }
}

/// `curvefit refine < f.json` reads standard input without `-`; with standard input a terminal,
/// a missing problem file is a one-line refusal instead of a wait.
#[test]
fn no_problem_file_reads_standard_input() {
    let p = problem_path("refine-interpolate-closed.json");
    let text = std::fs::read_to_string(&p).unwrap();
    let (code, out, err) = run_cli(&["refine"], &text);
    assert_eq!(code, 0, "{err}");
    let (_, want, _) = run_cli(&["refine", &p.to_string_lossy()], "");
    assert_eq!(out, want);
    let (mut o, mut e) = (Vec::new(), Vec::new());
    let code = curvefit::cli::run_with_terminal(
        ["curvefit", "refine"],
        &mut std::io::empty(),
        true,
        &mut o,
        &mut e,
    );
    let e = String::from_utf8_lossy(&e);
    assert_eq!(code, 2);
    assert!(e.contains("problem: no problem given"), "{e}");
}

/// `strip --points FILE.csv` reads the sites and values from two columns (as `--help` says),
/// with or without a header, and gives the same result as the JSON problem.
#[test]
fn strip_reads_t_and_y_from_a_csv() {
    let dir = scratch_dir("strip-csv");
    let csv = dir.join("ty.csv");
    std::fs::write(&csv, "t,y\n0,0\n1,1\n2,0\n3,0\n4,1\n").unwrap();
    let c = csv.to_string_lossy().into_owned();
    let (code, out, err) = run_cli(&["strip", "--points", &c], "");
    assert_eq!(code, 0, "{err}");
    let (code, want, err) = run_cli(
        &["strip", "-"],
        r#"{"t": [0, 1, 2, 3, 4], "y": [0, 1, 0, 0, 1]}"#,
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(out, want);
    // With bounds from the problem file.
    let (code, _, err) = run_cli(
        &["strip", "-", "--points", &c],
        r#"{"lower": {"pieces": [[-0.05,0,0,0],[-0.05,0,0,0],[-0.05,0,0,0],[-0.05,0,0,0]]}}"#,
    );
    assert_eq!(code, 0, "{err}");
    std::fs::write(&csv, "0,0,1\n1,1,2\n").unwrap();
    assert_refused(&["strip", "--points", &c], "", "--points");
    assert_refused(
        &["strip", "-", "--points", &c],
        r#"{"t": [0, 1], "y": [0, 1]}"#,
        "t",
    );
}

/// One documented CSV separator, the comma: anything else is an error naming the line.
#[test]
fn csv_separators_other_than_comma_name_the_line() {
    let dir = scratch_dir("csv-sep");
    let csv = dir.join("p.csv");
    let c = csv.to_string_lossy().into_owned();
    for (text, words) in [
        ("x;y\n0;0\n1;0\n0;1\n", "line 1"),
        ("0;0\n1;0\n0;1\n", "semicolon"),
        ("0,0\n1,0,\n0,1\n", "line 2"),
        ("0,0\n1 0\n0,1\n", "not whitespace"),
    ] {
        std::fs::write(&csv, text).unwrap();
        let (code, _, err) = run_cli(&["refine", "--points", &c], "");
        assert_eq!(code, 2, "{text:?}");
        assert!(err.contains(words), "{text:?}: {err}");
    }
    std::fs::write(&csv, "x,y\n0,0\n1,0\n0,1\n").unwrap();
    let (code, _, err) = run_cli(&["refine", "--points", &c], "");
    assert_eq!(code, 0, "a header line is accepted: {err}");
}

/// `--quiet` (no progress line) is accepted by the JSON subcommands and changes no output; the
/// progress line itself is only written when the process's standard error is a terminal.
#[test]
fn quiet_changes_no_output() {
    let p = problem_path("refine-interpolate-closed.json");
    let p = p.to_string_lossy();
    let (code, out, err) = run_cli(&["refine", &p, "--quiet"], "");
    assert_eq!(code, 0, "{err}");
    let (_, want, want_err) = run_cli(&["refine", &p], "");
    assert_eq!((out, err), (want, want_err));
}
