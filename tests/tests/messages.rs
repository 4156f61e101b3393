//! Error messages in the user's words (issue 19 §2): each bad input below is refused with a
//! message that says what the field must look like in JSON, never a Rust type name, with numbers
//! as a person writes them.

use curvefit_tests::run_cli;

const P: &str = r#""points": [[0, 0], [1, 0], [0, 1]]"#;

/// Words of the implementation that must never reach a user.
const RUST_WORDS: &[&str] = &[
    "usize",
    "f64",
    "Spec",
    "struct",
    "enum",
    "Vec<",
    "Option",
    "tuple",
    "a sequence",
    "a map",
    "variant",
    "internally tagged",
];

fn message(sub: &str, doc: &str) -> String {
    let (code, out, err) = run_cli(&[sub, "-"], doc);
    assert_eq!(code, 2, "{doc}: {err}");
    assert!(out.is_empty());
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    for w in RUST_WORDS {
        assert!(!err.contains(w), "{doc}: `{w}` in {err}");
    }
    // No number in exponent form with a long mantissa (3.400000000000001e-1).
    let long = err
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
        .any(|w| w.contains('e') && w.split('e').next().is_some_and(|m| m.len() > 8));
    assert!(!long, "{doc}: unreadable number in {err}");
    err.trim_end().to_string()
}

#[test]
fn messages_say_what_the_field_must_be() {
    let cases: &[(&str, String, &str)] = &[
        (
            "refine",
            format!(r#"{{{P}, "closed": false, "boundary": "clamped"}}"#),
            r#"error: boundary: must be an object like {"type": "clamped", "start": [...], "end": [...]}"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "constraint": "balls"}}"#),
            r#"error: constraint: must be an object like {"type": "balls", "radii": [...]}"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "constraint": {{"type": "balls"}}}}"#),
            r#"error: constraint: needs the field "radii""#,
        ),
        // A required field of the problem itself is named (serde reports it at the problem,
        // and the line was "error: needs the field \"rows\"", with no field).
        (
            "surface",
            r#"{"cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]]}"#.to_string(),
            "error: rows: is required (this problem has no default for it)",
        ),
        // Inside an object with a "type", errors keep their path (`spec::tagged`) …
        (
            "refine",
            format!(r#"{{{P}, "constraint": {{"type": "balls", "radii": 0.1}}}}"#),
            "error: constraint.radii: must be an array, not 0.1",
        ),
        (
            "refine",
            format!(
                r#"{{{P}, "constraint": {{"type": "halfspaces", "sets": [[], [{{"normal": [1, 0], "offset": "x"}}], []]}}}}"#
            ),
            r#"error: constraint.sets[1][0].offset: must be a number, not the string "x""#,
        ),
        (
            "refine",
            format!(
                r#"{{{P}, "tangents": [null, {{"type": "ball", "center": [1, "x"], "radius": 1}}, null]}}"#
            ),
            r#"error: tangents[1].center[1]: must be a number, not the string "x""#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "boundary": {{"type": "clamped", "start": [1, 0], "end": 2}}}}"#),
            "error: boundary.end: must be an array, not 2",
        ),
        // … a field of another type is refused, not ignored …
        (
            "refine",
            format!(r#"{{{P}, "constraint": {{"type": "interpolate", "radii": [1, 1, 1]}}}}"#),
            r#"error: constraint: unknown field "radii": this type has no other field than "type""#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "boundary": {{"type": "natural", "start": [1, 0]}}}}"#),
            r#"error: boundary: unknown field "start": this type has no other field than "type""#,
        ),
        (
            "refine",
            format!(
                r#"{{{P}, "tangents": [{{"type": "tension", "radius": 1, "center": [0, 0]}}, null, null]}}"#
            ),
            r#"error: tangents[0]: unknown field "center" (the fields are "radius")"#,
        ),
        // A field given twice is named, at any depth (serde reported "duplicate field `k`"
        // at the object holding it: no field at the top).
        (
            "refine",
            format!(r#"{{{P}, "k": 3, "k": 5}}"#),
            "error: k: is given twice (each field at most once)",
        ),
        (
            "refine",
            format!(
                r#"{{{P}, "constraint": {{"type": "balls", "radii": [1, 1, 1], "radii": [2, 2, 2]}}}}"#
            ),
            "error: constraint.radii: is given twice (each field at most once)",
        ),
        // … and neither an array nor a number is read as the object or its type.
        (
            "refine",
            format!(r#"{{{P}, "constraint": [1, 2]}}"#),
            r#"error: constraint: must be an object like {"type": "balls", "radii": [...]}"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "constraint": {{"type": 3}}}}"#),
            r#"error: constraint.type: must be a string: constraint must be an object like"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "tangents": ["wedge", null, null]}}"#),
            r#"error: tangents[0]: must be null or an object like {"type": "wedge", "direction": [...], "half_angle": 0.2}"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "parametrization": "centripedal"}}"#),
            r#"error: parametrization: "centripedal" is not allowed: parametrization must be "uniform", "centripetal", "chordal" or an object like {"exponent": 0.5}"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "parametrization": 0.5}}"#),
            r#"error: parametrization: must be "uniform", "centripetal", "chordal" or an object like {"exponent": 0.5}"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "closed": false, "boundary": {{"type": "clamp"}}}}"#),
            r#"error: boundary.type: "clamp" is not allowed: boundary must be an object like"#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "k": -1}}"#),
            "error: k: must be a whole number ≥ 0, not -1",
        ),
        (
            "refine",
            format!(r#"{{{P}, "k": 1.5}}"#),
            "error: k: must be a whole number ≥ 0, not 1.5",
        ),
        (
            "refine",
            format!(r#"{{{P}, "closed": "yes"}}"#),
            r#"error: closed: must be true or false, not the string "yes""#,
        ),
        (
            "refine",
            format!(r#"{{{P}, "knots": [0, 1, 2, "a"]}}"#),
            r#"error: knots[3]: must be a number, not the string "a""#,
        ),
        (
            "refine",
            r#"{"points": [1, 2, 3]}"#.to_string(),
            "error: points[0]: must be a point, an array of numbers like [0.5, 1.25], not 1",
        ),
        (
            "refine",
            format!(r#"{{{P}, "constraint": {{"type": "balls", "radii": [1, -0.34, 1]}}}}"#),
            "error: constraint.radii[1]: must be ≥ 0, got -0.34",
        ),
        (
            "refine",
            format!(r#"{{{P}, "constraint": {{"type": "balls", "radii": [1, -1e-300, 1]}}}}"#),
            "error: constraint.radii[1]: must be ≥ 0, got -1e-300",
        ),
        (
            "strip",
            r#"{"t": [0, 1, 2], "y": [0, 1.34, 0], "upper": {"pieces": [[1, 0, 0, 0], [1, 0, 0, 0]]}}"#.to_string(),
            "error: y[1]: lies outside the upper bound by 0.34 at t = 1",
        ),
        (
            "strip",
            r#"{"t": [0, 1, 2], "y": [0, 1, 0], "upper": {"polyline": [[1, 0, 0]]}}"#.to_string(),
            "error: upper.polyline[0]: must be a vertex [t, value]: two numbers",
        ),
        (
            "strip",
            r#"{"t": [0, 1, 2], "y": [0, 1, 0], "upper": [[1, 0, 0, 0]]}"#.to_string(),
            r#"error: upper: must be null or an object like {"pieces": [[c0, c1, c2, c3], ...]}"#,
        ),
        (
            "strip",
            r#"{"t": [0, 1, 2], "y": [0, 1, 0], "end_slopes": [1]}"#.to_string(),
            "error: end_slopes: must be an array [start, end] of two numbers or nulls, not an array of 1 entry",
        ),
        (
            "surface",
            r#"{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]], "scheme": 4}"#.to_string(),
            r#"error: scheme: must be an object like {"points": 4, "arity": 2}, not 4"#,
        ),
        (
            // A triangle given with inward normals: every two half-planes meet, the three do
            // not (proved exactly before any solve).
            "refine",
            format!(
                r#"{{{P}, "constraint": {{"type": "halfspaces", "sets": [[], [{{"normal": [0, 1], "offset": 0}}, {{"normal": [1, 0], "offset": 0}}, {{"normal": [-1, -1], "offset": -1}}], []]}}}}"#
            ),
            "error: constraint.sets[1]: is empty: its half-spaces 0, 1, 2 have no common point",
        ),
        (
            // Sites 1e6 + ~3e-5 apart and a strip ±8e-12 about a zigzag of slope ~6: the
            // sites' rounding (slope × ulp(t) ≈ 7e-10) is wider than the strip, and the message
            // blames t, not the bound (found by a sweep; shifted to 0 it solves, see
            // crates/strip/tests/conditioning.rs).
            "strip",
            r#"{"t": [1000000.0, 1000000.0000315087, 1000000.000032026, 1000000.0000323687], "y": [1.5972995006188544e-06, -1.5972995006188544e-06, 1.5972995006188544e-06, -1.5972995006188544e-06], "lower": {"polyline": [[1000000.0, 1.597291377628902e-06], [1000000.0000315087, -1.5973076236088068e-06], [1000000.000032026, 1.597291377628902e-06], [1000000.0000323687, -1.5973076236088068e-06]]}, "upper": {"polyline": [[1000000.0, 1.5973076236088068e-06], [1000000.0000315087, -1.597291377628902e-06], [1000000.000032026, 1.5973076236088068e-06], [1000000.0000323687, -1.597291377628902e-06]]}}"#.to_string(),
            "error: t: the solution leaves the upper bound by 8.1",
        ),
    ];
    for (sub, doc, want) in cases {
        let got = message(sub, doc);
        assert!(got.starts_with(*want), "{doc}\n got: {got}\nwant: {want}");
    }
    let got = message("strip", &cases.last().expect("the strip case").1);
    assert!(got.ends_with("shift t to start near 0"), "{got}");

    // One tiny ball among large ones (found by a sweep; ROBUSTNESS.md §4, item 20): a solve
    // after a knot update is not certified (the first solve is: item 33), and the refusal names
    // the radius, the last knot_iterations that stops before it, and the remedies, which work —
    // radius 0 solves, and so do knot_iterations 1 and 0. (Radius 1e-8, this test's case until
    // the balls' start of 2026-12-07, is now certified after every update, against Clarabel's
    // point on the final knots to 5e-9: how near such a stiff spring comes to its certificate
    // turns on the start, and 2e-8 is refused at the second update.)
    let balls = |r3: &str| {
        format!(
            r#"{{"points": [[0, 0], [1, 1], [2, 0], [3, 1], [4, 0], [5, 1]], "k": 3, "closed": true, "constraint": {{"type": "balls", "radii": [0.3, 0.3, 0.3, {r3}, 0.3, 0.3]}}}}"#
        )
    };
    let got = message("refine", &balls("2e-8"));
    assert!(
        got.starts_with("error: constraint.radii[3]: after knot update 2 ")
            && got.contains("this radius, 2e-8, is 4e-9 of the data's extent")
            && got.ends_with(
                "give that point radius 0 to interpolate it exactly, or a larger radius"
            ),
        "{got}"
    );
    assert!(got.contains("knot_iterations 1 stops there"), "{got}");
    let (code, _, err) = run_cli(&["refine", "-"], &balls("0"));
    assert_eq!(code, 0, "{err}");
    for updates in [1, 0] {
        let fewer = balls("2e-8").replacen('{', &format!(r#"{{"knot_iterations": {updates}, "#), 1);
        let (code, _, err) = run_cli(&["refine", "-"], &fewer);
        assert_eq!(code, 0, "knot_iterations {updates}: {err}");
    }
}

#[test]
fn a_polygon_whose_refinement_overflows_says_so() {
    // Finite points near the f64 limit: the rule's weights > 1 overflow the refined polygon. The
    // refusal said "polygon.points: points[11] is not finite" of a polygon of four finite points.
    let dir = curvefit_tests::scratch_dir("overflow");
    let poly = dir.join("poly.json");
    std::fs::write(
        &poly,
        r#"{"points": [[0, 0], [1, 0], [1, 1.7e308], [0, 1]], "closed": true}"#,
    )
    .unwrap();
    let p = poly.to_str().unwrap();
    let args = [
        "scheme",
        "--stencil",
        "4",
        "--arity",
        "2",
        "--apply",
        p,
        "--levels",
        "3",
    ];
    let (code, out, err) = run_cli(&args, "");
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty());
    assert!(
        err.starts_with(
            "error: polygon.points: coordinates too large: the refined polygon overflows f64"
        ),
        "{err}"
    );
}

#[test]
fn levels_without_a_polygon_are_refused_not_ignored() {
    // `scheme --levels 5` alone printed the rules, exit 0: the levels went nowhere.
    let args = ["scheme", "--stencil", "4", "--arity", "2", "--levels", "5"];
    let (code, out, err) = run_cli(&args, "");
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty());
    assert_eq!(
        err.trim_end(),
        "error: --levels: needs --apply POLYGON.json"
    );
}

#[test]
fn a_polygon_file_that_cannot_be_read_is_named_by_its_flag() {
    // The file's own errors were prefixed as a field of the polygon: "polygon.--apply: cannot
    // open …".
    let dir = curvefit_tests::scratch_dir("apply_missing");
    let missing = dir.join("no_such_polygon.json");
    let m = missing.to_str().unwrap();
    let d = dir.to_str().unwrap();
    for (path, want) in [
        (m, format!("error: --apply: cannot open {m}: ")),
        (d, format!("error: --apply: {d} is a directory, not a file")),
    ] {
        let args = ["scheme", "--stencil", "4", "--arity", "2", "--apply", path];
        let (code, out, err) = run_cli(&args, "");
        assert_eq!(code, 2, "{err}");
        assert!(out.is_empty());
        assert!(err.starts_with(&want), "{err}\nwant: {want}");
    }
}
