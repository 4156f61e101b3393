//! Points as JSON rows `[[x, y, …], …]`, read straight into one flat vector and written
//! straight from it.
//!
//! Reading costs 8 bytes per coordinate and nothing per point: a row is never a `Vec` of its
//! own, and no `serde_json::Value` is built (a `Vec` per point cost ~56 bytes for a 1-D point,
//! 14 times the 4 bytes of `[1],` — ROBUSTNESS.md §3). The number of coordinates is limited while
//! reading ([`MAX_POINT_COORDS`]), so an oversized input is refused before its memory is spent.

use std::fmt;

use serde::de::{DeserializeSeed, Error as _, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Largest number of coordinates (points × dimension) in one `points` array. No subcommand can
/// use more: a refinement has at least twice the data's coordinates and is limited to
/// [`refine::MAX_REFINED_COORDS`](super::refine::MAX_REFINED_COORDS) = 5·10⁷; the other
/// subcommands' results are limited to 10⁷ coordinates.
pub const MAX_POINT_COORDS: usize = 25_000_000;

/// Largest number of entries in one array of numbers read by [`Numbers`] (`t`, `y` of `strip`).
pub const MAX_NUMBERS: usize = 25_000_000;

/// Points `[[x, y, …], …]` of one dimension d ≥ 1 (an empty array has d = 0), stored flat as a
/// [`divdiff::Points`]. Deserializing checks that every row has the first row's length and
/// refuses more than `MAX` coordinates (default [`MAX_POINT_COORDS`]) as soon as the array
/// reaches it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rows<const MAX: usize = MAX_POINT_COORDS>(pub divdiff::Points);

impl<const MAX: usize> std::ops::Deref for Rows<MAX> {
    type Target = divdiff::Points;
    fn deref(&self) -> &divdiff::Points {
        &self.0
    }
}

impl<const MAX: usize> Rows<MAX> {
    /// Rows from nested vectors (for tests and callers that have them).
    ///
    /// # Errors
    /// When the rows have different lengths, no coordinates, or non-finite values.
    pub fn from_rows<R: AsRef<[f64]>>(rows: &[R]) -> Result<Self, divdiff::Error> {
        if rows.is_empty() {
            return Ok(Rows::default());
        }
        divdiff::Points::from_rows(rows).map(Rows)
    }
}

impl<const MAX: usize> Serialize for Rows<MAX> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        // An empty `Rows` (the default) has dimension 0, which has no rows to iterate.
        if self.0.dim() > 0 {
            for p in self.0.iter() {
                seq.serialize_element(p)?;
            }
        }
        seq.end()
    }
}

/// The message of an array cut off at its limit (the count is a lower bound: reading stops
/// there).
pub(crate) fn too_large(what: &str, limit: usize) -> String {
    format!(
        "more than {limit} {what}, the limit (nothing larger can be solved within the output limits)"
    )
}

/// Reads one row, appending its coordinates to `coords`; a row of another length than
/// `expected` is an error here, inside the row, so that its path names the point.
struct Row<'a> {
    coords: &'a mut Vec<f64>,
    expected: Option<usize>,
    max: usize,
}

impl<'de> DeserializeSeed<'de> for Row<'_> {
    type Value = usize;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for Row<'_> {
    type Value = usize;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a point, an array of numbers like [0.5, 1.25]")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let start = self.coords.len();
        while let Some(x) = seq.next_element::<f64>()? {
            if self.coords.len() >= self.max {
                return Err(A::Error::custom(too_large("coordinates", self.max)));
            }
            self.coords.push(x);
        }
        let d = self.coords.len() - start;
        match self.expected {
            None if d == 0 => Err(A::Error::custom(
                "a point needs at least one coordinate (dimension d ≥ 1)",
            )),
            Some(e) if d != e => Err(A::Error::custom(format!(
                "has {d} coordinates, expected {e} like the first point"
            ))),
            _ => Ok(d),
        }
    }
}

struct RowsVisitor<const MAX: usize>;

impl<'de, const MAX: usize> Visitor<'de> for RowsVisitor<MAX> {
    type Value = Rows<MAX>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an array of points like [[0, 0], [1, 0.5]]")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Rows<MAX>, A::Error> {
        let mut coords = Vec::new();
        let mut dim = 0;
        let mut n = 0usize;
        // A reader that knows the number of rows (a numpy array, a Python list; not JSON text)
        // gets the whole buffer once the first row gives the dimension: no regrowing copies.
        let rows = seq.size_hint();
        while let Some(d) = seq.next_element_seed(Row {
            coords: &mut coords,
            expected: (n > 0).then_some(dim),
            max: MAX,
        })? {
            dim = d;
            n += 1;
            if let (1, Some(rows)) = (n, rows) {
                coords.reserve_exact(rows.saturating_mul(d).min(MAX).saturating_sub(d));
            }
        }
        if n == 0 {
            return Ok(Rows::default());
        }
        coords.shrink_to_fit();
        // JSON numbers are finite (serde_json refuses 1e999), so this cannot fail.
        divdiff::Points::new(dim, coords)
            .map(Rows)
            .map_err(A::Error::custom)
    }
}

impl<'de, const MAX: usize> Deserialize<'de> for Rows<MAX> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Rows<MAX>, D::Error> {
        d.deserialize_seq(RowsVisitor::<MAX>)
    }
}

/// An array of numbers, refused beyond [`MAX_NUMBERS`] entries while it is read (a
/// `Vec<f64>` would first grow to the input's size).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Numbers(pub Vec<f64>);

impl std::ops::Deref for Numbers {
    type Target = Vec<f64>;
    fn deref(&self) -> &Vec<f64> {
        &self.0
    }
}

impl Serialize for Numbers {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Numbers {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Numbers, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Numbers;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an array of numbers like [0, 0.5, 2]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Numbers, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = seq.next_element::<f64>()? {
                    if v.len() >= MAX_NUMBERS {
                        return Err(A::Error::custom(too_large("numbers", MAX_NUMBERS)));
                    }
                    v.push(x);
                }
                v.shrink_to_fit();
                Ok(Numbers(v))
            }
        }
        d.deserialize_seq(V)
    }
}

#[cfg(feature = "schema")]
impl<const MAX: usize> schemars::JsonSchema for Rows<MAX> {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Points".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "Points [[x, y, …], …]: each an array of numbers, all of one length d ≥ 1.",
            "type": "array",
            "items": {"type": "array", "items": {"type": "number"}, "minItems": 1},
            "maxItems": MAX
        })
    }
}

#[cfg(feature = "schema")]
impl schemars::JsonSchema for Numbers {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Numbers".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "type": "array",
            "items": {"type": "number"},
            "maxItems": MAX_NUMBERS
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(s: &str) -> Result<Rows, String> {
        let mut de = serde_json::Deserializer::from_str(s);
        super::super::from_deserializer::<Rows, _>(&mut de).map_err(|e| e.to_string())
    }

    #[test]
    fn rows_are_read_flat() {
        let r = rows("[[0, 1], [2, 3.5], [4, 5]]").unwrap();
        assert_eq!((r.len(), r.dim()), (3, 2));
        assert_eq!(r.coords(), &[0.0, 1.0, 2.0, 3.5, 4.0, 5.0]);
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            "[[0.0,1.0],[2.0,3.5],[4.0,5.0]]"
        );
        assert!(rows("[]").unwrap().is_empty());
        assert_eq!(serde_json::to_string(&Rows::<10>::default()).unwrap(), "[]");
    }

    #[test]
    fn bad_rows_name_the_point() {
        let e = rows("[[0, 1], [2]]").unwrap_err();
        assert!(e.starts_with("[1]: has 1 coordinates, expected 2"), "{e}");
        let e = rows("[[], []]").unwrap_err();
        assert!(e.starts_with("[0]: a point needs"), "{e}");
        let e = rows("[[0, 1], [2, \"x\"]]").unwrap_err();
        assert!(e.starts_with("[1][1]"), "{e}");
    }
}
