//! `curvefit surface`: the subcommand (the JSON contract is
//! [`spec::surface`](mod@crate::spec::surface)), its OBJ mesh and its picture.

use super::super::format::Table;
use crate::plot::{palette, Figure, Style};
use crate::spec::surface::*;
use crate::spec::{InputError, Rows};

/// An isometric projection of a point of R^2 or R^3 (x to the right-down, y to the left-down,
/// z up), for wireframe pictures.
pub fn isometric(p: &[f64]) -> [f64; 2] {
    let (x, y) = (p[0], p[1]);
    let z = p.get(2).copied().unwrap_or(0.0);
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    [(x - y) * c, (x + y) * s + z]
}

/// The `surface` subcommand.
pub enum SurfaceCmd {}

impl super::super::Command for SurfaceCmd {
    type Problem = SurfaceProblem;
    type Solution = SurfaceSolution;

    /// `--points FILE.csv`: the problem's `points`.
    fn set_points(p: &mut SurfaceProblem, csv: super::super::input::Csv) -> Result<(), InputError> {
        super::set_points(&mut p.points, csv)
    }

    /// The refined grid points, row-major (point (i, j) is row i·cols + j).
    fn table(s: &SurfaceSolution) -> Option<Table<'_>> {
        Some(Table {
            columns: Table::point_columns(s.points.dim()),
            data: s.points.coords().into(),
        })
    }

    fn solve(problem: &SurfaceProblem) -> Result<SurfaceSolution, InputError> {
        crate::spec::surface(problem)
    }

    /// The refined grid as an OBJ quad mesh (`--obj`).
    fn obj(_: &SurfaceProblem, solution: &SurfaceSolution) -> Option<Result<String, InputError>> {
        Some(obj_text(solution))
    }

    /// An isometric wireframe of the refined grid over the dashed control net.
    fn svg(problem: &SurfaceProblem, solution: &SurfaceSolution) -> Option<String> {
        let mut fig = Figure::new("Tensor-product subdivision surface (Khan et al. §4)");
        fig.equal_aspect(true).axes(false);
        let lines = |fig: &mut Figure,
                     rows: usize,
                     cols: usize,
                     closed: [bool; 2],
                     pts: &Rows,
                     style: Style| {
            for i in 0..rows {
                let mut line: Vec<[f64; 2]> = (0..cols)
                    .map(|j| isometric(pts.point(i * cols + j)))
                    .collect();
                if closed[1] {
                    line.push(line[0]);
                }
                fig.polyline(&line, style.clone());
            }
            for j in 0..cols {
                let mut line: Vec<[f64; 2]> = (0..rows)
                    .map(|i| isometric(pts.point(i * cols + j)))
                    .collect();
                if closed[0] {
                    line.push(line[0]);
                }
                fig.polyline(&line, style.clone());
            }
        };
        lines(
            &mut fig,
            solution.rows,
            solution.cols,
            solution.closed,
            &solution.points,
            Style::stroke(palette::CURVE, 0.6),
        );
        lines(
            &mut fig,
            problem.rows,
            problem.cols,
            problem.closed,
            &problem.points,
            Style::stroke(palette::SECOND, 1.2).dashed("4 3"),
        );
        fig.legend("refined grid", Style::stroke(palette::CURVE, 0.6));
        fig.legend(
            "control net (interpolated)",
            Style::stroke(palette::SECOND, 1.2).dashed("4 3"),
        );
        fig.caption("isometric view of (x, y, z): no axes");
        fig.caption(&format!(
            "{}-point {}-ary tensor-product scheme, {} level(s): {} × {} grid",
            problem.scheme.points,
            problem.scheme.arity,
            solution.levels,
            solution.rows,
            solution.cols
        ));
        Some(fig.to_svg())
    }
}
