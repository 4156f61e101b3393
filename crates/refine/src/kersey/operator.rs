//! The energy (2.1), its gradient Hp and the jumps jmp = ½Hp, applied matrix-free from the
//! α-stencil of Kersey §2 (math.md §1). Used for the certificates, so they are computed
//! independently of whichever solver produced the points.

use divdiff::{Knots, Points};

/// Row i of A: (α_{i,1}, α_{i,2}, α_{i,3}) on vertices i − 1, i, i + 1 (wrapping for closed
/// curves); `None` for the first and last rows of an open curve, which are zero.
pub(crate) fn alpha(knots: &Knots, i: usize) -> Option<[f64; 3]> {
    let n = knots.vertex_count();
    if !knots.is_closed() && (i == 0 || i + 1 >= n) {
        return None;
    }
    let (hm, h) = (knots.h(i as isize - 1), knots.h(i as isize));
    let r = (2.0 / (hm + h)).sqrt();
    let a1 = r / hm;
    let a3 = r / h;
    Some([a1, -a1 - a3, a3])
}

/// Index of vertex i + o with periodic wrap (closed) — callers only ask in range for open.
fn wrap(i: usize, o: isize, n: usize) -> usize {
    (i as isize + o).rem_euclid(n as isize) as usize
}

/// A p (one row per vertex, d columns; zero rows at the ends of an open curve).
pub(crate) fn apply_a(knots: &Knots, p: &Points) -> Vec<f64> {
    let n = p.len();
    let d = p.dim();
    let mut out = vec![0.0; n * d];
    for i in 0..n {
        if let Some(a) = alpha(knots, i) {
            for (o, &ao) in a.iter().enumerate() {
                let v = p.point(wrap(i, o as isize - 1, n));
                for c in 0..d {
                    out[i * d + c] += ao * v[c];
                }
            }
        }
    }
    out
}

/// H p = Aᵀ(A p), vertex-major with d columns.
pub(crate) fn apply_h(knots: &Knots, p: &Points) -> Vec<f64> {
    let n = p.len();
    let d = p.dim();
    let ap = apply_a(knots, p);
    let mut out = vec![0.0; n * d];
    for i in 0..n {
        if let Some(a) = alpha(knots, i) {
            for (o, &ao) in a.iter().enumerate() {
                let j = wrap(i, o as isize - 1, n);
                for c in 0..d {
                    out[j * d + c] += ao * ap[i * d + c];
                }
            }
        }
    }
    out
}

/// E = ½|Ap|² = Σ |s_i − s_{i−1}|² / (h_{i−1} + h_i) (Kersey (2.1)).
pub(crate) fn energy(knots: &Knots, p: &Points) -> f64 {
    0.5 * apply_a(knots, p).iter().map(|x| x * x).sum::<f64>()
}

/// max_i Σ_j |H_ij| (the ∞-norm of H), the scale against which Hp is judged.
pub(crate) fn h_norm_inf(knots: &Knots) -> f64 {
    let n = knots.vertex_count();
    let mut row = vec![0.0; n];
    // |H_ij| ≤ Σ_r |A_ri||A_rj|, so Σ_j |H_ij| ≤ Σ_r |A_ri| Σ_j |A_rj|: a cheap, tight bound.
    for r in 0..n {
        if let Some(a) = alpha(knots, r) {
            let s: f64 = a.iter().map(|x| x.abs()).sum();
            for (o, &ao) in a.iter().enumerate() {
                row[wrap(r, o as isize - 1, n)] += ao.abs() * s;
            }
        }
    }
    row.into_iter().fold(0.0, f64::max)
}
