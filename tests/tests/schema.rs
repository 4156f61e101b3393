//! `curvefit schema SUBCOMMAND` (issue 19 §2): a JSON Schema per subcommand, generated from the
//! problem types, that every example and test problem satisfies, and that refuses what the
//! command line refuses for its shape (unknown fields, wrong types, missing points).

use curvefit_tests::{problem_path, run_cli, schema_errors};
use serde_json::{json, Value};

fn schema(sub: &str) -> Value {
    let (code, out, err) = run_cli(&["schema", sub], "");
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["$schema"], "https://json-schema.org/draft/2020-12/schema");
    v
}

fn json_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_example_and_test_problem_satisfies_its_schema() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = json_files(&root.join("crates/curvefit/examples/data"));
    files.extend(json_files(&problem_path("")));
    let mut checked = 0;
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let doc: Value = serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
        let (sub, doc) = match name.split('-').next().unwrap() {
            // `scheme --apply` reads a polygon: the schema's `polygon` field.
            "polygon" => ("scheme", json!({"points": 4, "arity": 2, "polygon": doc})),
            s => (s, doc),
        };
        let errors = schema_errors(&schema(sub), &doc);
        assert!(errors.is_empty(), "{name}: {errors:?}");
        checked += 1;
    }
    assert!(checked >= 25, "{checked} files");
}

#[test]
fn the_schema_refuses_what_the_parser_refuses() {
    let bad = [
        (
            "refine",
            json!({"points": [[0, 0], [1, 0], [0, 1]], "boundary": "clamped"}),
        ),
        (
            "refine",
            json!({"points": [[0, 0], [1, 0], [0, 1]], "k": -1}),
        ),
        (
            "refine",
            json!({"points": [[0, 0], [1, 0], [0, 1]], "colsed": true}),
        ),
        ("refine", json!({"k": 3})),
        ("refine", json!({"points": [[0, 0], [1, "x"]]})),
        (
            "refine",
            json!({"points": [[0, 0], [1, 0], [0, 1]], "constraint": {"type": "balls"}}),
        ),
        (
            "refine",
            json!({"points": [[0, 0], [1, 0], [0, 1]], "tangents": [{"type": "wedge", "direction": [1, 0]}, null, null]}),
        ),
        (
            "refine",
            json!({"points": [[0, 0], [1, 0], [0, 1]], "parametrization": "centripedal"}),
        ),
        (
            "strip",
            json!({"t": [0, 1], "y": [0, 1], "lower": {"pieces": [[0, 0, 0]]}}),
        ),
        ("strip", json!({"t": [0, 1]})),
        ("natural", json!({"points": [[0], [1]], "levels": 1.5})),
        (
            "surface",
            json!({"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]], "closed": true}),
        ),
        ("scheme", json!({"points": 4})),
    ];
    for (sub, doc) in bad {
        let errors = schema_errors(&schema(sub), &doc);
        assert!(!errors.is_empty(), "{sub}: schema accepts {doc}");
        let (code, _, err) = run_cli(&[sub, "-"], &doc.to_string());
        if sub != "scheme" {
            assert_eq!(code, 2, "{sub}: the command line accepts {doc}: {err}");
        }
    }
}

#[test]
fn unknown_subcommands_have_no_schema() {
    let (code, out, err) = run_cli(&["schema", "bogus"], "");
    assert_eq!(code, 2);
    assert!(out.is_empty() && err.contains("bogus"), "{err}");
}

/// Every field the schemas know (top level and inside every object form) appears in
/// docs/input.md, so a new field cannot go undocumented.
#[test]
fn docs_input_names_every_field() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let doc = std::fs::read_to_string(root.join("docs/input.md")).unwrap();
    fn names(v: &Value, out: &mut Vec<String>) {
        match v {
            Value::Object(o) => {
                if let Some(Value::Object(props)) = o.get("properties") {
                    out.extend(props.keys().cloned());
                }
                if let Some(c) = o.get("const").and_then(Value::as_str) {
                    out.push(c.to_string());
                }
                o.values().for_each(|x| names(x, out));
            }
            Value::Array(a) => a.iter().for_each(|x| names(x, out)),
            _ => {}
        }
    }
    for sub in ["refine", "strip", "scheme", "surface", "natural"] {
        let mut all = Vec::new();
        names(&schema(sub), &mut all);
        let section = doc
            .split("\n## ")
            .find(|s| s.starts_with(sub))
            .unwrap_or_else(|| panic!("docs/input.md has a section {sub}"));
        for n in all {
            assert!(
                section.contains(&format!("`{n}`")) || section.contains(&format!("\"{n}\"")),
                "docs/input.md, section {sub}, does not mention `{n}`"
            );
        }
    }
}
