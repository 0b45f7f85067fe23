//! numpy in and out: every array argument of the module goes through here, and all the
//! `unsafe` of the crate is in this file (each block with its SAFETY argument).
//!
//! Inputs: a C-contiguous `float64` ndarray is read in place, without a copy; anything else that
//! numpy can turn into one (lists, other dtypes, strided views) is converted once by
//! `numpy.ascontiguousarray(x, dtype=float64)`. The shape is then checked against what the
//! model needs, and a wrong one is a `ValueError` naming the argument, the shape given and the
//! shape expected.
//!
//! Outputs are new C-contiguous `float64` arrays that the caller owns; a batched call allocates
//! its result before the GIL is released and the loop in Rust fills it in place.

use numpy::{Element, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

/// An input array of `float64`, C-contiguous, held for the duration of a call.
pub struct Input<'py> {
    array: Bound<'py, PyArrayDyn<f64>>,
}

/// `numpy.ascontiguousarray`, looked up once.
fn ascontiguousarray<'py>(py: Python<'py>) -> PyResult<&'py Bound<'py, PyAny>> {
    static FUNCTION: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    FUNCTION.import(py, "numpy", "ascontiguousarray")
}

/// The `float64` dtype, looked up once.
fn float64<'py>(py: Python<'py>) -> PyResult<&'py Bound<'py, PyAny>> {
    static DTYPE: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    DTYPE.import(py, "numpy", "float64")
}

impl<'py> Input<'py> {
    /// `ob` as a C-contiguous `float64` array: itself when it already is one, else a converted
    /// copy. `name` is the argument's name for errors.
    pub fn new(ob: &Bound<'py, PyAny>, name: &str) -> PyResult<Self> {
        if let Ok(a) = ob.cast::<PyArrayDyn<f64>>() {
            if a.is_c_contiguous() && a.is_aligned() {
                return Ok(Self { array: a.clone() });
            }
        }
        let py = ob.py();
        let converted = ascontiguousarray(py)?
            .call1((ob, float64(py)?))
            .map_err(|e| {
                PyValueError::new_err(format!("{name}: not an array of numbers ({})", e.value(py)))
            })?;
        let array = converted.cast_into::<PyArrayDyn<f64>>().map_err(|_| {
            PyValueError::new_err(format!("{name}: numpy did not give a float64 array"))
        })?;
        Ok(Self { array })
    }

    /// The shape.
    pub fn shape(&self) -> &[usize] {
        self.array.shape()
    }

    /// The elements in C order.
    ///
    /// Only for calls that keep the GIL until they are done with the slice: batched calls that
    /// release it take [`Input::shared`] instead.
    pub fn slice(&self) -> &[f64] {
        // SAFETY: the array is C-contiguous and aligned `float64` (checked in `new`, or made so
        // by numpy), so its buffer is `len` initialised f64 in order. We hold a reference to the
        // array, so the buffer is not freed (numpy refuses to resize an array that has other
        // references). The GIL is held for as long as the slice lives (the borrow is tied to
        // `self`, which lives in a call that does not release the GIL), so no Python code can
        // write to the buffer meanwhile; another extension writing to it without the GIL would
        // break numpy's own rules.
        unsafe { self.array.as_slice() }.unwrap_or(&[])
    }

    /// A read-only borrow registered with numpy's borrow checker, for a loop that runs with
    /// the GIL released: while it lives, a writable borrow of the same array elsewhere fails.
    pub fn shared(&self) -> PyResult<numpy::PyReadonlyArrayDyn<'py, f64>> {
        self.array
            .try_readonly()
            .map_err(|e| PyValueError::new_err(format!("array is being written elsewhere: {e}")))
    }
}

/// The elements of a read-only borrow (C-contiguous by construction of [`Input`]).
pub fn shared_slice<'a>(a: &'a numpy::PyReadonlyArrayDyn<'_, f64>) -> &'a [f64] {
    a.as_slice().unwrap_or(&[])
}

/// A new 1-D array with these values.
pub fn vector<'py>(py: Python<'py>, values: &[f64]) -> Bound<'py, PyAny> {
    PyArray1::from_slice(py, values).into_any()
}

/// A new C-contiguous result array, filled in Rust before it is handed to Python.
pub struct Output<'py, T: Element> {
    array: Bound<'py, PyArrayDyn<T>>,
}

impl<'py, T: Element> Output<'py, T> {
    /// A zeroed array of this shape.
    pub fn zeros(py: Python<'py>, shape: &[usize]) -> Self {
        Self {
            array: PyArrayDyn::<T>::zeros(py, shape, false),
        }
    }

    /// Its elements in C order, to fill (also with the GIL released).
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        // SAFETY: the array was created by `zeros` (C-contiguous, aligned, `len` initialised
        // elements) and its only handle is inside this `Output` until `into_array`, so nothing
        // else, with or without the GIL, can reach the buffer while the `&mut self` borrow
        // lives. The buffer lives as long as the array, which `self` keeps.
        unsafe { std::slice::from_raw_parts_mut(self.array.data(), self.array.len()) }
    }

    /// The filled array, for Python, as any object.
    pub fn into_any(self) -> Bound<'py, PyAny> {
        self.array.into_any()
    }
}

/// `ob` as one number: a Python number or a 0-d array; `None` for anything with a shape.
pub fn scalar(ob: &Bound<'_, PyAny>) -> Option<f64> {
    if let Ok(a) = ob.cast::<numpy::PyUntypedArray>() {
        if a.ndim() > 0 {
            return None;
        }
    } else if ob.hasattr("__len__").unwrap_or(false) {
        return None;
    }
    ob.extract::<f64>().ok()
}

/// A shape as Python writes it: `(6,)`, `(10, 6)`.
pub fn shape_text(shape: &[usize]) -> String {
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

/// What an argument of a possibly batched call must look like: `width` values, or a 2-D array
/// of rows of `width` values (`batch` rows when another argument fixed it already).
pub fn check_shape(
    name: &str,
    input: &Input<'_>,
    width: usize,
    batch: &mut Option<Option<usize>>,
) -> PyResult<()> {
    let shape = input.shape();
    let rows = match shape {
        [n] if *n == width => None,
        [b, n] if *n == width => Some(*b),
        _ => {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {}, expected ({width},) or (batch, {width})",
                shape_text(shape)
            )));
        }
    };
    match batch {
        None => *batch = Some(rows),
        Some(expected) if *expected == rows => {}
        Some(expected) => {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {} does not match the other arguments ({})",
                shape_text(shape),
                match expected {
                    None => "one state".to_owned(),
                    Some(b) => format!("{b} states"),
                }
            )));
        }
    }
    Ok(())
}
