//! NumPy arguments in, NumPy arrays out.
//!
//! An array argument of rows (origins, directions) must be float64 of shape
//! `(n, 3)`: a C-contiguous array is read in place, any other layout (a
//! slice with a step, a transpose, Fortran order) is copied once into row
//! order, which costs far less than casting its rays. Another dtype
//! (float32, int64 ...) is refused with a `ValueError` that names the
//! argument and says how to convert, rather than converted silently; a
//! Python list (not an array) is converted with `numpy.asarray(x,
//! dtype=float64)`. Every problem is a `ValueError` naming the argument.

use crate::errors::value_error;
use numpy::ndarray::{Array2, Array3};
use numpy::{
    PyArray2, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The rows of an `(n, 3)` float64 argument: borrowed from the NumPy array
/// when it is C-contiguous, copied into row order otherwise.
pub struct Rows3<'py> {
    data: Data<'py>,
    rows: usize,
}

enum Data<'py> {
    /// A C-contiguous array, read in place.
    Borrowed(PyReadonlyArray2<'py, f64>),
    /// Any other layout, copied in row order.
    Copied(Vec<f64>),
}

impl Rows3<'_> {
    /// The values row after row (`x0 y0 z0 x1 ...`), `3 × len()` of them.
    pub fn flat(&self) -> &[f64] {
        match &self.data {
            // C-contiguity was checked when the borrow was taken.
            Data::Borrowed(a) => a.as_slice().unwrap_or(&[]),
            Data::Copied(v) => v,
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows
    }

    /// `true` without rows.
    pub fn is_empty(&self) -> bool {
        self.rows == 0
    }

    /// `true` when the rows are read in place (a C-contiguous array).
    pub fn is_borrowed(&self) -> bool {
        matches!(self.data, Data::Borrowed(_))
    }
}

/// A shape as Python prints it: `(4,)`, `(2, 3)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The argument `name` as the rows of an `(n, 3)` float64 array (module docs).
pub fn rows3<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<Rows3<'py>> {
    let py = obj.py();
    let array = if let Ok(a) = obj.cast::<PyUntypedArray>() {
        a.clone()
    } else {
        let kwargs = PyDict::new(py);
        kwargs.set_item("dtype", "float64")?;
        let converted = py
            .import("numpy")?
            .getattr("asarray")?
            .call((obj,), Some(&kwargs))
            .map_err(|e| {
                value_error(format!(
                    "{name}: expected a float64 array of shape (n, 3), got a {} that NumPy \
                     cannot convert: {e}",
                    type_name(obj)
                ))
            })?;
        converted.cast_into::<PyUntypedArray>().map_err(|_| {
            value_error(format!(
                "{name}: expected a float64 array of shape (n, 3), got a {}",
                type_name(obj)
            ))
        })?
    };
    let dtype = array.dtype();
    if !dtype.is_equiv_to(&numpy::dtype::<f64>(py)) {
        return Err(value_error(format!(
            "{name}: expected dtype float64, got {dtype} (convert with \
             {name}.astype(numpy.float64))"
        )));
    }
    let shape = array.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(value_error(format!(
            "{name}: expected shape (n, 3), one row x, y, z per ray, got {}",
            shape_text(shape)
        )));
    }
    let rows = shape[0];
    if !array.is_aligned() {
        return Err(value_error(format!(
            "{name}: the array's data is not aligned for float64 (pass \
             numpy.require({name}, requirements=\"CA\"))"
        )));
    }
    let c_contiguous = array.is_c_contiguous();
    let typed = array.cast_into::<PyArray2<f64>>().map_err(|e| {
        value_error(format!(
            "{name}: expected a float64 array of shape (n, 3): {e}"
        ))
    })?;
    let readonly = typed.try_readonly().map_err(|e| {
        value_error(format!(
            "{name}: the array cannot be read now ({e}); pass a copy"
        ))
    })?;
    let data = if c_contiguous && readonly.as_slice().is_ok() {
        Data::Borrowed(readonly)
    } else {
        Data::Copied(readonly.as_array().iter().copied().collect())
    };
    Ok(Rows3 { data, rows })
}

/// The Python type name of `obj`, for messages.
fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "object".to_owned(), |n| n.to_string())
}

/// A joint vector argument: a sequence (list, tuple, 1-D array) of numbers,
/// radians for revolute joints and metres for prismatic ones. Its length
/// and finiteness are checked by the kinematics (a `ValueError` naming the
/// joint).
pub fn joint_values(obj: &Bound<'_, PyAny>, dof: usize) -> PyResult<Vec<f64>> {
    // A complex array would be cast to its real part (issue 48).
    let complex = |o: &Bound<'_, PyAny>| type_name(o).contains("complex");
    let complex_dtype = obj
        .getattr("dtype")
        .and_then(|d| d.getattr("kind"))
        .is_ok_and(|k| k.extract::<String>().is_ok_and(|k| k == "c"));
    // (Sequences only: iterating a generator would use it up.)
    let complex_item = obj.cast::<pyo3::types::PySequence>().is_ok_and(|seq| {
        seq.try_iter()
            .is_ok_and(|items| items.flatten().any(|item| complex(&item)))
    });
    if complex_dtype || complex_item || complex(obj) {
        return Err(value_error(format!(
            "q: complex values (a {}): expected {dof} real joint values (radians; metres for \
             prismatic joints)",
            type_name(obj)
        )));
    }
    obj.extract::<Vec<f64>>().map_err(|e| {
        value_error(format!(
            "q: expected a sequence of {dof} joint values (radians; metres for prismatic \
             joints), got a {}: {e}",
            type_name(obj)
        ))
    })
}

/// A 4 × 4 float64 array from row-major values.
pub fn matrix4<'py>(py: Python<'py>, rows: &[[f64; 4]; 4]) -> Bound<'py, PyArray2<f64>> {
    PyArray2::from_owned_array(py, Array2::from_shape_fn((4, 4), |(r, c)| rows[r][c]))
}

/// An `n × 4 × 4` float64 array from `n` row-major matrices.
pub fn matrices4<'py>(py: Python<'py>, all: &[[[f64; 4]; 4]]) -> Bound<'py, numpy::PyArray3<f64>> {
    numpy::PyArray3::from_owned_array(
        py,
        Array3::from_shape_fn((all.len(), 4, 4), |(k, r, c)| all[k][r][c]),
    )
}

/// The rows of an `(n, 3)` float64 argument as points (see [`rows3`]).
pub fn points_of(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<geom::Point3>> {
    let rows = rows3(name, obj)?;
    Ok(rows
        .flat()
        .chunks_exact(3)
        .map(|c| geom::Point3::new(c[0], c[1], c[2]))
        .collect())
}
