//! Uniform stationary subdivision: the (2m+2)-point n-ary interpolating family of Khan et al.
//! (seed 001, (3.13) and the tensor product (4.2)) and natural cubic splines by variational
//! subdivision on a bounded interval (Warren–Weimer ch. 6, seed 003, Theorems 6.3 and 6.4).
//!
//! Every rule is *derived* in exact rational arithmetic ([`BigRational`]) and only then rounded
//! (correctly, to the nearest `f64`) for application:
//!
//! * [`NaryScheme`]: p^{k+1}_{n i + a} = Σ_{j=−m}^{m+1} L_j(a/n) p^k_{i+j}, L_j the Lagrange basis on
//!   the nodes −m..m+1 (math.md §3). Applied to closed and open polygons in R^d
//!   ([`NaryScheme::subdivide`]) and to quad grids ([`NaryScheme::subdivide_grid`], [`QuadGrid`],
//!   [`quad_mesh_obj`]).
//! * Natural cubic splines on [0, L] (math.md §5): the inner-product matrices
//!   [`natural_inner_product_matrix`], upsampling [`upsampling_matrix`], subdivision matrices
//!   [`natural_subdivision_matrix`] solved from the two-scale relation E_k S_{k−1} = U_{k−1} E_{k−1},
//!   the interpolation matrix [`natural_interpolation_matrix`] from its recurrence, and the f64
//!   scheme [`NaturalScheme`] (subdivision, interpolation via N⁻¹, exact limit energy).

mod dense;
mod nary;
mod natural;
mod rational;
mod surface;

pub use dense::RationalMatrix;
pub use nary::{NaryScheme, MAX_ARITY, MAX_SCHEME_POINTS, MAX_SUBDIVISION_COORDS};
pub use natural::{
    natural_inner_product_matrix, natural_interpolation_matrix, natural_subdivision_matrix,
    upsampling_matrix, NaturalScheme, SparseRow, MAX_EXACT_INTERVALS, MAX_NATURAL_COORDS,
};
pub use num_rational::BigRational;
pub use rational::{lagrange_weights, rational_to_f64};
pub use surface::{quad_mesh_obj, QuadGrid, SurfaceRule};
