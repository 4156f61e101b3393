//! Test and benchmark support for `strip` (not part of its API; `publish = false`).
//!
//! * [`examples`]: problems in the spirit of the seed's §5 (the paper does not print its data;
//!   these are invented to show the same phenomena) and a large sweep problem.
//! * [`channel`]: a generator of hard channels — a smooth wave with steep tanh fronts and
//!   narrow bumps, half-width 0.01–0.04, bounds as polylines with M vertices or as one cubic per
//!   data interval, n nearly equispaced sites on the centre line.
//! * [`mod@lower_bound`]: an independent lower bound on the optimum — the fine-grid QP (values and
//!   second derivatives at grid points, bounds only at the grid points) solved by Clarabel.
//! * [`exact`]: exact checks of a returned solution, written independently of the solver: the
//!   strip on every sub-interval between consecutive breaks and bound vertices (roots of the
//!   derivative of the cubic minus the bound), interpolation and C² continuity.

// Index loops mirror the formulas (several arrays indexed together).
#![allow(clippy::needless_range_loop)]

pub mod channel;
pub mod exact;
pub mod examples;
pub mod lower_bound;

pub use channel::{BoundKind, Channel};
pub use exact::{
    c2_jump, c2_rounding, interpolation_error, lemma_1_1, moved_data, strip_violation, C2Rounding,
    Lemma11, Violation,
};
pub use lower_bound::{fine_grid, lower_bound, lower_bound_qp, LowerBound, LowerBoundQp};

/// The value at `x` of a bound in data interval `i` (the interval containing `x`; the right one
/// at a data site), evaluated directly from the user's description — independent of the
/// solver's own bound handling.
pub fn bound_at(b: &strip::Bound, t: &[f64], x: f64) -> Option<f64> {
    match b {
        strip::Bound::None => None,
        strip::Bound::Pieces(p) => {
            let n = t.len();
            let i = t.partition_point(|v| *v <= x).clamp(1, n - 1) - 1;
            let (c, s) = (p[i], x - t[i]);
            Some(c[0] + s * (c[1] + s * (c[2] + s * c[3])))
        }
        strip::Bound::Polyline(v) => {
            let k = v.partition_point(|q| q[0] <= x).clamp(1, v.len() - 1);
            let (a, b) = (v[k - 1], v[k]);
            Some(a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]))
        }
    }
}
