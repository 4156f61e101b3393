/// Errors of the `energy` crate. Variants name the offending field and index.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Invalid knots or points (from `divdiff`).
    #[error(transparent)]
    Divdiff(#[from] divdiff::Error),
    /// The linear system is singular: the factorization met a non-positive pivot at `vertex`
    /// (e.g. all weights zero, so the kernel of H is not pinned down).
    #[error("singular system: non-positive pivot at vertex {vertex}")]
    Singular {
        /// The vertex whose pivot failed.
        vertex: usize,
    },
    /// Two objects that must agree in size do not.
    #[error("{field} has size {got}, expected {expected}")]
    WrongLength {
        /// The field.
        field: &'static str,
        /// The expected size.
        expected: usize,
        /// The given size.
        got: usize,
    },
    /// An index is out of range.
    #[error("{field} index {index} is out of range (size {len})")]
    IndexOutOfRange {
        /// The field.
        field: &'static str,
        /// The index given.
        index: usize,
        /// The valid size.
        len: usize,
    },
    /// A stencil couples two vertices more than two steps apart (K would leave the band).
    #[error("stencil couples vertices {first} and {second}, more than two steps apart")]
    StencilTooWide {
        /// One stencil vertex.
        first: usize,
        /// Another stencil vertex.
        second: usize,
    },
    /// The banded linear algebra refused an argument (not expected: `energy` checks sizes,
    /// indices and the band before it calls `banded`; reported rather than assumed).
    #[error(transparent)]
    Banded(banded::Error),
    /// A vertex is fixed twice.
    #[error("fixed vertex {index} is given twice")]
    DuplicateFixed {
        /// The vertex.
        index: usize,
    },
}

impl From<banded::Error> for Error {
    /// A failing pivot names its vertex ([`Error::Singular`]); anything else is
    /// [`Error::Banded`].
    fn from(e: banded::Error) -> Self {
        match e {
            banded::Error::Singular { index } => Error::Singular { vertex: index },
            other => Error::Banded(other),
        }
    }
}
