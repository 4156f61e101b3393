//! The JSON results of `curvefit::spec` as Python values: one `dict` per JSON object with the
//! JSON's field names, numpy arrays for its arrays of numbers (points `(N, d)` float64, index
//! arrays int64, flags bool), Python scalars, lists and `str` for the rest. The Python layer
//! (`curvefit/_results.py`) wraps each dict in its result class.
//!
//! The large arrays (points, knots, breaks, coefficients) move into numpy without a copy: the
//! result's `Vec<f64>` becomes the array's buffer (`IntoPyArray`).

use curvefit::spec;
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

/// A flat row-major buffer as an `(rows, cols)` array, without a copy.
fn matrix<'py, T: numpy::Element>(
    py: Python<'py>,
    data: Vec<T>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let a = Array2::from_shape_vec((rows, cols), data)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}

/// Points as an `(N, d)` float64 array (an empty result is `(0, 0)`).
fn points<'py>(py: Python<'py>, rows: spec::Rows) -> PyResult<Bound<'py, PyAny>> {
    let (n, d) = (rows.len(), rows.dim());
    matrix(py, rows.0.into_coords(), n, d)
}

fn vector<'py, T: numpy::Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyAny> {
    v.into_pyarray(py).into_any()
}

fn indices<'py>(py: Python<'py>, v: &[usize]) -> PyResult<Bound<'py, PyAny>> {
    let v: Vec<i64> = v
        .iter()
        .map(|&i| i64::try_from(i))
        .collect::<Result<_, _>>()
        .map_err(|e| pyo3::exceptions::PyOverflowError::new_err(e.to_string()))?;
    Ok(vector(py, v))
}

/// Rows of equal length as a 2-D array (their buffer, without a copy), ragged rows as a list
/// of 1-D arrays.
fn table<'py>(py: Python<'py>, rows: curvefit::refine::Multipliers) -> PyResult<Bound<'py, PyAny>> {
    if let Some(width) = rows.width() {
        let n = rows.len();
        return matrix(py, rows.into_values(), n, width);
    }
    let list = PyList::empty(py);
    for r in rows.to_vecs() {
        list.append(vector(py, r))?;
    }
    Ok(list.into_any())
}

/// `refine`'s result.
pub fn refine<'py>(py: Python<'py>, r: spec::RefineResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let spec::RefineResult {
        points: pts,
        knots,
        data_vertex,
        energy,
        multipliers,
        active,
        kkt_residual,
        iterations,
    } = r;
    d.set_item("points", points(py, pts)?)?;
    d.set_item("knots", vector(py, knots))?;
    d.set_item("data_vertex", indices(py, &data_vertex)?)?;
    d.set_item("energy", energy)?;
    d.set_item("multipliers", table(py, multipliers)?)?;
    d.set_item("active", vector(py, active))?;
    d.set_item("kkt_residual", kkt_residual)?;
    let it = PyDict::new(py);
    it.set_item("knot_updates", iterations.knot_updates)?;
    it.set_item("solver", iterations.solver)?;
    it.set_item("solves", iterations.solves)?;
    d.set_item("iterations", it)?;
    Ok(d)
}

/// `strip`'s result.
pub fn strip<'py>(py: Python<'py>, s: spec::StripResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let spec::StripResult {
        breaks,
        coefficients,
        slopes,
        extra_knots,
        energy,
        norm,
        iterations,
        gradient_norm,
        shifted_data,
    } = s;
    let m = coefficients.len();
    d.set_item("breaks", vector(py, breaks))?;
    d.set_item(
        "coefficients",
        matrix(py, coefficients.into_iter().flatten().collect(), m, 4)?,
    )?;
    d.set_item("slopes", vector(py, slopes))?;
    let knots = PyList::empty(py);
    for k in extra_knots {
        knots.append(PyTuple::new(
            py,
            [
                k.t.into_pyobject(py)?.into_any(),
                k.kind.into_pyobject(py)?.into_any(),
            ],
        )?)?;
    }
    d.set_item("extra_knots", knots)?;
    d.set_item("energy", energy)?;
    d.set_item("norm", norm)?;
    d.set_item("iterations", iterations)?;
    d.set_item("gradient_norm", gradient_norm)?;
    let shifted: Vec<i64> = shifted_data.into_iter().map(|i| i as i64).collect();
    d.set_item("shifted_data", vector(py, shifted))?;
    Ok(d)
}

fn offsets<'py>(py: Python<'py>, v: &[isize]) -> PyResult<Bound<'py, PyAny>> {
    let v: Vec<i64> = v.iter().map(|&i| i as i64).collect();
    Ok(vector(py, v))
}

/// `scheme`'s result.
pub fn scheme<'py>(py: Python<'py>, s: spec::SchemeResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("arity", s.arity)?;
    d.set_item("points", s.points)?;
    match s.polygon {
        None => d.set_item("polygon", py.None())?,
        Some(p) => {
            let pd = PyDict::new(py);
            pd.set_item("closed", p.closed)?;
            pd.set_item("input", points(py, p.input)?)?;
            pd.set_item("levels", p.levels)?;
            pd.set_item("output", points(py, p.output)?)?;
            d.set_item("polygon", pd)?;
        }
    }
    let rules = PyList::empty(py);
    for r in s.rules {
        let rd = PyDict::new(py);
        rd.set_item("floats", vector(py, r.floats))?;
        rd.set_item("offsets", offsets(py, &r.offsets)?)?;
        rd.set_item("residue", r.residue)?;
        rd.set_item("weights", r.weights)?;
        rules.append(rd)?;
    }
    d.set_item("rules", rules)?;
    match s.surface_rules {
        None => d.set_item("surface_rules", py.None())?,
        Some(list) => {
            let out = PyList::empty(py);
            for r in list {
                let rd = PyDict::new(py);
                rd.set_item("floats", vector(py, r.floats))?;
                let n = r.offsets.len();
                let flat: Vec<i64> = r.offsets.iter().flatten().map(|&i| i as i64).collect();
                rd.set_item("offsets", matrix(py, flat, n, 2)?)?;
                rd.set_item("residue", PyTuple::new(py, r.residue)?)?;
                rd.set_item("weights", r.weights)?;
                out.append(rd)?;
            }
            d.set_item("surface_rules", out)?;
        }
    }
    Ok(d)
}

/// `surface`'s result.
pub fn surface<'py>(py: Python<'py>, s: spec::SurfaceResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("rows", s.rows)?;
    d.set_item("cols", s.cols)?;
    d.set_item("closed", PyTuple::new(py, s.closed)?)?;
    d.set_item("levels", s.levels)?;
    d.set_item("points", points(py, s.points)?)?;
    let m = s.quads.len();
    let flat: Vec<i64> = s
        .quads
        .iter()
        .flatten()
        .map(|&i| i64::try_from(i))
        .collect::<Result<_, _>>()
        .map_err(|e| pyo3::exceptions::PyOverflowError::new_err(e.to_string()))?;
    d.set_item("quads", matrix(py, flat, m, 4)?)?;
    Ok(d)
}

/// `natural`'s result.
pub fn natural<'py>(py: Python<'py>, s: spec::NaturalResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let levels = PyList::empty(py);
    for l in s.levels {
        let ld = PyDict::new(py);
        ld.set_item("level", l.level)?;
        ld.set_item("points", points(py, l.points)?)?;
        ld.set_item("energy", l.energy)?;
        levels.append(ld)?;
    }
    d.set_item("levels", levels)?;
    d.set_item("limit_energy", s.limit_energy)?;
    Ok(d)
}
