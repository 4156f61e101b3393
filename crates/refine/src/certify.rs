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
//! - **primal violation** over the length scale L, the largest coordinate distance of a vertex
//!   or a data point from the data's centroid; a derivative constraint's violation relative to
//!   its own scale (max(|L p|, the set's size, Σ_u |c_u||p_u − p_v|_∞ — the rounding scale of
//!   the stencil, which a zero target lacks));
//! - the **duality gap** Σ (multiplier × slack) over E (it bounds the relative excess E(p) − E*
//!   of a feasible p over the optimum; E* = 0 is measured against the rounding level ε F L).
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
//! The verification suite's independent recomputation (`xtask/src/verify/refine/kkt.rs`) uses
//! the same scale with ‖H‖_∞ alone in R (the same largest row sum, see [`Pass::h_norm`]): this
//! certificate is exactly as strict as that one except for radii or weights large enough that
//! w_max is comparable to ‖H‖_∞, where that one asks for accuracy below rounding.

use divdiff::{DerivativeRule, Knots, Points};

use crate::constraint::{At, Kind, Terms};

/// The multiple of ε ‖H‖_∞ max|p| that bounds the rounding in Hp (module docs).
const ROUNDING_MULTIPLE: f64 = 16.0;

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
    /// max |Hp| over the vertices that are not data vertices, when the pass was given them.
    pub free_stat: f64,
    /// E of (2.1).
    pub energy: f64,
    /// A bound on ‖H‖_∞: max_j Σ_r |A_rj| Σ_i |A_ri| with the α-rows of A.
    pub h_norm: f64,
    /// max_j |p_j − center|_∞.
    pub extent: f64,
    /// max_j |p_j|_∞, the size of the coordinates (the rounding level's scale).
    pub magnitude: f64,
}

/// Hp = 2 jmp (divided differences, module docs), E, ‖H‖_∞, the extent about `center` and the
/// largest coordinate, in one pass over the vertices. The reciprocals 1/h_{i−1}, 1/h_i and
/// 1/(h_{i−1} + h_i) are formed once per vertex and shared by its coordinates (divisions were
/// most of a large interpolation's certified solve); a missing span or second difference (the
/// ends of an open curve) has reciprocal 0, so its terms vanish without a branch.
///
/// Given the data vertices (strictly increasing), Hp is kept only there and its largest size over
/// the other vertices is returned instead (`hp_data`, `free_stat`): no N × d buffer.
pub(crate) fn pass(knots: &Knots, p: &Points, center: &[f64], data: Option<&[usize]>) -> Pass {
    let (n, d) = (p.len(), p.dim());
    let mut hp = vec![0.0; if data.is_some() { 0 } else { n * d }];
    let mut hp_data = vec![0.0; data.map_or(0, |v| v.len() * d)];
    // Chunks of vertices in parallel (`crate::par`), each with the slices of Hp it writes: all
    // of its vertices', or its data vertices'.
    let mut chunks = Vec::new();
    let (mut hp_rest, mut data_rest) = (&mut hp[..], &mut hp_data[..]);
    let mut first_data = 0;
    for range in crate::par::ranges(n, crate::par::CHUNK_VERTICES) {
        let own = if data.is_some() { 0 } else { range.len() * d };
        let (here, rest) = std::mem::take(&mut hp_rest).split_at_mut(own);
        hp_rest = rest;
        let end_data = data.map_or(0, |v| v.partition_point(|&x| x < range.end));
        let (dhere, drest) =
            std::mem::take(&mut data_rest).split_at_mut((end_data - first_data) * d);
        data_rest = drest;
        chunks.push((Chunk { range, first_data }, here, dhere));
        first_data = end_data;
    }
    let input = Input {
        knots,
        p,
        center,
        data,
    };
    let parts = crate::par::map(chunks, |(chunk, hp, hp_data)| {
        let mut out = Pass::default();
        // Blocks of up to three coordinates per sweep (the first one also forms ‖H‖_∞).
        let mut first = 0;
        while first < d {
            let width = (d - first).min(3);
            let (hp, hp_data) = (&mut hp[..], &mut hp_data[..]);
            let block = match width {
                3 => sweep::<3>(&input, &chunk, first, (hp, hp_data)),
                2 => sweep::<2>(&input, &chunk, first, (hp, hp_data)),
                _ => sweep::<1>(&input, &chunk, first, (hp, hp_data)),
            };
            out.merge(&block);
            first += width;
        }
        out
    });
    let mut out = Pass::default();
    for part in &parts {
        out.merge(part);
    }
    out.hp = hp;
    out.hp_data = hp_data;
    out
}

impl Pass {
    /// Folds another block's or chunk's sums and maxima into this one.
    fn merge(&mut self, other: &Pass) {
        self.free_stat = self.free_stat.max(other.free_stat);
        self.energy += other.energy;
        self.h_norm = self.h_norm.max(other.h_norm);
        self.extent = self.extent.max(other.extent);
        self.magnitude = self.magnitude.max(other.magnitude);
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

/// The reciprocals at vertex i (module docs of [`pass`]): 1/h_{i−1}, 1/h_i, h_{i−1} + h_i and
/// its reciprocal — 0 where the span or the centred difference does not exist.
#[derive(Clone, Copy)]
struct Geo {
    ihl: f64,
    ihr: f64,
    w: f64,
    iw: f64,
}

impl Geo {
    /// Row i's terms of the ‖H‖_∞ bound. The α-row of vertex i (Kersey §2) is
    /// α₁ = √2/(h_{i−1}√(h_{i−1}+h_i)), α₂ = −α₁ − α₃, α₃ = √2/(h_i√(h_{i−1}+h_i)) on vertices
    /// i − 1, i, i + 1, with absolute sum 2(α₁ + α₃); the products |α₃|·2(α₁ + α₃),
    /// |α₂|·2(α₁ + α₃), |α₁|·2(α₁ + α₃) — what row i adds at vertices i + 1, i, i − 1 — are
    /// 4/(h_{i−1} h_i²), 4(h_{i−1} + h_i)/(h_{i−1}² h_i²), 4/(h_{i−1}² h_i): no square root.
    /// Zero where the centred difference does not exist.
    fn norm_terms(&self) -> [f64; 3] {
        if self.w > 0.0 {
            let p = 4.0 * self.ihl * self.ihr;
            [p * self.ihr, p * (self.ihl + self.ihr), p * self.ihl]
        } else {
            [0.0; 3]
        }
    }
}

/// m ← max(m, v) for m not NaN: what `f64::max` gives (a NaN v leaves m), as one compare and
/// select instead of `max`'s NaN handling — the running maxima were a fifth of the sweep.
#[inline(always)]
fn raise(m: &mut f64, v: f64) {
    if v > *m {
        *m = v;
    }
}

/// Where a sweep writes Hp: every vertex's, or (given the data vertices) the data vertices'.
type HpOut<'a> = (&'a mut [f64], &'a mut [f64]);

/// [`pass`] over `chunk`'s vertices and the coordinates `first .. first + D`; ‖H‖_∞ with the first
/// block only.
fn sweep<const D: usize>(
    &Input {
        knots,
        p,
        center,
        data,
    }: &Input<'_>,
    chunk: &Chunk,
    first: usize,
    (hp, hp_data): HpOut<'_>,
) -> Pass {
    let (n, d) = (p.len(), p.dim());
    let x = p.coords();
    let closed = knots.is_closed();
    // h_j = t_{j+1} − t_j for every span j (n of a closed curve, n − 1 of an open one): the
    // knot values run past the last span, so no index wraps.
    let t = knots.values();
    let spans = knots.span_count();
    let next = |i: usize| if i + 1 == n { 0 } else { i + 1 };
    // The span before vertex i (none at the start of an open curve).
    let before = |i: usize| match (i, closed) {
        (0, true) => Some(n - 1),
        (0, false) => None,
        _ => Some(i - 1),
    };
    let recip = |j: usize| {
        if j < spans {
            1.0 / (t[j + 1] - t[j])
        } else {
            0.0
        }
    };
    // The vertex's geometry given 1/h_{i−1} (carried from the vertex before).
    let geo = |i: usize, ihl: f64| {
        let centred = closed || (i >= 1 && i + 1 < n);
        let hr = if i < spans { t[i + 1] - t[i] } else { 0.0 };
        let (w, iw) = if centred {
            let hl = if i == 0 {
                t[n] - t[n - 1]
            } else {
                t[i] - t[i - 1]
            };
            (hl + hr, 1.0 / (hl + hr))
        } else {
            (0.0, 0.0)
        };
        Geo {
            ihl,
            ihr: if i < spans { 1.0 / hr } else { 0.0 },
            w,
            iw,
        }
    };
    let geo_at = |i: usize| geo(i, before(i).map_or(0.0, recip));
    let at = |j: usize| -> [f64; D] { std::array::from_fn(|c| x[j * d + first + c]) };
    // s_j for span j (0 where it does not exist).
    let slope = |j: usize, ih: f64| -> [f64; D] {
        let (a, b) = (at(j), at(next(j)));
        std::array::from_fn(|c| (b[c] - a[c]) * ih)
    };
    let second = |g: &Geo, left: &[f64; D], right: &[f64; D]| -> [f64; D] {
        std::array::from_fn(|c| (right[c] - left[c]) * g.iw)
    };
    // c_i at vertex i from scratch: the same operations the loop below carries from vertex to
    // vertex, so a chunk starts exactly where the loop before it would have been.
    let second_at = |i: usize| -> [f64; D] {
        let g = geo_at(i);
        let left = before(i).map_or([0.0; D], |j| slope(j, recip(j)));
        second(&g, &left, &slope(i, g.ihr))
    };
    let start = chunk.range.start;
    let (g0, c0) = (geo_at(0), second_at(0));
    let mut g = geo_at(start);
    let mut cc = second_at(start);
    let mut s = slope(start, g.ihr);
    let mut cp = before(start).map_or([0.0; D], second_at);
    let mut row_prev = before(start).map_or([0.0; 3], |j| geo_at(j).norm_terms());
    let mut row = g.norm_terms();
    let c_mid: [f64; D] = std::array::from_fn(|c| center[first + c]);
    let mut out = Pass::default();
    // The next data vertex (when Hp is kept only there), and where this chunk's Hp starts.
    let mut next_data = chunk.first_data;
    for i in chunk.range.clone() {
        let i1 = next(i);
        let (g1, cn) = if i1 == 0 {
            (g0, c0)
        } else {
            let g1 = geo(i1, g.ihr);
            let s1 = slope(i1, g1.ihr);
            let cn = second(&g1, &s, &s1);
            s = s1;
            (g1, cn)
        };
        let xi = at(i);
        let v: [f64; D] =
            std::array::from_fn(|c| 2.0 * ((cn[c] - cc[c]) * g.ihr - (cc[c] - cp[c]) * g.ihl));
        match data {
            None => {
                let o = (i - start) * d + first;
                hp[o..o + D].copy_from_slice(&v);
            }
            Some(dv) if dv.get(next_data) == Some(&i) => {
                let o = (next_data - chunk.first_data) * d + first;
                hp_data[o..o + D].copy_from_slice(&v);
                next_data += 1;
            }
            Some(_) => {
                for vc in v {
                    raise(&mut out.free_stat, vc.abs());
                }
            }
        }
        for c in 0..D {
            out.energy += cc[c] * cc[c] * g.w;
            raise(&mut out.extent, (xi[c] - c_mid[c]).abs());
            raise(&mut out.magnitude, xi[c].abs());
        }
        if first == 0 {
            let row_next = if i1 == 0 && !closed {
                [0.0; 3]
            } else {
                g1.norm_terms()
            };
            // Σ_r |A_rj| Σ_l |A_rl| over the rows j − 1, j, j + 1 that touch vertex j.
            raise(&mut out.h_norm, row_prev[0] + row[1] + row_next[2]);
            (row_prev, row) = (row, row_next);
        }
        (cp, cc, g) = (cc, cn, g1);
    }
    out
}

/// Certifies points `p` for data `q` attached at `data_vertex` under `kinds` (the data kind
/// first), with the data kind's multipliers in the conventions of
/// [`crate::Refinement::multipliers`] (`None`: the reactions −(Hp)_{i_k} of interpolation,
/// computed here) and the derivative kinds' (dual, force) in the order of their rows. Returns
/// the certificate and the multipliers.
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
) -> (Certificate, Vec<Vec<f64>>) {
    let d = p.dim();
    let n = q.len();
    let nv = p.len();
    let mut centroid = vec![0.0; d];
    for x in q.iter() {
        for (c, v) in centroid.iter_mut().zip(x) {
            *c += v / n as f64;
        }
    }
    let derivative_kinds = kinds.iter().any(|k| k.on_derivatives());
    // Without derivative forces, stationarity away from the data vertices is |Hp| alone, so the
    // pass keeps Hp only at the data vertices (when they are in order, as every stage's are).
    let compact = !derivative_kinds
        && data_vertex.windows(2).all(|w| w[0] < w[1])
        && data_vertex.last().is_none_or(|&v| v < nv);
    let mut pass = pass(knots, p, &centroid, compact.then_some(data_vertex));
    let q_extent = q
        .iter()
        .map(|x| {
            x.iter()
                .zip(&centroid)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let length = pass.extent.max(q_extent).max(f64::MIN_POSITIVE);
    if !compact {
        pass.hp_data = data_vertex
            .iter()
            .flat_map(|&v| pass.hp[v * d..(v + 1) * d].iter().copied())
            .collect();
    }
    let hp_data = &pass.hp_data;
    let multipliers = multipliers.unwrap_or_else(|| {
        (0..n)
            .map(|i| hp_data[i * d..(i + 1) * d].iter().map(|x| -x).collect())
            .collect()
    });
    let mut terms = Terms::new(n, d, nv, derivative_kinds);
    let at = At {
        p,
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
    let hp_max = if compact {
        hp_data.iter().fold(pass.free_stat, |a, x| a.max(x.abs()))
    } else {
        pass.hp.iter().fold(0.0f64, |a, x| a.max(x.abs()))
    };
    let rounding =
        ROUNDING_MULTIPLE * f64::EPSILON * (pass.h_norm + terms.stiffness) * pass.magnitude;
    let force = hp_max
        .max(rounding / ROUNDING_COUNTS_AS)
        .max(f64::MIN_POSITIVE);
    // Stationarity at every vertex: Hp + derivative forces + data forces at the data vertices.
    let stat = if compact {
        hp_data
            .iter()
            .zip(&terms.force_data)
            .enumerate()
            .fold(pass.free_stat, |a, (k, (h, f))| {
                // what one rounding of a stiffly weighted vertex exerts is not a residual
                a.max(((h + f).abs() - terms.rounding_data[k / d]).max(0.0))
            })
    } else {
        // Summed into Hp's own buffer (Hp is not needed after this).
        let mut r = std::mem::take(&mut pass.hp);
        if let Some(all) = &terms.force_all {
            for (rc, f) in r.iter_mut().zip(all) {
                *rc += f;
            }
        }
        for (i, &v) in data_vertex.iter().enumerate() {
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
        r.iter().fold(0.0f64, |a, x| a.max(x.abs()))
    };
    // The duality gap bounds E(p) − E* for a feasible p; relative to E (or, for E ≈ 0, to the
    // rounding level of the force scale times the length scale).
    let gap_rel = terms.gap
        / pass
            .energy
            .max(f64::EPSILON * force * length)
            .max(f64::MIN_POSITIVE);
    let parts = [
        stat / force,
        terms.comp / force,
        terms.dual / force,
        terms.primal.max(0.0) / length,
        terms.primal_rel,
        gap_rel,
    ];
    // (NaN anywhere makes the residual NaN: never accepted.)
    let kkt = if parts.iter().any(|v| v.is_nan()) {
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
mod tests {
    use divdiff::{Knots, Points, Topology};
    use proptest::prelude::*;

    /// Across chunk boundaries (`crate::par`: each chunk restarts the sweep's carried state), the
    /// pass is still 2 × divdiff's jumps at every vertex and E (2.1) — open and closed, on
    /// jittered knots, N a few chunks long and not a multiple of the chunk.
    #[test]
    fn the_pass_is_the_jumps_across_chunks() {
        let n = 3 * crate::par::CHUNK_VERTICES + 123;
        let mut state: u64 = 7;
        let mut unif = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for topo in [Topology::Open, Topology::Closed] {
            let spans = if topo == Topology::Closed { n } else { n - 1 };
            let mut t = vec![0.0];
            for j in 0..spans {
                t.push(t[j] + 0.1 + unif());
            }
            let kn = Knots::new(topo, t).unwrap();
            let x: Vec<f64> = (0..2 * n).map(|_| unif() - 0.5).collect();
            let p = Points::new(2, x).unwrap();
            let pass = super::pass(&kn, &p, &[0.0, 0.0], None);
            let jmp = divdiff::jumps(&kn, &p).unwrap();
            let scale = pass.hp.iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for (j, (a, b)) in pass.hp.iter().zip(jmp.coords()).enumerate() {
                assert!(
                    (a - 2.0 * b).abs() <= 1e-12 * scale,
                    "{topo:?} at {j}: {a} vs 2 × {b}"
                );
            }
            let e = energy::energy(&kn, &p).unwrap();
            assert!(
                (pass.energy - e).abs() <= 1e-12 * e,
                "{} vs {e}",
                pass.energy
            );
            // The data-vertex form keeps the same values at the data vertices.
            let data: Vec<usize> = (0..n).step_by(8).collect();
            let compact = super::pass(&kn, &p, &[0.0, 0.0], Some(&data));
            let kept: Vec<f64> = data
                .iter()
                .flat_map(|&v| pass.hp[2 * v..2 * v + 2].to_vec())
                .collect();
            assert_eq!(compact.hp_data, kept);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The streaming pass gives 2 × divdiff's jumps and energy's E (2.1), on random knots,
        /// open and closed, d = 1…5 (blocks of three coordinates and a remainder).
        #[test]
        fn the_pass_is_divdiffs_jumps_and_the_energy(
            n in 3usize..12,
            d in 1usize..6,
            closed in any::<bool>(),
            h in proptest::collection::vec(0.05f64..2.0, 12),
            x in proptest::collection::vec(-1.0f64..1.0, 60),
        ) {
            let topo = if closed { Topology::Closed } else { Topology::Open };
            let spans = if closed { n } else { n - 1 };
            let mut t = vec![0.0];
            for j in 0..spans {
                t.push(t[j] + h[j]);
            }
            let kn = Knots::new(topo, t).unwrap();
            let p = Points::new(d, x[..n * d].to_vec()).unwrap();
            let pass = super::pass(&kn, &p, &vec![0.0; d], None);
            // Kept only at every other vertex: the same values there, the largest elsewhere.
            let data: Vec<usize> = (0..n).step_by(2).collect();
            let compact = super::pass(&kn, &p, &vec![0.0; d], Some(&data));
            let kept: Vec<f64> = data.iter().flat_map(|&v| pass.hp[v * d..(v + 1) * d].to_vec()).collect();
            prop_assert_eq!(&compact.hp_data, &kept);
            let free = (1..n).step_by(2).flat_map(|v| pass.hp[v * d..(v + 1) * d].to_vec()).fold(0.0f64, |a, x| a.max(x.abs()));
            prop_assert_eq!(compact.free_stat.to_bits(), free.to_bits());
            prop_assert_eq!(compact.energy.to_bits(), pass.energy.to_bits());
            let jmp = divdiff::jumps(&kn, &p).unwrap();
            let scale = pass.hp.iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for (a, b) in pass.hp.iter().zip(jmp.coords()) {
                prop_assert!((a - 2.0 * b).abs() <= 1e-12 * scale, "{a} vs 2 × {b}");
            }
            let e = energy::energy(&kn, &p).unwrap();
            prop_assert!((pass.energy - e).abs() <= 1e-12 * e.max(1e-300), "{} vs {e}", pass.energy);
            // ‖H‖_∞'s bound, row by row from its definition (every index through Knots::h),
            // and at least ‖H‖_∞ of energy's dense Hessian.
            let row = |i: isize| -> [f64; 3] {
                if !closed && (i < 1 || i >= n as isize - 1) {
                    return [0.0; 3];
                }
                let (hl, hr) = (kn.h(i - 1), kn.h(i));
                let r = (2.0 / (hl + hr)).sqrt();
                [r / hl, -r / hl - r / hr, r / hr]
            };
            let sum = |a: [f64; 3]| a.iter().map(|v| v.abs()).sum::<f64>();
            let bound = (0..n as isize)
                .map(|j| {
                    let (a, b, c) = (row(j - 1), row(j), row(j + 1));
                    a[2].abs() * sum(a) + b[1].abs() * sum(b) + c[0].abs() * sum(c)
                })
                .fold(0.0f64, f64::max);
            prop_assert!((pass.h_norm - bound).abs() <= 1e-12 * bound, "{} vs {bound}", pass.h_norm);
            let dense = energy::Hessian::new(&kn).to_dense();
            let norm = (0..n)
                .map(|i| (0..n).map(|j| dense[(i, j)].abs()).sum::<f64>())
                .fold(0.0f64, f64::max);
            prop_assert!(pass.h_norm >= norm * (1.0 - 1e-12), "{} < ‖H‖ = {norm}", pass.h_norm);
            let magnitude = p.coords().iter().fold(0.0f64, |a, x| a.max(x.abs()));
            prop_assert_eq!(
                pass.magnitude.to_bits(),
                magnitude.to_bits(),
                "magnitude {} vs {}",
                pass.magnitude,
                magnitude
            );
        }
    }
}
