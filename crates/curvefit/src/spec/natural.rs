//! `natural`: Warren–Weimer natural cubic subdivision on [0, L] with the control
//! points at the integers 0..L (seed 003, §6.2–6.3).
//!
//! Problem: `{"points": [[x, …], …], "levels": K}` — at least 2 points of one dimension d ≥ 1
//! (the curve is subdivided coordinate by coordinate), `levels` default 4. Result:
//! `{"levels": [{"level": k, "points": [...], "energy": p_kᵀE_kp_k}, … for k = 0..K],
//! "limit_energy": p₀ᵀE₀N₀p₀}`, energies summed over coordinates (E_k = 8^k D₂ᵀD₂; the limit
//! energy is ∫|p''|² of the limit curve, Theorem 6.4).

use serde::{Deserialize, Serialize};
use subdivision::NaturalScheme;

use super::scheme::validate_rows;
use super::{InputError, Rows};

/// Largest result accepted: coordinates summed over all levels (the output lists every level).
pub const MAX_NATURAL_OUTPUT_COORDS: usize = 10_000_000;

/// The `natural` problem.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NaturalProblem {
    /// Control points p_0 at the integers 0..L.
    #[serde(default)]
    pub points: Rows,
    /// Rounds of subdivision K (default 4).
    #[serde(default = "four")]
    pub levels: usize,
}

fn four() -> usize {
    4
}

/// One level of the result.
#[derive(Debug, Clone, Serialize)]
pub struct NaturalLevel {
    /// k.
    pub level: usize,
    /// p_k (2^k L + 1 points).
    pub points: Rows,
    /// p_kᵀ E_k p_k summed over coordinates.
    pub energy: f64,
}

/// The `natural` result.
#[derive(Debug, Clone, Serialize)]
pub struct NaturalSolution {
    /// Levels 0..=K.
    pub levels: Vec<NaturalLevel>,
    /// p₀ᵀE₀N₀p₀ summed over coordinates: the exact energy of the limit curve.
    pub limit_energy: f64,
}

/// `curvefit natural`: K levels of Warren–Weimer's natural scheme and the exact limit energy.
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn solve(problem: &NaturalProblem) -> Result<NaturalSolution, InputError> {
    let p0 = validate_rows("points", &problem.points, 2)?;
    let l = p0.len() - 1;
    // Σ_k (2^k L + 1) d ≤ (2^{K+1} L + K + 1) d, checked before any allocation.
    let total = u32::try_from(problem.levels + 1)
        .ok()
        .and_then(|e| 1usize.checked_shl(e))
        .and_then(|f| f.checked_mul(l))
        .and_then(|n| n.checked_add(problem.levels + 1))
        .and_then(|n| n.checked_mul(p0.dim()));
    if total.is_none_or(|t| t > MAX_NATURAL_OUTPUT_COORDS) {
        return Err(InputError::new(
            "levels",
            format!(
                "{} levels on {} points would exceed {MAX_NATURAL_OUTPUT_COORDS} output coordinates",
                problem.levels,
                p0.len()
            ),
        ));
    }
    let scheme = NaturalScheme::new().map_err(|e| InputError::new("", e))?;
    let levels = scheme
        .subdivide_levels(&p0, problem.levels)
        .map_err(|e| InputError::new("levels", e))?;
    let limit_energy = scheme
        .limit_energy(&p0)
        .map_err(|e| InputError::new("points", e))?;
    let solution = NaturalSolution {
        levels: levels
            .iter()
            .enumerate()
            .map(|(k, p)| NaturalLevel {
                level: k,
                points: Rows(p.clone()),
                energy: NaturalScheme::energy(p, k),
            })
            .collect(),
        limit_energy,
    };
    // The points are convex combinations of the input (always finite); the energies are
    // sums of squares and can overflow for coordinates near the f64 limit.
    let finite =
        solution.limit_energy.is_finite() && solution.levels.iter().all(|l| l.energy.is_finite());
    if !finite {
        return Err(InputError::new(
            "points",
            "coordinates too large: the energy overflows the f64 range",
        ));
    }
    Ok(solution)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(s: &str) -> NaturalProblem {
        super::super::from_json(s).unwrap()
    }

    /// The error of parsing or solving `s`.
    fn error(s: &str) -> InputError {
        match super::super::from_json::<NaturalProblem>(s) {
            Ok(p) => solve(&p).unwrap_err(),
            Err(e) => e,
        }
    }

    #[test]
    fn result_follows_the_contract() {
        let p = problem(r#"{"points": [[0,0],[1,2],[3,1],[4,3]], "levels": 3}"#);
        let s = solve(&p).unwrap();
        assert_eq!(s.levels.len(), 4);
        for (k, lv) in s.levels.iter().enumerate() {
            assert_eq!(lv.level, k);
            assert_eq!(lv.points.len(), 3 * (1 << k) + 1);
        }
        assert!(s.levels.windows(2).all(|w| w[1].energy < w[0].energy));
        assert!(s.levels[3].energy > s.limit_energy);
        let v = serde_json::to_value(&s).unwrap();
        assert!(v["levels"][0]["energy"].is_number() && v["limit_energy"].is_number());
        let d = problem(r#"{"points": [[0],[1]]}"#);
        assert_eq!(solve(&d).unwrap().levels.len(), 5);
    }

    #[test]
    fn bad_input_names_the_field() {
        let e = error(r#"{"points": [[0,0]]}"#);
        assert_eq!(e.field, "points");
        let e = error(r#"{"points": [[0,0],[1]]}"#);
        assert_eq!(e.field, "points[1]");
        let e = error(r#"{"points": [[0,0],[1,1]], "levels": 40}"#);
        assert_eq!(e.field, "levels");
        let e = error(r#"{"points": [[], []]}"#);
        assert_eq!(e.field, "points[0]");
        // Found by `cargo xtask fuzz`: finite input whose energy overflows.
        let e = error(r#"{"points": [[0,0],[1,1e308],[3,1]]}"#);
        assert_eq!(e.field, "points");
        assert!(serde_json::from_str::<NaturalProblem>(r#"{"points": [[0]], "x": 1}"#).is_err());
    }
}
