//! The outer problem (5) — and (10) on a §4 grid: Φ(s, z) = Σ_j φ_j(s_j, z_j, s_{j+1}, z_{j+1})
//! over the slopes z at the grid points and the values s at grid points that are not data
//! sites, each φ_j the value of the per-interval problem on grid cell j.

mod bfgs;
mod newton;
mod phi;
mod setup;

pub(crate) use bfgs::bfgs;
pub(crate) use newton::newton;
pub(crate) use phi::{projected_grad, Hints, Outer};
pub(crate) use setup::{alternative_starts, setup, Setup};
