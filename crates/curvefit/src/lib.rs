//! curvefit facade.

pub mod cli;
