//! Path, key-pose and reach synthesis (thesis 3.5, Huang et al. 2009's reach), as `surfcap synth
//! path | keyposes | reach`: `surfcap.prepare(subject, ...)` reads or builds the graph and the
//! walk model once (a [`Synthesizer`](PySynthesizer) sharing the subject's pipeline and cache)
//! and answers any number of queries; `synth_path`, `synth_keyposes` and `synth_reach` are the
//! one-call forms, which check the request before preparing anything, as the commands do.
//!
//! Each query returns `(Subject, report)`: the animation (one sequence, named after the query)
//! and the report the command writes beside it (`PathReport`, `KeyposesReport`, `ReachReport`).
//! Nothing is written unless `output=` is given; then the animation and its report are written
//! as the command writes them (planned first, all or nothing). A missed constraint is not an
//! error: the report says it and `ConstraintsMissedWarning` is issued.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use serde::Serialize;
use surfcap_formats::export::ExportFormat;
use surfcap_mesh::Subject;
use surfcap_mesh::output_set::OutputSet;
use surfcap_pipeline::constraint_files::{KeyPose, TimeSpec, TimeUnit, key_poses_from_rows, read_key_poses};
use surfcap_pipeline::{GraphParams, Pipeline};
use surfcap_synthesis::{
    Constraint, CurveSource, Output, PathRequest, Playback, Prepared, ReachRequest, SizeLimits, Tolerances,
    check_key_poses, plan_animation_and_report,
};

use crate::errors::{IntoPyResult, anyhow_to_py, warn_missed};
use crate::graphs::{graph_options, graph_params};
use crate::progress::PyProgress;
use crate::reports;
use crate::subject::PySubject;

/// Where the animation goes (`output`, `format`, `force`) and when its constraints count as
/// missed (`tolerance`, `frame_tolerance`), checked as the command line checks its options.
fn output(
    output: Option<PathBuf>,
    format: Option<&str>,
    force: bool,
    tolerance: Option<f64>,
    frame_tolerance: Option<i64>,
) -> PyResult<Output> {
    if let Some(t) = tolerance
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(PyValueError::new_err(format!("tolerance {t}: expected a finite number >= 0")));
    }
    if let Some(f) = frame_tolerance
        && f < 0
    {
        return Err(PyValueError::new_err(format!("frame_tolerance {f}: expected a whole number >= 0")));
    }
    let format = format.map(|f| f.parse::<ExportFormat>()).transpose().py_err()?;
    if format.is_some() && output.is_none() {
        return Err(PyValueError::new_err("format: only with output (nothing is written without one)"));
    }
    let tolerances = Tolerances { distance: tolerance, frames: frame_tolerance.map(|f| f as usize) };
    Ok(Output { path: output, format, force, tolerances })
}

/// Runs `work` with the output planned before it and committed after it, as the command does
/// (`inputs` may not be overwritten); without an output path, just runs it.
fn with_output<T>(
    out: &Output,
    inputs: &[&Path],
    work: impl FnOnce() -> surfcap_synthesis::Result<T>,
) -> anyhow::Result<T> {
    let Some(path) = &out.path else { return Ok(work()?) };
    let mut set = OutputSet::new(inputs);
    plan_animation_and_report(&mut set, out.format, path, out.force)?;
    let value = work()?;
    set.commit()?;
    Ok(value)
}

/// The animation as a `Subject` (cached like `subject`) and the report as `surfcap.reports.<kind>`,
/// with `ConstraintsMissedWarning` for each missed constraint.
fn finish<'py>(
    py: Python<'py>,
    subject: &PySubject,
    animation: Subject,
    kind: &str,
    report: &impl Serialize,
    constraints: &[Constraint],
) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
    let report = reports::report(py, kind, report)?;
    let missed: Vec<String> = constraints
        .iter()
        .filter(|c| c.missed)
        .map(|c| format!("{}; tolerance= and frame_tolerance= set it)", c.missed_text()))
        .collect();
    if !missed.is_empty() {
        warn_missed(py, &missed.join("\n"))?;
    }
    Ok((subject.derived(animation), report))
}

/// A frame given as an int (global index) or `"sequence:frame"`, as the command line's text.
fn frame_text(frame: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    if let Ok(g) = frame.extract::<i64>() {
        return Ok(g.to_string());
    }
    frame.extract::<String>().map_err(|_| {
        PyTypeError::new_err(format!("{what}: a frame is an int (global index) or a str \"sequence:frame\""))
    })
}

/// `curve`: a CSV file (str or path) or an (N, 2) / (N, 3) array of numbers; the file, if one.
fn curve_source(curve: &Bound<'_, PyAny>) -> PyResult<(CurveSource, Option<PathBuf>)> {
    if let Ok(file) = curve.extract::<PathBuf>() {
        return Ok((CurveSource::File(file.clone()), Some(file)));
    }
    let not_numbers = |e: PyErr| {
        PyTypeError::new_err(format!("curve: expected a CSV file or an (N, 2) or (N, 3) array of numbers: {e}"))
    };
    let a = curve.py().import("numpy")?.call_method1("asarray", (curve, "float64")).map_err(not_numbers)?;
    let a = a.cast::<PyArrayDyn<f64>>().map_err(|e| not_numbers(e.into()))?;
    let columns = match a.shape() {
        [_, c @ (2 | 3)] => *c,
        s => {
            return Err(PyValueError::new_err(format!(
                "curve: shape {s:?}, expected (points, 2) for the ground plane or (points, 3)"
            )));
        }
    };
    let ro = a.try_readonly().map_err(|e| PyValueError::new_err(format!("curve: {e}")))?;
    let values: Vec<f64> = ro.as_array().iter().copied().collect();
    Ok((CurveSource::Points { name: "curve".into(), columns, values }, None))
}

/// `tags`: a list of `TAG:FROM-TO`, or one string of them separated by commas (as `--tags`).
fn tag_list(tags: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(tags) = tags else { return Ok(Vec::new()) };
    if let Ok(text) = tags.extract::<String>() {
        return Ok(text.split(',').map(str::to_string).collect());
    }
    tags.extract::<Vec<String>>()
        .map_err(|_| PyTypeError::new_err("tags: expected a list of \"TAG:FROM-TO\" strings, e.g. [\"run:5-9\"]"))
}

/// The path request of the keywords, checked as `synth path`'s options are.
#[allow(clippy::too_many_arguments)]
fn path_request(
    curve: &Bound<'_, PyAny>,
    planar: bool,
    tags: Option<&Bound<'_, PyAny>>,
    start: Option<&Bound<'_, PyAny>>,
    track: Vec<usize>,
    window: Option<f64>,
    max_transitions: Option<usize>,
    branching: i64,
) -> PyResult<(PathRequest, Option<PathBuf>)> {
    if let Some(w) = window
        && !(w.is_finite() && w > 0.0)
    {
        return Err(PyValueError::new_err(format!("window {w}: expected a finite number > 0")));
    }
    if branching < 1 {
        return Err(PyValueError::new_err(format!("branching {branching}: expected a whole number >= 1")));
    }
    let (curve, file) = curve_source(curve)?;
    let request = PathRequest {
        curve,
        planar,
        tags: tag_list(tags)?,
        start: start.map(|s| frame_text(s, "start")).transpose()?,
        track,
        window,
        max_transitions,
        branching: branching as usize,
    };
    Ok((request, file))
}

/// Key poses: a file as `--keys` reads it, or a list of `(frame, time)` pairs: the frame an int
/// or `"sequence:frame"`, the time a number of seconds or a str as in the file (`"90"` or
/// `"90f"`: output frame, `"3s"`: seconds). The file, if one, and how messages name the keys.
fn key_poses(keys: &Bound<'_, PyAny>, s: &Subject) -> PyResult<(Vec<KeyPose>, Option<PathBuf>, String)> {
    if let Ok(file) = keys.extract::<PathBuf>() {
        let k = read_key_poses(&file, s).py_err()?;
        let name = file.display().to_string();
        return Ok((k, Some(file), name));
    }
    let pairs: Vec<(Bound<'_, PyAny>, Bound<'_, PyAny>)> = keys.extract().map_err(|_| {
        PyTypeError::new_err(
            "keys: expected a key file or a list of (frame, time) pairs, e.g. [(\"walk:0\", 0), (\"walk:40\", 2.5)]",
        )
    })?;
    let mut rows = Vec::with_capacity(pairs.len());
    for (k, (frame, time)) in pairs.iter().enumerate() {
        let time = if let Ok(text) = time.extract::<String>() {
            text
        } else if let Ok(x) = time.extract::<f64>() {
            format!("{x}s")
        } else {
            return Err(PyTypeError::new_err(format!(
                "keys[{k}]: the time is seconds (a number) or a str such as \"90f\" or \"3s\""
            )));
        };
        rows.push((k + 1, vec![frame_text(frame, &format!("keys[{k}]"))?, time]));
    }
    let k = key_poses_from_rows(rows, Path::new("keys"), s).py_err()?;
    Ok((k, None, "keys".into()))
}

/// The reach request of the keywords, checked as `synth reach`'s options are.
fn reach_request(
    from: &Bound<'_, PyAny>,
    to: &Bound<'_, PyAny>,
    distance: f64,
    time: &Bound<'_, PyAny>,
    distance_scale: f64,
    time_scale: f64,
) -> PyResult<ReachRequest> {
    if !(distance.is_finite() && distance >= 0.0) {
        return Err(PyValueError::new_err(format!("distance {distance}: expected a finite number >= 0")));
    }
    for (name, x) in [("distance_scale", distance_scale), ("time_scale", time_scale)] {
        if !(x.is_finite() && x > 0.0) {
            return Err(PyValueError::new_err(format!("{name} {x}: expected a finite number > 0")));
        }
    }
    let spec = if let Ok(text) = time.extract::<String>() {
        text.parse::<TimeSpec>().ok()
    } else {
        time.extract::<f64>().ok().map(|x| TimeSpec { value: x, unit: Some(TimeUnit::Seconds) })
    };
    let time = match spec {
        Some(t) if t.value.is_finite() && t.value > 0.0 => t,
        _ => {
            return Err(PyValueError::new_err(format!(
                "time {time}: expected a duration > 0 in seconds (3 or \"3s\") or frames (\"90f\")"
            )));
        }
    };
    Ok(ReachRequest {
        from: frame_text(from, "from_")?,
        to: frame_text(to, "to")?,
        distance,
        time,
        distance_scale,
        time_scale,
    })
}

/// The graph parameters of the keywords for `subject`.
fn params_of(
    subject: &PySubject,
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'_, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
) -> PyResult<GraphParams> {
    graph_params(subject, &graph_options(kind, k, alpha, slope, l_min, l_max)?)
}

/// A subject prepared for synthesis: its graph and walk model, built (or read from the
/// subject's cache) once by `surfcap.prepare`, answering `path`, `keyposes` and `reach`.
#[pyclass(frozen, name = "Synthesizer", module = "surfcap")]
pub struct PySynthesizer {
    prep: Prepared,
    subject: Py<PySubject>,
}

impl PySynthesizer {
    fn pipe(&self) -> &Arc<Pipeline> {
        &self.prep.pipe
    }
}

#[pymethods]
impl PySynthesizer {
    /// The subject this was prepared from.
    #[getter]
    fn subject(&self, py: Python<'_>) -> Py<PySubject> {
        self.subject.clone_ref(py)
    }

    /// The graph's kind (``"essential"``, ``"sparse-essential:K"``, ``"motion"``).
    #[getter]
    fn kind(&self) -> String {
        self.prep.params.kind.to_string()
    }

    /// Edges of the graph the walks are searched in.
    #[getter]
    fn n_edges(&self) -> usize {
        self.prep.graph.edges().len()
    }

    /// Transitions of the walk model.
    #[getter]
    fn n_transitions(&self) -> usize {
        self.prep.model.n_transitions()
    }

    /// Seconds taken to read or build the graph and the walk model.
    #[getter]
    fn prepare_seconds(&self) -> f64 {
        self.prep.seconds
    }

    /// Starts a live session of the interactive controller on this subject (`surfcap play`'s
    /// player without the page): the moves precomputed, the captured frames coded at ``bits``
    /// (8 to 16) bits per coordinate, the blending thread started. Returns a ``LiveSession``.
    #[pyo3(signature = (*, bits=16))]
    fn live(&self, py: Python<'_>, bits: u32) -> PyResult<crate::live::PyLiveSession> {
        let prep = py
            .detach(|| Prepared::new(self.prep.pipe.clone(), self.prep.params.clone(), self.prep.tracked.as_deref()))
            .py_err()?;
        crate::live::PyLiveSession::start(py, prep, bits)
    }

    /// Follows a curve with the centre of mass (or of the tracked vertices), as `surfcap synth
    /// path` (thesis 3.5.1). ``curve``: a CSV file or an (N, 3) array of x,y,z (or (N, 2): the
    /// ground plane's two axes) in the subject's units, float32 or float64. Returns
    /// ``(Subject, PathReport)``: the animation, (F, V, 3) float32 positions in one sequence
    /// ``path``, and its report.
    #[pyo3(signature = (curve, *, planar=false, tags=None, start=None, window=None, max_transitions=None, branching=8, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn path<'py>(
        &self,
        py: Python<'py>,
        curve: &Bound<'py, PyAny>,
        planar: bool,
        tags: Option<&Bound<'py, PyAny>>,
        start: Option<&Bound<'py, PyAny>>,
        window: Option<f64>,
        max_transitions: Option<usize>,
        branching: i64,
        tolerance: Option<f64>,
        frame_tolerance: Option<i64>,
        output: Option<PathBuf>,
        format: Option<&str>,
        force: bool,
    ) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
        let (request, file) = path_request(curve, planar, tags, start, Vec::new(), window, max_transitions, branching)?;
        let out = self::output(output, format, force, tolerance, frame_tolerance)?;
        let progress = PyProgress::new();
        let inputs: Vec<&Path> = file.iter().map(PathBuf::as_path).collect();
        let o = py
            .detach(|| {
                with_output(&out, &inputs, || {
                    let checked = request.check(self.pipe(), &out, &SizeLimits::default())?;
                    self.prep.follow_path(&checked.query(), &out, &progress)
                })
            })
            .map_err(anyhow_to_py)?;
        drop(progress);
        let subject = self.subject.get();
        finish(py, subject, o.played.output, "PathReport", &o.report, &o.constraints)
    }

    /// Moves key poses to new times, as `surfcap synth keyposes` (thesis 3.5.2, Fig. 3.18).
    /// ``keys``: a key file (``frame,time`` lines) or a list of ``(frame, time)`` pairs: the
    /// frame an int or ``"sequence:frame"``, the time seconds (a number) or a str as in the file
    /// (``"90"``/``"90f"`` output frame, ``"3s"`` seconds). Returns ``(Subject, KeyposesReport)``.
    #[pyo3(signature = (keys, *, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn keyposes<'py>(
        &self,
        py: Python<'py>,
        keys: &Bound<'py, PyAny>,
        tolerance: Option<f64>,
        frame_tolerance: Option<i64>,
        output: Option<PathBuf>,
        format: Option<&str>,
        force: bool,
    ) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
        let out = self::output(output, format, force, tolerance, frame_tolerance)?;
        let (keys, file, source) = key_poses(keys, self.prep.subject())?;
        let progress = PyProgress::new();
        let inputs: Vec<&Path> = file.iter().map(PathBuf::as_path).collect();
        let o = py
            .detach(|| {
                with_output(&out, &inputs, || {
                    check_key_poses(self.prep.subject(), &keys, &source, &out, &SizeLimits::default())?;
                    self.prep.time_key_poses(&keys, &out, &progress)
                })
            })
            .map_err(anyhow_to_py)?;
        drop(progress);
        finish(py, self.subject.get(), o.played.output, "KeyposesReport", &o.report, &o.constraints)
    }

    /// Goes from one frame to another covering a ground distance (subject units) in a time, as
    /// `surfcap synth reach` (Huang et al. 2009's constraint in the essential graph). ``time``:
    /// seconds (a number or ``"3s"``) or frames shown (``"90f"``). Returns ``(Subject,
    /// ReachReport)``.
    #[pyo3(signature = (from_, to, distance, time, *, distance_scale=0.3, time_scale=10.0, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn reach<'py>(
        &self,
        py: Python<'py>,
        from_: &Bound<'py, PyAny>,
        to: &Bound<'py, PyAny>,
        distance: f64,
        time: &Bound<'py, PyAny>,
        distance_scale: f64,
        time_scale: f64,
        tolerance: Option<f64>,
        frame_tolerance: Option<i64>,
        output: Option<PathBuf>,
        format: Option<&str>,
        force: bool,
    ) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
        let request = reach_request(from_, to, distance, time, distance_scale, time_scale)?;
        let out = self::output(output, format, force, tolerance, frame_tolerance)?;
        let progress = PyProgress::new();
        let o = py
            .detach(|| {
                with_output(&out, &[], || {
                    let query = request.check(self.prep.subject(), &out, &SizeLimits::default())?;
                    self.prep.reach(&query, &out, &progress)
                })
            })
            .map_err(anyhow_to_py)?;
        drop(progress);
        finish(py, self.subject.get(), o.played.output, "ReachReport", &o.report, &o.constraints)
    }

    fn __repr__(&self) -> String {
        format!(
            "Synthesizer({:?}: {} graph, {} edges, {} transitions)",
            self.prep.subject().name,
            self.prep.params.kind,
            self.prep.graph.edges().len(),
            self.prep.model.n_transitions()
        )
    }
}

/// Prepares a subject for synthesis: reads (or builds and caches, under the command line's
/// keys) its graph and walk model once. ``track``: follow the centre of these vertex ids
/// instead of the centre of mass. Returns a ``Synthesizer``.
#[pyfunction]
#[pyo3(signature = (subject, *, kind="essential", k=None, alpha=0.05, slope=None, l_min=None, l_max=None, track=None))]
#[allow(clippy::too_many_arguments)]
pub fn prepare(
    py: Python<'_>,
    subject: &Bound<'_, PySubject>,
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'_, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
    track: Option<Vec<usize>>,
) -> PyResult<PySynthesizer> {
    let s = subject.get();
    let params = params_of(s, kind, k, alpha, slope, l_min, l_max)?;
    let pipe = s.pipe().clone();
    let tracked = track.filter(|t| !t.is_empty());
    let prep = py.detach(|| Prepared::new(pipe, params, tracked.as_deref())).py_err()?;
    Ok(PySynthesizer { prep, subject: subject.clone().unbind() })
}

/// `synth_path(subject, curve, ...)`: ``prepare(subject, ...).path(curve, ...)`` in one call,
/// the request checked before the graph is built (as `surfcap synth path`). Returns
/// ``(Subject, PathReport)``.
#[pyfunction]
#[pyo3(signature = (subject, curve, *, kind="essential", k=None, alpha=0.05, slope=None, l_min=None, l_max=None, track=None, planar=false, tags=None, start=None, window=None, max_transitions=None, branching=8, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn synth_path<'py>(
    py: Python<'py>,
    subject: &Bound<'py, PySubject>,
    curve: &Bound<'py, PyAny>,
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'py, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
    track: Option<Vec<usize>>,
    planar: bool,
    tags: Option<&Bound<'py, PyAny>>,
    start: Option<&Bound<'py, PyAny>>,
    window: Option<f64>,
    max_transitions: Option<usize>,
    branching: i64,
    tolerance: Option<f64>,
    frame_tolerance: Option<i64>,
    output: Option<PathBuf>,
    format: Option<&str>,
    force: bool,
) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
    let s = subject.get();
    let params = params_of(s, kind, k, alpha, slope, l_min, l_max)?;
    let (request, file) =
        path_request(curve, planar, tags, start, track.unwrap_or_default(), window, max_transitions, branching)?;
    let out = self::output(output, format, force, tolerance, frame_tolerance)?;
    let progress = PyProgress::new();
    let inputs: Vec<&Path> = file.iter().map(PathBuf::as_path).collect();
    let pipe = s.pipe().clone();
    let o = py
        .detach(|| {
            with_output(&out, &inputs, || {
                surfcap_synthesis::synthesize_path(
                    pipe,
                    params,
                    &request,
                    Playback::default(),
                    &out,
                    &SizeLimits::default(),
                    &progress,
                )
            })
        })
        .map_err(anyhow_to_py)?;
    drop(progress);
    finish(py, s, o.played.output, "PathReport", &o.report, &o.constraints)
}

/// `synth_keyposes(subject, keys, ...)`: ``prepare(subject, ...).keyposes(keys, ...)`` in one
/// call, the keys checked before the graph is built (as `surfcap synth keyposes`). Returns
/// ``(Subject, KeyposesReport)``.
#[pyfunction]
#[pyo3(signature = (subject, keys, *, kind="essential", k=None, alpha=0.05, slope=None, l_min=None, l_max=None, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn synth_keyposes<'py>(
    py: Python<'py>,
    subject: &Bound<'py, PySubject>,
    keys: &Bound<'py, PyAny>,
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'py, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
    tolerance: Option<f64>,
    frame_tolerance: Option<i64>,
    output: Option<PathBuf>,
    format: Option<&str>,
    force: bool,
) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
    let s = subject.get();
    let params = params_of(s, kind, k, alpha, slope, l_min, l_max)?;
    let out = self::output(output, format, force, tolerance, frame_tolerance)?;
    let (keys, file, source) = key_poses(keys, s.subject())?;
    let progress = PyProgress::new();
    let inputs: Vec<&Path> = file.iter().map(PathBuf::as_path).collect();
    let pipe = s.pipe().clone();
    let o = py
        .detach(|| {
            with_output(&out, &inputs, || {
                check_key_poses(pipe.subject(), &keys, &source, &out, &SizeLimits::default())?;
                let prep = Prepared::new(pipe.clone(), params, None)?;
                prep.time_key_poses(&keys, &out, &progress)
            })
        })
        .map_err(anyhow_to_py)?;
    drop(progress);
    finish(py, s, o.played.output, "KeyposesReport", &o.report, &o.constraints)
}

/// `synth_reach(subject, from_, to, distance, time, ...)`: ``prepare(subject, ...).reach(...)``
/// in one call, the request checked before the graph is built (as `surfcap synth reach`).
/// Returns ``(Subject, ReachReport)``.
#[pyfunction]
#[pyo3(signature = (subject, from_, to, distance, time, *, kind="essential", k=None, alpha=0.05, slope=None, l_min=None, l_max=None, distance_scale=0.3, time_scale=10.0, tolerance=None, frame_tolerance=None, output=None, format=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn synth_reach<'py>(
    py: Python<'py>,
    subject: &Bound<'py, PySubject>,
    from_: &Bound<'py, PyAny>,
    to: &Bound<'py, PyAny>,
    distance: f64,
    time: &Bound<'py, PyAny>,
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'py, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
    distance_scale: f64,
    time_scale: f64,
    tolerance: Option<f64>,
    frame_tolerance: Option<i64>,
    output: Option<PathBuf>,
    format: Option<&str>,
    force: bool,
) -> PyResult<(PySubject, Bound<'py, PyAny>)> {
    let s = subject.get();
    let params = params_of(s, kind, k, alpha, slope, l_min, l_max)?;
    let request = reach_request(from_, to, distance, time, distance_scale, time_scale)?;
    let out = self::output(output, format, force, tolerance, frame_tolerance)?;
    let progress = PyProgress::new();
    let pipe = s.pipe().clone();
    let o = py
        .detach(|| {
            with_output(&out, &[], || {
                surfcap_synthesis::synthesize_reach(
                    pipe,
                    params,
                    &request,
                    Playback::default(),
                    &out,
                    &SizeLimits::default(),
                    &progress,
                )
            })
        })
        .map_err(anyhow_to_py)?;
    drop(progress);
    finish(py, s, o.played.output, "ReachReport", &o.report, &o.constraints)
}

/// Benchmark hook (`python/bench/overhead.py`): the seconds of the library work
/// `Synthesizer.path(curve)` does (the request checked, the path followed and played, in
/// memory), timed in Rust around the very calls the binding makes, without the binding's
/// conversions; the binding's overhead is its wall time minus this.
#[pyfunction]
fn _library_path_seconds(py: Python<'_>, synth: &PySynthesizer, curve: &Bound<'_, PyAny>) -> PyResult<f64> {
    let (request, _) = path_request(curve, false, None, None, Vec::new(), None, None, 8)?;
    let out = self::output(None, None, false, None, None)?;
    py.detach(|| -> anyhow::Result<f64> {
        let t0 = std::time::Instant::now();
        let checked = request.check(synth.pipe(), &out, &SizeLimits::default())?;
        let o = synth.prep.follow_path(&checked.query(), &out, &surfcap_mesh::NoProgress)?;
        let secs = t0.elapsed().as_secs_f64();
        drop(o);
        Ok(secs)
    })
    .map_err(anyhow_to_py)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_library_path_seconds, m)?)?;
    m.add_class::<PySynthesizer>()?;
    m.add_function(wrap_pyfunction!(prepare, m)?)?;
    m.add_function(wrap_pyfunction!(synth_path, m)?)?;
    m.add_function(wrap_pyfunction!(synth_keyposes, m)?)?;
    m.add_function(wrap_pyfunction!(synth_reach, m)?)
}
