//! `surfcap.Subject`: one topology, named sequences of vertex positions, frame rate, up axis and
//! units (`surfcap_mesh::Subject`), with its derived products (`surfcap_pipeline::Pipeline`:
//! distances, transition tables, graphs, walk models) cached in the same folder and under the
//! same keys as the command line's, so that the two share results.
//!
//! A subject made from a C-contiguous float32 array ([`PySubject::from_arrays`]) reads that
//! array in place; its `positions` are read-only views of its own numbers.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray2, PyArrayDyn};
use pyo3::exceptions::{PyIndexError, PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfcap_formats::export::{ExportFormat, ExportOptions};
use surfcap_formats::import::ImportOptions;
use surfcap_mesh::{PositionBuffer, Sequence, Subject, Topology, Units, UpAxis};
use surfcap_pipeline::{CacheStore, Pipeline};

use crate::arrays;
use crate::errors::IntoPyResult;
use crate::progress::PyProgress;

/// Where a subject's derived products are cached: `cache_dir` (default: the command line's
/// default folder), `cache=False` for memory only, `refresh=True` to recompute what is on disk.
#[derive(Debug, Clone)]
pub struct CacheChoice {
    pub dir: Option<PathBuf>,
    pub refresh: bool,
}

impl CacheChoice {
    pub fn new(cache_dir: Option<PathBuf>, cache: bool, refresh: bool) -> Self {
        let dir = cache.then(|| cache_dir.unwrap_or_else(surfcap_pipeline::default_cache_dir));
        CacheChoice { dir, refresh }
    }

    pub fn store(&self) -> CacheStore {
        match &self.dir {
            Some(d) => CacheStore::in_folder(d.clone(), self.refresh),
            None => CacheStore::memory_only(),
        }
    }
}

/// A subject and its derived products.
#[pyclass(frozen, name = "Subject", module = "surfcap")]
pub struct PySubject {
    pipe: Arc<Pipeline>,
    cache: CacheChoice,
}

impl PySubject {
    /// Wraps a subject, its products cached as `cache` says.
    pub fn new(subject: Subject, cache: CacheChoice) -> Self {
        let pipe = Pipeline::new(subject, cache.store(), Box::new(PyProgress::new()));
        PySubject { pipe: Arc::new(pipe), cache }
    }

    /// A result made from this subject (an interpolation, a synthesised animation): cached like
    /// this one.
    pub fn derived(&self, subject: Subject) -> Self {
        PySubject::new(subject, self.cache.clone())
    }

    pub fn subject(&self) -> &Subject {
        self.pipe.subject()
    }

    /// The derived-product pipeline (shared: cloning the `Arc` is cheap).
    pub fn pipe(&self) -> &Arc<Pipeline> {
        &self.pipe
    }

    pub fn cache_choice(&self) -> &CacheChoice {
        &self.cache
    }

    /// The global index of a frame given as an int or `"sequence:frame"`.
    pub fn frame_of(&self, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
        let s = self.subject();
        if let Ok(g) = frame.extract::<i64>() {
            if g < 0 || g as usize >= s.n_frames() {
                return Err(PyIndexError::new_err(format!(
                    "frame {g}: the subject has frames 0 to {} ({})",
                    s.n_frames() - 1,
                    sequence_list(s)
                )));
            }
            return Ok(g as usize);
        }
        let spec: String = frame.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err("a frame is an int (global index) or a str \"sequence:frame\"")
        })?;
        s.resolve_frame(&spec).py_err()
    }
}

fn sequence_list(s: &Subject) -> String {
    s.sequences().iter().map(|q| format!("{} ({} frames)", q.name, q.n_frames())).collect::<Vec<_>>().join(", ")
}

/// What the sources do not say (`--fps`, `--up-axis`, `--units`, `--name`), checked.
pub(crate) fn import_options(
    name: Option<String>,
    fps: Option<f64>,
    up_axis: Option<&str>,
    units: Option<&str>,
) -> PyResult<ImportOptions> {
    let up_axis = up_axis.map(UpAxis::parse).transpose().py_err()?;
    if let Some(f) = fps {
        surfcap_mesh::subject::check_frame_rate(f).map_err(|e| PyValueError::new_err(format!("fps: {e}")))?;
    }
    Ok(ImportOptions { name, fps, up_axis, units: units.map(Units::parse) })
}

/// Shares `len` numbers of a buffer from `start` without a copy.
struct Slice {
    buffer: PositionBuffer,
    start: usize,
    len: usize,
}

impl AsRef<[f32]> for Slice {
    fn as_ref(&self) -> &[f32] {
        &self.buffer.as_slice()[self.start..self.start + self.len]
    }
}

#[pymethods]
impl PySubject {
    /// Opens a subject: a subject cache (`surfcap import -o x.subject`) or any source the
    /// command line reads (OBJ/PLY folders, npy layouts, PC2, glb, Alembic, USD, BVH, manifests).
    #[staticmethod]
    #[pyo3(signature = (path, *, fps=None, up_axis=None, units=None, cache_dir=None, cache=true, refresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn load(
        py: Python<'_>,
        path: PathBuf,
        fps: Option<f64>,
        up_axis: Option<&str>,
        units: Option<&str>,
        cache_dir: Option<PathBuf>,
        cache: bool,
        refresh: bool,
    ) -> PyResult<Self> {
        let opts = import_options(None, fps, up_axis, units)?;
        let progress = PyProgress::new();
        let imported = py.detach(|| surfcap_formats::import::open_subject(&path, &opts, &progress)).py_err()?;
        drop(progress);
        crate::progress::log_notes(py, &imported.notes)?;
        Ok(PySubject::new(imported.subject, CacheChoice::new(cache_dir, cache, refresh)))
    }

    /// Imports one or several sources into one subject, as `surfcap import` does.
    #[staticmethod]
    #[pyo3(signature = (paths, *, name=None, fps=None, up_axis=None, units=None, cache_dir=None, cache=true, refresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn import_(
        py: Python<'_>,
        paths: &Bound<'_, PyAny>,
        name: Option<String>,
        fps: Option<f64>,
        up_axis: Option<&str>,
        units: Option<&str>,
        cache_dir: Option<PathBuf>,
        cache: bool,
        refresh: bool,
    ) -> PyResult<Self> {
        let paths: Vec<PathBuf> = match paths.extract::<PathBuf>() {
            Ok(p) => vec![p],
            Err(_) => paths.extract()?,
        };
        if paths.is_empty() {
            return Err(PyValueError::new_err("paths: expected at least one source"));
        }
        let opts = import_options(name, fps, up_axis, units)?;
        let progress = PyProgress::new();
        let imported = py.detach(|| surfcap_formats::import::import(&paths, &opts, &progress)).py_err()?;
        drop(progress);
        crate::progress::log_notes(py, &imported.notes)?;
        Ok(PySubject::new(imported.subject, CacheChoice::new(cache_dir, cache, refresh)))
    }

    /// A subject from arrays: `faces` `(T, 3)` of any integer dtype, `positions` `(F, V, 3)`
    /// float32 or float64, any order or strides. A C-contiguous float32 `positions` is read in
    /// place (no copy; do not change its numbers while the subject lives) unless `copy=True`.
    /// `sequences` splits the frames into named sequences: a list of `(name, frames)` pairs
    /// (default: one sequence named `name`).
    #[staticmethod]
    #[pyo3(signature = (faces, positions, *, fps=30.0, name="subject".to_string(), sequences=None, up_axis="+y", units="m", copy=false, cache_dir=None, cache=true, refresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays(
        faces: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        fps: f64,
        name: String,
        sequences: Option<Vec<(String, usize)>>,
        up_axis: &str,
        units: &str,
        copy: bool,
        cache_dir: Option<PathBuf>,
        cache: bool,
        refresh: bool,
    ) -> PyResult<Self> {
        let (pos, n_frames, nv) = arrays::positions(positions, "positions", !copy)?;
        let tris = arrays::faces(faces, "faces", nv)?;
        let topology = Topology::new(nv, tris, None).py_err()?;
        let split = sequences.unwrap_or_else(|| vec![(name.clone(), n_frames)]);
        let total: usize = split.iter().map(|(_, n)| n).sum();
        if total != n_frames {
            return Err(PyValueError::new_err(format!(
                "sequences: {total} frames in all, but positions hold {n_frames}"
            )));
        }
        let per_frame = 3 * nv;
        let mut seqs = Vec::with_capacity(split.len());
        let mut start = 0;
        for (seq_name, n) in split {
            let buffer = if start == 0 && n == n_frames {
                pos.buffer.clone()
            } else {
                PositionBuffer::shared(Slice {
                    buffer: pos.buffer.clone(),
                    start: start * per_frame,
                    len: n * per_frame,
                })
            };
            seqs.push(Sequence::from_buffer(seq_name, nv, buffer).py_err()?);
            start += n;
        }
        let up = UpAxis::parse(up_axis).py_err()?;
        let subject = Subject::new(name, topology, seqs, fps, up, Units::parse(units)).py_err()?;
        Ok(PySubject::new(subject, CacheChoice::new(cache_dir, cache, refresh)))
    }

    #[getter]
    fn name(&self) -> String {
        self.subject().name.clone()
    }

    #[getter]
    fn fps(&self) -> f64 {
        self.subject().fps
    }

    /// The up axis: `"+x"`, `"+y"`, `"+z"`, `"-x"`, `"-y"` or `"-z"`.
    #[getter]
    fn up_axis(&self) -> &'static str {
        self.subject().up_axis.as_str()
    }

    /// The length unit's name (`"m"`, `"cm"`, ... or a word for arbitrary units).
    #[getter]
    fn units(&self) -> String {
        self.subject().units.name.clone()
    }

    /// Metres per unit, or None for arbitrary units.
    #[getter]
    fn metres_per_unit(&self) -> Option<f64> {
        self.subject().units.metres_per_unit
    }

    #[getter]
    fn n_frames(&self) -> usize {
        self.subject().n_frames()
    }

    #[getter]
    fn n_vertices(&self) -> usize {
        self.subject().topology().n_vertices()
    }

    #[getter]
    fn n_faces(&self) -> usize {
        self.subject().topology().n_triangles()
    }

    fn __len__(&self) -> usize {
        self.subject().n_frames()
    }

    /// The sequence names, in order.
    #[getter]
    fn sequences(&self) -> Vec<String> {
        self.subject().sequences().iter().map(|s| s.name.clone()).collect()
    }

    /// `{sequence name: frame count}`, in order.
    #[getter]
    fn sequence_frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for s in self.subject().sequences() {
            d.set_item(&s.name, s.n_frames())?;
        }
        Ok(d)
    }

    /// The cache folder of the derived products, or None when they are kept in memory only.
    #[getter]
    fn cache_dir(&self) -> Option<PathBuf> {
        self.cache.dir.clone()
    }

    /// Triangles `(T, 3)` uint32, a read-only view.
    #[getter]
    fn faces<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        let tris = slf.get().subject().topology().triangles();
        let flat: &[u32] = tris.as_flattened();
        let view =
            ndarray::ArrayView2::from_shape((tris.len(), 3), flat).map_err(|e| PyValueError::new_err(e.to_string()))?;
        // SAFETY: the triangles belong to the subject, which never changes them and lives as
        // long as the view (the view's base).
        let arr = unsafe { PyArray2::borrow_from_array(&view, slf.clone().into_any()) };
        arr.call_method1("setflags", (false,))?;
        Ok(arr)
    }

    /// All positions `(F, V, 3)` float32 in global frame order: a read-only view of the
    /// subject's own numbers when it has one sequence, a copy joining them when it has several
    /// (`sequence_positions` views one sequence).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let s = self.subject();
        let nv = s.topology().n_vertices();
        if let [one] = s.sequences() {
            return arrays::position_view(py, one.buffer(), 0, &[one.n_frames(), nv, 3]);
        }
        let mut all = Vec::with_capacity(s.n_frames() * nv * 3);
        for q in s.sequences() {
            all.extend_from_slice(q.positions());
        }
        arrays::matrix(py, all, &[s.n_frames(), nv, 3])
    }

    /// The positions `(F, V, 3)` float32 of one sequence, a read-only view.
    fn sequence_positions<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let s = self.subject();
        let Some((_, q)) = s.sequence(name) else {
            return Err(PyKeyError::new_err(format!(
                "no sequence named {name:?}: the subject has {}",
                sequence_list(s)
            )));
        };
        arrays::position_view(py, q.buffer(), 0, &[q.n_frames(), s.topology().n_vertices(), 3])
    }

    /// One frame's positions `(V, 3)` float32, a read-only view; `frame` is a global index or
    /// `"sequence:frame"`.
    fn frame<'py>(&self, py: Python<'py>, frame: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let g = self.frame_of(frame)?;
        let s = self.subject();
        let (si, f) = s.frame_index().locate(g).expect("a resolved frame");
        let nv = s.topology().n_vertices();
        arrays::position_view(py, s.sequences()[si].buffer(), f * nv * 3, &[nv, 3])
    }

    /// The global index of a frame given as `"sequence:frame"` (or a global index).
    fn resolve_frame(&self, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
        self.frame_of(frame)
    }

    /// A global frame index written as `"sequence:frame"`.
    fn frame_name(&self, frame: usize) -> PyResult<String> {
        let s = self.subject();
        if frame >= s.n_frames() {
            return Err(PyIndexError::new_err(format!("frame {frame}: the subject has {} frames", s.n_frames())));
        }
        Ok(s.frame_index().label(frame))
    }

    /// Writes the subject as `surfcap export` does: `format` is glb, obj, ply, pc2, npy, usda
    /// or abc (default: from the extension). Nothing surfcap did not write is replaced unless
    /// `force`; a failed export leaves nothing half-written. Returns the paths written.
    #[pyo3(signature = (path, format=None, *, sequences=None, ascii=false, force=false))]
    fn export(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        sequences: Option<Vec<String>>,
        ascii: bool,
        force: bool,
    ) -> PyResult<Vec<PathBuf>> {
        let format = match format {
            Some(f) => f.parse::<ExportFormat>().py_err()?,
            None => surfcap_synthesis::animation_output::output_format(None, &path),
        };
        let s = self.subject().clone().select(&sequences.unwrap_or_default()).py_err()?;
        let progress = PyProgress::new();
        let written = py
            .detach(|| -> anyhow::Result<Vec<PathBuf>> {
                let mut outs = surfcap_mesh::output_set::OutputSet::new(&[]);
                surfcap_formats::export::plan_export(&mut outs, format, &path, force)?;
                let w = surfcap_formats::export::export(
                    &s,
                    format,
                    &path,
                    ExportOptions { ply_ascii: ascii, force },
                    &progress,
                )?;
                outs.commit()?;
                Ok(w)
            })
            .map_err(crate::errors::anyhow_to_py)?;
        Ok(written)
    }

    /// Writes a subject cache (what `surfcap import -o x.subject` writes), which every command
    /// and `Subject.load` open fast.
    #[pyo3(signature = (path, *, force=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, force: bool) -> PyResult<()> {
        let progress = PyProgress::new();
        let s = self.subject();
        py.detach(|| surfcap_mesh::cache::write_cache(&path, s, force, &progress)).py_err()
    }

    fn __repr__(&self) -> String {
        let s = self.subject();
        format!(
            "Subject({:?}: {} vertices, {} triangles, {} frames at {} fps in {} ({}), up {})",
            s.name,
            s.topology().n_vertices(),
            s.topology().n_triangles(),
            s.n_frames(),
            s.fps,
            s.units.symbol(),
            sequence_list(s),
            s.up_axis.as_str()
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySubject>()?;
    m.add_class::<arrays::BufferOwner>()?;
    crate::progress::register(m)
}
