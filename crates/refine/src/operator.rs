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
#[inline]
pub(crate) fn alpha_row(hl: f64, hr: f64) -> [f64; 3] {
    let r = (2.0 / (hl + hr)).sqrt();
    let a1 = r / hl;
    let a3 = r / hr;
    [a1, -a1 - a3, a3]
}

impl Stencil {
    pub(crate) fn new(knots: &Knots) -> Self {
        let t = knots.values();
        let n = knots.vertex_count();
        let closed = knots.is_closed();
        let mut rows = vec![[0.0; 3]; n];
        for i in 1..n - 1 {
            rows[i] = alpha_row(t[i] - t[i - 1], t[i + 1] - t[i]);
        }
        if closed {
            // h_{−1} = h_{N−1}: the periodic extension (math.md §1).
            rows[0] = alpha_row(t[n] - t[n - 1], t[1] - t[0]);
            rows[n - 1] = alpha_row(t[n - 1] - t[n - 2], t[n] - t[n - 1]);
        }
        Stencil { rows, closed }
    }

    /// The three vertex indices of row i.
    #[inline]
    fn cols(&self, i: usize, n: usize) -> [usize; 3] {
        let l = if i == 0 { n - 1 } else { i - 1 };
        let r = if i + 1 == n { 0 } else { i + 1 };
        [l, i, r]
    }

    fn row_range(&self, n: usize) -> std::ops::Range<usize> {
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

/// What one streaming pass over the vertices yields for the certificates.
pub(crate) struct Pass {
    /// ½|Ap|².
    pub energy: f64,
    /// max |(Hp)_j| over vertices j that are not data vertices (one stationarity block).
    pub free_gradient: f64,
    /// (Hp)_v at the data vertices 0, stride, 2·stride, … (n × d, row-major).
    pub data_gradient: Vec<f64>,
    /// A bound on ‖H‖_∞: max_j Σ_r |A_rj| Σ_i |A_ri|.
    pub h_norm: f64,
    /// max_j |p_j − center|_∞.
    pub extent: f64,
    /// max_j |p_{j+1} − p_j|_∞ (the largest coordinate step between consecutive vertices).
    pub step: f64,
}

impl Stencil {
    /// One pass per coordinate computing Hp (kept only at the data vertices, which sit at
    /// multiples of `stride`), E, ‖H‖_∞ and the extent of p about `center`, without O(N)
    /// temporaries. Each row residual (Ap)_r is computed once and slides through a window of
    /// three: (Hp)_j = α_{j−1,3}(Ap)_{j−1} + α_{j,2}(Ap)_j + α_{j+1,1}(Ap)_{j+1}.
    pub(crate) fn pass(&self, p: &Points, stride: usize, center: &[f64]) -> Pass {
        let n = p.len();
        let d = p.dim();
        let x = p.coords();
        let nd = n.div_ceil(stride);
        let mut data_gradient = vec![0.0; nd * d];
        let (mut energy, mut free_gradient, mut extent, mut step) = (0.0, 0.0f64, 0.0f64, 0.0f64);
        let closed = self.closed;
        let rows = &self.rows;
        // Rows outside an open curve (and its first and last rows) are zero rows.
        let row = |r: isize| -> [f64; 3] {
            if r >= 0 && (r as usize) < n {
                rows[r as usize]
            } else if closed {
                rows[r.rem_euclid(n as isize) as usize]
            } else {
                [0.0; 3]
            }
        };
        for c in 0..d {
            let at = |j: isize| x[j.rem_euclid(n as isize) as usize * d + c];
            // (Ap)_r in difference form α₁(p_{r−1} − p_r) + α₃(p_{r+1} − p_r) (α₂ = −α₁ − α₃):
            // the rounding error scales with the local spacing, not with |p|.
            let res_wrapped = |r: isize| {
                let a = row(r);
                let x0 = at(r);
                a[0] * (at(r - 1) - x0) + a[2] * (at(r + 1) - x0)
            };
            // Vertex j given the residuals of rows j − 1, j, j + 1.
            // Data vertices are j = stride·i: a phase counter instead of a division per vertex.
            let (mut phase, mut data) = (0, 0);
            let mut visit = |j: usize, rp: f64, rc: f64, rn: f64, wp: f64, wn: f64, next: f64| {
                let x0 = x[j * d + c];
                let hp = wp * rp + rows[j][1] * rc + wn * rn;
                energy += rc * rc;
                extent = extent.max((x0 - center[c]).abs());
                step = step.max((next - x0).abs());
                if phase == 0 {
                    data_gradient[data * d + c] = hp;
                    data += 1;
                } else {
                    free_gradient = free_gradient.max(hp.abs());
                }
                phase = if phase + 1 == stride { 0 } else { phase + 1 };
            };
            let ends = |j: usize| {
                let ji = j as isize;
                // The step from the last vertex wraps to the first for open curves too: the
                // force scale has always included that end-to-end chord (ROBUSTNESS.md).
                let next = at(ji + 1);
                (
                    res_wrapped(ji - 1),
                    res_wrapped(ji),
                    res_wrapped(ji + 1),
                    row(ji - 1)[2],
                    row(ji + 1)[0],
                    next,
                )
            };
            if n < 4 {
                for j in 0..n {
                    let (rp, rc, rn, wp, wn, next) = ends(j);
                    visit(j, rp, rc, rn, wp, wn, next);
                }
                continue;
            }
            let (rp, rc, rn, wp, wn, next) = ends(0);
            visit(0, rp, rc, rn, wp, wn, next);
            // Interior: no index wraps; each row residual is computed once.
            let (mut rp, mut rc) = (rc, rn);
            for j in 1..n - 2 {
                let a = rows[j + 1];
                let (xl, x0, xr) = (x[j * d + c], x[(j + 1) * d + c], x[(j + 2) * d + c]);
                let rn = a[0] * (xl - x0) + a[2] * (xr - x0);
                visit(j, rp, rc, rn, rows[j - 1][2], a[0], x0);
                (rp, rc) = (rc, rn);
            }
            for j in n - 2..n {
                let (rp, rc, rn, wp, wn, next) = ends(j);
                visit(j, rp, rc, rn, wp, wn, next);
            }
        }
        // ‖H‖_∞ bound: Σ_r |A_rj| Σ_i |A_ri| over the three rows through vertex j.
        let rowsum = |a: [f64; 3]| a[0].abs() + a[1].abs() + a[2].abs();
        let mut h_norm: f64 = 0.0;
        for j in 0..n as isize {
            let (ap, ac, an) = (row(j - 1), row(j), row(j + 1));
            let hn = ap[2].abs() * rowsum(ap) + ac[1].abs() * rowsum(ac) + an[0].abs() * rowsum(an);
            h_norm = h_norm.max(hn);
        }
        Pass {
            energy: 0.5 * energy,
            free_gradient,
            data_gradient,
            h_norm,
            extent,
            step,
        }
    }
}
