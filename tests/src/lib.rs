//! Test-only package: insta snapshot tests (`tests/snapshots.rs`) and end-to-end tests of the
//! `curvefit` command line (`tests/cli.rs`). Shared helpers live here.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static NEXT: AtomicUsize = AtomicUsize::new(0);

/// Runs the curvefit command line in-process: returns (exit code, stdout, stderr).
pub fn run_cli(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut argv = vec!["curvefit"];
    argv.extend_from_slice(args);
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let code = curvefit::cli::run(argv, &mut stdin.as_bytes(), &mut out, &mut err);
    (
        code,
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
    )
}

/// Path of a file under `tests/problems/`.
pub fn problem_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(name)
}

/// A fresh scratch directory under the target directory.
pub fn scratch_dir(tag: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("target")
        .join("test-scratch")
        .join(format!(
            "{tag}-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Rounds every float in a JSON value to `digits` significant digits (values below `floor` in
/// magnitude become 0), so snapshots are stable across machines.
pub fn round_json(v: &serde_json::Value, digits: usize, floor: f64) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Number(n) if n.is_f64() => {
            let x = n.as_f64().unwrap_or(0.0);
            if x.abs() < floor {
                Value::from(0.0)
            } else {
                let s = format!("{:.*e}", digits.saturating_sub(1), x);
                Value::String(s)
            }
        }
        Value::Array(a) => Value::Array(a.iter().map(|x| round_json(x, digits, floor)).collect()),
        Value::Object(o) => Value::Object(
            o.iter()
                .map(|(k, x)| (k.clone(), round_json(x, digits, floor)))
                .collect(),
        ),
        other => other.clone(),
    }
}
