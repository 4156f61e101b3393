//! Kersey's Newton systems behind [`conic::KktSystem`]: the full-vertex system on all refined
//! vertices ([`full`]) and the condensation onto the data vertices ([`condensed`], with the
//! inverses of its points' weights in [`inverse`]), solved over a working set of data
//! constraints ([`working_set`], whose rounds are polished by [`round_polish`]).

pub(crate) mod condensed;
pub(crate) mod full;
mod inverse;
mod round_polish;
pub(crate) mod working_set;
