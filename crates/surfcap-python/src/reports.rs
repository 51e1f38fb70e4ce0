//! Reports as Python objects: the JSON a command writes beside its output (serde, the same
//! struct) read into the report class of `surfcap.reports` named `kind` (attribute access to
//! the fields, `.to_dict()`, `.to_json()`), or its base `Report` when there is no such class.

use pyo3::prelude::*;
use serde::Serialize;

/// `value` as an instance of `surfcap.reports.<kind>`.
pub fn report<'py>(py: Python<'py>, kind: &str, value: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("report {kind}: {e}")))?;
    from_json(py, kind, &text)
}

/// A JSON text as an instance of `surfcap.reports.<kind>`.
pub fn from_json<'py>(py: Python<'py>, kind: &str, text: &str) -> PyResult<Bound<'py, PyAny>> {
    let dict = py.import("json")?.call_method1("loads", (text,))?;
    let reports = py.import("surfcap.reports")?;
    let class = reports.getattr(kind).or_else(|_| reports.getattr("Report"))?;
    class.call1((dict,))
}
