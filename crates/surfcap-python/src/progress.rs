//! Progress of long computations, shown with `tqdm` when it is installed (silent otherwise, or
//! after `surfcap.set_progress(False)`); the library's notes (a cache entry rejected and
//! recomputed, an assumption made while reading a file) go to the `surfcap` logger at level
//! WARNING, so that they show by default as the command line shows them.
//!
//! Deadlock-free by construction: Python is only called from the thread that made the
//! progress (the caller's thread). Steps counted on worker threads (rayon) are added to an
//! atomic counter and shown at that thread's next call. Bars are redrawn at most every 0.1 s.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::ThreadId;
use std::time::{Duration, Instant};

use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfcap_mesh::Progress;

static ENABLED: AtomicBool = AtomicBool::new(true);

/// `surfcap.set_progress(enabled)`: show (default) or hide progress bars.
#[pyfunction]
pub fn set_progress(enabled: bool) {
    ENABLED.store(enabled, Ordering::Relaxed);
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(set_progress, m)?)
}

struct Bar {
    bar: Option<Py<PyAny>>,
    shown: u64,
    drawn_at: Instant,
}

/// A [`Progress`] that drives tqdm bars from the thread that made it.
pub struct PyProgress {
    owner: ThreadId,
    done: AtomicU64,
    bar: Mutex<Bar>,
    /// Notes made on worker threads, logged at the owner thread's next call.
    notes: Mutex<Vec<String>>,
}

impl Default for PyProgress {
    fn default() -> Self {
        Self::new()
    }
}

impl PyProgress {
    pub fn new() -> Self {
        PyProgress {
            owner: std::thread::current().id(),
            done: AtomicU64::new(0),
            bar: Mutex::new(Bar { bar: None, shown: 0, drawn_at: Instant::now() }),
            notes: Mutex::new(Vec::new()),
        }
    }

    fn on_owner(&self) -> bool {
        std::thread::current().id() == self.owner
    }

    /// Shows the steps counted and the notes made so far (owner thread only).
    fn flush(&self, force: bool) {
        let notes = std::mem::take(&mut *self.notes.lock().unwrap_or_else(|e| e.into_inner()));
        for n in notes {
            log_note(&n);
        }
        let mut b = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if b.bar.is_none() || (!force && b.drawn_at.elapsed() < Duration::from_millis(100)) {
            return;
        }
        let done = self.done.load(Ordering::Relaxed);
        let delta = done.saturating_sub(b.shown);
        if delta == 0 {
            return;
        }
        b.shown = done;
        b.drawn_at = Instant::now();
        if let Some(bar) = &b.bar {
            Python::attach(|py| {
                let _ = bar.call_method1(py, "update", (delta,));
            });
        }
    }

    fn close(&self) {
        self.flush(true);
        let mut b = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(bar) = b.bar.take() {
            Python::attach(|py| {
                let _ = bar.call_method0(py, "close");
            });
        }
    }
}

fn make_bar(label: &str, total: u64) -> Option<Py<PyAny>> {
    if !ENABLED.load(Ordering::Relaxed) {
        return None;
    }
    Python::attach(|py| {
        let tqdm = py.import("tqdm.auto").or_else(|_| py.import("tqdm")).ok()?;
        let kw = PyDict::new(py);
        kw.set_item("total", total).ok()?;
        kw.set_item("desc", label).ok()?;
        kw.set_item("leave", false).ok()?;
        tqdm.call_method("tqdm", (), Some(&kw)).ok().map(Bound::unbind)
    })
}

/// Logs notes a library call made (an import's assumptions, a proposed choice) to the
/// `surfcap` logger at level WARNING, as the command line prints its `note:` lines.
pub fn log_notes(py: Python<'_>, notes: &[String]) -> PyResult<()> {
    let logger = py.import("logging")?.call_method1("getLogger", ("surfcap",))?;
    for n in notes {
        logger.call_method1("warning", (n,))?;
    }
    Ok(())
}

/// Logs a note to the `surfcap` logger at level WARNING.
fn log_note(text: &str) {
    Python::attach(|py| {
        if let Ok(logging) = py.import("logging")
            && let Ok(logger) = logging.call_method1("getLogger", ("surfcap",))
        {
            let _ = logger.call_method1("warning", (text,));
        }
    });
}

impl Progress for PyProgress {
    fn start(&self, label: &str, total: u64) {
        if !self.on_owner() {
            return;
        }
        self.close();
        self.done.store(0, Ordering::Relaxed);
        let mut b = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        b.bar = make_bar(label, total);
        b.shown = 0;
        b.drawn_at = Instant::now();
    }

    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
        if self.on_owner() {
            self.flush(false);
        }
    }

    fn finish(&self) {
        if self.on_owner() {
            self.close();
        }
    }

    fn note(&self, text: &str) {
        if self.on_owner() {
            log_note(text);
        } else {
            self.notes.lock().unwrap_or_else(|e| e.into_inner()).push(text.to_string());
        }
    }
}

impl Drop for PyProgress {
    fn drop(&mut self) {
        if self.on_owner() {
            self.close();
        }
    }
}
