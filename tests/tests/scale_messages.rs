//! Scale-free geometry and refusals that name the user's field (issue 17 §3, §5), through the
//! binary: each input that used to be refused naming an internal quantity (`knots[1]` where no
//! knots were given, `axis[0]`, `knots[5]` of the refined knots) is now either solved with its
//! certificate or refused with exit code 2 and one line naming exactly the JSON field at fault.

use curvefit_tests::run_cli;

/// The field named by a refusal: the text between `error: ` and the next `: `.
fn refused_field(doc: &str) -> String {
    let (code, out, err) = run_cli(&["refine", "-"], doc);
    assert_eq!(code, 2, "{doc}: {err}");
    assert!(out.is_empty());
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let line = err.trim_end();
    let rest = line.strip_prefix("error: ").unwrap_or(line);
    rest.split(": ").next().unwrap_or("").to_string()
}

/// A fixture of `tests/fixtures` and the one line its refusal prints (exit code 2, nothing on
/// standard output).
fn refused_fixture(name: &str) -> (String, String) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name);
    let doc = std::fs::read_to_string(path).unwrap();
    let (code, out, err) = run_cli(&["refine", "-"], &doc);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty());
    let line = err.trim_end().to_string();
    (doc, line)
}

fn solved(doc: &str) -> serde_json::Value {
    let (code, out, err) = run_cli(&["refine", "-"], doc);
    assert_eq!(code, 0, "{doc}: {err}");
    assert!(!out.contains("null"), "{doc}: non-finite output");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let kkt = v["kkt_residual"].as_f64().unwrap();
    assert!(kkt <= 1e-9, "{doc}: kkt {kkt}");
    v
}

#[test]
fn extreme_scales_are_refused_naming_points() {
    // Squared distances overflow (was `knots[1] is not finite`) and underflow (was `points[0]
    // and points[1] coincide`): beyond refine::EXTENT_RANGE, refused naming the farthest point.
    for s in ["1e300", "1e-300", "1e200", "1e-200"] {
        let doc = format!(r#"{{"points": [[{s}, -{s}], [-{s}, {s}], [{s}, {s}]]}}"#);
        assert_eq!(refused_field(&doc), "points[1]", "{s}");
    }
}

#[test]
fn small_and_large_data_inside_the_range_are_solved() {
    // Well inside refine::EXTENT_RANGE: solved with the certificate like data at 1.
    for s in ["1e-40", "1e40"] {
        let doc = format!(
            r#"{{"points": [[0, 0], [{s}, {s}], [0, {s}], [{s}, 0]], "parametrization": "uniform"}}"#
        );
        solved(&doc);
    }
}

#[test]
fn a_tiny_wedge_direction_is_a_direction() {
    // [1e-200, 0] has length 1e-200, whose square underflows (was `axis[0] is not finite`).
    solved(
        r#"{"points": [[0,0],[1,1],[2,0],[3,1]],
            "tangents": [null, {"type": "wedge", "direction": [1e-200, 0], "half_angle": 0.3}, null, null]}"#,
    );
}

#[test]
fn knots_too_close_to_split_name_the_given_knot() {
    // Valid (increasing) knots whose span 2.2e-16 cannot hold k + 1 increasing sub-spans: the
    // refined knot index (was `knots[5]`) is mapped back to the data knot.
    let doc = r#"{"points": [[0,0],[1,1],[2,0],[3,1]], "knots": [0, 1, 1.0000000000000002, 2]}"#;
    assert_eq!(refused_field(doc), "knots[2]");
}

#[test]
fn an_exponent_too_large_names_the_exponent() {
    // |p_{j+1} − p_j|^50 of the refined vertices vanishes against the knot values (was
    // `knots[3] is not greater than knots[2]`).
    let doc = r#"{"points": [[0,0],[1,1],[2,0],[3,1]], "parametrization": {"exponent": 50}}"#;
    assert_eq!(refused_field(doc), "parametrization.exponent");
    // Without knot updates the data parameters (spans 2^25) are fine: solved.
    solved(
        r#"{"points": [[0,0],[1,1],[2,0],[3,1]], "parametrization": {"exponent": 50}, "knot_iterations": 0}"#,
    );
}

#[test]
fn badly_scaled_spans_inside_the_range() {
    // Chordal spans of 1e-100 make H ~ 1e300 (was `singular system: non-positive pivot at
    // vertex …` with no field, then refused naming `points`): solved on data and knots scaled by
    // powers of two (ROBUSTNESS.md item 39), the answer's energy ∝ 1/s of the same star at 1.
    let star = |s: &str| {
        format!(
            r#""points": [[0,0],[{s},{s}],[0,{s}],[{s},0]], "parametrization": "chordal", "k": 7"#
        )
    };
    let small = solved(&format!("{{{}}}", star("1e-100")));
    let one = solved(&format!("{{{}}}", star("1")));
    let (e, e1) = (
        small["energy"].as_f64().unwrap(),
        one["energy"].as_f64().unwrap(),
    );
    assert!((e * 1e-100 - e1).abs() <= 1e-9 * e1, "{e} vs {e1}");
    // Smoothing weights of 1 against that stiffness leave H + W singular to rounding: named.
    let doc = format!(
        r#"{{{}, "constraint": {{"type": "smoothing", "weights": [1, 1, 1, 1]}}}}"#,
        star("1e-100")
    );
    assert_eq!(refused_field(&doc), "constraint.weights");
    // Weights of 1e300 on spans of 1e100 (w·h³ = 1e600: no solve can tell them from
    // interpolated points; unscaled, E came back 0 with a certificate of 0) are refused naming
    // the first; weights of 1 there are solved, with the interpolant's energy.
    let diamond = |w: &str| {
        format!(
            r#"{{"points": [[0,0],[1e100,1e100],[0,2e100],[-1e100,1e100]], "closed": true, "parametrization": "chordal",
                "knot_iterations": 0, "constraint": {{"type": "smoothing", "weights": [{w},{w},{w},{w}]}}}}"#
        )
    };
    assert_eq!(refused_field(&diamond("1e300")), "constraint.weights[0]");
    let e = solved(&diamond("1"))["energy"].as_f64().unwrap();
    let unit = r#"{"points": [[0,0],[1,1],[0,2],[-1,1]], "closed": true, "parametrization": "chordal", "knot_iterations": 0}"#;
    let e1 = solved(unit)["energy"].as_f64().unwrap();
    assert!((e * 1e100 - e1).abs() <= 1e-9 * e1, "{e} vs {e1}");
    // A span of 1e-100 beside spans of 1 stays out of reach: the point is named.
    let doc =
        r#"{"points": [[0,0],[1e-100,1e-100],[1,1],[2,0]], "parametrization": "chordal", "k": 1}"#;
    assert_eq!(refused_field(doc), "points[1]");
}

#[test]
fn library_fields_are_the_json_paths() {
    // The library's `weights` is the JSON's `constraint.weights`.
    let doc = r#"{"points": [[0,0],[1,1],[2,0]], "constraint": {"type": "smoothing", "weights": [1, 0, 0]}}"#;
    assert_eq!(refused_field(doc), "constraint.weights");
}

#[test]
fn a_solve_lost_after_a_knot_update_names_knot_iterations() {
    // The robustness sweep's smallest such case (ROBUSTNESS.md §4, 15): 50 points in clusters
    // 1e-3 apart, smoothing weights over six decades, a wedge of half-angle 0.2 at every point,
    // the default three knot updates. The first two solves are certified, the third is not
    // (best residual 1.1e-7): refused naming knot_iterations with the number of updates that
    // were certified (it was "full-vertex interior point did not converge …", naming nothing).
    let (doc, line) = refused_fixture("refine-refused-after-knot-update.json");
    assert!(
        line.starts_with("error: knot_iterations: stage 0, knot update 3: "),
        "{line}"
    );
    assert!(line.ends_with("use knot_iterations 2 or fewer"), "{line}");
    // The advice holds: with two updates the same problem is certified, and so with none.
    let mut v: serde_json::Value = serde_json::from_str(&doc).unwrap();
    for kit in [2, 0] {
        v["knot_iterations"] = kit.into();
        let r = solved(&v.to_string());
        assert_eq!(r["iterations"]["knot_updates"], kit, "{kit}");
    }
}

#[test]
fn a_constraint_is_not_called_infeasible_on_a_guess() {
    // ROBUSTNESS.md §4, 18: 20 nearly collinear points, balls and tangent sets, k = 3. With
    // k ≥ 2 every data vertex has free neighbours of its own that can give its derivative any
    // value, and every set here is non-empty, so the constraints can always be met together.
    // After the first knot update the method stopped uncertified and the most violated
    // constraint was reported as "constraint.radii[1]: cannot be satisfied together with the
    // other constraints". It is refused naming the update instead, and the advice holds.
    let (doc, line) = refused_fixture("refine-heuristic-infeasible.json");
    assert!(!line.contains("cannot be satisfied"), "{line}");
    assert!(
        line.starts_with("error: knot_iterations: stage 0, knot update 1: "),
        "{line}"
    );
    assert!(line.ends_with("use knot_iterations 0"), "{line}");
    let mut v: serde_json::Value = serde_json::from_str(&doc).unwrap();
    v["knot_iterations"] = 0.into();
    let r = solved(&v.to_string());
    assert!(r["kkt_residual"].as_f64().unwrap() <= 1e-9, "{r}");
}

#[test]
fn an_uncertified_solve_with_derivative_constraints_names_them() {
    // ROBUSTNESS.md §4, 22 (seed 1107 of that sweep, rounded): eight points with balls, a
    // tension tangent and a wedge of half-angle 0.005 at a point whose optimal derivative
    // vanishes (the wedge's apex). The general interior-point method stops uncertified (~1e-6);
    // it was refused as "full-vertex interior point did not converge …", naming nothing. It now
    // names `tangents`, and the advice holds: with a wider half_angle it is certified.
    let (doc, line) = refused_fixture("refine-apex-wedge.json");
    assert!(line.starts_with("error: tangents: "), "{line}");
    assert!(line.contains("a wider half_angle"), "{line}");
    let mut v: serde_json::Value = serde_json::from_str(&doc).unwrap();
    v["tangents"][5]["half_angle"] = 0.05.into();
    solved(&v.to_string());
}

#[test]
fn ball_radii_far_beyond_or_far_below_the_data() {
    // A radius of 1e10 or 1e300 leaves its point free: solved and certified, as a radius of
    // 10 (the optimum's ball there is inactive, so the energies are equal). A closed curve
    // with one ball of 1e10 stopped uncertified; 1e300 (ε² overflows) made the certificate NaN.
    let doc = |big: &str| {
        format!(
            r#"{{"points": [[0, 0], [1, 1], [2, 0], [3, 1], [4, 0], [5, 1]], "closed": true, "constraint": {{"type": "balls", "radii": [0.1, {big}, 0.1, 0.1, {big}, 0.1]}}}}"#
        )
    };
    let reference = solved(&doc("10"))["energy"].as_f64().unwrap();
    for big in ["1e10", "1e300"] {
        let e = solved(&doc(big))["energy"].as_f64().unwrap();
        assert!(
            (e - reference).abs() <= 1e-9 * reference,
            "{big}: {e} vs {reference}"
        );
    }
    // Radii of 1e-310 (subnormal) on data of size 1: refused naming the radius, where radii of
    // 1e-260 on data of size 1e-100 were refused as "start.s[0] is invalid: not strictly inside
    // its cone", a field the user never wrote (those are now solved on rescaled data).
    let tiny = |r: &str, s: &str| {
        format!(
            r#"{{"points": [[0, 0], [{s}, {s}], [2{s2}, 0], [3{s2}, {s}]], "constraint": {{"type": "balls", "radii": [{r}, {r}, {big}, {r}]}}}}"#,
            s2 = if s == "1" { "" } else { "e-100" },
            big = if s == "1" { "1e-1" } else { "1e-101" },
        )
    };
    assert_eq!(refused_field(&tiny("1e-310", "1")), "constraint.radii[0]");
    // On the rescaled data that solve is certified, but the balls' multipliers (force over
    // radius, ~1e310) overflow: refused naming the first such radius, not written as null.
    assert_eq!(
        refused_field(&tiny("1e-260", "1e-100")),
        "constraint.radii[0]"
    );
    solved(&tiny("1e-200", "1e-100"));
}

#[test]
fn end_derivatives_whose_energy_overflows_are_refused_naming_the_boundary() {
    // A clamped end of 1e200 on data of size 1: the optimum's energy is ~1e400. It was written
    // with `"energy": null` and exit code 0, as if certified; it is refused naming `boundary`.
    // At 1e150 the energy (~3e299) is representable and the solve is certified.
    let doc = |v: &str| {
        format!(
            r#"{{"points": [[0, 0], [1, 1], [2, 0], [3, 1], [4, 0]], "boundary": {{"type": "clamped", "start": [{v}, 0], "end": [0, {v}]}}}}"#
        )
    };
    assert_eq!(refused_field(&doc("1e200")), "boundary");
    let e = solved(&doc("1e150"))["energy"].as_f64().unwrap();
    assert!(e.is_finite() && e > 1e290, "{e}");
}
