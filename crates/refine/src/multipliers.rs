//! The multipliers of a refinement's data constraints, one row per data point, stored flat.
//!
//! A row's meaning is the constraint's ([`crate::Refinement::multipliers`]): the d components
//! of an interpolation reaction, a ball's or a smoothing weight, one weight per half-space of a
//! polytope. Rows of one width (every kind but half-space sets of different sizes) are one
//! array of n × width values; otherwise the rows' starts are kept too. Why flat: a row per heap
//! allocation was a fifth of a large certified interpolation (10⁵ allocations and frees per
//! solve).

use std::ops::Index;

/// Rows of multipliers, one per data point ([`crate::Refinement::multipliers`]).
///
/// ```
/// use refine::Multipliers;
/// let m = Multipliers::from(vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
/// assert_eq!((m.len(), m.width()), (2, Some(2)));
/// assert_eq!(&m[1], &[3.0, 4.0]);
/// assert_eq!(m.iter().map(|r| r[0]).sum::<f64>(), 4.0);
/// ```
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Multipliers {
    values: Vec<f64>,
    /// `None`: every row is `width` values long; else the start of each row and the end.
    starts: Option<Vec<usize>>,
    width: usize,
    rows: usize,
}

impl Multipliers {
    /// `rows` rows of `width` values each, row after row in `values`.
    ///
    /// # Panics
    /// If `values.len() != rows * width` (a caller's bug, never input).
    pub fn uniform(width: usize, rows: usize, values: Vec<f64>) -> Self {
        assert_eq!(values.len(), rows * width, "rows × width values");
        Multipliers {
            values,
            starts: None,
            width,
            rows,
        }
    }

    /// The number of rows (data points).
    pub fn len(&self) -> usize {
        self.rows
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.rows == 0
    }

    /// The common width of the rows, or `None` when they differ.
    pub fn width(&self) -> Option<usize> {
        self.starts.is_none().then_some(self.width)
    }

    /// Row `i`.
    ///
    /// # Panics
    /// If `i >= len()`.
    pub fn row(&self, i: usize) -> &[f64] {
        assert!(i < self.rows, "row {i} of {}", self.rows);
        match &self.starts {
            None => &self.values[i * self.width..(i + 1) * self.width],
            Some(s) => &self.values[s[i]..s[i + 1]],
        }
    }

    /// The rows in order.
    pub fn iter(&self) -> Iter<'_> {
        Iter {
            rows: self,
            next: 0,
        }
    }

    /// Every value, row after row.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Every value, row after row, to change in place.
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Every value, row after row, without a copy.
    pub fn into_values(self) -> Vec<f64> {
        self.values
    }

    /// The rows as vectors.
    pub fn to_vecs(&self) -> Vec<Vec<f64>> {
        self.iter().map(<[f64]>::to_vec).collect()
    }
}

impl From<Vec<Vec<f64>>> for Multipliers {
    fn from(rows: Vec<Vec<f64>>) -> Self {
        let width = rows.first().map_or(0, Vec::len);
        let values: Vec<f64> = rows.iter().flatten().copied().collect();
        if rows.iter().all(|r| r.len() == width) {
            return Multipliers::uniform(width, rows.len(), values);
        }
        let mut starts = Vec::with_capacity(rows.len() + 1);
        let mut at = 0;
        starts.push(0);
        for r in &rows {
            at += r.len();
            starts.push(at);
        }
        Multipliers {
            values,
            starts: Some(starts),
            width: 0,
            rows: rows.len(),
        }
    }
}

/// The rows of [`Multipliers`] in order.
#[derive(Clone, Debug)]
pub struct Iter<'a> {
    rows: &'a Multipliers,
    next: usize,
}

impl<'a> Iterator for Iter<'a> {
    type Item = &'a [f64];

    fn next(&mut self) -> Option<&'a [f64]> {
        (self.next < self.rows.len()).then(|| {
            self.next += 1;
            self.rows.row(self.next - 1)
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.rows.len() - self.next;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Iter<'_> {}

impl<'a> IntoIterator for &'a Multipliers {
    type Item = &'a [f64];
    type IntoIter = Iter<'a>;

    fn into_iter(self) -> Iter<'a> {
        self.iter()
    }
}

impl Index<usize> for Multipliers {
    type Output = [f64];

    fn index(&self, i: usize) -> &[f64] {
        self.row(i)
    }
}

#[cfg(test)]
mod tests {
    use super::Multipliers;

    #[test]
    fn rows_of_different_widths_keep_their_starts() {
        let rows = vec![vec![1.0], vec![], vec![2.0, 3.0, 4.0]];
        let m = Multipliers::from(rows.clone());
        assert_eq!((m.len(), m.width()), (3, None));
        assert_eq!(m.to_vecs(), rows);
        assert_eq!(m.values(), &[1.0, 2.0, 3.0, 4.0]);
        assert!(m[1].is_empty());
        let empty = Multipliers::from(Vec::new());
        assert!(empty.is_empty() && empty.width() == Some(0));
    }
}
