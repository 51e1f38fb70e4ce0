//! Huang et al. 2009's surface motion graph from Python, as `surfcap smg query | build`:
//! `smg_query` answers one query (the path between two key frames that covers a distance in a
//! time at the least transition cost) on a `Subject` or a `FrameSet` and returns the animation
//! with its `SmgQueryReport`; `smg_build` returns the shape similarity (the matrix the command
//! caches as `smg-similarity-*.npy`) and the graph's `SmgGraphReport`. Both call
//! `surfcap_synthesis::smg_query::SmgGraph`, as the command does.
//!
//! `FrameSet` is a frame set: every frame its own mesh (a `.frames` folder, or any source the
//! command line reads as one), its frames `(V_i, 3)` float32 positions and `(T_i, 3)` uint32
//! triangles.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::PyArray2;
use pyo3::exceptions::{PyIndexError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use surfcap_formats::export::{ExportFormat, ExportOptions};
use surfcap_formats::import::{Imported, ImportedData, ImportedFrames};
use surfcap_mesh::frame_set::{FrameSet, FrameSetSequence};
use surfcap_mesh::output_set::OutputSet;
use surfcap_mesh::{Topology, Units, UpAxis};
use surfcap_pipeline::constraint_files::{TimeSpec, TimeUnit};
use surfcap_smg::loop_exclusion::LoopRule;
use surfcap_synthesis::smg_query::{SimilarityCache, SmgAnimation, SmgGraph, SmgGraphRequest, SmgQuery};
use surfcap_synthesis::{Animation, Output, Tolerances};

use crate::arrays;
use crate::errors::{IntoPyResult, anyhow_to_py};
use crate::progress::PyProgress;
use crate::subject::{CacheChoice, PySubject};

/// A frame set: named sequences of frames, each frame its own mesh, with frame rate, up axis
/// and units.
#[pyclass(frozen, name = "FrameSet", module = "surfcap")]
pub struct PyFrameSet {
    set: Arc<FrameSet>,
    cache: CacheChoice,
}

impl PyFrameSet {
    pub fn new(set: FrameSet, cache: CacheChoice) -> Self {
        PyFrameSet { set: Arc::new(set), cache }
    }

    pub fn frame_set(&self) -> &FrameSet {
        &self.set
    }

    fn frame_of(&self, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
        let n = self.set.frame_count();
        if let Ok(g) = frame.extract::<i64>() {
            if g < 0 || g as usize >= n {
                return Err(PyIndexError::new_err(format!("frame {g}: the frame set has frames 0 to {}", n - 1)));
            }
            return Ok(g as usize);
        }
        let spec: String = frame
            .extract()
            .map_err(|_| PyTypeError::new_err("a frame is an int (global index) or a str \"sequence:frame\""))?;
        self.set.resolve_frame(&spec).py_err()
    }
}

/// A read-only view of `values` (owned by `owner`) with `shape`.
fn view<'py, T: numpy::Element>(
    owner: &Bound<'py, PyAny>,
    values: &[T],
    shape: (usize, usize),
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let v = ndarray::ArrayView2::from_shape(shape, values).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // SAFETY: the numbers belong to the frame set held (behind an `Arc` that is never changed)
    // by `owner`, which becomes the array's base and so lives as long as the view.
    let arr = unsafe { PyArray2::borrow_from_array(&v, owner.clone()) };
    arr.call_method1("setflags", (false,))?;
    Ok(arr)
}

#[pymethods]
impl PyFrameSet {
    /// Opens a frame set: a `.frames` folder (`surfcap remesh-frames`, `surfcap smg query -o
    /// x.frames`) or any source the command line reads as one (frames of different meshes).
    /// A source whose frames share one mesh is a subject: open it with `Subject.load`.
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
        let opts = crate::subject::import_options(None, fps, up_axis, units)?;
        let progress = PyProgress::new();
        let data = py.detach(|| surfcap_formats::import::open_any(&path, &opts, &progress)).py_err()?;
        drop(progress);
        match data {
            ImportedData::FrameSet(f) => {
                crate::progress::log_notes(py, &f.notes)?;
                Ok(PyFrameSet::new(f.frame_set, CacheChoice::new(cache_dir, cache, refresh)))
            }
            ImportedData::Subject(_) => Err(PyValueError::new_err(format!(
                "path: {} reads as a subject (every frame on one mesh): open it with Subject.load",
                path.display()
            ))),
        }
    }

    /// A frame set from arrays: `positions` a list of `(V_i, 3)` float arrays and `faces` a
    /// list of `(T_i, 3)` integer arrays, one per frame. `sequences` splits the frames into
    /// named sequences: a list of `(name, frames)` pairs (default: one sequence named `name`).
    #[staticmethod]
    #[pyo3(signature = (positions, faces, *, fps=30.0, name="frames".to_string(), sequences=None, up_axis="+y", units="m", cache_dir=None, cache=true, refresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays(
        positions: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        fps: f64,
        name: String,
        sequences: Option<Vec<(String, usize)>>,
        up_axis: &str,
        units: &str,
        cache_dir: Option<PathBuf>,
        cache: bool,
        refresh: bool,
    ) -> PyResult<Self> {
        let positions: Vec<Bound<'_, PyAny>> =
            positions.extract().map_err(|_| PyTypeError::new_err("positions: expected a list of (V, 3) arrays"))?;
        let faces: Vec<Bound<'_, PyAny>> =
            faces.extract().map_err(|_| PyTypeError::new_err("faces: expected a list of (T, 3) arrays"))?;
        if positions.len() != faces.len() {
            return Err(PyValueError::new_err(format!(
                "faces: {} arrays for {} frames of positions: expected one per frame",
                faces.len(),
                positions.len()
            )));
        }
        let mut frames = Vec::with_capacity(positions.len());
        for (f, (p, t)) in positions.iter().zip(&faces).enumerate() {
            let (a, n, nv) = arrays::positions(p, &format!("positions[{f}]"), false)?;
            if n != 1 || a.shape.len() != 2 {
                return Err(PyValueError::new_err(format!(
                    "positions[{f}]: shape {:?}, expected (vertices, 3)",
                    a.shape
                )));
            }
            let tris = arrays::faces(t, &format!("faces[{f}]"), nv)?;
            let topology = Topology::new(nv, tris, None).py_err()?;
            frames.push((topology, a.buffer.as_slice().to_vec()));
        }
        let n_frames = frames.len();
        let split = sequences.unwrap_or_else(|| vec![(name.clone(), n_frames)]);
        let total: usize = split.iter().map(|(_, n)| n).sum();
        if total != n_frames {
            return Err(PyValueError::new_err(format!(
                "sequences: {total} frames in all, but positions hold {n_frames}"
            )));
        }
        let mut rest = frames.into_iter();
        let mut seqs = Vec::with_capacity(split.len());
        for (seq_name, n) in split {
            let part: Vec<_> = rest.by_ref().take(n).collect();
            seqs.push(FrameSetSequence::from_frames(seq_name, part).py_err()?);
        }
        let up = UpAxis::parse(up_axis).py_err()?;
        let set = FrameSet::new(name, seqs, fps, up, Units::parse(units)).py_err()?;
        Ok(PyFrameSet::new(set, CacheChoice::new(cache_dir, cache, refresh)))
    }

    #[getter]
    fn name(&self) -> String {
        self.set.name.clone()
    }

    #[getter]
    fn fps(&self) -> f64 {
        self.set.fps
    }

    /// The up axis: `"+x"`, `"+y"`, `"+z"`, `"-x"`, `"-y"` or `"-z"`.
    #[getter]
    fn up_axis(&self) -> &'static str {
        self.set.up_axis.as_str()
    }

    /// The length unit's name.
    #[getter]
    fn units(&self) -> String {
        self.set.units.name.clone()
    }

    #[getter]
    fn n_frames(&self) -> usize {
        self.set.frame_count()
    }

    fn __len__(&self) -> usize {
        self.set.frame_count()
    }

    /// The sequence names, in order.
    #[getter]
    fn sequences(&self) -> Vec<String> {
        self.set.sequences().iter().map(|s| s.name.clone()).collect()
    }

    /// `{sequence name: frame count}`, in order.
    #[getter]
    fn sequence_frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for s in self.set.sequences() {
            d.set_item(&s.name, s.n_frames())?;
        }
        Ok(d)
    }

    /// The vertex count of every frame, in global frame order.
    #[getter]
    fn vertex_counts(&self) -> Vec<usize> {
        self.set.sequences().iter().flat_map(|s| s.frames().iter().map(|f| f.n_vertices())).collect()
    }

    /// One frame: its positions `(V_i, 3)` float32 and triangles `(T_i, 3)` uint32, read-only
    /// views; `frame` is a global index or `"sequence:frame"`.
    fn frame<'py>(slf: Bound<'py, Self>, frame: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyTuple>> {
        let me = slf.get();
        let g = me.frame_of(frame)?;
        let f = me.set.frame(g).ok_or_else(|| PyIndexError::new_err(format!("frame {g}")))?;
        let owner = slf.clone().into_any();
        let p = view(&owner, f.positions(), (f.n_vertices(), 3))?;
        let tris = f.topology().triangles();
        let t = view(&owner, tris.as_flattened(), (tris.len(), 3))?;
        PyTuple::new(slf.py(), [p.into_any(), t.into_any()])
    }

    /// The global index of a frame given as `"sequence:frame"` (or a global index).
    fn resolve_frame(&self, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
        self.frame_of(frame)
    }

    /// A global frame index written as `"sequence:frame"`.
    fn frame_name(&self, frame: usize) -> PyResult<String> {
        if frame >= self.set.frame_count() {
            return Err(PyIndexError::new_err(format!(
                "frame {frame}: the frame set has {} frames",
                self.set.frame_count()
            )));
        }
        Ok(self.set.frame_index().label(frame))
    }

    /// The cache folder of the derived products (the shape similarity), or None.
    #[getter]
    fn cache_dir(&self) -> Option<PathBuf> {
        self.cache.dir.clone()
    }

    /// Writes the frame set as the synthesis commands write one: a `.frames` folder
    /// (lossless, surfcap's own), or glb (a mesh per frame), abc or obj (`format`, default: from
    /// the extension, else glb). Nothing surfcap did not write is replaced unless `force`.
    /// Returns the paths written.
    #[pyo3(signature = (path, format=None, *, force=false))]
    fn export(&self, py: Python<'_>, path: PathBuf, format: Option<&str>, force: bool) -> PyResult<Vec<PathBuf>> {
        let format = format.map(|f| f.parse::<ExportFormat>()).transpose().py_err()?;
        let set = &*self.set;
        let progress = PyProgress::new();
        py.detach(|| -> anyhow::Result<Vec<PathBuf>> {
            let mut outs = OutputSet::new(&[]);
            surfcap_synthesis::plan_animation(&mut outs, format, &path, force)?;
            let options = ExportOptions { force, ..Default::default() };
            let w = surfcap_synthesis::write_animation(Animation::FrameSet(set), format, &path, options, &progress)?;
            outs.commit()?;
            Ok(w)
        })
        .map_err(anyhow_to_py)
    }

    fn __repr__(&self) -> String {
        let s = &self.set;
        let (lo, hi) = s.vertex_count_range();
        format!(
            "FrameSet({:?}: {} frames of {lo} to {hi} vertices at {} fps in {}, up {}; sequences {})",
            s.name,
            s.frame_count(),
            s.fps,
            s.units.name,
            s.up_axis.as_str(),
            s.sequences().iter().map(|q| format!("{} ({})", q.name, q.n_frames())).collect::<Vec<_>>().join(", ")
        )
    }
}

/// The input of a query: a subject or a frame set, its data as the command opens it, and how
/// its derived products are cached.
struct Input<'py> {
    data: ImportedData,
    cache: CacheChoice,
    subject: Option<Bound<'py, PySubject>>,
    label: String,
}

fn open_input<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Input<'py>> {
    if let Ok(s) = obj.cast::<PySubject>() {
        let me = s.get();
        let subject = me.subject().clone();
        let label = subject.name.clone();
        return Ok(Input {
            data: ImportedData::Subject(Imported { subject, notes: Vec::new(), sources: Vec::new() }),
            cache: me.cache_choice().clone(),
            subject: Some(s.clone()),
            label,
        });
    }
    if let Ok(f) = obj.cast::<PyFrameSet>() {
        let me = f.get();
        let frame_set = (*me.set).clone();
        let label = frame_set.name.clone();
        return Ok(Input {
            data: ImportedData::FrameSet(ImportedFrames {
                frame_set,
                notes: Vec::new(),
                sources: Vec::new(),
                frame_set_origin: None,
            }),
            cache: me.cache.clone(),
            subject: None,
            label,
        });
    }
    Err(PyTypeError::new_err("input: expected a Subject or a FrameSet"))
}

/// The graph request of both functions (the input named by `label` in reports).
fn request(
    label: &str,
    connect: Vec<String>,
    windows: String,
    transitions: usize,
    separation: usize,
    resolution: usize,
) -> PyResult<SmgGraphRequest> {
    if connect.is_empty() {
        return Err(PyValueError::new_err("connect: expected at least one FROM:TO sequence pair"));
    }
    if !(1..=20).contains(&transitions) {
        return Err(PyValueError::new_err(format!("transitions: {transitions}, expected 1 to 20")));
    }
    if !(8..=512).contains(&resolution) {
        return Err(PyValueError::new_err(format!("resolution: {resolution}, expected 8 to 512")));
    }
    Ok(SmgGraphRequest {
        input: PathBuf::from(label),
        connect,
        windows,
        transitions,
        separation,
        resolution,
        loops: Some(LoopRule::default()),
        loops_per_sequence: SmgGraphRequest::DEFAULT_LOOPS_PER_SEQUENCE,
    })
}

fn similarity_cache(c: &CacheChoice) -> Option<SimilarityCache> {
    c.dir.clone().map(|dir| SimilarityCache { dir, refresh: c.refresh })
}

/// `connect` as a list: a str `"A:B,C:D"` or a list of `"A:B"`.
fn connections(obj: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(s.split(',').map(|x| x.trim().to_string()).filter(|x| !x.is_empty()).collect());
    }
    obj.extract::<Vec<String>>()
        .map_err(|_| PyTypeError::new_err("connect: expected \"FROM:TO\" pairs, a str (comma-separated) or a list"))
}

fn check_non_negative(what: &str, x: f64) -> PyResult<()> {
    if !(x.is_finite() && x >= 0.0) {
        return Err(PyValueError::new_err(format!("{what}: {x}, expected a finite number >= 0")));
    }
    Ok(())
}

fn check_positive(what: &str, x: f64) -> PyResult<()> {
    if !(x.is_finite() && x > 0.0) {
        return Err(PyValueError::new_err(format!("{what}: {x}, expected a finite number > 0")));
    }
    Ok(())
}

/// `surfcap.smg_query(input, *, connect, from_, to, distance, time, ...)`: Huang et al.
/// 2009's surface motion graph query, as `surfcap smg query`. `input` is a `Subject` or a
/// `FrameSet`; returns `(animation, SmgQueryReport)`: a `Subject` (one sequence `smg`, `(F, V,
/// 3)` float32 positions) for a subject, a `FrameSet` for a frame set. `output=` writes the
/// animation and its report as the command does. A missed distance or time issues
/// `ConstraintsMissedWarning` (the report says which and why).
#[pyfunction]
#[pyo3(signature = (input, *, connect, from_, to, distance, time, windows="3-30".to_string(), transitions=1, separation=15, resolution=64, distance_weight=1.0/0.3, time_weight=0.1, paper_cost=false, min_loop=10, loop_variation_floor=1.0, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn smg_query<'py>(
    py: Python<'py>,
    input: &Bound<'py, PyAny>,
    connect: &Bound<'py, PyAny>,
    from_: String,
    to: String,
    distance: f64,
    time: f64,
    windows: String,
    transitions: usize,
    separation: usize,
    resolution: usize,
    distance_weight: f64,
    time_weight: f64,
    paper_cost: bool,
    min_loop: usize,
    loop_variation_floor: f64,
    tolerance: Option<f64>,
    frame_tolerance: Option<usize>,
    output: Option<PathBuf>,
    format: Option<&str>,
    force: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    check_non_negative("distance", distance)?;
    check_positive("time", time)?;
    check_positive("distance_weight", distance_weight)?;
    check_positive("time_weight", time_weight)?;
    check_non_negative("loop_variation_floor", loop_variation_floor)?;
    if let Some(t) = tolerance {
        check_non_negative("tolerance", t)?;
    }
    let format = format.map(|f| f.parse::<ExportFormat>()).transpose().py_err()?;
    if format.is_some() && output.is_none() {
        return Err(PyValueError::new_err("format: given without output"));
    }
    let inp = open_input(input)?;
    let mut req = request(&inp.label, connections(connect)?, windows, transitions, separation, resolution)?;
    let loops = LoopRule { min_frames: min_loop, variation_floor: loop_variation_floor };
    req.loops = Some(loops);
    let q = SmgQuery {
        from: from_.clone(),
        to: to.clone(),
        distance,
        time: TimeSpec { value: time, unit: Some(TimeUnit::Seconds) },
        distance_weight,
        time_weight,
        paper_cost,
        loops,
    };
    let tolerances = Tolerances { distance: tolerance, frames: frame_tolerance };
    let cache = similarity_cache(&inp.cache);
    let progress = PyProgress::new();
    let (animation, report, constraints) = py
        .detach(|| -> anyhow::Result<_> {
            let mut outs = OutputSet::new(&[]);
            if let Some(o) = &output {
                surfcap_synthesis::plan_animation_and_report(&mut outs, format, o, force)?;
            }
            let keys = [("--from", from_.as_str()), ("--to", to.as_str())];
            let g = SmgGraph::from_data(inp.data, &req, cache.as_ref(), &keys, &progress)?;
            Ok(match &output {
                Some(o) => {
                    let out = Output { path: Some(o.clone()), format, force, tolerances };
                    let done = g.query(&req, &q, &out, &progress)?;
                    outs.commit()?;
                    (done.animation, done.report, done.constraints)
                }
                None => {
                    let p = g.play(&req, &q, &tolerances)?;
                    (p.animation, p.report, p.constraints)
                }
            })
        })
        .map_err(anyhow_to_py)?;
    drop(progress);
    let report = crate::reports::report(py, "SmgQueryReport", &report)?;
    let missed: Vec<String> = constraints.iter().filter(|c| c.missed).map(|c| c.missed_text()).collect();
    if !missed.is_empty() {
        crate::errors::warn_missed(py, &missed.join("\n"))?;
    }
    let animation = match animation {
        SmgAnimation::Subject(s) => {
            let parent = inp.subject.as_ref().expect("a subject's query plays a subject");
            Bound::new(py, parent.get().derived(s))?.into_any()
        }
        SmgAnimation::FrameSet(f) => Bound::new(py, PyFrameSet::new(f, inp.cache))?.into_any(),
    };
    Ok((animation, report))
}

/// `surfcap.smg_build(input, *, connect, keys=(), ...)`: the precomputation of `surfcap smg
/// build`. Returns `(similarity, SmgGraphReport)`: the shape similarity of every frame pair
/// (Huang et al. eq. 2), `(F, F)` float64, the matrix the command caches as
/// `smg-similarity-*.npy` (read from the input's cache folder when there), and the graph built
/// with the key frames `keys` (`"sequence:frame"`). `output=` writes the report as the
/// command's JSON (replacing the file, as the command does).
#[pyfunction]
#[pyo3(signature = (input, *, connect, keys=Vec::new(), windows="3-30".to_string(), transitions=1, separation=15, resolution=64, output=None))]
#[allow(clippy::too_many_arguments)]
pub fn smg_build<'py>(
    py: Python<'py>,
    input: &Bound<'py, PyAny>,
    connect: &Bound<'py, PyAny>,
    keys: Vec<String>,
    windows: String,
    transitions: usize,
    separation: usize,
    resolution: usize,
    output: Option<PathBuf>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let inp = open_input(input)?;
    let req = request(&inp.label, connections(connect)?, windows, transitions, separation, resolution)?;
    let cache = similarity_cache(&inp.cache);
    let progress = PyProgress::new();
    let (similarity, n, report) = py
        .detach(|| -> anyhow::Result<_> {
            let keys: Vec<(&str, &str)> = keys.iter().map(|k| ("--keys", k.as_str())).collect();
            let g = SmgGraph::from_data(inp.data, &req, cache.as_ref(), &keys, &progress)?;
            let report = g.report(&req);
            if let Some(o) = &output {
                surfcap_mesh::atomic::write_file(o, |w| {
                    serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)?;
                    w.write_all(b"\n")
                })?;
            }
            let n = g.frames.n_frames();
            Ok((g.similarity, n, report))
        })
        .map_err(anyhow_to_py)?;
    drop(progress);
    let m = arrays::matrix(py, similarity, &[n, n])?;
    let report = crate::reports::report(py, "SmgGraphReport", &report)?;
    Ok((m.into_any(), report))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyFrameSet>()?;
    m.add_function(wrap_pyfunction!(smg_query, m)?)?;
    m.add_function(wrap_pyfunction!(smg_build, m)?)?;
    Ok(())
}
