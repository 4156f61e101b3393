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

    /// A p (one row per vertex, d columns).
    pub(crate) fn apply_a(&self, p: &Points) -> Vec<f64> {
        let n = p.len();
        let d = p.dim();
        let x = p.coords();
        let mut out = vec![0.0; n * d];
        for i in self.row_range(n) {
            let a = self.rows[i];
            let [l, m, r] = self.cols(i, n);
            for c in 0..d {
                out[i * d + c] = a[0] * x[l * d + c] + a[1] * x[m * d + c] + a[2] * x[r * d + c];
            }
        }
        out
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
    /// One pass computing Hp (kept only at the data vertices, which sit at multiples of
    /// `stride`), E, ‖H‖_∞ and the extent of p about `center`, without O(N) temporaries.
    /// (Ap)_r is evaluated three times per vertex rather than stored: flops are cheaper here
    /// than a fresh N·d buffer.
    pub(crate) fn pass(&self, p: &Points, stride: usize, center: &[f64]) -> Pass {
        let n = p.len();
        let d = p.dim();
        let x = p.coords();
        let nd = n.div_ceil(stride);
        let mut data_gradient = vec![0.0; nd * d];
        let rowsum = |r: usize| {
            let a = self.rows[r];
            a[0].abs() + a[1].abs() + a[2].abs()
        };
        let (mut energy, mut free_gradient, mut h_norm, mut extent) = (0.0, 0.0f64, 0.0f64, 0.0f64);
        let mut step: f64 = 0.0;
        let mut phase = 0;
        let mut hp = vec![0.0; d];
        for j in 0..n {
            let jp = if j == 0 { n - 1 } else { j - 1 };
            let jn = if j + 1 == n { 0 } else { j + 1 };
            let jpp = if jp == 0 { n - 1 } else { jp - 1 };
            let jnn = if jn + 1 == n { 0 } else { jn + 1 };
            // Rows outside an open curve (and its first and last rows) are zero rows.
            let (ap, ac, an) = (self.rows[jp], self.rows[j], self.rows[jn]);
            let wp = if j > 0 || self.closed { ap[2] } else { 0.0 };
            let wn = if j + 1 < n || self.closed { an[0] } else { 0.0 };
            let wc = ac[1];
            for c in 0..d {
                let xm2 = x[jpp * d + c];
                let xm1 = x[jp * d + c];
                let x0 = x[j * d + c];
                let xp1 = x[jn * d + c];
                let xp2 = x[jnn * d + c];
                // Difference form α₁(p_{i−1} − p_i) + α₃(p_{i+1} − p_i) (α₂ = −α₁ − α₃): the
                // rounding error scales with the local spacing, not with |p|.
                let rp = ap[0] * (xm2 - xm1) + ap[2] * (x0 - xm1);
                let rc = ac[0] * (xm1 - x0) + ac[2] * (xp1 - x0);
                let rn = an[0] * (x0 - xp1) + an[2] * (xp2 - xp1);
                step = step.max((xp1 - x0).abs());
                energy += rc * rc;
                hp[c] = wp * rp + wc * rc + wn * rn;
                extent = extent.max((x0 - center[c]).abs());
            }
            let hn = wc.abs() * rowsum(j) + wp.abs() * rowsum(jp) + wn.abs() * rowsum(jn);
            h_norm = h_norm.max(hn);
            if phase == 0 {
                let i = j / stride;
                data_gradient[i * d..(i + 1) * d].copy_from_slice(&hp);
            } else {
                free_gradient = hp.iter().fold(free_gradient, |a, v| a.max(v.abs()));
            }
            phase = if phase + 1 == stride { 0 } else { phase + 1 };
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
