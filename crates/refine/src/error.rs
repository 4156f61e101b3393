/// Errors of the `refine` crate. Variants name the offending field and index.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Invalid knots or points (from `divdiff`).
    #[error(transparent)]
    Divdiff(#[from] divdiff::Error),
    /// A linear-algebra failure (from `energy`).
    #[error(transparent)]
    Energy(#[from] energy::Error),
    /// A subdivision-scheme parameter is out of its valid range (e.g. an odd number of stencil
    /// points, arity 1, a grid with one row).
    #[error("{field} = {value} is invalid: {reason}")]
    SchemeParameter {
        /// The parameter (e.g. `"points"`, `"arity"`, `"rows"`).
        field: &'static str,
        /// The value given.
        value: usize,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// The requested result would exceed a documented size limit (or overflow `usize`).
    #[error("{field}: the result would exceed the limit of {limit}")]
    TooLarge {
        /// What would grow too large (e.g. `"levels"`).
        field: &'static str,
        /// The limit that would be exceeded.
        limit: usize,
    },
    /// A quad mesh can be written as OBJ only for points in R^2 or R^3.
    #[error("OBJ output needs points in R^2 or R^3, got dimension {dim}")]
    ObjDimension {
        /// The dimension of the grid's points.
        dim: usize,
    },
    /// An exact linear system of a rule derivation turned out singular (pivot `index`).
    #[error("exact rule derivation: singular system at pivot {index}")]
    SingularExactSystem {
        /// The pivot (row) at which elimination failed.
        index: usize,
    },
}
