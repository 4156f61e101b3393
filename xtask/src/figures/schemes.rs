//! Figures for the uniform schemes: Khan et al. Fig. 3 (ternary 4- and 6-point curves, levels
//! 1–3) and Fig. 4 (tensor-product 4-point surface), and Warren–Weimer Fig. 6.5 (the natural
//! cubic basis on [0, 4]), Fig. 6.6 (parametric subdivision progression), Fig. 6.7 (interpolation
//! through N⁻¹), plus the energies p_kᵀE_kp_k converging to p_0ᵀE_0N_0p_0.

use std::path::Path;

use curvefit::plot::{palette, Figure, Marker, Style};
use divdiff::{Points, Topology};
use subdivision::{NaryScheme, NaturalScheme, QuadGrid};

use super::save;

fn xy(p: &Points) -> Vec<[f64; 2]> {
    p.iter().map(|q| [q[0], q[1]]).collect()
}

/// The control polygon of Khan et al. Fig. 3 is not printed; a closed hexagon-like polygon with
/// one sharp corner shows the same behaviour (interpolation, smoothing, overshoot near the corner).
fn khan_polygon() -> anyhow::Result<Points> {
    Ok(Points::from_rows(&[
        [0.0, 0.0],
        [2.0, -0.6],
        [4.0, 0.0],
        [4.4, 2.0],
        [3.0, 3.6],
        [2.0, 1.6],
        [1.0, 3.6],
        [-0.4, 2.0],
    ])?)
}

fn khan_curves(dir: &Path, points: usize, name: &str) -> anyhow::Result<()> {
    let s = NaryScheme::new(points, 3)?;
    let p0 = khan_polygon()?;
    let colors = [palette::THIRD, palette::SECOND, palette::CURVE];
    let mut fig = Figure::new(&format!(
        "Khan et al. Fig. 3: ternary {points}-point scheme, levels 1-3"
    ));
    fig.polygon(&xy(&p0), Style::stroke(palette::REGION, 1.0).dashed("4 3"))
        .legend(
            "control polygon",
            Style::stroke(palette::REGION, 1.0).dashed("4 3"),
        );
    for (k, color) in (1..=3).zip(colors) {
        let pk = s.subdivide(&p0, Topology::Closed, k)?;
        fig.polygon(
            &xy(&pk),
            Style::stroke(color, if k == 3 { 1.8 } else { 1.0 }),
        )
        .legend(
            &format!("level {k} ({} points)", pk.len()),
            Style::stroke(color, 1.5),
        );
    }
    fig.points(&xy(&p0), Marker::Dot, Style::fill(palette::DATA));
    let w: Vec<String> = s.exact_rule(1).iter().map(|q| q.to_string()).collect();
    fig.caption(&format!(
        "rule a = 1: ({}); a = 2 is its mirror; old points are kept",
        w.join(", ")
    ));
    save(dir, name, &fig.to_svg())
}

fn khan_members_open(dir: &Path) -> anyhow::Result<()> {
    let p0 = Points::from_rows(&[
        [0.0, 0.0],
        [1.0, 2.0],
        [2.0, 0.5],
        [3.0, 2.5],
        [4.0, 0.0],
        [5.0, 1.5],
        [6.0, 1.0],
    ])?;
    let mut fig = Figure::new("(2m+2)-point n-ary members on an open polygon (4 levels)");
    fig.polyline(&xy(&p0), Style::stroke(palette::REGION, 1.0).dashed("4 3"));
    fig.points(&xy(&p0), Marker::Dot, Style::fill(palette::DATA));
    for ((points, arity, levels), color) in [(2, 2, 4), (4, 2, 4), (6, 2, 4), (4, 3, 3)]
        .into_iter()
        .zip([
            palette::REGION,
            palette::CURVE,
            palette::SECOND,
            palette::THIRD,
        ])
    {
        let s = NaryScheme::new(points, arity)?;
        let pk = s.subdivide(&p0, Topology::Open, levels)?;
        let label = format!("{points}-point, arity {arity}, {levels} levels");
        fig.polyline(&xy(&pk), Style::stroke(color, 1.4))
            .legend(&label, Style::stroke(color, 1.4));
    }
    fig.caption(
        "open ends: one-sided stencils of the same width (degree 2m+1 reproduced up to the ends)",
    );
    save(dir, "khan_members_open.svg", &fig.to_svg())
}

/// Isometric projection (x right-down, y left-down, z up).
fn iso(p: &[f64]) -> [f64; 2] {
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    [(p[0] - p[1]) * c, (p[0] + p[1]) * s + p[2]]
}

fn wire(fig: &mut Figure, g: &QuadGrid, style: Style) {
    for i in 0..g.rows() {
        let line: Vec<[f64; 2]> = (0..g.cols()).map(|j| iso(g.point(i, j))).collect();
        fig.polyline(&line, style.clone());
    }
    for j in 0..g.cols() {
        let line: Vec<[f64; 2]> = (0..g.rows()).map(|i| iso(g.point(i, j))).collect();
        fig.polyline(&line, style.clone());
    }
}

fn khan_surface(dir: &Path) -> anyhow::Result<()> {
    // A 6 × 6 height field with a raised middle and one spike, open in both directions
    // (Khan et al. Fig. 4 uses the tensor-product 4-point binary scheme).
    let (rows, cols) = (6, 6);
    let mut pts = Vec::new();
    for i in 0..rows {
        for j in 0..cols {
            let (x, y) = (i as f64, j as f64);
            let mut z = if (2..=3).contains(&i) && (2..=3).contains(&j) {
                1.6
            } else {
                0.0
            };
            if (i, j) == (1, 4) {
                z = 1.0;
            }
            pts.push([x, y, z]);
        }
    }
    let g0 = QuadGrid::new(rows, cols, Points::from_rows(&pts)?, false, false)?;
    let s = NaryScheme::new(4, 2)?;
    for (levels, name) in [
        (1, "khan_fig4_surface_level1.svg"),
        (3, "khan_fig4_surface_level3.svg"),
    ] {
        let g = s.subdivide_grid(&g0, levels)?;
        let mut fig = Figure::new(&format!(
            "Khan et al. Fig. 4: tensor-product 4-point binary surface, level {levels}"
        ));
        fig.axes(false);
        wire(
            &mut fig,
            &g,
            Style::stroke(palette::CURVE, if levels == 1 { 0.9 } else { 0.5 }),
        );
        wire(
            &mut fig,
            &g0,
            Style::stroke(palette::SECOND, 1.3).dashed("4 3"),
        );
        let pts0: Vec<[f64; 2]> = g0.points().iter().map(iso).collect();
        fig.points(&pts0, Marker::Dot, Style::fill(palette::DATA));
        fig.caption(&format!(
            "{} x {} control net (dashed) -> {} x {} points (isometric view); the net's points are interpolated",
            g0.rows(), g0.cols(), g.rows(), g.cols()
        ));
        save(dir, name, &fig.to_svg())?;
    }
    Ok(())
}

fn ww_basis(dir: &Path, scheme: &NaturalScheme) -> anyhow::Result<()> {
    let mut fig = Figure::new("Warren-Weimer Fig. 6.5: natural cubic basis functions on [0, 4]");
    fig.equal_aspect(false);
    let colors = [
        palette::CURVE,
        palette::SECOND,
        palette::THIRD,
        palette::ACTIVE,
        palette::DATA,
    ];
    for (i, color) in colors.iter().enumerate() {
        let e: Vec<[f64; 1]> = (0..5).map(|j| [if j == i { 1.0 } else { 0.0 }]).collect();
        let levels = scheme.subdivide_levels(&Points::from_rows(&e)?, 6)?;
        let pts: Vec<[f64; 2]> = levels[6]
            .iter()
            .enumerate()
            .map(|(k, v)| [k as f64 / 64.0, v[0]])
            .collect();
        fig.polyline(&pts, Style::stroke(color, 1.6));
    }
    fig.caption("limits of e_0..e_4 after 6 levels; the middle one is the uniform cubic B-spline");
    save(dir, "ww_fig6_5_basis.svg", &fig.to_svg())
}

/// A control polygon in the spirit of Fig. 6.6 (coordinates not printed in the seed).
fn ww_polygon() -> anyhow::Result<Points> {
    Ok(Points::from_rows(&[
        [0.1, 0.1],
        [0.2, 0.8],
        [0.5, 0.9],
        [0.45, 0.4],
        [0.8, 0.3],
        [0.9, 0.8],
    ])?)
}

fn ww_progression(dir: &Path, scheme: &NaturalScheme) -> anyhow::Result<()> {
    let p0 = ww_polygon()?;
    let levels = scheme.subdivide_levels(&p0, 3)?;
    let mut fig =
        Figure::new("Warren-Weimer Fig. 6.6: natural cubic subdivision, applied parametrically");
    fig.polyline(&xy(&p0), Style::stroke(palette::REGION, 1.0).dashed("4 3"));
    fig.points(&xy(&p0), Marker::Ring, Style::stroke(palette::DATA, 1.2));
    for (k, color) in [
        (1, palette::THIRD),
        (2, palette::SECOND),
        (3, palette::CURVE),
    ] {
        fig.polyline(&xy(&levels[k]), Style::stroke(color, 1.0 + 0.3 * k as f64))
            .legend(
                &format!("p_{k}: energy {:.3}", NaturalScheme::energy(&levels[k], k)),
                Style::stroke(color, 1.5),
            );
        fig.points_sized(
            &xy(&levels[k]),
            Marker::Dot,
            2.0 + 0.0 * k as f64,
            Style::fill(color),
        );
    }
    fig.caption(&format!(
        "p_0 energy {:.3}; exact limit energy p0ᵀE0N0p0 = {:.4}; end points interpolated",
        NaturalScheme::energy(&p0, 0),
        scheme.limit_energy(&p0)?
    ));
    save(dir, "ww_fig6_6_progression.svg", &fig.to_svg())
}

fn ww_interpolation(dir: &Path, scheme: &NaturalScheme) -> anyhow::Result<()> {
    let b = ww_polygon()?;
    let p0 = scheme.interpolate(&b)?;
    let limit = scheme
        .subdivide_levels(&p0, 4)?
        .pop()
        .ok_or_else(|| anyhow::anyhow!("no level"))?;
    let mut fig = Figure::new("Warren-Weimer Fig. 6.7: interpolation through N^-1");
    fig.polyline(&xy(&b), Style::stroke(palette::REGION, 1.0).dashed("4 3"))
        .legend(
            "points b",
            Style::stroke(palette::REGION, 1.0).dashed("4 3"),
        );
    fig.polyline(&xy(&p0), Style::stroke(palette::SECOND, 1.0))
        .legend(
            "control polygon p0 = N^-1 b",
            Style::stroke(palette::SECOND, 1.0),
        );
    fig.points(&xy(&p0), Marker::Square, Style::fill(palette::SECOND));
    fig.polyline(&xy(&limit), Style::stroke(palette::CURVE, 1.8))
        .legend(
            "4 rounds of subdivision",
            Style::stroke(palette::CURVE, 1.8),
        );
    fig.points(&xy(&b), Marker::Dot, Style::fill(palette::DATA));
    fig.caption("the curve passes through b at the integer parameters");
    save(dir, "ww_fig6_7_interpolation.svg", &fig.to_svg())
}

fn ww_energies(dir: &Path, scheme: &NaturalScheme) -> anyhow::Result<()> {
    let p0 = ww_polygon()?;
    let levels = scheme.subdivide_levels(&p0, 8)?;
    let exact = scheme.limit_energy(&p0)?;
    let e: Vec<[f64; 2]> = levels
        .iter()
        .enumerate()
        .map(|(k, p)| [k as f64, NaturalScheme::energy(p, k)])
        .collect();
    let mut fig = Figure::new("Energies p_kᵀE_kp_k decrease to p0ᵀE0N0p0 (Theorem 6.4)");
    fig.equal_aspect(false);
    fig.segment(
        [0.0, exact],
        [8.0, exact],
        Style::stroke(palette::ACTIVE, 1.0).dashed("5 3"),
    )
    .legend(
        &format!("exact limit {exact:.5}"),
        Style::stroke(palette::ACTIVE, 1.0).dashed("5 3"),
    );
    fig.polyline(&e, Style::stroke(palette::CURVE, 1.5))
        .legend("p_kᵀE_kp_k, k = 0..8", Style::stroke(palette::CURVE, 1.5));
    fig.points(&e, Marker::Dot, Style::fill(palette::CURVE));
    fig.caption(&format!(
        "gap ratios (E_k - E)/(E_k+1 - E): {:.3}, {:.3}, {:.3} (error O(4^-k))",
        (e[0][1] - exact) / (e[1][1] - exact),
        (e[1][1] - exact) / (e[2][1] - exact),
        (e[2][1] - exact) / (e[3][1] - exact)
    ));
    save(dir, "ww_energies.svg", &fig.to_svg())
}

/// Draws this area's figures into `dir`.
pub fn draw(dir: &Path) -> anyhow::Result<()> {
    khan_curves(dir, 4, "khan_fig3_ternary4.svg")?;
    khan_curves(dir, 6, "khan_fig3_ternary6.svg")?;
    khan_members_open(dir)?;
    khan_surface(dir)?;
    let scheme = NaturalScheme::new()?;
    ww_basis(dir, &scheme)?;
    ww_progression(dir, &scheme)?;
    ww_interpolation(dir, &scheme)?;
    ww_energies(dir, &scheme)?;
    Ok(())
}
