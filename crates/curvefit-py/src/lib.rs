//! # curvefit for Python: the extension module `curvefit._curvefit`
//!
//! The Python package `curvefit` (`python/curvefit/`, built by maturin from `pyproject.toml` in
//! this folder: `pip install ./crates/curvefit-py`) calls the command line's JSON contract,
//! [`curvefit::spec`], in process. A problem given as keyword arguments is read by the same serde
//! types as `curvefit SUBCOMMAND file.json` — same names, defaults, validation and messages —
//! through `de::PyDe`, a `serde::Deserializer` over Python objects (numpy arrays are read in
//! place: the only copy is the one into the problem's own vectors; a large array given as a
//! C-contiguous float64 array is copied as one slice, `bulk`). The solve runs with the GIL
//! released ([`Python::detach`]) and with panics caught; the result comes back as a dict of numpy
//! arrays and scalars whose keys are the JSON result's fields (`out`), which the Python layer
//! wraps in its result classes.
//!
//! | function | does |
//! |---|---|
//! | `solve(subcommand, problem)` | one problem (a dict of the JSON's fields) → the result's dict; raises `curvefit.InputError` |
//! | `solve_many(subcommand, problems, threads)` | a list of problems solved in parallel (rayon) → results or `InputError` instances, in order |
//! | `schema(subcommand)` | the JSON Schema of the problem, as JSON text |
//!
//! # Building, and why this crate is an ordinary workspace member
//! PyO3 0.30 links an extension module without libpython when maturin (≥ 1.9.4) sets
//! `PYO3_BUILD_EXTENSION_MODULE`; the deprecated `pyo3/extension-module` feature, which broke
//! the linking of test binaries, is not used. A plain `cargo build`, `cargo clippy --workspace`
//! or `cargo test --workspace` builds this cdylib linked against the interpreter's libpython
//! (found by PyO3's build script from `python3` on `PATH`), and the crate has no Rust test
//! harness (`test = false`: the module is tested from Python, by the pytest suite in
//! `tests/`, which `.ci/run` runs against a freshly installed wheel), so nothing here needs a
//! Python interpreter at `cargo test` time.
//!
//! The module uses the stable ABI (`abi3-py39`): one wheel serves CPython 3.9 and later.

/// mimalloc, not the system allocator: repeated solves reuse the memory of the previous one
/// instead of faulting fresh pages in (glibc's malloc hands blocks of megabytes back to the
/// kernel on free; ~4 µs per 4 KiB page on the development VM). The arrays handed to numpy are
/// freed by this allocator too (their owner is a Rust `Vec`).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod bulk;
mod de;
mod out;

use std::panic::{catch_unwind, AssertUnwindSafe};

use curvefit::spec::arrays::LargeArrays;
use curvefit::spec::{self, InputError};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyMapping};
use rayon::prelude::*;

/// A parsed problem of one subcommand.
enum Problem {
    Refine(spec::RefineProblem),
    Strip(spec::StripProblem),
    Scheme(spec::SchemeProblem),
    Surface(spec::SurfaceProblem),
    Natural(spec::NaturalProblem),
}

/// A solution of one subcommand.
enum Solution {
    Refine(spec::RefineResult),
    Strip(spec::StripResult),
    Scheme(spec::SchemeResult),
    Surface(spec::SurfaceResult),
    Natural(spec::NaturalResult),
}

/// Why a problem has no solution.
enum Failure {
    /// Bad input, in the command line's words.
    Input(InputError),
    /// A panic inside the library (a bug), with its message.
    Panic(String),
}

/// The subcommand named `name`, checked before any problem is read.
fn check_subcommand(name: &str) -> PyResult<()> {
    if spec::SUBCOMMANDS.contains(&name) {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "unknown subcommand {name:?}: one of {}",
            spec::SUBCOMMANDS.join(", ")
        )))
    }
}

/// Reads one problem of type `P` from a Python mapping, naming the field of any error.
fn parse<'py, P: LargeArrays>(
    obj: &Bound<'py, PyAny>,
    ctx: &de::Ctx<'py>,
) -> Result<P, InputError> {
    // A problem is an object, as for the command line (which refuses anything else by its
    // first character).
    if obj.cast::<PyDict>().is_err() && obj.cast::<PyMapping>().is_err() {
        return Err(spec::not_an_object(Some(b'[')).err().unwrap_or_else(|| {
            InputError::new("problem", "must be a mapping of the problem's fields")
        }));
    }
    // The large arrays in bulk (`bulk`) when they are all they seem, the rest as given.
    if let Some(bulk::Taken { rest, arrays }) = bulk::take::<P>(obj) {
        ctx.trailing.set(None);
        let read = P::deserialize(de::PyDe::new(&rest, ctx)).ok();
        if let Some(p) = read.and_then(|p| p.with_arrays(arrays)) {
            return Ok(p);
        }
    }
    // Untracked first: the field path is wanted only for an error, and tracking it was a
    // quarter of a 10^5-point interpolation called from Python. A failure is read again with the
    // path tracked (the same reader over the same objects — sequences and mappings, which
    // reading does not consume — so the same error).
    ctx.trailing.set(None);
    if let Ok(p) = P::deserialize(de::PyDe::new(obj, ctx)) {
        return Ok(p);
    }
    ctx.trailing.set(None);
    match serde_path_to_error::deserialize(de::PyDe::new(obj, ctx)) {
        Ok(p) => Ok(p),
        Err(e) => {
            let path = e.path().to_string();
            let path = if path == "." { String::new() } else { path };
            let mut err = spec::path_error(e);
            // A key that is not a string has no name: the path ends at its dict (serde's
            // tracker writes `?` for it).
            if let Some(owner) = err.field.strip_suffix(".?") {
                err = InputError::new(owner, err.message);
            }
            // The command line reports these two at a line and column of the file; here there
            // is no file, so the field path says where.
            if err.field == "problem" && err.message.starts_with("malformed JSON") {
                return Err(match ctx.trailing.get() {
                    Some((taken, len)) => InputError::new(
                        path,
                        format!(
                            "must be an array of {taken} entries, not an array of {len} entries"
                        ),
                    ),
                    None => InputError::new(path, "is a value of the wrong kind"),
                });
            }
            Err(err)
        }
    }
}

fn parse_problem<'py>(
    subcommand: &str,
    obj: &Bound<'py, PyAny>,
    ctx: &de::Ctx<'py>,
) -> Result<Problem, InputError> {
    Ok(match subcommand {
        "refine" => Problem::Refine(parse(obj, ctx)?),
        "strip" => Problem::Strip(parse(obj, ctx)?),
        "scheme" => Problem::Scheme(parse(obj, ctx)?),
        "surface" => Problem::Surface(parse(obj, ctx)?),
        _ => Problem::Natural(parse(obj, ctx)?),
    })
}

/// Runs `f`, turning a panic into [`Failure::Panic`] with its message: nothing unwinds into
/// Python (where PyO3 would raise a `BaseException`).
fn guard<T>(f: impl FnOnce() -> Result<T, Failure>) -> Result<T, Failure> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into());
            Err(Failure::Panic(msg))
        }
    }
}

/// Solves without touching Python (callable with the GIL released). The problem is consumed: a
/// refinement's and a strip's arrays move into the solve, no copy.
fn solve_problem(p: Problem) -> Result<Solution, Failure> {
    guard(|| {
        Ok(match p {
            Problem::Refine(p) => {
                Solution::Refine(spec::refine::solve_owned(p).map_err(Failure::Input)?)
            }
            Problem::Strip(p) => {
                Solution::Strip(spec::strip::solve_owned(p).map_err(Failure::Input)?)
            }
            Problem::Scheme(p) => Solution::Scheme(spec::scheme(&p).map_err(Failure::Input)?),
            Problem::Surface(p) => Solution::Surface(spec::surface(&p).map_err(Failure::Input)?),
            Problem::Natural(p) => Solution::Natural(spec::natural(&p).map_err(Failure::Input)?),
        })
    })
}

/// Reads one problem, a panic while reading included.
fn read_problem<'py>(
    subcommand: &str,
    obj: &Bound<'py, PyAny>,
    ctx: &de::Ctx<'py>,
) -> Result<Problem, Failure> {
    guard(|| parse_problem(subcommand, obj, ctx).map_err(Failure::Input))
}

fn to_python<'py>(py: Python<'py>, s: Solution) -> PyResult<Bound<'py, PyDict>> {
    match s {
        Solution::Refine(r) => out::refine(py, r),
        Solution::Strip(r) => out::strip(py, r),
        Solution::Scheme(r) => out::scheme(py, r),
        Solution::Surface(r) => out::surface(py, r),
        Solution::Natural(r) => out::natural(py, r),
    }
}

/// The Python exception object for a failure (`curvefit.InputError` or
/// `curvefit.InternalError`, defined in `curvefit/_errors.py`).
fn exception<'py>(py: Python<'py>, f: Failure) -> PyResult<Bound<'py, PyAny>> {
    let errors = py.import("curvefit._errors")?;
    match f {
        Failure::Input(e) => errors
            .getattr("InputError")?
            .call1((e.field, e.index, e.message)),
        Failure::Panic(msg) => errors.getattr("InternalError")?.call1((format!(
            "internal error (a bug in curvefit, please report it with the problem): {msg}"
        ),)),
    }
}

/// `solve(subcommand, problem)`: one problem, given as a mapping of the JSON problem's fields,
/// solved with the GIL released. Returns the result's fields as a dict; raises
/// `curvefit.InputError` for bad input.
#[pyfunction]
fn solve<'py>(
    py: Python<'py>,
    subcommand: &str,
    problem: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    check_subcommand(subcommand)?;
    let ctx = de::Ctx::new(py)?;
    let parsed = match read_problem(subcommand, problem, &ctx) {
        Ok(p) => p,
        Err(f) => return Err(PyErr::from_value(exception(py, f)?)),
    };
    match py.detach(|| solve_problem(parsed)) {
        Ok(s) => to_python(py, s),
        Err(f) => Err(PyErr::from_value(exception(py, f)?)),
    }
}

/// `solve_many(subcommand, problems, threads=None)`: every problem read (with the GIL), then
/// all solved in parallel on `threads` threads (default: rayon's global pool, one thread per
/// core) with the GIL released. Returns one entry per problem, in order: the result's dict,
/// or the `curvefit.InputError` (or `curvefit.InternalError`) instance for that problem.
#[pyfunction]
#[pyo3(signature = (subcommand, problems, threads=None))]
fn solve_many<'py>(
    py: Python<'py>,
    subcommand: &str,
    problems: &Bound<'py, PyAny>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyList>> {
    check_subcommand(subcommand)?;
    let pool = match threads {
        None => None,
        Some(0) => {
            return Err(PyValueError::new_err(
                "threads must be at least 1 (or None)",
            ))
        }
        Some(n) => Some(
            curvefit::threads::builder(Some(n))
                .build()
                .map_err(|e| PyValueError::new_err(format!("threads: {e}")))?,
        ),
    };
    let ctx = de::Ctx::new(py)?;
    let mut parsed = Vec::new();
    for item in problems.try_iter()? {
        parsed.push(read_problem(subcommand, &item?, &ctx));
    }
    let solved: Vec<Result<Solution, Failure>> = py.detach(|| {
        let run = || {
            parsed
                .into_par_iter()
                .map(|p| p.and_then(solve_problem))
                .collect()
        };
        match &pool {
            Some(pool) => pool.install(run),
            None => run(),
        }
    });
    let list = PyList::empty(py);
    for s in solved {
        match s {
            Ok(s) => list.append(to_python(py, s)?)?,
            Err(f) => list.append(exception(py, f)?)?,
        }
    }
    Ok(list)
}

/// `schema(subcommand)`: the JSON Schema (draft 2020-12) of the subcommand's problem, as JSON
/// text — what `curvefit schema SUBCOMMAND` prints.
#[pyfunction]
fn schema(subcommand: &str) -> PyResult<String> {
    check_subcommand(subcommand)?;
    let v = spec::schema(subcommand)
        .ok_or_else(|| PyValueError::new_err(format!("no schema for {subcommand:?}")))?;
    serde_json::to_string_pretty(&v).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `_panic_guard_check()`: raises what a panic inside the library raises (for the tests of
/// that path: no input makes the library panic on purpose).
#[pyfunction]
fn _panic_guard_check(py: Python<'_>) -> PyResult<()> {
    match guard(|| -> Result<(), Failure> { panic!("the guard's own check") }) {
        Ok(()) => Ok(()),
        Err(f) => Err(PyErr::from_value(exception(py, f)?)),
    }
}

#[pymodule]
fn _curvefit(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The solves' worker threads, each on its own processor (`curvefit::threads`).
    curvefit::threads::install_global();
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve_many, m)?)?;
    m.add_function(wrap_pyfunction!(schema, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_guard_check, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
