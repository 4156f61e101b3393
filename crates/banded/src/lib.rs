//! Banded, block-banded and cyclic symmetric factorizations, a tridiagonal LU, and small vector
//! helpers: the linear algebra under every curvefit solver, written once. No dependencies.
//!
//! # What is here
//!
//! - [`SymBand`]`<W>`: a symmetric band matrix of half-bandwidth W ∈ 1..=4 (tridiagonal,
//!   pentadiagonal, …), open or cyclic ([`Topology`]), and its root-free LDLᵀ factor
//!   [`SymBandFactor`], solved for any number of right-hand-side columns at once (they share
//!   the factor and advance side by side).
//! - [`BlockBand`]`<W>`: A = S ⊗ I_d + B with d×d blocks (S a [`SymBand`], B symmetric block
//!   band), open or cyclic, and its block Cholesky factor [`BlockFactor`]; d = 1..4 run kernels
//!   with d fixed at compile time, larger d a general path.
//! - [`TridiagonalLu`]: a general (nonsymmetric) tridiagonal LU without pivoting, with solves
//!   by A and Aᵀ.
//! - [`vector`]: [`vector::dot`], [`vector::norm`] and [`vector::dist`] (scaled, no overflow or
//!   underflow, as LAPACK's `dnrm2`), [`vector::axpy`].
//! - [`lanes`]: sums and maxima over long arrays in four independent lanes, so that each step
//!   does not wait for the one before.
//!
//! Every factorization is O(n) in time and memory for a fixed bandwidth, tests each pivot
//! against the diagonal of its own row ([`PIVOT_RTOL`], [`FactorOptions::pivot_rtol`]) and
//! reports a failing one as [`Error::Singular`] naming the row, can replace chosen rows by
//! identity rows ([`FactorOptions::eliminated`]: prescribed unknowns), refactors into existing
//! storage (`factor_into`) and solves in place without allocating (`solve_in_place`).
//!
//! # The math
//!
//! **Band LDLᵀ / Cholesky** (Golub–Van Loan, *Matrix Computations*, 4th ed., §4.1.2, §4.2.9,
//! §4.3.5–4.3.6): a symmetric positive definite matrix of half-bandwidth W factors as
//! A = L D Lᵀ (or L Lᵀ) with L of the same lower bandwidth, so the factor costs O(n W²) and a
//! solve O(n W) per column. The scalar kind is root-free (u_ij = L_ij D_j,
//! D_i = A_ii − Σ u_ij L_ij), and for W = 1 takes its pivots from the determinant recurrence of
//! the leading minors (no division on the dependency chain); the block kind forms every Schur
//! complement as A − Σ X Xᵀ, which stays symmetric and accurate when diagonal blocks are very
//! ill-conditioned (interior-point scalings), and inverts no block.
//!
//! **Cyclic bands, bordered** (GVL §4.5.4 on block elimination; the "arrowhead" view of a
//! periodic band): a cyclic band matrix (a closed curve's couplings A_{i,i±k}, indices mod n)
//! is factored in its natural order with its last t = min(W, n) (block) rows as a dense border.
//! The first m = n − t rows are an ordinary band; L's border rows G fill in but decay
//! geometrically away from the wrap-around couplings for the matrices met here, and are flushed
//! to exact zeros once below 1e−60 of their largest entry, so only a few rows near both ends
//! carry a border; the t×t Schur complement A₂₂ − G D Gᵀ is factored densely. For n ≤ 2W the
//! band aliases: entries naming the same position add up and everything is border. The result
//! is an exact LDLᵀ / Cholesky of A in a fixed order, backward stable like any band
//! factorization.
//!
//! **The alternatives this replaces, and the measurement behind the choice**: the *zig-zag
//! order* 0, n−1, 1, n−2, … turns a cyclic band of half-bandwidth W into an open band of
//! half-bandwidth 2W (refine's condensed solver used it); *Sherman–Morrison(–Woodbury)*
//! (GVL §2.1.4) writes a cyclic tridiagonal matrix as a tridiagonal one plus a rank-one
//! correction, A = T + v vᵀ, x = T⁻¹b − (vᵀT⁻¹b)/(1 + vᵀT⁻¹v) T⁻¹v (refine's interpolation used
//! it; it can lose accuracy when 1 + vᵀT⁻¹v cancels, the bordered form cannot). Measured on the
//! same matrices, n = 10⁵, factor + solve (`cargo bench -p banded -- "cyclic ordering"`, a
//! loaded 2-core machine), the bordered form was faster in every case: cyclic tridiagonal with
//! 2 columns 15 ns/row against 20 for the zig-zag order (and 8.2 against 8.5 ns/row for
//! refine's Sherman–Morrison copy, measured side by side on an idle moment), block
//! pentadiagonal with 2×2 blocks 91 against 153 ns/row, with 3×3 blocks (assembly included)
//! 352 against 578. So the bordered form is the only cyclic form kept.
//!
//! # Who uses what
//!
//! | caller | matrix | kind |
//! |---|---|---|
//! | `energy::System` (interpolation, smoothing) | H ⊗ I_d + weights, open or closed, fixed vertices | [`SymBand`]`<2>`, d columns, `eliminated` |
//! | `energy::System` (interior-point Newton systems, tangent stencils) | H ⊗ I_d + d×d blocks | [`BlockBand`]`<2>`, `eliminated`, small `pivot_rtol` |
//! | `refine` interpolation by span condensation (`refine::fast`, `refine::uniform`) | data-row system T, cyclic tridiagonal, d columns | [`SymBand`]`<1>` |
//! | `refine` span condensation (`refine::fast::span_lu`, `span_gh`) | α-row span matrices B_i, nonsymmetric tridiagonal; first and last rows of B⁻¹ | [`TridiagonalLu`] (`solve_transposed_in_place` on e₀, e_{k−1}) |
//! | `refine` condensed backend (`backend::condensed`: balls, half-space sets) | T (d columns) and S = T ⊗ I_d + K D⁻¹ Kᵀ, cyclic block pentadiagonal | [`SymBand`]`<1>`; [`BlockBand`]`<2>` with `add_scalar`, `add_scaled`, `clear` |
//! | `strip` Newton on Φ (`strip::linalg::Band`) | Hessian of half-bandwidth ≤ 3, one column | [`SymBand`]`<3>`, `pivot_rtol(0.0)` |
//! | `strip` spline moments (`strip::spline::moments`, every step of the exchange) | symmetric diagonally dominant tridiagonal | [`TridiagonalLu`] |
//! | every crate | dot, norm, distance, axpy | [`vector`] |
//!
//! # Example
//!
//! ```
//! use banded::{FactorOptions, SymBand, Topology};
//! // A closed curve's second-difference energy with a unit weight at vertex 0 (which pins
//! // down the constants, the kernel of the energy): cyclic pentadiagonal, d = 2 columns.
//! let n = 10;
//! let mut a = SymBand::<2>::zeros(n, Topology::Cyclic);
//! for i in 0..n {
//!     // Row i of A is (1, −2, 1) on i − 1, i, i + 1: AᵀA has 6, −4, 1 on its bands.
//!     a.add(i, i, 6.0).unwrap();
//!     a.add(i, (i + 1) % n, -4.0).unwrap();
//!     a.add(i, (i + 2) % n, 1.0).unwrap();
//! }
//! // Without the weight the matrix is singular, and the factorization says where.
//! assert!(matches!(a.factor(), Err(banded::Error::Singular { index: 9 })));
//! a.add(0, 0, 1.0).unwrap();
//! let f = a.factor().unwrap();
//! let b: Vec<f64> = (0..2 * n).map(|k| (k as f64).sin()).collect();
//! let mut x = b.clone();
//! f.solve_in_place(&mut x, 2).unwrap();
//! let mut ax = vec![0.0; 2 * n];
//! a.mul_add(&x, &mut ax, 2).unwrap();
//! assert!(ax.iter().zip(&b).all(|(u, v)| (u - v).abs() < 1e-12));
//! // Vertex 3 prescribed (eliminated): its row of the solution is its right-hand side.
//! let mut fixed = vec![false; n];
//! fixed[3] = true;
//! let f = a.factor_with(&FactorOptions::default().eliminated(&fixed)).unwrap();
//! f.solve_in_place(&mut x, 2).unwrap();
//! ```
//!
//! # References
//!
//! - G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., Johns Hopkins, 2013:
//!   §4.1 (LDLᵀ), §4.2 (Cholesky, block Cholesky §4.2.9), §4.3 (banded systems, band
//!   Cholesky §4.3.5, tridiagonal systems §4.3.6), §4.5.4 (block elimination / bordered
//!   systems), §2.1.4 (Sherman–Morrison–Woodbury).
//! - N. J. Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., SIAM, 2002:
//!   Theorems 10.3–10.5 (backward error of Cholesky and LDLᵀ; the tests' bounds).
//! - E. Anderson, *Algorithm 978: Safe Scaling in the Level 1 BLAS*, ACM TOMS 44(1), 2017
//!   ([`vector::norm`]).

mod block;
mod border;
mod dense;
mod error;
pub mod lanes;
mod scalar;
#[cfg(test)]
mod tests;
mod tridiagonal;
pub mod vector;

pub use block::{BlockBand, BlockFactor};
pub use error::Error;
pub use scalar::{SymBand, SymBandFactor, MAX_HALF_BANDWIDTH};
pub use tridiagonal::TridiagonalLu;

/// The default relative pivot tolerance: a pivot p of row i is accepted only if it is finite
/// and p > `PIVOT_RTOL` · A_ii.
///
/// The pivot of a positive semidefinite matrix never exceeds its diagonal entry, and a
/// singular one (an energy Hessian with nothing pinned down: its kernel holds the constants)
/// produces pivots at rounding level, ~1e−16 · A_ii times a modest growth factor. A positive
/// definite matrix whose smallest pivot is below 1e−13 · A_ii has a condition number beyond
/// 1e13 and is treated as numerically singular. Callers that know their matrix is positive
/// definite with legitimately tiny relative pivots (interior-point Newton systems, where
/// barrier terms grow without bound on some rows) pass a smaller tolerance in
/// [`FactorOptions::pivot_rtol`]; 0 accepts every positive pivot.
pub const PIVOT_RTOL: f64 = 1e-13;

/// Open or cyclic: whether the band wraps around (a closed curve's couplings A_{i,i+k} with
/// indices mod n).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Topology {
    /// An ordinary band matrix: A_ij = 0 for |i − j| > W.
    Open,
    /// A cyclic band matrix: A_ij = 0 unless i − j or j − i is at most W mod n.
    Cyclic,
}

/// Options of a factorization: the pivot test and the rows to eliminate.
///
/// ```
/// use banded::{FactorOptions, PIVOT_RTOL};
/// let o = FactorOptions::default();
/// assert_eq!(o.pivot_rtol, PIVOT_RTOL);
/// let e = [false, true, false];
/// let o = FactorOptions::default().pivot_rtol(1e-22).eliminated(&e);
/// assert_eq!(o.eliminated, Some(&e[..]));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactorOptions<'a> {
    /// Relative pivot tolerance (default [`PIVOT_RTOL`]): a pivot p of row i is accepted only
    /// if it is finite and p > `pivot_rtol` · A_ii (for a block, A_ii is the diagonal entry of
    /// the scalar row).
    pub pivot_rtol: f64,
    /// (Block) rows to eliminate (default none): where `eliminated[i]`, row and column i are
    /// replaced by those of the identity, so solves return x_i = b_i there and the other rows
    /// do not see x_i. A caller that prescribes x_i moves A_{ji} x_i to the right-hand side
    /// itself (Dirichlet elimination).
    pub eliminated: Option<&'a [bool]>,
}

impl Default for FactorOptions<'_> {
    fn default() -> Self {
        FactorOptions {
            pivot_rtol: PIVOT_RTOL,
            eliminated: None,
        }
    }
}

impl<'a> FactorOptions<'a> {
    /// With the relative pivot tolerance `rtol`.
    pub fn pivot_rtol(self, rtol: f64) -> Self {
        FactorOptions {
            pivot_rtol: rtol,
            ..self
        }
    }

    /// With the (block) rows marked in `eliminated` replaced by identity rows.
    pub fn eliminated(self, eliminated: &'a [bool]) -> Self {
        FactorOptions {
            eliminated: Some(eliminated),
            ..self
        }
    }
}

fn check_eliminated(eliminated: Option<&[bool]>, n: usize) -> Result<(), Error> {
    match eliminated {
        Some(e) if e.len() != n => Err(Error::WrongLength {
            field: "eliminated",
            expected: n,
            got: e.len(),
        }),
        _ => Ok(()),
    }
}
