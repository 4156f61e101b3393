//! `curvefit natural`: the subcommand (the JSON contract is
//! [`spec::natural`](mod@crate::spec::natural)) and its picture.

use super::super::format::Table;
use crate::plot::{palette, Figure, Marker, Style};
use crate::spec::natural::*;
use crate::spec::{InputError, Rows};

/// The `natural` subcommand.
pub enum NaturalCmd {}

impl super::super::Command for NaturalCmd {
    type Problem = NaturalProblem;
    type Solution = NaturalSolution;

    /// `--points FILE.csv`: the problem's `points`.
    fn set_points(p: &mut NaturalProblem, csv: super::super::input::Csv) -> Result<(), InputError> {
        super::set_points(&mut p.points, csv)
    }

    /// The last level's points.
    fn table(s: &NaturalSolution) -> Option<Table<'_>> {
        let last = s.levels.last()?;
        Some(Table {
            columns: Table::point_columns(last.points.dim()),
            data: last.points.coords().into(),
        })
    }

    fn solve(problem: &NaturalProblem) -> Result<NaturalSolution, InputError> {
        crate::spec::natural(problem)
    }

    /// The control polygon p_0 and the last level; for d = 1 the graph over [0, L], for d ≥ 2
    /// the first two coordinates (parametric, as in Fig. 6.6).
    fn svg(problem: &NaturalProblem, solution: &NaturalSolution) -> Option<String> {
        let project = |rows: &Rows, scale: f64| -> Vec<[f64; 2]> {
            rows.iter()
                .enumerate()
                .map(|(i, r)| {
                    if r.len() == 1 {
                        [i as f64 * scale, r[0]]
                    } else {
                        [r[0], r[1]]
                    }
                })
                .collect()
        };
        let last = solution.levels.last()?;
        let k = last.level;
        let mut fig = Figure::new("Natural cubic subdivision (Warren–Weimer §6.2)");
        fig.equal_aspect(problem.points.dim() >= 2);
        if problem.points.dim() >= 2 {
            fig.axis_labels("x", "y");
        } else {
            fig.axis_labels("t (grid 0, 1, …, L)", "value");
        }
        fig.polyline(
            &project(&problem.points, 1.0),
            Style::stroke(palette::REGION, 1.0).dashed("4 3"),
        );
        fig.points(
            &project(&problem.points, 1.0),
            Marker::Ring,
            Style::stroke(palette::DATA, 1.2),
        );
        fig.polyline(
            &project(&last.points, 1.0 / (1u64 << k.min(60)) as f64),
            Style::stroke(palette::CURVE, 1.8),
        );
        fig.legend(
            "control polygon",
            Style::stroke(palette::REGION, 1.0).dashed("4 3"),
        );
        fig.legend_marker(
            "control point",
            Marker::Ring,
            5.0,
            Style::stroke(palette::DATA, 1.2),
        );
        fig.legend(
            &format!("level {k} (→ natural cubic spline)"),
            Style::stroke(palette::CURVE, 1.8),
        );
        fig.caption(
            "The points are control points of an approximating scheme: the curve passes through the two end points only.",
        );
        fig.caption_fields(&[
            (
                &format!("energy at level {k}") as &str,
                format!("{:.6}", last.energy),
            ),
            (
                "exact limit energy p0ᵀE0N0p0",
                format!("{:.6}", solution.limit_energy),
            ),
        ]);
        Some(fig.to_svg())
    }
}
