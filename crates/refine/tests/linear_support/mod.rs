//! The dense reference of the linear problems' tests (`clamped.rs`, `linear_accuracy.rs`): the
//! minimizer of ½pᵀ(H ⊗ I)p + ½Σ w_i|p_{v_i} − q_i|² (interpolation, p_{v_i} = q_i, when
//! `weights` is `None`), with clamped ends L_s p = start, L_e p = end when given, on the knots
//! and data vertices the library chose: nalgebra's LU of the KKT matrix [H + W  Cᵀ; C  0] per
//! coordinate, refined with this file's own residual (Aᵀ(Ap) in difference form, which does not
//! cancel terms of size ‖H‖|p| as the band form does on badly scaled knots).

use divdiff::{DerivativeRule, Knots, Points};
use nalgebra::{DMatrix, DVector};
use refine::Refinement;

/// Aᵀ(Ap) on the knots, Ap in difference form (open curves).
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

/// The optimum's vertices (vertex-major, d per vertex; module docs) and the multipliers λ of the constraint rows
/// (row-major, d per row: interpolation's data rows first, in data order, then the start and
/// end rows), H p + W p + Cᵀλ = W q.
pub fn dense_kkt(
    r: &Refinement,
    q: &Points,
    weights: Option<&[f64]>,
    rule: DerivativeRule,
    ends: Option<[&[f64]; 2]>,
) -> (Vec<f64>, Vec<f64>) {
    let (nv, d) = (r.points.len(), q.dim());
    // The constraint rows C (vertex, coefficient) and, per coordinate, their targets.
    let mut rows: Vec<Vec<(usize, f64)>> = Vec::new();
    let mut targets: Vec<Vec<f64>> = Vec::new();
    if weights.is_none() {
        for (i, &v) in r.data_vertex.iter().enumerate() {
            rows.push(vec![(v, 1.0)]);
            targets.push(q.point(i).to_vec());
        }
    }
    if let Some(ends) = ends {
        for (v, target) in [(0, ends[0]), (nv - 1, ends[1])] {
            rows.push(
                divdiff::derivative_stencil(&r.knots, v, rule)
                    .unwrap()
                    .to_vec(),
            );
            targets.push(target.to_vec());
        }
    }
    let m = rows.len();
    let mut k = DMatrix::zeros(nv + m, nv + m);
    k.view_mut((0, 0), (nv, nv))
        .copy_from(&energy::Hessian::new(&r.knots).to_dense());
    let mut w = vec![0.0; nv];
    if let Some(weights) = weights {
        for (i, &v) in r.data_vertex.iter().enumerate() {
            w[v] = weights[i];
            k[(v, v)] += weights[i];
        }
    }
    for (j, row) in rows.iter().enumerate() {
        for &(u, c) in row {
            k[(nv + j, u)] += c;
            k[(u, nv + j)] += c;
        }
    }
    let lu = k.lu();
    let mut out = vec![0.0; nv * d];
    let mut lambda = vec![0.0; m * d];
    for c in 0..d {
        let mut b = DVector::zeros(nv + m);
        if weights.is_some() {
            for (i, &v) in r.data_vertex.iter().enumerate() {
                b[v] = w[v] * q.point(i)[c];
            }
        }
        for (j, t) in targets.iter().enumerate() {
            b[nv + j] = t[c];
        }
        let mut x = lu.solve(&b).expect("the KKT matrix is nonsingular");
        for _ in 0..5 {
            let p = x.rows(0, nv).into_owned();
            let mut res = b.clone();
            let kp = hp(&r.knots, &p);
            for v in 0..nv {
                res[v] -= kp[v] + w[v] * p[v];
            }
            for (j, row) in rows.iter().enumerate() {
                for &(u, cu) in row {
                    res[u] -= cu * x[nv + j];
                    res[nv + j] -= cu * p[u];
                }
            }
            x += lu.solve(&res).expect("the same LU");
        }
        for v in 0..nv {
            out[v * d + c] = x[v];
        }
        for j in 0..m {
            lambda[j * d + c] = x[nv + j];
        }
    }
    (out, lambda)
}

/// The largest coordinate difference between two point arrays.
pub fn max_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// Uniform numbers in [0, 1) from a fixed seed (a 64-bit LCG: the tests' data, reproducible
/// without a dependency).
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64)
    }
}
