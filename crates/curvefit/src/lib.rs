//! curvefit facade.

pub mod cli;
pub mod plot;
