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
}
