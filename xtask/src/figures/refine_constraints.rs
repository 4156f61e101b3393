//! Figures for the constraint kinds of Kersey §3.4–3.6 (issue 4), drawn with the command line's
//! own picture of a refinement (`curvefit::cli::refine::picture`) so what `cargo xtask figures`
//! shows is exactly what `curvefit refine --svg` draws: Fig. 3.4 (convex polygons: corner, edge
//! and interior contacts), Figs. 3.6–3.8 (tangent balls, wedges and tension with shrinking
//! tolerances) and Fig. 3.9 (open curves, clamped and near-clamped ends).

use std::path::Path;

use curvefit::cli::refine::{picture, RefineCmd};
use curvefit::cli::refine_types::RefineProblem;
use curvefit::cli::Command;
use serde_json::json;

fn draw_one(dir: &Path, name: &str, problem: serde_json::Value) -> anyhow::Result<()> {
    let p: RefineProblem = serde_json::from_value(problem)?;
    let r = RefineCmd::solve(&p).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    anyhow::ensure!(
        r.kkt_residual <= 1e-8,
        "{name}: certificate {:.1e}",
        r.kkt_residual
    );
    super::save(dir, name, &picture(&p, &r))
}

/// The four data points of Figs. 3.6–3.8 (a rounded diamond), closed, with small position balls.
fn diamond() -> serde_json::Value {
    json!([[0.0, 0.0], [2.0, -1.0], [4.0, 0.0], [2.0, 1.0]])
}

pub fn draw(dir: &Path) -> anyhow::Result<()> {
    // Fig. 3.4: each point confined to a polygon; contacts at corners, edges, or none.
    let centers = [
        [0.0, 0.0],
        [3.0, -0.5],
        [5.0, 1.5],
        [4.0, 4.0],
        [1.0, 4.5],
        [-1.5, 2.5],
    ];
    let sets: Vec<serde_json::Value> = centers
        .iter()
        .enumerate()
        .map(|(i, &[x, y])| {
            let w = if i == 2 { 1.2 } else { 0.5 }; // one large square: an interior (inactive) point
            json!([
                {"normal": [1, 0], "offset": x + w}, {"normal": [-1, 0], "offset": -(x - w)},
                {"normal": [0, 1], "offset": y + w}, {"normal": [0, -1], "offset": -(y - w)},
                {"normal": [1, 1], "offset": x + y + 0.8 * w}
            ])
        })
        .collect();
    draw_one(
        dir,
        "kersey_fig3_4_convex_polygons.svg",
        json!({"points": centers, "closed": true, "k": 3, "constraint": {"type": "halfspaces", "sets": sets}}),
    )?;
    // Figs. 3.6–3.8: tangent balls about horizontal/vertical vectors, direction wedges, tension;
    // tolerances shrink from left (a) to right (c).
    let dirs = [[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]];
    for (tag, tol) in [("a", 1.0), ("b", 0.3), ("c", 0.05)] {
        let balls: Vec<_> = dirs
            .iter()
            .map(|v| json!({"type": "ball", "center": [3.0 * v[0], 3.0 * v[1]], "radius": tol}))
            .collect();
        draw_one(
            dir,
            &format!("kersey_fig3_6{tag}_tangent_balls.svg"),
            json!({"points": diamond(), "closed": true, "k": 6, "constraint": {"type": "balls", "radii": [0.05, 0.05, 0.05, 0.05]}, "tangents": balls}),
        )?;
        let wedges: Vec<_> = dirs
            .iter()
            .map(|v| {
                let (c, s) = (0.6f64.cos(), 0.6f64.sin());
                json!({"type": "wedge", "direction": [c * v[0] - s * v[1], s * v[0] + c * v[1]], "half_angle": 0.5 * tol})
            })
            .collect();
        draw_one(
            dir,
            &format!("kersey_fig3_7{tag}_tangent_wedges.svg"),
            json!({"points": diamond(), "closed": true, "k": 6, "constraint": {"type": "balls", "radii": [0.05, 0.05, 0.05, 0.05]}, "tangents": wedges}),
        )?;
        let tension: Vec<_> = (0..4)
            .map(|_| json!({"type": "tension", "radius": 2.0 * tol}))
            .collect();
        draw_one(
            dir,
            &format!("kersey_fig3_8{tag}_tension.svg"),
            json!({"points": diamond(), "closed": true, "k": 6, "constraint": {"type": "balls", "radii": [0.05, 0.05, 0.05, 0.05]}, "tangents": tension}),
        )?;
    }
    draw_slots(dir)?;
    // Fig. 3.9: open curves with clamped and near-clamped ends.
    let open = json!([
        [0.0, 0.0],
        [1.0, 1.2],
        [2.0, 1.4],
        [3.0, 0.2],
        [4.0, -0.4],
        [5.0, 0.6],
        [6.0, 2.0]
    ]);
    draw_one(
        dir,
        "kersey_fig3_9_clamped.svg",
        json!({"points": open, "closed": false, "k": 3, "boundary": {"type": "clamped", "start": [0, 3], "end": [0, 3]}}),
    )?;
    draw_one(
        dir,
        "kersey_fig3_9_near_clamped.svg",
        json!({"points": open, "closed": false, "k": 3,
               "constraint": {"type": "balls", "radii": [0, 0.1, 0.1, 0.4, 0.1, 0.4, 0]},
               "boundary": {"type": "near_clamped", "start": [0, 3], "end": [0, 3], "radius": 1.0}}),
    )?;
    Ok(())
}

/// Fig. 4.1: the paper's slot construction. For the triangle of one data point, each edge's slot
/// (the band of width 2ε between the edge and the parallel line through the opposite vertex) is
/// drawn; the slots intersect in the triangle. The curve is the paper's slot iteration
/// (`"solver": "paper"`), and the caption compares its energy with the exact optimum.
fn draw_slots(dir: &Path) -> anyhow::Result<()> {
    use curvefit::plot::{palette, Figure, Marker, Style};
    let c = [
        [0.0, 0.0],
        [3.0, -0.5],
        [5.0, 1.5],
        [4.0, 4.0],
        [1.0, 4.5],
        [-1.5, 2.5],
    ];
    let tri = |x: f64, y: f64, r: f64| -> Vec<serde_json::Value> {
        (0..3)
            .map(|k| {
                let a = std::f64::consts::FRAC_PI_2 + 2.0 * std::f64::consts::PI * k as f64 / 3.0;
                json!({"normal": [a.cos(), a.sin()], "offset": a.cos() * x + a.sin() * y + r})
            })
            .collect()
    };
    let sets: Vec<_> = c.iter().map(|&[x, y]| tri(x, y, 0.6)).collect();
    let base = json!({"points": c, "closed": true, "k": 3, "constraint": {"type": "halfspaces", "sets": sets}});
    let mut paper = base.clone();
    paper["solver"] = json!("paper");
    let pp: RefineProblem = serde_json::from_value(paper)?;
    let pe: RefineProblem = serde_json::from_value(base)?;
    let rp = RefineCmd::solve(&pp).map_err(|e| anyhow::anyhow!("slots: {e}"))?;
    let re = RefineCmd::solve(&pe).map_err(|e| anyhow::anyhow!("slots: {e}"))?;
    let mut fig =
        Figure::new("Kersey Fig. 4.1: slots of width 2ε whose intersection is the triangle");
    let (x, y) = (c[1][0], c[1][1]);
    let set: Vec<refine::HalfSpace> = tri(x, y, 0.6)
        .iter()
        .map(|h| refine::HalfSpace {
            normal: h["normal"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect(),
            offset: h["offset"].as_f64().unwrap(),
        })
        .collect();
    let triangle = refine::halfplane_polygon(&set, [x, y], 3.0);
    let lowest = |h: &refine::HalfSpace| {
        triangle
            .iter()
            .map(|p| h.normal[0] * p[0] + h.normal[1] * p[1])
            .fold(f64::INFINITY, f64::min)
    };
    for (h, color) in set
        .iter()
        .zip([palette::SECOND, palette::THIRD, palette::KNOT])
    {
        let far = refine::HalfSpace {
            normal: vec![-h.normal[0], -h.normal[1]],
            offset: -lowest(h),
        };
        let band = refine::halfplane_polygon(&[h.clone(), far], [x, y], 1.6);
        fig.polygon(&band, Style::stroke(color, 0.8).with_fill(color, 0.12));
    }
    fig.polygon(&triangle, Style::stroke(palette::ACTIVE, 1.5));
    let curve: Vec<[f64; 2]> = rp.points.iter().map(|v| [v[0], v[1]]).collect();
    fig.polygon(&curve, Style::stroke(palette::CURVE, 1.6));
    let data: Vec<[f64; 2]> = c.to_vec();
    fig.points(&data, Marker::Dot, Style::fill(palette::DATA));
    fig.caption(&format!(
        "slot iteration (50 weight updates): E = {:.8}; exact optimum E = {:.8}; relative gap {:.1e}",
        rp.energy,
        re.energy,
        (rp.energy - re.energy).abs() / re.energy
    ));
    super::save(dir, "kersey_fig4_1_slots.svg", &fig.to_svg())
}
