//! The discrete energy of piecewise-linear curves, its derivatives, and O(N) solves with its
//! Hessian.
//!
//! Implements S. N. Kersey, *near-interpolatory variational refinement of piecewise-linear
//! curves* (J. Comput. Appl. Math. 223, 2009; seed `000_8a81be4d4deadca6.txt`) §2 (energy, (2.1),
//! Theorem 2.1, Corollary 2.2, Lemmas 2.3–2.4, Corollary 2.7) and §3.6 (open curves), and relates
//! it to Warren–Weimer, *Subdivision Methods for Geometric Design* §6.2 (seed
//! `003_b8a6b4d8b36f17f8.txt`). Vertex indices are 0-based; knots, points and the divided
//! differences come from [`divdiff`]; the O(N) factorizations from [`banded`]. The dense
//! nalgebra exports (`alpha_matrix`, `second_difference_matrix`, `warren_weimer_matrix`,
//! `Hessian::to_dense`) are behind the cargo feature `dense`, off by default: they serve tests
//! and verification, the solve path never forms a dense matrix.
//!
//! # The math
//!
//! For a polygon p_0..p_{N−1} in R^d with knots t_i (see [`divdiff::Knots`]), slopes
//! s_i = (p_{i+1} − p_i)/h_i and second differences Δ_{i−1,2} f = (s_i − s_{i−1})/(h_{i−1} + h_i):
//!
//! - **Energy (2.1)** ([`energy`]): E(f) = Σ_i |Δ_{i−1,2} f|² h_{i−1,2} = Σ_i |s_i − s_{i−1}|²/(h_{i−1} + h_i),
//!   over all vertices of a closed curve and the interior ones of an open curve; it discretizes
//!   ½∫|f''|².
//! - **Matrix form** ([`alphas`], [`Hessian`]): E = ½ pᵀHp with H = AᵀA, row i of A holding
//!   α_{i,1} = √2/(h_{i−1}√h_{i−1,2}), α_{i,2} = −α_{i,1} − α_{i,3}, α_{i,3} = √2/(h_i√h_{i−1,2}) on
//!   columns i − 1, i, i + 1. Closed curves use the periodic extension h_{−1} = h_{N−1} (the
//!   printed shortcut α_{1,1} := α_{n,3} is right only for uniform knots); open curves have zero
//!   first and last rows. H is symmetric positive semidefinite, (cyclic) pentadiagonal, with
//!   kernel the constants (closed, dim 1) or the linear polynomials in t (open, dim 2). It is
//!   stored as three bands and applied in O(N d); `Hessian::to_dense` (cargo feature `dense`)
//!   is for tests only.
//!   (§3.6 writes E = pᵀHp for open curves; the ½ of (2.1) still applies.)
//! - **Theorem 2.1** ([`energy_by_jumps`]): E = Σ p_i · jmp_i(D³f); **Corollary 2.2**: jmp = ½Hp;
//!   **Lemma 2.3**: ∂E/∂p = Hp ([`Hessian::apply`]).
//! - **Lemma 2.4, corrected** ([`knot_gradient`], [`vertex_knot_gradient`]): for fixed points,
//!   ∂E/∂t_i = 2[s_{i−1}·(Δ_{i−1,2} − Δ_{i−2,2})/h_{i−1} − s_i·(Δ_{i,2} − Δ_{i−1,2})/h_i] +
//!   |Δ_{i,2} f|² − |Δ_{i−2,2} f|². The printed Lemma 2.4 ([`knot_gradient_printed`]) lacks the
//!   factor 2 and the last two terms and fails a finite-difference check (`cargo xtask verify`
//!   shows both). **Corollary 2.7** residuals Df(t_i)·(Hp)_i: [`orthogonality_residuals`].
//! - **Solves** ([`System`], [`solve_interpolatory`]): K = H ⊗ I_d + weights + d×d blocks +
//!   tangent stencils, fixed vertices eliminated, factored in O(N) by the `banded` crate (scalar
//!   LDLᵀ shared by the d columns, or block Cholesky; closed curves bordered).
//! - **Warren–Weimer §6.2** (`warren_weimer_matrix`, feature `dense`): E_k = 8^k D₂ᵀD₂ on the
//!   grid 2^{−k} Z.
//!   On uniform open knots of spacing h, α_i = h^{−3/2}(1, −2, 1), so H = h^{−3} D₂ᵀD₂; with
//!   h = 2^{−k} that is **exactly E_k as a matrix**. The energies differ by ½: Kersey's
//!   E = ½ pᵀHp approximates ½∫|f''|², Warren–Weimer's pᵀE_k p approximates ∫|f''|².
//!
//! # Example
//!
//! ```
//! use divdiff::{jumps, Knots, Points};
//! use energy::{energy, energy_by_jumps, Hessian};
//! let knots = Knots::closed(vec![0.0, 0.4, 1.5, 2.0, 3.2]).unwrap();
//! let p = Points::from_rows(&[[0.0, 0.0], [1.0, 0.1], [1.2, 1.0], [0.1, 0.8]]).unwrap();
//! let h = Hessian::new(&knots);
//! // E three ways: (2.1), ½pᵀHp, pᵀ·jmp (Theorem 2.1).
//! let e = energy(&knots, &p).unwrap();
//! assert!((h.energy(&p).unwrap() - e).abs() < 1e-12 * e);
//! assert!((energy_by_jumps(&knots, &p).unwrap() - e).abs() < 1e-12 * e);
//! // Corollary 2.2: jmp = ½Hp.
//! let hp = h.apply(&p);
//! let j = jumps(&knots, &p).unwrap();
//! assert!(j.coords().iter().zip(hp.coords()).all(|(a, b)| (a - 0.5 * b).abs() < 1e-12 * e));
//! ```

#[cfg(feature = "dense")]
mod dense;
mod error;
mod functional;
mod hessian;
mod system;

#[cfg(feature = "dense")]
pub use dense::{alpha_matrix, second_difference_matrix, warren_weimer_matrix};
pub use error::Error;
pub use functional::{
    energy, energy_by_jumps, knot_gradient, knot_gradient_printed, orthogonality_residuals,
    vertex_knot_gradient,
};
pub use hessian::{alphas, Hessian};
pub use system::{solve_interpolatory, Factor, System, PIVOT_RTOL};
