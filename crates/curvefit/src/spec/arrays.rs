//! A problem's large numeric arrays (`points`, `constraint.radii`, `t`, …): where they are in
//! the problem and what they hold, so that a reader can take them in bulk and leave the rest of
//! the problem to serde.
//!
//! Two readers do: the command line's JSON reader (`cli::fastjson`: the arrays' text parsed on
//! every core) and the Python package (a C-contiguous float64 numpy array copied as one slice).
//! Both only ever *accept*: an array is taken only when the problem's serde types would read it
//! to the same values (numbers, all finite, in the expected shape, within the field's limit).
//! The rest of the problem is read with each taken array replaced by an empty one, and the
//! arrays are then put in ([`LargeArrays::put`]); when anything does not fit, the reader reads
//! the whole problem by serde, so every error (field, index, wording) is serde's.

use serde::de::DeserializeOwned;

use super::refine::{ConstraintSpec, RefineProblem};
use super::{Numbers, Rows, MAX_NUMBERS, MAX_POINT_COORDS};

/// What one large array holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Rows of one length d ≥ 1, `[[x, y], …]` (a [`crate::spec::Rows`]); at most `max`
    /// coordinates.
    Rows {
        /// Most coordinates (the field's limit).
        max: usize,
    },
    /// Numbers, `[a, b, …]`; at most `max` of them.
    Numbers {
        /// Most numbers (the field's limit).
        max: usize,
    },
}

/// One large array of a problem: where it is (object keys from the top of the document) and
/// what it holds.
#[derive(Clone, Copy, Debug)]
pub struct Array {
    /// The keys leading to it, e.g. `["constraint", "radii"]`.
    pub path: &'static [&'static str],
    /// Its shape and limit.
    pub kind: Kind,
}

/// A large array, read by a fast path.
#[derive(Debug, PartialEq)]
pub enum Parsed {
    /// Rows, flat (row-major), and their length.
    Rows(divdiff::Points),
    /// Numbers.
    Numbers(Vec<f64>),
}

/// A problem whose large arrays a reader may parse itself.
pub trait LargeArrays: DeserializeOwned {
    /// The problem's large arrays (none by default).
    const ARRAYS: &'static [Array] = &[];
    /// Puts `value`, the array [`Self::ARRAYS`]`[i]`, into a problem that serde read with that
    /// array empty (`[]`); `false` when the problem has no place for it (then the reader reads
    /// the whole problem by serde).
    fn put(&mut self, _i: usize, _value: Parsed) -> bool {
        false
    }

    /// This problem, read with the arrays `taken` (each with its index in [`Self::ARRAYS`])
    /// empty, with them put in; `None` when one of them has no place in it.
    fn with_arrays(mut self, taken: impl IntoIterator<Item = (usize, Parsed)>) -> Option<Self> {
        taken
            .into_iter()
            .all(|(i, value)| self.put(i, value))
            .then_some(self)
    }
}

/// A problem's `points`.
const POINTS: Array = Array {
    path: &["points"],
    kind: Kind::Rows {
        max: MAX_POINT_COORDS,
    },
};

/// `rows` ← the parsed `points`, into a field read as `[]`.
fn rows(rows: &mut Rows, value: Parsed) -> bool {
    match value {
        Parsed::Rows(p) if rows.is_empty() => {
            *rows = Rows(p);
            true
        }
        _ => false,
    }
}

/// `v` ← parsed numbers, into a field read as `[]`.
fn numbers(v: &mut Vec<f64>, value: Parsed) -> bool {
    match value {
        Parsed::Numbers(x) if v.is_empty() => {
            *v = x;
            true
        }
        _ => false,
    }
}

impl LargeArrays for RefineProblem {
    const ARRAYS: &'static [Array] = &[
        POINTS,
        Array {
            path: &["knots"],
            kind: Kind::Numbers { max: usize::MAX },
        },
        Array {
            path: &["constraint", "radii"],
            kind: Kind::Numbers { max: usize::MAX },
        },
        Array {
            path: &["constraint", "weights"],
            kind: Kind::Numbers { max: usize::MAX },
        },
    ];
    fn put(&mut self, i: usize, value: Parsed) -> bool {
        match (i, &mut self.knots, &mut self.constraint) {
            (0, _, _) => rows(&mut self.points, value),
            (1, Some(knots), _) => numbers(knots, value),
            (2, _, ConstraintSpec::Balls { radii }) => numbers(radii, value),
            (3, _, ConstraintSpec::Smoothing { weights }) => numbers(weights, value),
            _ => false,
        }
    }
}

impl LargeArrays for super::StripProblem {
    const ARRAYS: &'static [Array] = &[
        Array {
            path: &["t"],
            kind: Kind::Numbers { max: MAX_NUMBERS },
        },
        Array {
            path: &["y"],
            kind: Kind::Numbers { max: MAX_NUMBERS },
        },
    ];
    fn put(&mut self, i: usize, value: Parsed) -> bool {
        let field = match i {
            0 => &mut self.t,
            1 => &mut self.y,
            _ => return false,
        };
        let Numbers(v) = field;
        numbers(v, value)
    }
}

impl LargeArrays for super::NaturalProblem {
    const ARRAYS: &'static [Array] = &[POINTS];
    fn put(&mut self, _: usize, value: Parsed) -> bool {
        rows(&mut self.points, value)
    }
}

impl LargeArrays for super::SurfaceProblem {
    const ARRAYS: &'static [Array] = &[POINTS];
    fn put(&mut self, _: usize, value: Parsed) -> bool {
        rows(&mut self.points, value)
    }
}

impl LargeArrays for super::scheme::PolygonInput {
    const ARRAYS: &'static [Array] = &[POINTS];
    fn put(&mut self, _: usize, value: Parsed) -> bool {
        rows(&mut self.points, value)
    }
}

impl LargeArrays for super::SchemeProblem {
    const ARRAYS: &'static [Array] = &[Array {
        path: &["polygon", "points"],
        kind: POINTS.kind,
    }];
    fn put(&mut self, _: usize, value: Parsed) -> bool {
        match &mut self.polygon {
            Some(polygon) => rows(&mut polygon.points, value),
            None => false,
        }
    }
}
