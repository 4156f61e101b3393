//! The paper's slot construction for convex polygonal constraints (Kersey §4, Fig. 4.1).
//!
//! Each half-plane K_ij = {x : u·x ≤ c} (u the unit normal) of a 2-D polygon K_i is replaced by
//! the slot {c − 2ε_ij ≤ u·x ≤ c} of half-width ε_ij = ½ (c − min_{x∈K_i} u·x), the narrowest
//! slot with that boundary edge that contains K_i, so ∩_j slots = K_i. The multiplier iteration
//! solves (H + Σ w_ij u_ij u_ijᵀ) p = Σ w_ij m_ij u_ij (a spring pulling the vertex towards each
//! slot's centre line u·x = m_ij = c − ε_ij) and updates w_ij := w_ij |u·p − m_ij| / ε_ij: the
//! weight grows while the vertex is outside its slot and decays to 0 while it stays inside, as
//! the slack condition of (3.8) requires. It is approximate, like the ball iteration; the exact
//! solver is the default.

use crate::constraint::HalfSpace;

/// Vertices of the polygon ∩ {n·x ≤ c} clipped to the square of half-size `extent` about
/// `around` (Sutherland–Hodgman); empty when the intersection is empty. Unbounded polygons are
/// represented by their part inside the square.
pub fn halfplane_polygon(halfspaces: &[HalfSpace], around: [f64; 2], extent: f64) -> Vec<[f64; 2]> {
    let (x, y, e) = (around[0], around[1], extent);
    let mut poly = vec![
        [x - e, y - e],
        [x + e, y - e],
        [x + e, y + e],
        [x - e, y + e],
    ];
    for h in halfspaces {
        if h.normal.len() < 2 {
            continue;
        }
        let f = |p: &[f64; 2]| h.normal[0] * p[0] + h.normal[1] * p[1] - h.offset;
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (fa, fb) = (f(&a), f(&b));
            if fa <= 0.0 {
                out.push(a);
            }
            if (fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0) {
                let s = fa / (fa - fb);
                out.push([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])]);
            }
        }
        poly = out;
        if poly.is_empty() {
            break;
        }
    }
    poly
}

/// One slot: unit normal u, centre line u·x = `centre`, half-width ε.
#[derive(Clone, Debug)]
pub(crate) struct Slot {
    pub unit: [f64; 2],
    pub norm: f64,
    pub centre: f64,
    pub half_width: f64,
}

/// The slots of a 2-D polygon `set`; `extent` bounds unbounded polygons (see
/// [`halfplane_polygon`]). `None` when the polygon is empty.
pub(crate) fn slots(set: &[HalfSpace], around: [f64; 2], extent: f64) -> Option<Vec<Slot>> {
    let poly = halfplane_polygon(set, around, extent);
    if poly.is_empty() {
        return None;
    }
    Some(
        set.iter()
            .map(|h| {
                let norm = h.normal[0].hypot(h.normal[1]);
                let unit = [h.normal[0] / norm, h.normal[1] / norm];
                let c = h.offset / norm;
                let lowest = poly
                    .iter()
                    .map(|p| unit[0] * p[0] + unit[1] * p[1])
                    .fold(f64::INFINITY, f64::min);
                // A degenerate (zero-width) polygon still gets a slot of positive width.
                let half_width = (0.5 * (c - lowest)).max(f64::EPSILON * extent);
                Slot {
                    unit,
                    norm,
                    centre: c - half_width,
                    half_width,
                }
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hs(n: [f64; 2], c: f64) -> HalfSpace {
        HalfSpace {
            normal: n.to_vec(),
            offset: c,
        }
    }

    #[test]
    fn slots_of_a_square_are_its_width() {
        // The square |x| ≤ 1, |y| ≤ 1: every slot has half-width 1 and centre line through 0.
        let set = [
            hs([1.0, 0.0], 1.0),
            hs([-1.0, 0.0], 1.0),
            hs([0.0, 2.0], 2.0),
            hs([0.0, -1.0], 1.0),
        ];
        let s = slots(&set, [0.0, 0.0], 10.0).unwrap();
        for slot in &s {
            assert!(
                (slot.half_width - 1.0).abs() < 1e-12 && slot.centre.abs() < 1e-12,
                "{slot:?}"
            );
        }
        assert!((s[2].norm - 2.0).abs() < 1e-15);
    }

    #[test]
    fn empty_polygon_has_no_slots() {
        assert!(slots(
            &[hs([1.0, 0.0], -1.0), hs([-1.0, 0.0], -1.0)],
            [0.0, 0.0],
            10.0
        )
        .is_none());
    }
}
