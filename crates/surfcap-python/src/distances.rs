//! Pose distances and non-linear interpolation (thesis chapter 2), as `surfcap distance` and
//! `surfcap interpolate` compute them.
//!
//! - `pose_distances(subject, *, metric, w)`: the all-pairs matrix `(F, F)` float64 from the
//!   subject's pipeline, so the same cache file (and the same bits) as `surfcap distance`; a
//!   read-only view of the pipeline's matrix, no copy.
//! - `pose_distance(subject, a, b, *, metric, w)`: one entry, the same bits as the matrix's,
//!   computed for the pair alone unless the matrix is already at hand.
//! - `interpolate(subject, from_, to, *, steps, method, stretch)`: the poses between two frames
//!   as a new `Subject` (`surfcap_synthesis::interpolation_run`, the command's function).

use std::path::PathBuf;
use std::sync::Arc;

use numpy::PyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_geometry::pose_interpolation::StretchInterpolation;
use surfcap_pipeline::PoseDistances;
use surfcap_synthesis::interpolation_run::InterpolationMethod;

use crate::errors::IntoPyResult;
use crate::subject::PySubject;

/// A library error as a Python exception: a parameter out of its domain (the message names it)
/// is a `ValueError`, anything else a `SurfcapError`.
pub fn pipeline_err(e: surfcap_pipeline::Error) -> PyErr {
    match e {
        surfcap_pipeline::Error::Parameter { .. } => PyValueError::new_err(e.to_string()),
        e => crate::errors::to_py(e),
    }
}

/// `metric` and `w` as the distance parameters of `surfcap distance --metric --w`.
fn distance_params(metric: &str, w: f64) -> PyResult<DistanceParams> {
    let metric: PoseMetric = metric.parse().map_err(|e| PyValueError::new_err(format!("metric: {e}")))?;
    Ok(DistanceParams { metric, w, vertex_weights: None })
}

/// A frame as the caller wrote it (`"walk:12"` or `"12"`), for names and messages.
pub fn frame_text(frame: &Bound<'_, PyAny>) -> PyResult<String> {
    match frame.extract::<String>() {
        Ok(s) => Ok(s),
        Err(_) => Ok(frame.str()?.to_string()),
    }
}

/// Holds a distance matrix of the pipeline for the numpy views of it.
#[pyclass(frozen, module = "surfcap._surfcap")]
pub struct MatrixOwner {
    matrix: Arc<PoseDistances>,
}

/// The all-pairs pose distances `(F, F)` float64 of `subject`, global frame order (row i,
/// column j: the distance between frames i and j; symmetric, 0 on the diagonal), as
/// `surfcap distance --metric METRIC --w W -o d.npy` writes them: the same cache file (read
/// when there, written when computed) and the same bits. `metric`: "deformation" (thesis
/// eq. 2.13), "deformation-log" (eq. 2.14), "euclidean" (eq. 2.2, in squared units) or
/// "deformation-literal" (eq. 2.13 with eq. 2.6 read literally, A^-1 B); `w`: the weight of the
/// stretch term. A read-only view of the cached matrix (`.copy()` to change it).
#[pyfunction]
#[pyo3(signature = (subject, *, metric="deformation", w=0.01))]
pub fn pose_distances<'py>(
    py: Python<'py>,
    subject: &PySubject,
    metric: &str,
    w: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let params = distance_params(metric, w)?;
    let pipe = subject.pipe().clone();
    let fetched = py.detach(|| pipe.distances(&params)).map_err(pipeline_err)?;
    matrix_view(py, fetched.value)
}

/// A read-only `(n, n)` view of a pipeline's matrix, kept alive by the view.
fn matrix_view(py: Python<'_>, matrix: Arc<PoseDistances>) -> PyResult<Bound<'_, PyArray2<f64>>> {
    let n = matrix.n;
    let owner = Bound::new(py, MatrixOwner { matrix })?;
    let values: &[f64] = &owner.get().matrix.values;
    let view = ndarray::ArrayView2::from_shape((n, n), values).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // SAFETY: the numbers belong to the `Arc` that `owner` holds; `owner` becomes the array's
    // base, so it lives as long as the view, and nothing writes to a pipeline's matrix.
    let arr = unsafe { PyArray2::borrow_from_array(&view, owner.clone().into_any()) };
    arr.call_method1("setflags", (false,))?;
    Ok(arr)
}

/// The pose distance between frames `a` and `b` (a global index or `"sequence:frame"`): the
/// same number, to the bit, as entry (a, b) of `pose_distances(subject, metric=..., w=...)`,
/// computed for this pair alone unless the matrix is already at hand.
#[pyfunction]
#[pyo3(signature = (subject, a, b, *, metric="deformation", w=0.01))]
pub fn pose_distance(
    py: Python<'_>,
    subject: &PySubject,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    metric: &str,
    w: f64,
) -> PyResult<f64> {
    let params = distance_params(metric, w)?;
    let (i, j) = (subject.frame_of(a)?, subject.frame_of(b)?);
    let pipe = subject.pipe().clone();
    py.detach(|| pipe.pose_distance(&params, i, j)).map_err(pipeline_err)
}

/// The poses from frame `from_` to frame `to` (each a global index or `"sequence:frame"`), as
/// `surfcap interpolate` makes them: `steps` poses (>= 2) both ends included, the first frame
/// `from_` as captured, the last frame `to` aligned onto it (thesis eq. 2.3), the ones between
/// by `method` "nonlinear" (eq. 2.45-2.49, `stretch` "linear" eq. 2.45 or "log" eq. 2.46) or
/// "linear" (eq. 2.23). Returns a `Subject` of one sequence named `<from>_to_<to>`: positions
/// `(steps, V, 3)` float32, the subject's faces. `output=` (with `format=` as `--format`, default
/// from the extension, and `force=`) also writes it as the command does.
#[pyfunction]
#[pyo3(signature = (subject, from_, to, *, steps=10, method="nonlinear", stretch="linear", output=None, format=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn interpolate<'py>(
    py: Python<'py>,
    subject: &PySubject,
    from_: &Bound<'_, PyAny>,
    to: &Bound<'_, PyAny>,
    steps: i64,
    method: &str,
    stretch: &str,
    output: Option<PathBuf>,
    format: Option<&str>,
    force: bool,
) -> PyResult<Bound<'py, PySubject>> {
    if steps < 2 {
        return Err(PyValueError::new_err(format!("steps {steps}: expected a whole number >= 2")));
    }
    let method: InterpolationMethod = method.parse().map_err(|e| PyValueError::new_err(format!("method: {e}")))?;
    let stretch: StretchInterpolation = stretch.parse().map_err(|e| PyValueError::new_err(format!("stretch: {e}")))?;
    let (gi, gj) = (subject.frame_of(from_)?, subject.frame_of(to)?);
    let (from_name, to_name) = (frame_text(from_)?, frame_text(to)?);
    let pipe = subject.pipe().clone();
    let made = py
        .detach(|| {
            surfcap_synthesis::interpolation_run::interpolate(
                pipe.subject(),
                (gi, &from_name),
                (gj, &to_name),
                steps as usize,
                method,
                stretch,
            )
        })
        .py_err()?;
    let out = Bound::new(py, subject.derived(made.animation))?;
    if let Some(path) = output {
        write_animation(&out, path, format, force)?;
    }
    Ok(out)
}

/// Writes an animation with `Subject.export` (what the command writes for `-o`, `--format`).
pub fn write_animation(out: &Bound<'_, PySubject>, path: PathBuf, format: Option<&str>, force: bool) -> PyResult<()> {
    let kw = pyo3::types::PyDict::new(out.py());
    kw.set_item("force", force)?;
    out.call_method("export", (path, format), Some(&kw))?;
    Ok(())
}

/// Benchmark hook (`python/bench/overhead.py`): the seconds of the library work
/// `pose_distances(subject)` does on a subject whose products are kept in memory (a fresh
/// pipeline, so the matrix is computed), timed in Rust around that call alone.
#[pyfunction]
#[pyo3(signature = (subject, *, metric="deformation", w=0.01))]
fn _library_pose_distances_seconds(py: Python<'_>, subject: &PySubject, metric: &str, w: f64) -> PyResult<f64> {
    let params = distance_params(metric, w)?;
    let s = subject.subject().clone();
    py.detach(|| {
        let pipe = surfcap_pipeline::Pipeline::new(
            s,
            surfcap_pipeline::CacheStore::memory_only(),
            Box::new(surfcap_mesh::NoProgress),
        );
        let t0 = std::time::Instant::now();
        let d = pipe.distances(&params)?;
        let secs = t0.elapsed().as_secs_f64();
        drop(d);
        Ok(secs)
    })
    .map_err(pipeline_err)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_library_pose_distances_seconds, m)?)?;
    m.add_class::<MatrixOwner>()?;
    m.add_function(wrap_pyfunction!(pose_distances, m)?)?;
    m.add_function(wrap_pyfunction!(pose_distance, m)?)?;
    m.add_function(wrap_pyfunction!(interpolate, m)?)?;
    Ok(())
}
