//! Graphs over the frames (thesis 3.3-3.4): `surfcap.graph(subject, ...)` builds (or reads from
//! the subject's cache, under the command line's keys) the essential, sparse essential or
//! motion graph as `surfcap graph build` does, and returns its edges as arrays with the numbers
//! of `graph.json`; `output=` writes the command's folder.
//!
//! The graph options (`kind`, `k`, `alpha`, `slope`, `l_min`, `l_max`) are read here once
//! ([`graph_options`]) for every binding that builds a graph (the synthesis bindings too).

use std::path::PathBuf;
use std::time::Instant;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfcap_motion::dtw::Slope;
use surfcap_motion::edge_weights::Alpha;
use surfcap_pipeline::{GraphKind, GraphOptions, GraphParams, GraphSummary, edge_arrays, write_graph};

use crate::arrays;
use crate::errors::IntoPyResult;
use crate::subject::PySubject;

/// `slope`: a whole number >= 1, or `"inf"` / `math.inf` for no slope constraint; not given:
/// 3, the command line's default.
pub fn slope_arg(slope: Option<&Bound<'_, PyAny>>) -> PyResult<Slope> {
    let Some(slope) = slope else { return Ok(Some(3)) };
    let bad = || PyValueError::new_err(format!("slope {slope}: expected a whole number >= 1 or inf"));
    if let Ok(text) = slope.extract::<String>() {
        return match text.as_str() {
            "inf" | "infinity" => Ok(None),
            _ => Err(bad()),
        };
    }
    if let Ok(p) = slope.extract::<i64>() {
        return if p >= 1 { Ok(Some(p as usize)) } else { Err(bad()) };
    }
    match slope.extract::<f64>() {
        Ok(x) if x == f64::INFINITY => Ok(None),
        Ok(_) => Err(bad()),
        Err(_) => Err(PyTypeError::new_err("slope: expected an int >= 1 or \"inf\"")),
    }
}

/// A whole number >= 1 given for `name`, when given.
fn count_arg(value: Option<i64>, name: &str) -> PyResult<Option<usize>> {
    match value {
        Some(v) if v < 1 => Err(PyValueError::new_err(format!("{name} {v}: expected a whole number >= 1"))),
        v => Ok(v.map(|v| v as usize)),
    }
}

/// The graph options as the command line's `GraphOpts` reads them.
pub fn graph_options(
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'_, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
) -> PyResult<GraphOptions> {
    let kind: GraphKind = kind.parse().map_err(|e: surfcap_pipeline::Error| PyValueError::new_err(e.to_string()))?;
    let alpha = Alpha::new(alpha).map_err(|e| PyValueError::new_err(format!("alpha: {e}")))?;
    Ok(GraphOptions {
        kind,
        k: count_arg(k, "k")?,
        alpha,
        slope: slope_arg(slope)?,
        l_min: count_arg(l_min, "l_min")?,
        l_max: count_arg(l_max, "l_max")?,
    })
}

/// The graph's parameters for a subject (segment bounds from its clips unless given).
pub fn graph_params(subject: &PySubject, options: &GraphOptions) -> PyResult<GraphParams> {
    options.params_for(subject.pipe()).py_err()
}

/// The graph over the subject's frames, as `surfcap graph build` builds it.
///
/// Returns a dict: ``edges`` (E, 2) uint32 (from, to frame, global indices, sorted), ``weights``
/// (E,) float64, and the numbers of ``graph.json`` (``subject``, ``kind``, ``alpha``, ``nodes``,
/// ``frames_in_graph``, ``original_edges``, ``transition_edges``, ``density``, ``l_min``,
/// ``l_max``, ``slope`` (None: no constraint), ``seconds``, ``cached``). With ``output``, writes
/// the command's folder (``edges.npy``, ``weights.npy``, ``graph.json``); a folder surfcap did
/// not write is replaced only with ``force=True``.
#[pyfunction]
#[pyo3(signature = (subject, *, kind="essential", k=None, alpha=0.05, slope=None, l_min=None, l_max=None, output=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn graph<'py>(
    py: Python<'py>,
    subject: &Bound<'py, PySubject>,
    kind: &str,
    k: Option<i64>,
    alpha: f64,
    slope: Option<&Bound<'py, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
    output: Option<PathBuf>,
    force: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let subject = subject.get();
    let options = graph_options(kind, k, alpha, slope, l_min, l_max)?;
    let params = graph_params(subject, &options)?;
    let pipe = subject.pipe().clone();
    let (summary, ends, weights) = py
        .detach(|| -> anyhow::Result<_> {
            // Planned first, as the command does: nothing is left half-written.
            let mut outs = surfcap_mesh::output_set::OutputSet::new(&[]);
            let dir = match &output {
                Some(dir) => {
                    outs.dir(dir, "graph", force)?;
                    Some(surfcap_mesh::output_path::claim_dir(dir, "graph", force)?)
                }
                None => None,
            };
            let t0 = Instant::now();
            let fetched = pipe.graph(&params)?;
            let secs = t0.elapsed().as_secs_f64();
            let g = &fetched.value;
            let summary = GraphSummary::of(g, pipe.subject(), &params, secs, fetched.from_cache);
            if let Some(dir) = &dir {
                write_graph(dir, g, &summary)?;
                outs.commit()?;
            }
            let (ends, weights) = edge_arrays(g);
            Ok((summary, ends, weights))
        })
        .map_err(crate::errors::anyhow_to_py)?;
    let text = serde_json::to_string(&summary).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let fields = py.import("json")?.call_method1("loads", (text,))?;
    let fields = fields.cast_into::<PyDict>()?;
    let out = PyDict::new(py);
    let n = weights.len();
    out.set_item("edges", arrays::matrix(py, ends, &[n, 2])?)?;
    out.set_item("weights", arrays::vector(py, weights))?;
    for (key, value) in fields.iter() {
        let name: String = key.extract()?;
        // `edges` is the array above (its length the count); `files` names what `output` holds.
        if name != "edges" && name != "files" {
            out.set_item(key, value)?;
        }
    }
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(graph, m)?)
}
