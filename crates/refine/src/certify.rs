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
//!   by the force scale F = ‖H‖_∞ · δ (δ the largest coordinate step between consecutive
//!   vertices: Hp is formed from such differences, so this is its rounding scale); at a data
//!   vertex with smoothing weight w, the part beyond w·ε·max(|p_{i_k}|_∞, |q_i|_∞, L), the force
//!   one rounding of the vertex's coordinates exerts (stiff weights, w ≫ ‖H‖);
//! - **complementarity** (|multiplier × slack|) and **negative multipliers**, over F;
//! - **primal violation** over the length scale L, the largest coordinate distance of a vertex
//!   or a data point from the data's centroid; a derivative constraint's violation relative to
//!   its own scale (max(|L p|, the set's size, Σ_u |c_u||p_u − p_v|_∞ — the rounding scale of
//!   the stencil, which a zero target lacks));
//! - the **duality gap** Σ (multiplier × slack) over E (it bounds the relative excess E(p) − E*
//!   of a feasible p over the optimum; E* = 0 is measured against the rounding level ε F L).

use divdiff::{DerivativeRule, Knots, Points};

use crate::constraint::{At, Kind, Terms};

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
pub(crate) struct Pass {
    /// Hp at every vertex (N × d).
    pub hp: Vec<f64>,
    /// E of (2.1).
    pub energy: f64,
    /// A bound on ‖H‖_∞: max_j Σ_r |A_rj| Σ_i |A_ri| with the α-rows of A.
    pub h_norm: f64,
    /// max_j |p_j − center|_∞.
    pub extent: f64,
    /// max_j |p_{j+1} − p_j|_∞ (for an open curve the chord from the last vertex back to the
    /// first counts too, as it always has in this force scale).
    pub step: f64,
}

/// Hp = 2 jmp (divided differences, module docs), E, ‖H‖_∞, the extent about `center` and the
/// largest step, in one pass per coordinate.
pub(crate) fn pass(knots: &Knots, p: &Points, center: &[f64]) -> Pass {
    let n = p.len();
    let d = p.dim();
    let x = p.coords();
    let closed = knots.is_closed();
    let h = |i: isize| knots.h(i);
    let mut hp = vec![0.0; n * d];
    let (mut energy, mut extent, mut step) = (0.0, 0.0f64, 0.0f64);
    // Whether the second difference centred at vertex i exists (all of a closed curve, the
    // interior of an open one).
    let centred = |i: usize| closed || (i >= 1 && i + 1 < n);
    // Whether span j exists.
    let span = |j: usize| closed || j + 1 < n;
    for c in 0..d {
        let at = |j: usize| x[(j % n) * d + c];
        let slope = |j: usize| (at(j + 1) - at(j)) / h(j as isize);
        // c_i for vertex i (0 where it does not exist).
        let second = |i: usize| {
            if !centred(i) {
                return 0.0;
            }
            let im = (i + n - 1) % n;
            let hl = h(i as isize - 1);
            let hr = h(i as isize);
            (slope(i) - slope(im)) / (hl + hr)
        };
        let (mut cp, mut cc) = (second(n - 1), second(0));
        for i in 0..n {
            let cn = second((i + 1) % n);
            let mut v = 0.0;
            if span(i) {
                v += (cn - cc) / h(i as isize);
            }
            if closed || i >= 1 {
                v -= (cc - cp) / h(i as isize - 1);
            }
            hp[i * d + c] = 2.0 * v;
            if centred(i) {
                energy += cc * cc * (h(i as isize - 1) + h(i as isize));
            }
            let xi = x[i * d + c];
            extent = extent.max((xi - center[c]).abs());
            step = step.max((at(i + 1) - xi).abs());
            (cp, cc) = (cc, cn);
        }
    }
    // ‖H‖_∞ bound from the α-rows (Kersey §2): row i has α₁ = √2/(h_{i−1}√(h_{i−1}+h_i)),
    // α₃ = √2/(h_i√(h_{i−1}+h_i)), α₂ = −α₁ − α₃ on vertices i − 1, i, i + 1.
    let row = |i: isize| -> [f64; 3] {
        let iu = i.rem_euclid(n as isize) as usize;
        if !closed && (i < 1 || i >= n as isize - 1 || n < 3) {
            return [0.0; 3];
        }
        let (hl, hr) = (h(iu as isize - 1), h(iu as isize));
        let r = (2.0 / (hl + hr)).sqrt();
        let (a1, a3) = (r / hl, r / hr);
        [a1, -a1 - a3, a3]
    };
    let rowsum = |a: [f64; 3]| a[0].abs() + a[1].abs() + a[2].abs();
    let mut h_norm: f64 = 0.0;
    for j in 0..n as isize {
        let (ap, ac, an) = (row(j - 1), row(j), row(j + 1));
        h_norm = h_norm
            .max(ap[2].abs() * rowsum(ap) + ac[1].abs() * rowsum(ac) + an[0].abs() * rowsum(an));
    }
    Pass {
        hp,
        energy,
        h_norm,
        extent,
        step,
    }
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
    let pass = pass(knots, p, &centroid);
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
    let force = (pass.h_norm * pass.step).max(f64::MIN_POSITIVE);
    let hp = &pass.hp;
    let hp_data: Vec<f64> = data_vertex
        .iter()
        .flat_map(|&v| hp[v * d..(v + 1) * d].iter().copied())
        .collect();
    let multipliers = multipliers.unwrap_or_else(|| {
        (0..n)
            .map(|i| hp_data[i * d..(i + 1) * d].iter().map(|x| -x).collect())
            .collect()
    });
    let derivative_kinds = kinds.iter().any(|k| k.on_derivatives());
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
    // Stationarity at every vertex: Hp + derivative forces + data forces at the data vertices.
    let mut stat: f64 = 0.0;
    let mut r = vec![0.0; d];
    let mut data_index = vec![usize::MAX; nv];
    for (i, &v) in data_vertex.iter().enumerate() {
        data_index[v] = i;
    }
    for j in 0..nv {
        r.copy_from_slice(&hp[j * d..(j + 1) * d]);
        if let Some(all) = &terms.force_all {
            for (rc, f) in r.iter_mut().zip(&all[j * d..(j + 1) * d]) {
                *rc += f;
            }
        }
        let mut rounding = 0.0;
        if data_index[j] != usize::MAX {
            let i = data_index[j];
            for (rc, f) in r.iter_mut().zip(&terms.force_data[i * d..(i + 1) * d]) {
                *rc += f;
            }
            rounding = terms.rounding_data[i];
        }
        stat = r
            .iter()
            .fold(stat, |a, x| a.max((x.abs() - rounding).max(0.0)));
    }
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

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The streaming pass gives 2 × divdiff's jumps and energy's E (2.1), on random knots,
        /// open and closed, d = 1…3.
        #[test]
        fn the_pass_is_divdiffs_jumps_and_the_energy(
            n in 3usize..12,
            d in 1usize..4,
            closed in any::<bool>(),
            h in proptest::collection::vec(0.05f64..2.0, 12),
            x in proptest::collection::vec(-1.0f64..1.0, 36),
        ) {
            let topo = if closed { Topology::Closed } else { Topology::Open };
            let spans = if closed { n } else { n - 1 };
            let mut t = vec![0.0];
            for j in 0..spans {
                t.push(t[j] + h[j]);
            }
            let kn = Knots::new(topo, t).unwrap();
            let p = Points::new(d, x[..n * d].to_vec()).unwrap();
            let pass = super::pass(&kn, &p, &vec![0.0; d]);
            let jmp = divdiff::jumps(&kn, &p).unwrap();
            let scale = pass.hp.iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for (a, b) in pass.hp.iter().zip(jmp.coords()) {
                prop_assert!((a - 2.0 * b).abs() <= 1e-12 * scale, "{a} vs 2 × {b}");
            }
            let e = energy::energy(&kn, &p).unwrap();
            prop_assert!((pass.energy - e).abs() <= 1e-12 * e.max(1e-300), "{} vs {e}", pass.energy);
        }
    }
}
