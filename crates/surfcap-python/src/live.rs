//! The live session of the interactive controller (`surfcap play`'s player) from Python: a
//! host (a notebook, a game loop, Blender) steps it under its own input and shows what it
//! answers. `Synthesizer.live(bits)` starts one on the prepared subject.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use surfcap_formats::stream::StreamFile;
use surfcap_synthesis::Prepared;
use surfcap_synthesis::controller::live_session::{LiveAsk, LiveSession};

use crate::arrays::matrix;
use crate::errors::IntoPyResult;

/// A live session (`surfcap play`'s player, without the page): ``step`` advances the
/// controller under an input and returns what falls due as a dict (the frames with their
/// placement, the decisions, the transitions chosen and their blend ids, what cannot be
/// followed, the predicted and desired trajectories); ``blend`` and ``blend_from`` give a
/// chosen transition's blended frames as (F, V, 3) float32 positions.
#[pyclass(frozen, name = "LiveSession", module = "surfcap")]
pub struct PyLiveSession {
    session: LiveSession,
}

impl PyLiveSession {
    pub fn start(py: Python<'_>, prep: Prepared, bits: u32) -> PyResult<Self> {
        let session = py.detach(|| LiveSession::start(prep, bits)).py_err()?;
        Ok(PyLiveSession { session })
    }

    fn json<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?.call_method1("loads", (value.to_string(),))
    }

    /// A compact stream's frames as (F, V, 3) float32 positions.
    fn decoded<'py>(&self, py: Python<'py>, stream: &[u8]) -> PyResult<Bound<'py, PyAny>> {
        let n = self.session.prepared().subject().topology().n_vertices();
        let file = StreamFile::parse(stream).map_err(|e| PyRuntimeError::new_err(format!("a blend's stream: {e}")))?;
        let values = file.decode().map_err(|e| PyRuntimeError::new_err(format!("a blend's stream: {e}")))?;
        let frames = values.len() / (3 * n);
        Ok(matrix(py, values, &[frames, n, 3])?.into_any())
    }
}

#[pymethods]
impl PyLiveSession {
    /// The subject and the session (name, fps, units, up and ground axes, the start frame, the
    /// gaits and their speeds, the blends made so far with their timings), as a dict.
    #[getter]
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Self::json(py, &self.session.info())
    }

    /// Advances the controller by ``dt`` seconds under the asked input: ``direction`` on the
    /// subject's two ground axes, of length 0 (stop) to 1 (the gait's full speed); ``run``
    /// rather than walk. Returns the page's answer as a dict: ``frames`` (each a captured
    /// ``frame`` or a ``blend`` id and its frame ``k``, with its placement ``theta`` and ``t``
    /// and ``centre``), ``decisions``, ``blends``, ``cannot_follow``, ``predicted``,
    /// ``desired``.
    #[pyo3(signature = (direction, *, run=false, dt=1.0 / 60.0))]
    fn step<'py>(&self, py: Python<'py>, direction: (f64, f64), run: bool, dt: f64) -> PyResult<Bound<'py, PyAny>> {
        if !(0.0..=1.0).contains(&dt) {
            return Err(PyValueError::new_err(format!("dt {dt}: expected seconds from 0 to 1")));
        }
        if !(direction.0.is_finite() && direction.1.is_finite()) {
            return Err(PyValueError::new_err(format!("direction {direction:?}: expected two finite numbers")));
        }
        let ask = LiveAsk { direction: [direction.0, direction.1], run, dt };
        let answer = py.detach(|| self.session.step(&ask)).map_err(PyRuntimeError::new_err)?;
        Self::json(py, &answer)
    }

    /// Blend ``id``'s frames (every frame after the transition's source, the last one its
    /// destination), waiting for the blending thread: (F, V, 3) float32 positions, placed as the
    /// source frame is captured (a step's ``theta`` and ``t`` place them in the world).
    fn blend<'py>(&self, py: Python<'py>, id: u64) -> PyResult<Bound<'py, PyAny>> {
        let stream = py.detach(|| self.session.blend(id)).map_err(PyRuntimeError::new_err)?;
        self.decoded(py, &stream)
    }

    /// Blend ``id``'s frames from ``frame`` on that are made so far (waits for at least one),
    /// and the transition's number of frames: ``(positions, total)``.
    fn blend_from<'py>(&self, py: Python<'py>, id: u64, frame: usize) -> PyResult<(Bound<'py, PyAny>, usize)> {
        let (stream, total) = py.detach(|| self.session.blend_from(id, frame)).map_err(PyRuntimeError::new_err)?;
        Ok((self.decoded(py, &stream)?, total))
    }

    /// Every captured frame as one compact stream (the play page's format), as bytes.
    fn captured_stream<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.session.captured_stream())
    }

    /// Starts the controller again from its start frame.
    fn restart(&self, py: Python<'_>) -> PyResult<()> {
        py.detach(|| self.session.restart()).map_err(PyRuntimeError::new_err)
    }

    fn __repr__(&self) -> String {
        let s = self.session.prepared().subject();
        format!("LiveSession({:?}, {} moves)", s.name, self.session.moves())
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyLiveSession>()
}
