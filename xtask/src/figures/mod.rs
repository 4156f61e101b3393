//! `cargo xtask figures [--out DIR]`: redraws the seeds' figures as SVG (default `figures-out/`).

mod refine;
mod refine_constraints;
mod schemes;
mod strip;

use std::path::{Path, PathBuf};

/// Writes one SVG document to `dir/name` and reports it.
pub fn save(dir: &Path, name: &str, svg: &str) -> anyhow::Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, svg)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Runs every figure generator.
pub fn run(args: &[String]) -> anyhow::Result<bool> {
    let mut out = PathBuf::from("figures-out");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--out" {
            out = PathBuf::from(
                it.next()
                    .ok_or_else(|| anyhow::anyhow!("--out needs a directory"))?,
            );
        }
    }
    std::fs::create_dir_all(&out)?;
    refine::draw(&out)?;
    refine::draw_free_knots(&out)?;
    refine_constraints::draw(&out)?;
    schemes::draw(&out)?;
    strip::draw(&out)?;
    Ok(true)
}
