use crate::Error;

/// A sequence of points in R^d, stored vertex-major: coordinate `c` of point `i` is
/// `coords[i * dim + c]`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Points {
    dim: usize,
    coords: Vec<f64>,
}

impl Points {
    /// Points of dimension `dim` from a flat vertex-major coordinate vector.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] if `dim == 0`, [`Error::LengthMismatch`] if `coords.len()` is not a
    /// multiple of `dim`, [`Error::NonFinite`] (naming the point) for NaN or infinite coordinates.
    pub fn new(dim: usize, coords: Vec<f64>) -> Result<Self, Error> {
        if dim == 0 {
            return Err(Error::OutOfRange {
                field: "dim",
                value: 0.0,
                reason: "dimension must be at least 1",
            });
        }
        if !coords.len().is_multiple_of(dim) {
            return Err(Error::LengthMismatch {
                field: "coords",
                expected: coords.len().div_ceil(dim) * dim,
                got: coords.len(),
            });
        }
        // A branch-free scan first (it vectorizes); the index is searched only on failure.
        if !all_finite(&coords) {
            let k = coords
                .iter()
                .position(|x| !x.is_finite())
                .expect("a non-finite coordinate");
            return Err(Error::NonFinite {
                field: "points",
                index: k / dim,
            });
        }
        Ok(Points { dim, coords })
    }

    /// Points from rows `[[x, y, …], …]`, all of the same dimension d ≥ 1.
    ///
    /// # Errors
    /// [`Error::TooFew`] for no rows, [`Error::DimensionMismatch`] naming the first row whose
    /// length differs from the first row's, [`Error::NonFinite`] naming the point.
    pub fn from_rows<R: AsRef<[f64]>>(rows: &[R]) -> Result<Self, Error> {
        let first = rows.first().ok_or(Error::TooFew {
            field: "points",
            needed: 1,
            got: 0,
        })?;
        let dim = first.as_ref().len();
        if dim == 0 {
            return Err(Error::DimensionMismatch {
                index: 0,
                expected: 1,
                got: 0,
            });
        }
        let mut coords = Vec::with_capacity(rows.len() * dim);
        for (i, r) in rows.iter().enumerate() {
            let r = r.as_ref();
            if r.len() != dim {
                return Err(Error::DimensionMismatch {
                    index: i,
                    expected: dim,
                    got: r.len(),
                });
            }
            coords.extend_from_slice(r);
        }
        Points::new(dim, coords)
    }

    /// Points of `D` coordinates from their rows, moved without a copy. Unlike [`Points::new`]
    /// the coordinates are not scanned for NaN or infinities: this is for computed points whose
    /// finiteness their producer checked while writing them (as with [`Points::zeros`] and
    /// [`Points::coords_mut`]); input goes through [`Points::new`].
    ///
    /// # Panics
    /// If `D == 0`.
    pub fn from_array_rows<const D: usize>(rows: Vec<[f64; D]>) -> Self {
        assert!(D > 0, "points need at least one coordinate");
        Points {
            dim: D,
            coords: rows.into_flattened(),
        }
    }

    /// `n` points at the origin of R^dim.
    pub fn zeros(n: usize, dim: usize) -> Self {
        Points {
            dim: dim.max(1),
            coords: vec![0.0; n * dim.max(1)],
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.coords.len() / self.dim.max(1)
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// The dimension d.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Point `i` as a slice of length d.
    ///
    /// # Panics
    /// If `i >= self.len()`.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.coords[i * self.dim..(i + 1) * self.dim]
    }

    /// Point `i`, mutably.
    ///
    /// # Panics
    /// If `i >= self.len()`.
    pub fn point_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.coords[i * self.dim..(i + 1) * self.dim]
    }

    /// All coordinates, vertex-major.
    pub fn coords(&self) -> &[f64] {
        &self.coords
    }

    /// All coordinates, vertex-major, mutably.
    pub fn coords_mut(&mut self) -> &mut [f64] {
        &mut self.coords
    }

    /// Consumes the points, returning the flat coordinate vector.
    pub fn into_coords(self) -> Vec<f64> {
        self.coords
    }

    /// Iterator over the points as slices.
    pub fn iter(&self) -> std::slice::ChunksExact<'_, f64> {
        self.coords.chunks_exact(self.dim)
    }

    /// The points as rows (for serialization and tests).
    pub fn to_rows(&self) -> Vec<Vec<f64>> {
        self.iter().map(<[f64]>::to_vec).collect()
    }

    /// The first span whose two ends coincide, as the pair of indices `(i, j)` with
    /// point i == point j: j = i + 1, and with `wrap` also the closing span (n − 1, 0). `None`
    /// when every span has length (the condition the spans' parametrization needs). One
    /// branch-free scan first; the index is searched for only when it finds a repeat.
    ///
    /// ```
    /// use divdiff::Points;
    /// let p = Points::from_rows(&[[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]]).unwrap();
    /// assert_eq!(p.coincident_span(false), None);
    /// assert_eq!(p.coincident_span(true), Some((2, 0)));
    /// ```
    pub fn coincident_span(&self, wrap: bool) -> Option<(usize, usize)> {
        let (n, d, x) = (self.len(), self.dim, &self.coords[..]);
        if n < 2 {
            return None;
        }
        let consecutive = x.chunks_exact(d).zip(x[d..].chunks_exact(d));
        let closing = wrap.then(|| (&x[(n - 1) * d..], &x[..d]));
        let any = consecutive
            .chain(closing)
            .fold(false, |any, (a, b)| any | (a == b));
        if !any {
            return None;
        }
        let spans = if wrap { n } else { n - 1 };
        (0..spans)
            .map(|i| (i, if i + 1 == n { 0 } else { i + 1 }))
            .find(|&(i, j)| self.point(i) == self.point(j))
    }
}

/// Whether every value is finite, by a branch-free scan that vectorizes (a short-circuiting
/// search does not): a value is ±∞ or NaN exactly when its exponent bits are all set, and the
/// flags are OR-ed (no floating-point dependency chain).
#[inline]
pub fn all_finite(x: &[f64]) -> bool {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    x.iter().fold(0u64, |bad, v| {
        bad | u64::from(v.to_bits() & EXPONENT == EXPONENT)
    }) == 0
}

#[cfg(test)]
mod scan_tests {
    use super::all_finite;

    /// Every position of every length up to 13 (the four lanes and the tail), each
    /// non-finite kind; signed zeros and huge values are finite.
    #[test]
    fn all_finite_finds_every_non_finite_value() {
        for len in 0..13 {
            let base: Vec<f64> = (0..len)
                .map(|i| [1e308, -0.0, 3.5, -1e-300][i % 4])
                .collect();
            assert!(all_finite(&base), "len {len}");
            for pos in 0..len {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let mut x = base.clone();
                    x[pos] = bad;
                    assert!(!all_finite(&x), "len {len} pos {pos} {bad}");
                }
            }
        }
    }
}
