//! The discrete energy of piecewise-linear curves and O(N) solves with its Hessian.
//!
//! (Module docs, math and examples: to be written by the energy work — Kersey §2, §3.6;
//! Warren–Weimer §6.2.)

mod error;
mod solve;

pub use error::Error;
pub use solve::*;
