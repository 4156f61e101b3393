//! The seam between the method and its linear algebra.

use crate::cone::Cones;
use crate::weights::Weights;
use crate::Error;

/// Fixed scales of a problem, below which the relative residuals ([`crate::Residuals`]) do
/// not divide: a force scale F₀ (units of P x) and a length scale L₀ (units of x and s). A
/// problem whose optimum has P x* = 0 or b = 0 needs them to measure anything relative; 0
/// means "no floor" (only the iterate's own sizes are used).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Scales {
    /// F₀.
    pub force: f64,
    /// L₀.
    pub length: f64,
}

/// A quadratic cone program
///
///   minimize ½ xᵀPx + qᵀx + c  subject to  s = b − A x ∈ K,
///
/// P symmetric positive semidefinite (n × n), A (m × n), K a product of cones ([`Cones`]),
/// exposed through the operations the method needs. A backend owns the structure: it may apply
/// P matrix-free, keep eliminated variables out of x (folding them into q and c), and factor the
/// Newton matrix with whatever banded, condensed or dense factorization fits.
///
/// The method ([`crate::solve`]) only ever solves with the matrix
///
///   K(Θ, σ) = P + AᵀΘA + σ D̂,
///
/// Θ block diagonal ([`Weights`]) and D̂ a positive diagonal of the backend's choosing that
/// scales like P's diagonal (σ > 0 is the static regularization of
/// [`crate::Regularization`]); every direction is refined against the exact operators
/// ([`KktSystem::apply_p`], [`KktSystem::apply_a`], [`KktSystem::apply_at`]), so a backend may
/// regularize or eliminate inexactly inside `factor` as long as its solves are close to K⁻¹.
pub trait KktSystem {
    /// The number of variables n.
    fn num_vars(&self) -> usize;

    /// The cones of the slack's rows (m rows in all).
    fn cones(&self) -> &Cones;

    /// b (m entries).
    fn b(&self) -> &[f64];

    /// g = P x + q into `g`; returns the objective ½ xᵀPx + qᵀx + c (c the backend's constant,
    /// so that the objective is the model's own, e.g. the energy, which the duality gap is
    /// measured against).
    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> f64;

    /// y = P v.
    fn apply_p(&mut self, v: &[f64], y: &mut [f64]);

    /// y = A x (m entries).
    fn apply_a(&self, x: &[f64], y: &mut [f64]);

    /// out = Aᵀ z (n entries, overwritten).
    fn apply_at(&self, z: &[f64], out: &mut [f64]);

    /// G = A_b A_bᵀ, the Gram matrix of block `block`'s rows (m_b × m_b row-major, into `out`).
    /// The default is [`gram_through_apply_at`], O(n + m) per row; a backend that knows its
    /// blocks' rows forms it locally.
    fn block_gram(&self, block: usize, out: &mut [f64]) {
        gram_through_apply_at(self, block, out);
    }

    /// A positive estimate of P's diagonal over the variables that block `b`'s rows touch,
    /// divided by the squared size of those rows: a weight θ on the block competes with P where
    /// θ is comparable to this. The regularization δ_b of equality rows and the polish's
    /// penalties are set relative to it.
    fn diagonal_scale(&self, block: usize) -> f64;

    /// The problem's fixed scales (default: none).
    fn scales(&self) -> Scales {
        Scales::default()
    }

    /// Factors K(Θ, σ) (see the trait docs) for the following [`KktSystem::solve`]s.
    ///
    /// # Errors
    /// [`Error::Singular`] when the factorization meets a non-positive pivot.
    fn factor(&mut self, weights: &Weights, static_regularization: f64) -> Result<(), Error>;

    /// rhs ← K(Θ, σ)⁻¹ rhs with the last factorization.
    fn solve(&mut self, rhs: &mut [f64]);

    /// out = (P + AᵀΘA) v for the Θ of the last factorization (without its σ), if the backend
    /// has that operator at hand (e.g. the factored system itself); `false` (the default) lets
    /// the method form it from [`KktSystem::apply_p`], [`KktSystem::apply_a`] and
    /// [`KktSystem::apply_at`]. Used by iterative refinement when there are no zero cones.
    fn apply_newton(&mut self, v: &[f64], out: &mut [f64]) -> bool {
        let _ = (v, out);
        false
    }

    /// Called when a direction's iterative refinement stalled far from its target: the last
    /// factorization is too far from K(Θ, σ). A backend that can factor more exactly (at a
    /// higher cost) switches to that — for the repeated iteration at least, for the rest of the
    /// solve at most, as it sees fit — and returns `true`; the method then repeats the iteration.
    /// The default returns `false` (nothing better to offer).
    fn escalate(&mut self) -> bool {
        false
    }

    /// Whether the last factorization is of K(Θ, σ) itself, up to rounding (default false: a
    /// backend that regularizes or eliminates inexactly inside `factor`). With an exact
    /// factorization the method refines its directions only once the iterate is close
    /// ([`crate::RefinementOptions::exact_from`]).
    fn factor_is_exact(&self) -> bool {
        false
    }
}

/// [`KktSystem::block_gram`] from [`KktSystem::apply_at`] on unit vectors: A_bᵀ e_k for each of
/// the block's rows, then their dot products (the default, and the reference a backend's own
/// Gram matrix is tested against).
pub fn gram_through_apply_at<K: KktSystem + ?Sized>(kkt: &K, block: usize, out: &mut [f64]) {
    let r = kkt.cones().range(block);
    let n = kkt.num_vars();
    let mut unit = vec![0.0; kkt.cones().rows()];
    let cols: Vec<Vec<f64>> = r
        .map(|k| {
            unit[k] = 1.0;
            let mut c = vec![0.0; n];
            kkt.apply_at(&unit, &mut c);
            unit[k] = 0.0;
            c
        })
        .collect();
    let m = cols.len();
    for i in 0..m {
        for j in 0..m {
            out[i * m + j] = crate::vector::dot(&cols[i], &cols[j]);
        }
    }
}
