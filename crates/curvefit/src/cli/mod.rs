//! The `curvefit` command-line tool: framework shared by every subcommand.
//!
//! Every subcommand reads a JSON problem from a file path or `-` (stdin), writes the JSON result
//! to `-o FILE` (default stdout) and, with `--svg FILE`, a picture. Bad input gives exit code 2,
//! one line on stderr naming the field (and index), and no output file.

mod commands;
pub mod demo;
pub mod export;
pub mod fastjson;
pub mod format;
pub mod input;
pub mod output;
pub mod progress;

pub use self::commands::{natural, refine, strip, surface};
/// The JSON types of `refine` (kept at this path for existing callers; the home is
/// [`crate::spec::refine`](mod@crate::spec::refine)).
pub use crate::spec::refine as refine_types;
pub use crate::spec::InputError;
pub use input::MAX_INPUT_BYTES;
pub use output::{bytes_writer, Outputs, Writer};

use std::ffi::OsString;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, Parser, Subcommand};

/// One subcommand: a JSON problem in, a JSON solution (and optionally a picture) out.
pub trait Command {
    /// The JSON problem (`#[serde(deny_unknown_fields)]`, documented defaults).
    type Problem: crate::spec::arrays::LargeArrays;
    /// The JSON result.
    type Solution: serde::Serialize;
    /// Validates and solves; errors name the field path and index.
    fn solve(problem: &Self::Problem) -> Result<Self::Solution, InputError>;
    /// [`Command::solve`], telling the progress `line` how a long solve goes (the default: a
    /// command with no progress events solves without).
    fn solve_observed(
        problem: &Self::Problem,
        _line: &std::sync::Arc<progress::Line>,
    ) -> Result<Self::Solution, InputError> {
        Self::solve(problem)
    }
    /// The picture for `--svg`, or `None`.
    fn svg(problem: &Self::Problem, solution: &Self::Solution) -> Option<String>;
    /// Puts the points of `--points FILE.csv` into the problem.
    ///
    /// # Errors
    /// When the command takes no points from a CSV file, or the problem has points already.
    fn set_points(_problem: &mut Self::Problem, _csv: input::Csv) -> Result<(), InputError> {
        Err(InputError::new(
            "--points",
            "this subcommand reads no points from a CSV file",
        ))
    }
    /// Writes the JSON result (one line); the default is serde_json's. A command with large
    /// arrays may format them faster, byte for byte the same.
    ///
    /// # Errors
    /// The output's write errors.
    fn write_json(solution: &Self::Solution, w: &mut dyn Write) -> std::io::Result<()> {
        format::write_json(solution, w)
    }
    /// The result's main array for `--format csv|npy`, or `None` (JSON only).
    fn table(_solution: &Self::Solution) -> Option<format::Table<'_>> {
        None
    }
    /// The curve for `--export` in `format` (`samples`: the CSV count), or `None` when the
    /// command has no curve to export.
    fn export(
        _problem: &Self::Problem,
        _solution: &Self::Solution,
        _format: crate::export::ExportFormat,
        _samples: Option<usize>,
    ) -> Option<Result<String, InputError>> {
        None
    }
    /// A mesh for `--obj` (Wavefront OBJ text), or `None` when the command has none.
    fn obj(
        _problem: &Self::Problem,
        _solution: &Self::Solution,
    ) -> Option<Result<String, InputError>> {
        None
    }
}

/// `curvefit scheme`: flags in, JSON out (written atomically to `-o` or standard output).
fn run_scheme_cmd(
    a: &SchemeArgs,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> Result<(), Failure> {
    let t0 = Instant::now();
    if a.levels.is_some() && a.apply.is_none() {
        // (The rules alone have no levels: the flag would be ignored.)
        return Err(InputError::new("--levels", "needs --apply POLYGON.json").into());
    }
    let polygon = match &a.apply {
        Some(p) => Some(input::read_problem_file(p, "--apply").map_err(|e| {
            let field = if e.field.is_empty() || e.field == "problem" {
                "polygon".to_string()
            } else if e.field.starts_with("--") {
                // The file itself (cannot open it, a directory): the flag that named it.
                e.field.clone()
            } else {
                format!("polygon.{}", e.field)
            };
            InputError::new(field, e.message)
        })?),
        None => None,
    };
    let t1 = Instant::now();
    let problem = crate::spec::SchemeProblem {
        points: a.stencil,
        arity: a.arity,
        surface: a.surface,
        polygon,
        levels: a.levels.unwrap_or(1),
    };
    // Field names of the JSON problem back to the flags they came from.
    let value = crate::spec::scheme(&problem).map_err(|e| {
        let field = match e.field.as_str() {
            "points" => "--stencil".to_string(),
            "arity" => "--arity".to_string(),
            "levels" => "--levels".to_string(),
            f => f.to_string(),
        };
        InputError::new(field, e.message)
    })?;
    let t2 = Instant::now();
    let json = serde_json::to_string(&value).map_err(|e| InputError::new("", e))? + "\n";
    let mut outputs = Outputs::new();
    outputs.add("-o", a.output.as_deref(), bytes_writer(json.into_bytes()))?;
    outputs.commit(stdout)?;
    if a.timings {
        let line = serde_json::json!({
            "parse_s": (t1 - t0).as_secs_f64(),
            "solve_s": (t2 - t1).as_secs_f64(),
            "write_s": t2.elapsed().as_secs_f64(),
        });
        writeln!(stderr, "{line}").map_err(|e| {
            InputError::new("--timings", format!("cannot write to standard error: {e}"))
        })?;
    }
    Ok(())
}

/// The message on one line: control characters (e.g. a newline inside an unknown field's name)
/// are escaped, so the error is always exactly one line on stderr.
fn one_line(s: &str) -> String {
    s.chars()
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect()
}

/// Exit code for bad input (and any other refusal): nothing was written.
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit code for an internal error (a bug): nothing was written.
pub const EXIT_INTERNAL: i32 = 70;

#[derive(Parser, Debug)]
#[command(
    name = "curvefit",
    version,
    about = "Variational curve refinement and constrained spline interpolation",
    long_about = None,
    arg_required_else_help = true,
    after_help = "Every JSON subcommand reads its problem from a file, `-` or standard input; `curvefit schema SUBCOMMAND` prints its fields, docs/input.md explains them."
)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

/// Options shared by the JSON subcommands.
#[derive(Args, Debug, Clone, Default)]
pub struct JsonArgs {
    /// Problem file (JSON); `-` or nothing reads standard input (nothing: unless `--points` is
    /// given, then the problem is `{}` with those points).
    pub problem: Option<PathBuf>,
    /// Write the JSON result here (default: standard output).
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also draw the result as an SVG picture.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Read the problem's points from a CSV file: one point per line, coordinates separated by
    /// commas, an optional header line (`x,y`); for `strip` two columns, t and y.
    #[arg(long = "points", value_name = "FILE.csv")]
    pub points_csv: Option<PathBuf>,
    /// Output format: the whole JSON result, or the result's main array (refined points,
    /// strip pieces) as CSV or as a NumPy .npy file [default: json, or the -o file's extension]
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub format: Option<format::Format>,
    /// Print one JSON line {"parse_s", "solve_s", "write_s"} on standard error.
    #[arg(long)]
    pub timings: bool,
    /// `--export FILE` (refine): the limit curve as CSV, SVG, DXF or JSON.
    #[command(flatten)]
    pub export: export::ExportArgs,
    /// No progress line on standard error (by default a solve running past a second shows its
    /// stage, iteration, residual and time there when standard error is a terminal).
    #[arg(short = 'q', long)]
    pub quiet: bool,
    /// Whether standard input is a terminal (then no problem file is an error, not a wait).
    #[arg(skip)]
    pub stdin_is_terminal: bool,
    /// Whether standard error is a terminal (then a long solve shows a progress line).
    #[arg(skip)]
    pub stderr_is_terminal: bool,
}

/// Options of `curvefit scheme`.
#[derive(Args, Debug, Clone)]
pub struct SchemeArgs {
    /// Stencil size: the number of points P = 2m + 2 of the rule (even, 2 ≤ P ≤ 16; the JSON
    /// result's "points").
    #[arg(long, value_name = "P")]
    pub stencil: usize,
    /// Arity N ≥ 2 (binary 2, ternary 3, …).
    #[arg(long, value_name = "N")]
    pub arity: usize,
    /// Also print the tensor-product surface rules.
    #[arg(long)]
    pub surface: bool,
    /// Apply the scheme to this polygon ({"points": [[…], …], "closed": bool}).
    #[arg(long, value_name = "POLYGON.json")]
    pub apply: Option<PathBuf>,
    /// Levels of refinement for `--apply` [default: 1].
    #[arg(long)]
    pub levels: Option<usize>,
    /// Write the JSON result here (default: standard output).
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Print one JSON line {"parse_s", "solve_s", "write_s"} on standard error.
    #[arg(long)]
    pub timings: bool,
}

/// Options of `curvefit surface`.
#[derive(Args, Debug, Clone)]
pub struct SurfaceArgs {
    #[command(flatten)]
    json: JsonArgs,
    /// Write the refined quad mesh as Wavefront OBJ.
    #[arg(long, value_name = "FILE")]
    obj: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Kersey variational refinement (interpolation, balls, smoothing, half-spaces, tangents).
    Refine(JsonArgs),
    /// Best interpolation in a strip (Dontchev–Kolmanovsky).
    Strip(JsonArgs),
    /// Warren–Weimer natural cubic subdivision on [0, L].
    Natural(JsonArgs),
    /// The (2m+2)-point n-ary interpolating rules (exact rationals), optionally applied to a polygon.
    Scheme(SchemeArgs),
    /// The tensor-product n-ary scheme on a quad grid; `--obj` writes the refined quad mesh.
    Surface(SurfaceArgs),
    /// The JSON Schema of a subcommand's problem (generated from the types).
    Schema {
        /// refine, strip, scheme, surface or natural.
        #[arg(value_parser = clap::builder::PossibleValuesParser::new(crate::spec::SUBCOMMANDS))]
        subcommand: String,
        /// Write the schema here (default: standard output).
        #[arg(short = 'o', long = "output", value_name = "FILE")]
        output: Option<PathBuf>,
    },
    /// The main job on built-in data: solves the seeds' examples, writes SVGs, index.html and a summary.
    Demo {
        /// Output directory.
        #[arg(long, default_value = "demo-out")]
        out: PathBuf,
    },
}

/// What went wrong, and which exit code it maps to.
#[derive(Debug)]
pub struct Failure {
    /// Exit code.
    pub code: i32,
    /// The one-line message.
    pub error: InputError,
}

impl From<InputError> for Failure {
    fn from(error: InputError) -> Self {
        Failure {
            code: EXIT_BAD_INPUT,
            error,
        }
    }
}

/// Runs the command line `args` (including the program name) with the given streams and returns
/// the process exit code. Never panics on bad input; a panic inside a solver is caught and
/// reported as an internal error with nothing written.
pub fn run<I, T>(
    args: I,
    stdin: &mut dyn Read,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    run_with_terminal(args, stdin, false, stdout, stderr)
}

/// [`run`], told whether standard input is a terminal: then a JSON subcommand without a problem
/// file refuses instead of waiting for input.
pub fn run_with_terminal<I, T>(
    args: I,
    stdin: &mut dyn Read,
    stdin_is_terminal: bool,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    run_with_terminals(
        args,
        stdin,
        Terminals {
            stdin: stdin_is_terminal,
            stderr: false,
        },
        stdout,
        stderr,
    )
}

/// Which of the process's streams are terminals.
#[derive(Clone, Copy, Debug, Default)]
pub struct Terminals {
    /// Standard input: a JSON subcommand without a problem file refuses instead of waiting.
    pub stdin: bool,
    /// The process's standard error: a long solve shows a progress line there
    /// ([`progress`]; written to the process's standard error, not to `stderr`).
    pub stderr: bool,
}

/// [`run`], told which streams are terminals.
pub fn run_with_terminals<I, T>(
    args: I,
    stdin: &mut dyn Read,
    terminals: Terminals,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            // A bare `curvefit` (or `curvefit scheme` without flags): the usage and the list of
            // subcommands, on standard error, exit 2.
            let _ = write!(stderr, "{}", e.render());
            return EXIT_BAD_INPUT;
        }
        Err(e) => {
            let code = if e.use_stderr() { EXIT_BAD_INPUT } else { 0 };
            let text = e.render().to_string();
            if code == 0 {
                // `--help`, `--version`: a failed write (e.g. `> /dev/full`) is an error too.
                if stdout
                    .write_all(text.as_bytes())
                    .and_then(|_| stdout.flush())
                    .is_err()
                {
                    let _ = writeln!(stderr, "error: cannot write to standard output");
                    return EXIT_BAD_INPUT;
                }
            } else {
                // One line: clap's message up to its usage section, whitespace collapsed.
                let msg: Vec<&str> = text
                    .lines()
                    .take_while(|l| {
                        !l.starts_with("Usage:") && !l.starts_with("For more information")
                    })
                    .map(str::trim)
                    .filter(|l| !l.is_empty())
                    .collect();
                let line = if msg.is_empty() {
                    "error: invalid arguments".to_string()
                } else {
                    msg.join(" ")
                };
                let _ = writeln!(stderr, "{}", one_line(&line));
            }
            return code;
        }
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        dispatch(cli, stdin, terminals, stdout, stderr)
    }));
    match result {
        Ok(Ok(())) => 0,
        Ok(Err(f)) => {
            let _ = writeln!(stderr, "error: {}", one_line(&f.error.to_string()));
            f.code
        }
        Err(_) => {
            let _ = writeln!(
                stderr,
                "error: internal error (a bug in curvefit); nothing was written"
            );
            EXIT_INTERNAL
        }
    }
}

fn dispatch(
    cli: Cli,
    stdin: &mut dyn Read,
    terminals: Terminals,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> Result<(), Failure> {
    let mut command = cli.command;
    let json = match &mut command {
        Cmd::Refine(a) | Cmd::Strip(a) | Cmd::Natural(a) => Some(a),
        Cmd::Surface(a) => Some(&mut a.json),
        _ => None,
    };
    if let Some(a) = json {
        a.stdin_is_terminal = terminals.stdin;
        a.stderr_is_terminal = terminals.stderr;
    }
    match command {
        Cmd::Refine(a) => run_json::<refine::RefineCmd>(&a, "refine", stdin, stdout, stderr),
        Cmd::Strip(a) => run_json::<strip::Strip>(&a, "strip", stdin, stdout, stderr),
        Cmd::Natural(a) => run_json::<natural::NaturalCmd>(&a, "natural", stdin, stdout, stderr),
        Cmd::Surface(a) => run_json_with::<surface::SurfaceCmd>(
            &a.json,
            "surface",
            a.obj.as_deref(),
            stdin,
            stdout,
            stderr,
        ),
        Cmd::Scheme(a) => run_scheme_cmd(&a, stdout, stderr),
        Cmd::Demo { out } => Ok(demo::run(&out, stdout, solve_example)?),
        Cmd::Schema { subcommand, output } => {
            let schema = crate::spec::schema(&subcommand).ok_or_else(|| {
                InputError::new("subcommand", format!("no schema for `{subcommand}`"))
            })?;
            let text = serde_json::to_string_pretty(&schema).map_err(|e| InputError::new("", e))?;
            let mut outputs = Outputs::new();
            outputs.add(
                "-o",
                output.as_deref(),
                bytes_writer((text + "\n").into_bytes()),
            )?;
            Ok(outputs.commit(stdout)?)
        }
    }
}

/// Solves one built-in example with its subcommand.
fn solve_example(ex: &demo::Example) -> Result<demo::Summary, InputError> {
    match ex.command {
        "refine" => demo::solve_with::<refine::RefineCmd>(ex.problem, |s| {
            format!(
                "N = {}, E = {:.6}, KKT = {:.1e}",
                s.points.len(),
                s.energy,
                s.kkt_residual
            )
        }),
        "strip" => demo::solve_with::<strip::Strip>(ex.problem, |s| {
            format!(
                "‖f''‖ = {:.6}, ∫f''² = {:.6}, {} extra knots, {} iterations, |∇Φ| = {:.1e}",
                s.norm,
                s.energy,
                s.extra_knots.len(),
                s.iterations,
                s.gradient_norm
            )
        }),
        "natural" => demo::solve_with::<natural::NaturalCmd>(ex.problem, |s| {
            let last = s.levels.last().map_or(f64::NAN, |l| l.energy);
            format!(
                "level {} energy {:.6} → exact limit {:.6}",
                s.levels.len().saturating_sub(1),
                last,
                s.limit_energy
            )
        }),
        "surface" => demo::solve_with::<surface::SurfaceCmd>(ex.problem, |s| {
            format!(
                "{} × {} grid after {} levels, {} quads",
                s.rows,
                s.cols,
                s.levels,
                s.quads.len()
            )
        }),
        other => Err(InputError::new(
            "command",
            format!("unknown example command {other}"),
        )),
    }
}

/// The generic JSON pipeline: read → parse (with field paths) → solve → serialize → write
/// atomically (temporary file + rename, all outputs prepared before any is renamed).
pub fn run_json<C: Command>(
    args: &JsonArgs,
    name: &str,
    stdin: &mut dyn Read,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> Result<(), Failure> {
    run_json_with::<C>(args, name, None, stdin, stdout, stderr)
}

/// [`run_json`] with an optional OBJ mesh output (from [`Command::obj`]).
pub fn run_json_with<C: Command>(
    args: &JsonArgs,
    name: &str,
    obj: Option<&Path>,
    stdin: &mut dyn Read,
    stdout: &mut dyn Write,
    stderr: &mut dyn Write,
) -> Result<(), Failure> {
    let t0 = Instant::now();
    args.export.check()?;
    let problem: C::Problem = parse_problem::<C>(args, stdin)?;
    let t1 = Instant::now();
    let solution = if args.stderr_is_terminal && !args.quiet {
        let line = progress::Line::new(name_static(name));
        let solution = C::solve_observed(&problem, &line);
        line.finish();
        solution?
    } else {
        C::solve(&problem)?
    };
    let t2 = Instant::now();
    let svg = match &args.svg {
        Some(_) => C::svg(&problem, &solution),
        None => None,
    };
    let mut outputs = Outputs::new();
    // The result is streamed into its file (or standard output): no copy of it in memory.
    let fmt = format::Format::choose(args.format, args.output.as_deref());
    let json: Writer<'_> = Box::new(|w: &mut dyn Write| C::write_json(&solution, w));
    let result = format::writer(fmt, json, C::table(&solution), name)?;
    outputs.add("-o", args.output.as_deref(), result)?;
    if let Some(path) = obj {
        let text = C::obj(&problem, &solution)
            .ok_or_else(|| InputError::new("--obj", format!("`{name}` has no mesh output")))??;
        outputs.add("--obj", Some(path), bytes_writer(text.into_bytes()))?;
    }
    if let Some(path) = &args.export.export_file {
        let format = args.export.format(path)?;
        let text =
            C::export(&problem, &solution, format, args.export.samples).ok_or_else(|| {
                InputError::new("--export", format!("`{name}` has no curve to export"))
            })??;
        outputs.add("--export", Some(path), bytes_writer(text.into_bytes()))?;
    }
    match (&args.svg, svg) {
        (Some(path), Some(svg)) => {
            outputs.add("--svg", Some(path), bytes_writer(svg.into_bytes()))?
        }
        (Some(path), None) => {
            return Err(InputError::new(
                "--svg",
                format!(
                    "`{name}` has no picture for this problem ({})",
                    path.display()
                ),
            )
            .into())
        }
        _ => {}
    }
    outputs.commit(stdout)?;
    let t3 = Instant::now();
    if args.timings {
        let line = serde_json::json!({
            "parse_s": (t1 - t0).as_secs_f64(),
            "solve_s": (t2 - t1).as_secs_f64(),
            "write_s": (t3 - t2).as_secs_f64(),
        });
        writeln!(stderr, "{line}").map_err(|e| {
            InputError::new("--timings", format!("cannot write to standard error: {e}"))
        })?;
    }
    Ok(())
}

/// The subcommand's name for the progress line.
fn name_static(name: &str) -> &'static str {
    crate::spec::SUBCOMMANDS
        .iter()
        .copied()
        .find(|s| *s == name)
        .unwrap_or("curvefit")
}

/// Reads and parses the problem (streamed: the text is never held); `--points FILE.csv`
/// supplies `points` (or `t` and `y`), which the problem must not have already.
fn parse_problem<C: Command>(args: &JsonArgs, stdin: &mut dyn Read) -> Result<C::Problem, Failure> {
    let mut problem: C::Problem = match &args.problem {
        Some(p) if p.as_os_str() == "-" => input::read_problem(stdin, "standard input")?,
        Some(p) => input::read_problem_file(p, "problem")?,
        None if args.points_csv.is_some() => crate::spec::from_json("{}")?,
        None if args.stdin_is_terminal => {
            return Err(InputError::new(
                "problem",
                "no problem given: name a JSON file, or pipe one into standard input (curvefit refine < problem.json)",
            )
            .into())
        }
        None => input::read_problem(stdin, "standard input")?,
    };
    if let Some(csv) = &args.points_csv {
        let what = csv.display().to_string();
        let points = input::read_csv(input::open(csv, "--points")?, &what)?;
        C::set_points(&mut problem, points)?;
    }
    Ok(problem)
}
