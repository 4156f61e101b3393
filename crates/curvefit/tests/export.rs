//! `--export` and `curvefit::export`: the DXF and JSON B-splines, read back by the small parsers
//! below and evaluated with de Boor's algorithm (not the Bézier form the spline evaluates with),
//! agree with `CubicSpline::eval` at random parameters to 1e-12 relative; the SVG path's Béziers
//! too; CSV samples are the curve's values; the command line writes the file all-or-nothing.

#![cfg(feature = "cli")]

use curvefit::export::{self, ExportFormat};
use curvefit::refine::{limit_curve, Boundary, Constraint, CubicSpline, Problem};
use divdiff::{Points, Topology};

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Limit curves of hard problems: jittered, very unequal spans, balls, clamped, d = 2 and 3,
/// open and closed.
fn splines() -> Vec<(String, CubicSpline)> {
    let mut g = Lcg(7);
    let mut out = Vec::new();
    for (closed, d) in [(false, 2), (true, 2), (false, 3), (true, 3)] {
        let n = 9;
        let rows: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * (i as f64 + 0.4 * g.next()) / n as f64;
                let r = 1.0 + 2.0 * g.next();
                let mut p = vec![r * a.cos() * 40.0, r * a.sin() * 40.0 + 1000.0];
                if d == 3 {
                    p.push(5.0 * g.next());
                }
                p
            })
            .collect();
        let q = Points::from_rows(&rows).unwrap();
        let topology = if closed {
            Topology::Closed
        } else {
            Topology::Open
        };
        let mut problem = Problem::new(q)
            .with_topology(topology)
            .with_constraint(Constraint::Balls(vec![3.0; n]));
        if !closed {
            problem = problem.with_boundary(Boundary::Clamped {
                start: vec![1.0; d],
                end: vec![-1.0; d],
            });
        }
        let r = problem.solve().unwrap();
        out.push((
            format!("closed {closed}, d = {d}"),
            limit_curve(&problem, &r).unwrap(),
        ));
    }
    out
}

/// de Boor's algorithm for a degree-3 B-spline.
fn de_boor(knots: &[f64], control: &[Vec<f64>], u: f64) -> Vec<f64> {
    let p = 3;
    let last = control.len() - 1;
    // The span k with knots[k] ≤ u < knots[k + 1], k in p..=last.
    let k = (p..=last)
        .rev()
        .find(|&k| knots[k] <= u && knots[k] < knots[k + 1])
        .unwrap_or(p);
    let mut d: Vec<Vec<f64>> = (0..=p).map(|j| control[j + k - p].clone()).collect();
    for r in 1..=p {
        for j in (r..=p).rev() {
            let a = (u - knots[j + k - p]) / (knots[j + 1 + k - r] - knots[j + k - p]);
            let prev = d[j - 1].clone();
            for (x, y) in d[j].iter_mut().zip(prev) {
                *x = (1.0 - a) * y + a * *x;
            }
        }
    }
    d.swap_remove(p)
}

fn assert_close(name: &str, got: &[f64], want: &[f64], scale: f64) {
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g - w).abs() <= 1e-12 * scale,
            "{name}: {got:?} vs {want:?}"
        );
    }
}

fn scale(s: &CubicSpline) -> f64 {
    (0..s.pieces())
        .flat_map(|i| s.bezier(i).unwrap().to_vec())
        .fold(1.0f64, |m, x| m.max(x.abs()))
}

fn random_params(s: &CubicSpline, g: &mut Lcg) -> Vec<f64> {
    let (a, b) = s.domain();
    let mut u: Vec<f64> = (0..50).map(|_| a + (b - a) * g.next()).collect();
    u.extend(s.breaks().iter().copied());
    u
}

/// Reads the DXF group-code pairs of the one SPLINE: degree, knots and control points.
fn read_dxf(text: &str) -> (usize, Vec<f64>, Vec<Vec<f64>>) {
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len() % 2, 0);
    let (mut degree, mut knots, mut control) = (0, Vec::new(), Vec::<Vec<f64>>::new());
    let (mut nk, mut nc) = (0, 0);
    for pair in lines.chunks(2) {
        let code: u32 = pair[0].trim().parse().unwrap();
        let v = pair[1].trim();
        match code {
            71 => degree = v.parse().unwrap(),
            72 => nk = v.parse().unwrap(),
            73 => nc = v.parse().unwrap(),
            40 => knots.push(v.parse().unwrap()),
            10 => control.push(vec![v.parse().unwrap()]),
            20 | 30 => control.last_mut().unwrap().push(v.parse().unwrap()),
            _ => {}
        }
    }
    assert_eq!((knots.len(), control.len()), (nk, nc));
    assert_eq!(nk, nc + degree + 1);
    (degree, knots, control)
}

#[test]
fn dxf_and_json_read_back_evaluate_as_the_spline() {
    let mut g = Lcg(99);
    for (name, s) in splines() {
        let sc = scale(&s);
        let d = s.dim();
        let (degree, knots, control) = read_dxf(&export::dxf(&s));
        assert_eq!(degree, 3);
        let json: serde_json::Value = serde_json::from_str(&export::json(&s)).unwrap();
        assert_eq!(json["degree"], 3);
        assert_eq!(json["closed"], s.is_closed());
        let jk: Vec<f64> = serde_json::from_value(json["knots"].clone()).unwrap();
        let jc: Vec<Vec<f64>> = serde_json::from_value(json["control_points"].clone()).unwrap();
        let bez: Vec<Vec<Vec<f64>>> = serde_json::from_value(json["bezier"].clone()).unwrap();
        let breaks: Vec<f64> = serde_json::from_value(json["breaks"].clone()).unwrap();
        for u in random_params(&s, &mut g) {
            let want = s.eval(u);
            let dxf = de_boor(&knots, &control, u);
            assert_close(&format!("dxf {name} u = {u}"), &dxf[..d], &want, sc);
            assert_close(&format!("json {name}"), &de_boor(&jk, &jc, u), &want, sc);
            // The Bézier pieces of the JSON, by Bernstein polynomials.
            let i = breaks
                .partition_point(|&x| x <= u)
                .saturating_sub(1)
                .min(bez.len() - 1);
            let t = (u - breaks[i]) / (breaks[i + 1] - breaks[i]);
            let w = [
                (1.0 - t).powi(3),
                3.0 * t * (1.0 - t).powi(2),
                3.0 * t * t * (1.0 - t),
                t.powi(3),
            ];
            let b: Vec<f64> = (0..d)
                .map(|c| (0..4).map(|r| w[r] * bez[i][r][c]).sum())
                .collect();
            assert_close(&format!("bezier {name}"), &b, &want, sc);
        }
        // A closed curve closes: first and last control points coincide.
        if s.is_closed() {
            assert_eq!(control.first(), control.last());
        }
    }
}

#[test]
fn svg_path_is_the_spline_and_refuses_space_curves() {
    let mut g = Lcg(5);
    for (name, s) in splines() {
        if s.dim() != 2 {
            let e = export::svg(&s).unwrap_err();
            assert_eq!(e.field, "--export");
            assert!(e.message.contains("plane curve"), "{e:?}");
            continue;
        }
        let text = export::svg(&s).unwrap();
        let start = text.find(" d=\"").unwrap() + 4;
        let d = &text[start..start + text[start..].find('"').unwrap()];
        let tokens: Vec<&str> = d.split_whitespace().collect();
        let mut pieces: Vec<[[f64; 2]; 4]> = Vec::new();
        let mut cur = [0.0; 2];
        let mut i = 0;
        let num = |k: usize| -> f64 { tokens[k].parse().unwrap() };
        while i < tokens.len() {
            match tokens[i] {
                "M" => {
                    cur = [num(i + 1), num(i + 2)];
                    i += 3;
                }
                "C" => {
                    let p = [
                        cur,
                        [num(i + 1), num(i + 2)],
                        [num(i + 3), num(i + 4)],
                        [num(i + 5), num(i + 6)],
                    ];
                    cur = p[3];
                    pieces.push(p);
                    i += 7;
                }
                "Z" => i += 1,
                t => panic!("unexpected token {t}"),
            }
        }
        assert_eq!(pieces.len(), s.pieces());
        assert_eq!(d.ends_with('Z'), s.is_closed());
        let sc = scale(&s);
        for u in random_params(&s, &mut g) {
            let br = s.breaks();
            let k = br
                .partition_point(|&x| x <= u)
                .saturating_sub(1)
                .min(pieces.len() - 1);
            let t = (u - br[k]) / (br[k + 1] - br[k]);
            let w = [
                (1.0 - t).powi(3),
                3.0 * t * (1.0 - t).powi(2),
                3.0 * t * t * (1.0 - t),
                t.powi(3),
            ];
            let p: Vec<f64> = (0..2)
                .map(|c| (0..4).map(|r| w[r] * pieces[k][r][c]).sum())
                .collect();
            assert_close(&format!("svg {name}"), &p, &s.eval(u), sc);
        }
    }
}

#[test]
fn csv_samples_are_the_curve() {
    for (name, s) in splines() {
        let text = export::csv(&s, None).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        assert_eq!(header, if s.dim() == 2 { "u,x,y" } else { "u,x,y,z" });
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(
            rows.len(),
            export::DEFAULT_SAMPLES_PER_PIECE * s.pieces() + 1
        );
        for r in &rows {
            assert_eq!(&r[1..], &s.eval(r[0])[..], "{name}");
        }
        // Every break is a sample, exactly (u = t_i + 0 · h_i).
        for b in s.breaks() {
            assert!(
                rows.iter().any(|r| r[0].to_bits() == b.to_bits()),
                "{name}: break {b}"
            );
        }
        let n = export::csv(&s, Some(7)).unwrap().lines().count();
        assert_eq!(n, 8);
        assert_eq!(export::csv(&s, Some(1)).unwrap_err().field, "--samples");
    }
}

fn scratch(tag: &str) -> std::path::PathBuf {
    let d = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("export-{tag}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> (i32, String) {
    let mut out = Vec::new();
    let mut err = Vec::new();
    let code = curvefit::cli::run(
        std::iter::once("curvefit").chain(args.iter().copied()),
        &mut std::io::empty(),
        &mut out,
        &mut err,
    );
    (code, String::from_utf8_lossy(&err).into_owned())
}

/// End to end: `curvefit refine P --export F.dxf` writes the library's limit curve; a 3-D curve
/// to `.svg` is exit 2 and no file is written, the JSON result included.
#[test]
fn the_command_line_writes_the_export_all_or_nothing() {
    let dir = scratch("cli");
    let problem = dir.join("p.json");
    std::fs::write(
        &problem,
        r#"{"points": [[0,0,0],[1,2,0.5],[3,1,1],[4,3,0],[6,0,2]], "closed": false, "k": 4,
            "constraint": {"type": "balls", "radii": [0.1,0.3,0.2,0.3,0.1]}}"#,
    )
    .unwrap();
    let p = problem.to_str().unwrap();
    let result = dir.join("r.json");
    let dxf = dir.join("c.dxf");
    let (code, err) = run(&[
        "refine",
        p,
        "-o",
        result.to_str().unwrap(),
        "--export",
        dxf.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let spec: curvefit::spec::refine::RefineProblem =
        curvefit::spec::from_json(&std::fs::read_to_string(&problem).unwrap()).unwrap();
    let r = curvefit::spec::refine::solve(&spec).unwrap();
    let s = export::refine_limit(&spec, &r).unwrap();
    assert_eq!(std::fs::read_to_string(&dxf).unwrap(), export::dxf(&s));
    let (_, knots, control) = read_dxf(&std::fs::read_to_string(&dxf).unwrap());
    let mut g = Lcg(1);
    for u in random_params(&s, &mut g) {
        assert_close(
            "cli dxf",
            &de_boor(&knots, &control, u),
            &s.eval(u),
            scale(&s),
        );
    }

    // --export-format overrides a missing extension; --samples only with csv.
    let any = dir.join("curve.txt");
    let (code, err) = run(&[
        "refine",
        p,
        "-o",
        "/dev/null",
        "--export",
        any.to_str().unwrap(),
        "--export-format",
        "csv",
        "--samples",
        "11",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read_to_string(&any).unwrap().lines().count(), 12);

    let fresh = scratch("cli-refused");
    let out = fresh.join("r.json");
    let svg = fresh.join("c.svg");
    let (code, err) = run(&[
        "refine",
        p,
        "-o",
        out.to_str().unwrap(),
        "--export",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--export") && err.contains("plane curve"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(&fresh).unwrap().count(), 0);
    let (code, err) = run(&["refine", p, "-o", "/dev/null", "--export", "c.step"]);
    assert_eq!(code, 2);
    assert!(err.contains("extension"), "{err}");
    let (code, err) = run(&["refine", p, "-o", "/dev/null", "--samples", "3"]);
    assert_eq!(code, 2);
    assert!(err.contains("--samples"), "{err}");
    // Samples beyond the output limit are refused, not allocated (10^12 was killed for memory),
    // and nothing is written.
    let csv = fresh.join("c.csv");
    let (code, err) = run(&[
        "refine",
        p,
        "-o",
        out.to_str().unwrap(),
        "--export",
        csv.to_str().unwrap(),
        "--samples",
        "1000000000000",
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--samples") && err.contains("the limit"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(&fresh).unwrap().count(), 0);
}

#[test]
fn formats_are_named_by_extension() {
    assert_eq!(ExportFormat::from_name("DXF"), Some(ExportFormat::Dxf));
    assert_eq!(ExportFormat::from_name("step"), None);
}
