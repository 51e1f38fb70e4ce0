//! surfcap from Python: the extension module `surfcap._surfcap` of the `surfcap` wheel
//! (`python/pyproject.toml`, built with maturin; the package `python/surfcap/` re-exports it).
//!
//! Every binding mirrors one command of the command line and returns what that command writes:
//! numpy arrays where it writes `.npy`, a [`subject::PySubject`] where it writes an animation, a
//! report (`surfcap.reports`, the same fields as the command's `.report.json`) where it writes
//! one. The numbers are the library's, so a binding and the command give the same bytes for the
//! same inputs and seed.
//!
//! # Conventions (see `docs/src/python.md` for the user's side)
//! - Arrays in: any float32/float64 array, C- or F-ordered or strided ([`arrays`]); a
//!   C-contiguous float32 position array is used in place, without a copy (the subject keeps a
//!   reference to it). Arrays out: `(F, V, 3)` float32 positions, `(T, 3)` uint32 faces, float64
//!   matrices; a subject's positions are a read-only view of its own buffer.
//! - Frames: a global index or `"sequence:frame"`, as on the command line.
//! - Long work runs with the GIL released ([`pyo3::Python::detach`]); progress goes to `tqdm`
//!   when it is installed ([`progress`]).
//! - Errors are `surfcap.SurfcapError` with the command line's message ([`errors`]).
//!
//! # Where to start reading
//! [`subject`] (the `Subject` class and the derived-product pipeline every binding uses), then one
//! file per area: [`distances`], [`transitions`], [`graphs`], [`synthesis`], [`smg`],
//! [`transfer`], [`variation`], [`appearance`].

use pyo3::prelude::*;

pub mod appearance;
pub mod arrays;
pub mod distances;
pub mod errors;
pub mod graphs;
pub mod live;
pub mod progress;
pub mod reports;
pub mod smg;
pub mod subject;
pub mod synthesis;
pub mod transfer;
pub mod transitions;
pub mod variation;

/// The extension module: each area registers its classes and functions.
#[pymodule]
fn _surfcap(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    subject::register(m)?;
    // Pose distances and non-linear interpolation (thesis chapter 2).
    distances::register(m)?;
    // Transitions and the transition table (thesis 3.2).
    transitions::register(m)?;
    // Graphs over the frames (thesis 3.3-3.4).
    graphs::register(m)?;
    // Path, key-pose and reach synthesis (thesis 3.5).
    synthesis::register(m)?;
    // The interactive controller's live session (surfcap play's player).
    live::register(m)?;
    // Huang et al. 2009's surface motion graph.
    smg::register(m)?;
    // Motion transfer (thesis chapter 5).
    transfer::register(m)?;
    // Variation models (thesis chapter 6).
    variation::register(m)?;
    // Appearance models (thesis chapter 4).
    appearance::register(m)?;
    Ok(())
}
