//! `surface`: the tensor-product (2m+2)-point n-ary scheme (Khan
//! et al. §4, (4.2)) applied to a regular quad grid; the result as JSON and as an OBJ quad mesh.
//!
//! Grid problem:
//! ```json
//! {"rows": 4, "cols": 5, "points": [[x, y, z], …],
//!  "closed": [false, false], "scheme": {"points": 4, "arity": 2}, "levels": 1}
//! ```
//! `points` lists the rows × cols grid points row-major (point (i, j) is entry i·cols + j), all of
//! one dimension d ∈ {2, 3} (OBJ needs 2 or 3; d = 2 is written with z = 0). `closed` = [wrap the
//! row index i, wrap the column index j] (default both open; open directions use the one-sided end
//! stencils of `subdivision::NaryScheme`). `scheme` = the stencil size P = 2m + 2 and the arity N
//! (default {"points": 4, "arity": 2}: Kobbelt's tensor-product 4-point scheme). `levels` default
//! 1. Result: `{"rows", "cols", "closed", "levels", "points": [...] (row-major), "quads": [[a, b,
//! c, d], …] (0-based point indices)}`; [`obj_text`] gives the OBJ text for `--obj`.

use serde::{Deserialize, Serialize};
use subdivision::{quad_mesh_obj, QuadGrid};

use super::scheme::{scheme_from_flags, validate_rows};
use super::{InputError, Rows};

/// Largest result accepted: refined grid points × dimension.
pub const MAX_SURFACE_OUTPUT_COORDS: usize = 10_000_000;

/// The scheme of a grid problem.
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SchemeSpec {
    /// Stencil size P = 2m + 2 (default 4).
    #[serde(default = "four")]
    pub points: usize,
    /// Arity N (default 2).
    #[serde(default = "two")]
    pub arity: usize,
}

impl Default for SchemeSpec {
    fn default() -> Self {
        SchemeSpec {
            points: 4,
            arity: 2,
        }
    }
}

fn four() -> usize {
    4
}
fn two() -> usize {
    2
}
fn one() -> usize {
    1
}

/// The `surface` problem (a quad grid).
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceProblem {
    /// Number of rows (range of i), at least 2.
    pub rows: usize,
    /// Number of columns (range of j), at least 2.
    pub cols: usize,
    /// rows × cols points, row-major.
    #[serde(default)]
    pub points: Rows,
    /// [closed in i, closed in j]; default both open.
    #[serde(default)]
    pub closed: [bool; 2],
    /// The curve scheme applied in each direction.
    #[serde(default)]
    pub scheme: SchemeSpec,
    /// Levels of refinement (default 1).
    #[serde(default = "one")]
    pub levels: usize,
}

/// The `surface` result.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceSolution {
    /// Rows of the refined grid.
    pub rows: usize,
    /// Columns of the refined grid.
    pub cols: usize,
    /// As in the problem.
    pub closed: [bool; 2],
    /// As in the problem.
    pub levels: usize,
    /// The refined points, row-major.
    pub points: Rows,
    /// The quads as 0-based point indices (i, j), (i, j+1), (i+1, j+1), (i+1, j).
    pub quads: Vec<[usize; 4]>,
}

fn grid_of(solution: &SurfaceSolution) -> Result<QuadGrid, InputError> {
    let pts = validate_rows("points", &solution.points, 4)?;
    QuadGrid::new(
        solution.rows,
        solution.cols,
        pts,
        solution.closed[0],
        solution.closed[1],
    )
    .map_err(|e| InputError::new("points", e))
}

/// The OBJ quad mesh of a result (for `--obj FILE`).
///
/// # Errors
/// An [`InputError`] if the solution is inconsistent (not produced by [`solve`]).
pub fn obj_text(solution: &SurfaceSolution) -> Result<String, InputError> {
    quad_mesh_obj(&grid_of(solution)?).map_err(|e| InputError::new("points", e))
}

/// `curvefit surface`: the tensor-product scheme applied `levels` times to the grid.
///
/// # Errors
/// An [`InputError`] naming the user's field and index.
pub fn solve(problem: &SurfaceProblem) -> Result<SurfaceSolution, InputError> {
    for (field, v) in [("rows", problem.rows), ("cols", problem.cols)] {
        if v < 2 {
            return Err(InputError::new(
                field,
                format!("must be at least 2, got {v}"),
            ));
        }
    }
    let expected = problem
        .rows
        .checked_mul(problem.cols)
        .ok_or_else(|| InputError::new("rows", "rows × cols overflows"))?;
    if problem.points.len() != expected {
        return Err(InputError::new(
            "points",
            format!(
                "has {} points, expected rows × cols = {expected}",
                problem.points.len()
            ),
        ));
    }
    let pts = validate_rows("points", &problem.points, 4)?;
    if !(2..=3).contains(&pts.dim()) {
        return Err(InputError::new(
            "points[0]",
            format!(
                "grid points must be in R^2 or R^3, got dimension {}",
                pts.dim()
            ),
        ));
    }
    let scheme = scheme_from_flags(problem.scheme.points, problem.scheme.arity).map_err(|e| {
        let field = if e.field == "arity" {
            "scheme.arity"
        } else {
            "scheme.points"
        };
        InputError::new(field, e.message)
    })?;
    let n = scheme.arity();
    let grow = |c: usize, closed: bool| -> Option<usize> {
        let mut c = c;
        for _ in 0..problem.levels {
            c = if closed {
                c.checked_mul(n)?
            } else {
                (c - 1).checked_mul(n)?.checked_add(1)?
            };
            if c > MAX_SURFACE_OUTPUT_COORDS {
                return None;
            }
        }
        Some(c)
    };
    let total = grow(problem.rows, problem.closed[0])
        .zip(grow(problem.cols, problem.closed[1]))
        .and_then(|(r, c)| r.checked_mul(c))
        .and_then(|rc| rc.checked_mul(pts.dim()));
    if total.is_none_or(|t| t > MAX_SURFACE_OUTPUT_COORDS) {
        return Err(InputError::new(
            "levels",
            format!(
                "{} levels would exceed {MAX_SURFACE_OUTPUT_COORDS} output coordinates",
                problem.levels
            ),
        ));
    }
    let grid = QuadGrid::new(
        problem.rows,
        problem.cols,
        pts,
        problem.closed[0],
        problem.closed[1],
    )
    .map_err(|e| InputError::new("points", e))?;
    let fine = scheme
        .subdivide_grid(&grid, problem.levels)
        .map_err(|e| match e {
            subdivision::Error::TooLarge { .. } => InputError::new("levels", e),
            // Affine combinations with weights > 1 can overflow for coordinates near the
            // f64 limit.
            _ => InputError::new(
                "points",
                format!("coordinates too large: the refined surface overflows f64 ({e})"),
            ),
        })?;
    Ok(SurfaceSolution {
        rows: fine.rows(),
        cols: fine.cols(),
        closed: problem.closed,
        levels: problem.levels,
        points: Rows(fine.points().clone()),
        quads: fine.quads(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_json(rows: usize, cols: usize, extra: &str) -> String {
        let pts: Vec<String> = (0..rows)
            .flat_map(|i| (0..cols).map(move |j| format!("[{i}, {j}, {}]", (i * j) % 3)))
            .collect();
        format!(
            r#"{{"rows": {rows}, "cols": {cols}, "points": [{}] {extra}}}"#,
            pts.join(",")
        )
    }

    #[test]
    fn surface_follows_the_contract() {
        let p: SurfaceProblem = serde_json::from_str(&grid_json(4, 5, "")).unwrap();
        assert_eq!(
            (p.scheme.points, p.scheme.arity, p.levels, p.closed),
            (4, 2, 1, [false, false])
        );
        let s = solve(&p).unwrap();
        assert_eq!((s.rows, s.cols), (7, 9));
        assert_eq!(s.points.len(), 63);
        assert_eq!(s.quads.len(), 6 * 8);
        let obj = obj_text(&s).unwrap();
        assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 63);
        assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 48);
        let p: SurfaceProblem = serde_json::from_str(&grid_json(
            4,
            4,
            r#", "closed": [true, false], "scheme": {"points": 4, "arity": 3}, "levels": 2"#,
        ))
        .unwrap();
        let s = solve(&p).unwrap();
        assert_eq!((s.rows, s.cols), (36, 28));
    }

    #[test]
    fn bad_input_names_the_field() {
        let solve = |s: &str| match super::super::from_json::<SurfaceProblem>(s) {
            Ok(p) => solve(&p).unwrap_err(),
            Err(e) => e,
        };
        assert_eq!(solve(&grid_json(1, 4, "")).field, "rows");
        let e = solve(r#"{"rows": 2, "cols": 2, "points": [[0,0],[1,0],[0,1]]}"#);
        assert_eq!(e.field, "points");
        let e =
            solve(r#"{"rows": 2, "cols": 2, "points": [[0,0,0,0],[1,0,0,0],[0,1,0,0],[1,1,0,0]]}"#);
        assert_eq!(e.field, "points[0]");
        let e = solve(r#"{"rows": 2, "cols": 2, "points": [[0,0],[1,0],[0,1],[1]]}"#);
        assert_eq!(e.field, "points[3]");
        assert_eq!(
            solve(&grid_json(3, 3, r#", "scheme": {"points": 5}"#)).field,
            "scheme.points"
        );
        assert_eq!(
            solve(&grid_json(3, 3, r#", "scheme": {"arity": 0}"#)).field,
            "scheme.arity"
        );
        assert_eq!(solve(&grid_json(3, 3, r#", "levels": 30"#)).field, "levels");
        let e = solve(
            r#"{"rows": 2, "cols": 3, "points": [[0,0],[1,1e308],[2,-1e308],[0,1],[1,1],[2,1]], "levels": 2}"#,
        );
        assert_eq!(e.field, "points");
        assert!(
            serde_json::from_str::<SurfaceProblem>(&grid_json(2, 2, r#", "bogus": 1"#)).is_err()
        );
    }
}
