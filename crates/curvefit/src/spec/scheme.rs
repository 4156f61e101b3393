//! `scheme`: the
//! (2m+2)-point n-ary interpolating rules of Khan et al. (P = 2m + 2) as exact rationals and
//! correctly rounded doubles, optionally their tensor-product masks and their application to a
//! polygon.
//!
//! Result: `{"points": P, "arity": N, "rules": [{"residue": a, "offsets": [−m, …, m+1],
//! "weights": ["num/den" or "num" for integers, …], "floats": [...]}, … for a = 0..N−1]}`, meaning
//! p^{k+1}_{N·i+a} = Σ_l weights\[l\] · p^k_{i+offsets\[l\]}. `--surface` adds `"surface_rules":
//! [{"residue": [a, b], "offsets": [[r, s], …], "weights": [...], "floats": [...]}, …]` (row-major
//! in (a, b) and in (r, s)). `--apply` adds `"polygon": {"closed", "levels", "input", "output"}`.
//!
//! The polygon file (`--apply`) is JSON: `{"points": [[x, y, …], …], "closed": true}` — at least
//! two points, all of the same dimension d ≥ 1, finite coordinates; `closed` defaults to `false`
//! (an open polygon keeps its end points and uses one-sided end stencils that keep the
//! polynomial reproduction, see `subdivision::NaryScheme`; `true` is a periodic polygon). Unknown fields are an error.

use divdiff::{Points, Topology};
use serde::{Deserialize, Serialize};
use subdivision::{rational_to_f64, BigRational, NaryScheme};

use super::{InputError, Rows};

/// Largest stencil size P accepted on the command line (the weights of wider rules are too large
/// to be useful in floating point, and the output grows like P² N² with `--surface`).
pub const MAX_CLI_SCHEME_POINTS: usize = 16;
/// Largest arity N accepted on the command line.
pub const MAX_CLI_ARITY: usize = 16;
/// Largest `--apply` result: points × dimension of the refined polygon.
pub const MAX_CLI_POLYGON_COORDS: usize = 10_000_000;

/// The polygon file of `--apply`.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PolygonInput {
    /// The vertices, each `[x, y, …]`.
    pub points: Rows,
    /// Closed (periodic) polygon, or open (default: open, like `refine`'s curves).
    #[serde(default)]
    pub closed: bool,
}

/// An exact weight as `"num/den"` in lowest terms with den > 0, or `"num"` when it is an
/// integer (den = 1): `"-1/16"`, `"0"`, `"1"`.
pub fn format_rational(q: &BigRational) -> String {
    if q.is_integer() {
        q.numer().to_string()
    } else {
        format!("{}/{}", q.numer(), q.denom())
    }
}

/// Points with at least `min` rows (rows already have one dimension d ≥ 1 and finite
/// coordinates). Errors name `field`.
pub fn validate_rows(field: &str, rows: &Rows, min: usize) -> Result<Points, InputError> {
    if rows.len() < min {
        return Err(InputError::new(
            field,
            format!("needs at least {min} points, got {}", rows.len()),
        ));
    }
    Ok(rows.0.clone())
}

/// Builds the scheme P = `points`, N = `arity`, naming the field on error.
pub fn scheme_from_flags(points: usize, arity: usize) -> Result<NaryScheme, InputError> {
    if points < 2 || !points.is_multiple_of(2) {
        return Err(InputError::new(
            "points",
            format!("must be even and at least 2 (P = 2m + 2), got {points}"),
        ));
    }
    if points > MAX_CLI_SCHEME_POINTS {
        return Err(InputError::new(
            "points",
            format!("at most {MAX_CLI_SCHEME_POINTS}, got {points}"),
        ));
    }
    if !(2..=MAX_CLI_ARITY).contains(&arity) {
        return Err(InputError::new(
            "arity",
            format!("must be between 2 and {MAX_CLI_ARITY}, got {arity}"),
        ));
    }
    NaryScheme::new(points, arity).map_err(|e| InputError::new("points", e))
}

fn weights_json(w: &[BigRational]) -> (Vec<String>, Vec<f64>) {
    (
        w.iter().map(format_rational).collect(),
        w.iter().map(rational_to_f64).collect(),
    )
}

fn one() -> usize {
    1
}

/// The `scheme` problem: the rule P = `points`, N = `arity`; `surface` adds the tensor-product
/// masks; `polygon` (with `levels`) adds the refined polygon.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SchemeProblem {
    /// Stencil size P = 2m + 2 (even, 2 ≤ P ≤ 16).
    pub points: usize,
    /// Arity N (2 ≤ N ≤ 16).
    pub arity: usize,
    /// Also give the tensor-product surface rules (default false).
    #[serde(default)]
    pub surface: bool,
    /// A polygon to refine (default none).
    #[serde(default)]
    pub polygon: Option<PolygonInput>,
    /// Levels of refinement of `polygon` (default 1).
    #[serde(default = "one")]
    pub levels: usize,
}

/// One rule p^{k+1}_{N·i+a} = Σ_l weights\[l\] · p^k_{i+offsets\[l\]} (fields in the order the
/// result has always printed them).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SchemeRule {
    /// The weights as correctly rounded doubles.
    pub floats: Vec<f64>,
    /// Offsets −m, …, m + 1.
    pub offsets: Vec<isize>,
    /// The residue a.
    pub residue: usize,
    /// The exact weights, `"num/den"`.
    pub weights: Vec<String>,
}

/// One tensor-product rule (row-major in (a, b) and in (r, s)).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SurfaceRule {
    /// The weights as correctly rounded doubles.
    pub floats: Vec<f64>,
    /// Offsets (r, s).
    pub offsets: Vec<[isize; 2]>,
    /// The residue (a, b).
    pub residue: [usize; 2],
    /// The exact weights, `"num/den"`.
    pub weights: Vec<String>,
}

/// The refined polygon of a `scheme` problem.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PolygonResult {
    /// As in the problem.
    pub closed: bool,
    /// The input points.
    pub input: Rows,
    /// Levels applied.
    pub levels: usize,
    /// The refined points.
    pub output: Rows,
}

/// The `scheme` result (fields in the order the result has always printed them).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SchemeResult {
    /// N.
    pub arity: usize,
    /// P.
    pub points: usize,
    /// The refined polygon, when the problem has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polygon: Option<PolygonResult>,
    /// The N rules, one per residue a = 0..N−1.
    pub rules: Vec<SchemeRule>,
    /// The N² tensor-product rules, when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_rules: Option<Vec<SurfaceRule>>,
}

/// `curvefit scheme`: the rules, optionally the tensor-product masks and the refined polygon.
///
/// # Errors
/// An [`InputError`] naming `points`, `arity`, `levels` or the polygon's field
/// (`polygon.points[i]`, …).
pub fn solve(problem: &SchemeProblem) -> Result<SchemeResult, InputError> {
    let (points, arity, levels) = (problem.points, problem.arity, problem.levels);
    let scheme = scheme_from_flags(points, arity)?;
    let rules = (0..arity)
        .map(|a| {
            let (weights, floats) = weights_json(scheme.exact_rule(a));
            SchemeRule {
                floats,
                offsets: scheme.offsets().to_vec(),
                residue: a,
                weights,
            }
        })
        .collect();
    let surface_rules = problem.surface.then(|| {
        scheme
            .surface_rules()
            .iter()
            .map(|r| {
                let (weights, floats) = weights_json(&r.weights);
                SurfaceRule {
                    floats,
                    offsets: r.offsets.iter().map(|&(a, b)| [a, b]).collect(),
                    residue: [r.residue.0, r.residue.1],
                    weights,
                }
            })
            .collect()
    });
    let polygon = match &problem.polygon {
        None => None,
        Some(poly) => {
            let pts = validate_rows("polygon.points", &poly.points, 2)?;
            let topology = if poly.closed {
                Topology::Closed
            } else {
                Topology::Open
            };
            let too_many = || {
                InputError::new(
                    "levels",
                    format!(
                        "{levels} levels on {} points would exceed {MAX_CLI_POLYGON_COORDS} output coordinates",
                        pts.len()
                    ),
                )
            };
            let count = scheme
                .refined_count(pts.len(), topology, levels)
                .ok_or_else(too_many)?;
            if count
                .checked_mul(pts.dim())
                .is_none_or(|c| c > MAX_CLI_POLYGON_COORDS)
            {
                return Err(too_many());
            }
            // (The points are validated finite: a non-finite refined point is an overflow of
            // the affine combinations, weights > 1, near the f64 limit, as for surfaces.)
            let refined = scheme
                .subdivide(&pts, topology, levels)
                .map_err(|e| match e {
                    subdivision::Error::NonFinite { .. } => InputError::new(
                        "polygon.points",
                        format!("coordinates too large: the refined polygon overflows f64 ({e})"),
                    ),
                    e => InputError::new("polygon.points", e),
                })?;
            Some(PolygonResult {
                closed: poly.closed,
                input: poly.points.clone(),
                levels,
                output: Rows(refined),
            })
        }
    };
    Ok(SchemeResult {
        arity,
        points,
        polygon,
        rules,
        surface_rules,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(points: usize, arity: usize, surface: bool, polygon: Option<&str>) -> SchemeProblem {
        let polygon = polygon.map(|p| super::super::from_json(p).unwrap());
        SchemeProblem {
            points,
            arity,
            surface,
            polygon,
            levels: 1,
        }
    }

    #[test]
    fn rules_follow_the_contract() {
        let v = serde_json::to_value(solve(&problem(4, 3, false, None)).unwrap()).unwrap();
        assert_eq!(v["points"], 4);
        assert_eq!(v["arity"], 3);
        let rules = v["rules"].as_array().unwrap();
        assert_eq!(rules.len(), 3);
        assert_eq!(rules[1]["residue"], 1);
        assert_eq!(rules[1]["offsets"], serde_json::json!([-1, 0, 1, 2]));
        assert_eq!(
            rules[1]["weights"],
            serde_json::json!(["-5/81", "20/27", "10/27", "-4/81"])
        );
        assert_eq!(rules[0]["weights"], serde_json::json!(["0", "1", "0", "0"]));
        let f = rules[1]["floats"][0].as_f64().unwrap();
        assert!((f + 5.0 / 81.0).abs() < 1e-17);
        assert!(v.get("surface_rules").is_none() && v.get("polygon").is_none());
    }

    #[test]
    fn surface_and_apply() {
        let poly = r#"{"points": [[0,0],[1,0],[1,1],[0,1]], "closed": false}"#;
        let mut p = problem(4, 2, true, Some(poly));
        p.levels = 2;
        let v = serde_json::to_value(solve(&p).unwrap()).unwrap();
        let s = v["surface_rules"].as_array().unwrap();
        assert_eq!(s.len(), 4);
        assert_eq!(s[3]["residue"], serde_json::json!([1, 1]));
        assert_eq!(s[3]["offsets"][0], serde_json::json!([-1, -1]));
        assert_eq!(s[3]["weights"][5], serde_json::json!("81/256"));
        let p = &v["polygon"];
        assert_eq!(p["closed"], false);
        assert_eq!(p["levels"], 2);
        assert_eq!(p["output"].as_array().unwrap().len(), 13);
        assert_eq!(
            p["input"],
            serde_json::json!([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        );
    }

    #[test]
    fn bad_input_names_the_field() {
        let field = |p: SchemeProblem| solve(&p).unwrap_err().field;
        assert_eq!(field(problem(3, 2, false, None)), "points");
        assert_eq!(field(problem(18, 2, false, None)), "points");
        assert_eq!(field(problem(4, 1, false, None)), "arity");
        assert_eq!(field(problem(4, 17, false, None)), "arity");
        let e = super::super::from_json::<SchemeProblem>(
            r#"{"points": 4, "arity": 2, "polygon": {"points": [[0,0],[1]]}}"#,
        )
        .unwrap_err();
        assert_eq!(e.field, "polygon.points[1]");
        let p = problem(4, 2, false, Some(r#"{"points": [[0,0]]}"#));
        assert_eq!(field(p), "polygon.points");
        let mut p = problem(4, 2, false, Some(r#"{"points": [[0,0],[1,1]]}"#));
        p.levels = 40;
        assert_eq!(field(p), "levels");
    }
}
