//! The `curvefit` command-line tool.
fn main() {}
