//! `curvefit scheme --points P --arity N [--surface] [--apply POLYGON.json --levels L]`: the
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
//! two points, all of the same dimension d ≥ 1, finite coordinates; `closed` defaults to `true`
//! (a periodic polygon; `false` keeps the end points and uses one-sided end stencils that keep
//! the polynomial reproduction, see `subdivision::NaryScheme`). Unknown fields are an error.

use divdiff::{Points, Topology};
use serde::Deserialize;
use serde_json::{json, Value};
use subdivision::{rational_to_f64, BigRational, NaryScheme};

use super::InputError;

/// Largest stencil size P accepted on the command line (the weights of wider rules are too large
/// to be useful in floating point, and the output grows like P² N² with `--surface`).
pub const MAX_CLI_SCHEME_POINTS: usize = 16;
/// Largest arity N accepted on the command line.
pub const MAX_CLI_ARITY: usize = 16;
/// Largest `--apply` result: points × dimension of the refined polygon.
pub const MAX_CLI_POLYGON_COORDS: usize = 10_000_000;

/// The polygon file of `--apply`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolygonInput {
    /// The vertices, each `[x, y, …]`.
    pub points: Vec<Vec<f64>>,
    /// Closed (periodic) polygon; default `true`.
    #[serde(default = "yes")]
    pub closed: bool,
}

fn yes() -> bool {
    true
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

/// Validates rows of points: at least `min` rows, equal dimension ≥ 1, finite coordinates.
/// Errors name `field[i]` or `field[i][j]`.
pub fn validate_rows(field: &str, rows: &[Vec<f64>], min: usize) -> Result<Points, InputError> {
    if rows.len() < min {
        return Err(InputError::new(
            field,
            format!("needs at least {min} points, got {}", rows.len()),
        ));
    }
    let dim = rows[0].len();
    if dim == 0 {
        return Err(InputError::new(
            format!("{field}[0]"),
            "a point needs at least one coordinate",
        ));
    }
    for (i, r) in rows.iter().enumerate() {
        if r.len() != dim {
            return Err(InputError::new(
                format!("{field}[{i}]"),
                format!("has {} coordinates, expected {dim}", r.len()),
            ));
        }
        if let Some(j) = r.iter().position(|x| !x.is_finite()) {
            return Err(InputError::new(
                format!("{field}[{i}][{j}]"),
                "must be a finite number",
            ));
        }
    }
    Points::from_rows(rows).map_err(|e| InputError::new(field, e))
}

/// Builds the scheme from command-line values, naming the flag on error.
pub fn scheme_from_flags(points: usize, arity: usize) -> Result<NaryScheme, InputError> {
    if points < 2 || points % 2 != 0 {
        return Err(InputError::new(
            "--points",
            format!("must be even and at least 2 (P = 2m + 2), got {points}"),
        ));
    }
    if points > MAX_CLI_SCHEME_POINTS {
        return Err(InputError::new(
            "--points",
            format!("at most {MAX_CLI_SCHEME_POINTS}, got {points}"),
        ));
    }
    if !(2..=MAX_CLI_ARITY).contains(&arity) {
        return Err(InputError::new(
            "--arity",
            format!("must be between 2 and {MAX_CLI_ARITY}, got {arity}"),
        ));
    }
    NaryScheme::new(points, arity).map_err(|e| InputError::new("--points", e))
}

fn weights_json(w: &[BigRational]) -> (Vec<String>, Vec<f64>) {
    (
        w.iter().map(format_rational).collect(),
        w.iter().map(rational_to_f64).collect(),
    )
}

/// The `scheme` subcommand: `points` = P, `arity` = N, `surface` adds the 2-D masks, `apply`
/// = (polygon JSON text, levels) adds the refined polygon.
///
/// # Errors
/// An [`InputError`] naming `--points`, `--arity`, `--levels`, or the polygon's field
/// (`polygon.points[i][j]`, `polygon.closed`, …) for malformed polygon JSON.
pub fn run_scheme(
    points: usize,
    arity: usize,
    surface: bool,
    apply: Option<(&str, usize)>,
) -> Result<Value, InputError> {
    let scheme = scheme_from_flags(points, arity)?;
    let rules: Vec<Value> = (0..arity)
        .map(|a| {
            let (weights, floats) = weights_json(scheme.exact_rule(a));
            json!({"residue": a, "offsets": scheme.offsets(), "weights": weights, "floats": floats})
        })
        .collect();
    let mut out = json!({"points": points, "arity": arity, "rules": rules});
    if surface {
        let surface_rules: Vec<Value> = scheme
            .surface_rules()
            .iter()
            .map(|r| {
                let (weights, floats) = weights_json(&r.weights);
                let offsets: Vec<[isize; 2]> = r.offsets.iter().map(|&(a, b)| [a, b]).collect();
                json!({"residue": [r.residue.0, r.residue.1], "offsets": offsets,
                       "weights": weights, "floats": floats})
            })
            .collect();
        out["surface_rules"] = Value::from(surface_rules);
    }
    if let Some((text, levels)) = apply {
        let value: Value = serde_json::from_str(text)
            .map_err(|e| InputError::new("polygon", format!("malformed JSON: {e}")))?;
        let poly: PolygonInput = serde_path_to_error::deserialize(value).map_err(|e| {
            let path = e.path().to_string();
            let field = if path == "." {
                "polygon".to_string()
            } else {
                format!("polygon.{path}")
            };
            InputError::new(field, e.into_inner())
        })?;
        let pts = validate_rows("polygon.points", &poly.points, 2)?;
        let topology = if poly.closed {
            Topology::Closed
        } else {
            Topology::Open
        };
        let too_many = || {
            InputError::new(
                "--levels",
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
        let refined = scheme
            .subdivide(&pts, topology, levels)
            .map_err(|e| InputError::new("polygon.points", e))?;
        out["polygon"] = json!({
            "closed": poly.closed,
            "levels": levels,
            "input": poly.points,
            "output": refined.to_rows(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_follow_the_contract() {
        let v = run_scheme(4, 3, false, None).unwrap();
        assert_eq!(v["points"], 4);
        assert_eq!(v["arity"], 3);
        let rules = v["rules"].as_array().unwrap();
        assert_eq!(rules.len(), 3);
        assert_eq!(rules[1]["residue"], 1);
        assert_eq!(rules[1]["offsets"], json!([-1, 0, 1, 2]));
        assert_eq!(
            rules[1]["weights"],
            json!(["-5/81", "20/27", "10/27", "-4/81"])
        );
        assert_eq!(rules[0]["weights"], json!(["0", "1", "0", "0"]));
        let f = rules[1]["floats"][0].as_f64().unwrap();
        assert!((f + 5.0 / 81.0).abs() < 1e-17);
        assert!(v.get("surface_rules").is_none() && v.get("polygon").is_none());
    }

    #[test]
    fn surface_and_apply() {
        let poly = r#"{"points": [[0,0],[1,0],[1,1],[0,1]], "closed": false}"#;
        let v = run_scheme(4, 2, true, Some((poly, 2))).unwrap();
        let s = v["surface_rules"].as_array().unwrap();
        assert_eq!(s.len(), 4);
        assert_eq!(s[3]["residue"], json!([1, 1]));
        assert_eq!(s[3]["offsets"][0], json!([-1, -1]));
        assert_eq!(s[3]["weights"][5], json!("81/256"));
        let p = &v["polygon"];
        assert_eq!(p["closed"], false);
        assert_eq!(p["levels"], 2);
        assert_eq!(p["output"].as_array().unwrap().len(), 13);
        assert_eq!(
            p["input"],
            json!([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        );
    }

    #[test]
    fn bad_input_names_the_field() {
        assert_eq!(run_scheme(3, 2, false, None).unwrap_err().field, "--points");
        assert_eq!(
            run_scheme(18, 2, false, None).unwrap_err().field,
            "--points"
        );
        assert_eq!(run_scheme(4, 1, false, None).unwrap_err().field, "--arity");
        assert_eq!(run_scheme(4, 17, false, None).unwrap_err().field, "--arity");
        let e = run_scheme(4, 2, false, Some(("{\"points\": [[0,0],[1]]}", 1))).unwrap_err();
        assert_eq!(e.field, "polygon.points[1]");
        let e = run_scheme(4, 2, false, Some(("{\"points\": [[0,0]]}", 1))).unwrap_err();
        assert_eq!(e.field, "polygon.points");
        let e = run_scheme(
            4,
            2,
            false,
            Some(("{\"points\": [[0,0],[1,1]], \"x\": 1}", 1)),
        )
        .unwrap_err();
        assert_eq!(e.field, "polygon.x");
        let e = run_scheme(4, 2, false, Some(("{\"points\": [[0,0],[1,\"a\"]]}", 1))).unwrap_err();
        assert_eq!(e.field, "polygon.points[1][1]");
        let e = run_scheme(4, 2, false, Some(("{\"points\": [[0,0],[1,1]]}", 40))).unwrap_err();
        assert_eq!(e.field, "--levels");
        let e = run_scheme(4, 2, false, Some(("not json", 1))).unwrap_err();
        assert_eq!(e.field, "polygon");
    }
}
