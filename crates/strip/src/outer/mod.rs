//! The outer problem (5) of the seed on the data sites — Φ(z) = Σ φ_i(z_i, z_{i+1}) over the
//! slopes — for bounds given as cubic pieces per data interval: Newton's method on its
//! tridiagonal Hessian (default) or argmin's BFGS (the seed's method).

mod bfgs;
mod newton;
mod phi;
mod setup;

pub(crate) use bfgs::bfgs;
pub(crate) use newton::{decrement_at, newton};
pub(crate) use phi::{Hints, Outer, OuterOut};
pub(crate) use setup::{alternative_starts, setup, Setup};
