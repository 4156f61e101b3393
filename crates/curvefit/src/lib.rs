//! # curvefit
//!
//! Variational curve refinement and constrained spline interpolation: the smoothest curve that
//! honours a handful of data points — exact, known only within tolerances, or bounded by
//! obstacles — with a certificate (KKT residual, multipliers, active set) that it is optimal.
//!
//! This crate is the facade. It re-exports the library crates and their vocabulary:
//!
//! | module | source |
//! |---|---|
//! | [`divdiff`] | knots, divided differences, discrete derivatives, parametrizations (Kersey §2) |
//! | [`energy`] | the discrete energy E = ½pᵀHp, its identities and gradients, O(N) banded solves (Kersey §2) |
//! | [`refine`] | Kersey's variational refinement (§3–4) |
//! | [`subdivision`] | Khan et al.'s (2m+2)-point n-ary schemes for curves and tensor-product surfaces, Warren–Weimer's natural cubic subdivision (§6.2–6.3) |
//! | [`strip`] | best interpolation in a strip (Dontchev–Kolmanovsky) |
//!
//! plus [`export`], a refinement's limit curve as CSV, SVG, DXF and B-spline JSON text, and
//! [`spec`], the JSON contract of every subcommand as a library (problem and result types,
//! validation naming the user's field and index, one entry point per subcommand), and — with the
//! default feature `cli` — [`plot`] (SVG figures) and [`cli`] (the `curvefit` command line,
//! callable in-process).
//!
//! # Features
//! - `cli` (default): the command line (clap) and the pictures (svg); the `curvefit` binary needs
//!   it. As a library dependency, turn it off to build without clap and svg:
//!   `curvefit = { path = "…/crates/curvefit", default-features = false }`.
//!
//! ```
//! use curvefit::prelude::*;
//! let knots = Knots::closed(vec![0.0, 1.0, 2.5, 3.0, 4.0]).unwrap();
//! let h = Hessian::new(&knots);
//! assert_eq!(h.len(), 4);
//! ```

#[cfg(feature = "cli")]
pub mod cli;
pub mod export;
#[cfg(feature = "cli")]
pub mod plot;
pub mod spec;
#[cfg(not(target_arch = "wasm32"))]
pub mod threads;

pub use divdiff;
pub use energy;
pub use refine;
pub use strip;
pub use subdivision;

/// The vocabulary most programs need: `use curvefit::prelude::*;`.
pub mod prelude {
    pub use divdiff::{Knots, Points, Topology};
    pub use energy::Hessian;
}

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
