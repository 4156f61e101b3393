//! Benchmarks for `strip`.
use super::Opts;

/// Runs this group and prints its table.
pub fn run(opts: Opts) -> anyhow::Result<()> {
    let _ = opts;
    Ok(())
}
