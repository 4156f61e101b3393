//! Smoothing on badly scaled knots (chordal spans over three orders of magnitude, weights up to
//! 1e4): the one banded solve alone left the answer 1e-6 … 7e-5 of the data's extent from the
//! optimum (objective 1e-6 too high) while its certificate, relative to the largest force,
//! read 1e-11. The solves now refine with a residual in difference form (`linear::Factored`).
//! The reference here: a dense LU of K = AᵀA + W (nalgebra), refined with this file's own
//! residual Aᵀ(Ap) + Wp − b, to its rounding.

use divdiff::{Knots, Parametrization, Points, Topology};
use nalgebra::{DMatrix, DVector};
use refine::{Boundary, Constraint, Problem, Refinement};

/// n points on a loop whose spacing varies over three orders of magnitude (d = 3).
fn unequal(n: usize, seed: u64) -> (Points, Vec<f64>) {
    let mut s = seed;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64)
    };
    let mut g = Vec::with_capacity(n);
    let mut acc = 0.0;
    for _ in 0..n {
        acc += 10f64.powf(-3.0 * rnd());
        g.push(acc);
    }
    let mut rows = Vec::with_capacity(3 * n);
    for v in &g {
        let a = v / acc * 2.0 * std::f64::consts::PI;
        let r = 1.0 + 0.2 * (5.0 * a).sin();
        rows.extend_from_slice(&[r * a.cos(), r * a.sin(), 0.3 * (3.0 * a).sin()]);
    }
    let w = (0..n).map(|_| 10f64.powf(5.0 * rnd() - 1.0)).collect();
    (Points::new(3, rows).unwrap(), w)
}

/// Aᵀ(Ap) on the knots, Ap in difference form (this file's own, independent of the library's).
fn hp(knots: &Knots, x: &DVector<f64>) -> DVector<f64> {
    let a = energy::alphas(knots);
    let n = x.len();
    let mut out = DVector::zeros(n);
    for i in 1..n - 1 {
        let ap = a[i][0] * (x[i - 1] - x[i]) + a[i][2] * (x[i + 1] - x[i]);
        out[i - 1] += a[i][0] * ap;
        out[i] += a[i][1] * ap;
        out[i + 1] += a[i][2] * ap;
    }
    out
}

/// The smoothing optimum on r's knots, with clamped ends when given: dense KKT by LU, refined.
fn reference(r: &Refinement, q: &Points, w: &[f64], ends: Option<[&[f64]; 2]>) -> Vec<f64> {
    let (nv, d) = (r.points.len(), q.dim());
    let h = energy::Hessian::new(&r.knots).to_dense();
    let stencils = [0, nv - 1]
        .map(|v| divdiff::derivative_stencil(&r.knots, v, refine::DerivativeRule::Bessel).unwrap());
    let m = if ends.is_some() { 2 } else { 0 };
    let mut k = DMatrix::zeros(nv + m, nv + m);
    k.view_mut((0, 0), (nv, nv)).copy_from(&h);
    for (i, &v) in r.data_vertex.iter().enumerate() {
        k[(v, v)] += w[i];
    }
    if ends.is_some() {
        for (e, st) in stencils.iter().enumerate() {
            for &(u, c) in st {
                k[(nv + e, u)] += c;
                k[(u, nv + e)] += c;
            }
        }
    }
    let lu = k.lu();
    let mut out = vec![0.0; nv * d];
    for c in 0..d {
        let mut b = DVector::zeros(nv + m);
        for (i, &v) in r.data_vertex.iter().enumerate() {
            b[v] = w[i] * q.point(i)[c];
        }
        if let Some(ends) = ends {
            for e in 0..2 {
                b[nv + e] = ends[e][c];
            }
        }
        let mut x = lu.solve(&b).unwrap();
        for _ in 0..5 {
            let p = x.rows(0, nv).into_owned();
            let mut res = b.clone();
            let kp = hp(&r.knots, &p);
            for v in 0..nv {
                res[v] -= kp[v];
            }
            for (i, &v) in r.data_vertex.iter().enumerate() {
                res[v] -= w[i] * p[v];
            }
            for (e, st) in stencils.iter().enumerate().take(m) {
                let lp: f64 = st.iter().map(|&(u, cu)| cu * p[u]).sum();
                for &(u, cu) in st {
                    res[u] -= cu * x[nv + e];
                }
                res[nv + e] -= lp;
            }
            x += lu.solve(&res).unwrap();
        }
        for v in 0..nv {
            out[v * d + c] = x[v];
        }
    }
    out
}

#[test]
fn smoothing_on_badly_scaled_knots_is_the_optimum() {
    for (seed, clamped) in [(91, false), (91, true), (7, false), (7, true)] {
        let (q, w) = unequal(300, seed);
        let (start, end) = ([1.2, -1.0, 0.3], [0.1, 0.4, 1.4]);
        let mut p = Problem::new(q.clone())
            .with_topology(Topology::Open)
            .with_k(3)
            .with_knot_iterations(0)
            .with_parametrization(Parametrization::Chordal)
            .with_constraint(Constraint::Smoothing(w.clone()));
        if clamped {
            p = p.with_boundary(Boundary::Clamped {
                start: start.to_vec(),
                end: end.to_vec(),
            });
        }
        let r = p.solve().unwrap();
        assert!(r.kkt_residual <= 1e-9, "kkt {}", r.kkt_residual);
        let want = reference(&r, &q, &w, clamped.then_some([&start[..], &end[..]]));
        let c = q.coords();
        let extent = c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let dist = r
            .points
            .coords()
            .iter()
            .zip(&want)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(
            dist <= 1e-9 * extent,
            "seed {seed} clamped {clamped}: {dist:e} of {extent} from the refined dense optimum"
        );
    }
}
