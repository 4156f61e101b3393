//! Test-only package: insta snapshot tests (`tests/snapshots.rs`) and end-to-end tests of the
//! `curvefit` command line (`tests/cli.rs`). Shared helpers live here.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static NEXT: AtomicUsize = AtomicUsize::new(0);

/// Runs the curvefit command line in-process: returns (exit code, stdout, stderr).
pub fn run_cli(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut argv = vec!["curvefit"];
    argv.extend_from_slice(args);
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let code = curvefit::cli::run(argv, &mut stdin.as_bytes(), &mut out, &mut err);
    (
        code,
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
    )
}

/// Path of a file under `tests/problems/`.
pub fn problem_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(name)
}

/// A fresh scratch directory under the target directory.
pub fn scratch_dir(tag: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("target")
        .join("test-scratch")
        .join(format!(
            "{tag}-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Rounds every float in a JSON value to `digits` significant digits (values below `floor` in
/// magnitude become 0), so snapshots are stable across machines.
pub fn round_json(v: &serde_json::Value, digits: usize, floor: f64) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Number(n) if n.is_f64() => {
            let x = n.as_f64().unwrap_or(0.0);
            if x.abs() < floor {
                Value::from(0.0)
            } else {
                let s = format!("{:.*e}", digits.saturating_sub(1), x);
                Value::String(s)
            }
        }
        Value::Array(a) => Value::Array(a.iter().map(|x| round_json(x, digits, floor)).collect()),
        Value::Object(o) => Value::Object(
            o.iter()
                .map(|(k, x)| (k.clone(), round_json(x, digits, floor)))
                .collect(),
        ),
        other => other.clone(),
    }
}

/// A small JSON Schema (draft 2020-12) validator for the keywords `curvefit schema` emits:
/// `type`, `properties`, `required`, `additionalProperties`, `items`, `minItems`, `maxItems`,
/// `minimum`, `const`, `enum`, `oneOf`, `anyOf`, `$ref` (to `#/$defs/…`), `format` (`uint`,
/// `double` and the like: checked through `type`/`minimum`), and the annotations `$schema`,
/// `title`, `description`, `default`, `$defs`. Any other keyword is a test failure, so a schema
/// that grows a keyword this validator does not check cannot pass unchecked. Returns the errors
/// (`path: what`), empty when `value` is valid.
pub fn schema_errors(schema: &serde_json::Value, value: &serde_json::Value) -> Vec<String> {
    let mut errors = Vec::new();
    check(schema, schema, value, "", &mut errors);
    errors
}

fn check(
    root: &serde_json::Value,
    schema: &serde_json::Value,
    v: &serde_json::Value,
    path: &str,
    errors: &mut Vec<String>,
) {
    use serde_json::Value;
    let Some(s) = schema.as_object() else {
        if schema == &Value::Bool(false) {
            errors.push(format!("{path}: not allowed"));
        }
        return;
    };
    for (key, rule) in s {
        match key.as_str() {
            "$schema" | "title" | "description" | "default" | "$defs" | "format" => {}
            "$ref" => {
                let name = rule
                    .as_str()
                    .and_then(|r| r.strip_prefix("#/$defs/"))
                    .unwrap_or_else(|| panic!("unsupported $ref {rule}"));
                check(root, &root["$defs"][name], v, path, errors);
            }
            "type" => {
                let types: Vec<&str> = match rule {
                    Value::String(t) => vec![t.as_str()],
                    Value::Array(a) => a.iter().filter_map(Value::as_str).collect(),
                    _ => panic!("bad type {rule}"),
                };
                let ok = types.iter().any(|t| match *t {
                    "object" => v.is_object(),
                    "array" => v.is_array(),
                    "string" => v.is_string(),
                    "number" => v.is_number(),
                    "integer" => v.is_i64() || v.is_u64(),
                    "boolean" => v.is_boolean(),
                    "null" => v.is_null(),
                    other => panic!("unknown type {other}"),
                });
                if !ok {
                    errors.push(format!("{path}: expected type {rule}, got {v}"));
                }
            }
            "properties" => {
                if let (Some(props), Some(obj)) = (rule.as_object(), v.as_object()) {
                    for (k, sub) in props {
                        if let Some(x) = obj.get(k) {
                            check(root, sub, x, &format!("{path}.{k}"), errors);
                        }
                    }
                }
            }
            "required" => {
                if let Some(obj) = v.as_object() {
                    for r in rule.as_array().into_iter().flatten() {
                        let r = r.as_str().unwrap_or_default();
                        if !obj.contains_key(r) {
                            errors.push(format!("{path}: missing required `{r}`"));
                        }
                    }
                }
            }
            "additionalProperties" => {
                if let Some(obj) = v.as_object() {
                    let known = s.get("properties").and_then(Value::as_object);
                    for (k, x) in obj {
                        if known.is_some_and(|p| p.contains_key(k)) {
                            continue;
                        }
                        match rule {
                            Value::Bool(false) => {
                                errors.push(format!("{path}: unknown field `{k}`"))
                            }
                            Value::Bool(true) => {}
                            sub => check(root, sub, x, &format!("{path}.{k}"), errors),
                        }
                    }
                }
            }
            "items" => {
                if let Some(a) = v.as_array() {
                    for (i, x) in a.iter().enumerate() {
                        check(root, rule, x, &format!("{path}[{i}]"), errors);
                    }
                }
            }
            "minItems" | "maxItems" => {
                if let (Some(a), Some(n)) = (v.as_array(), rule.as_u64()) {
                    let bad = if key == "minItems" {
                        (a.len() as u64) < n
                    } else {
                        (a.len() as u64) > n
                    };
                    if bad {
                        errors.push(format!("{path}: {key} {n}, got {} items", a.len()));
                    }
                }
            }
            "minimum" => {
                if let (Some(x), Some(m)) = (v.as_f64(), rule.as_f64()) {
                    if x < m {
                        errors.push(format!("{path}: below the minimum {m}"));
                    }
                }
            }
            "const" => {
                if v != rule {
                    errors.push(format!("{path}: expected {rule}, got {v}"));
                }
            }
            "enum" => {
                if !rule.as_array().is_some_and(|a| a.contains(v)) {
                    errors.push(format!("{path}: {v} is not one of {rule}"));
                }
            }
            "oneOf" | "anyOf" => {
                let subs = rule.as_array().expect("array");
                let passing = subs
                    .iter()
                    .filter(|sub| {
                        let mut e = Vec::new();
                        check(root, sub, v, path, &mut e);
                        e.is_empty()
                    })
                    .count();
                let ok = if key == "oneOf" {
                    passing == 1
                } else {
                    passing >= 1
                };
                if !ok {
                    errors.push(format!(
                        "{path}: {passing} of the {key} alternatives match {v}"
                    ));
                }
            }
            other => panic!("schema keyword `{other}` is not checked by this validator"),
        }
    }
}
