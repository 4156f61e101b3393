//! Outputs are all-or-nothing (issue 17 §1): every output (files, devices, standard output) is
//! produced in full before any is committed, a failure removes what was staged, and two outputs
//! naming the same file are refused. `/dev/full` (writes fail with ENOSPC) stands in for a full
//! disk; the real binary with its standard output on `/dev/full` is tested in
//! `crates/curvefit/tests/binary.rs`.

use std::io::Write;

use curvefit_tests::{problem_path, scratch_dir};

/// A standard output on a full disk.
struct Full;

impl Write for Full {
    fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
        Err(std::io::Error::from_raw_os_error(28))
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn run(args: &[&str], stdout: &mut dyn Write) -> (i32, String) {
    let mut argv = vec!["curvefit"];
    argv.extend_from_slice(args);
    let mut err = Vec::new();
    let code = curvefit::cli::run(argv, &mut std::io::empty(), stdout, &mut err);
    (code, String::from_utf8_lossy(&err).into_owned())
}

fn listing(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn has_dev_full() -> bool {
    std::path::Path::new("/dev/full").exists()
}

#[test]
fn svg_then_failing_json_output_leaves_no_svg() {
    if !has_dev_full() {
        return;
    }
    let dir = scratch_dir("out-a");
    let svg = dir.join("a.svg");
    let p = problem_path("refine-interpolate-closed.json");
    let (code, err) = run(
        &[
            "refine",
            &p.to_string_lossy(),
            "--svg",
            &svg.to_string_lossy(),
            "-o",
            "/dev/full",
        ],
        &mut Vec::new(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("/dev/full") && err.contains("-o"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
}

#[test]
fn json_then_failing_svg_output_leaves_no_json() {
    if !has_dev_full() {
        return;
    }
    let dir = scratch_dir("out-b");
    let json = dir.join("a.json");
    let p = problem_path("refine-interpolate-closed.json");
    let (code, err) = run(
        &[
            "refine",
            &p.to_string_lossy(),
            "-o",
            &json.to_string_lossy(),
            "--svg",
            "/dev/full",
        ],
        &mut Vec::new(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--svg"), "{err}");
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
}

#[test]
fn full_standard_output_leaves_no_file() {
    let dir = scratch_dir("out-c");
    let svg = dir.join("a.svg");
    let p = problem_path("refine-interpolate-closed.json");
    let (code, err) = run(
        &[
            "refine",
            &p.to_string_lossy(),
            "--svg",
            &svg.to_string_lossy(),
        ],
        &mut Full,
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("standard output"), "{err}");
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
    // Every subcommand, and the demo: its summary goes to standard output.
    let q = problem_path("strip-small.json");
    let (code, err) = run(&["strip", &q.to_string_lossy()], &mut Full);
    assert_eq!(code, 2, "{err}");
    let (code, err) = run(&["scheme", "--stencil", "4", "--arity", "2"], &mut Full);
    assert_eq!(code, 2, "{err}");
    let out = dir.join("demo");
    let (code, err) = run(&["demo", "--out", &out.to_string_lossy()], &mut Full);
    assert_eq!(code, 2, "{err}");
    assert!(!out.exists(), "the demo's directory is removed again");
    let (code, _) = run(&["--help"], &mut Full);
    assert_eq!(code, 2);
}

#[test]
fn the_same_file_twice_is_refused() {
    let dir = scratch_dir("out-d");
    let x = dir.join("x");
    let p = problem_path("refine-interpolate-closed.json");
    let p = p.to_string_lossy();
    let xs = x.to_string_lossy().into_owned();
    let dotted = format!("{}/./x", dir.display());
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let up = format!("{}/sub/../x", dir.display());
    for (a, b) in [(&xs, &xs), (&xs, &dotted), (&dotted, &up)] {
        let (code, err) = run(&["refine", &p, "-o", a, "--svg", b], &mut Vec::new());
        assert_eq!(code, 2, "{a} {b}: {err}");
        assert!(err.contains("--svg") && err.contains("-o"), "{err}");
        assert_eq!(listing(&dir), ["sub"]);
    }
    // A symlink to the same file, existing or not.
    #[cfg(unix)]
    {
        let link = dir.join("link");
        std::os::unix::fs::symlink(&x, &link).unwrap();
        let l = link.to_string_lossy().into_owned();
        std::fs::write(&x, "old").unwrap();
        let (code, err) = run(&["refine", &p, "-o", &xs, "--svg", &l], &mut Vec::new());
        assert_eq!(code, 2, "{err}");
        assert_eq!(std::fs::read_to_string(&x).unwrap(), "old", "x unchanged");
    }
    // Standard output twice.
    let (code, err) = run(&["refine", &p, "-o", "-", "--svg", "-"], &mut Vec::new());
    assert_eq!(code, 2, "{err}");
}

#[test]
fn a_failure_keeps_existing_files_unchanged() {
    if !has_dev_full() {
        return;
    }
    let dir = scratch_dir("out-e");
    let json = dir.join("a.json");
    std::fs::write(&json, "previous").unwrap();
    let p = problem_path("refine-interpolate-closed.json");
    let (code, _) = run(
        &[
            "refine",
            &p.to_string_lossy(),
            "-o",
            &json.to_string_lossy(),
            "--svg",
            "/dev/full",
        ],
        &mut Vec::new(),
    );
    assert_eq!(code, 2);
    assert_eq!(std::fs::read_to_string(&json).unwrap(), "previous");
    assert_eq!(listing(&dir), ["a.json"]);
}

#[test]
fn successful_outputs_are_all_written() {
    let dir = scratch_dir("out-f");
    let (json, svg) = (dir.join("a.json"), dir.join("a.svg"));
    let p = problem_path("refine-interpolate-closed.json");
    let mut out = Vec::new();
    let (code, err) = run(
        &[
            "refine",
            &p.to_string_lossy(),
            "-o",
            &json.to_string_lossy(),
            "--svg",
            &svg.to_string_lossy(),
        ],
        &mut out,
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.is_empty());
    assert_eq!(listing(&dir), ["a.json", "a.svg"]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["points"].is_array());
}
