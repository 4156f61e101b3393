//! Kersey's Newton systems behind [`conic::KktSystem`]: the full-vertex system on all refined
//! vertices ([`full`]) and the condensation onto the data vertices ([`condensed`]).

pub(crate) mod condensed;
pub(crate) mod full;
pub(crate) mod working_set;
