//! A problem's large arrays ([`curvefit::spec::arrays`]) taken in bulk: a `points`, `radii`,
//! `weights`, `knots`, `t` or `y` given as a C-contiguous float64 numpy array is copied as one
//! slice instead of being walked element by element through serde (a (10⁵, 2) array took
//! ~1.3 ms that way, an eighth of a large interpolation's call).
//!
//! An array is taken only when serde would read it to the same values: float64, C-contiguous,
//! the field's shape (rows of one length d ≥ 1, or numbers), not empty, within the field's
//! limit, every entry finite. The rest of the problem is read from a copy of its dicts with the
//! taken arrays replaced by `[]` (the caller's dicts are not changed), and the arrays are put in
//! after; when anything does not fit, the caller reads the problem as given, so every error is
//! the serde reader's.

use curvefit::divdiff;
use curvefit::spec::arrays::{Kind, LargeArrays, Parsed};
use numpy::{PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// A problem whose large arrays were taken: the rest of it (each taken array replaced by `[]`)
/// and the arrays, each with its index in `LargeArrays::ARRAYS`.
pub struct Taken<'py> {
    pub rest: Bound<'py, PyDict>,
    pub arrays: Vec<(usize, Parsed)>,
}

/// The problem `obj` with its bulk-readable large arrays taken out; `None` when it has none.
pub fn take<'py, P: LargeArrays>(obj: &Bound<'py, PyAny>) -> Option<Taken<'py>> {
    let top = obj.cast::<PyDict>().ok()?;
    let mut arrays = Vec::new();
    for (i, array) in P::ARRAYS.iter().enumerate() {
        if let Some(parsed) = lookup(top, array.path).and_then(|v| read(&v, array.kind)) {
            arrays.push((i, parsed));
        }
    }
    if arrays.is_empty() {
        return None;
    }
    let rest = top.copy().ok()?;
    for &(i, _) in &arrays {
        emptied(&rest, P::ARRAYS[i].path).ok()?;
    }
    Some(Taken { rest, arrays })
}

/// The value at `path` (keys of nested dicts).
fn lookup<'py>(top: &Bound<'py, PyDict>, path: &[&str]) -> Option<Bound<'py, PyAny>> {
    let (last, dicts) = path.split_last()?;
    let mut d = top.clone();
    for key in dicts {
        d = d.get_item(key).ok()??.cast_into::<PyDict>().ok()?;
    }
    d.get_item(last).ok()?
}

/// `d` with the value at `path` replaced by `[]`, each nested dict on the way replaced by a copy.
fn emptied(d: &Bound<'_, PyDict>, path: &[&str]) -> PyResult<()> {
    let py = d.py();
    match path {
        [key] => d.set_item(key, PyList::empty(py)),
        [key, tail @ ..] => {
            let inner = d
                .get_item(key)?
                .ok_or_else(|| pyo3::exceptions::PyKeyError::new_err(key.to_string()))?
                .cast_into::<PyDict>()?
                .copy()?;
            emptied(&inner, tail)?;
            d.set_item(key, inner)
        }
        [] => Ok(()),
    }
}

/// The array `value` as `kind`, when serde would read it to the same values.
fn read(value: &Bound<'_, PyAny>, kind: Kind) -> Option<Parsed> {
    let array = value.cast::<PyArrayDyn<f64>>().ok()?;
    let readonly = array.try_readonly().ok()?;
    let view = readonly.as_array();
    let flat = view.as_slice()?;
    match (kind, view.shape()) {
        // `Points::new` refuses a non-finite coordinate.
        (Kind::Rows { max }, &[n, d]) if n > 0 && d > 0 && n * d <= max => {
            divdiff::Points::new(d, flat.to_vec())
                .ok()
                .map(Parsed::Rows)
        }
        (Kind::Numbers { max }, &[n]) if n > 0 && n <= max => {
            divdiff::all_finite(flat).then(|| Parsed::Numbers(flat.to_vec()))
        }
        _ => None,
    }
}
