//! One file per subcommand: its [`Command`](super::Command) (the solve is the library's
//! [`crate::spec`] entry point) and its picture.

pub mod natural;
pub mod refine;
pub mod strip;
pub mod surface;
