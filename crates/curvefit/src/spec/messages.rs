//! Error messages in the user's words: what a field must look like, in JSON, instead of the
//! parser's Rust vocabulary (`expected internally tagged enum BoundarySpec`, `expected usize`),
//! and numbers printed as a person writes them (`0.34`, not `3.400000000000001e-1`).

/// `x` with at most six significant digits, trailing zeros dropped; plain decimals between 1e-4
/// and 1e6, else `1.5e-300` style.
pub fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" {
            "0".into()
        } else {
            s
        }
    } else {
        let s = format!("{x:.5e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = if mantissa.contains('.') {
            mantissa.trim_end_matches('0').trim_end_matches('.')
        } else {
            mantissa
        };
        format!("{mantissa}e{exp}")
    }
}

/// The field path with every index replaced by `[]` (`tangents[3].direction` →
/// `tangents[].direction`).
fn shape(field: &str) -> String {
    let mut out = String::with_capacity(field.len());
    let mut in_index = false;
    for c in field.chars() {
        match c {
            '[' => {
                in_index = true;
                out.push('[');
            }
            ']' => {
                in_index = false;
                out.push(']');
            }
            _ if in_index => {}
            c => out.push(c),
        }
    }
    out
}

/// What a field must be, in JSON, for the fields whose form is not obvious from their name.
pub fn expected(field: &str) -> Option<&'static str> {
    Some(match shape(field).as_str() {
        "boundary" => {
            r#"an object like {"type": "clamped", "start": [...], "end": [...]} (type "natural", "clamped", or "near_clamped" with a "radius")"#
        }
        "constraint" => {
            r#"an object like {"type": "balls", "radii": [...]} (type "interpolate", "balls" with "radii", "smoothing" with "weights", or "halfspaces" with "sets")"#
        }
        "tangents" => "an array with one entry per point: an object or null",
        "tangents[]" => {
            r#"null or an object like {"type": "wedge", "direction": [...], "half_angle": 0.2} (type "ball" with "center" and "radius", "wedge", "tension" with "radius", or "halfspaces")"#
        }
        "parametrization" => {
            r#""uniform", "centripetal", "chordal" or an object like {"exponent": 0.5}"#
        }
        "derivative" => r#""bessel" or "average""#,
        "solver" => r#""exact" or "paper""#,
        "constraint.sets" => {
            r#"an array with one array of half-spaces per point, like [[{"normal": [1, 0], "offset": 2}], []]"#
        }
        "constraint.sets[]" | "tangents[].halfspaces" => {
            r#"an array of half-spaces like [{"normal": [1, 0], "offset": 2}]"#
        }
        "constraint.sets[][]" | "tangents[].halfspaces[]" => {
            r#"a half-space like {"normal": [1, 0], "offset": 2} (normal · x ≤ offset)"#
        }
        "lower" | "upper" => {
            r#"null or an object like {"pieces": [[c0, c1, c2, c3], ...]} or {"polyline": [[t, value], ...]}"#
        }
        "lower.pieces" | "upper.pieces" => "an array with one cubic [c0, c1, c2, c3] per interval",
        "lower.pieces[]" | "upper.pieces[]" => "a cubic [c0, c1, c2, c3]: four numbers",
        "lower.polyline" | "upper.polyline" => "an array of vertices [t, value]",
        "lower.polyline[]" | "upper.polyline[]" => "a vertex [t, value]: two numbers",
        "end_slopes" => "an array [start, end] of two numbers or nulls",
        "scheme" => r#"an object like {"points": 4, "arity": 2}"#,
        "polygon" => r#"an object like {"points": [[0, 0], [1, 0], [1, 1]], "closed": true}"#,
        _ => return None,
    })
}

/// Rust and serde words for JSON types, replaced by JSON words.
fn json_words(expected: &str) -> String {
    let e = expected.trim();
    let word = match e {
        "usize" | "u64" | "u32" | "integer" => "a whole number ≥ 0",
        "isize" | "i64" | "i32" => "a whole number",
        "f64" | "f32" => "a number",
        "a boolean" | "bool" => "true or false",
        "a sequence" => "an array",
        "a map" => "an object",
        "a string" => "a string",
        _ => "",
    };
    if !word.is_empty() {
        return word.to_string();
    }
    if let Some(n) = e
        .strip_prefix("an array of length ")
        .and_then(|n| n.parse::<usize>().ok())
    {
        return format!("an array of {n} entries");
    }
    for prefix in [
        "internally tagged enum ",
        "struct ",
        "enum ",
        "tuple struct ",
    ] {
        if e.starts_with(prefix) {
            return "an object".to_string();
        }
    }
    e.to_string()
}

/// serde's name for a JSON value (`string "clamped"`, `integer `-1``, `map`) in JSON words.
fn value_words(unexpected: &str) -> String {
    let u = unexpected.trim();
    if let Some(rest) = u.strip_prefix("string ") {
        return format!("the string {rest}");
    }
    for (prefix, _) in [("integer ", ()), ("floating point ", ()), ("boolean ", ())] {
        if let Some(rest) = u.strip_prefix(prefix) {
            return rest.trim_matches('`').to_string();
        }
    }
    match u {
        "map" => "an object".into(),
        "sequence" => "an array".into(),
        "null" | "unit value" => "null".into(),
        other => other.to_string(),
    }
}

/// The JSON kind a description asks for: `[`-things, `{`-things or other values.
fn kind(text: &str) -> char {
    let t = text.trim_start_matches("null or ");
    if t.starts_with("an array") || t.starts_with("a cubic [") || t.starts_with("a vertex [") {
        '['
    } else if t.starts_with("an object") || t.starts_with("a half-space like {") {
        '{'
    } else {
        '"'
    }
}

/// What the `type` of an object with one (`constraint.type`, …) must be: a string naming the
/// object's form; `None` for other fields.
fn type_field(field: &str) -> Option<String> {
    let owner = field.strip_suffix(".type")?;
    expected(owner).map(|e| format!("a string: {owner} must be {e}"))
}

/// What `field` must be, given the parser's expectation `want`: the table's description when it
/// is about the field itself; the parser's (in JSON words) when the error is about a value
/// nested inside it that the parser could not locate (a reader without path tracking; the
/// objects with a `"type"` are read flat so that their paths are kept, `spec::tagged`). A
/// `"type"` of the wrong kind (serde's "variant identifier") is told with its object's form.
fn must_be(field: &str, want: &str) -> String {
    if want.trim() == "variant identifier" {
        return type_field(field).unwrap_or_else(|| "a string".into());
    }
    let generic = json_words(want);
    match expected(field) {
        Some(table) => {
            let about_field = [
                "internally tagged enum ",
                "struct ",
                "enum ",
                "tuple struct ",
            ]
            .iter()
            .any(|p| want.trim().starts_with(p))
                || kind(table) == kind(&generic);
            if about_field {
                table.to_string()
            } else {
                format!("{generic} (a value inside {field}, which must be {table})")
            }
        }
        None => generic,
    }
}

/// The field a serde message of the form "`what` `name`" is about ("missing field `rows`",
/// "duplicate field `k`"), or `None` for another message.
pub fn field_named<'a>(raw: &'a str, what: &str) -> Option<&'a str> {
    raw.strip_prefix(what)?
        .strip_prefix(" `")?
        .strip_suffix('`')
}

/// Rewrites a parser message for `field` in the user's words.
pub fn rewrite(field: &str, raw: &str) -> String {
    // "invalid type: X, expected Y" / "invalid value: X, expected Y"
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = raw.strip_prefix(prefix) {
            if let Some((got, want)) = rest.split_once(", expected ") {
                return format!("must be {}, not {}", must_be(field, want), value_words(got));
            }
        }
    }
    // "invalid length 3, expected an array of length 4"
    if let Some(rest) = raw.strip_prefix("invalid length ") {
        if let Some((got, want)) = rest.split_once(", expected ") {
            let entries = if got == "1" { "entry" } else { "entries" };
            return format!(
                "must be {}, not an array of {got} {entries}",
                must_be(field, want)
            );
        }
    }
    // "unknown variant `clamp`, expected one of `natural`, …": at `x.type`, `x` says the form.
    if let Some(rest) = raw.strip_prefix("unknown variant `") {
        if let Some((got, want)) = rest.split_once('`') {
            let owner = field.strip_suffix(".type").unwrap_or(field);
            let names = want
                .trim_start_matches(", expected one of ")
                .trim_start_matches(", expected ")
                .replace('`', "\"");
            return match expected(owner) {
                Some(e) => format!("\"{got}\" is not allowed: {owner} must be {e}"),
                None => format!("\"{got}\" is not allowed: must be {names}"),
            };
        }
    }
    // "missing field `radii`"
    if let Some(name) = field_named(raw, "missing field") {
        return match expected(field) {
            Some(e) if e.contains(&format!("\"{name}\"")) => {
                format!("needs the field \"{name}\": must be {e}")
            }
            _ if name == "normal" || name == "offset" => format!(
                "needs the field \"{name}\" in a half-space: each is like {{\"normal\": [1, 0], \"offset\": 2}}"
            ),
            _ => format!("needs the field \"{name}\""),
        };
    }
    // "unknown field `x`, expected one of `a`, `b`" / "expected `a` or `b`"
    if let Some(rest) = raw.strip_prefix("unknown field `") {
        if let Some((name, tail)) = rest.split_once('`') {
            if tail == ", there are no fields" {
                return format!(
                    "unknown field \"{name}\": this type has no other field than \"type\""
                );
            }
            let fields = tail
                .trim_start_matches(", expected one of ")
                .trim_start_matches(", expected ")
                .replace('`', "\"");
            return format!("unknown field \"{name}\" (the fields are {fields})");
        }
    }
    raw.to_string()
}

/// A syntax error at a field that is really a value of the wrong kind (serde_json reports a
/// number where an enum is expected as "expected value", and a fixed-size array that is too
/// long as "trailing characters").
pub fn syntax_at_field(field: &str, raw: &str) -> Option<String> {
    // (serde_json reads a number where a `type` is expected as a syntax error.)
    if let Some(e) = type_field(field) {
        return raw
            .starts_with("expected value")
            .then(|| format!("must be {e}"));
    }
    let e = expected(field)?;
    (raw.starts_with("expected value") || raw.starts_with("trailing characters"))
        .then(|| format!("must be {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_as_written() {
        assert_eq!(num(3.400000000000001e-1), "0.34");
        assert_eq!(num(4.0), "4");
        assert_eq!(num(-1e-300), "-1e-300");
        assert_eq!(num(1.234567e12), "1.23457e12");
        assert_eq!(num(0.000123456789), "0.000123457");
        assert_eq!(num(250000.0), "250000");
        assert_eq!(num(0.0), "0");
    }

    #[test]
    fn nested_errors_say_they_are_inside() {
        assert_eq!(
            rewrite("constraint", "invalid type: map, expected a sequence"),
            r#"must be an array (a value inside constraint, which must be an object like {"type": "balls", "radii": [...]} (type "interpolate", "balls" with "radii", "smoothing" with "weights", or "halfspaces" with "sets")), not an object"#
        );
        assert_eq!(
            rewrite(
                "boundary.type",
                "unknown variant `clamp`, expected one of `natural`, `clamped`, `near_clamped`"
            ),
            r#""clamp" is not allowed: boundary must be an object like {"type": "clamped", "start": [...], "end": [...]} (type "natural", "clamped", or "near_clamped" with a "radius")"#
        );
        assert_eq!(
            rewrite(
                "solver",
                "unknown variant `fast`, expected `exact` or `paper`"
            ),
            r#""fast" is not allowed: solver must be "exact" or "paper""#
        );
        assert!(rewrite("constraint", "missing field `offset`").contains("in a half-space"));
        assert_eq!(
            rewrite("constraint", "missing field `radii`"),
            format!(
                "needs the field \"radii\": must be {}",
                expected("constraint").unwrap()
            )
        );
    }

    #[test]
    fn parser_words_become_json_words() {
        assert_eq!(
            rewrite(
                "boundary",
                "invalid type: string \"clamped\", expected internally tagged enum BoundarySpec"
            ),
            r#"must be an object like {"type": "clamped", "start": [...], "end": [...]} (type "natural", "clamped", or "near_clamped" with a "radius"), not the string "clamped""#
        );
        assert_eq!(
            rewrite("k", "invalid value: integer `-1`, expected usize"),
            "must be a whole number ≥ 0, not -1"
        );
        assert_eq!(
            rewrite("k", "invalid type: floating point `1.5`, expected usize"),
            "must be a whole number ≥ 0, not 1.5"
        );
        assert_eq!(
            rewrite("knots[3]", "invalid type: string \"a\", expected f64"),
            "must be a number, not the string \"a\""
        );
        assert_eq!(
            rewrite(
                "end_slopes",
                "invalid length 1, expected an array of length 2"
            ),
            "must be an array [start, end] of two numbers or nulls, not an array of 1 entry"
        );
        assert_eq!(
            rewrite(
                "scheme",
                "invalid type: integer `4`, expected struct SchemeSpec"
            ),
            r#"must be an object like {"points": 4, "arity": 2}, not 4"#
        );
    }
}
