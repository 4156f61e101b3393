//! Uniform stationary subdivision: the (2m+2)-point n-ary interpolating family of Khan et al.
//! and natural cubic splines by variational subdivision on a bounded interval (Warren–Weimer).
//!
//! Every rule is *derived* in exact rational arithmetic ([`BigRational`]) and only then rounded
//! (correctly, to the nearest `f64`) for application. The crate depends on `divdiff` (for
//! [`divdiff::Points`] and [`divdiff::Topology`]) and on `num-rational` only.
//!
//! # Khan et al.: the (2m+2)-point n-ary scheme
//!
//! F. Khan, I. Mukhtar, N. Batool, *A unified interpolating subdivision scheme for
//! curves/surfaces by using Newton interpolating polynomial*, Open J. Appl. Sci. 3 (2013)
//! 263–269 (seed `001_cafe51339d0f2638.txt`), §3 (curves) and §4 (surfaces).
//!
//! - **(3.13)** ([`NaryScheme`]): for m ≥ 0 and n ≥ 2,
//!   p^{k+1}_{n i + a} = Σ_{j=−m}^{m+1} L_j(a/n) p^k_{i+j}, a = 0, …, n − 1, where L_j is the
//!   Lagrange basis on the nodes −m, …, m+1 ([`lagrange_weights`]; the seed writes it through
//!   Newton's form (2.3)–(2.5) and the coefficients C of (3.6), (3.12)). Residue a = 0 is the
//!   identity (the scheme interpolates), every rule sums to 1 ((2.2)) and reproduces
//!   polynomials of degree ≤ 2m + 1. Remark 3.1's members: m = 1, n = 2 is the 4-point
//!   Dubuc–Deslauriers / Dyn–Levin–Gregory rule (−1, 9, 9, −1)/16; m = 2, n = 2 the 6-point
//!   rule (3, −25, 150, 150, −25, 3)/256; m = 1, n = 3 the ternary 4-point rule
//!   (−5, 60, 30, −4)/81 and its mirror. (The seed's printed masks have lost their signs and
//!   carry typos; `cargo xtask verify` lists each.) Applied to closed polygons periodically and
//!   to open polygons with one-sided end stencils of the same width.
//! - **(4.1)–(4.2)** ([`NaryScheme::subdivide_grid`], [`NaryScheme::surface_rules`],
//!   [`QuadGrid`], [`quad_mesh_obj`]): the tensor product on a regular quad grid,
//!   p^{k+1}_{n i + a, n j + b} = Σ_{r,s} L_r(a/n) L_s(b/n) p^k_{i+r, j+s}.
//! - **Support and smoothness** ([`Mask`], [`smoothness`]): the masks of the curve and surface
//!   schemes ([`NaryScheme::mask`], [`NaryScheme::surface_mask`]), the support of their basic
//!   limit functions (±(n(m+1) − 1)/(n − 1) per direction: Lemma 4.1 and Remark 4.2, four-sided
//!   support, the product of the curve supports), and their Hölder exponent and Cᵏ class from
//!   difference schemes and joint-spectral-radius bounds (Lemma 4.2: the tensor product is as
//!   smooth as the curve scheme). The seed states no smoothness per (m, n); the computed values
//!   are compared with the literature in the tests and in `cargo xtask verify`.
//!
//! # Warren–Weimer: natural cubic splines by variational subdivision
//!
//! J. Warren, H. Weimer, *Subdivision Methods for Geometric Design*, Morgan Kaufmann 2002,
//! ch. 6 (seed `003_b8a6b4d8b36f17f8.txt`), §6.2.4 and §6.3. On the grid 2^{−k} Z ∩ [0, L]:
//!
//! - the inner-product matrix E_k = 8^k D₂ᵀD₂ ([`natural_inner_product_matrix`]; D₂ the
//!   second-difference matrix) and the upsampling matrix U_k ([`upsampling_matrix`]);
//! - **Theorem 6.3** ([`natural_subdivision_matrix`]): subdivision matrices solving the two-scale
//!   relation E_{k+1} S_k = U_k E_k (6.17) make p_k = S_{k−1} p_{k−1} satisfy the multiscale
//!   relation E_k p_k = U_{k−1} ⋯ U_0 E_0 p_0 (6.16). The relation fixes S only up to the
//!   kernel of E_{k+1}; interpolating ends pin it, and the solution has the book's rows (end unit
//!   vectors, interior (½, ½) and (⅛, ¾, ⅛));
//! - **§6.3.1** ([`natural_interpolation_matrix`]): the interpolation matrix N with
//!   Uᵀ N S = N, rows (1), (⅙, ⅔, ⅙), (1): the limit curve of p_0 takes the values N p_0 at the
//!   integers, so p_0 = N⁻¹ b interpolates b ([`NaturalScheme::interpolate`], Fig. 6.7);
//! - **Theorem 6.4** ([`NaturalScheme::limit_energy`]): the limit curve's energy is exactly
//!   ∫ p_∞''² = p_0ᵀ E_0 N_0 p_0, the limit of the discrete energies p_kᵀ E_k p_k
//!   ([`NaturalScheme::energy`]).
//!
//! [`NaturalScheme`] applies the exactly derived rules in `f64` to points in R^d, coordinate by
//! coordinate (the parametric use of Fig. 6.6), in O(N) per level.
//!
//! # Example
//!
//! ```
//! use divdiff::{Points, Topology};
//! use subdivision::{BigRational, NaryScheme, NaturalScheme};
//! // Khan et al. (3.13) with m = 1, n = 2: the 4-point rule (−1, 9, 9, −1)/16, exactly.
//! let four_point = NaryScheme::new(4, 2)?;
//! let sixteenth = |v: i64| BigRational::new(v.into(), 16.into());
//! assert_eq!(four_point.exact_rule(1), &[sixteenth(-1), sixteenth(9), sixteenth(9), sixteenth(-1)]);
//! // Two levels on a closed square: 4 · 2² points, the old ones kept (interpolating).
//! let square = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])?;
//! let fine = four_point.subdivide(&square, Topology::Closed, 2)?;
//! assert_eq!(fine.len(), 16);
//! assert_eq!(fine.point(4), square.point(1));
//!
//! // Warren–Weimer: natural cubic subdivision of an open polygon on [0, 4]; the discrete
//! // energies decrease to the exact limit energy p0ᵀE0N0p0 (Theorem 6.4).
//! let natural = NaturalScheme::new()?;
//! let p0 = Points::from_rows(&[[0.0], [1.0], [0.0], [2.0], [1.0]])?;
//! let levels = natural.subdivide_levels(&p0, 6)?;
//! let exact = natural.limit_energy(&p0)?;
//! let e6 = NaturalScheme::energy(&levels[6], 6);
//! assert!(e6 > exact && (e6 - exact) / exact < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod error;
mod jsr;
mod matrix;
mod nary;
mod natural;
mod rational;
mod smoothness;
mod surface;

pub use error::Error;
pub use matrix::RationalMatrix;
pub use nary::{NaryScheme, MAX_ARITY, MAX_SCHEME_POINTS, MAX_SUBDIVISION_COORDS};
pub use natural::{
    natural_inner_product_matrix, natural_interpolation_matrix, natural_subdivision_matrix,
    upsampling_matrix, NaturalScheme, SparseRow, MAX_EXACT_INTERVALS, MAX_NATURAL_COORDS,
};
pub use num_rational::BigRational;
pub use rational::{lagrange_weights, rational_to_f64};
pub use smoothness::{smoothness, Bounds, Mask, Smoothness, SmoothnessOptions};
pub use surface::{quad_mesh_obj, QuadGrid, SurfaceRule};
