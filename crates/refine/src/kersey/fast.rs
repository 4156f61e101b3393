//! Interpolatory refinement (3.3) by static condensation of the data spans: O(N) work with
//! only short, independent dependency chains, plus one tridiagonal system of size n.
//!
//! Write E = ½ Σ_r (a_r · p)², a_r the α-row r of A (Kersey §2). With the data vertices
//! v_i = m·i (m = k + 1) fixed at q_i, the rows split in two kinds:
//! - the k *span rows* r = v_i + 1 … v_i + k of data span i involve only the vertices
//!   v_i … v_{i+1} of that span. Collect them as e_i = B_i x_i + c_i, with x_i the k free
//!   vertices, B_i the k×k tridiagonal matrix of their α's (nonsingular: weakly diagonally
//!   dominant with strict dominance in its first and last rows), and c_i the fixed ends;
//! - the *data rows* s_i = a_{v_i} · p, coupling the last free vertex of span i − 1 with the first
//!   of span i (all of them for a closed curve; the first and last rows of an open curve are zero).
//!
//! x_i ↦ e_i is a bijection, so minimize over e_i: stationarity gives
//! e_i = −(α_{v_i,3} s_i) g_i − (α_{v_{i+1},1} s_{i+1}) h_i with g_i = B_i⁻ᵀ e_first and
//! h_i = B_i⁻ᵀ e_last (so p_{v_i+1} = g_i · (e_i − c_i), p_{v_{i+1}−1} = h_i · (e_i − c_i)). Substituting into
//! the definition of the data rows gives a symmetric positive definite tridiagonal system
//! (cyclic for closed curves) for the n data-row values s_i:
//!
//! s_i (1 + α_{v_i,1}² h_{i−1}·h_{i−1} + α_{v_i,3}² g_i·g_i) + s_{i−1} α_{v_i,1} α_{v_{i−1},3} g_{i−1}·h_{i−1}
//!   + s_{i+1} α_{v_i,3} α_{v_{i+1},1} g_i·h_i = α_{v_i,2} q_i − α_{v_i,1} h_{i−1}·c_{i−1} − α_{v_i,3} g_i·c_i,
//!
//! after which every span is recovered independently, x_i = B_i⁻¹(e_i − c_i). The cyclic system
//! is solved by Sherman–Morrison on a tridiagonal LDLᵀ.

use divdiff::{Knots, Points};

use super::operator::Stencil;
use crate::Error;

/// Tridiagonal LU of the span matrix B (sub `a`, diagonal `b`, super `c`, each of length k):
/// B = L U, L unit lower bidiagonal with multipliers `l`, U upper bidiagonal with diagonal u and
/// super-diagonal `c`.
/// `u` holds the reciprocals 1/u_j of the pivots (one division per row, on the chain anyway;
/// every later use multiplies).
#[inline]
fn span_lu(rows: &[[f64; 3]], l: &mut [f64], u: &mut [f64]) -> Result<(), usize> {
    let k = rows.len();
    let mut inv = 1.0 / rows[0][1];
    u[0] = inv;
    for j in 1..k {
        l[j] = rows[j][0] * inv;
        inv = 1.0 / (rows[j][1] - l[j] * rows[j - 1][2]);
        u[j] = inv;
    }
    // B has α_2 = −α_1 − α_3 < 0 on the diagonal: the pivots stay negative and bounded away from
    // zero by its diagonal dominance; anything else means the knots were not valid.
    match u[..k]
        .iter()
        .position(|&x| x.is_nan() || x >= 0.0 || x.is_infinite())
    {
        Some(j) => Err(j),
        None => Ok(()),
    }
}

/// First and last rows of B⁻¹ as vectors g = B⁻ᵀ e_0 and h = B⁻ᵀ e_{k−1}.
#[inline]
fn span_gh(rows: &[[f64; 3]], l: &[f64], u: &[f64], g: &mut [f64], h: &mut [f64]) {
    let k = rows.len();
    // Bᵀ = Uᵀ Lᵀ. g: Uᵀ w = e_0 (forward), Lᵀ g = w (backward).
    let mut w = u[0];
    g[0] = w;
    for j in 1..k {
        w = -rows[j - 1][2] * w * u[j];
        g[j] = w;
    }
    for j in (0..k - 1).rev() {
        g[j] -= l[j + 1] * g[j + 1];
    }
    // h: Uᵀ w = e_{k−1} gives w = e_{k−1}/u_{k−1}; Lᵀ h = w.
    h[k - 1] = u[k - 1];
    for j in (0..k - 1).rev() {
        h[j] = -l[j + 1] * h[j + 1];
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves the interpolation problem (3.3) on `knots` with q_i fixed at vertex `stride · i`,
/// using the α-rows in `stencil` (built from the same knots).
///
/// # Errors
/// [`Error::Energy`] (`Singular`) naming a vertex whose pivot is not of the sign and size the
/// structure guarantees (impossible for valid knots; reported rather than assumed).
pub(crate) fn interpolate(
    knots: &Knots,
    stencil: &Stencil,
    q: &Points,
    stride: usize,
) -> Result<Points, Error> {
    let nv = knots.vertex_count();
    let d = q.dim();
    let n = q.len();
    let closed = knots.is_closed();
    let m = stride;
    let k = m - 1;
    let spans = if closed { n } else { n - 1 };
    let rows = &stencil.rows;
    let qn = |i: usize| q.point(if i == n { 0 } else { i });
    let singular = |v: usize| Error::from(energy::Error::Singular { vertex: v });

    // Pass 1: per span, G = g·g, X = g·h, Y = h·h and the d-vectors g·c, h·c.
    let mut gg = vec![0.0; spans];
    let mut gh = vec![0.0; spans];
    let mut hh = vec![0.0; spans];
    let mut gc = vec![0.0; spans * d];
    let mut hc = vec![0.0; spans * d];
    let (mut l, mut u, mut g, mut h) = (vec![0.0; k], vec![0.0; k], vec![0.0; k], vec![0.0; k]);
    for i in 0..spans {
        let a = i * m;
        let span_rows = &rows[a + 1..a + m];
        span_lu(span_rows, &mut l, &mut u).map_err(|j| singular(a + 1 + j))?;
        span_gh(span_rows, &l, &u, &mut g, &mut h);
        gg[i] = dot(&g, &g);
        gh[i] = dot(&g, &h);
        hh[i] = dot(&h, &h);
        // c = α_{a+1,1} q_i e_0 + α_{a+k,3} q_{i+1} e_{k−1}.
        let (c0, c1) = (span_rows[0][0], span_rows[k - 1][2]);
        let (qa, qb) = (qn(i), qn(i + 1));
        for c in 0..d {
            gc[i * d + c] = c0 * qa[c] * g[0] + c1 * qb[c] * g[k - 1];
            hc[i * d + c] = c0 * qa[c] * h[0] + c1 * qb[c] * h[k - 1];
        }
    }

    // The data-row system for s (rows 0..n closed, 1..n−1 open), tridiagonal with off-diagonal
    // e_i between unknowns i and i + 1.
    let first = usize::from(!closed);
    let last = if closed { n } else { n - 1 }; // exclusive
    let size = last.saturating_sub(first);
    let mut s = vec![0.0; n * d];
    if size > 0 {
        let mut diag = vec![0.0; size];
        let mut off = vec![0.0; size]; // off[j] couples unknowns j and j+1 (cyclic: last ↔ 0)
        let mut rhs = vec![0.0; size * d];
        for (j, i) in (first..last).enumerate() {
            let ar = rows[i * m];
            let prev = if i == 0 { spans - 1 } else { i - 1 };
            diag[j] = 1.0 + ar[0] * ar[0] * hh[prev] + ar[2] * ar[2] * gg[i % spans];
            let next = i + 1;
            if next < last || closed {
                let an = rows[(next % n) * m];
                off[j] = ar[2] * an[0] * gh[i % spans];
            }
            let qi = q.point(i);
            for c in 0..d {
                rhs[j * d + c] =
                    ar[1] * qi[c] - ar[0] * hc[prev * d + c] - ar[2] * gc[(i % spans) * d + c];
            }
        }
        solve_tridiagonal(&mut diag, &mut off, &mut rhs, d, closed && size >= 3)
            .map_err(|j| singular((first + j) * m))?;
        for (j, i) in (first..last).enumerate() {
            s[i * d..(i + 1) * d].copy_from_slice(&rhs[j * d..(j + 1) * d]);
        }
    }

    // Pass 2: recover every span, x = B⁻¹(e − c), e = −μ g − ν h.
    let mut x = vec![0.0; nv * d];
    for i in 0..n {
        x[i * m * d..(i * m + 1) * d].copy_from_slice(q.point(i));
    }
    let mut f = vec![0.0; k * d];
    for i in 0..spans {
        let a = i * m;
        let span_rows = &rows[a + 1..a + m];
        span_lu(span_rows, &mut l, &mut u).map_err(|j| singular(a + 1 + j))?;
        span_gh(span_rows, &l, &u, &mut g, &mut h);
        let (c0, c1) = (span_rows[0][0], span_rows[k - 1][2]);
        let (qa, qb) = (qn(i), qn(i + 1));
        let right = if i + 1 == n { 0 } else { i + 1 };
        for c in 0..d {
            // μ = α_{v_i,3} s_i, ν = α_{v_{i+1},1} s_{i+1} (zero for the end rows of open curves).
            let mu = rows[a][2] * s[i * d + c];
            let nu = rows[right * m][0] * s[right * d + c];
            for j in 0..k {
                f[j * d + c] = -mu * g[j] - nu * h[j];
            }
            f[c] -= c0 * qa[c];
            f[(k - 1) * d + c] -= c1 * qb[c];
        }
        // B x = f: forward with L, backward with U (super-diagonal = α_{·,3}).
        for j in 1..k {
            for c in 0..d {
                f[j * d + c] -= l[j] * f[(j - 1) * d + c];
            }
        }
        for c in 0..d {
            f[(k - 1) * d + c] *= u[k - 1];
        }
        for j in (0..k - 1).rev() {
            for c in 0..d {
                f[j * d + c] = (f[j * d + c] - span_rows[j][2] * f[(j + 1) * d + c]) * u[j];
            }
        }
        x[(a + 1) * d..(a + m) * d].copy_from_slice(&f);
    }
    Ok(Points::new(d, x)?)
}

/// Solves the symmetric tridiagonal (or, with `cyclic`, cyclic tridiagonal: `off[len−1]`
/// couples the last unknown with the first) positive definite system in place, for `d`
/// right-hand-side columns stored row-major in `rhs`. Returns the index of a non-positive pivot.
pub(super) fn solve_tridiagonal(
    diag: &mut [f64],
    off: &mut [f64],
    rhs: &mut [f64],
    d: usize,
    cyclic: bool,
) -> Result<(), usize> {
    let size = diag.len();
    if !cyclic {
        return ldl_solve(diag, &off[..size.saturating_sub(1)], rhs, d, None);
    }
    // Sherman–Morrison: A = T + v vᵀ with v = (γ, 0, …, 0, corner/γ) and T the tridiagonal part
    // with its first and last diagonal entries reduced by γ and corner²/γ.
    let corner = off[size - 1];
    let gamma = -diag[0];
    diag[0] -= gamma;
    diag[size - 1] -= corner * corner / gamma;
    let mut v = vec![0.0; size];
    v[0] = gamma;
    v[size - 1] = corner;
    ldl_solve(diag, &off[..size - 1], rhs, d, Some(&mut v))?;
    // v now holds T⁻¹v (with v = (γ, 0, …, corner)); vᵀ(·) uses the same v.
    let vt = |y0: f64, yl: f64| y0 + corner / gamma * yl;
    let denom = 1.0 + vt(v[0], v[size - 1]);
    for c in 0..d {
        let f = vt(rhs[c], rhs[(size - 1) * d + c]) / denom;
        for j in 0..size {
            rhs[j * d + c] -= f * v[j];
        }
    }
    Ok(())
}

/// LDLᵀ of a symmetric tridiagonal matrix (diagonal `diag`, overwritten with the reciprocal
/// pivots; off-diagonal `off`), solving for the `d` columns of `rhs` and, if given, one extra
/// column `extra`. Pivots must be positive.
fn ldl_solve(
    diag: &mut [f64],
    off: &[f64],
    rhs: &mut [f64],
    d: usize,
    mut extra: Option<&mut Vec<f64>>,
) -> Result<(), usize> {
    let size = diag.len();
    // diag[j] ends as the reciprocal pivot 1/D_j: one division per row, the rest multiplies.
    let mut lm = vec![0.0; size];
    for j in 0..size {
        if j > 0 {
            lm[j] = off[j - 1] * diag[j - 1];
            diag[j] -= lm[j] * off[j - 1];
            for c in 0..d {
                rhs[j * d + c] -= lm[j] * rhs[(j - 1) * d + c];
            }
            if let Some(e) = extra.as_deref_mut() {
                e[j] -= lm[j] * e[j - 1];
            }
        }
        if diag[j].is_nan() || diag[j] <= 0.0 {
            return Err(j);
        }
        diag[j] = 1.0 / diag[j];
    }
    for j in (0..size).rev() {
        for c in 0..d {
            let mut y = rhs[j * d + c] * diag[j];
            if j + 1 < size {
                y -= lm[j + 1] * rhs[(j + 1) * d + c];
            }
            rhs[j * d + c] = y;
        }
        if let Some(e) = extra.as_deref_mut() {
            let mut y = e[j] * diag[j];
            if j + 1 < size {
                y -= lm[j + 1] * e[j + 1];
            }
            e[j] = y;
        }
    }
    Ok(())
}
