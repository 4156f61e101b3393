//! `cargo xtask fuzz libfuzzer [TARGET…] [--time S | --runs N] [--out DIR]`: runs the cargo-fuzz
//! targets of `fuzz/` one after another with `cargo +nightly fuzz run`, libFuzzer's artifacts
//! (crashes, timeouts, out-of-memory inputs) under `--out`, and sums the executions libFuzzer
//! reports (`stat::number_of_executed_units`). Fails when a target finds a crash.

use std::path::PathBuf;
use std::process::Command;

/// The targets of `fuzz/Cargo.toml`, in the order they run.
pub const TARGETS: &[&str] = &[
    "refine_json",
    "refine_structured",
    "strip_json",
    "strip_structured",
    "scheme_json",
    "csv_reader",
];

pub fn run(args: &[String]) -> anyhow::Result<bool> {
    let mut targets: Vec<String> = Vec::new();
    let mut limit = vec!["-max_total_time=60".to_string()];
    let mut out = PathBuf::from("target/fuzz/artifacts");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--time" => {
                let s: u64 = it
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--time SECONDS"))?
                    .parse()?;
                limit = vec![format!("-max_total_time={s}")];
            }
            "--runs" => {
                let n: u64 = it
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--runs N"))?
                    .parse()?;
                limit = vec![format!("-runs={n}")];
            }
            "--out" => out = PathBuf::from(it.next().ok_or_else(|| anyhow::anyhow!("--out DIR"))?),
            t if TARGETS.contains(&t) => targets.push(t.to_string()),
            other => anyhow::bail!(
                "unknown argument or target {other} (targets: {}; see cargo xtask fuzz --help)",
                TARGETS.join(", ")
            ),
        }
    }
    if targets.is_empty() {
        targets = TARGETS.iter().map(|s| s.to_string()).collect();
    }
    let probe = Command::new("cargo")
        .args(["+nightly", "fuzz", "--version"])
        .output();
    anyhow::ensure!(
        probe.as_ref().is_ok_and(|o| o.status.success()),
        "cargo-fuzz on a nightly toolchain is needed: `rustup toolchain install nightly --profile minimal` and `cargo install cargo-fuzz`"
    );
    let out = std::path::absolute(&out)?;
    let (mut total, mut clean) = (0u64, true);
    for t in &targets {
        let corpus = PathBuf::from("fuzz/corpus").join(t);
        std::fs::create_dir_all(&corpus)?;
        let artifacts = out.join(t);
        std::fs::create_dir_all(&artifacts)?;
        let mut cmd = Command::new("cargo");
        cmd.current_dir("fuzz")
            .args([
                "+nightly",
                "fuzz",
                "run",
                "--release",
                "--debug-assertions",
                t,
            ])
            .arg(std::path::absolute(&corpus)?)
            .arg("--")
            .arg(format!("-artifact_prefix={}/", artifacts.display()))
            .arg("-print_final_stats=1")
            .arg("-rss_limit_mb=2048")
            .arg("-timeout=10")
            .args(&limit);
        let o = cmd.output()?;
        let err = String::from_utf8_lossy(&o.stderr);
        let execs: u64 = err
            .lines()
            .filter_map(|l| l.strip_prefix("stat::number_of_executed_units:"))
            .filter_map(|v| v.trim().parse::<u64>().ok())
            .sum();
        total += execs;
        let ok = o.status.success();
        clean &= ok;
        println!(
            "{t:<18} {execs:>12} executions  {}",
            if ok {
                "no crash".to_string()
            } else {
                format!("FAILED (artifacts in {})", artifacts.display())
            }
        );
        if !ok {
            let tail: Vec<&str> = err.lines().rev().take(40).collect();
            for l in tail.into_iter().rev() {
                println!("    {l}");
            }
        }
    }
    println!(
        "libfuzzer: {total} executions over {} target(s)",
        targets.len()
    );
    Ok(clean)
}
