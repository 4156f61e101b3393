//! Structured strips (`arbitrary`): 2–40 sites with arbitrary positive gaps (ratios up to
//! 2^16), values on a scale 10^e, polyline or piecewise-constant-as-cubic bounds at arbitrary
//! distances (zero allowed: the data on a bound), optional end slopes. A strip whose data lie
//! inside is feasible and must be solved; every solution is checked by the oracles.
#![no_main]
use arbitrary::Arbitrary;
use curvefit::spec;
use libfuzzer_sys::fuzz_target;
use serde_json::json;

#[derive(Arbitrary, Debug)]
struct Input {
    sites: Vec<(u16, i16, u8, u8)>,
    exponent: i8,
    polyline: bool,
    slopes: Option<(i8, i8)>,
}

fuzz_target!(|inp: Input| {
    let n = inp.sites.len().min(40);
    if n < 2 {
        return;
    }
    let scale = 10f64.powi(i32::from(inp.exponent).clamp(-30, 30));
    let mut t = Vec::with_capacity(n);
    let mut acc = 0.0;
    for &(gap, ..) in &inp.sites[..n] {
        acc += 1.0 + f64::from(gap);
        t.push(acc);
    }
    let y: Vec<f64> = inp.sites[..n]
        .iter()
        .map(|s| f64::from(s.1) * scale / 100.0)
        .collect();
    let below: Vec<f64> = inp.sites[..n]
        .iter()
        .map(|s| f64::from(s.2) * scale)
        .collect();
    let above: Vec<f64> = inp.sites[..n]
        .iter()
        .map(|s| f64::from(s.3) * scale)
        .collect();
    let (lower, upper) = if inp.polyline {
        // through (t_i, y_i ∓ gap_i): the channel contains the data at the sites
        let lo: Vec<[f64; 2]> = (0..n).map(|i| [t[i], y[i] - below[i]]).collect();
        let up: Vec<[f64; 2]> = (0..n).map(|i| [t[i], y[i] + above[i]]).collect();
        (json!({"polyline": lo}), json!({"polyline": up}))
    } else {
        // constant pieces at the data's range ∓ the first gap
        let (ymin, ymax) = y
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        let lo: Vec<[f64; 4]> = (0..n - 1)
            .map(|_| [ymin - below[0], 0.0, 0.0, 0.0])
            .collect();
        let up: Vec<[f64; 4]> = (0..n - 1)
            .map(|_| [ymax + above[0], 0.0, 0.0, 0.0])
            .collect();
        (json!({"pieces": lo}), json!({"pieces": up}))
    };
    let mut problem = json!({"t": t, "y": y, "lower": lower, "upper": upper});
    if let Some((a, b)) = inp.slopes {
        problem["end_slopes"] = json!([f64::from(a) * scale, f64::from(b) * scale]);
    }
    let Ok(p) = spec::from_json::<spec::StripProblem>(&problem.to_string()) else {
        return;
    };
    match spec::strip(&p) {
        Ok(s) => curvefit_fuzz::check_strip(&p, &s),
        Err(e) => curvefit_fuzz::check_refusal(&e),
    }
});
