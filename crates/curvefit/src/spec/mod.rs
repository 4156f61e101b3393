//! The JSON contract of every subcommand, as a library: the problem and result types, their
//! validation (errors name the user's field and index) and one entry point per subcommand that
//! turns a problem into a result.
//!
//! | entry point | problem | result | library call |
//! |---|---|---|---|
//! | [`refine()`] | [`RefineProblem`] | [`RefineResult`] | [`::refine::Problem::solve`] |
//! | [`strip()`] | [`StripProblem`] | [`StripResult`] | [`strip::solve`](::strip::solve) |
//! | [`scheme()`] | [`SchemeProblem`] | [`SchemeResult`] | [`subdivision::NaryScheme`] |
//! | [`surface()`] | [`SurfaceProblem`] | [`SurfaceResult`] | [`subdivision::NaryScheme::subdivide_grid`] |
//! | [`natural()`] | [`NaturalProblem`] | [`NaturalResult`] | [`subdivision::NaturalScheme`] |
//!
//! The `curvefit` binary, the Python package and the WebAssembly page all call these functions,
//! so a problem means the same everywhere: `curvefit refine f.json` prints
//! `serde_json::to_string(&spec::refine(&problem)?)` for the problem [`from_json`] reads from
//! `f.json`. This module needs only `serde` and `serde_json` (plus `serde_path_to_error`, which
//! depends on `serde` alone, for the field paths of parse errors); it does no I/O.
//!
//! ```
//! use curvefit::spec;
//! let problem: spec::RefineProblem =
//!     spec::from_json(r#"{"points": [[0, 0], [1, 0], [0, 1]], "closed": true}"#).unwrap();
//! let result = spec::refine(&problem).unwrap();
//! assert!(result.kkt_residual <= 1e-9);
//! let bad = spec::from_json::<spec::RefineProblem>(r#"{"points": [[0, 0], [1, "x"]]}"#);
//! assert_eq!(bad.unwrap_err().field, "points[1][1]");
//! ```

pub mod arrays;
pub mod messages;
pub mod natural;
pub(crate) mod points;
pub mod refine;
mod refine_types;
pub mod scheme;
pub mod strip;
pub mod surface;
mod tagged;

use std::fmt::Display;

pub use self::natural::{NaturalProblem, NaturalSolution as NaturalResult};
pub use self::points::{Numbers, Rows, MAX_NUMBERS, MAX_POINT_COORDS};
pub use self::refine::{RefineProblem, RefineResult};
pub use self::scheme::{SchemeProblem, SchemeResult};
pub use self::strip::{Problem as StripProblem, Solution as StripResult};
pub use self::surface::{SurfaceProblem, SurfaceSolution as SurfaceResult};

/// A bad-input error: the user's field path (e.g. `points[3]`, `constraint.radii[2]`,
/// `tangents[1].direction`), the index of the offending entry, and what is wrong in the user's
/// words. The command line prints it as `error: {field}: {message}`.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct InputError {
    /// Path of the offending field, with indices (`""` when the problem as a whole is wrong).
    pub field: String,
    /// The first index in `field` (the data point, bound piece or knot at fault), if any.
    pub index: Option<usize>,
    /// What is wrong with it.
    pub message: String,
}

impl InputError {
    /// A new error for the field path `field`; [`InputError::index`] is read from its first
    /// `[i]`.
    pub fn new(field: impl Into<String>, message: impl Display) -> Self {
        let field = field.into();
        let index = first_index(&field);
        InputError {
            field,
            index,
            message: message.to_string(),
        }
    }
}

/// The first `[i]` of a field path.
fn first_index(field: &str) -> Option<usize> {
    let open = field.find('[')?;
    let close = open + field[open..].find(']')?;
    field[open + 1..close].parse().ok()
}

impl Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.field, self.message)
        }
    }
}

impl std::error::Error for InputError {}

/// `refine`: Kersey's variational refinement ([`refine::solve`]).
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn refine(problem: &RefineProblem) -> Result<RefineResult, InputError> {
    self::refine::solve(problem)
}

/// `strip`: best interpolation in a strip ([`strip::solve`]).
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn strip(problem: &StripProblem) -> Result<StripResult, InputError> {
    self::strip::solve(problem)
}

/// `scheme`: the (2m+2)-point n-ary rules ([`scheme::solve`]).
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn scheme(problem: &SchemeProblem) -> Result<SchemeResult, InputError> {
    self::scheme::solve(problem)
}

/// `surface`: the tensor-product scheme on a quad grid ([`surface::solve`]).
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn surface(problem: &SurfaceProblem) -> Result<SurfaceResult, InputError> {
    self::surface::solve(problem)
}

/// `natural`: Warren–Weimer's natural cubic subdivision ([`natural::solve`]).
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn natural(problem: &NaturalProblem) -> Result<NaturalResult, InputError> {
    self::natural::solve(problem)
}

/// The subcommands whose problems [`schema`] describes.
pub const SUBCOMMANDS: [&str; 5] = ["refine", "strip", "scheme", "surface", "natural"];

/// The JSON Schema (draft 2020-12) of a subcommand's problem, generated from its type, or
/// `None` for an unknown subcommand.
#[cfg(feature = "schema")]
pub fn schema(subcommand: &str) -> Option<serde_json::Value> {
    let schema = match subcommand {
        "refine" => schemars::schema_for!(RefineProblem),
        "strip" => schemars::schema_for!(StripProblem),
        "scheme" => schemars::schema_for!(SchemeProblem),
        "surface" => schemars::schema_for!(SurfaceProblem),
        "natural" => schemars::schema_for!(NaturalProblem),
        _ => return None,
    };
    let mut v = schema.to_value();
    // Points (strip: t and y) are required: the types default them to empty only so that the
    // command line can fill them from `--points FILE.csv`.
    let required: &[&str] = match subcommand {
        "refine" | "natural" | "surface" => &["points"],
        "strip" => &["t", "y"],
        _ => &[],
    };
    if let Some(obj) = v.as_object_mut() {
        let list = obj
            .entry("required")
            .or_insert_with(|| serde_json::Value::Array(Vec::new()));
        if let Some(list) = list.as_array_mut() {
            for r in required {
                if !list.iter().any(|x| x == r) {
                    list.push(serde_json::Value::from(*r));
                }
            }
        }
        for r in required {
            if let Some(field) = obj
                .get_mut("properties")
                .and_then(|p| p.get_mut(*r))
                .and_then(|f| f.as_object_mut())
            {
                field.remove("default");
            }
        }
    }
    Some(v)
}

/// Parses a problem from JSON text; errors name the field path (`points[1][1]`) and say what
/// is expected.
///
/// # Errors
/// An [`InputError`]: `problem` for malformed JSON, else the path of the offending field.
pub fn from_json<P: serde::de::DeserializeOwned>(text: &str) -> Result<P, InputError> {
    not_an_object(text.bytes().find(|b| !b.is_ascii_whitespace()))?;
    from_json_bytes(text.as_bytes())
}

/// [`from_json`] of JSON held whole in memory, after the caller has checked that it is an
/// object ([`not_an_object`]); the command line's reader uses it for files it reads whole.
///
/// # Errors
/// As [`from_json`].
pub(crate) fn from_json_bytes<P: serde::de::DeserializeOwned>(
    bytes: &[u8],
) -> Result<P, InputError> {
    // Untracked first: the field path is wanted only for an error (tracking it costs about a
    // third of parsing 10^5 points); a failure is parsed again with the path tracked, which
    // meets the same error.
    if let Ok(p) = serde_json::from_slice::<P>(bytes) {
        return Ok(p);
    }
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let problem = from_deserializer(&mut de)?;
    de.end()
        .map_err(|e| InputError::new("problem", format!("malformed JSON: {e}")))?;
    Ok(problem)
}

/// [`from_json`] for any `serde_json` deserializer (a slice, a reader, a `Value`): the field
/// path of an error is tracked through the typed parse.
///
/// # Errors
/// As [`from_json`].
pub fn from_deserializer<'de, P, D>(de: D) -> Result<P, InputError>
where
    P: serde::Deserialize<'de>,
    D: serde::Deserializer<'de, Error = serde_json::Error>,
{
    serde_path_to_error::deserialize(de).map_err(path_error)
}

/// A problem is a JSON object: anything else (serde would read an array positionally, as the
/// struct's fields in order) is refused by its first character.
///
/// # Errors
/// When `first` (the first non-whitespace byte, if any) does not open an object.
pub fn not_an_object(first: Option<u8>) -> Result<(), InputError> {
    match first {
        Some(b'{') => Ok(()),
        None => Err(InputError::new(
            "problem",
            "is empty: it must be a JSON object like {\"points\": [...]}",
        )),
        Some(_) => Err(InputError::new(
            "problem",
            "must be a JSON object like {\"points\": [...]}",
        )),
    }
}

/// The [`InputError`] of a parse error at a field path: what [`from_json`] and
/// [`from_deserializer`] return. Public for readers that track the path themselves (the Python
/// package reads keyword arguments through its own `serde::Deserializer` over Python objects,
/// whose error type is `serde_json::Error`, and words its errors exactly as the JSON's).
pub fn path_error(e: serde_path_to_error::Error<serde_json::Error>) -> InputError {
    let path = e.path().to_string();
    let field = if path == "." { String::new() } else { path };
    let inner = e.into_inner();
    // The field path says where; the line and column serde_json appends add nothing.
    let text = inner.to_string();
    let bare = match text.rfind(" at line ") {
        Some(i) if inner.line() > 0 => text[..i].to_string(),
        _ => text,
    };
    // "duplicate field `k`" is reported at the object holding it: name the field itself.
    if let Some(name) = messages::field_named(&bare, "duplicate field") {
        let at = if field.is_empty() {
            name.to_string()
        } else {
            format!("{field}.{name}")
        };
        return InputError::new(at, "is given twice (each field at most once)");
    }
    // A required field of the problem itself left out: serde reports it at the problem (an
    // empty path), so the message named no field ("error: needs the field \"rows\"", and an
    // `InputError` with an empty `field`). Name it. (Inside an object the object is named and
    // the message says which of its fields is missing: `constraint: needs the field "radii"`.)
    if let Some(name) = messages::field_named(&bare, "missing field").filter(|_| field.is_empty()) {
        return InputError::new(name, "is required (this problem has no default for it)");
    }
    if inner.is_syntax() || inner.is_eof() {
        match messages::syntax_at_field(&field, &bare) {
            Some(m) => InputError::new(field, m),
            None => InputError::new("problem", format!("malformed JSON: {inner}")),
        }
    } else {
        InputError::new(field.clone(), messages::rewrite(&field, &bare))
    }
}

#[cfg(test)]
mod tests {
    use super::refine::*;
    use super::*;

    fn parse(s: &str) -> Result<RefineProblem, String> {
        from_json(s).map_err(|e| format!("{} | {}", e.field, e.message))
    }

    #[test]
    fn errors_carry_the_first_index_of_their_field() {
        assert_eq!(InputError::new("points[3][1]", "x").index, Some(3));
        assert_eq!(InputError::new("tangents[1].direction", "x").index, Some(1));
        assert_eq!(InputError::new("k", "x").index, None);
        assert_eq!(InputError::new("k", "bad").to_string(), "k: bad");
        assert_eq!(InputError::new("", "bad").to_string(), "bad");
    }

    /// Numbers are read exactly: the same double as Rust's correctly rounded `str::parse`, also
    /// for literals that serde_json's default (not `float_roundtrip`) parser reads one unit in
    /// the last place off — this one is a refined vertex the CLI wrote, read back as
    /// 1.661015572644016 without the feature.
    #[test]
    fn numbers_are_read_exactly() {
        for text in [
            "1.6610155726440161",
            "1.067051959704762",
            "0.1",
            "2.2250738585072014e-308",
        ] {
            let p = parse(&format!(r#"{{"points": [[{text}, 0], [1, 1]]}}"#)).unwrap();
            let want: f64 = text.parse().unwrap();
            assert_eq!(p.points.point(0)[0].to_bits(), want.to_bits(), "{text}");
        }
    }

    #[test]
    fn refine_defaults_follow_the_contract() {
        let p = parse(r#"{"points": [[0,0],[1,0],[0,1]]}"#).unwrap();
        assert!(!p.closed && p.knots.is_none());
        assert_eq!((p.k, p.knot_iterations, p.levels, p.level_k), (3, 3, 0, 1));
        assert_eq!(p.parametrization, ParamSpec::Centripetal);
        assert_eq!(p.constraint, ConstraintSpec::Interpolate);
        assert_eq!(p.derivative, DerivativeSpec::Bessel);
        assert_eq!(p.boundary, BoundarySpec::Natural);
        assert_eq!(p.solver, SolverSpec::Exact);
    }

    #[test]
    fn refine_variants_parse() {
        let p = parse(
            r#"{"points": [[0,0],[1,0],[0,1]], "parametrization": {"exponent": 0.3},
                "constraint": {"type": "balls", "radii": [0.1, 0, 0.2]},
                "tangents": [null, {"type": "wedge", "direction": [1,0], "half_angle": 0.2}, {"type": "tension", "radius": 1}],
                "boundary": {"type": "near_clamped", "start": [1,0], "end": [0,1], "radius": 0.1},
                "derivative": "average", "solver": "paper"}"#,
        )
        .unwrap();
        assert_eq!(p.parametrization, ParamSpec::Exponent(0.3));
        assert!(matches!(p.constraint, ConstraintSpec::Balls { ref radii } if radii.len() == 3));
        assert_eq!(p.solver, SolverSpec::Paper);
    }

    #[test]
    fn unknown_fields_are_errors_with_paths() {
        let e = parse(r#"{"points": [[0,0]], "bogus": 1}"#).unwrap_err();
        assert!(e.contains("bogus"), "{e}");
        let e = parse(
            r#"{"points": [[0,0]], "constraint": {"type": "balls", "radii": [1], "extra": 2}}"#,
        )
        .unwrap_err();
        assert!(e.contains("extra"), "{e}");
        let e = parse(r#"{"points": [[0,0], [1, "x"]]}"#).unwrap_err();
        assert!(e.starts_with("points[1][1]"), "{e}");
    }
}
