//! Khan et al. (seed 001), the rules: the (2m+2)-point n-ary rules (3.13) and their printed
//! members (Remark 3.1, (3.10)), the Newton-form derivation (2.3)–(2.5), (3.8), polynomial
//! reproduction, application to polygons and quad grids (4.1)–(4.2) with the printed 2-D masks
//! (Remark 4.1). Supports and smoothness are in `khan_shape.rs`. See the inventory in
//! `verify/schemes.rs`.

use divdiff::{Points, Topology};
use subdivision::{lagrange_weights, rational_to_f64, BigRational, NaryScheme, QuadGrid};

use super::super::{worst, Case, Oracle, Outcome};
use super::{abs, lcg, max_diff, q, qs, show};

/// A named member: the derived rule for `residue` against the literature's weights.
fn member(
    points: usize,
    arity: usize,
    residue: usize,
    expect: &'static [&'static str],
    source: &'static str,
) -> anyhow::Result<Outcome> {
    let s = NaryScheme::new(points, arity)?;
    let w = s.exact_rule(residue);
    Ok(Outcome::check(
        max_diff(w, &qs(expect)),
        0.0,
        format!("derived {} vs {source}", show(w)),
    )
    .against(Oracle::ExactRational))
}

/// A rule as printed in the seed: magnitudes (the text extraction lost every sign) on the
/// printed stencil offsets. Compared with the derived rule offset by offset: an offset the
/// print does not list has weight 0, one the derivation does not have has weight 0 too. The
/// residual is the largest | |printed| − |derived| |; the detail names each differing weight.
fn printed(
    points: usize,
    arity: usize,
    residue: usize,
    offsets: std::ops::RangeInclusive<isize>,
    magnitudes: &'static [&'static str],
) -> anyhow::Result<Outcome> {
    let s = NaryScheme::new(points, arity)?;
    let printed: Vec<(isize, BigRational)> = offsets.zip(qs(magnitudes)).collect();
    let derived: Vec<(isize, BigRational)> = s
        .offsets()
        .into_iter()
        .zip(s.exact_rule(residue).iter().map(abs))
        .collect();
    let lo = printed[0].0.min(derived[0].0);
    let hi = printed[printed.len() - 1]
        .0
        .max(derived[derived.len() - 1].0);
    let at = |v: &[(isize, BigRational)], j: isize| {
        v.iter()
            .find(|(o, _)| *o == j)
            .map_or(q("0"), |(_, w)| w.clone())
    };
    let mut diffs = Vec::new();
    let mut residuals = Vec::new();
    for j in lo..=hi {
        let (p, d) = (at(&printed, j), at(&derived, j));
        residuals.push(rational_to_f64(&abs(&(&p - &d))));
        if p != d {
            let at = if j == 0 {
                "p_i".to_string()
            } else {
                format!("p_(i{j:+})")
            };
            diffs.push(format!("{at}: printed {p}, derived {d}"));
        }
    }
    let detail = if diffs.is_empty() {
        format!(
            "residue {residue}: all {} printed |weights| equal the derived ones",
            hi - lo + 1
        )
    } else {
        format!(
            "residue {residue}: {} of {} weights differ — {}",
            diffs.len(),
            hi - lo + 1,
            diffs.join("; ")
        )
    };
    Ok(Outcome::check(worst(residuals), 0.0, detail).against(Oracle::ExactRational))
}

/// (2.3)–(2.5): the Newton form of the interpolant through p_{−m}, …, p_{m+1}, built from the
/// divided-difference table of the unit data e_j and the Newton basis Π_{l<k} (x − x_l),
/// evaluated at a/n, against the library's (barycentric Lagrange) rules.
fn newton_form() -> anyhow::Result<Outcome> {
    let mut residuals = Vec::new();
    let mut rules = 0;
    for points in (2..=8).step_by(2) {
        for arity in 2..=5usize {
            let s = NaryScheme::new(points, arity)?;
            let nodes: Vec<BigRational> = s.offsets().iter().map(|&o| q(&o.to_string())).collect();
            for a in 0..arity {
                let x = q(&format!("{a}/{arity}"));
                let mut weights = Vec::new();
                for j in 0..points {
                    // Divided differences of e_j: column k holds [x_i, …, x_{i+k}].
                    let mut col: Vec<BigRational> = (0..points)
                        .map(|i| if i == j { q("1") } else { q("0") })
                        .collect();
                    let mut value = col[0].clone();
                    let mut basis = q("1");
                    for k in 1..points {
                        col = (0..points - k)
                            .map(|i| (&col[i + 1] - &col[i]) / (&nodes[i + k] - &nodes[i]))
                            .collect();
                        basis *= &x - &nodes[k - 1];
                        value += &col[0] * &basis;
                    }
                    weights.push(value);
                }
                residuals.push(max_diff(&weights, s.exact_rule(a)));
                rules += 1;
            }
        }
    }
    Ok(Outcome::check(
        worst(residuals),
        0.0,
        format!("{rules} rules (P = 2..8, n = 2..5): Newton divided-difference form vs the library's Lagrange weights"),
    )
    .against(Oracle::ExactRational))
}

/// (3.8) as printed, P(x) = p_{−1} + Δp (x+1) + ½Δ²p (x+1)x + ⅙Δ³p (x+1)x(x−1) with forward
/// differences from p_{−1}, evaluated at the parameter values (3.9) x = 1/3, 2/3: the ternary
/// 4-point rules, against the library's.
fn ternary_newton_printed() -> anyhow::Result<Outcome> {
    let s = NaryScheme::new(4, 3)?;
    let mut residuals = Vec::new();
    for a in 1..3usize {
        let x = q(&format!("{a}/3"));
        let (x1, x0, xm) = (&x + q("1"), x.clone(), &x - q("1"));
        // Coefficients of p_{−1}, p_0, p_1, p_2 in 1, Δ, Δ², Δ³ (forward differences from p_{−1}).
        let diffs: [[i64; 4]; 4] = [[1, 0, 0, 0], [-1, 1, 0, 0], [1, -2, 1, 0], [-1, 3, -3, 1]];
        let basis = [
            q("1"),
            x1.clone(),
            &x1 * &x0 / q("2"),
            &x1 * &x0 * &xm / q("6"),
        ];
        let w: Vec<BigRational> = (0..4)
            .map(|j| {
                (0..4).fold(q("0"), |acc, k| {
                    acc + &basis[k] * q(&diffs[k][j].to_string())
                })
            })
            .collect();
        residuals.push(max_diff(&w, s.exact_rule(a)));
    }
    Ok(Outcome::check(
        worst(residuals),
        0.0,
        "(3.8) at x = 1/3, 2/3 (3.9) vs the derived rules (−5, 60, 30, −4)/81 and mirror",
    )
    .against(Oracle::ExactRational))
}

/// Σ_j w_j j^d − x^d over all rules (centred and one-sided), degrees 0..=2m+1: the largest
/// |defect|; also counts the rules that (wrongly) reproduce degree 2m+2.
fn reproduction() -> anyhow::Result<Outcome> {
    let mut defects = Vec::new();
    let mut too_good = 0usize;
    let mut rules = 0usize;
    for points in [2usize, 4, 6, 8] {
        for arity in 2..=5usize {
            let s = NaryScheme::new(points, arity)?;
            for t in 0..points - 1 {
                for a in 1..arity {
                    rules += 1;
                    let x = q(&format!("{}/{}", t * arity + a, arity));
                    for deg in 0..=points {
                        let defect =
                            rational_to_f64(&abs(&moment_defect(s.boundary_rule(t, a), &x, deg)));
                        if deg < points {
                            defects.push(defect);
                        } else if defect == 0.0 {
                            too_good += 1;
                        }
                    }
                }
            }
        }
    }
    Ok(Outcome::check(
        worst(defects) + too_good as f64,
        0.0,
        format!("{rules} rules (P = 2..8, n = 2..5, all end shifts): degree ≤ 2m+1 exact, degree 2m+2 reproduced by {too_good}"),
    )
    .against(Oracle::ExactRational))
}

/// Σ_j w_j j^deg − x^deg for a rule on the nodes 0, 1, … .
pub(super) fn moment_defect(w: &[BigRational], x: &BigRational, deg: usize) -> BigRational {
    let mut lhs = q("0");
    for (j, wj) in w.iter().enumerate() {
        let mut p = q("1");
        for _ in 0..deg {
            p *= q(&j.to_string());
        }
        lhs += wj * p;
    }
    let mut rhs = q("1");
    for _ in 0..deg {
        rhs *= x;
    }
    lhs - rhs
}

fn partition_of_unity() -> anyhow::Result<Outcome> {
    let mut sums = Vec::new();
    for points in (2..=12).step_by(2) {
        for arity in 2..=7 {
            let s = NaryScheme::new(points, arity)?;
            for t in 0..points - 1 {
                for a in 0..arity {
                    let sum = s.boundary_rule(t, a).iter().fold(q("0"), |acc, w| acc + w);
                    sums.push(rational_to_f64(&abs(&(sum - q("1")))));
                }
            }
        }
    }
    Ok(Outcome::check(
        worst(sums),
        0.0,
        "|Σ w − 1| over every rule, P = 2..12, n = 2..7",
    )
    .against(Oracle::ExactRational))
}

fn rounding() -> anyhow::Result<Outcome> {
    let mut excess = Vec::new();
    for (points, arity) in [(4, 2), (6, 2), (4, 3), (6, 3), (10, 5), (16, 7)] {
        let s = NaryScheme::new(points, arity)?;
        for a in 0..arity {
            for (w, f) in s.exact_rule(a).iter().zip(s.rule(a)) {
                let err = |g: f64| -> anyhow::Result<f64> {
                    // Exact |g − w| via the exact value of g (a dyadic rational).
                    let gq =
                        BigRational::from_float(g).ok_or_else(|| anyhow::anyhow!("non-finite"))?;
                    Ok(rational_to_f64(&abs(&(gq - w))))
                };
                let e = err(*f)?;
                let up = err(f.next_up())?;
                let down = err(f.next_down())?;
                // ≤ 0 when no neighbour is strictly closer.
                excess.push((e - up.min(down)).max(0.0));
            }
        }
    }
    Ok(Outcome::check(
        worst(excess.iter().copied()),
        0.0,
        format!(
            "{} weights: distance to the exact value minus the nearest neighbour's",
            excess.len()
        ),
    )
    .against(Oracle::ExactRational))
}

fn closed_vs_reference() -> anyhow::Result<Outcome> {
    let mut seed = 7u64;
    let mut errors = Vec::new();
    for (points, arity, dim, n) in [(4, 2, 3, 9), (6, 3, 2, 7), (8, 4, 5, 11), (4, 3, 1, 3)] {
        let s = NaryScheme::new(points, arity)?;
        let coords: Vec<f64> = (0..n * dim).map(|_| lcg(&mut seed)).collect();
        let p = Points::new(dim, coords.clone())?;
        let got = s.subdivide(&p, Topology::Closed, 1)?;
        for i in 0..n {
            for a in 0..arity {
                for c in 0..dim {
                    let mut v = 0.0;
                    for (off, w) in s.offsets().iter().zip(s.rule(a)) {
                        let k = (i as isize + off).rem_euclid(n as isize) as usize;
                        v += w * coords[k * dim + c];
                    }
                    errors.push((got.point(i * arity + a)[c] - v).abs());
                }
            }
        }
    }
    Ok(Outcome::check(
        worst(errors),
        1e-14,
        "max |kernel − naive periodic sum (2.1)|, 4 schemes, d = 1..5",
    )
    .against(Oracle::IndependentSolver("naive periodic sum of (2.1)")))
}

/// The scheme is interpolating: level-k point i is level-(k+1) point n·i, bit for bit.
fn old_points_kept() -> anyhow::Result<Outcome> {
    let mut seed = 3u64;
    let mut kept = true;
    for (points, arity, topology) in [
        (4, 2, Topology::Closed),
        (6, 3, Topology::Open),
        (8, 5, Topology::Closed),
        (4, 4, Topology::Open),
    ] {
        let s = NaryScheme::new(points, arity)?;
        let coords: Vec<f64> = (0..10 * 3).map(|_| lcg(&mut seed)).collect();
        let p = Points::new(3, coords)?;
        let fine = s.subdivide(&p, topology, 2)?;
        for i in 0..p.len() {
            let a = p.point(i).iter().map(|x| x.to_bits());
            kept &= a.eq(fine.point(i * arity * arity).iter().map(|x| x.to_bits()));
        }
    }
    Ok(Outcome::flag(
        kept,
        "old points reappear unchanged (bitwise) after 2 levels, open and closed",
    )
    .against(Oracle::Property("interpolation: p^{k+1}_{ni} = p^k_i")))
}

fn open_cubic() -> anyhow::Result<Outcome> {
    let f = |x: f64| [x * x * x - 2.0 * x + 1.0, 0.5 * x * x - x * x * x / 7.0];
    let mut errors = Vec::new();
    for arity in 2..=4 {
        let s = NaryScheme::new(4, arity)?;
        let rows: Vec<[f64; 2]> = (0..6).map(|i| f(i as f64)).collect();
        let got = s.subdivide(&Points::from_rows(&rows)?, Topology::Open, 2)?;
        let nn = (arity * arity) as f64;
        for k in 0..got.len() {
            let e = f(k as f64 / nn);
            for (g, ec) in got.point(k).iter().zip(e) {
                errors.push((g - ec).abs());
            }
        }
    }
    Ok(Outcome::check(
        worst(errors),
        1e-12,
        "open 6-point polygon on a cubic, 4-point rules n = 2..4, 2 levels: max |p − q(k/n²)| (ends included)",
    )
    .against(Oracle::ClosedForm))
}

/// The seed's 2-D masks (magnitudes as printed in Remark 4.1, r outer, s inner).
fn seed_mask(
    arity: usize,
    residue: (usize, usize),
    printed: &'static [&'static str],
) -> anyhow::Result<Outcome> {
    let s = NaryScheme::new(4, arity)?;
    let rules = s.surface_rules();
    let rule = rules
        .iter()
        .find(|r| r.residue == residue)
        .ok_or_else(|| anyhow::anyhow!("no rule {residue:?}"))?;
    let mags: Vec<BigRational> = rule.weights.iter().map(abs).collect();
    let sum = rule.weights.iter().fold(q("0"), |a, w| a + w);
    Ok(Outcome::check(
        max_diff(&mags, &qs(printed)) + rational_to_f64(&abs(&(sum - q("1")))),
        0.0,
        format!("|mask {residue:?}| vs the printed 16 entries, and Σ = 1"),
    )
    .against(Oracle::Seed))
}

/// Remark 4.1's one-dimensional rules inside the 2-D masks (residues (a, 0) and (0, b)): the
/// printed magnitudes on the stencil −1..2 against the 2-D rule's nonzero weights.
fn seed_axis_rules() -> anyhow::Result<Outcome> {
    let printed: [(usize, (usize, usize), [&str; 4]); 6] = [
        (2, (0, 1), ["1/16", "9/16", "9/16", "1/16"]),
        (2, (1, 0), ["1/16", "9/16", "9/16", "1/16"]),
        (3, (1, 0), ["5/81", "20/27", "10/27", "4/81"]),
        (3, (2, 0), ["4/81", "10/27", "20/27", "5/81"]),
        (3, (0, 1), ["5/81", "20/27", "10/27", "4/81"]),
        (3, (0, 2), ["4/81", "10/27", "20/27", "5/81"]),
    ];
    let mut residuals = Vec::new();
    for (arity, residue, mags) in printed {
        let s = NaryScheme::new(4, arity)?;
        let rules = s.surface_rules();
        let rule = rules
            .iter()
            .find(|r| r.residue == residue)
            .ok_or_else(|| anyhow::anyhow!("no rule {residue:?}"))?;
        // The stencil along the refined direction: offsets (r, 0) for (a, 0), (0, s) for (0, b).
        let along: Vec<BigRational> = (-1..=2isize)
            .map(|o| {
                let key = if residue.1 == 0 { (o, 0) } else { (0, o) };
                rule.offsets
                    .iter()
                    .zip(&rule.weights)
                    .find(|(off, _)| **off == key)
                    .map_or(q("0"), |(_, w)| abs(w))
            })
            .collect();
        let rest = rule
            .offsets
            .iter()
            .zip(&rule.weights)
            .filter(|(off, _)| {
                if residue.1 == 0 {
                    off.1 != 0
                } else {
                    off.0 != 0
                }
            })
            .map(|(_, w)| rational_to_f64(&abs(w)));
        residuals.push(max_diff(&along, &qs(&mags)));
        residuals.push(worst(rest));
    }
    Ok(Outcome::check(
        worst(residuals),
        0.0,
        "Remark 4.1's edge rules p_(2i,2j+1), p_(2i+1,2j) (Kobbelt) and p_(3i+a,3j), p_(3i,3j+b) (ternary): printed |weights| vs the 2-D rules (zero off the axis)",
    )
    .against(Oracle::Seed))
}

fn separable_vs_mask() -> anyhow::Result<Outcome> {
    let mut seed = 11u64;
    let mut errors = Vec::new();
    for (points, arity, rows, cols) in [(4, 2, 4, 5), (4, 3, 3, 4), (6, 2, 5, 3)] {
        let s = NaryScheme::new(points, arity)?;
        let coords: Vec<f64> = (0..rows * cols * 3).map(|_| lcg(&mut seed)).collect();
        let grid = QuadGrid::new(rows, cols, Points::new(3, coords.clone())?, true, true)?;
        let fine = s.subdivide_grid(&grid, 1)?;
        let nc = cols * arity;
        for rule in s.surface_rules() {
            let (a, b) = rule.residue;
            for i in 0..rows {
                for j in 0..cols {
                    for c in 0..3 {
                        let mut v = 0.0;
                        for ((r, t), w) in rule.offsets.iter().zip(&rule.weights) {
                            let si = (i as isize + r).rem_euclid(rows as isize) as usize;
                            let sj = (j as isize + t).rem_euclid(cols as isize) as usize;
                            v += rational_to_f64(w) * coords[(si * cols + sj) * 3 + c];
                        }
                        let got = fine.points().point((arity * i + a) * nc + arity * j + b)[c];
                        errors.push((got - v).abs());
                    }
                }
            }
        }
    }
    Ok(Outcome::check(
        worst(errors),
        1e-13,
        "doubly periodic grids: separable refinement vs direct application of the 2-D masks (4.1)",
    )
    .against(Oracle::IndependentSolver("direct 2-D mask sums of (4.1)")))
}

fn bicubic() -> anyhow::Result<Outcome> {
    let f =
        |x: f64, y: f64| x * x * y - 0.3 * y * y * y + x * y + 2.0 * x * x * x * y * y * y / 50.0;
    let s = NaryScheme::new(4, 3)?;
    let (rows, cols) = (5, 6);
    let mut pts = Vec::new();
    for i in 0..rows {
        for j in 0..cols {
            pts.push([i as f64, j as f64, f(i as f64, j as f64)]);
        }
    }
    let grid = QuadGrid::new(rows, cols, Points::from_rows(&pts)?, false, false)?;
    let fine = s.subdivide_grid(&grid, 1)?;
    let mut errors = Vec::new();
    for i in 0..fine.rows() {
        for j in 0..fine.cols() {
            let (x, y) = (i as f64 / 3.0, j as f64 / 3.0);
            errors.push((fine.point(i, j)[2] - f(x, y)).abs());
        }
    }
    Ok(Outcome::check(
        worst(errors),
        1e-11,
        "open 5×6 grid sampled from a bicubic, ternary 4-point: max |z − f| (edges included)",
    )
    .against(Oracle::ClosedForm))
}

/// (4.2) read as a mask: the 2-D mask assembled from the surface rules equals the tensor
/// product of the curve mask with itself, coefficient by coefficient.
fn surface_mask_is_tensor() -> anyhow::Result<Outcome> {
    let mut bad = 0usize;
    let mut total = 0usize;
    for (points, arity) in [(2, 2), (4, 2), (6, 2), (4, 3), (6, 3), (4, 5)] {
        let s = NaryScheme::new(points, arity)?;
        let (curve, surface) = (s.mask(), s.surface_mask());
        let (lo, len) = (curve.first()[0], curve.shape()[0] as isize);
        for r in lo..lo + len {
            for t in lo..lo + len {
                total += 1;
                let product = curve.coefficient(&[r]) * curve.coefficient(&[t]);
                bad += usize::from(surface.coefficient(&[r, t]) != product);
            }
        }
    }
    Ok(Outcome::check(
        bad as f64,
        0.0,
        format!("{total} coefficients of six 2-D masks vs a(r)·a(s) of the curve masks"),
    )
    .against(Oracle::ExactRational))
}

fn lagrange_direct() -> anyhow::Result<Outcome> {
    // The barycentric evaluation against the product formula, on a wide stencil.
    let x = q("7/5");
    let w = lagrange_weights(-3, 8, &x);
    let mut residuals = Vec::new();
    for (j, wj) in w.iter().enumerate() {
        let mut v = q("1");
        for l in 0..8 {
            if l != j {
                v = v * (&x - q(&(l as i64 - 3).to_string()))
                    / q(&(j as i64 - l as i64).to_string());
            }
        }
        residuals.push(rational_to_f64(&abs(&(v - wj))));
    }
    Ok(Outcome::check(
        worst(residuals),
        0.0,
        "barycentric Lagrange weights vs the product form C of (3.6)/(3.12), nodes −3..4 at 7/5",
    )
    .against(Oracle::ExactRational))
}

/// The cases of seed 001.
pub fn cases() -> Vec<Case> {
    vec![
        Case::holds("khan/3.3/binary-2-point", || {
            member(2, 2, 1, &["1/2", "1/2"], "(3.3) p_(2i+1) = (p_i + p_(i+1))/2")
        }),
        Case::holds("khan/3.13/binary-4-point-DD", || {
            member(
                4,
                2,
                1,
                &["-1/16", "9/16", "9/16", "-1/16"],
                "Dyn–Levin–Gregory / Dubuc (math.md §3)",
            )
        }),
        Case::holds("khan/3.13/binary-6-point-DD", || {
            member(
                6,
                2,
                1,
                &["3/256", "-25/256", "150/256", "150/256", "-25/256", "3/256"],
                "Deslauriers–Dubuc (math.md §3)",
            )
        }),
        Case::holds("khan/3.13/ternary-4-point-a1", || {
            member(
                4,
                3,
                1,
                &["-5/81", "60/81", "30/81", "-4/81"],
                "math.md §3",
            )
        }),
        Case::holds("khan/3.13/ternary-4-point-a2-mirror", || {
            member(
                4,
                3,
                2,
                &["-4/81", "30/81", "60/81", "-5/81"],
                "the mirror of a = 1",
            )
        }),
        Case::holds("khan/3.13/ternary-6-point-a1", || {
            member(
                6,
                3,
                1,
                &["8/729", "-70/729", "560/729", "280/729", "-56/729", "7/729"],
                "Lagrange basis on −2..3 at 1/3, by hand",
            )
        }),
        Case::holds("khan/2.3-2.5/newton-form-equals-lagrange", newton_form),
        Case::holds(
            "khan/3.8/ternary-newton-form-at-(3.9)",
            ternary_newton_printed,
        ),
        Case::holds("khan/3.13/lagrange-barycentric-vs-product", lagrange_direct),
        Case::holds("khan/remark3.1/printed-binary-4-point", || {
            printed(4, 2, 1, -1..=2, &["1/16", "9/16", "9/16", "1/16"])
        }),
        Case::holds("khan/remark3.1/printed-binary-6-point", || {
            printed(
                6,
                2,
                1,
                -2..=3,
                &["3/256", "25/256", "75/128", "75/128", "25/256", "3/256"],
            )
        }),
        Case::fails(
            "khan/3.10/printed-ternary-4-point-a1",
            "(3.10) prints the weight of p_(i+2) as 4/80 (it is 4/81)",
            || printed(4, 3, 1, -1..=2, &["5/81", "20/27", "10/27", "4/80"]),
        ),
        Case::fails(
            "khan/3.10/printed-ternary-4-point-a2",
            "(3.10) prints the weight of p_(i+2) as 5/80 (it is 5/81)",
            || printed(4, 3, 2, -1..=2, &["4/81", "10/27", "20/27", "5/80"]),
        ),
        Case::fails(
            "khan/remark3.1/printed-ternary-4-point",
            "Remark 3.1 prints 20/27 for the weight of p_(i+1) (it is 10/27)",
            || printed(4, 3, 1, -1..=2, &["5/81", "20/27", "20/27", "4/81"]),
        ),
        Case::fails(
            "khan/remark3.1/printed-ternary-4-point-a2",
            "Remark 3.1 prints 20/27 for the weight of p_i (it is 10/27)",
            || printed(4, 3, 2, -1..=2, &["4/81", "20/27", "20/27", "5/81"]),
        ),
        Case::fails(
            "khan/remark3.1/printed-ternary-6-point",
            "Remark 3.1's 'ternary 6-point' rule is a 4-point rule on p_(i−1)..p_(i+2) (the ternary 4-point one, with 20/27 for 10/27); the 6-point weights are (8, −70, 560, 280, −56, 7)/729 on p_(i−2)..p_(i+3)",
            || printed(6, 3, 1, -1..=2, &["5/81", "20/27", "20/27", "4/81"]),
        ),
        Case::holds("khan/3.13/polynomial-reproduction-2m+1", reproduction),
        Case::holds("khan/2.2/partition-of-unity", partition_of_unity),
        Case::holds("khan/3.13/floats-correctly-rounded", rounding),
        Case::holds("khan/2.1/closed-apply-vs-naive", closed_vs_reference),
        Case::holds("khan/3.13/open-ends-reproduce-cubics", open_cubic),
        Case::holds("khan/3.13/interpolating-old-points-kept", old_points_kept),
        Case::holds("khan/4.2/kobbelt-mask-(1,1)", || {
            seed_mask(
                2,
                (1, 1),
                &[
                    "1/256", "9/256", "9/256", "1/256", "9/256", "81/256", "81/256", "9/256",
                    "9/256", "81/256", "81/256", "9/256", "1/256", "9/256", "9/256", "1/256",
                ],
            )
        }),
        Case::holds("khan/4.2/ternary-mask-(1,1)", || {
            seed_mask(
                3,
                (1, 1),
                &[
                    "25/6561", "100/2187", "50/2187", "20/6561", "100/2187", "400/729", "200/729",
                    "80/2187", "50/2187", "200/729", "100/729", "40/2187", "20/6561", "80/2187",
                    "40/2187", "16/6561",
                ],
            )
        }),
        Case::holds("khan/4.2/ternary-mask-(1,2)", || {
            seed_mask(
                3,
                (1, 2),
                &[
                    "20/6561", "50/2187", "100/2187", "25/6561", "80/2187", "200/729", "400/729",
                    "100/2187", "40/2187", "100/729", "200/729", "50/2187", "16/6561", "40/2187",
                    "80/2187", "20/6561",
                ],
            )
        }),
        Case::holds("khan/4.2/ternary-mask-(2,1)", || {
            seed_mask(
                3,
                (2, 1),
                &[
                    "20/6561", "80/2187", "40/2187", "16/6561", "50/2187", "200/729", "100/729",
                    "40/2187", "100/2187", "400/729", "200/729", "80/2187", "25/6561", "100/2187",
                    "50/2187", "20/6561",
                ],
            )
        }),
        Case::holds("khan/4.2/ternary-mask-(2,2)", || {
            seed_mask(
                3,
                (2, 2),
                &[
                    "16/6561", "40/2187", "80/2187", "20/6561", "40/2187", "100/729", "200/729",
                    "50/2187", "80/2187", "200/729", "400/729", "100/2187", "20/6561", "50/2187",
                    "100/2187", "25/6561",
                ],
            )
        }),
        Case::holds("khan/remark4.1/printed-edge-rules", seed_axis_rules),
        Case::holds("khan/4.2/surface-mask-is-tensor-product", surface_mask_is_tensor),
        Case::holds("khan/4.1/separable-equals-2d-masks", separable_vs_mask),
        Case::holds("khan/4.2/open-grid-reproduces-bicubics", bicubic),
    ]
}
