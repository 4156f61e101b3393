//! Replays every saved fuzz input (`tests/fuzz-corpus/**.json`, including past crashes) through
//! the command line: each must give exit code 0 with valid JSON, or exit code 2 with one line on
//! stderr — never a panic (exit code 70).

use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                files(&p, out);
            } else if p.extension().is_some_and(|x| x == "json") {
                out.push(p);
            }
        }
    }
}

#[test]
fn every_saved_fuzz_input_is_answered_or_refused_cleanly() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz-corpus");
    let mut all = Vec::new();
    files(&root, &mut all);
    assert!(!all.is_empty(), "the corpus is not empty");
    for f in &all {
        let cmd = f
            .ancestors()
            .filter_map(|a| a.file_name()?.to_str())
            .find(|n| ["refine", "strip", "natural", "surface"].contains(n))
            .expect("corpus files live under a command directory");
        let input = std::fs::read_to_string(f).unwrap();
        let (code, out, err) = curvefit_tests::run_cli(&[cmd, "-"], &input);
        match code {
            0 => {
                let v: serde_json::Value =
                    serde_json::from_str(&out).expect("valid JSON on success");
                assert!(
                    !out.contains("null"),
                    "{}: no NaN (null) in the result: {v}",
                    f.display()
                );
            }
            2 => assert_eq!(
                err.trim_end().lines().count(),
                1,
                "{}: one line: {err}",
                f.display()
            ),
            _ => panic!("{}: exit code {code}: {err}", f.display()),
        }
    }
}
