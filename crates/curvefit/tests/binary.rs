//! The `curvefit` binary itself, as a process: a write error on its real standard output (here
//! `/dev/full`, where every write fails with ENOSPC) is an error with exit code 2 and leaves no
//! file behind — the demo included (issue 17 §1).

#![cfg(all(unix, feature = "cli"))]

use std::path::PathBuf;
use std::process::{Command, Stdio};

fn scratch(tag: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("binary-{tag}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn full() -> Option<Stdio> {
    std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .ok()
        .map(Stdio::from)
}

fn example(name: &str) -> String {
    format!("{}/examples/data/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn standard_output_on_a_full_disk_is_exit_2_and_no_file() {
    let Some(stdout) = full() else { return };
    let dir = scratch("full");
    let svg = dir.join("a.svg");
    let out = Command::new(env!("CARGO_BIN_EXE_curvefit"))
        .args(["refine", &example("refine-balls-closed.json"), "--svg"])
        .arg(&svg)
        .stdout(stdout)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("standard output"), "{err}");
    assert!(!svg.exists());
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

#[test]
fn demo_with_standard_output_on_a_full_disk_is_exit_2() {
    let Some(stdout) = full() else { return };
    let dir = scratch("demo");
    let d = dir.join("d");
    let out = Command::new(env!("CARGO_BIN_EXE_curvefit"))
        .args(["demo", "--out"])
        .arg(&d)
        .stdout(stdout)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!d.exists(), "no demo directory left");
}
