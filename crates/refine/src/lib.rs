//! Variational refinement of curves and uniform interpolating subdivision.
//!
//! (Crate docs, math and examples: to be written — Kersey §3–4; Khan et al.; Warren–Weimer §6.)

mod conic;
mod error;
mod kersey;
mod schemes;

pub use conic::*;
pub use error::Error;
pub use kersey::*;
pub use schemes::*;
