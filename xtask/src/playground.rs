//! `cargo xtask playground [--out DIR]`: the interactive page of issue 20, written to `DIR`
//! (default `target/playground`) as static files that any web server can serve.
//!
//! Steps: build `curvefit-wasm` for `wasm32-unknown-unknown` (the workspace's `wasm` profile:
//! release without debug info; its `Cargo.toml` comment says which settings were measured), bind
//! it with the `wasm-bindgen` command line (`--target web`: an ES module the page imports, no
//! bundler) into `DIR/pkg/`, optimise the bound module with `wasm-opt -O3` when Binaryen's
//! command line is there, and copy the page's sources (`crates/curvefit-wasm/www/`: HTML, plain
//! JS, CSS) next to it. The command line must be exactly the version of the `wasm-bindgen` crate
//! that `Cargo.lock` records (the two generate and read the same glue); both prerequisites are
//! checked first, and a missing one is reported with the command that installs it.
//!
//! `wasm-opt` is optional: it makes a 200-point balls solve 6–12% faster in Chromium (measured
//! A/B in one page on the browser test's drag problems, replies byte-identical: Binaryen keeps
//! IEEE semantics unless told `--fast-math`), and the page is the same without it. It is taken
//! from `$WASM_OPT`, else `wasm-opt` on the `PATH` (Debian's `binaryen`, or npm's `binaryen`,
//! which `.ci/run` installs with the browser test's packages).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context};

/// The WebAssembly target the page's module is built for (no WASI, no Emscripten: the browser).
const WASM_TARGET: &str = "wasm32-unknown-unknown";
/// The Cargo profile of the module (`[profile.wasm]` in the workspace `Cargo.toml`).
const PROFILE: &str = "wasm";
/// The WebAssembly features rustc emits for `wasm32-unknown-unknown` by default (and every
/// browser the page targets runs); `wasm-opt` is told them so that it neither rejects the module
/// nor uses a feature beyond them.
const WASM_FEATURES: [&str; 6] = [
    "--enable-bulk-memory",
    "--enable-multivalue",
    "--enable-mutable-globals",
    "--enable-nontrapping-float-to-int",
    "--enable-reference-types",
    "--enable-sign-ext",
];
/// The page's sources in the tree.
const WWW: &str = "crates/curvefit-wasm/www";

pub fn run(args: &[String]) -> anyhow::Result<bool> {
    let mut out = PathBuf::from("target/playground");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => {
                out = PathBuf::from(
                    it.next()
                        .ok_or_else(|| anyhow::anyhow!("--out needs a directory"))?,
                );
            }
            other => {
                bail!("unknown argument {other:?} (usage: cargo xtask playground [--out DIR])")
            }
        }
    }
    check_wasm_target()?;
    let version = locked_wasm_bindgen_version()?;
    check_wasm_bindgen(&version)?;

    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(&cargo)
        .args([
            "build",
            "-p",
            "curvefit-wasm",
            "--profile",
            PROFILE,
            "--target",
            WASM_TARGET,
        ])
        .status()
        .context("running cargo build for the wasm module")?;
    anyhow::ensure!(status.success(), "cargo build of curvefit-wasm failed");

    let wasm = target_dir(&cargo)?
        .join(WASM_TARGET)
        .join(PROFILE)
        .join("curvefit_wasm.wasm");
    let pkg = out.join("pkg");
    std::fs::create_dir_all(&pkg)?;
    let status = Command::new("wasm-bindgen")
        .arg("--target")
        .arg("web")
        .arg("--no-typescript")
        .arg("--out-dir")
        .arg(&pkg)
        .arg(&wasm)
        .status()
        .context("running wasm-bindgen")?;
    anyhow::ensure!(
        status.success(),
        "wasm-bindgen failed on {}",
        wasm.display()
    );

    optimise(&pkg.join("curvefit_wasm_bg.wasm"))?;
    copy_dir(Path::new(WWW), &out)?;
    println!(
        "wrote the playground to {} (serve it, e.g. `python3 -m http.server -d {}`, and open /index.html)",
        out.display(),
        out.display()
    );
    Ok(true)
}

/// `wasm-opt -O3` on the bound module, in place, when Binaryen's command line is found (see the
/// module docs); otherwise says so and leaves the module as bound.
fn optimise(wasm: &Path) -> anyhow::Result<()> {
    let cmd = std::env::var_os("WASM_OPT").unwrap_or_else(|| "wasm-opt".into());
    let found = Command::new(&cmd)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        println!(
            "note: no wasm-opt ({}): the module is not optimised after binding (6–12% slower \
             balls solves; install Debian's binaryen or npm's binaryen, or set WASM_OPT)",
            cmd.to_string_lossy()
        );
        return Ok(());
    }
    let tmp = wasm.with_extension("opt.wasm");
    let status = Command::new(&cmd)
        .arg("-O3")
        .args(WASM_FEATURES)
        .arg(wasm)
        .arg("-o")
        .arg(&tmp)
        .status()
        .context("running wasm-opt")?;
    anyhow::ensure!(status.success(), "wasm-opt failed on {}", wasm.display());
    std::fs::rename(&tmp, wasm)
        .with_context(|| format!("replacing {} by its optimised copy", wasm.display()))?;
    Ok(())
}

/// The wasm target's standard library is installed (rustup puts it under the sysroot).
fn check_wasm_target() -> anyhow::Result<()> {
    let out = Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .context("running rustc --print sysroot")?;
    let sysroot = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let lib = Path::new(&sysroot)
        .join("lib/rustlib")
        .join(WASM_TARGET)
        .join("lib");
    if !lib.is_dir() {
        bail!(
            "the Rust target {WASM_TARGET} is not installed (no {}); install it with\n    rustup target add {WASM_TARGET}",
            lib.display()
        );
    }
    Ok(())
}

/// The `wasm-bindgen` crate's version in `Cargo.lock`.
fn locked_wasm_bindgen_version() -> anyhow::Result<String> {
    let lock = std::fs::read_to_string("Cargo.lock").context("reading Cargo.lock")?;
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line.trim() == "name = \"wasm-bindgen\"" {
            if let Some(v) = lines
                .next()
                .and_then(|l| l.trim().strip_prefix("version = "))
            {
                return Ok(v.trim_matches('"').to_string());
            }
        }
    }
    bail!("Cargo.lock has no wasm-bindgen package (is crates/curvefit-wasm in the workspace?)")
}

/// `wasm-bindgen --version` prints `wasm-bindgen X.Y.Z`; it must be the locked version.
fn check_wasm_bindgen(version: &str) -> anyhow::Result<()> {
    let install = |force: &str| {
        format!(
            "install it with\n    cargo install wasm-bindgen-cli --version {version} --locked{force}\n\
             (drop --locked if the registry lacks one of its locked dependencies)"
        )
    };
    let out = match Command::new("wasm-bindgen").arg("--version").output() {
        Ok(o) if o.status.success() => o,
        _ => bail!(
            "the wasm-bindgen command line is not installed; {}",
            install("")
        ),
    };
    let text = String::from_utf8_lossy(&out.stdout);
    let got = text.split_whitespace().nth(1).unwrap_or("");
    if got != version {
        bail!(
            "wasm-bindgen {got} is installed, but Cargo.lock has the wasm-bindgen crate at {version} (the two must match); {}",
            install(" --force")
        );
    }
    Ok(())
}

fn target_dir(cargo: &str) -> anyhow::Result<PathBuf> {
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()
        .context("running cargo metadata")?;
    anyhow::ensure!(out.status.success(), "cargo metadata failed");
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    meta["target_directory"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| anyhow::anyhow!("cargo metadata has no target_directory"))
}

fn copy_dir(from: &Path, to: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let entry = entry?;
        let dest = to.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            copy_dir(&entry.path(), &dest)?;
        } else {
            std::fs::copy(entry.path(), &dest)
                .with_context(|| format!("copying {}", entry.path().display()))?;
        }
    }
    Ok(())
}
