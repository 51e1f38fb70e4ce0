//! numpy arrays in and out, without a slow path.
//!
//! In: any array-like of float32 or float64 (or anything `numpy.asarray` makes a float array
//! of), C- or F-ordered or strided. A C-contiguous float32 position array is used in place: the
//! [`PositionBuffer`] keeps a reference to the array and reads its memory, no copy is made.
//! Anything else is copied once by numpy into a float32 array in C order, which is then read in
//! place (a strided or F-ordered array costs numpy's one pass over its numbers, not a slow
//! path). float64 positions are rounded to the nearest float32, the precision of every surfcap
//! subject.
//!
//! Out: [`position_view`] gives a read-only numpy view of a buffer, kept alive by the view;
//! [`matrix`] and [`vector`] hand a Rust vector over to numpy without a copy.

use ndarray::{ArrayView, IxDyn};
use numpy::{Element, PyArray, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use surfcap_mesh::PositionBuffer;

/// The memory of a C-contiguous float32 numpy array, kept alive by a reference to the array.
struct NumpyMemory {
    _owner: Py<PyAny>,
    ptr: *const f32,
    len: usize,
}

// SAFETY: the array's memory stays where it is while `_owner` holds a reference to it (numpy
// refuses to resize an array that others refer to), and surfcap only reads it. Python code may
// still write into the array: `Subject.from_arrays` documents that the caller must not change
// the numbers while the subject lives (or pass `copy=True`).
unsafe impl Send for NumpyMemory {}
unsafe impl Sync for NumpyMemory {}

impl AsRef<[f32]> for NumpyMemory {
    fn as_ref(&self) -> &[f32] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: see the Send/Sync note: `ptr` points at `len` initialised f32 of the live array.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

/// A float array's numbers and shape, as an owned float32 C-order buffer or borrowed in place.
pub struct FloatArray {
    pub shape: Vec<usize>,
    pub buffer: PositionBuffer,
    /// Whether the numbers are the caller's memory (no copy was made).
    pub borrowed: bool,
}

/// Any float array-like as float32 C-order numbers: borrowed when `borrow` and the array is a
/// C-contiguous float32 numpy array, copied in one pass otherwise. `what` names the argument
/// in errors.
///
/// The copy of a float32 or float64 array of any order or strides is numpy's own
/// (`numpy.array(x, dtype=float32, order="C")`, a tight loop that releases the GIL), which the
/// subject then reads in place: an F-ordered, strided or reversed array costs what numpy's
/// single pass costs (ndarray's element iterator over a dynamic-rank view was 8 to 22 times
/// slower; `python/bench/arrays.py` measures both).
pub fn float_array(obj: &Bound<'_, PyAny>, what: &str, borrow: bool) -> PyResult<FloatArray> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f32>>()
        && borrow
        && a.is_c_contiguous()
    {
        return Ok(FloatArray { shape: a.shape().to_vec(), buffer: numpy_memory(a), borrowed: true });
    }
    let np = obj.py().import("numpy")?;
    if obj.cast::<PyArrayDyn<f32>>().is_ok() || obj.cast::<PyArrayDyn<f64>>().is_ok() {
        let kw = pyo3::types::PyDict::new(obj.py());
        kw.set_item("dtype", "float32")?;
        kw.set_item("order", "C")?;
        kw.set_item("copy", true)?;
        let copy =
            np.call_method("array", (obj,), Some(&kw)).map_err(|e| PyValueError::new_err(format!("{what}: {e}")))?;
        let copy = copy.cast::<PyArrayDyn<f32>>().map_err(|e| PyTypeError::new_err(format!("{what}: {e}")))?;
        return Ok(FloatArray { shape: copy.shape().to_vec(), buffer: numpy_memory(copy), borrowed: false });
    }
    // Lists, integer arrays, float16...: numpy makes a float64 array of them (once).
    let converted = np
        .call_method1("asarray", (obj, "float64"))
        .map_err(|e| PyTypeError::new_err(format!("{what}: expected an array of numbers (float32 or float64): {e}")))?;
    if converted.cast::<PyArrayDyn<f64>>().is_err() {
        return Err(PyTypeError::new_err(format!("{what}: expected an array of numbers (float32 or float64)")));
    }
    float_array(&converted, what, false)
}

/// The numbers of a C-contiguous float32 array, read in place (the buffer keeps the array alive).
fn numpy_memory(a: &Bound<'_, PyArrayDyn<f32>>) -> PositionBuffer {
    debug_assert!(a.is_c_contiguous());
    let mem = NumpyMemory { _owner: a.clone().into_any().unbind(), ptr: a.data() as *const f32, len: a.len() };
    PositionBuffer::shared(mem)
}

/// Positions `(F, V, 3)` or one frame `(V, 3)`: the buffer and `(frames, vertices)`.
pub fn positions(obj: &Bound<'_, PyAny>, what: &str, borrow: bool) -> PyResult<(FloatArray, usize, usize)> {
    let a = float_array(obj, what, borrow)?;
    let (f, v) = match a.shape.as_slice() {
        [f, v, 3] => (*f, *v),
        [v, 3] => (1, *v),
        s => {
            return Err(PyValueError::new_err(format!(
                "{what}: shape {s:?}, expected (frames, vertices, 3) or (vertices, 3)"
            )));
        }
    };
    Ok((a, f, v))
}

/// Any integer array-like of shape `(T, 3)` as triangles, each index checked against
/// `n_vertices`.
pub fn faces(obj: &Bound<'_, PyAny>, what: &str, n_vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    let np = obj.py().import("numpy")?;
    let kind: String = np.call_method1("asarray", (obj,))?.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind != "i" && kind != "u" {
        return Err(PyTypeError::new_err(format!("{what}: dtype kind {kind:?}, expected an integer array")));
    }
    let a = np.call_method1("asarray", (obj, "int64"))?;
    let a = a.cast::<PyArrayDyn<i64>>().map_err(|e| PyTypeError::new_err(format!("{what}: {e}")))?;
    let ro = a.try_readonly().map_err(|e| PyValueError::new_err(format!("{what}: {e}")))?;
    let view = ro.as_array();
    let shape = view.shape().to_vec();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!("{what}: shape {shape:?}, expected (triangles, 3)")));
    }
    let mut out = Vec::with_capacity(shape[0]);
    for (t, row) in view.outer_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (k, &x) in row.iter().enumerate() {
            if x < 0 || x as u64 >= n_vertices as u64 {
                return Err(PyValueError::new_err(format!(
                    "{what}: triangle {t} has vertex index {x}, expected 0 to {}",
                    n_vertices.saturating_sub(1)
                )));
            }
            tri[k] = x as u32;
        }
        out.push(tri);
    }
    Ok(out)
}

/// Holds a [`PositionBuffer`] for the numpy views of it.
#[pyclass(frozen, module = "surfcap._surfcap")]
pub struct BufferOwner {
    buffer: PositionBuffer,
}

/// A read-only numpy view of `buffer[offset..offset + shape.product()]` with `shape`, kept
/// alive by the view itself (no copy).
pub fn position_view<'py>(
    py: Python<'py>,
    buffer: &PositionBuffer,
    offset: usize,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let n: usize = shape.iter().product();
    let all = buffer.as_slice();
    if offset + n > all.len() {
        return Err(PyValueError::new_err(format!(
            "a view of {n} numbers at {offset} is past the buffer's {}",
            all.len()
        )));
    }
    let owner = Bound::new(py, BufferOwner { buffer: buffer.clone() })?;
    let slice = &owner.get().buffer.as_slice()[offset..offset + n];
    let view = ArrayView::from_shape(IxDyn(shape), slice).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // SAFETY: the memory belongs to the buffer `owner` holds; `owner` becomes the array's base,
    // so it lives as long as the view, and nothing ever writes to a PositionBuffer.
    let arr = unsafe { PyArrayDyn::borrow_from_array(&view, owner.clone().into_any()) };
    arr.call_method1("setflags", (false,))?;
    Ok(arr)
}

/// A Rust vector as a numpy array of `shape` (moved, not copied).
pub fn matrix<'py, T: Element>(
    py: Python<'py>,
    values: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let n: usize = shape.iter().product();
    if n != values.len() {
        return Err(PyValueError::new_err(format!("{} numbers do not fill shape {shape:?}", values.len())));
    }
    PyArray::from_vec(py, values).reshape(shape.to_vec())
}

/// A Rust vector as a 1-D numpy array (moved, not copied).
pub fn vector<'py, T: Element>(py: Python<'py>, values: Vec<T>) -> Bound<'py, numpy::PyArray1<T>> {
    PyArray::from_vec(py, values)
}
