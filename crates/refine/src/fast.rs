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
//! is solved by `banded`'s tridiagonal LDLᵀ (bordered when cyclic).

use banded::vector::dot;
use divdiff::{Knots, Points};

use crate::operator::{alpha_row, Stencil};
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
    match u[..k].iter().position(|&x| bad_pivot(x)) {
        Some(j) => Err(j),
        None => Ok(()),
    }
}

/// Whether a reciprocal pivot of a span's LU is not what B's structure guarantees (negative and
/// finite): the test of [`span_lu`] and [`SpanBlock::factor`].
#[inline(always)]
fn bad_pivot(x: f64) -> bool {
    x.is_nan() || x >= 0.0 || x.is_infinite()
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

/// The data-row condensation of the energy on fixed knots (module docs): with the data vertices
/// v_i = m·i at y_i, the data-row values s solve T s = K y, T symmetric positive definite
/// tridiagonal (cyclic for closed curves), K tridiagonal (cyclic) on the data points; the
/// energy minimized over the free vertices is E(y) = ½ Σ_coords sᵀ K y = ½ (Ky)ᵀ T⁻¹ (Ky), and
/// its gradient is Kᵀ s = (Hp)_{v_i}. (With s = L e + K y and e = −Lᵀ s, T = I + L Lᵀ and
/// E = ½|e|² + ½|s|² = ½ sᵀ T s.)
pub(crate) struct Condensation {
    /// Number of data points n.
    pub n: usize,
    /// The vertex of each data point (increasing; `new` spaces them `stride` apart).
    pub vertices: Vec<usize>,
    /// Whether the curve is closed.
    pub closed: bool,
    /// The first data row with an unknown (0 closed, 1 open: the end rows are zero).
    pub first: usize,
    /// T: diagonal (one entry per data row first..first + len).
    pub diag: Vec<f64>,
    /// T: `off[j]` couples rows j and j + 1 (cyclic: the last couples back to 0; unused on open
    /// curves).
    pub off: Vec<f64>,
    /// K: row j holds the coefficients on the data points first + j − 1, first + j,
    /// first + j + 1 (indices modulo n on closed curves).
    pub krows: Vec<[f64; 3]>,
    /// Per free vertex (indexed by vertex): its span's LU multiplier l and reciprocal pivot u,
    /// and the entries of g = B⁻ᵀe_first and h = B⁻ᵀe_last (pass 1's work, reused by pass 2).
    factors: [Vec<f64>; 4],
    /// Per span: [g·g, g·h, h·h, c0 g0, c1 g_{k−1}, c0 h0, c1 h_{k−1}] (reused by
    /// [`Condensation::at_vertices_reusing`]).
    spans: Vec<[f64; 7]>,
}

impl Condensation {
    #[cfg(test)]
    /// Pass 1 over the spans of `knots` (α-rows in `stencil`), n data points every `stride`
    /// vertices.
    ///
    /// # Errors
    /// [`Error::Energy`] (`Singular`) naming a vertex whose pivot is not of the sign and size the
    /// structure guarantees (impossible for valid knots; reported rather than assumed).
    pub(crate) fn new(
        knots: &Knots,
        stencil: &Stencil,
        n: usize,
        stride: usize,
    ) -> Result<Self, Error> {
        let vertices: Vec<usize> = (0..n).map(|i| i * stride).collect();
        Self::at_vertices_reusing(knots, stencil, vertices, None)
    }

    /// Pass 1 with the data points at the given increasing `vertices` of `knots` (any spacing
    /// of at least two; the first is vertex 0, and for an open curve the last is the last
    /// vertex): every other vertex is free. The working-set method of the balls solver
    /// condenses onto a subset of the data vertices this way, reusing the span work of `prev`,
    /// a condensation of the same knots onto other vertices: a span of `prev` that is also a
    /// span here (same ends) keeps its factors; only the others are factored (new points split
    /// a few spans between rounds).
    ///
    /// # Errors
    /// As [`Condensation::new`]; also `Singular` at a vertex whose span has no free vertex or
    /// where the vertex list is not of that shape (an internal error, reported).
    pub(crate) fn at_vertices_reusing(
        knots: &Knots,
        stencil: &Stencil,
        vertices: Vec<usize>,
        prev: Option<Condensation>,
    ) -> Result<Self, Error> {
        let closed = knots.is_closed();
        let n = vertices.len();
        let nv = knots.vertex_count();
        let spans = if closed { n } else { n - 1 };
        let rows = &stencil.rows;
        let singular = |v: usize| Error::from(energy::Error::Singular { vertex: v });
        // End of span i (exclusive: its right data vertex; nv for the closing span).
        let end = |i: usize| if i + 1 < n { vertices[i + 1] } else { nv };
        if vertices.first() != Some(&0) || (!closed && vertices.last() != Some(&(nv - 1))) {
            return Err(singular(0));
        }
        for (i, &a) in vertices[..spans].iter().enumerate() {
            if end(i) < a + 2 {
                return Err(singular(a));
            }
        }
        let prev = prev.filter(|p| p.closed == closed && p.factors[0].len() == nv);
        // The span factors, kept for the second pass (indexed by vertex; the data vertices'
        // entries are unused), and per span G = g·g, X = g·h, Y = h·h and the weights of its two
        // data points in g·c and h·c, c = α_{a+1,1} q_i e_0 + α_{b−1,3} q_{i+1} e_{k−1}:
        // [G, X, Y, c0 g0, c1 g_{k−1}, c0 h0, c1 h_{k−1}].
        let (mut factors, prev_spans) = match prev {
            Some(p) => (p.factors, Some((p.vertices, p.spans))),
            None => (
                [vec![0.0; nv], vec![0.0; nv], vec![0.0; nv], vec![0.0; nv]],
                None,
            ),
        };
        let mut span = vec![[0.0; 7]; spans];
        let [fl, fu, fg, fh] = &mut factors;
        for i in 0..spans {
            let (a, b) = (vertices[i], end(i));
            if let Some((pv, ps)) = &prev_spans {
                if let Ok(p) = pv.binary_search(&a) {
                    let pend = if p + 1 < pv.len() { pv[p + 1] } else { nv };
                    if pend == b && p < ps.len() {
                        span[i] = ps[p];
                        continue;
                    }
                }
            }
            let span_rows = &rows[a + 1..b];
            let (l, u, g, h) = (
                &mut fl[a + 1..b],
                &mut fu[a + 1..b],
                &mut fg[a + 1..b],
                &mut fh[a + 1..b],
            );
            span_lu(span_rows, l, u).map_err(|j| singular(a + 1 + j))?;
            span_gh(span_rows, l, u, g, h);
            span[i] = span_summary(span_rows, g, h);
        }

        let first = usize::from(!closed);
        let (diag, off, krows) = data_row_system(&span, n, closed, |i| rows[vertices[i]]);
        Ok(Condensation {
            n,
            vertices,
            closed,
            first,
            diag,
            off,
            krows,
            factors,
            spans: span,
        })
    }

    /// Number of data rows with an unknown (n closed, n − 2 open).
    pub(crate) fn len(&self) -> usize {
        self.diag.len()
    }

    /// The data point of column `t` (0, 1, 2) of K's row j.
    #[inline(always)]
    pub(crate) fn col(&self, j: usize, t: usize) -> usize {
        let c = self.first + j + t;
        if self.closed {
            (c + self.n - 1) % self.n
        } else {
            c - 1
        }
    }

    /// out = K y (row j, d columns), y with n × d entries. Evaluated in difference form,
    /// K_{j,0}(y_a − y_b) + K_{j,2}(y_c − y_b): K annihilates constants (constant data are
    /// interpolated with zero energy), so the rounding error scales with the steps between data
    /// points rather than with |y|.
    #[inline]
    pub(crate) fn apply_k(&self, y: &[f64], d: usize, out: &mut [f64]) {
        match d {
            1 => self.apply_k_d::<1>(y, out),
            2 => self.apply_k_d::<2>(y, out),
            3 => self.apply_k_d::<3>(y, out),
            _ => self.apply_k_any(y, d, out),
        }
    }

    /// [`Condensation::apply_k`] for a compile-time d: the rows that wrap around a closed curve
    /// are done apart, so the others index without a modulo.
    fn apply_k_d<const D: usize>(&self, y: &[f64], out: &mut [f64]) {
        let size = self.krows.len();
        if !self.closed {
            // Open: row j has columns j, j + 1, j + 2 (first = 1).
            for ((o, yw), kr) in out
                .chunks_exact_mut(D)
                .zip(y.windows(3 * D).step_by(D))
                .zip(&self.krows)
            {
                for e in 0..D {
                    o[e] = k_row(*kr, yw[e], yw[D + e], yw[2 * D + e]);
                }
            }
            return;
        }
        if size < 3 {
            return self.apply_k_any(y, D, out);
        }
        // Closed: row j has columns j − 1, j, j + 1 (first = 0).
        let yc = |i: usize| -> [f64; D] { std::array::from_fn(|e| y[i * D + e]) };
        let row = |j: usize, a: [f64; D], b: [f64; D], c: [f64; D], out: &mut [f64]| {
            let kr = self.krows[j];
            for e in 0..D {
                out[j * D + e] = k_row(kr, a[e], b[e], c[e]);
            }
        };
        row(0, yc(size - 1), yc(0), yc(1), out);
        let (mut a, mut b) = (yc(0), yc(1));
        for j in 1..size - 1 {
            let c = yc(j + 1);
            row(j, a, b, c, out);
            (a, b) = (b, c);
        }
        row(size - 1, a, b, yc(0), out);
    }

    fn apply_k_any(&self, y: &[f64], d: usize, out: &mut [f64]) {
        for (j, kr) in self.krows.iter().enumerate() {
            let (a, b, c) = (self.col(j, 0), self.col(j, 1), self.col(j, 2));
            for e in 0..d {
                out[j * d + e] = k_row(*kr, y[a * d + e], y[b * d + e], y[c * d + e]);
            }
        }
    }

    /// out = Kᵀ s (n × d), s with one row per data row.
    #[inline]
    pub(crate) fn apply_kt(&self, s: &[f64], d: usize, out: &mut [f64]) {
        match d {
            1 => self.apply_kt_d::<1>(s, out),
            2 => self.apply_kt_d::<2>(s, out),
            3 => self.apply_kt_d::<3>(s, out),
            _ => self.apply_kt_any(s, d, out),
        }
    }

    /// [`Condensation::apply_kt`] for a compile-time d, gathering per output point (column i of
    /// a closed curve collects rows i − 1, i, i + 1) without a modulo away from the ends.
    fn apply_kt_d<const D: usize>(&self, s: &[f64], out: &mut [f64]) {
        let size = self.krows.len();
        if !self.closed {
            // Open: column i gathers rows i − 2 (t = 2), i − 1 (t = 1), i (t = 0), in that order
            // (the order of `apply_kt_any`'s sums).
            let k = &self.krows;
            for (i, o) in out.chunks_exact_mut(D).enumerate() {
                for e in 0..D {
                    let mut v = 0.0;
                    if (2..size + 2).contains(&i) {
                        v += k[i - 2][2] * s[(i - 2) * D + e];
                    }
                    if (1..size + 1).contains(&i) {
                        v += k[i - 1][1] * s[(i - 1) * D + e];
                    }
                    if i < size {
                        v += k[i][0] * s[i * D + e];
                    }
                    o[e] = v;
                }
            }
            return;
        }
        if size < 3 {
            return self.apply_kt_any(s, D, out);
        }
        let k = &self.krows;
        // (The interior columns as one loop over windows of three rows, without a call or a
        // bounds check per point: the interior-point method's hottest pass.)
        let col = |i: usize, jp: usize, jn: usize, out: &mut [f64]| {
            for e in 0..D {
                out[i * D + e] =
                    k[jp][2] * s[jp * D + e] + k[i][1] * s[i * D + e] + k[jn][0] * s[jn * D + e];
            }
        };
        col(0, size - 1, 1, out);
        for ((o, sw), kw) in out[D..(size - 1) * D]
            .chunks_exact_mut(D)
            .zip(s.windows(3 * D).step_by(D))
            .zip(k.windows(3))
        {
            let (a, b, c) = (kw[0][2], kw[1][1], kw[2][0]);
            for e in 0..D {
                o[e] = a * sw[e] + b * sw[D + e] + c * sw[2 * D + e];
            }
        }
        col(size - 1, size - 2, 0, out);
    }

    fn apply_kt_any(&self, s: &[f64], d: usize, out: &mut [f64]) {
        out.fill(0.0);
        for (j, kr) in self.krows.iter().enumerate() {
            for (t, &kv) in kr.iter().enumerate() {
                let c = self.col(j, t);
                for e in 0..d {
                    out[c * d + e] += kv * s[j * d + e];
                }
            }
        }
    }

    /// Pass 2: the minimizing curve with the data vertices at y (n × d) and data-row values
    /// `s` (one row of d per data row first..first + len, i.e. T s = K y).
    ///
    /// # Errors
    /// As [`Condensation::new`].
    pub(crate) fn reconstruct(
        &self,
        knots: &Knots,
        stencil: &Stencil,
        y: &[f64],
        s: &[f64],
        d: usize,
    ) -> Result<Points, Error> {
        let nv = knots.vertex_count();
        let mut x = vec![0.0; nv * d];
        match d {
            1 => self.reconstruct_into::<1>(&stencil.rows, y, s, 1, &mut x),
            2 => self.reconstruct_into::<2>(&stencil.rows, y, s, 2, &mut x),
            3 => self.reconstruct_into::<3>(&stencil.rows, y, s, 3, &mut x),
            _ => self.reconstruct_into::<0>(&stencil.rows, y, s, d, &mut x),
        }
        Ok(Points::new(d, x)?)
    }

    /// [`Condensation::reconstruct`] into `x` (N × d), with d a compile-time constant for
    /// d = 1, 2, 3 (`D` = 0: `d`). Each span is solved in place in its slice of `x`.
    fn reconstruct_into<const D: usize>(
        &self,
        rows: &[[f64; 3]],
        y: &[f64],
        s: &[f64],
        d: usize,
        x: &mut [f64],
    ) {
        let d = if D == 0 { d } else { D };
        let nv = x.len() / d;
        let n = self.n;
        let vertices = &self.vertices;
        let end = |i: usize| if i + 1 < n { vertices[i + 1] } else { nv };
        let spans = if self.closed { n } else { n - 1 };
        let yp = |i: usize| {
            let i = if i == n { 0 } else { i };
            &y[i * d..(i + 1) * d]
        };
        // The data-row value of row i (zero for the end rows of an open curve).
        let srow = |i: usize, c: usize| {
            if i >= self.first && i - self.first < self.len() {
                s[(i - self.first) * d + c]
            } else {
                0.0
            }
        };
        let [fl, fu, fg, fh] = &self.factors;
        for (i, &v) in vertices.iter().enumerate() {
            x[v * d..(v + 1) * d].copy_from_slice(yp(i));
        }
        for i in 0..spans {
            let (a, b) = (vertices[i], end(i));
            let span_rows = &rows[a + 1..b];
            let (l, u, g, h) = (&fl[a + 1..b], &fu[a + 1..b], &fg[a + 1..b], &fh[a + 1..b]);
            let right = if i + 1 == n { 0 } else { i + 1 };
            let f = &mut x[(a + 1) * d..b * d];
            let factors = SpanFactors {
                rows: span_rows,
                l,
                u,
                g,
                h,
            };
            factors.solve(f, yp(i), yp(i + 1), d, |c| {
                // μ = α_{v_i,3} s_i, ν = α_{v_{i+1},1} s_{i+1}.
                (
                    rows[a][2] * srow(i, c),
                    rows[vertices[right]][0] * srow(right, c),
                )
            });
        }
    }
}

/// Solves the interpolation problem (3.3) on `knots` with q_i fixed at vertex `stride · i`, by
/// the condensation of the module docs in two streaming passes over the spans, without the
/// N-row stencil or per-vertex factors of [`Condensation`] (the working-set method keeps those
/// to reuse spans between rounds; interpolation solves once): pass 1 builds the spans' α-rows,
/// LU and the summaries g·g, g·h, h·h in a block-sized buffer and assembles T s = K y; pass 2
/// builds them again and writes the spans' free vertices. The arithmetic is that of
/// [`Condensation`] operation for operation (the α-rows as [`Stencil::new`] computes them), so
/// the results are the same to the last bit (tested) — at about half the memory traffic, which
/// is what the knot updates of Algorithm 4.1 paid for at N = 8·10⁵. The spans are factored
/// [`LANES`] at a time side by side ([`SpanBlock`]), which is what makes the passes fast on the
/// non-uniform knots of a knot update.
///
/// # Errors
/// [`Error::Energy`] (`Singular`) naming a vertex whose pivot is not of the sign and size the
/// structure guarantees (impossible for valid knots; reported rather than assumed).
pub(crate) fn interpolate(
    knots: &Knots,
    q: &Points,
    stride: usize,
    recycled: Option<Points>,
) -> Result<Points, Error> {
    let (data_rows, s) = data_row_values(knots, q, stride)?;
    let (d, n) = (q.dim(), q.len());
    let nv = knots.vertex_count();
    let closed = knots.is_closed();
    let spans = if closed { n } else { n - 1 };
    let t = knots.values();
    let k = stride - 1;
    let first = usize::from(!closed);

    // Pass 2: a block of LANES spans (each its data vertex, then its free vertices) per unit of
    // the output, in parallel chunks. (Pass 1 factored every span with the same arithmetic, so
    // a pivot cannot fail here; if it did, the span's NaN would be refused as a non-finite
    // point.)
    let p = crate::par::points_by_units(
        d,
        nv,
        recycled,
        stride * LANES,
        || SpanBlock::new(k),
        |block, unit, x| {
            crate::par::vectorized(Reconstruct {
                t,
                q,
                s: &s,
                first,
                data_rows: &data_rows,
                stride,
                spans,
                unit,
                block,
                x,
            })
        },
    );
    Ok(p?)
}

/// Pass 1 and the data-row solve of [`interpolate`] (module docs): the α-rows of the data
/// vertices and the data-row values s (data rows first …, `d` per row).
fn data_row_values(
    knots: &Knots,
    q: &Points,
    stride: usize,
) -> Result<(Vec<[f64; 3]>, Vec<f64>), Error> {
    let d = q.dim();
    let n = q.len();
    let nv = knots.vertex_count();
    let closed = knots.is_closed();
    let spans = if closed { n } else { n - 1 };
    let singular = |v: usize| Error::from(energy::Error::Singular { vertex: v });
    if stride < 2 || spans * stride + usize::from(!closed) != nv {
        return Err(singular(0));
    }
    let t = knots.values();
    let k = stride - 1;
    // Pass 1: per span [G, X, Y, c0 g0, c1 g_{k−1}, c0 h0, c1 h_{k−1}] (as `Condensation`) and
    // the α-row of its first (data) vertex, a block of LANES spans at a time in parallel runs of
    // blocks (`crate::par`), each run with its own block buffer. (An open curve's last data
    // row is a zero row, as its first.)
    let blocks = spans.div_ceil(LANES);
    let per_run = crate::par::units_per_chunk(stride * LANES);
    let failed = std::sync::atomic::AtomicUsize::new(usize::MAX);
    let (span, data_rows) = crate::par::unzip_blocks(
        blocks,
        per_run,
        1,
        || SpanBlock::new(k),
        |block, b| {
            let i0 = b * LANES;
            crate::par::vectorized(Summaries {
                t,
                stride,
                closed,
                i0,
                count: LANES.min(spans - i0),
                block,
                failed: &failed,
            })
        },
    );
    let failed = failed.into_inner();
    if failed != usize::MAX {
        return Err(singular(failed));
    }
    let mut span = span.into_flattened();
    span.truncate(spans);
    let mut data_rows = data_rows.into_flattened();
    data_rows.truncate(spans);
    data_rows.resize(n, [0.0; 3]);
    // T and K y (K's rows in difference form, as `Condensation::apply_k`), assembled straight
    // into the band and the right-hand side, rows in parallel chunks: each row is its own
    // formula ([`data_row`]).
    let first = usize::from(!closed);
    let last = if closed { n } else { n - 1 }; // exclusive
    let size = last.saturating_sub(first);
    let y = q.coords();
    let mut s = vec![0.0; size * d];
    if size > 0 {
        let (mut diag, mut off) = (vec![0.0; size], vec![[0.0]; size]);
        let row = |i: usize| data_rows[i];
        crate::par::band_rows(&mut diag, &mut off, &mut s, d, stride, |j, dg, of, r| {
            let i = first + j;
            let kr;
            (*dg, *of, kr) = data_row(&span, n, closed, &row, i);
            let ip = if i == 0 { n - 1 } else { i - 1 };
            let inext = if i + 1 == n { 0 } else { i + 1 };
            for (c, rc) in r.iter_mut().enumerate() {
                *rc = k_row(kr, y[ip * d + c], y[i * d + c], y[inext * d + c]);
            }
        });
        solve_band(diag, off, &mut s, d, closed && size >= 3)
            .map_err(|j| singular((first + j) * stride))?;
    }
    Ok((data_rows, s))
}

/// How many spans [`SpanBlock`] factors side by side: two vectors of four doubles, so that
/// each step of a span's chains (a division per row in the LU, products in g and h) has
/// independent work beside it instead of waiting on the one before.
const LANES: usize = 8;

/// The α-rows, LU, g and h of [`LANES`] spans of k free vertices each, stored row by row with
/// the spans side by side (`x[j][lane]`: row j of span `lane`), so that every step of
/// [`span_lu`] and [`span_gh`] runs on all spans at once. Each lane does exactly the scalar
/// functions' arithmetic in the same order: the same bits as one span at a time.
struct SpanBlock {
    /// The spans' sub-span lengths h_0 … h_k.
    h: Vec<[f64; LANES]>,
    /// α-rows: sub-diagonal (α₁), diagonal (α₂), super-diagonal (α₃).
    a: Vec<[f64; LANES]>,
    b: Vec<[f64; LANES]>,
    c: Vec<[f64; LANES]>,
    /// LU multipliers and reciprocal pivots, as [`span_lu`].
    l: Vec<[f64; LANES]>,
    u: Vec<[f64; LANES]>,
    /// First and last rows of B⁻¹, as [`span_gh`].
    g: Vec<[f64; LANES]>,
    hh: Vec<[f64; LANES]>,
    /// Pass 2's right-hand sides and solutions (row j, coordinate c at j·d + c).
    f: Vec<[f64; LANES]>,
}

impl SpanBlock {
    fn new(k: usize) -> Self {
        let rows = || vec![[0.0; LANES]; k];
        SpanBlock {
            h: vec![[0.0; LANES]; k + 1],
            a: rows(),
            b: rows(),
            c: rows(),
            l: rows(),
            u: rows(),
            g: rows(),
            hh: rows(),
            f: Vec::new(),
        }
    }

    /// Factors the `count` (1 ≤ count ≤ LANES) spans whose first vertices are `a0`,
    /// `a0 + stride`, …: their α-rows on the knots `t` (as
    /// [`vertex_row`](crate::operator::vertex_row): a free vertex's neighbours are in its
    /// span), LU, g and h; the unused lanes repeat the last span. Err: the vertex of the first
    /// pivot (in span order) that is not negative and finite.
    #[inline(always)]
    fn factor(&mut self, t: &[f64], a0: usize, stride: usize, count: usize) -> Result<(), usize> {
        let k = self.a.len();
        for lane in 0..LANES {
            let a = a0 + lane.min(count - 1) * stride;
            let tt = &t[a..a + k + 2];
            for (m, h) in self.h.iter_mut().enumerate() {
                h[lane] = tt[m + 1] - tt[m];
            }
        }
        // Every step on local rows of lanes (arrays by value): stores through the block's
        // separate vectors would keep the compiler from proving the lanes independent.
        for j in 0..k {
            let (hl, hr) = (self.h[j], self.h[j + 1]);
            let (mut x, mut y, mut z) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
            for lane in 0..LANES {
                [x[lane], y[lane], z[lane]] = alpha_row(hl[lane], hr[lane]);
            }
            (self.a[j], self.b[j], self.c[j]) = (x, y, z);
        }
        // span_lu, lane by lane.
        let mut inv = [0.0; LANES];
        let b0 = self.b[0];
        for lane in 0..LANES {
            inv[lane] = 1.0 / b0[lane];
        }
        self.u[0] = inv;
        for j in 1..k {
            let (aj, bj, cp) = (self.a[j], self.b[j], self.c[j - 1]);
            let mut lj = [0.0; LANES];
            for lane in 0..LANES {
                lj[lane] = aj[lane] * inv[lane];
                inv[lane] = 1.0 / (bj[lane] - lj[lane] * cp[lane]);
            }
            (self.l[j], self.u[j]) = (lj, inv);
        }
        // (A branch-free scan first: the position is wanted only on failure.)
        if self
            .u
            .iter()
            .flatten()
            .fold(false, |b, &x| b | bad_pivot(x))
        {
            for lane in 0..count {
                if let Some(j) = self.u.iter().position(|r| bad_pivot(r[lane])) {
                    return Err(a0 + lane * stride + 1 + j);
                }
            }
        }
        // span_gh, lane by lane.
        let mut w = self.u[0];
        self.g[0] = w;
        for j in 1..k {
            let (cp, uj) = (self.c[j - 1], self.u[j]);
            for lane in 0..LANES {
                w[lane] = -cp[lane] * w[lane] * uj[lane];
            }
            self.g[j] = w;
        }
        let mut next = self.g[k - 1];
        for j in (0..k - 1).rev() {
            let (mut gj, ln) = (self.g[j], self.l[j + 1]);
            for lane in 0..LANES {
                gj[lane] -= ln[lane] * next[lane];
            }
            (self.g[j], next) = (gj, gj);
        }
        let mut next = self.u[k - 1];
        self.hh[k - 1] = next;
        for j in (0..k - 1).rev() {
            let ln = self.l[j + 1];
            for lane in 0..LANES {
                next[lane] *= -ln[lane];
            }
            self.hh[j] = next;
        }
        Ok(())
    }

    /// Lane `lane`'s [`span_summary`] (dot products summed left to right, as
    /// [`banded::vector::dot`]).
    #[inline(always)]
    fn summary(&self, lane: usize) -> [f64; 7] {
        let k = self.a.len();
        let (g, h) = (&self.g, &self.hh);
        let (mut gg, mut gh, mut hh) = (-0.0, -0.0, -0.0);
        for j in 0..k {
            gg += g[j][lane] * g[j][lane];
            gh += g[j][lane] * h[j][lane];
            hh += h[j][lane] * h[j][lane];
        }
        let (c0, c1) = (self.a[0][lane], self.c[k - 1][lane]);
        [
            gg,
            gh,
            hh,
            c0 * g[0][lane],
            c1 * g[k - 1][lane],
            c0 * h[0][lane],
            c1 * h[k - 1][lane],
        ]
    }

    /// The α-rows of the data vertices a0, a0 + stride, … (the first vertex of each of the
    /// `rows.len()` spans last [factored](SpanBlock::factor)) into `rows`, as
    /// [`vertex_row`](crate::operator::vertex_row) computes them: the sub-span before the
    /// vertex (the closing one before vertex 0 of a closed curve) and the span's first; vertex
    /// 0 of an open curve has a zero row.
    #[inline(always)]
    fn data_rows(&self, t: &[f64], a0: usize, stride: usize, closed: bool, rows: &mut [[f64; 3]]) {
        let last = t.len() - 1;
        let mut hl = [1.0; LANES];
        for (lane, h) in hl.iter_mut().enumerate().take(rows.len()) {
            let a = a0 + lane * stride;
            // (Vertex 0 of an open curve has no span before it: its row is zeroed below.)
            *h = match a {
                0 if closed => t[last] - t[last - 1],
                0 => 1.0,
                _ => t[a] - t[a - 1],
            };
        }
        let hr = self.h[0];
        let (mut x, mut y, mut z) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for lane in 0..LANES {
            [x[lane], y[lane], z[lane]] = alpha_row(hl[lane], hr[lane]);
        }
        for (lane, r) in rows.iter_mut().enumerate() {
            *r = [x[lane], y[lane], z[lane]];
        }
        if a0 == 0 && !closed {
            rows[0] = [0.0; 3];
        }
    }
}

/// Pass 1 of [`interpolate`] on one block of spans (`count` ≤ [`LANES`] from span `i0`), as
/// [`crate::par::vectorized`] runs it: the spans' summaries and their data rows (the lanes past
/// `count`, and every lane of a block whose factorization failed, zero), the vertex of a bad
/// pivot folded into `failed` (the smallest: the first in span order).
struct Summaries<'a> {
    t: &'a [f64],
    stride: usize,
    closed: bool,
    i0: usize,
    count: usize,
    block: &'a mut SpanBlock,
    failed: &'a std::sync::atomic::AtomicUsize,
}

impl pulp::WithSimd for Summaries<'_> {
    type Output = ([[f64; 7]; LANES], [[f64; 3]; LANES]);
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Self::Output {
        let Summaries {
            t,
            stride,
            closed,
            i0,
            count,
            block,
            failed,
        } = self;
        let (mut out, mut rows) = ([[0.0; 7]; LANES], [[0.0; 3]; LANES]);
        if let Err(v) = block.factor(t, i0 * stride, stride, count) {
            failed.fetch_min(v, std::sync::atomic::Ordering::Relaxed);
            return (out, rows);
        }
        for (lane, o) in out.iter_mut().take(count).enumerate() {
            *o = block.summary(lane);
        }
        block.data_rows(t, i0 * stride, stride, closed, &mut rows[..count]);
        (out, rows)
    }
}

/// Pass 2 of [`interpolate`] on one unit of the output (the vertices of up to [`LANES`] spans,
/// and the last data point of an open curve after its last span), as
/// [`crate::par::vectorized`] runs it: each span's data vertex, then its free vertices
/// x = B⁻¹(e − c), e = −μ g − ν h (module docs), every step of the solve on the block's spans
/// at once ([`SpanFactors::solve`]'s arithmetic, lane by lane).
struct Reconstruct<'a> {
    t: &'a [f64],
    q: &'a Points,
    /// The data-row values (rows first …).
    s: &'a [f64],
    first: usize,
    data_rows: &'a [[f64; 3]],
    stride: usize,
    spans: usize,
    unit: usize,
    block: &'a mut SpanBlock,
    x: &'a mut [f64],
}

impl pulp::WithSimd for Reconstruct<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Reconstruct {
            t,
            q,
            s,
            first,
            data_rows,
            stride,
            spans,
            unit,
            block,
            x,
        } = self;
        let (d, n) = (q.dim(), q.len());
        let i0 = unit * LANES;
        let count = LANES.min(spans.saturating_sub(i0));
        if count < LANES && x.len() > count * stride * d {
            // The open curve's last data vertex, after its last span.
            x[count * stride * d..].copy_from_slice(q.point(n - 1));
        }
        if count == 0 {
            return;
        }
        if block.factor(t, i0 * stride, stride, count).is_err() {
            x[..count * stride * d].fill(f64::NAN);
            return;
        }
        let k = stride - 1;
        let size = s.len() / d.max(1);
        // The data-row value of data point i (zero for the end rows of an open curve).
        let srow = |i: usize, c: usize| {
            if i >= first && i - first < size {
                s[(i - first) * d + c]
            } else {
                0.0
            }
        };
        block.f.resize(k * d, [0.0; LANES]);
        let SpanBlock {
            a,
            c: sup,
            l,
            u,
            g,
            hh: h,
            f,
            ..
        } = block;
        for c in 0..d {
            // μ = α_{v_i,3} s_i, ν = α_{v_{i+1},1} s_{i+1}, and the span's ends, per lane.
            let (mut mu, mut nu, mut qa, mut qb) =
                ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
            for lane in 0..LANES {
                let i = i0 + lane.min(count - 1);
                let right = if i + 1 == n { 0 } else { i + 1 };
                mu[lane] = data_rows[i][2] * srow(i, c);
                nu[lane] = data_rows[right][0] * srow(right, c);
                qa[lane] = q.point(i)[c];
                qb[lane] = q.point(right)[c];
            }
            for j in 0..k {
                let (gj, hj) = (g[j], h[j]);
                let mut e = [0.0; LANES];
                for lane in 0..LANES {
                    e[lane] = -mu[lane] * gj[lane] - nu[lane] * hj[lane];
                }
                f[j * d + c] = e;
            }
            let (c0, c1) = (a[0], sup[k - 1]);
            for lane in 0..LANES {
                f[c][lane] -= c0[lane] * qa[lane];
            }
            for lane in 0..LANES {
                f[(k - 1) * d + c][lane] -= c1[lane] * qb[lane];
            }
        }
        // B x = f: forward with L, backward with U (super-diagonal = α_{·,3}), on local rows
        // of lanes (as in `SpanBlock::factor`).
        for c in 0..d {
            let mut prev = f[c];
            for j in 1..k {
                let (lj, mut cur) = (l[j], f[j * d + c]);
                for lane in 0..LANES {
                    cur[lane] -= lj[lane] * prev[lane];
                }
                (f[j * d + c], prev) = (cur, cur);
            }
            let ul = u[k - 1];
            for lane in 0..LANES {
                prev[lane] *= ul[lane];
            }
            f[(k - 1) * d + c] = prev;
            for j in (0..k - 1).rev() {
                let (sj, uj, mut cur) = (sup[j], u[j], f[j * d + c]);
                for lane in 0..LANES {
                    cur[lane] = (cur[lane] - sj[lane] * prev[lane]) * uj[lane];
                }
                (f[j * d + c], prev) = (cur, cur);
            }
        }
        for (lane, out) in x.chunks_exact_mut(stride * d).take(count).enumerate() {
            out[..d].copy_from_slice(q.point(i0 + lane));
            for (o, fj) in out[d..].iter_mut().zip(f.iter()) {
                *o = fj[lane];
            }
        }
    }
}

/// One factored span (its α-rows, LU and g, h), wherever they are stored.
struct SpanFactors<'s> {
    rows: &'s [[f64; 3]],
    l: &'s [f64],
    u: &'s [f64],
    g: &'s [f64],
    h: &'s [f64],
}

impl SpanFactors<'_> {
    /// The free vertices x = B⁻¹(e − c) into `f` (k × d), e = −μ g − ν h with (μ, ν) =
    /// `mu_nu(coordinate)`, c from the span's ends `qa`, `qb` (module docs).
    #[inline(always)]
    fn solve(
        &self,
        f: &mut [f64],
        qa: &[f64],
        qb: &[f64],
        d: usize,
        mu_nu: impl Fn(usize) -> (f64, f64),
    ) {
        let SpanFactors { rows, l, u, g, h } = *self;
        let k = rows.len();
        let (c0, c1) = (rows[0][0], rows[k - 1][2]);
        for c in 0..d {
            let (mu, nu) = mu_nu(c);
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
                f[j * d + c] = (f[j * d + c] - rows[j][2] * f[(j + 1) * d + c]) * u[j];
            }
        }
    }
}

/// Per span [G, X, Y, c0 g0, c1 g_{k−1}, c0 h0, c1 h_{k−1}] from its α-rows and g, h: G = g·g,
/// X = g·h, Y = h·h and the weights of its two data points in g·c and h·c,
/// c = α_{a+1,1} q_i e_0 + α_{b−1,3} q_{i+1} e_{k−1}.
#[inline]
fn span_summary(rows: &[[f64; 3]], g: &[f64], h: &[f64]) -> [f64; 7] {
    let k = rows.len();
    let (c0, c1) = (rows[0][0], rows[k - 1][2]);
    [
        dot(g, g),
        dot(g, h),
        dot(h, h),
        c0 * g[0],
        c1 * g[k - 1],
        c0 * h[0],
        c1 * h[k - 1],
    ]
}

/// The data-row system T s = K y from the span summaries and the data rows' α (`row(i)` of data
/// point i): T's diagonal and off-diagonal (`off[j]` couples rows j and j + 1, cyclic for a
/// closed curve) and K's rows, one per data row first … last − 1 (n closed, 1 … n − 2 open),
/// each as [`data_row`] gives it.
#[allow(clippy::type_complexity)]
fn data_row_system(
    span: &[[f64; 7]],
    n: usize,
    closed: bool,
    row: impl Fn(usize) -> [f64; 3],
) -> (Vec<f64>, Vec<f64>, Vec<[f64; 3]>) {
    let first = usize::from(!closed);
    let last = if closed { n } else { n - 1 }; // exclusive
    let size = last.saturating_sub(first);
    let (mut diag, mut off, mut krows) = (
        Vec::with_capacity(size),
        Vec::with_capacity(size),
        Vec::with_capacity(size),
    );
    for i in first..last {
        let (dg, of, kr) = data_row(span, n, closed, &row, i);
        diag.push(dg);
        off.push(of);
        krows.push(kr);
    }
    (diag, off, krows)
}

/// One coordinate of (Ky)_j from K's row `kr` and the data at its three columns, in difference
/// form (α₂ = −α₁ − α₃: exact under translation of the data).
#[inline(always)]
fn k_row(kr: [f64; 3], prev: f64, at: f64, next: f64) -> f64 {
    kr[0] * (prev - at) + kr[2] * (next - at)
}

/// Data row i of the data-row system: T's diagonal there, its coupling with row i + 1 (0 after
/// an open curve's last row), and K's row, with
/// (Ky)_i = α_{v_i,2} y_i − α_{v_i,1} h_{i−1}·c_{i−1} − α_{v_i,3} g_i·c_i.
#[inline(always)]
fn data_row(
    span: &[[f64; 7]],
    n: usize,
    closed: bool,
    row: &impl Fn(usize) -> [f64; 3],
    i: usize,
) -> (f64, f64, [f64; 3]) {
    let spans = span.len();
    let last = if closed { n } else { n - 1 }; // exclusive
    let ar = row(i);
    let prev = if i == 0 { spans - 1 } else { i - 1 };
    let cur = if i == spans { 0 } else { i };
    let diag = 1.0 + ar[0] * ar[0] * span[prev][2] + ar[2] * ar[2] * span[cur][0];
    let next = i + 1;
    let off = if next < last || closed {
        let an = row(if next == n { 0 } else { next });
        ar[2] * an[0] * span[cur][1]
    } else {
        0.0
    };
    let krow = [
        -ar[0] * span[prev][5],
        ar[1] - ar[0] * span[prev][6] - ar[2] * span[cur][3],
        -ar[2] * span[cur][4],
    ];
    (diag, off, krow)
}

/// The interpolation of [`interpolate`] through [`Condensation`] (the working-set method's
/// path): the reference the streaming passes are tested against.
#[cfg(test)]
pub(crate) fn interpolate_condensed(
    knots: &Knots,
    stencil: &Stencil,
    q: &Points,
    stride: usize,
) -> Result<Points, Error> {
    let d = q.dim();
    let n = q.len();
    let cond = Condensation::new(knots, stencil, n, stride)?;
    let size = cond.len();
    let mut s = vec![0.0; size * d];
    if size > 0 {
        cond.apply_k(q.coords(), d, &mut s);
        solve_tridiagonal(&cond.diag, &cond.off, &mut s, d, cond.closed && size >= 3).map_err(
            |j| {
                Error::from(energy::Error::Singular {
                    vertex: (cond.first + j) * stride,
                })
            },
        )?;
    }
    cond.reconstruct(knots, stencil, q.coords(), &s, d)
}

/// [`solve_band`] of borrowed bands (the tests' reference path).
#[cfg(test)]
fn solve_tridiagonal(
    diag: &[f64],
    off: &[f64],
    rhs: &mut [f64],
    d: usize,
    cyclic: bool,
) -> Result<(), usize> {
    solve_band(
        diag.to_vec(),
        off.iter().map(|&v| [v]).collect(),
        rhs,
        d,
        cyclic,
    )
}

/// Solves the symmetric tridiagonal (or, with `cyclic`, cyclic tridiagonal: `off[len−1]`
/// couples the last unknown with the first) positive definite system in place, for `d`
/// right-hand-side columns stored row-major in `rhs`, by [`banded::SymBand`]`<1>` (root-free
/// LDLᵀ, pivots from the determinant recurrence; a cyclic system bordered); the bands are taken
/// by value (`off[j]` couples rows j and j + 1), so the callers assemble them in place and
/// nothing is copied. Returns the index of a non-positive pivot.
pub(super) fn solve_band(
    diag: Vec<f64>,
    off: Vec<[f64; 1]>,
    rhs: &mut [f64],
    d: usize,
    cyclic: bool,
) -> Result<(), usize> {
    use banded::{FactorOptions, SymBand, Topology};
    let topology = if cyclic {
        Topology::Cyclic
    } else {
        Topology::Open
    };
    let row = |e: banded::Error| match e {
        banded::Error::Singular { index } => index,
        _ => 0,
    };
    let a = SymBand::<1>::from_bands(topology, diag, off).map_err(row)?;
    a.factor_with(&FactorOptions::default().pivot_rtol(0.0))
        .map_err(row)?
        .solve_in_place(rhs, d)
        .map_err(row)
}

#[cfg(test)]
mod tests {
    use divdiff::{Knots, Points};
    use proptest::prelude::*;

    use crate::operator::Stencil;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// The streaming passes, which factor `LANES` spans side by side, give the bits of the
        /// condensation that factors one span at a time, on knots as a knot update leaves them
        /// (every sub-span of its own length, over a range of 10⁴), open and closed, with
        /// several blocks and a partial last one, k = 1 … 8, d = 1 … 4.
        #[test]
        fn blocks_of_spans_give_the_bits_of_one_span_at_a_time(
            n in 3usize..40,
            stride in 2usize..10,
            d in 1usize..5,
            closed in any::<bool>(),
            seed in 0u64..1_000_000,
        ) {
            let mut unif = crate::par::uniform_stream(seed);
            let spans = if closed { n } else { n - 1 };
            let mut t = vec![0.0];
            for _ in 0..spans * stride {
                let last = *t.last().unwrap();
                t.push(last + 1e-2 * 10f64.powf(4.0 * unif()));
            }
            let knots = if closed { Knots::closed(t) } else { Knots::open(t) }.unwrap();
            let q = Points::new(d, (0..n * d).map(|_| 4.0 * unif() - 2.0).collect()).unwrap();
            let streamed = super::interpolate(&knots, &q, stride, None).unwrap();
            let reference =
                super::interpolate_condensed(&knots, &Stencil::new(&knots), &q, stride).unwrap();
            prop_assert_eq!(streamed.coords(), reference.coords());
            // Written into the points of an earlier solve (here NaN everywhere, and of the
            // wrong size), every coordinate is the same.
            let nv = knots.vertex_count();
            for len in [nv, nv + 1] {
                let mut old = Points::zeros(len, d);
                old.coords_mut().fill(f64::NAN);
                let recycled = super::interpolate(&knots, &q, stride, Some(old)).unwrap();
                prop_assert_eq!(recycled.coords(), reference.coords());
            }
        }
    }
}
