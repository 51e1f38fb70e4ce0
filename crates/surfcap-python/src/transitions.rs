//! Transitions and the transition table (thesis 2.5.3-2.5.5), as `surfcap transition`,
//! `surfcap transitions` and `surfcap eval transitions` compute them.
//!
//! - `transition(subject, from_, to, *, slope, l_min, l_max)`: one optimal transition as a new
//!   `Subject` and its `TransitionReport` (`surfcap_synthesis::transition_run`, the command's
//!   function: the same frames and report).
//! - `transition_table(subject, *, slope, l_min, l_max)`: the all-pairs table from the
//!   subject's pipeline (the same cache file as `surfcap transitions`): `D`, `L`, `li`, `lj` as
//!   the command's `.npy` files, read-only views without a copy.
//! - `transition_costs(subject, *, slopes, fixed, plot_pairs, dtw_first_step)`: thesis
//!   Fig. 2.15's comparison of standard, DTW and DTW + variable-length transitions
//!   (`surfcap_eval::transition_costs_eval`, the function `surfcap eval transitions` calls),
//!   with the sampled cost and duration curves the command plots.

use std::sync::Arc;

use numpy::{Element, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::json;
use surfcap_eval::transition_costs_eval::{TransitionCostsOptions, transition_costs_eval};
use surfcap_motion::dtw::{FirstStep, Slope};
use surfcap_motion::transition_table::{TableParams, TransitionTable};
use surfcap_pipeline::Pipeline;

use crate::distances::{frame_text, pipeline_err};
use crate::errors::IntoPyResult;
use crate::subject::PySubject;

/// A slope constraint p (thesis eq. 2.53) as `--slope` takes it: a whole number >= 1, or
/// `"inf"` / `float("inf")` for none.
fn slope_of(obj: &Bound<'_, PyAny>) -> PyResult<Slope> {
    let bad = || {
        let text = obj.repr().map(|r| r.to_string()).unwrap_or_default();
        PyValueError::new_err(format!("slope: {text}: expected a whole number >= 1 or inf"))
    };
    if let Ok(p) = obj.extract::<i64>() {
        return if p >= 1 { Ok(Some(p as usize)) } else { Err(bad()) };
    }
    if let Ok(s) = obj.extract::<String>() {
        return match s.as_str() {
            "inf" | "infinity" => Ok(None),
            _ => s.parse::<usize>().ok().filter(|&p| p >= 1).map(Some).ok_or_else(bad),
        };
    }
    match obj.extract::<f64>() {
        Ok(x) if x == f64::INFINITY => Ok(None),
        _ => Err(bad()),
    }
}

/// A whole number >= 1 given for `name`, as the command line's `count` values.
fn count(name: &str, v: Option<i64>) -> PyResult<Option<usize>> {
    match v {
        Some(x) if x < 1 => Err(PyValueError::new_err(format!("{name} {x}: expected a whole number >= 1"))),
        Some(x) => Ok(Some(x as usize)),
        None => Ok(None),
    }
}

/// The table parameters of `--slope --l-min --l-max` for a pipeline's subject: segment bounds
/// default to the ones that fit its clips, as the commands' (the pipeline checks
/// `1 <= l_min <= l_max` when the table is asked for).
pub fn table_params(
    pipe: &Pipeline,
    slope: &Bound<'_, PyAny>,
    l_min: Option<i64>,
    l_max: Option<i64>,
) -> PyResult<TableParams> {
    let slope = slope_of(slope)?;
    let (l_min, l_max) = (count("l_min", l_min)?, count("l_max", l_max)?);
    let (lo, hi) = pipe.segment_bounds();
    Ok(TableParams { l_min: l_min.unwrap_or(lo), l_max: l_max.unwrap_or(hi), slope })
}

/// Holds a transition table of the pipeline for the numpy views of it.
#[pyclass(frozen, module = "surfcap._surfcap")]
pub struct TableOwner {
    table: Arc<TransitionTable>,
}

/// A read-only `(n, n)` view of one layer of the table `owner` holds.
fn layer<'py, T: Element>(
    owner: &Bound<'py, TableOwner>,
    pick: fn(&TransitionTable) -> &[T],
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let t = &owner.get().table;
    let view =
        ndarray::ArrayView2::from_shape((t.n, t.n), pick(t)).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // SAFETY: the numbers belong to the `Arc` that `owner` holds; `owner` becomes the array's
    // base, so it lives as long as the view, and nothing writes to a pipeline's table.
    let arr = unsafe { PyArray2::borrow_from_array(&view, owner.clone().into_any()) };
    arr.call_method1("setflags", (false,))?;
    Ok(arr)
}

/// One optimal transition from frame `from_` (the source segment starts there) to frame `to`
/// (the destination segment ends there), each a global index or `"sequence:frame"`, as
/// `surfcap transition --from --to` makes it: segment lengths from the transition table
/// (`slope`: p of eq. 2.53, a whole number >= 1 or "inf"; `l_min`, `l_max`: segment bounds in
/// frames, default the command's), frames blended along the DTW warp (Algorithm 2). Returns
/// `(Subject, TransitionReport)`: one sequence `<from>_to_<to>` of `duration` frames (positions
/// `(duration, V, 3)` float32) and the report `<output>.transition.json` holds.
#[pyfunction]
#[pyo3(signature = (subject, from_, to, *, slope=None, l_min=None, l_max=None))]
pub fn transition<'py>(
    py: Python<'py>,
    subject: &PySubject,
    from_: &Bound<'py, PyAny>,
    to: &Bound<'py, PyAny>,
    slope: Option<&Bound<'py, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
) -> PyResult<(Bound<'py, PySubject>, Bound<'py, PyAny>)> {
    let (i, j) = (subject.frame_of(from_)?, subject.frame_of(to)?);
    let (from_name, to_name) = (frame_text(from_)?, frame_text(to)?);
    let pipe = subject.pipe().clone();
    let p = table_params(&pipe, &default_slope(py, slope), l_min, l_max)?;
    let t = py
        .detach(|| surfcap_synthesis::transition_run::transition(&pipe, (i, &from_name), (j, &to_name), &p))
        .map_err(synthesis_err)?;
    let report = crate::reports::report(py, "TransitionReport", &t.report)?;
    Ok((Bound::new(py, subject.derived(t.animation))?, report))
}

/// The `slope` argument, 3 (the command's default) when not given.
fn default_slope<'py>(py: Python<'py>, slope: Option<&Bound<'py, PyAny>>) -> Bound<'py, PyAny> {
    match slope {
        Some(s) => s.clone(),
        None => 3i64.into_pyobject(py).expect("an int").into_any(),
    }
}

/// A synthesis error as a Python exception (a parameter out of its domain: `ValueError`).
fn synthesis_err(e: surfcap_synthesis::Error) -> PyErr {
    match e {
        surfcap_synthesis::Error::Pipeline(p) => pipeline_err(p),
        e => crate::errors::to_py(e),
    }
}

/// The all-pairs transition table (thesis 2.5.3-2.5.4) of `subject`, as `surfcap transitions
/// -o dir/` writes it (the same cache file and the same numbers): a dict of read-only `(F, F)`
/// arrays over global frames, row i the source frame, column j the destination frame:
/// `"D"` float64 normalised cost (inf where no transition fits), `"L"` uint32 duration in
/// frames, `"li"`, `"lj"` uint32 source and destination segment lengths; and the parameters
/// used, `"l_min"`, `"l_max"` (ints) and `"slope"` (int, or None for inf).
#[pyfunction]
#[pyo3(signature = (subject, *, slope=None, l_min=None, l_max=None))]
pub fn transition_table<'py>(
    py: Python<'py>,
    subject: &PySubject,
    slope: Option<&Bound<'py, PyAny>>,
    l_min: Option<i64>,
    l_max: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let pipe = subject.pipe().clone();
    let p = table_params(&pipe, &default_slope(py, slope), l_min, l_max)?;
    let table = py.detach(|| pipe.table(&p)).map_err(pipeline_err)?.value;
    let owner = Bound::new(py, TableOwner { table })?;
    let d = PyDict::new(py);
    d.set_item("D", layer(&owner, |t| &t.cost)?)?;
    d.set_item("L", layer(&owner, |t| &t.len)?)?;
    d.set_item("li", layer(&owner, |t| &t.li)?)?;
    d.set_item("lj", layer(&owner, |t| &t.lj)?)?;
    d.set_item("l_min", p.l_min)?;
    d.set_item("l_max", p.l_max)?;
    d.set_item("slope", p.slope)?;
    Ok(d)
}

/// Thesis 2.5.5, Fig. 2.15, as `surfcap eval transitions` computes it: for each slope
/// constraint in `slopes`, the mean and standard deviation of the normalised costs of standard
/// transitions (fixed length `fixed`, default one second), DTW with that length and DTW with
/// variable segment lengths (the table), over the frame pairs where all three exist; and the
/// curves the command plots. Returns a `TransitionCostsReport`: the fields of the command's
/// `transitions.json` (`rows`, ...) plus `plot` (`slope`, `sample`: up to `plot_pairs` pairs'
/// `standard`, `dtw_vls` costs and `duration`, `shown`: the warp drawn on the distance matrix);
/// `report.curves()` gives the sampled curves as numpy arrays. `dtw_first_step`: "surfcap" or
/// "literal" (eq. 2.53 read literally).
#[pyfunction]
#[pyo3(signature = (subject, *, slopes=vec![2, 3, 4, 5], fixed=None, plot_pairs=100, dtw_first_step="surfcap"))]
pub fn transition_costs<'py>(
    py: Python<'py>,
    subject: &PySubject,
    slopes: Vec<i64>,
    fixed: Option<i64>,
    plot_pairs: i64,
    dtw_first_step: &str,
) -> PyResult<Bound<'py, PyAny>> {
    if slopes.is_empty() || slopes.iter().any(|&p| p < 1) {
        return Err(PyValueError::new_err(format!("slopes {slopes:?}: expected whole numbers >= 1")));
    }
    let first_step = match dtw_first_step {
        "surfcap" => FirstStep::Straight,
        "literal" => FirstStep::Diagonal,
        s => {
            return Err(PyValueError::new_err(format!("dtw_first_step: {s:?}: expected surfcap or literal")));
        }
    };
    let opts = TransitionCostsOptions {
        slopes: slopes.iter().map(|&p| p as usize).collect(),
        fixed: count("fixed", fixed)?,
        plot_pairs: count("plot_pairs", Some(plot_pairs))?.expect("given"),
        first_step,
        normalisation: surfcap_motion::dtw::Normalisation::default(),
    };
    let pipe = subject.pipe().clone();
    let r = py.detach(|| transition_costs_eval(&pipe, &opts)).py_err()?;
    let mut value = serde_json::to_value(&r).map_err(|e| PyValueError::new_err(e.to_string()))?;
    value["plot"] = json!({ "slope": r.plot.slope, "sample": r.plot.sample, "shown": r.plot.shown });
    crate::reports::report(py, "TransitionCostsReport", &value)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<TableOwner>()?;
    m.add_function(wrap_pyfunction!(transition, m)?)?;
    m.add_function(wrap_pyfunction!(transition_table, m)?)?;
    m.add_function(wrap_pyfunction!(transition_costs, m)?)?;
    Ok(())
}
