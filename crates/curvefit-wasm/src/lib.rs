//! # curvefit-wasm
//!
//! The playground's bridge to the library: `curvefit::spec` — the JSON contract of every
//! subcommand — compiled to WebAssembly (`wasm32-unknown-unknown`, bound by `wasm-bindgen`).
//! `cargo xtask playground --out DIR` builds it and writes the page around it.
//!
//! The page speaks the command line's JSON and nothing else: [`solve`] takes a subcommand name
//! and the problem as JSON text — exactly the file `curvefit SUBCOMMAND FILE` reads — parses it
//! with [`curvefit::spec::from_json`] and solves it with the same entry point the binary calls
//! ([`curvefit::spec::refine()`], …). What the page shows, downloads or puts in its URL therefore
//! runs unchanged through the binary and the Python package.
//!
//! The reply is JSON text, one of
//! - `{"result": R}` where `R` is the result `curvefit SUBCOMMAND` prints, or
//! - `{"error": {"field": F, "index": I, "message": M, "text": T}}`, the library's
//!   [`InputError`] (`T` is `"F: M"`, the line the command line prints after `error: `).
//!
//! Text in and out keeps the boundary to one string each way; at the playground's sizes
//! (hundreds of points) the JSON is a small part of a frame: the browser test splits each drag
//! frame's time, and with 200 points and balls the page's `JSON.stringify` and `JSON.parse`
//! take about 0.3 ms of a 17–20 ms frame, the module's serde parse and write under 1% of its
//! time (a native profile of the same problems) — the rest is the solve.
//!
//! ```
//! let reply = curvefit_wasm::reply("refine", r#"{"points": [[0, 0], [1, 0], [0, 1]]}"#);
//! let v: serde_json::Value = serde_json::from_str(&reply).unwrap();
//! assert!(v["result"]["kkt_residual"].as_f64().unwrap() <= 1e-9);
//! let reply = curvefit_wasm::reply("refine", r#"{"points": [[0, 0], [0, 0]]}"#);
//! let v: serde_json::Value = serde_json::from_str(&reply).unwrap();
//! assert_eq!(v["error"]["field"], "points[1]");
//! ```

use std::sync::Mutex;

use curvefit::spec::{self, InputError};
use wasm_bindgen::prelude::wasm_bindgen;

/// Parses `problem` (JSON text) as a problem of `subcommand` and solves it through
/// `curvefit::spec`; the `Ok` text is the result the command line prints for the same problem.
///
/// # Errors
/// The library's [`InputError`]: a parse error names the field path (`points[1][0]`), a bad
/// problem the user's field and index, an unknown subcommand the field `subcommand`.
pub fn solve_json(subcommand: &str, problem: &str) -> Result<String, InputError> {
    fn run<P, R>(
        problem: &str,
        solve: impl FnOnce(&P) -> Result<R, InputError>,
    ) -> Result<String, InputError>
    where
        P: serde::de::DeserializeOwned,
        R: serde::Serialize,
    {
        let p: P = spec::from_json(problem)?;
        let r = solve(&p)?;
        // The results are plain numbers, strings and arrays: serializing them cannot fail, but
        // a failure would still be reported, not unwrapped.
        serde_json::to_string(&r)
            .map_err(|e| InputError::new("", format!("the result could not be written: {e}")))
    }
    match subcommand {
        "refine" => run(problem, spec::refine),
        "strip" => run(problem, spec::strip),
        "scheme" => run(problem, spec::scheme),
        "surface" => run(problem, spec::surface),
        "natural" => run(problem, spec::natural),
        _ => Err(InputError::new(
            "subcommand",
            format!(
                "unknown subcommand {subcommand:?}: one of {}",
                spec::SUBCOMMANDS.join(", ")
            ),
        )),
    }
}

/// [`solve_json`] as one JSON reply: `{"result": …}` or `{"error": {"field", "index",
/// "message", "text"}}` (see the crate docs).
pub fn reply(subcommand: &str, problem: &str) -> String {
    match solve_json(subcommand, problem) {
        Ok(result) => format!("{{\"result\":{result}}}"),
        Err(e) => serde_json::json!({
            "error": {
                "field": e.field,
                "index": e.index,
                "message": e.message,
                "text": e.to_string(),
            }
        })
        .to_string(),
    }
}

/// The page's entry point: [`reply`] for `subcommand` and the problem's JSON text.
#[wasm_bindgen]
pub fn solve(subcommand: &str, problem: &str) -> String {
    reply(subcommand, problem)
}

/// The version of the curvefit library inside this module (the workspace version).
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// The message of the last panic, if any. The libraries never panic on input; should one
/// still panic (a bug), WebAssembly traps and the page catches the trap, then shows this message
/// instead of a bare "unreachable".
static LAST_PANIC: Mutex<String> = Mutex::new(String::new());

/// Records every panic's message for [`last_panic`] (wasm-bindgen runs this when the module
/// starts).
#[wasm_bindgen(start)]
pub fn start() {
    std::panic::set_hook(Box::new(|info| {
        if let Ok(mut last) = LAST_PANIC.lock() {
            *last = info.to_string();
        }
    }));
}

/// The message of the last panic (empty if none): see [`start`].
#[wasm_bindgen]
pub fn last_panic() -> String {
    LAST_PANIC.lock().map(|s| s.clone()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

    fn parse(s: &str) -> Value {
        serde_json::from_str(s).expect("the reply is JSON")
    }

    /// The reply's result is the library's result, serialized as the command line does.
    #[test]
    fn results_are_the_specs() {
        let problems = [
            (
                "refine",
                r#"{"points": [[0,0],[2,1],[3,-1],[5,0.5]], "constraint": {"type": "balls", "radii": [0.1, 0.3, 0.3, 0]}, "k": 4}"#,
            ),
            (
                "strip",
                r#"{"t": [0,1,2,3], "y": [0,1,0,1], "lower": {"polyline": [[0,-0.1],[3,-0.1]]}}"#,
            ),
            (
                "scheme",
                r#"{"points": 4, "arity": 3, "polygon": {"points": [[0,0],[1,1],[2,0],[3,1]]}, "levels": 2}"#,
            ),
            (
                "natural",
                r#"{"points": [[0,0],[1,2],[3,1],[4,3]], "levels": 3}"#,
            ),
            (
                "surface",
                r#"{"rows": 2, "cols": 2, "points": [[0,0,0],[0,1,0],[1,0,0],[1,1,1]]}"#,
            ),
        ];
        for (sub, text) in problems {
            // Compared as text: the reply must be the very bytes `curvefit SUBCOMMAND` writes
            // (serde_json's `to_writer` of the result), not merely close after a re-parse.
            let expected = match sub {
                "refine" => {
                    serde_json::to_string(&spec::refine(&spec::from_json(text).unwrap()).unwrap())
                }
                "strip" => {
                    serde_json::to_string(&spec::strip(&spec::from_json(text).unwrap()).unwrap())
                }
                "scheme" => {
                    serde_json::to_string(&spec::scheme(&spec::from_json(text).unwrap()).unwrap())
                }
                "natural" => {
                    serde_json::to_string(&spec::natural(&spec::from_json(text).unwrap()).unwrap())
                }
                _ => {
                    serde_json::to_string(&spec::surface(&spec::from_json(text).unwrap()).unwrap())
                }
            }
            .unwrap();
            let got = reply(sub, text);
            assert!(parse(&got).get("error").is_none(), "{sub}: {got}");
            assert_eq!(got, format!("{{\"result\":{expected}}}"), "{sub}");
        }
    }

    /// Bad states the page can reach by dragging give the library's message, field and index.
    #[test]
    fn bad_states_reply_with_the_librarys_error() {
        let cases = [
            // Two consecutive points dragged onto each other.
            (
                "refine",
                r#"{"points": [[0,0],[1,1],[1,1]]}"#,
                "points[2]",
                Some(2),
            ),
            // A site dragged past its neighbour.
            ("strip", r#"{"t": [0,2,1], "y": [0,1,0]}"#, "t[2]", Some(2)),
            // The upper polyline dragged below a data value.
            (
                "strip",
                r#"{"t": [0,1,2], "y": [0,2,0], "upper": {"polyline": [[0,1],[2,1]]}}"#,
                "y[1]",
                Some(1),
            ),
            ("scheme", r#"{"points": 3, "arity": 2}"#, "points", None),
            (
                "refine",
                r#"{"points": [[0,0],[1,"x"]]}"#,
                "points[1][1]",
                Some(1),
            ),
            ("refine", "[1, 2]", "problem", None),
            ("nonsense", "{}", "subcommand", None),
        ];
        for (sub, text, field, index) in cases {
            let v = parse(&reply(sub, text));
            let e = &v["error"];
            assert_eq!(e["field"], field, "{sub} {text}: {v}");
            assert_eq!(e["index"].as_u64(), index.map(|i| i as u64), "{text}");
            let message = e["message"].as_str().unwrap();
            assert!(!message.is_empty());
            assert_eq!(e["text"], format!("{field}: {message}"));
            assert!(v.get("result").is_none());
        }
    }

    /// The playground's drawing needs the result fields it reads; a renamed field would leave
    /// the page blank, so their presence is part of the contract checked here.
    #[test]
    fn results_carry_the_fields_the_page_draws() {
        let v = parse(&reply(
            "refine",
            r#"{"points": [[0,0],[1,1],[2,0]], "closed": true, "constraint": {"type": "halfspaces", "sets": [[{"normal": [0,1], "offset": 0.5}], [], []]}}"#,
        ));
        let r = &v["result"];
        for f in [
            "points",
            "knots",
            "data_vertex",
            "energy",
            "active",
            "multipliers",
            "kkt_residual",
        ] {
            assert!(r.get(f).is_some(), "refine result lacks {f}: {r}");
        }
        let v = parse(&reply(
            "strip",
            r#"{"t": [0,1,2,3,4], "y": [0,1,0,0,1], "lower": {"polyline": [[0,-0.05],[4,-0.05]]}}"#,
        ));
        let r = &v["result"];
        for f in [
            "breaks",
            "coefficients",
            "extra_knots",
            "norm",
            "gradient_norm",
        ] {
            assert!(r.get(f).is_some(), "strip result lacks {f}: {r}");
        }
        assert!(r["extra_knots"][0].get("kind").is_some());
    }
}
