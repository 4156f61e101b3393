//! Structured refinement problems (`arbitrary`): 3–12 points on a grid scaled by 10^e
//! (e in −40..40), open or closed, d = 2 or 3, k 1–6, each constraint kind, chosen
//! parametrization and ends. Every result is checked by the oracles, and the same problem
//! translated by three times its extent must give the same energy (to 1e-6 relative: the
//! translation itself rounds the data at ~1e-16 of the offset, and the certificate bounds the
//! energy's error at ~1e-9) and points moved by the offset.
#![no_main]
use arbitrary::Arbitrary;
use curvefit::spec;
use libfuzzer_sys::fuzz_target;
use serde_json::json;

#[derive(Arbitrary, Debug)]
struct Input {
    coords: Vec<(i8, i8, i8)>,
    three_d: bool,
    closed: bool,
    k: u8,
    exponent: i8,
    kind: u8,
    sizes: Vec<u8>,
    param: u8,
    ends: u8,
    knot_iterations: u8,
}

fuzz_target!(|inp: Input| {
    let n = inp.coords.len().clamp(0, 12);
    if n < 3 {
        return;
    }
    let d = if inp.three_d { 3 } else { 2 };
    let scale = 10f64.powi(i32::from(inp.exponent).clamp(-40, 40));
    let pts: Vec<Vec<f64>> = inp.coords[..n]
        .iter()
        .map(|&(x, y, z)| {
            let v = [f64::from(x), f64::from(y), f64::from(z)];
            v[..d].iter().map(|c| c * scale).collect()
        })
        .collect();
    let size = |i: usize| f64::from(inp.sizes.get(i).copied().unwrap_or(0)) / 32.0 * scale;
    let constraint = match inp.kind % 4 {
        0 => json!({"type": "interpolate"}),
        1 => json!({"type": "balls", "radii": (0..n).map(size).collect::<Vec<_>>()}),
        2 => json!({"type": "smoothing", "weights": (0..n)
            .map(|i| 10f64.powi(i32::from(inp.sizes.get(i).copied().unwrap_or(0) % 20) - 4) / (scale * scale))
            .collect::<Vec<_>>()}),
        _ => {
            // a box of half-width size(i) about each point
            let sets: Vec<Vec<serde_json::Value>> = pts
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    (0..d)
                        .flat_map(|c| {
                            let mut e = vec![0.0; d];
                            e[c] = 1.0;
                            let mut m = vec![0.0; d];
                            m[c] = -1.0;
                            [
                                json!({"normal": e, "offset": p[c] + size(i)}),
                                json!({"normal": m, "offset": -p[c] + size(i)}),
                            ]
                        })
                        .collect()
                })
                .collect();
            json!({"type": "halfspaces", "sets": sets})
        }
    };
    let parametrization = ["uniform", "chordal", "centripetal"][usize::from(inp.param % 3)];
    let mut problem = json!({
        "points": pts,
        "closed": inp.closed,
        "k": 1 + inp.k % 6,
        "knot_iterations": inp.knot_iterations % 3,
        "parametrization": parametrization,
        "constraint": constraint,
    });
    if !inp.closed && inp.ends % 3 == 1 {
        let mut start = vec![0.0; d];
        start[0] = scale;
        let end = vec![0.0; d];
        problem["boundary"] = json!({"type": "clamped", "start": start, "end": end});
    }
    let Ok(p) = spec::from_json::<spec::RefineProblem>(&problem.to_string()) else {
        return;
    };
    let Ok(r) = spec::refine(&p) else { return };
    curvefit_fuzz::check_refine(&p, &r);

    // translation invariance
    let extent = pts.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let offset = 3.0 * extent;
    let mut moved = problem.clone();
    moved["points"] = json!(pts
        .iter()
        .map(|p| p.iter().map(|x| x + offset).collect::<Vec<_>>())
        .collect::<Vec<_>>());
    if let serde_json::Value::Object(c) = &mut moved["constraint"] {
        if let Some(serde_json::Value::Array(sets)) = c.get_mut("sets") {
            for set in sets.iter_mut().filter_map(|s| s.as_array_mut()) {
                for h in set.iter_mut() {
                    let shift: f64 = h["normal"]
                        .as_array()
                        .map(|v| v.iter().filter_map(|x| x.as_f64()).sum::<f64>() * offset)
                        .unwrap_or(0.0);
                    let o = h["offset"].as_f64().unwrap_or(0.0);
                    h["offset"] = json!(o + shift);
                }
            }
        }
    }
    let mp = spec::from_json::<spec::RefineProblem>(&moved.to_string()).expect("moved parses");
    let rm = spec::refine(&mp).unwrap_or_else(|e| {
        panic!(
            "solved at the origin, refused translated by {offset:e}: {}: {}",
            e.field, e.message
        )
    });
    curvefit_fuzz::check_refine(&mp, &rm);
    // Energies are compared on the problem's own scale extent²/T³ (T the knots' span): a
    // nearly straight curve's E is rounding noise of that size, not a relative quantity.
    let span = r.knots[r.knots.len() - 1] - r.knots[0];
    let natural = extent * extent / (span * span * span);
    let floor = 1e-9 * natural;
    if r.energy.max(rm.energy) > floor {
        let rel = (r.energy - rm.energy).abs() / r.energy.max(rm.energy);
        assert!(
            rel <= 1e-6 || (r.energy - rm.energy).abs() <= floor,
            "energy {} vs {} translated ({rel:e})",
            r.energy,
            rm.energy
        );
    }
});
