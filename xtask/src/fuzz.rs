//! `cargo xtask fuzz` (see [`USAGE`]): two fuzzers.
//!
//! - `cargo xtask fuzz libfuzzer …` runs the coverage-guided cargo-fuzz (libFuzzer) targets of
//!   `fuzz/` on a nightly toolchain, whose oracles check results (finite, feasible, certified,
//!   translation-invariant), not only exit codes (`libfuzzer.rs`).
//! - `cargo xtask fuzz [mutate] …` is a mutational fuzzer of the binary's contract that needs only
//!   stable Rust, driving `curvefit::cli::run` in-process: seeds from
//!   `tests/fuzz-corpus/<command>/`, structure-aware mutations (numbers replaced by extremes,
//!   elements duplicated or dropped, fields removed, types swapped, bytes flipped), and three
//!   oracles:
//! 1. no panic (a panic is caught by `cli::run` and reported as exit code 70);
//! 2. exit code 0 or 2 only;
//! 3. on success, the output is valid JSON without `null` (serde_json writes NaN as null).
//!
//! Inputs that break an oracle are saved under `--out DIR` (default `target/fuzz/mutate`, never
//! the current directory); copied to `tests/fuzz-corpus/crashes/<command>/` they are replayed by
//! CI through `tests/tests/fuzz_corpus.rs`. Inputs that reach a new (command, exit code,
//! error-field) outcome are kept in memory as further seeds.

/// What `cargo xtask fuzz --help` prints.
pub const USAGE: &str = "\
usage: cargo xtask fuzz [mutate] [--execs N] [--seed S] [--out DIR]
       cargo xtask fuzz libfuzzer [TARGET…] [--time SECONDS | --runs N] [--out DIR]

mutate (the default; stable Rust)
  Mutates the JSON problems of tests/fuzz-corpus/<command>/ and runs the binary's contract
  in-process (curvefit::cli::run). Oracles: no panic; exit code 0 or 2; on success valid JSON
  without null; on refusal one line on standard error.
  --execs N     executions (default 100000)
  --seed S      the generator's seed (default fixed: runs are reproducible)
  --out DIR     where inputs that break an oracle are written (default target/fuzz/mutate)

libfuzzer (coverage-guided; needs `rustup toolchain install nightly` and `cargo install cargo-fuzz`)
  Runs the cargo-fuzz targets of fuzz/ (all of them when none is named): refine_json,
  refine_structured, strip_json, strip_structured, scheme_json, csv_reader. Oracles (fuzz/src/lib.rs):
  every result finite; an exact refinement certified <= 1e-9 and feasible; a strip interpolating,
  C2 and within its bounds; translated problems solved with the same energy; refusals with a
  field and a message. Seeds: fuzz/corpus/<target>/ (committed); new coverage is added there.
  --time SECONDS  per target (default 60)
  --runs N        per target instead of a time limit
  --out DIR       crash and timeout artifacts (default target/fuzz/artifacts/<target>/)
  Prints the executions per target and their total.
";

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

thread_local! {
    static LAST_PANIC: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
}

/// xorshift64*: a small deterministic generator (reproducible runs from `--seed`).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const EXTREMES: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "1e308",
    "-1e308",
    "1e-308",
    "5e-324",
    "1e400",
    "-1e400",
    "1e-12",
    "1e12",
    "0.5",
    "3",
    "1000000",
    "-7",
    "18446744073709551616",
    "null",
    "true",
    "\"x\"",
    "[]",
    "{}",
    "[[]]",
    "NaN",
    "Infinity",
];

fn mutate_value(v: &mut serde_json::Value, rng: &mut Rng, depth: usize) {
    use serde_json::Value;
    match v {
        Value::Array(a) if !a.is_empty() && depth < 8 => match rng.below(6) {
            0 => {
                let i = rng.below(a.len());
                a.remove(i);
            }
            1 => {
                let i = rng.below(a.len());
                let x = a[i].clone();
                a.insert(i, x);
            }
            2 => a.clear(),
            _ => {
                let i = rng.below(a.len());
                mutate_value(&mut a[i], rng, depth + 1);
            }
        },
        Value::Object(o) if !o.is_empty() && depth < 8 => {
            let keys: Vec<String> = o.keys().cloned().collect();
            let k = &keys[rng.below(keys.len())];
            match rng.below(6) {
                0 => {
                    o.remove(k);
                }
                1 => {
                    let x = o[k].clone();
                    o.insert(format!("{k}_"), x);
                }
                _ => {
                    if let Some(x) = o.get_mut(k) {
                        mutate_value(x, rng, depth + 1);
                    }
                }
            }
        }
        _ => {
            let text = EXTREMES[rng.below(EXTREMES.len())];
            if let Ok(x) = serde_json::from_str(text) {
                *v = x;
            } else if let Value::Number(n) = v {
                // Perturb a number instead (NaN/Infinity are not JSON; the byte mutator covers them).
                let x = n.as_f64().unwrap_or(0.0);
                *v = serde_json::json!(
                    x * (1.0 + (rng.below(5) as f64 - 2.0) * 1e-9) + rng.below(3) as f64
                );
            }
        }
    }
}

/// Numbers of `v` changed in place: mode 0 relative noise 1e-3, mode 1 rounding to one decimal
/// (creates coincident and collinear points), mode 2 multiplies every float by `scale`, mode 3
/// replaces one number by a small random value.
fn jitter(v: &mut serde_json::Value, rng: &mut Rng, mode: usize, scale: f64) {
    use serde_json::Value;
    match v {
        Value::Array(a) => a.iter_mut().for_each(|x| jitter(x, rng, mode, scale)),
        Value::Object(o) => o.iter_mut().for_each(|(_, x)| jitter(x, rng, mode, scale)),
        Value::Number(n) if n.is_f64() || mode == 2 => {
            let x = n.as_f64().unwrap_or(0.0);
            let y = match mode {
                0 => x * (1.0 + 1e-3 * (rng.below(2001) as f64 - 1000.0) / 1000.0),
                1 => (x * 10.0).round() / 10.0,
                2 if n.is_f64() => x * scale,
                3 if rng.below(8) == 0 => (rng.below(200) as f64 - 100.0) / 50.0,
                _ => x,
            };
            if let Some(m) = serde_json::Number::from_f64(y) {
                *n = m;
            }
        }
        _ => {}
    }
}

fn mutate(seed: &str, rng: &mut Rng) -> String {
    if rng.below(5) == 0 {
        // Byte-level: flip, delete, insert or splice an extreme token.
        let mut b = seed.as_bytes().to_vec();
        if b.is_empty() {
            return EXTREMES[rng.below(EXTREMES.len())].to_string();
        }
        for _ in 0..1 + rng.below(3) {
            let i = rng.below(b.len().max(1));
            match rng.below(4) {
                0 if i < b.len() => b[i] ^= 1 << rng.below(8),
                1 if i < b.len() => {
                    b.remove(i);
                }
                2 => b.insert(i.min(b.len()), b"[]{},:\"-.e0123456789"[rng.below(20)]),
                _ => {
                    let t = EXTREMES[rng.below(EXTREMES.len())].as_bytes();
                    let at = i.min(b.len());
                    b.splice(at..at, t.iter().copied());
                }
            }
        }
        return String::from_utf8_lossy(&b).into_owned();
    }
    match serde_json::from_str::<serde_json::Value>(seed) {
        Ok(mut v) if rng.below(2) == 0 => {
            // Structure-preserving: jitter or rescale the numbers so that most inputs stay valid
            // and reach the solvers (degenerate geometry, extreme scales, near-coincident points).
            let mode = rng.below(4);
            let scale = [1e-8, 1e-3, 1e3, 1e8][rng.below(4)];
            jitter(&mut v, rng, mode, scale);
            v.to_string()
        }
        Ok(mut v) => {
            for _ in 0..1 + rng.below(3) {
                mutate_value(&mut v, rng, 0);
            }
            v.to_string()
        }
        Err(_) => seed.chars().rev().collect(),
    }
}

fn load_corpus(root: &Path) -> anyhow::Result<Vec<(String, String)>> {
    let mut seeds = Vec::new();
    for cmd in ["refine", "strip", "natural", "surface"] {
        let dir = root.join(cmd);
        if let Ok(rd) = std::fs::read_dir(&dir) {
            let mut files: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
            files.sort();
            for f in files {
                seeds.push((cmd.to_string(), std::fs::read_to_string(&f)?));
            }
        }
    }
    // The built-in examples are seeds too: their file names start with the command.
    let examples = PathBuf::from("crates/curvefit/examples/data");
    if let Ok(rd) = std::fs::read_dir(&examples) {
        let mut files: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
        files.sort();
        for f in files {
            let stem = f
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if let Some(cmd) = ["refine", "strip", "natural", "surface"]
                .into_iter()
                .find(|c| stem.starts_with(c))
            {
                seeds.push((cmd.to_string(), std::fs::read_to_string(&f)?));
            }
        }
    }
    Ok(seeds)
}

pub fn run(args: &[String]) -> anyhow::Result<bool> {
    match args.first().map(String::as_str) {
        Some("--help" | "-h" | "help") => {
            print!("{USAGE}");
            return Ok(true);
        }
        Some("libfuzzer") => return crate::libfuzzer::run(&args[1..]),
        Some("mutate") => return mutational(&args[1..]),
        _ => {}
    }
    mutational(args)
}

fn mutational(args: &[String]) -> anyhow::Result<bool> {
    let mut execs: u64 = 100_000;
    let mut crash_dir = PathBuf::from("target/fuzz/mutate");
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--execs" => {
                execs = it
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--execs N"))?
                    .parse()?
            }
            "--seed" => {
                seed = it
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--seed S"))?
                    .parse()?
            }
            "--out" => {
                crash_dir = PathBuf::from(it.next().ok_or_else(|| anyhow::anyhow!("--out DIR"))?)
            }
            other => anyhow::bail!("unknown argument {other} (see cargo xtask fuzz --help)"),
        }
    }
    // Record each panic's location and message instead of printing a backtrace per crash.
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let loc = info
            .location()
            .map(|l| format!("{}:{}", l.file(), l.line()))
            .unwrap_or_default();
        LAST_PANIC.with(|p| *p.borrow_mut() = format!("{loc}: {msg}"));
    }));
    let root = PathBuf::from("tests/fuzz-corpus");
    let mut seeds = load_corpus(&root)?;
    anyhow::ensure!(!seeds.is_empty(), "no seeds in {}", root.display());
    // Seeds loaded from disk are valid problems (crash files aside); jitter mutations start from them.
    let n_base = seeds.len();
    let mut rng = Rng(seed | 1);
    let mut outcomes: HashSet<(String, i32, String)> = HashSet::new();
    let (mut crashes, mut slow) = (0u64, 0u64);
    let started = Instant::now();
    let mut codes = [0u64; 3];
    for n in 0..execs {
        let pick = if rng.below(2) == 0 {
            rng.below(n_base)
        } else {
            rng.below(seeds.len())
        };
        let (cmd, base) = seeds[pick].clone();
        let input = mutate(&base, &mut rng);
        let t = Instant::now();
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let code = curvefit::cli::run(
            ["curvefit", cmd.as_str(), "-"],
            &mut input.as_bytes(),
            &mut out,
            &mut err,
        );
        let dt = t.elapsed().as_secs_f64();
        let stdout = String::from_utf8_lossy(&out);
        let stderr = String::from_utf8_lossy(&err);
        let broken = match code {
            0 => {
                serde_json::from_str::<serde_json::Value>(&stdout).is_err()
                    || stdout.contains("null")
            }
            2 => stderr.trim_end().lines().count() != 1,
            _ => true,
        };
        codes[match code {
            0 => 0,
            2 => 1,
            _ => 2,
        }] += 1;
        if broken {
            crashes += 1;
            std::fs::create_dir_all(crash_dir.join(&cmd))?;
            let name = format!("{:016x}.json", fxhash(&input));
            std::fs::write(crash_dir.join(&cmd).join(&name), &input)?;
            println!(
                "oracle broken (exit {code}) for {cmd}: saved {}: {}",
                crash_dir.join(&cmd).join(&name).display(),
                stderr.trim()
            );
        }
        if dt > 2.0 {
            slow += 1;
            println!(
                "slow input ({dt:.1} s) for {cmd}: {}",
                &input[..input.len().min(200)]
            );
        }
        let field = stderr.split(':').nth(1).unwrap_or("").trim().to_string();
        if outcomes.insert((cmd.clone(), code, field)) && seeds.len() < 5000 {
            seeds.push((cmd, input));
        }
        if (n + 1) % 100_000 == 0 {
            println!(
                "{} execs, {} outcomes, {crashes} crashes, {:.0} execs/s",
                n + 1,
                outcomes.len(),
                (n + 1) as f64 / started.elapsed().as_secs_f64()
            );
        }
    }
    println!(
        "fuzz: {execs} executions in {:.1} s: {} ok, {} refused (exit 2), {} other; {} distinct outcomes; {crashes} oracle failures; {slow} slow inputs",
        started.elapsed().as_secs_f64(),
        codes[0],
        codes[1],
        codes[2],
        outcomes.len()
    );
    Ok(crashes == 0)
}

fn fxhash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}
