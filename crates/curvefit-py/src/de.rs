//! A serde [`Deserializer`](serde::Deserializer) over Python objects, so that a problem given as
//! keyword arguments is read by the very types, defaults and validation of `curvefit::spec`
//! that read the command line's JSON — and fails with the same field paths and messages.
//!
//! Each Python value is presented to serde as the JSON value it stands for, calling the visitor
//! method `serde_json` would call for that JSON:
//!
//! | Python | JSON | visitor |
//! |---|---|---|
//! | `None` | `null` | `visit_unit` / `visit_none` |
//! | `bool`, `numpy.bool_` | `true`, `false` | `visit_bool` |
//! | `int`, numpy integers | an integer | `visit_u64` (≥ 0) or `visit_i64`; beyond 64 bits `visit_f64`, as serde_json parses it |
//! | `float`, numpy floats | a number | `visit_f64`; NaN and ±∞ (no JSON for them) are refused |
//! | `str` | a string | `visit_str` |
//! | `list`, `tuple`, other sequences, `numpy.ndarray`, objects with `__array__` | an array | `visit_seq` (an n-D array is an array of (n−1)-D arrays) |
//! | `dict`, other mappings | an object | `visit_map` |
//!
//! Arrays of float64, float32 and the integer and bool dtypes are read in place through their
//! strides (any layout, any order, no temporary copy): each element is converted once, straight
//! into the `Vec` the problem type builds (`spec::Rows` reads points flat). Other dtypes go
//! through `ndarray.tolist()`.
//!
//! The error type is `serde_json::Error`, so serde's own messages ("invalid type: string
//! \"x\", expected f64") are worded exactly as for JSON text, and `spec`'s rewriting of them into
//! the user's words applies unchanged. Where serde_json reports a wrong kind of value as a
//! *syntax* error (a number where an enum's string or object is expected; an array with more
//! entries than a fixed-size field takes), this deserializer raises the same syntax error
//! ([`syntax`]), which `spec` words by the field.

use std::cell::Cell;

use numpy::ndarray::{ArrayView1, ArrayViewD, Ix0, Ix1, Ix2};
use numpy::{Element, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{
    PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyInt, PyList, PyMapping, PySequence, PyString,
    PyTuple,
};
use serde::de::{self, DeserializeSeed, IntoDeserializer, Unexpected, Visitor};
use serde_json::Error;

/// State shared by one deserialization.
pub struct Ctx<'py> {
    /// `numpy.generic`, the base class of numpy's scalars.
    generic: Bound<'py, PyAny>,
    /// `numpy.asarray`.
    asarray: Bound<'py, PyAny>,
    /// The lengths (taken, given) of the last array that had entries left over (see
    /// [`Ctx::trailing`]).
    pub trailing: Cell<Option<(usize, usize)>>,
}

impl<'py> Ctx<'py> {
    /// A context for one problem.
    pub fn new(py: Python<'py>) -> PyResult<Self> {
        let numpy = py.import("numpy")?;
        Ok(Ctx {
            generic: numpy.getattr("generic")?,
            asarray: numpy.getattr("asarray")?,
            trailing: Cell::new(None),
        })
    }
}

/// A serde_json syntax error with the message `text` produces (serde_json's wording of the
/// error, for `spec`'s rewriting; its position in `text` is dropped by `spec`).
fn syntax(text: &str) -> Error {
    match serde_json::from_str::<de::IgnoredAny>(text) {
        Err(e) => e,
        Ok(_) => de::Error::custom("malformed value"),
    }
}

/// serde_json's error for a value of the wrong kind where an enum is expected.
fn expected_value() -> Error {
    syntax("x")
}

fn py_err(e: PyErr) -> Error {
    de::Error::custom(format!("cannot be read: {e}"))
}

fn finite(x: f64) -> Result<f64, Error> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(de::Error::custom(format!(
            "must be a finite number, not {x}"
        )))
    }
}

fn visit_int<'de, V: Visitor<'de>>(i: &Bound<'_, PyInt>, v: V) -> Result<V::Value, Error> {
    if let Ok(x) = i.extract::<u64>() {
        v.visit_u64(x)
    } else if let Ok(x) = i.extract::<i64>() {
        v.visit_i64(x)
    } else {
        // serde_json reads an integer beyond 64 bits as a float.
        let x = i.extract::<f64>().map_err(|_| {
            de::Error::custom("must be a finite number, not an integer beyond the float range")
        })?;
        v.visit_f64(x)
    }
}

/// One Python value.
pub struct PyDe<'a, 'py> {
    obj: &'a Bound<'py, PyAny>,
    ctx: &'a Ctx<'py>,
}

impl<'a, 'py> PyDe<'a, 'py> {
    /// The deserializer of `obj`.
    pub fn new(obj: &'a Bound<'py, PyAny>, ctx: &'a Ctx<'py>) -> Self {
        PyDe { obj, ctx }
    }
}

/// What a Python value is, in JSON's terms.
enum Kind<'py> {
    Null,
    Bool(bool),
    Int(Bound<'py, PyInt>),
    Float(f64),
    Str(Bound<'py, PyString>),
    List(Bound<'py, PyList>),
    Tuple(Bound<'py, PyTuple>),
    Dict(Bound<'py, PyDict>),
    Array(Bound<'py, PyUntypedArray>),
    Other(String),
}

fn kind<'py>(obj: &Bound<'py, PyAny>, ctx: &Ctx<'py>) -> Result<Kind<'py>, Error> {
    // Floats first: the coordinates of points given as lists are most of the values read.
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(Kind::Float(f.value()));
    }
    if obj.is_none() {
        return Ok(Kind::Null);
    }
    // bool before int: Python's bool is an int.
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Kind::Bool(b.is_true()));
    }
    if let Ok(i) = obj.cast::<PyInt>() {
        return Ok(Kind::Int(i.clone()));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Kind::Str(s.clone()));
    }
    if let Ok(l) = obj.cast::<PyList>() {
        return Ok(Kind::List(l.clone()));
    }
    if let Ok(t) = obj.cast::<PyTuple>() {
        return Ok(Kind::Tuple(t.clone()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return Ok(Kind::Dict(d.clone()));
    }
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        if a.ndim() == 0 {
            // A 0-d array is its one value.
            return kind(&a.call_method0("item").map_err(py_err)?, ctx);
        }
        return Ok(Kind::Array(a.clone()));
    }
    if obj.is_instance(&ctx.generic).unwrap_or(false) {
        // numpy's scalars (np.float32(1), np.int64(3), np.bool_(True)) as Python's.
        let item = obj.call_method0("item").map_err(py_err)?;
        if !item.is(obj) {
            return kind(&item, ctx);
        }
    }
    // Bytes are a sequence of small integers to Python, but no JSON value.
    if obj.cast::<PyBytes>().is_ok() || obj.cast::<PyByteArray>().is_ok() {
        return Ok(Kind::Other(type_name(obj)));
    }
    // Array-likes (pandas, xarray, array-API tensors on the CPU) as numpy sees them.
    if obj.hasattr("__array__").unwrap_or(false) {
        if let Ok(a) = ctx.asarray.call1((obj,)) {
            if a.cast::<PyUntypedArray>().is_ok() {
                return kind(&a, ctx);
            }
        }
    }
    if obj.cast::<PyMapping>().is_ok() {
        let d = PyDict::new(obj.py());
        d.update(obj.cast::<PyMapping>().map_err(|e| py_err(e.into()))?)
            .map_err(py_err)?;
        return Ok(Kind::Dict(d));
    }
    if let Ok(s) = obj.cast::<PySequence>() {
        if let Ok(l) = s.to_list() {
            return Ok(Kind::List(l));
        }
    }
    Ok(Kind::Other(type_name(obj)))
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "object".into())
}

/// The entries of a list or tuple, one at a time.
struct Items<'a, 'py> {
    seq: Seq<'py>,
    next: usize,
    len: usize,
    ctx: &'a Ctx<'py>,
}

enum Seq<'py> {
    List(Bound<'py, PyList>),
    Tuple(Bound<'py, PyTuple>),
}

impl<'de> de::SeqAccess<'de> for Items<'_, '_> {
    type Error = Error;
    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Error> {
        if self.next >= self.len {
            return Ok(None);
        }
        let item = match &self.seq {
            Seq::List(l) => l.get_item(self.next),
            Seq::Tuple(t) => t.get_item(self.next),
        }
        .map_err(py_err)?;
        self.next += 1;
        seed.deserialize(PyDe::new(&item, self.ctx)).map(Some)
    }
    fn size_hint(&self) -> Option<usize> {
        Some(self.len - self.next)
    }
}

/// An array whose visitor stopped before its end is an error, as serde_json's "trailing
/// characters" (a fixed-size field such as a cubic's four coefficients given five).
fn no_trailing(ctx: &Ctx<'_>, taken: usize, len: usize) -> Result<(), Error> {
    if taken < len {
        ctx.trailing.set(Some((taken, len)));
        return Err(syntax("0 0"));
    }
    Ok(())
}

fn visit_items<'de, V: Visitor<'de>>(seq: Seq<'_>, ctx: &Ctx<'_>, v: V) -> Result<V::Value, Error> {
    let len = match &seq {
        Seq::List(l) => l.len(),
        Seq::Tuple(t) => t.len(),
    };
    let mut items = Items {
        seq,
        next: 0,
        len,
        ctx,
    };
    let value = v.visit_seq(&mut items)?;
    no_trailing(ctx, items.next, len)?;
    Ok(value)
}

/// The entries of a dict, one at a time.
struct Entries<'a, 'py> {
    items: std::vec::IntoIter<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    value: Option<Bound<'py, PyAny>>,
    ctx: &'a Ctx<'py>,
}

fn key_string(key: &Bound<'_, PyAny>) -> Result<String, Error> {
    match key.cast::<PyString>() {
        Ok(s) => Ok(s.to_string()),
        Err(_) => Err(de::Error::custom(format!(
            "keys must be strings, not {}",
            key.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))),
    }
}

impl<'de> de::MapAccess<'de> for Entries<'_, '_> {
    type Error = Error;
    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Error> {
        match self.items.next() {
            None => Ok(None),
            Some((k, v)) => {
                self.value = Some(v);
                let key: de::value::StringDeserializer<Error> = key_string(&k)?.into_deserializer();
                seed.deserialize(key).map(Some)
            }
        }
    }
    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, Error> {
        match self.value.take() {
            Some(v) => seed.deserialize(PyDe::new(&v, self.ctx)),
            None => Err(de::Error::custom("a value without its key")),
        }
    }
    fn size_hint(&self) -> Option<usize> {
        Some(self.items.len())
    }
}

fn entries<'a, 'py>(d: &Bound<'py, PyDict>, ctx: &'a Ctx<'py>) -> Entries<'a, 'py> {
    let items: Vec<_> = d.iter().collect();
    Entries {
        items: items.into_iter(),
        value: None,
        ctx,
    }
}

/// An externally tagged enum given as `{"variant": value}`.
struct VariantEntry<'a, 'py> {
    name: String,
    value: Bound<'py, PyAny>,
    ctx: &'a Ctx<'py>,
}

impl<'de, 'a, 'py> de::EnumAccess<'de> for VariantEntry<'a, 'py> {
    type Error = Error;
    type Variant = VariantValue<'a, 'py>;
    fn variant_seed<V: DeserializeSeed<'de>>(
        self,
        seed: V,
    ) -> Result<(V::Value, Self::Variant), Error> {
        let key: de::value::StringDeserializer<Error> = self.name.into_deserializer();
        let variant = seed.deserialize(key)?;
        Ok((
            variant,
            VariantValue {
                value: self.value,
                ctx: self.ctx,
            },
        ))
    }
}

struct VariantValue<'a, 'py> {
    value: Bound<'py, PyAny>,
    ctx: &'a Ctx<'py>,
}

impl<'de> de::VariantAccess<'de> for VariantValue<'_, '_> {
    type Error = Error;
    fn unit_variant(self) -> Result<(), Error> {
        de::Deserialize::deserialize(PyDe::new(&self.value, self.ctx))
    }
    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value, Error> {
        seed.deserialize(PyDe::new(&self.value, self.ctx))
    }
    fn tuple_variant<V: Visitor<'de>>(self, _len: usize, v: V) -> Result<V::Value, Error> {
        de::Deserializer::deserialize_seq(PyDe::new(&self.value, self.ctx), v)
    }
    fn struct_variant<V: Visitor<'de>>(
        self,
        _fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, Error> {
        de::Deserializer::deserialize_map(PyDe::new(&self.value, self.ctx), v)
    }
}

impl<'de> de::Deserializer<'de> for PyDe<'_, '_> {
    type Error = Error;

    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        match kind(self.obj, self.ctx)? {
            Kind::Null => v.visit_unit(),
            Kind::Bool(b) => v.visit_bool(b),
            Kind::Int(i) => visit_int(&i, v),
            Kind::Float(x) => v.visit_f64(finite(x)?),
            Kind::Str(s) => v.visit_str(&s.to_cow().map_err(py_err)?),
            Kind::List(l) => visit_items(Seq::List(l), self.ctx, v),
            Kind::Tuple(t) => visit_items(Seq::Tuple(t), self.ctx, v),
            Kind::Dict(d) => v.visit_map(entries(&d, self.ctx)),
            Kind::Array(a) => visit_array(&a, self.ctx, v),
            Kind::Other(name) => Err(de::Error::invalid_type(
                Unexpected::Other(&format!("a Python {name}")),
                &v,
            )),
        }
    }

    fn deserialize_option<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        if self.obj.is_none() {
            v.visit_none()
        } else {
            v.visit_some(self)
        }
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, Error> {
        match kind(self.obj, self.ctx)? {
            Kind::Str(s) => {
                let name: de::value::StringDeserializer<Error> = s.to_string().into_deserializer();
                v.visit_enum(name)
            }
            Kind::Dict(d) if d.len() == 1 => {
                let (k, value) = d.iter().next().ok_or_else(expected_value)?;
                v.visit_enum(VariantEntry {
                    name: key_string(&k)?,
                    value,
                    ctx: self.ctx,
                })
            }
            // serde_json: "expected value" for anything but a string or a one-entry object.
            _ => Err(expected_value()),
        }
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        v: V,
    ) -> Result<V::Value, Error> {
        v.visit_newtype_struct(self)
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        v.visit_unit()
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf unit unit_struct seq tuple tuple_struct map struct identifier
    }
}

/// An element type read in place from a numpy array.
trait Elem: Element + Copy {
    fn visit<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error>;
}

impl Elem for f64 {
    fn visit<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        v.visit_f64(finite(self)?)
    }
}
impl Elem for f32 {
    fn visit<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        v.visit_f64(finite(f64::from(self))?)
    }
}
impl Elem for bool {
    fn visit<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        v.visit_bool(self)
    }
}
macro_rules! signed {
    ($($t:ty)*) => {$(
        impl Elem for $t {
            fn visit<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
                let x = i64::from(self);
                match u64::try_from(x) {
                    Ok(u) => v.visit_u64(u),
                    Err(_) => v.visit_i64(x),
                }
            }
        }
    )*};
}
signed!(i8 i16 i32 i64);
macro_rules! unsigned {
    ($($t:ty)*) => {$(
        impl Elem for $t {
            fn visit<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
                v.visit_u64(u64::from(self))
            }
        }
    )*};
}
unsigned!(u8 u16 u32 u64);

/// Dispatches on the array's dtype; dtypes without an in-place reader go through `tolist()`.
fn visit_array<'de, V: Visitor<'de>>(
    a: &Bound<'_, PyUntypedArray>,
    ctx: &Ctx<'_>,
    v: V,
) -> Result<V::Value, Error> {
    macro_rules! try_dtype {
        ($($t:ty)*) => {$(
            if let Ok(typed) = a.cast::<PyArrayDyn<$t>>() {
                let ro = typed.try_readonly().map_err(|e| de::Error::custom(format!("cannot be read: {e}")))?;
                return visit_view(ro.as_array(), ctx, v);
            }
        )*};
    }
    try_dtype!(f64 f32 i64 i32 i16 i8 u64 u32 u16 u8 bool);
    let list = a.call_method0("tolist").map_err(py_err)?;
    PyDe::new(&list, ctx).deserialize_any_owned(v)
}

impl PyDe<'_, '_> {
    fn deserialize_any_owned<'de, V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        de::Deserializer::deserialize_any(self, v)
    }
}

/// An n-D array view (n ≥ 1) as an array of (n−1)-D arrays. One- and two-dimensional views
/// (points, radii, cubics) are walked with static dimensions, contiguous rows as slices.
fn visit_view<'de, T: Elem, V: Visitor<'de>>(
    view: ArrayViewD<'_, T>,
    ctx: &Ctx<'_>,
    v: V,
) -> Result<V::Value, Error> {
    let shape_error = |e: numpy::ndarray::ShapeError| -> Error { de::Error::custom(e.to_string()) };
    match view.ndim() {
        1 => visit_1d(
            view.into_dimensionality::<Ix1>().map_err(shape_error)?,
            ctx,
            v,
        ),
        2 => {
            let view = view.into_dimensionality::<Ix2>().map_err(shape_error)?;
            let len = view.nrows();
            // A C-contiguous matrix (numpy's default layout): its rows are slices of one
            // buffer, read without a strided view per row (a (10⁵, 2) array's rows that way
            // were 27 ns each, a tenth of a large interpolation's call).
            match (view.to_slice(), view.ncols()) {
                (Some(flat), cols @ 1..) => {
                    visit_rows(flat.chunks_exact(cols).map(View::Slice), len, ctx, v)
                }
                _ => visit_rows(view.outer_iter().map(View::One), len, ctx, v),
            }
        }
        _ => {
            let len = view.shape()[0];
            visit_rows(view.outer_iter().map(View::Dyn), len, ctx, v)
        }
    }
}

/// The `len` sub-arrays of an array, each read by [`ViewDe`]; an array with elements left over
/// after the visitor stops is refused ([`no_trailing`]).
fn visit_rows<'de, 'v, T: Elem + 'v, V: Visitor<'de>>(
    iter: impl Iterator<Item = View<'v, T>>,
    len: usize,
    ctx: &Ctx<'_>,
    v: V,
) -> Result<V::Value, Error> {
    let mut rows = Rows {
        iter,
        taken: 0,
        ctx,
    };
    let value = v.visit_seq(&mut rows)?;
    no_trailing(ctx, rows.taken, len)?;
    Ok(value)
}

fn visit_1d<'de, T: Elem, V: Visitor<'de>>(
    view: ArrayView1<'_, T>,
    ctx: &Ctx<'_>,
    v: V,
) -> Result<V::Value, Error> {
    match view.to_slice() {
        Some(slice) => visit_slice(slice, ctx, v),
        None => visit_scalars(view.iter(), view.len(), ctx, v),
    }
}

/// The elements of a contiguous one-dimensional array (or row).
fn visit_slice<'de, T: Elem, V: Visitor<'de>>(
    slice: &[T],
    ctx: &Ctx<'_>,
    v: V,
) -> Result<V::Value, Error> {
    visit_scalars(slice.iter(), slice.len(), ctx, v)
}

/// The `len` elements of a one-dimensional array, in order; elements left over after the
/// visitor stops are refused ([`no_trailing`]).
fn visit_scalars<'de, 'v, T: Elem + 'v, V: Visitor<'de>>(
    iter: impl Iterator<Item = &'v T>,
    len: usize,
    ctx: &Ctx<'_>,
    v: V,
) -> Result<V::Value, Error> {
    let mut items = Scalars { iter, taken: 0 };
    let value = v.visit_seq(&mut items)?;
    no_trailing(ctx, items.taken, len)?;
    Ok(value)
}

struct Scalars<I> {
    iter: I,
    taken: usize,
}

impl<'de, 'v, T: Elem + 'v, I: Iterator<Item = &'v T>> de::SeqAccess<'de> for Scalars<I> {
    type Error = Error;
    fn next_element_seed<S: DeserializeSeed<'de>>(
        &mut self,
        seed: S,
    ) -> Result<Option<S::Value>, Error> {
        match self.iter.next() {
            None => Ok(None),
            Some(&x) => {
                self.taken += 1;
                seed.deserialize(ScalarDe(x)).map(Some)
            }
        }
    }
    fn size_hint(&self) -> Option<usize> {
        self.iter.size_hint().1
    }
}

/// A sub-array: one-dimensional (the rows of a matrix) or of any dimension.
enum View<'v, T> {
    /// A row of a C-contiguous matrix.
    Slice(&'v [T]),
    One(ArrayView1<'v, T>),
    Dyn(ArrayViewD<'v, T>),
}

struct Rows<'a, 'py, I> {
    iter: I,
    taken: usize,
    ctx: &'a Ctx<'py>,
}

impl<'de, 'v, T: Elem + 'v, I> de::SeqAccess<'de> for Rows<'_, '_, I>
where
    I: Iterator<Item = View<'v, T>>,
{
    type Error = Error;
    fn next_element_seed<S: DeserializeSeed<'de>>(
        &mut self,
        seed: S,
    ) -> Result<Option<S::Value>, Error> {
        match self.iter.next() {
            None => Ok(None),
            Some(row) => {
                self.taken += 1;
                seed.deserialize(ViewDe {
                    view: row,
                    ctx: self.ctx,
                })
                .map(Some)
            }
        }
    }
    fn size_hint(&self) -> Option<usize> {
        self.iter.size_hint().1
    }
}

/// The Deserializer methods of an array value (an element or a sub-array) besides
/// `deserialize_any`: present (`Some`), never an enum, transparent to newtypes, everything else
/// through `deserialize_any`.
macro_rules! array_value_methods {
    () => {
        fn deserialize_option<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
            v.visit_some(self)
        }
        fn deserialize_enum<V: Visitor<'de>>(
            self,
            _name: &'static str,
            _variants: &'static [&'static str],
            _v: V,
        ) -> Result<V::Value, Error> {
            Err(expected_value())
        }
        fn deserialize_newtype_struct<V: Visitor<'de>>(
            self,
            _name: &'static str,
            v: V,
        ) -> Result<V::Value, Error> {
            v.visit_newtype_struct(self)
        }
        fn deserialize_ignored_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
            v.visit_unit()
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
            bytes byte_buf unit unit_struct seq tuple tuple_struct map struct identifier
        }
    };
}

/// One element of an array.
struct ScalarDe<T>(T);

impl<'de, T: Elem> de::Deserializer<'de> for ScalarDe<T> {
    type Error = Error;
    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        self.0.visit(v)
    }
    array_value_methods!();
}

/// A sub-array (n ≥ 0 dimensions) of an array.
struct ViewDe<'a, 'v, 'py, T> {
    view: View<'v, T>,
    ctx: &'a Ctx<'py>,
}

impl<'de, T: Elem> de::Deserializer<'de> for ViewDe<'_, '_, '_, T> {
    type Error = Error;
    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, Error> {
        match self.view {
            View::Slice(row) => visit_slice(row, self.ctx, v),
            View::One(view) => visit_1d(view, self.ctx, v),
            View::Dyn(view) if view.ndim() == 0 => {
                let x = view
                    .into_dimensionality::<Ix0>()
                    .map_err(|e| de::Error::custom(e.to_string()))?;
                x.into_scalar().visit(v)
            }
            View::Dyn(view) => visit_view(view, self.ctx, v),
        }
    }
    array_value_methods!();
}
