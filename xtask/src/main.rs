//! `cargo xtask` — curvefit's single entry point for project tasks.
//!
//! * `cargo xtask verify`  — every identity, theorem and worked example of the seeds as a named case.
//! * `cargo xtask figures [--out DIR]` — redraws the seeds' figures as SVG.
//! * `cargo xtask bench [--quick]` — the benchmark tables (ratios measured in the same run).
//! * `cargo xtask fuzz [--help]` — mutational fuzzing of the command line on stable, and the
//!   coverage-guided cargo-fuzz targets of `fuzz/` (`fuzz libfuzzer`).
//! * `cargo xtask playground [--out DIR]` — the interactive page (WebAssembly + static files).
//! * `cargo xtask tidy`    — checks the architectural invariants of ARCHITECTURE.md.

/// The benches time the libraries with the allocator the `curvefit` binary and the Python module
/// use (mimalloc; see `crates/curvefit/src/main.rs`), not the system's: with glibc's malloc the
/// tens of megabytes of a large solve are mapped fresh and faulted in on every call, and which
/// calls do so depends on glibc's thresholds more than on the solver.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod bench;
mod figures;
mod fuzz;
mod libfuzzer;
mod playground;
mod tidy;
mod verify;

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (cmd, rest) = match args.split_first() {
        Some((c, r)) => (c.as_str(), r),
        None => ("help", &[][..]),
    };
    let result = match cmd {
        "verify" => verify::run(rest),
        "figures" => figures::run(rest),
        "bench" => bench::run(rest),
        "tidy" => tidy::run(rest),
        "fuzz" => fuzz::run(rest),
        "playground" => playground::run(rest),
        _ => {
            eprintln!("usage: cargo xtask <verify [FILTER] | figures [--out DIR] | bench [--quick] [FILTER] | tidy | fuzz [--help] | playground [--out DIR]>");
            return if cmd == "help" || cmd == "--help" {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(2)
            };
        }
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("xtask {cmd}: {e:#}");
            ExitCode::FAILURE
        }
    }
}
