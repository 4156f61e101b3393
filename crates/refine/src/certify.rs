//! The certificate of a fixed-knot solution: energy, relative KKT residual, active set,
//! Corollary 3.3's jumps — recomputed from the points, the knots and the multipliers,
//! independently of the solver that produced them.
//!
//! # Independence
//!
//! Hp comes from the jumps of D³f (Kersey Theorem 2.1, Corollary 2.2: Hp = 2 jmp), computed
//! here from divided differences exactly as [`divdiff::jumps`] defines them — slopes
//! s_j = (p_{j+1} − p_j)/h_j, second differences c_i = (s_i − s_{i−1})/(h_{i−1} + h_i),
//! jmp_i = (c_{i+1} − c_i)/h_i − (c_i − c_{i−1})/h_{i−1} — in one streaming pass (tested
//! against `divdiff::jumps`). The solvers apply H through the α-rows of A (`operator`, the
//! backends) or the condensation; none of that code is used here. E = Σ_i |c_i|²(h_{i−1} + h_i)
//! is (2.1). Each constraint kind adds its own terms ([`crate::constraint::Kind::certify`]).
//!
//! # The relative KKT residual
//!
//! The largest of:
//! - **stationarity** ‖Hp + Σ (constraint gradient × multiplier)‖_∞ over all vertices, divided
//!   by the force scale F = max(‖Hp‖_∞, R / [`ROUNDING_COUNTS_AS`]): the largest force the
//!   curve actually carries (the reactions of its active constraints), but no smaller than
//!   the scale on which the rounding level R (below) is [`ROUNDING_COUNTS_AS`] = 1e-9 of it;
//!   at a data vertex with smoothing weight w, only the part beyond w·ε·max(|p_{i_k}|_∞,
//!   |q_i|_∞, L) counts, the force one rounding of the vertex's coordinates exerts (stiff
//!   weights, w ≫ ‖H‖);
//! - **complementarity** (|multiplier × slack|) and **negative multipliers**, over F;
//! - **primal violation** of the data constraints over the length scale L_data, the largest
//!   coordinate distance of a data vertex or a data point from the data's centroid (L, the
//!   length scale of the other terms, is the same over every vertex; measured against L, a
//!   curve that runs off with its data vertices outside their sets would measure its violations
//!   against its own run); a derivative constraint's violation relative to
//!   its own scale (max(|L p|, the set's size, Σ_u |c_u||p_u − p_v|_∞ — the rounding scale of
//!   the stencil, which a zero target lacks));
//! - the **duality gap** Σ (multiplier × slack) over E (it bounds the relative excess E(p) − E*
//!   of a feasible p over the optimum; E* = 0 is measured against the rounding level ε F L);
//! - the **arc bound** (`crate::arcs`): a lower bound on the objective's excess over its optimum
//!   from the net force on runs of vertices, measured across the spans at their ends, over the
//!   objective (E, plus smoothing's penalty): the per-vertex floors below forgive each stiff row
//!   its rounding, and on a cluster of very short spans those roundings can add up to a net force
//!   on the cluster that no vertex shows (ROBUSTNESS.md item 40);
//! - **run-off**: 0 while the curve's extent about the data's centroid is at most [`RUN_OFF`]
//!   (1e6) times L_data + V·T — V the largest size of a derivative constraint's set (|centre| +
//!   radius, |offset| / |normal|, an end derivative; 0 without derivative constraints, and for a
//!   wedge), T the knots' span — and that extent over the bound (≥ 1) beyond it.
//!
//! ## Why run-off is a term
//!
//! Every other term is relative to the answer's own scales (its largest force, its extent, its
//! energy), so a curve that runs away is judged on its own run. At data scales of 1e80 the
//! interior-point method once returned curves with wedges or tangent half-spaces whose free
//! vertices reached 6e115, balanced by huge cone multipliers, at 1e73 times the optimal energy:
//! every residual was below the rounding of those coordinates, and they scored 2.9e-32
//! (ROBUSTNESS.md §4, item 35). An optimal curve stays within a modest multiple of what its data
//! and the sizes its derivative bounds allow over the knots' span (the overshoot of spline
//! interpolation is bounded independently of the knots; ball radii and half-space offsets beyond
//! the data are capped for the solvers at 100 times the extent, and the data vertices count in
//! L_data); 1e6 leaves room for every answer the sweeps certify (one-sided half-planes on an open
//! arc, whose optimum straightens away from its data, reach 6 × L_data) and none for a
//! run-away.
//!
//! ## Why the force scale is the largest force
//!
//! A residual means something only relative to the forces it is a residual of. Dividing by the
//! size of the terms Hp is summed from (‖H‖_∞ times the largest step between vertices, as an
//! earlier version did) measures backward error, and that scale exceeds the reactions by a factor
//! that grows like 1/h² under refinement (the terms are first differences over h³, the reactions
//! third differences): on 120 jittered balls with k = 3 a curve certified at 3.8e-12 that way
//! had a stationarity residual of 8.4e-9 of its largest reaction, and the knot gradient of
//! [`crate::optimize_knots`] (the envelope formula, linear in that residual) was too noisy for
//! its line search. Relative to ‖Hp‖_∞ the certificate says what "relative KKT ≤ 1e-9"
//! promises: the unbalanced force is at most 1e-9 of the largest force in the solution.
//!
//! The floor keeps this honest where the forces cannot be resolved better than rounding:
//! R = 16 ε (‖H‖_∞ + w_max) max_j |p_j|_∞ bounds what rounding alone leaves in the stationarity
//! residual. Evaluating 2 jmp from points of size |p| errs by up to ε ‖H‖_∞ |p| (the slopes err
//! by 2ε|p|/h, and Hp divides three differences of them by h², as H's row (1, −4, 6, −4, 1)/h³
//! does), and a backward-stable banded solve leaves a few (bandwidth + 1) ε ‖H‖_∞ |p| more; a
//! constraint force w_i(p_{i_k} − q_i) errs by w_i times the rounding of p, so w_max is the
//! largest curvature the constraints add to the Lagrangian's Hessian H + W (a ball's multiplier,
//! a smoothing weight; [`crate::constraint::Terms::stiffness`]). A residual below R cannot be
//! told from 0 and scores at most [`ROUNDING_COUNTS_AS`]. The floor matters when E* ≈ 0 (a
//! nearly straight curve, forces at rounding level) and for tiny balls: at ε_i = 1e-9 L the
//! multiplier is w_i ≈ F/ε_i and rounding alone moves the ball's force by ~1e-7 of F.
//!
//! The floor is only as wide as each vertex's own rounding: past R_j = 16 ε (r_j + w_max) m_j at
//! vertex j (r_j row j's sum of |H|, m_j the largest coordinate around it) the residual also
//! counts against the largest force ‖Hp‖_∞ with no floor. A global R, set by the stiffest row,
//! covered residuals where the rows are soft: on spans of 1.5e-6 beside spans of 0.5 with
//! coordinates near 1e3, a curve with 1.6e7 times the optimal energy once scored 8.3e-10
//! (`tests/tests/optimality.rs`).
//!
//! The verification suite's independent recomputation (`xtask/src/verify/refine/kkt.rs`) uses
//! the same scale and the same R (‖H‖_∞ the same largest row sum, see [`Pass::h_norm`]; w_max
//! the largest ball multiplier or smoothing weight). It does not discount the rounding of each
//! smoothing force at its own vertex, so it is as strict as this certificate or stricter.

use divdiff::{DerivativeRule, Knots, Points};

use crate::constraint::{At, Kind, Terms};
use banded::lanes::{by_lanes, raise, raise_abs, raise_all, raise_over, sum_abs, sum_over, total};

/// The multiple of ε ‖H‖_∞ max|p| that bounds the rounding in Hp (module docs).
pub(crate) const ROUNDING_MULTIPLE: f64 = 16.0;

/// How far beyond its reach a curve may run before the certificate refuses it (module docs,
/// "Run-off"): its extent about the data's centroid against this times L_data + V·T.
const RUN_OFF: f64 = 1e6;

/// The relative residual that a stationarity residual at the rounding level R scores at most:
/// the force scale is at least R / this (module docs). Equal to the default acceptance
/// [`crate::EXACT_ACCEPT_KKT`], so that a curve exact to rounding is accepted whatever its
/// forces.
pub(crate) const ROUNDING_COUNTS_AS: f64 = 1e-9;

/// What one fixed-knot stage certifies.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Certificate {
    pub energy: f64,
    pub kkt_residual: f64,
    pub active: Vec<bool>,
    /// max |jmp_{i_k}| over inactive data vertices, relative; `None` when none is inactive.
    pub jmp_inactive: Option<f64>,
}

/// What one streaming pass over the vertices yields.
#[derive(Default)]
pub(crate) struct Pass {
    /// Hp at every vertex (N × d) when the pass was not given the data vertices; else empty.
    pub hp: Vec<f64>,
    /// Hp at the data vertices (n × d) when the pass was given them; else empty.
    pub hp_data: Vec<f64>,
    /// The points at the data vertices (n × d) when the pass was given them; else empty.
    pub p_data: Vec<f64>,
    /// Row j's sum of |H| at every vertex (N) when the pass was not given the data vertices;
    /// else empty.
    pub rows: Vec<f64>,
    /// The same at the data vertices (n) when the pass was given them; else empty.
    pub rows_data: Vec<f64>,
    /// max |Hp| over the vertices that are not data vertices, when the pass was given them.
    pub free_stat: f64,
    /// The largest part of |Hp| beyond its vertex's own rounding level over those vertices,
    /// max_j (|Hp_j|_∞ − [`ROUNDING_MULTIPLE`] ε r_j m_j)⁺, r_j row j's sum of |H| and m_j the
    /// largest coordinate of the vertices around it ([`local_rounding`]).
    pub free_excess: f64,
    /// E of (2.1).
    pub energy: f64,
    /// A bound on ‖H‖_∞: max_j Σ_r |A_rj| Σ_i |A_ri| with the α-rows of A.
    pub h_norm: f64,
    /// max_j |p_j − center|_∞.
    pub extent: f64,
    /// max_j |p_j|_∞, the size of the coordinates (the rounding level's scale).
    pub magnitude: f64,
    /// Σ |Hp| over the vertices that are not data vertices (every coordinate), when the pass was
    /// given them: the arc test's gate.
    pub free_sum: f64,
    /// The largest 1/k_j over the spans, k_j the stiffness of an arc's end on span j
    /// ([`crate::arcs`]): the gate of the arc test.
    pub compliance: f64,
}

/// Hp = 2 jmp (divided differences, module docs), E, ‖H‖_∞, the extent about `center` and the
/// largest coordinate, in one pass over the vertices, in blocks of [`BLOCK`] vertices: the
/// reciprocals 1/h_j and 1/(h_{i−1} + h_i) of a block are formed once and shared by its
/// coordinates, and each coordinate goes through slopes, second differences and Hp as straight
/// loops over the block's arrays (vectorized: a scalar vertex-by-vertex loop with its divisions
/// was most of a large interpolation's certified solve); a missing span or second difference
/// (the ends of an open curve) has reciprocal 0, so its terms vanish without a branch.
///
/// Given the vertices to keep (strictly increasing: the data vertices, and the derivative
/// constraints' stencils beside them), Hp is kept only there and its largest size over the
/// other vertices is returned instead (`hp_data`, `free_stat`): no N × d buffer. (`Pass`'s
/// "data vertices" are these kept vertices.)
pub(crate) fn pass(knots: &Knots, p: &Points, center: &[f64], data: Option<&[usize]>) -> Pass {
    let (n, d) = (p.len(), p.dim());
    let mut hp = vec![0.0; if data.is_some() { 0 } else { n * d }];
    let mut hp_data = vec![0.0; data.map_or(0, |v| v.len() * d)];
    let mut p_data = vec![0.0; hp_data.len()];
    // Row sums of |H| where Hp is kept (every vertex, or the data vertices).
    let mut rows = vec![0.0; if data.is_some() { 0 } else { n }];
    let mut rows_data = vec![0.0; data.map_or(0, |v| v.len())];
    // Chunks of vertices in parallel (`crate::par`), each with the slices of Hp it writes: all
    // of its vertices', or its data vertices' (and their points).
    let mut chunks = Vec::new();
    let (mut hp_rest, mut data_rest) = (&mut hp[..], &mut hp_data[..]);
    let mut points_rest = &mut p_data[..];
    let (mut rows_rest, mut rows_data_rest) = (&mut rows[..], &mut rows_data[..]);
    let mut first_data = 0;
    for range in crate::par::ranges(n, crate::par::CHUNK_VERTICES) {
        let own = if data.is_some() { 0 } else { range.len() };
        let (here, rest) = std::mem::take(&mut hp_rest).split_at_mut(own * d);
        hp_rest = rest;
        let (rhere, rrest) = std::mem::take(&mut rows_rest).split_at_mut(own);
        rows_rest = rrest;
        let end_data = data.map_or(0, |v| v.partition_point(|&x| x < range.end));
        let (dhere, drest) =
            std::mem::take(&mut data_rest).split_at_mut((end_data - first_data) * d);
        data_rest = drest;
        let (phere, prest) =
            std::mem::take(&mut points_rest).split_at_mut((end_data - first_data) * d);
        points_rest = prest;
        let (rdhere, rdrest) =
            std::mem::take(&mut rows_data_rest).split_at_mut(end_data - first_data);
        rows_data_rest = rdrest;
        chunks.push((
            Chunk { range, first_data },
            (here, rhere),
            (dhere, phere, rdhere),
        ));
        first_data = end_data;
    }
    let input = Input {
        knots,
        p,
        center,
        data,
    };
    let parts = crate::par::map(chunks, |(chunk, hp, out)| {
        crate::par::vectorized(Sweep {
            input: &input,
            chunk: &chunk,
            out: (hp, out),
        })
    });
    let mut out = Pass::default();
    for part in &parts {
        out.merge(part);
    }
    out.hp = hp;
    out.hp_data = hp_data;
    out.p_data = p_data;
    out.rows = rows;
    out.rows_data = rows_data;
    out
}

impl Pass {
    /// Folds another block's or chunk's sums and maxima into this one.
    fn merge(&mut self, other: &Pass) {
        self.free_stat = self.free_stat.max(other.free_stat);
        self.free_excess = self.free_excess.max(other.free_excess);
        self.energy += other.energy;
        self.h_norm = self.h_norm.max(other.h_norm);
        self.extent = self.extent.max(other.extent);
        self.magnitude = self.magnitude.max(other.magnitude);
        self.compliance = self.compliance.max(other.compliance);
        self.free_sum += other.free_sum;
    }
}

/// What every sweep of a pass reads: the knots, the points, the centre of the extent, and the
/// data vertices when Hp is kept only there.
struct Input<'a> {
    knots: &'a Knots,
    p: &'a Points,
    center: &'a [f64],
    data: Option<&'a [usize]>,
}

/// The vertices one sweep covers, and the index (among the data vertices) of its first data
/// vertex; its Hp slices start there.
struct Chunk {
    range: std::ops::Range<usize>,
    first_data: usize,
}

/// Vertices per block of a sweep: the block's arrays (1 KiB each) stay in L1 beside the knots
/// and points streaming through (at N = 8·10⁵, d = 2, one thread: 6.5 ms for the pass in blocks
/// of 256, 5.4 ms in blocks of 128 or 64, 6.9 ms in blocks of 32; medians of 60).
const BLOCK: usize = 128;

/// Where a sweep writes Hp: every vertex's, or (given the data vertices) the data vertices' and
/// their points.
type HpOut<'a> = (
    (&'a mut [f64], &'a mut [f64]),
    (&'a mut [f64], &'a mut [f64], &'a mut [f64]),
);

/// A block's arrays, in local indices: local vertex `l` is global vertex `a − 2 + l` for the
/// block's vertices `a .. b` (two vertices of halo each side), local span `l` the span from
/// local vertex `l` to `l + 1`. A vertex or span that does not exist (past the ends of an open
/// curve) has reciprocal spacing 0 and width 0, so its terms vanish without a branch (module
/// docs of [`pass`]).
#[derive(Default)]
struct Block {
    /// 1/h of each local span (0 where it does not exist).
    ih: Vec<f64>,
    /// h_{i−1} + h_i at each local vertex where the centred difference exists, else 0.
    w: Vec<f64>,
    /// Its reciprocal (0 where it does not exist).
    iw: Vec<f64>,
    /// The local vertices' coordinates, coordinate by coordinate: coordinate c of local vertex
    /// l at c·len + l.
    x: Vec<f64>,
    /// Slopes s_j of the local spans.
    s: Vec<f64>,
    /// Second differences c_i of the local vertices.
    c: Vec<f64>,
    /// Hp of the block's own vertices for one coordinate.
    v: Vec<f64>,
    /// The row sums of |H| at the block's own vertices.
    rows: Vec<f64>,
}

impl Block {
    /// Sizes the arrays for `len` local vertices of `d` coordinates.
    fn resize(&mut self, len: usize, d: usize) {
        self.x.resize(len * d, 0.0);
        for b in [
            &mut self.ih,
            &mut self.w,
            &mut self.iw,
            &mut self.s,
            &mut self.c,
            &mut self.v,
            &mut self.rows,
        ] {
            b.resize(len, 0.0);
        }
    }

    /// Fills `x` with the `d` coordinates of the local vertices `len` long from the interleaved
    /// `from` (local vertex l at l·d): one read of each point for all its coordinates, with the
    /// dimension known to the compiler for d = 2 and 3, instead of one strided read per
    /// coordinate with a run-time stride (a quarter of the pass's samples at N = 8·10⁵; the
    /// pass went from 3.36 to 2.78 ms there, medians of 240 calls on two threads).
    #[inline(always)]
    fn gather(&mut self, from: &[f64], d: usize, len: usize) {
        let x = &mut self.x[..len * d];
        match d {
            2 => deinterleave::<2>(x, &from[..len * 2], len),
            3 => deinterleave::<3>(x, &from[..len * 3], len),
            _ => {
                for c in 0..d {
                    for (l, xl) in x[c * len..(c + 1) * len].iter_mut().enumerate() {
                        *xl = from[l * d + c];
                    }
                }
            }
        }
    }
}

/// `x[c·len + l] = from[l·D + c]`: D interleaved coordinates to D contiguous rows.
#[inline(always)]
fn deinterleave<const D: usize>(x: &mut [f64], from: &[f64], len: usize) {
    let (points, _) = from.as_chunks::<D>();
    let mut chunks = x.chunks_exact_mut(len);
    let rows: [&mut [f64]; D] = std::array::from_fn(|_| chunks.next().expect("D rows of len"));
    for (l, pt) in points[..len].iter().enumerate() {
        for c in 0..D {
            rows[c][l] = pt[c];
        }
    }
}

/// The global vertex at local position `g` (relative to vertex 0), wrapped on a closed curve;
/// `None` past the ends of an open one.
#[inline]
fn wrap(g: isize, n: usize, closed: bool) -> Option<usize> {
    let n = n as isize;
    if (0..n).contains(&g) {
        Some(g as usize)
    } else if closed {
        Some(g.rem_euclid(n) as usize)
    } else {
        None
    }
}

/// Row g of |H|'s sum (‖H‖_∞ is the largest): A's rows g − 1, g and g + 1 (α₁, α₂, α₃ on
/// their vertices − 1, 0, + 1) add |α₃|Σ|α|, |α₂|Σ|α| and |α₁|Σ|α| at g, which are
/// 4/(h_{g−2}h_{g−1}²), 4(h_{g−1} + h_g)/(h_{g−1}²h_g²) and 4/(h_g²h_{g+1}) — no square root.
/// `ih` holds 1/h of the spans g − 2 … g + 1 (0 where one does not exist), `on` 4 or 0 for
/// whether rows g − 1, g, g + 1 exist.
#[inline(always)]
fn row_sum(ih: [f64; 4], on: [f64; 3]) -> f64 {
    on[0] * ih[0] * ih[1] * ih[1]
        + on[1] * ih[1] * ih[2] * (ih[1] + ih[2])
        + on[2] * ih[2] * ih[3] * ih[2]
}

/// The rounding level of Hp at a vertex whose row of |H| sums to `row` and whose neighbourhood's
/// coordinates are at most `magnitude`: what one rounding of those coordinates moves Hp there
/// by, times [`ROUNDING_MULTIPLE`] (module docs, "the floor").
#[inline(always)]
fn local_rounding(row: f64, magnitude: f64) -> f64 {
    ROUNDING_MULTIPLE * f64::EPSILON * row * magnitude
}

/// One chunk's [`sweep`], as [`crate::par::vectorized`] runs it.
struct Sweep<'a, 'b> {
    input: &'a Input<'b>,
    chunk: &'a Chunk,
    out: HpOut<'a>,
}

impl pulp::WithSimd for Sweep<'_, '_> {
    type Output = Pass;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Pass {
        sweep(self.input, self.chunk, self.out)
    }
}

/// [`pass`] over `chunk`'s vertices, block by block: the geometry of a block (reciprocal
/// spacings, widths, the ‖H‖_∞ row sums) once, then each coordinate through slopes, second
/// differences and Hp — each step a straight loop over equally long slices of the block's
/// arrays, which the compiler vectorizes.
#[inline(always)]
fn sweep(
    &Input {
        knots,
        p,
        center,
        data,
    }: &Input<'_>,
    chunk: &Chunk,
    ((hp, rows_out), (hp_data, p_data, rows_data)): HpOut<'_>,
) -> Pass {
    let (n, d) = (p.len(), p.dim());
    let x = p.coords();
    let closed = knots.is_closed();
    let t = knots.values();
    let spans = knots.span_count();
    let mut out = Pass::default();
    let mut bl = Block::default();
    let mut next_data = chunk.first_data;
    let mut a = chunk.range.start;
    while a < chunk.range.end {
        let b = (a + BLOCK).min(chunk.range.end);
        // m own vertices: local 2 .. m + 2 of len = m + 4.
        let m = b - a;
        let len = m + 4;
        bl.resize(len, d);
        let base = a as isize - 2;
        // Whether every local vertex is a vertex of the curve with both its spans and no wrap:
        // the arrays are then read straight from the knots and points.
        let inner = a >= 2 && b + 2 <= spans;
        // 1/h of local span l (spans 0 .. spans − 1, wrapped on a closed curve).
        {
            let ih = &mut bl.ih[..len];
            if inner {
                let (t0, t1) = (&t[a - 2..a - 2 + len], &t[a - 1..a - 1 + len]);
                for j in 0..len {
                    ih[j] = 1.0 / (t1[j] - t0[j]);
                }
            } else {
                for (l, ih) in ih.iter_mut().enumerate() {
                    let j = wrap(base + l as isize, n, closed).filter(|&j| j < spans);
                    *ih = j.map_or(0.0, |j| 1.0 / (t[j + 1] - t[j]));
                }
            }
        }
        // Widths h_{i−1} + h_i of the centred differences at local vertices 1 .. len − 1.
        {
            let (w, iw) = (&mut bl.w[..len], &mut bl.iw[..len]);
            w[0] = 0.0;
            iw[0] = 0.0;
            if inner {
                let k = len - 1;
                let (t0, t1, t2) = (&t[a - 2..][..k], &t[a - 1..][..k], &t[a..][..k]);
                let (w, iw) = (&mut w[1..], &mut iw[1..]);
                for j in 0..k {
                    w[j] = (t1[j] - t0[j]) + (t2[j] - t1[j]);
                    iw[j] = 1.0 / w[j];
                }
            } else {
                for l in 1..len {
                    let centred = wrap(base + l as isize, n, closed)
                        .filter(|&i| closed || (i >= 1 && i + 1 < n));
                    (w[l], iw[l]) = match centred {
                        Some(i) => {
                            let hl = if i == 0 {
                                t[n] - t[n - 1]
                            } else {
                                t[i] - t[i - 1]
                            };
                            let hr = t[i + 1] - t[i];
                            (hl + hr, 1.0 / (hl + hr))
                        }
                        None => (0.0, 0.0),
                    };
                }
            }
        }
        // ‖H‖_∞: row i of A (α₁, α₂, α₃ on i − 1, i, i + 1) adds |α₃|Σ|α|, |α₂|Σ|α|, |α₁|Σ|α|
        // at vertices i + 1, i, i − 1, which are 4/(h_{i−1}h_i²), 4(h_{i−1} + h_i)/(h_{i−1}²h_i²),
        // 4/(h_{i−1}²h_i) — no square root — and 0 where the row does not exist. Vertex i's row
        // sum takes the first from row i − 1, the second from row i, the third from row i + 1.
        {
            let k = m;
            let (ih0, ih1, ih2, ih3) = (
                &bl.ih[..k],
                &bl.ih[1..k + 1],
                &bl.ih[2..k + 2],
                &bl.ih[3..k + 3],
            );
            let (w1, w2, w3) = (&bl.w[1..k + 1], &bl.w[2..k + 2], &bl.w[3..k + 3]);
            let sums = &mut bl.rows[..k];
            let on = |w: f64| if w > 0.0 { 4.0 } else { 0.0 };
            for j in 0..k {
                // rows of own vertex j's neighbours (local j + 1, j + 3) and its own (j + 2)
                sums[j] = row_sum(
                    [ih0[j], ih1[j], ih2[j], ih3[j]],
                    [on(w1[j]), on(w2[j]), on(w3[j])],
                );
            }
            raise_abs(&mut out.h_norm, sums, 0.0);
            // The compliance 1/k of an arc's end on each own span (crate::arcs):
            // k = 2/h² (1/(h_{j−1} + h_j) + 1/(h_j + h_{j+1})), 0 where no row straddles it.
            let (ih, iw0, iw1) = (&bl.ih[2..k + 2], &bl.iw[2..k + 2], &bl.iw[3..k + 3]);
            // (The least positive k as the largest −k, one reciprocal per block.)
            // (Four spans at a time from arrays of four, in four lanes: `raise_over`, bit for bit,
            // but with no bounds check in the loop to keep the compiler from vectorizing it.)
            let mut lanes = [f64::NEG_INFINITY; 4];
            let least = |ih: f64, iw0: f64, iw1: f64| {
                let stiffness = 2.0 * ih * ih * (iw0 + iw1);
                if stiffness > 0.0 {
                    -stiffness
                } else {
                    f64::NEG_INFINITY
                }
            };
            let ((ihq, ihr), (w0q, w0r), (w1q, w1r)) = (
                ih.as_chunks::<4>(),
                iw0.as_chunks::<4>(),
                iw1.as_chunks::<4>(),
            );
            for ((ih, w0), w1) in ihq.iter().zip(w0q).zip(w1q) {
                for l in 0..4 {
                    raise(&mut lanes[l], least(ih[l], w0[l], w1[l]));
                }
            }
            for ((ih, w0), w1) in ihr.iter().zip(w0r).zip(w1r) {
                raise(&mut lanes[0], least(*ih, *w0, *w1));
            }
            let mut softest = f64::NEG_INFINITY;
            raise_all(&mut softest, lanes);
            if softest > f64::NEG_INFINITY {
                out.compliance = out.compliance.max(-1.0 / softest);
            }
        }
        // The block's data vertices (when Hp is kept only there).
        // (At most m of them: the data vertices are strictly increasing.)
        let data_end = data.map_or(next_data, |dv| {
            let ahead = &dv[next_data..(next_data + m).min(dv.len())];
            next_data + ahead.partition_point(|&v| v < b)
        });
        // The local vertices' coordinates (0 where a vertex does not exist).
        if inner {
            bl.gather(&x[(a - 2) * d..], d, len);
        } else {
            for coord in 0..d {
                for (l, xk) in bl.x[coord * len..(coord + 1) * len].iter_mut().enumerate() {
                    *xk = wrap(base + l as isize, n, closed).map_or(0.0, |i| x[i * d + coord]);
                }
            }
        }
        // The largest coordinate around the block's vertices: the scale of their rounding.
        let mut local_magnitude = 0.0f64;
        raise_abs(&mut local_magnitude, &bl.x[..len * d], 0.0);
        for (coord, &mid) in center[..d].iter().enumerate() {
            let xc = &bl.x[coord * len..(coord + 1) * len];
            // s_j = (p_{j+1} − p_j)/h_j for local spans 0 .. len − 1.
            {
                let k = len - 1;
                let (x0, x1, ih, s) = (&xc[..k], &xc[1..len], &bl.ih[..k], &mut bl.s[..k]);
                for j in 0..k {
                    s[j] = (x1[j] - x0[j]) * ih[j];
                }
            }
            // c_i = (s_i − s_{i−1})/(h_{i−1} + h_i) at local vertices 1 .. len − 1.
            {
                let k = len - 2;
                let (s0, s1, iw) = (&bl.s[..k], &bl.s[1..k + 1], &bl.iw[1..k + 1]);
                let c = &mut bl.c[1..k + 1];
                for j in 0..k {
                    c[j] = (s1[j] - s0[j]) * iw[j];
                }
            }
            // Hp_i = 2 jmp_i = 2((c_{i+1} − c_i)/h_i − (c_i − c_{i−1})/h_{i−1}) and E = Σ c_i² w_i
            // at the own vertices (local 2 .. m + 2).
            {
                let (c0, c1, c2) = (&bl.c[1..m + 1], &bl.c[2..m + 2], &bl.c[3..m + 3]);
                let (ih0, ih1, w) = (&bl.ih[1..m + 1], &bl.ih[2..m + 2], &bl.w[2..m + 2]);
                let v = &mut bl.v[..m];
                for j in 0..m {
                    v[j] = 2.0 * ((c2[j] - c1[j]) * ih1[j] - (c1[j] - c0[j]) * ih0[j]);
                }
                let mut e = [0.0f64; 4];
                let ((cq, cr), (wq, wr)) = (c1.as_chunks::<4>(), w.as_chunks::<4>());
                for (cq, wq) in cq.iter().zip(wq) {
                    for l in 0..4 {
                        e[l] += cq[l] * cq[l] * wq[l];
                    }
                }
                for (c, w) in cr.iter().zip(wr) {
                    e[0] += c * c * w;
                }
                out.energy += (e[0] + e[1]) + (e[2] + e[3]);
            }
            let own = &xc[2..m + 2];
            raise_abs(&mut out.extent, own, mid);
            raise_abs(&mut out.magnitude, own, 0.0);
            let v = &mut bl.v[..m];
            match data {
                None => {
                    let at = (a - chunk.range.start) * d + coord;
                    for (k, &vk) in v.iter().enumerate() {
                        hp[at + k * d] = vk;
                    }
                }
                Some(dv) => {
                    for (k, &i) in dv[next_data..data_end].iter().enumerate() {
                        let o = (next_data + k - chunk.first_data) * d + coord;
                        hp_data[o] = v[i - a];
                        p_data[o] = own[i - a];
                        v[i - a] = 0.0;
                    }
                    raise_abs(&mut out.free_stat, v, 0.0);
                    out.free_sum += sum_abs(v);
                    // (free_excess starts at 0: a negative part leaves it, as its positive
                    // part 0 would; four lanes from arrays of four, as `raise_over` takes
                    // them)
                    let mut lanes = [out.free_excess; 4];
                    let excess = |v: f64, row: f64| v.abs() - local_rounding(row, local_magnitude);
                    let ((vq, vr), (rq, rr)) = (v.as_chunks::<4>(), bl.rows[..m].as_chunks::<4>());
                    for (v, r) in vq.iter().zip(rq) {
                        for l in 0..4 {
                            raise(&mut lanes[l], excess(v[l], r[l]));
                        }
                    }
                    for (v, r) in vr.iter().zip(rr) {
                        raise(&mut lanes[0], excess(*v, *r));
                    }
                    raise_all(&mut out.free_excess, lanes);
                }
            }
        }
        // The row sums where Hp is kept, for the certificate's per-vertex rounding levels.
        match data {
            None => {
                let at = a - chunk.range.start;
                rows_out[at..at + m].copy_from_slice(&bl.rows[..m]);
            }
            Some(dv) => {
                for (k, &i) in dv[next_data..data_end].iter().enumerate() {
                    rows_data[next_data + k - chunk.first_data] = bl.rows[i - a];
                }
            }
        }
        next_data = data_end;
        a = b;
    }
    out
}

/// The arc test runs where a bound on it from the pass's residuals exceeds this fraction of E
/// (a thousandth of the acceptance: skipped, it could not have refused).
const ARC_GATE: f64 = 1e-12;

/// The most free vertices between two consecutive data vertices (open: also before the first and
/// after the last; closed: across the wrap), `data_vertex` strictly increasing.
fn longest_run(data_vertex: &[usize], vertices: usize, closed: bool) -> usize {
    let (Some(&first), Some(&last)) = (data_vertex.first(), data_vertex.last()) else {
        return vertices;
    };
    let inner = data_vertex
        .windows(2)
        .map(|w| w[1] - w[0] - 1)
        .max()
        .unwrap_or(0);
    let ends = if closed {
        vertices - 1 - last + first
    } else {
        first.max(vertices - 1 - last)
    };
    inner.max(ends)
}

/// The run-off term (module docs): 0 while `extent` is at most [`RUN_OFF`] × (`data_length` +
/// `reach` × `span`), else `extent` over that bound (> 1).
fn run_off(extent: f64, data_length: f64, reach: f64, span: f64) -> f64 {
    let bound = RUN_OFF * (data_length + reach * span);
    if extent > bound {
        extent / bound
    } else {
        0.0
    }
}

/// Certifies points `p` for data `q` attached at `data_vertex` under `kinds` (the data kind
/// first), with the data kind's multipliers in the conventions of
/// [`crate::Refinement::multipliers`] (`None`: the reactions of interpolation, −(Hp)_{i_k} less
/// the derivative constraints' forces at the data vertex, computed here) and the derivative
/// kinds' (dual, force) in the order of their rows. Returns the certificate and the
/// multipliers.
#[allow(clippy::too_many_arguments)]
pub(crate) fn certify(
    knots: &Knots,
    p: &Points,
    q: &Points,
    data_vertex: &[usize],
    kinds: &[Box<dyn Kind + '_>],
    multipliers: Option<Vec<Vec<f64>>>,
    derivative: &[(Vec<f64>, Vec<f64>)],
    rule: DerivativeRule,
    active_tol: f64,
) -> (Certificate, crate::Multipliers) {
    let d = p.dim();
    let n = q.len();
    let nv = p.len();
    // Coordinate by coordinate, each in four independent sums.
    let qc = q.coords();
    let centroid: Vec<f64> = (0..d)
        .map(|c| sum_over(n, |i| qc[i * d + c]) / n as f64)
        .collect();
    let derivative_kinds = kinds.iter().any(|k| k.on_derivatives());
    // Away from the data vertices and the derivative constraints' stencils, stationarity is
    // |Hp| alone, so the pass keeps Hp only at those vertices (when the data vertices are in
    // order, as every stage's are) and takes the maxima over the others itself.
    let compact =
        data_vertex.windows(2).all(|w| w[0] < w[1]) && data_vertex.last().is_none_or(|&v| v < nv);
    // The stencils' vertices that are not data vertices, in order.
    let stencil: Vec<usize> = if compact && derivative_kinds {
        let mut s: Vec<usize> = kinds
            .iter()
            .flat_map(|k| k.derivative_vertices(data_vertex, nv))
            .filter_map(|v| divdiff::derivative_stencil(knots, v, rule).ok())
            .flat_map(|st| st.map(|(u, _)| u))
            .filter(|u| data_vertex.binary_search(u).is_err())
            .collect();
        s.sort_unstable();
        s.dedup();
        s
    } else {
        Vec::new()
    };
    // The data vertices with the stencils' among them, in order; where each stencil vertex went.
    let mut at_kept = Vec::with_capacity(stencil.len());
    let kept: std::borrow::Cow<'_, [usize]> = if stencil.is_empty() {
        data_vertex.into()
    } else {
        let mut k = Vec::with_capacity(n + stencil.len());
        let mut from = 0;
        for &s in &stencil {
            let to = data_vertex.partition_point(|&v| v < s);
            k.extend_from_slice(&data_vertex[from..to]);
            at_kept.push(k.len());
            k.push(s);
            from = to;
        }
        k.extend_from_slice(&data_vertex[from..]);
        k.into()
    };
    let mut pass = pass(knots, p, &centroid, compact.then_some(&kept[..]));
    // Hp and the row sums at the stencils' vertices (s × d, s), split from the data vertices'.
    let (mut stencil_hp, mut stencil_rows): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    if !stencil.is_empty() {
        let (hp_kept, p_kept, rows_kept) = (
            std::mem::take(&mut pass.hp_data),
            std::mem::take(&mut pass.p_data),
            std::mem::take(&mut pass.rows_data),
        );
        let s = stencil.len();
        (stencil_hp, stencil_rows) = (Vec::with_capacity(s * d), Vec::with_capacity(s));
        pass.hp_data = Vec::with_capacity(n * d);
        pass.p_data = Vec::with_capacity(n * d);
        pass.rows_data = Vec::with_capacity(n);
        // (the runs of data vertices between the stencils' vertices, copied whole)
        let mut from = 0;
        for &j in at_kept.iter().chain([&kept.len()]) {
            pass.hp_data.extend_from_slice(&hp_kept[from * d..j * d]);
            pass.p_data.extend_from_slice(&p_kept[from * d..j * d]);
            pass.rows_data.extend_from_slice(&rows_kept[from..j]);
            if j < kept.len() {
                stencil_hp.extend_from_slice(&hp_kept[j * d..(j + 1) * d]);
                stencil_rows.push(rows_kept[j]);
            }
            from = j + 1;
        }
    }
    // The largest coordinate distance from the centroid of n points stored flat (d each).
    let extent_of = |x: &[f64]| {
        let mut e = 0.0f64;
        for (c, &m) in centroid.iter().enumerate() {
            raise_over(&mut e, n, |i| (x[i * d + c] - m).abs());
        }
        e
    };
    let q_extent = extent_of(qc);
    let length = pass.extent.max(q_extent).max(f64::MIN_POSITIVE);
    if !compact {
        // (Sized up front: collected through `flat_map`, whose length is unknown, the two
        // took 2.5 ms for 10⁵ data vertices.)
        let at_data = |x: &[f64]| {
            let mut out = Vec::with_capacity(data_vertex.len() * d);
            for &v in data_vertex {
                out.extend_from_slice(&x[v * d..(v + 1) * d]);
            }
            out
        };
        pass.hp_data = at_data(&pass.hp);
        pass.p_data = at_data(p.coords());
    }
    // L_data: the data vertices' and data points' largest coordinate distance from the
    // centroid, the scale of the data constraints' violations. (L itself also counts the other
    // vertices, which a curve running off with the constraints violated at its data vertices
    // carries far away: measured against L, a violation of 3e53 at radius 0.9 once read as
    // 1e-10.)
    let data_length = q_extent.max(extent_of(&pass.p_data)).max(f64::MIN_POSITIVE);
    let hp_data = &pass.hp_data;
    let reactions = multipliers.is_none();
    let mut multipliers = match multipliers {
        Some(m) => crate::Multipliers::from(m),
        None => crate::Multipliers::uniform(d, n, hp_data.iter().map(|x| -x).collect()),
    };
    let mut terms = Terms::new(n, d);
    let at = At {
        p,
        data_points: &pass.p_data,
        q,
        knots,
        data_vertex,
        multipliers: &multipliers,
        duals: derivative,
        rule,
        length,
        active_tol,
    };
    for k in kinds {
        k.certify(&at, &mut terms);
    }
    // The force scale F (module docs): the largest |Hp|, no smaller than the rounding level R
    // over ROUNDING_COUNTS_AS.
    let mut hp_max = if compact { pass.free_stat } else { 0.0 };
    raise_abs(&mut hp_max, if compact { hp_data } else { &pass.hp }, 0.0);
    raise_abs(&mut hp_max, &stencil_hp, 0.0);
    let rounding =
        ROUNDING_MULTIPLE * f64::EPSILON * (pass.h_norm + terms.stiffness) * pass.magnitude;
    let force = hp_max
        .max(rounding / ROUNDING_COUNTS_AS)
        .max(f64::MIN_POSITIVE);
    // Stationarity at every vertex: Hp + derivative forces + data forces at the data vertices;
    // and the part of it beyond each vertex's own rounding level (module docs, "the floor").
    let rounding_of = |row: f64| local_rounding(row + terms.stiffness, pass.magnitude);
    let mut excess = 0.0f64;
    // Σ over the data vertices of their stationarity residual (the arc test's gate), in four
    // independent sums (row i into sum i mod 4).
    let mut data_sums = [0.0f64; 4];
    let stat = if compact {
        let mut stat = pass.free_stat;
        excess = pass.free_excess;
        // The derivative forces: at a data vertex, into its Hp (and out of its reaction, which
        // balances every other force there: a clamped end's), at a stencil's other vertices
        // beside their Hp; at a vertex the pass did not keep (never: `derivative_vertices`
        // names every stencil), unbalanced.
        let mut at_data: Vec<(usize, usize, f64)> = Vec::new();
        let mut stencil_force = vec![0.0; stencil_hp.len()];
        let reaction = multipliers.values_mut();
        for (k, f) in Terms::derivative_forces(std::mem::take(&mut terms.derivative)) {
            let (v, c) = (k / d, k % d);
            if let Ok(i) = data_vertex.binary_search(&v) {
                if reactions {
                    reaction[i * d + c] -= f;
                    terms.force_data[i * d + c] -= f;
                }
                at_data.push((i, c, f));
            } else if let Ok(s) = stencil.binary_search(&v) {
                stencil_force[s * d + c] = f;
            } else {
                stat = f64::INFINITY;
            }
        }
        for (s, (hp, &row)) in stencil_hp.chunks_exact(d).zip(&stencil_rows).enumerate() {
            let mut m = 0.0f64;
            for (h, f) in hp.iter().zip(&stencil_force[s * d..(s + 1) * d]) {
                raise(&mut m, (h + f).abs());
            }
            raise(&mut stat, m);
            raise(&mut excess, m - rounding_of(row));
        }
        let (h, f, r) = (hp_data, &terms.force_data, &terms.rounding_data);
        let rows = (h.len() / d).min(f.len() / d).min(r.len());
        let mut forced = at_data.iter().peekable();
        let mut with_force = vec![0.0; d];
        // (what one rounding of a stiffly weighted vertex exerts is not a residual; the
        // residual past the vertex's own level too, from the same largest component)
        for i in 0..rows {
            let (mut hi, fi) = (&h[i * d..(i + 1) * d], &f[i * d..(i + 1) * d]);
            if forced.peek().is_some_and(|&&(j, _, _)| j == i) {
                with_force.copy_from_slice(hi);
                while let Some((_, c, f)) = forced.next_if(|&&(j, _, _)| j == i) {
                    with_force[*c] += f;
                }
                hi = &with_force;
            }
            let mut m = 0.0;
            for (h, f) in hi.iter().zip(fi) {
                let r = (h + f).abs();
                raise(&mut m, r);
                data_sums[i % 4] += r;
            }
            raise(&mut stat, (m - r[i]).max(0.0));
            raise(
                &mut excess,
                (m - r[i] - rounding_of(pass.rows_data[i])).max(0.0),
            );
        }
        stat
    } else {
        // Hp's own buffer takes the residual (Hp is not needed after this): at the data vertices
        // first, their derivative forces then spent, then the rest of the derivative forces at
        // their vertices, and at every vertex the maxima.
        let mut r = std::mem::take(&mut pass.hp);
        let mut forces = Terms::derivative_forces(std::mem::take(&mut terms.derivative));
        let reaction = multipliers.values_mut();
        for (i, &v) in data_vertex.iter().enumerate() {
            // A fixed data vertex's reaction balances every other force there: where a
            // derivative constraint's stencil reaches a data vertex (a clamped end's), its force
            // too.
            for c in 0..d {
                let k = v * d + c;
                if let Ok(j) = forces.binary_search_by_key(&k, |&(k, _)| k) {
                    let f = forces[j].1;
                    if reactions {
                        reaction[i * d + c] -= f;
                        terms.force_data[i * d + c] -= f;
                    }
                    r[k] += f;
                    forces[j].1 = 0.0;
                }
            }
            for (rc, f) in r[v * d..(v + 1) * d]
                .iter_mut()
                .zip(&terms.force_data[i * d..(i + 1) * d])
            {
                *rc += f;
            }
            // what one rounding of a stiffly weighted vertex exerts is not a residual
            let rounding = terms.rounding_data[i];
            for rc in &mut r[v * d..(v + 1) * d] {
                *rc = (rc.abs() - rounding).max(0.0);
            }
        }
        for &(k, f) in &forces {
            r[k] += f;
        }
        // The residual's largest component at every vertex and that component's part beyond
        // the vertex's level, four vertices at a time in independent running maxima. (Only data
        // vertices out of order come here: every stage's take the compact pass.)
        let rows = &pass.rows;
        let (mut stat_lanes, mut excess_lanes) = ([0.0f64; 4], [0.0f64; 4]);
        by_lanes(rows.len().min(r.len() / d), |l, j| {
            let mut m = 0.0f64;
            for x in &r[j * d..(j + 1) * d] {
                raise(&mut m, x.abs());
            }
            raise(&mut stat_lanes[l], m);
            raise(&mut excess_lanes[l], m - rounding_of(rows[j]));
        });
        let mut stat = 0.0f64;
        raise_all(&mut stat, stat_lanes);
        raise_all(&mut excess, excess_lanes);
        stat
    };
    // The duality gap bounds E(p) − E* for a feasible p; relative to E (or, for E ≈ 0, to the
    // rounding level of the force scale times the length scale).
    let gap_rel = terms.gap
        / pass
            .energy
            .max(f64::EPSILON * force * length)
            .max(f64::MIN_POSITIVE);
    // The arc test (crate::arcs): a lower bound on the objective's excess over its optimum
    // from the net force on runs of vertices, relative to the objective (E, plus smoothing's
    // penalty) as the gap is to E. Made where no derivative constraint acts (in the compact pass),
    // and only where a bound from the residuals the pass has seen could reach [`ARC_GATE`] of
    // it: any arc's net force is at most the sum of its vertices' residuals, and its stiffness
    // at least the least k of a span (the pass's compliance).
    let energy_scale = (pass.energy + terms.penalty)
        .max(f64::EPSILON * force * length)
        .max(f64::MIN_POSITIVE);
    let arc = if compact && !derivative_kinds {
        let weights = kinds.iter().find_map(|k| k.penalty_weights());
        // (Σ over an arc's vertices and coordinates of |residual| bounds its net force in every
        // coordinate, and the sum of squares that the bound takes.)
        let (mut sum, translation) = match weights {
            None => (
                (longest_run(data_vertex, nv, knots.is_closed()) * d) as f64 * pass.free_stat,
                0.0,
            ),
            Some(w) => (
                pass.free_sum + total(data_sums),
                crate::arcs::translation(&terms.force_data, w, d),
            ),
        };
        sum *= 1.0 + 1e-6;
        let bound = sum * sum * pass.compliance / 2.0;
        let runs = if bound > ARC_GATE * energy_scale {
            crate::arcs::excess(
                knots,
                p,
                data_vertex,
                &terms.force_data,
                weights,
                pass.magnitude,
            )
        } else {
            0.0
        };
        runs.max(translation) / energy_scale
    } else {
        0.0
    };
    let values = knots.values();
    let span = values[values.len() - 1] - values[0];
    let run_off = run_off(pass.extent, data_length, terms.reach, span);
    let parts = [
        stat / force,
        // (Past its own rounding level a vertex's residual counts against the largest force
        // the curve carries, not against the floor of the stiffest row: with spans 1e-6 beside
        // spans of 0.5 and coordinates near 1e3, that floor once passed a curve whose energy
        // was 1.6e7 times the optimum's.)
        excess / hp_max.max(f64::MIN_POSITIVE),
        terms.comp / force,
        terms.dual / force,
        terms.primal.max(0.0) / data_length,
        terms.primal_rel,
        gap_rel,
        arc,
        run_off,
    ];
    // (NaN anywhere makes the residual NaN: never accepted. So does a force scale that is not
    // finite: rows of H that overflow (spans whose cubes leave the doubles, 1e-141 on chordal
    // knots of data at 1e-140) made F and every vertex's rounding level infinite, and a curve
    // 1800 times the optimum's energy read 0.)
    let kkt = if parts.iter().any(|v| v.is_nan()) || !force.is_finite() {
        f64::NAN
    } else {
        parts.iter().fold(0.0f64, |a, &v| a.max(v))
    };
    // Corollary 3.3 / 3.6: jmp = ½Hp vanishes at inactive data vertices.
    let jmp_inactive = (0..n)
        .filter(|&i| !terms.active[i] && !terms.no_jump[i])
        .map(|i| (0..d).fold(0.0f64, |a, c| a.max((0.5 * hp_data[i * d + c]).abs())) / force)
        .reduce(f64::max);
    (
        Certificate {
            energy: pass.energy,
            kkt_residual: kkt,
            active: terms.active,
            jmp_inactive,
        },
        multipliers,
    )
}

#[cfg(test)]
mod tests;
