//! The discrete energy of piecewise-linear curves and O(N) solves with its Hessian.
//!
//! (Module docs, math and examples: to be written by the energy work — Kersey §2, §3.6;
//! Warren–Weimer §6.2.)

mod dense;
mod error;
mod functional;
mod hessian;
mod solve;

pub use dense::{alpha_matrix, second_difference_matrix, warren_weimer_matrix};
pub use error::Error;
pub use functional::energy;
pub use hessian::{alphas, Hessian};
pub use solve::*;
