//! Knots, divided differences and discrete derivatives of piecewise-linear curves.
//!
//! This crate implements the vocabulary of S. N. Kersey, *near-interpolatory variational
//! refinement of piecewise-linear curves* (J. Comput. Appl. Math. 223, 2009), §2 and §3.6, and the
//! parametrizations of its Algorithm 4.1 step (iv). A curve is a polygon p_1..p_N in R^d with knots
//! t_1 < … < t_N (open) or t_1 < … < t_{N+1} (closed: the last span closes the curve, and indices
//! wrap periodically, h_{i+N} = h_i).
//!
//! ```
//! use divdiff::{Knots, Points};
//! let knots = Knots::open(vec![0.0, 1.0, 3.0]).unwrap();
//! let pts = Points::from_rows(&[vec![0.0, 0.0], vec![1.0, 1.0], vec![3.0, 0.0]]).unwrap();
//! assert_eq!(knots.vertex_count(), pts.len());
//! ```

mod derivative;
mod differences;
mod error;
mod knots;
mod parametrize;
mod points;

pub use derivative::{derivative_stencil, vertex_derivative, vertex_derivatives, DerivativeRule};
pub use differences::{
    divided_difference, divided_difference_explicit, jumps, second_differences, slopes,
};
pub use error::Error;
pub use knots::{Knots, Topology};
pub use parametrize::{parametrize, Parametrization};
pub use points::Points;
