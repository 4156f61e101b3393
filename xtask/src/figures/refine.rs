//! Figures for `refine`: Kersey's Figs. 1.1, 3.1, 3.2, 3.3 and 3.9, redrawn with data chosen to
//! resemble them. Several panels of one figure are drawn side by side in one SVG, each shifted
//! along x.

use std::path::Path;

use curvefit::plot::{palette, Figure, Marker, Style};
use divdiff::{Parametrization, Points, Topology};
use refine::{Constraint, Problem, Refinement, Solver};

fn xy(p: &Points) -> Vec<[f64; 2]> {
    p.iter().map(|v| [v[0], v[1]]).collect()
}

fn shift(pts: &[[f64; 2]], dx: f64) -> Vec<[f64; 2]> {
    pts.iter().map(|p| [p[0] + dx, p[1]]).collect()
}

/// Draws a refined curve (closed or open) shifted by `dx`.
fn curve(fig: &mut Figure, r: &Refinement, closed: bool, dx: f64, color: &str) {
    let pts = shift(&xy(&r.points), dx);
    if closed {
        fig.polygon(&pts, Style::stroke(color, 1.6));
    } else {
        fig.polyline(&pts, Style::stroke(color, 1.6));
    }
}

fn data_points(fig: &mut Figure, q: &Points, dx: f64) {
    fig.points(&shift(&xy(q), dx), Marker::Dot, Style::fill(palette::DATA));
}

/// Balls drawn grey when inactive, red when active; the data vertex marked by a star.
fn balls(fig: &mut Figure, q: &Points, radii: &[f64], r: &Refinement, dx: f64) {
    for (i, c) in xy(q).iter().enumerate() {
        let color = if r.active[i] {
            palette::ACTIVE
        } else {
            palette::REGION
        };
        if radii[i] > 0.0 {
            fig.circle([c[0] + dx, c[1]], radii[i], Style::stroke(color, 1.0));
        }
        let v = r.points.point(r.data_vertex[i]);
        fig.points(&[[v[0] + dx, v[1]]], Marker::Star, Style::fill(color));
    }
}

/// Solves with the exact solver, falling back to the paper's iteration if the exact solver
/// does not handle the problem in this build; returns which one ran.
fn solve(problem: Problem) -> anyhow::Result<(Refinement, &'static str)> {
    match problem.solve() {
        Ok(r) => Ok((r, "exact")),
        Err(refine::Error::Unsupported { .. }) => Ok((
            problem.with_solver(Solver::Paper).solve()?,
            "paper iteration",
        )),
        Err(e) => Err(e.into()),
    }
}

fn star(n_tips: usize, outer: f64, inner: f64) -> Points {
    let mut rows = Vec::new();
    for i in 0..2 * n_tips {
        let th = std::f64::consts::PI / 2.0 + std::f64::consts::PI * i as f64 / n_tips as f64;
        let r = if i % 2 == 0 { outer } else { inner };
        rows.push(vec![r * th.cos(), r * th.sin()]);
    }
    Points::from_rows(&rows).expect("finite")
}

/// Draws this area's figures into `dir`.
pub fn draw(dir: &Path) -> anyhow::Result<()> {
    // Fig. 1.1: uniform vs non-uniform (centripetal) parametrization of unevenly spaced data.
    let q = Points::from_rows(&[
        [0.0, 0.0],
        [0.3, 0.05],
        [4.0, 0.0],
        [4.2, 1.5],
        [2.0, 2.2],
        [0.1, 1.6],
    ])?;
    let mut fig = Figure::new("Fig. 1.1: uniform (left) vs centripetal (right) parametrization");
    for (j, (param, name)) in [
        (Parametrization::Uniform, "uniform"),
        (Parametrization::Centripetal, "centripetal"),
    ]
    .into_iter()
    .enumerate()
    {
        let dx = 6.0 * j as f64;
        let r = Problem::new(q.clone())
            .with_parametrization(param)
            .with_k(7)
            .with_levels(2, 1)
            .solve()?;
        fig.polygon(
            &shift(&xy(&q), dx),
            Style::stroke(palette::REGION, 0.8).dashed("3 3"),
        );
        curve(&mut fig, &r, true, dx, palette::CURVE);
        data_points(&mut fig, &q, dx);
        fig.caption(&format!(
            "{name}: E = {:.4} on its own knots (k = 7, two further levels)",
            r.energy
        ));
    }
    super::save(dir, "kersey_fig1_1_parametrization.svg", &fig.to_svg())?;

    // Fig. 3.1: interpolatory subdivision: data, one k-level step, several levels.
    let q = Points::from_rows(&[
        [0.0, 0.0],
        [2.0, -0.3],
        [3.0, 1.0],
        [2.2, 2.4],
        [0.6, 2.0],
        [-0.6, 1.0],
    ])?;
    let mut fig = Figure::new("Fig. 3.1: interpolatory subdivision");
    fig.polygon(&xy(&q), Style::stroke(palette::REGION, 1.2));
    data_points(&mut fig, &q, 0.0);
    let one = Problem::new(q.clone()).with_k(1).solve()?;
    let many = Problem::new(q.clone())
        .with_k(1)
        .with_levels(4, 1)
        .solve()?;
    for (r, dx) in [(&one, 4.5), (&many, 9.0)] {
        fig.polygon(
            &shift(&xy(&r.points), dx),
            Style::stroke(palette::CURVE, 1.4),
        );
        fig.points(
            &shift(&xy(&r.points), dx),
            Marker::Dot,
            Style::fill(palette::CURVE),
        );
        data_points(&mut fig, &q, dx);
    }
    fig.caption("left: data; middle: one k = 1 step; right: four more levels");
    fig.caption(&format!(
        "middle: {} vertices, E = {:.4}; right: {} vertices, E = {:.4}",
        one.points.len(),
        one.energy,
        many.points.len(),
        many.energy
    ));
    super::save(dir, "kersey_fig3_1_interpolatory.svg", &fig.to_svg())?;

    // Fig. 3.2: near-interpolation to random balls; active (on the boundary) vs inactive.
    let mut s: u64 = 7;
    let mut rnd = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let n = 9;
    let mut rows = Vec::new();
    let mut radii = Vec::new();
    for i in 0..n {
        let th = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        let r = 2.0 + 0.8 * (rnd() - 0.5);
        rows.push(vec![1.3 * r * th.cos(), r * th.sin()]);
        radii.push(0.1 + 0.5 * rnd());
    }
    let q = Points::from_rows(&rows)?;
    let (r, which) = solve(
        Problem::new(q.clone())
            .with_k(7)
            .with_levels(2, 1)
            .with_constraint(Constraint::Balls(radii.clone())),
    )?;
    let mut fig = Figure::new("Fig. 3.2: near-interpolation to balls (random radii)");
    curve(&mut fig, &r, true, 0.0, palette::CURVE);
    balls(&mut fig, &q, &radii, &r, 0.0);
    data_points(&mut fig, &q, 0.0);
    let n_active = r.active.iter().filter(|&&a| a).count();
    fig.caption(&format!(
        "{which} solver, k = 7 + two levels: {n_active} of {n} balls active (red), E = {:.4}",
        r.energy
    ));
    fig.caption(&format!(
        "KKT residual of the ball step {:.1e}",
        r.stages[0].kkt_residual
    ));
    if let Some(j) = r.jmp_inactive() {
        fig.caption(&format!(
            "Corollary 3.3: max relative |jmp| at inactive data vertices = {j:.1e}"
        ));
    }
    super::save(dir, "kersey_fig3_2_balls.svg", &fig.to_svg())?;

    // Fig. 3.3: a star, tolerances shrinking to interpolation (cusps and loops appear).
    let q = star(5, 2.0, 0.8);
    let mut fig = Figure::new("Fig. 3.3: star, tolerances shrinking to interpolation");
    for (j, eps) in [0.6, 0.3, 0.1, 0.0].into_iter().enumerate() {
        let dx = 5.0 * j as f64;
        let radii = vec![eps; q.len()];
        let (r, which) = solve(
            Problem::new(q.clone())
                .with_k(7)
                .with_levels(1, 1)
                .with_constraint(Constraint::Balls(radii.clone())),
        )?;
        curve(&mut fig, &r, true, dx, palette::CURVE);
        if eps > 0.0 {
            for c in xy(&q) {
                fig.circle([c[0] + dx, c[1]], eps, Style::stroke(palette::REGION, 0.6));
            }
        }
        data_points(&mut fig, &q, dx);
        fig.caption(&format!(
            "panel {}: radius {eps}, E = {:.3} ({which})",
            j + 1,
            r.energy
        ));
    }
    super::save(dir, "kersey_fig3_3_star.svg", &fig.to_svg())?;

    // Fig. 3.9: open curves, natural ends: tolerances decreased left to right, then increased at
    // two points to reduce the overshoot.
    let q = Points::from_rows(&[
        [0.0, 0.0],
        [1.0, 1.6],
        [2.0, 1.7],
        [3.0, 0.1],
        [4.0, 0.0],
        [5.0, 1.5],
        [6.0, 1.6],
    ])?;
    let n = q.len();
    let mut fig = Figure::new("Fig. 3.9: open curves, natural ends");
    let mut relaxed = vec![0.05; n];
    relaxed[2] = 0.4;
    relaxed[3] = 0.4;
    for (j, radii) in [vec![0.5; n], vec![0.2; n], vec![0.05; n], relaxed]
        .into_iter()
        .enumerate()
    {
        let dy = -2.6 * j as f64;
        let (r, which) = solve(
            Problem::new(q.clone())
                .with_topology(Topology::Open)
                .with_k(7)
                .with_levels(1, 1)
                .with_constraint(Constraint::Balls(radii.clone())),
        )?;
        let up = |p: &[[f64; 2]]| p.iter().map(|v| [v[0], v[1] + dy]).collect::<Vec<_>>();
        fig.polyline(&up(&xy(&r.points)), Style::stroke(palette::CURVE, 1.6));
        for (i, c) in xy(&q).iter().enumerate() {
            let color = if r.active[i] {
                palette::ACTIVE
            } else {
                palette::REGION
            };
            fig.circle([c[0], c[1] + dy], radii[i], Style::stroke(color, 0.8));
        }
        fig.points(&up(&xy(&q)), Marker::Dot, Style::fill(palette::DATA));
        fig.caption(&format!(
            "row {}: radii {}, E = {:.3} ({which})",
            j + 1,
            ["0.5", "0.2", "0.05", "0.05 except 0.4 at two points"][j],
            r.energy
        ));
    }
    super::save(dir, "kersey_fig3_9_open.svg", &fig.to_svg())?;
    Ok(())
}

// ---- Free knots (issue 4 item 4) --------------------------------------------------------------

/// Ticks of a knot vector on a parameter axis drawn at height `y` from x = `x0` over `width`:
/// tall ticks at the data knots (every `stride`-th), short ones at the refined knots.
fn knot_ticks(
    fig: &mut Figure,
    t: &[f64],
    stride: usize,
    x0: f64,
    width: f64,
    y: f64,
    color: &str,
) {
    let (a, b) = (t[0], t[t.len() - 1]);
    let x = |v: f64| x0 + width * (v - a) / (b - a);
    fig.segment(
        [x0, y],
        [x0 + width, y],
        Style::stroke(palette::REGION, 0.8),
    );
    for (j, &v) in t.iter().enumerate() {
        let h = if j % stride == 0 { 0.22 } else { 0.09 };
        fig.segment([x(v), y - h], [x(v), y + h], Style::stroke(color, 1.2));
    }
}

/// Centripetal vs optimal free knots (`refine::optimize_knots`) on the same data.
pub fn draw_free_knots(dir: &Path) -> anyhow::Result<()> {
    let q = Points::from_rows(&[
        [0.0, 0.0],
        [0.2, 0.0],
        [3.0, 1.0],
        [3.2, 1.0],
        [6.0, 0.0],
        [6.1, 0.05],
        [9.0, 1.0],
    ])?;
    let problem = Problem::new(q.clone()).with_topology(Topology::Open);
    let r = refine::optimize_knots(&problem, &refine::FreeKnotOptions::default())?;
    let stride = problem.k + 1;
    let mut fig = Figure::new("Centripetal vs optimal free knots (open interpolation, k = 3)");
    fig.size(760.0, 520.0);
    fig.polyline(&xy(&r.start.points), Style::stroke(palette::SECOND, 1.6));
    fig.polyline(&xy(&r.points), Style::stroke(palette::CURVE, 1.6));
    fig.points_sized(
        &xy(&r.start.points),
        Marker::Dot,
        2.5,
        Style::fill(palette::SECOND),
    );
    fig.points_sized(
        &xy(&r.points),
        Marker::Dot,
        2.5,
        Style::fill(palette::CURVE),
    );
    data_points(&mut fig, &q, 0.0);
    fig.legend("centripetal knots", Style::stroke(palette::SECOND, 1.6));
    fig.legend("optimal free knots", Style::stroke(palette::CURVE, 1.6));
    // The two knot vectors on parameter axes below the curves (same total length T).
    knot_ticks(
        &mut fig,
        r.start.knots.values(),
        stride,
        0.0,
        9.0,
        -1.0,
        palette::SECOND,
    );
    knot_ticks(
        &mut fig,
        r.knots.values(),
        stride,
        0.0,
        9.0,
        -1.7,
        palette::CURVE,
    );
    fig.label([0.0, -0.62], "centripetal knots t", palette::SECOND);
    fig.label([0.0, -1.32], "optimal knots t (same T)", palette::CURVE);
    fig.caption(&format!(
        "E = {:.4} on centripetal knots, E = {:.4} on optimal free knots ({:.0}% lower), T = {:.3}",
        r.before.energy,
        r.after.energy,
        100.0 * (1.0 - r.after.energy / r.before.energy),
        r.total_length
    ));
    fig.caption(&format!(
        "max |dE/dt_i|/(3E/T): {:.1e} -> {:.1e}; max |Df·(Hp)_i|/(3E/T): {:.2} -> {:.2}; {} L-BFGS iterations",
        r.before.vertex_knot_residual,
        r.after.vertex_knot_residual,
        r.before.orthogonality_max,
        r.after.orthogonality_max,
        r.iterations
    ));
    super::save(dir, "kersey_free_knots.svg", &fig.to_svg())?;
    Ok(())
}
