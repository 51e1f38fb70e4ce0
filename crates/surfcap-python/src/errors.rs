//! Errors as Python exceptions: `surfcap.SurfcapError` carries the command line's message (the
//! file, line or frame at fault and what was expected) as its text, and the chain of causes the
//! command line prints as `caused by:` lines in `.causes`. Wrong arguments (a bad shape, dtype or
//! option value) are `ValueError` or `TypeError` naming the argument.
//!
//! A synthesis that misses a constraint is not an error here (the command line exits 3): the
//! report says which constraint was missed and why, and `surfcap.ConstraintsMissedWarning` is
//! issued so that a notebook shows it.

use pyo3::exceptions::{PyException, PyUserWarning};
use pyo3::prelude::*;
use pyo3::types::PyList;

pyo3::create_exception!(
    surfcap,
    SurfcapError,
    PyException,
    "A surfcap error: the message names the file, line or frame at fault and what was expected; `causes` holds the chain of lower-level causes."
);
pyo3::create_exception!(
    surfcap,
    ConstraintsMissedWarning,
    PyUserWarning,
    "A synthesis missed one of its constraints: the report says which, by how much, and why when the data cannot meet it."
);

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SurfcapError", py.get_type::<SurfcapError>())?;
    m.add("ConstraintsMissedWarning", py.get_type::<ConstraintsMissedWarning>())?;
    Ok(())
}

/// The messages of an error and its causes, as the command line prints them: a cause whose
/// text the previous message already contains is left out.
pub fn messages(e: &(dyn std::error::Error + 'static)) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut next: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(c) = next {
        let m = c.to_string();
        if out.last().is_none_or(|prev| !prev.contains(&m)) {
            out.push(m);
        }
        next = c.source();
    }
    out
}

/// A `SurfcapError` from a list of messages (the first is the error, the rest its causes).
pub fn from_messages(mut m: Vec<String>) -> PyErr {
    if m.is_empty() {
        m.push("unknown error".into());
    }
    let first = m.remove(0);
    Python::attach(|py| {
        let err = SurfcapError::new_err(first);
        if let Ok(list) = PyList::new(py, &m) {
            let _ = err.value(py).setattr("causes", list);
        }
        err
    })
}

/// Any surfcap library error as a `SurfcapError`.
pub fn to_py(e: impl std::error::Error + 'static) -> PyErr {
    from_messages(messages(&e))
}

/// An `anyhow` error (with its context chain) as a `SurfcapError`.
pub fn anyhow_to_py(e: anyhow::Error) -> PyErr {
    let mut out: Vec<String> = Vec::new();
    for m in e.chain().map(|c| c.to_string()) {
        if out.last().is_none_or(|prev| !prev.contains(&m)) {
            out.push(m);
        }
    }
    from_messages(out)
}

/// `result.map_err(to_py)` as a method: `lib_call().py_err()?`.
pub trait IntoPyResult<T> {
    fn py_err(self) -> PyResult<T>;
}

impl<T, E: std::error::Error + 'static> IntoPyResult<T> for Result<T, E> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// Issues `ConstraintsMissedWarning` with `text` (the command line's "missed" lines).
pub fn warn_missed(py: Python<'_>, text: &str) -> PyResult<()> {
    let category = py.get_type::<ConstraintsMissedWarning>();
    let c = std::ffi::CString::new(text.replace('\0', " ")).unwrap_or_default();
    PyErr::warn(py, &category, &c, 1)
}
