//! One primal–dual interior-point method for quadratic cone programs, with its linear algebra
//! behind a trait.
//!
//! # The problem
//!
//! minimize ½ xᵀPx + qᵀx + c  subject to  s = b − A x ∈ K,
//!
//! P symmetric positive semidefinite, K a product of zero cones (equalities), nonnegative
//! orthants and second-order cones of any size ([`Cone`], [`cone`]) — the form of Clarabel
//! (Goulart & Chen 2024) and CVXOPT's `coneqp` (Vandenberghe 2010). A ball |y − q| ≤ ε is
//! (ε, q − y) ∈ Q^{d+1}; a direction wedge {v : v·a ≥ |v| cos θ} is (v·a / cos θ, v) ∈ Q^{d+1}; a
//! half-space n·y ≤ c is c − n·y ≥ 0.
//!
//! # The method
//!
//! Mehrotra's predictor–corrector (Mehrotra 1992) with Nesterov–Todd scaling (Nesterov & Todd
//! 1997, 1998), as in Vandenberghe (2010) §3–§5: from (x, s, z) with s, z interior, and the
//! scaling V with V z = V⁻¹ s = λ,
//!
//! 1. residuals r_x = P x + q + Aᵀz, r_s = A x + s − b, gap sᵀz, μ = sᵀz/ν (ν the degree);
//! 2. the Newton system P dx + Aᵀdz = −r_x, A dx + ds = −r_s, V⁻¹ds + V dz = ξ, reduced to
//!
//!    (P + AᵀV⁻²A) dx = −r_x − Aᵀ(V⁻¹ξ + V⁻² r_s),  dz = V⁻¹ξ + V⁻²(r_s + A dx),  ds = −r_s − A dx,
//!
//!    with zero-cone rows as the quasi-definite block −δ I (Θ = I/δ, Vanderbei 1995) and the
//!    direction refined against δ = 0 ([`RefinementOptions`]);
//! 3. predictor ξ = −λ, step α_a to the boundary, centring σ = ((s + α_a ds)ᵀ(z + α_a dz)/sᵀz)³;
//! 4. corrector ξ = λ⁻¹ ∘ (σμe − λ∘λ − (V⁻¹ds_a)∘(V dz_a)), step 0.99 × the step to the boundary.
//!
//! One factorization per iteration serves both solves. The method stops when the relative KKT
//! residual ([`Residuals`], module [`residual`]) is at most [`Options::tolerance`]. An
//! active-set polish ([`polish`]) — Newton on the KKT system of the constraints the iterate
//! identifies as active, with a stiff penalty holding their normals — removes the interior-point
//! bias once the iterate is close, and the point returned carries its certificate.
//!
//! # The seam
//!
//! The method sees the problem only through [`KktSystem`]: apply P (and the gradient Px + q),
//! apply A and Aᵀ, and factor P + AᵀΘA + σD̂ for the block weights Θ ([`Weights`]) of the
//! current scaling. [`DenseProblem`] is the dense backend (small problems, the tests);
//! `refine` implements the trait for Kersey's banded Newton systems (the full-vertex system
//! H ⊗ I_d + Σ LᵀFᵀΘFL on ≤ 3-vertex stencils) and for the data-vertex condensation
//! ((T + K D⁻¹Kᵀ), the free vertices eliminated exactly). With the feature `clarabel`,
//! [`clarabel::solve`] hands a problem that exports its matrices ([`clarabel::Sparse`]) to
//! Clarabel instead.
//!
//! # Example
//!
//! The projection of (2, 1) onto the unit disc: minimize ½|x − (2, 1)|² s.t. (1, x) ∈ Q³.
//!
//! ```
//! use conic::{Cone, Cones, DenseProblem, Options};
//! let cones = Cones::new(vec![Cone::SecondOrder(3)]).unwrap();
//! // s = b − A x = (1, x): A = [0 0; −1 0; 0 −1], b = (1, 0, 0).
//! let mut problem = DenseProblem::new(
//!     vec![1.0, 0.0, 0.0, 1.0],
//!     vec![-2.0, -1.0],
//!     vec![0.0, 0.0, -1.0, 0.0, 0.0, -1.0],
//!     vec![1.0, 0.0, 0.0],
//!     cones,
//! )
//! .unwrap();
//! let sol = conic::solve(&mut problem, &Options::default()).unwrap();
//! let r = 5f64.sqrt();
//! assert!((sol.x[0] - 2.0 / r).abs() < 1e-9 && (sol.x[1] - 1.0 / r).abs() < 1e-9);
//! assert!(sol.residuals.total <= 1e-9);
//! ```
//!
//! # References
//!
//! - L. Vandenberghe, *The CVXOPT linear and quadratic cone program solvers*, 2010.
//! - Yu. Nesterov, M. J. Todd, *Self-scaled barriers and interior-point methods for convex
//!   programming*, Math. Oper. Res. 22 (1997); *Primal–dual interior-point methods for
//!   self-scaled cones*, SIAM J. Optim. 8 (1998).
//! - S. Mehrotra, *On the implementation of a primal–dual interior point method*, SIAM J.
//!   Optim. 2 (1992).
//! - P. J. Goulart, Y. Chen, *Clarabel: an interior-point solver for conic programs with
//!   quadratic objectives*, arXiv:2405.12762 (2024).
//! - R. J. Vanderbei, *Symmetric quasidefinite matrices*, SIAM J. Optim. 5 (1995).

pub mod cone;
mod dense;
mod error;
mod ipm;
mod kkt;
mod options;
pub mod polish;
mod product;
pub mod residual;
mod vector;
mod weights;

#[cfg(feature = "clarabel")]
pub mod clarabel;

pub use cone::{Cone, Cones, Kind};
pub use dense::DenseProblem;
pub use error::Error;
pub use ipm::{Iterate, Monitor, NoMonitor, Solution, Start, Status};
pub use kkt::{gram_through_apply_at, KktSystem, Scales};
pub use options::{Options, PolishOptions, RefinementOptions, Regularization};
pub use residual::Residuals;
pub use weights::{BlockWeight, Weights};

/// Solves the problem behind `kkt` from the default start (crate docs).
///
/// # Errors
/// [`Error::WrongLength`] / [`Error::NonFinite`] for a malformed `b`; [`Error::Singular`] when
/// the first Newton matrix does not factor. A run that does not reach the tolerance is returned
/// with its [`Status`] and certificate, not as an error: see [`Solution::accepted`].
pub fn solve<K: KktSystem + ?Sized>(kkt: &mut K, options: &Options) -> Result<Solution, Error> {
    ipm::run(kkt, options, None, &mut NoMonitor)
}

/// [`solve`] from a given start, with a [`Monitor`] watching the iterates.
///
/// # Errors
/// As [`solve`]; also [`Error::WrongLength`], [`Error::NonFinite`] or [`Error::InvalidValue`]
/// for a start of the wrong size or outside its cones.
pub fn solve_with<K: KktSystem + ?Sized>(
    kkt: &mut K,
    options: &Options,
    start: Option<Start>,
    monitor: &mut dyn Monitor,
) -> Result<Solution, Error> {
    ipm::run(kkt, options, start, monitor)
}
