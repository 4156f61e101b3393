//! The energy (2.1), its gradient Hp and the jumps jmp = ½Hp, applied matrix-free from the
//! α-stencil of Kersey §2 (math.md §1). Used for the certificates, so they are computed
//! independently of whichever solver produced the points. Everything is one streaming pass
//! over the vertices; the periodic wrap of a closed curve is handled at the two ends only.

use divdiff::{Knots, Points};

/// The rows of A: row i is (α_{i,1}, α_{i,2}, α_{i,3}) on vertices i − 1, i, i + 1 (wrapping for
/// closed curves); the first and last rows of an open curve are zero.
pub(crate) struct Stencil {
    pub rows: Vec<[f64; 3]>,
    pub closed: bool,
}

/// α of the row between spans of lengths `hl` (left) and `hr` (right).
#[inline(always)]
pub(crate) fn alpha_row(hl: f64, hr: f64) -> [f64; 3] {
    let r = (2.0 / (hl + hr)).sqrt();
    let a1 = r / hl;
    let a3 = r / hr;
    [a1, -a1 - a3, a3]
}

/// Row `v` of A on the knot values `t` of an `nv`-vertex curve (as [`Stencil`] stores it): the
/// spans on either side of vertex v, h_{−1} = h_{N−1} for a closed curve (the periodic extension,
/// math.md §1), a zero row at the ends of an open one.
#[inline]
pub(crate) fn vertex_row(t: &[f64], v: usize, nv: usize, closed: bool) -> [f64; 3] {
    if closed {
        let hl = if v == 0 {
            t[nv] - t[nv - 1]
        } else {
            t[v] - t[v - 1]
        };
        alpha_row(hl, t[v + 1] - t[v])
    } else if v == 0 || v + 1 == nv {
        [0.0; 3]
    } else {
        alpha_row(t[v] - t[v - 1], t[v + 1] - t[v])
    }
}

impl Stencil {
    pub(crate) fn new(knots: &Knots) -> Self {
        let t = knots.values();
        let n = knots.vertex_count();
        let closed = knots.is_closed();
        let rows = (0..n).map(|v| vertex_row(t, v, n, closed)).collect();
        Stencil { rows, closed }
    }

    /// The three vertex indices of row i.
    #[inline]
    pub(crate) fn cols(&self, i: usize, n: usize) -> [usize; 3] {
        let l = if i == 0 { n - 1 } else { i - 1 };
        let r = if i + 1 == n { 0 } else { i + 1 };
        [l, i, r]
    }

    pub(crate) fn row_range(&self, n: usize) -> std::ops::Range<usize> {
        if self.closed {
            0..n
        } else {
            1..n.saturating_sub(1)
        }
    }

    /// A p (one row per vertex, d columns), in difference form α₁(x_l − x_m) + α₃(x_r − x_m)
    /// (α₂ = −α₁ − α₃ exactly, [`alpha_row`]): the rounding scales with the steps between
    /// vertices rather than with |x|.
    pub(crate) fn apply_a(&self, p: &Points) -> Vec<f64> {
        let n = p.len();
        let d = p.dim();
        let x = p.coords();
        let mut out = vec![0.0; n * d];
        for i in self.row_range(n) {
            let a = self.rows[i];
            let [l, m, r] = self.cols(i, n);
            for c in 0..d {
                let xm = x[m * d + c];
                out[i * d + c] = a[0] * (x[l * d + c] - xm) + a[2] * (x[r * d + c] - xm);
            }
        }
        out
    }

    /// out = H x for flat vertex-major x (N·d entries, d columns), without temporaries: each
    /// row residual (Ax)_i, in difference form, is scattered as soon as it is formed. Returns
    /// ½|Ax|².
    pub(crate) fn apply_h_flat(&self, x: &[f64], d: usize, out: &mut [f64]) -> f64 {
        let n = x.len() / d;
        out.fill(0.0);
        let mut energy = 0.0;
        for i in self.row_range(n) {
            let a = self.rows[i];
            let [l, m, r] = self.cols(i, n);
            for c in 0..d {
                let xm = x[m * d + c];
                let v = a[0] * (x[l * d + c] - xm) + a[2] * (x[r * d + c] - xm);
                energy += v * v;
                out[l * d + c] += a[0] * v;
                out[m * d + c] += a[1] * v;
                out[r * d + c] += a[2] * v;
            }
        }
        0.5 * energy
    }

    /// (H p, ½|Ap|²) with H = AᵀA.
    pub(crate) fn apply_h(&self, p: &Points) -> (Vec<f64>, f64) {
        let n = p.len();
        let d = p.dim();
        let ap = self.apply_a(p);
        let energy = 0.5 * ap.iter().map(|v| v * v).sum::<f64>();
        let mut out = vec![0.0; n * d];
        for i in self.row_range(n) {
            let a = self.rows[i];
            let [l, m, r] = self.cols(i, n);
            for c in 0..d {
                let v = ap[i * d + c];
                out[l * d + c] += a[0] * v;
                out[m * d + c] += a[1] * v;
                out[r * d + c] += a[2] * v;
            }
        }
        (out, energy)
    }
}

/// H p = Aᵀ(A p), vertex-major with d columns.
pub(crate) fn apply_h(knots: &Knots, p: &Points) -> Vec<f64> {
    Stencil::new(knots).apply_h(p).0
}
