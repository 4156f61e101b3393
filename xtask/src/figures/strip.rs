//! Figures for `strip`: the seed's Figures 1–5 redrawn on the examples of `strip::examples`
//! (the paper does not print its data), plus the §4 convergence picture.

use std::path::Path;

use curvefit::plot::{palette, Figure, Marker, Style};
use strip::{solve, Bound, KnotKind, Options, Problem, Solution};
use strip_testkit::examples::{example_5_1, example_5_2, example_5_3};

/// Samples of the solution (24 per piece).
fn curve(s: &Solution) -> Vec<[f64; 2]> {
    let mut pts = Vec::new();
    for j in 0..s.coefficients.len() {
        let (a, b) = (s.breaks[j], s.breaks[j + 1]);
        for k in 0..24 {
            let x = a + (b - a) * k as f64 / 24.0;
            pts.push([x, s.eval(x)]);
        }
    }
    let last = *s.breaks.last().unwrap_or(&0.0);
    pts.push([last, s.eval(last)]);
    pts
}

/// The bound as polylines (one per data interval for pieces, so jumps are visible).
fn bound_lines(p: &Problem, b: &Bound) -> Vec<Vec<[f64; 2]>> {
    match b {
        Bound::None => vec![],
        Bound::Polyline(v) => vec![v.clone()],
        Bound::Pieces(pc) => pc
            .iter()
            .enumerate()
            .map(|(i, c)| {
                (0..=32)
                    .map(|k| {
                        let s = (p.t[i + 1] - p.t[i]) * k as f64 / 32.0;
                        [p.t[i] + s, c[0] + s * (c[1] + s * (c[2] + s * c[3]))]
                    })
                    .collect()
            })
            .collect(),
    }
}

fn draw_problem(fig: &mut Figure, p: &Problem) {
    let bstyle = Style::stroke(palette::BOUND, 1.2).dashed("5 3");
    for b in [&p.lower, &p.upper] {
        for line in bound_lines(p, b) {
            fig.polyline(&line, bstyle.clone());
        }
    }
    fig.legend("bounds e, d", bstyle);
}

fn draw_data(fig: &mut Figure, p: &Problem) {
    let data: Vec<[f64; 2]> = p.t.iter().zip(&p.y).map(|(a, b)| [*a, *b]).collect();
    fig.points(&data, Marker::Ring, Style::stroke(palette::DATA, 1.6));
}

fn constrained(p: &Problem, title: &str) -> anyhow::Result<(String, Solution)> {
    let s = solve(p, &Options::default())?;
    let mut fig = Figure::new(title);
    fig.equal_aspect(false);
    draw_problem(&mut fig, p);
    fig.polyline(&curve(&s), Style::stroke(palette::CURVE, 2.0));
    fig.legend("constrained spline", Style::stroke(palette::CURVE, 2.0));
    draw_data(&mut fig, p);
    let knots: Vec<[f64; 2]> = s.extra_knots.iter().map(|k| [k.t, s.eval(k.t)]).collect();
    fig.points(&knots, Marker::Star, Style::fill(palette::KNOT));
    fig.legend("extra knots", Style::fill(palette::KNOT));
    let count = |f: fn(&KnotKind) -> bool| s.extra_knots.iter().filter(|k| f(&k.kind)).count();
    fig.caption(&format!(
        "‖f''‖ = {:.4}   ({} extra knots: {} touching, {} subarc ends)   {} Newton iterations, |∇Φ| = {:.1e}",
        s.norm,
        s.extra_knots.len(),
        count(|k| matches!(k, KnotKind::Touch(_))),
        count(|k| !matches!(k, KnotKind::Touch(_))),
        s.iterations,
        s.gradient_norm
    ));
    Ok((fig.to_svg(), s))
}

fn unconstrained(p: &Problem, title: &str) -> anyhow::Result<String> {
    let free = Problem {
        lower: Bound::None,
        upper: Bound::None,
        ..p.clone()
    };
    let s = solve(&free, &Options::default())?;
    let mut fig = Figure::new(title);
    fig.equal_aspect(false);
    draw_problem(&mut fig, p);
    fig.polyline(&curve(&s), Style::stroke(palette::SECOND, 2.0));
    fig.legend("unconstrained spline", Style::stroke(palette::SECOND, 2.0));
    draw_data(&mut fig, p);
    fig.caption(&format!("‖f''‖ = {:.4}", s.norm));
    Ok(fig.to_svg())
}

/// Draws this area's figures into `dir`.
pub fn draw(dir: &Path) -> anyhow::Result<()> {
    let p1 = example_5_1();
    super::save(
        dir,
        "strip_fig1_unconstrained.svg",
        &unconstrained(
            &p1,
            "Figure 1: the unconstrained (natural) spline leaves the strip",
        )?,
    )?;
    let (svg, _) = constrained(
        &p1,
        "Figure 2: best interpolation in the strip (touching points, subarc, touching pair)",
    )?;
    super::save(dir, "strip_fig2_constrained.svg", &svg)?;
    let p2 = example_5_2();
    super::save(
        dir,
        "strip_fig3_unconstrained.svg",
        &unconstrained(
            &p2,
            "Figure 3: end slopes −2, −2; jumping bounds, cubic lower bound on [6, 8]",
        )?,
    )?;
    let (svg, _) = constrained(
        &p2,
        "Figure 4: the constrained spline with end slopes −2, −2",
    )?;
    super::save(dir, "strip_fig4_constrained.svg", &svg)?;
    let p3 = example_5_3();
    let (svg, _) = constrained(
        &p3,
        "Figure 5: two data points, end slopes −2 and 2, a polyline channel (§4, Remark 4.2)",
    )?;
    super::save(dir, "strip_fig5_polyline.svg", &svg)?;
    // §4: solutions for refining piecewise-linear approximations of continuous bounds
    let t = vec![0.0, 1.0, 2.0, 3.0, 4.0];
    let y = vec![0.0, 0.2, -0.3, 0.3, 0.0];
    let e = |x: f64| -0.6 + 0.3 * (2.0 * x).sin();
    let d = |x: f64| 0.6 + 0.25 * (3.0 * x).cos();
    let mut fig = Figure::new("§4, Theorem 4.1: refining polyline approximations of smooth bounds");
    fig.equal_aspect(false);
    let smooth = |f: &dyn Fn(f64) -> f64| -> Vec<[f64; 2]> {
        (0..=400)
            .map(|k| {
                let x = 4.0 * k as f64 / 400.0;
                [x, f(x)]
            })
            .collect()
    };
    let bstyle = Style::stroke(palette::BOUND, 1.2).dashed("5 3");
    fig.polyline(&smooth(&e), bstyle.clone());
    fig.polyline(&smooth(&d), bstyle.clone());
    fig.legend("e, d", bstyle);
    let mut caption = Vec::new();
    for (m, color) in [
        (4, palette::THIRD),
        (8, palette::SECOND),
        (64, palette::CURVE),
    ] {
        let p = Problem {
            t: t.clone(),
            y: y.clone(),
            lower: Bound::from_fn(e, 0.0, 4.0, m),
            upper: Bound::from_fn(d, 0.0, 4.0, m),
            end_slopes: [Some(3.0), Some(3.0)],
        };
        let s = solve(&p, &Options::default())?;
        fig.polyline(&curve(&s), Style::stroke(color, 1.8));
        fig.legend(&format!("m = {m} cells"), Style::stroke(color, 1.8));
        caption.push(format!("m = {m}: ‖f''‖ = {:.4}", s.norm));
    }
    let data: Vec<[f64; 2]> = t.iter().zip(&y).map(|(a, b)| [*a, *b]).collect();
    fig.points(&data, Marker::Ring, Style::stroke(palette::DATA, 1.6));
    fig.caption(&caption.join("   "));
    super::save(dir, "strip_thm4_1_convergence.svg", &fig.to_svg())?;
    Ok(())
}
