//! Motion transfer from Python (thesis chapter 5), as `surfcap transfer train | apply`:
//! `TransferModel.train(source, target, pairs, ...)` learns a model (GP regression on body parts,
//! or Baran et al. 2009), `save(dir)` writes the model folder the command writes (and `surfcap
//! transfer apply` reads), `TransferModel.load(dir)` reads one the command wrote, and
//! `apply(source, sequence, ...)` transfers a motion of the source onto the target, returning the
//! target playing it and the `TransferApplyReport`. Both call
//! `surfcap_synthesis::transfer_run`, as the command does.

use std::path::{Path, PathBuf};
use std::time::Instant;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use surfcap_transfer::body_parts_choice::choose_parts;

/// Collects the notes a library call makes (to log them once the GIL is back).
#[derive(Default)]
struct NoteList(std::sync::Mutex<Vec<String>>);

impl surfcap_mesh::Progress for NoteList {
    fn note(&self, text: &str) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(text.to_string());
    }
}
use surfcap_formats::export::{ExportFormat, ExportOptions};
use surfcap_mesh::output_set::OutputSet;
use surfcap_synthesis::transfer_run::{
    ApplyOptions, MotionOf, Reconstruction, TrainingCache, TransferApplication, TransferMethod, TransferTrainOptions,
    TransferTraining, model_shape, read_key_pairs, train_model, write_model_files,
};
use surfcap_transfer::pairs_file::KeyPair;
use surfcap_transfer::transfer_model::TransferKernel;
use surfcap_transfer::transfer_model_file::{KIND, SavedTransfer, read_any};

use crate::errors::{IntoPyResult, anyhow_to_py};
use crate::progress::PyProgress;
use crate::subject::PySubject;

/// A trained transfer from a source subject to a target subject.
#[pyclass(frozen, name = "TransferModel", module = "surfcap")]
pub struct PyTransferModel {
    model: SavedTransfer,
    /// The training report (`report.json` of the model folder), as JSON text.
    report: Option<String>,
    /// The folder it was read from or last saved to (names the model in reports and messages).
    folder: std::sync::Mutex<Option<PathBuf>>,
}

impl PyTransferModel {
    fn label(&self) -> PathBuf {
        let folder = self.folder.lock().unwrap_or_else(|e| e.into_inner()).clone();
        folder.unwrap_or_else(|| {
            let (meta, _, _) = model_shape(&self.model);
            PathBuf::from(format!("{} -> {} (not saved)", meta.source_name, meta.target_name))
        })
    }
}

/// The key pairs: a CSV path as the command reads (`source sequence:frame, target
/// sequence:frame` per line), or a list of `(source frame, target frame)` pairs, each an int
/// (global index) or `"sequence:frame"`.
fn key_pairs(pairs: &Bound<'_, PyAny>, source: &PySubject, target: &PySubject) -> PyResult<Vec<KeyPair>> {
    if let Ok(path) = pairs.extract::<PathBuf>()
        && !pairs.is_instance_of::<pyo3::types::PyList>()
        && !pairs.is_instance_of::<pyo3::types::PyTuple>()
    {
        return read_key_pairs(&path, source.subject(), target.subject()).py_err();
    }
    let list: Vec<(Bound<'_, PyAny>, Bound<'_, PyAny>)> = pairs.extract().map_err(|_| {
        PyTypeError::new_err("pairs: expected a CSV path or a list of (source frame, target frame) pairs")
    })?;
    if list.is_empty() {
        return Err(PyValueError::new_err("pairs: no pairs: expected at least one"));
    }
    list.iter()
        .enumerate()
        .map(|(i, (a, b))| {
            let at = |e: PyErr, side: &str| PyValueError::new_err(format!("pairs[{i}] {side}: {e}"));
            Ok(KeyPair {
                source: source.frame_of(a).map_err(|e| at(e, "source"))?,
                target: target.frame_of(b).map_err(|e| at(e, "target"))?,
                line: i + 1,
            })
        })
        .collect()
}

/// Writes the model folder `dir` as `surfcap transfer train -o dir` does: claimed (a folder
/// surfcap did not write is replaced only with `force`), the model files and `report.json`.
fn save_folder(
    dir: &Path,
    model: &SavedTransfer,
    report: Option<&serde_json::Value>,
    force: bool,
) -> anyhow::Result<()> {
    let mut outs = OutputSet::new(&[]);
    outs.dir(dir, KIND, force)?;
    let folder = surfcap_mesh::output_path::claim_dir(dir, KIND, force)?;
    write_model_files(&folder, model)?;
    if let Some(r) = report {
        let mut r = r.clone();
        if let Some(o) = r.as_object_mut() {
            o.insert("model".into(), serde_json::to_value(dir)?);
        }
        surfcap_mesh::atomic::write_file(&folder.join("report.json"), |w| {
            serde_json::to_writer_pretty(&mut *w, &r).map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        })?;
    }
    outs.commit()?;
    Ok(())
}

#[pymethods]
impl PyTransferModel {
    /// Learns the transfer from `source` to `target` (`Subject`s) from pairs of corresponding
    /// frames, as `surfcap transfer train`: `pairs` a CSV path (`source sequence:frame, target
    /// sequence:frame` per line, ranges `walk:0-29, walk:0-29`) or a list of `(source frame,
    /// target frame)` pairs (int or `"sequence:frame"`). `method` gp (thesis ch. 5) or baran
    /// (Baran et al. 2009; the part, component, kernel and densification options do not apply);
    /// `source_parts`/`target_parts` parts files (default: five parts proposed, noted to the
    /// `surfcap` logger), `whole_body` one part; `kernel` nn, se or linear. GP training goes
    /// through the source subject's cache folder, as the command's through its own. `output=`
    /// writes the model folder (as `save`).
    #[staticmethod]
    #[pyo3(signature = (source, target, pairs, *, method="gp", source_parts=None, target_parts=None, whole_body=false, components=20, kernel="nn", seed=0, no_densify=false, max_straight=3, output=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn train(
        py: Python<'_>,
        source: &Bound<'_, PySubject>,
        target: &Bound<'_, PySubject>,
        pairs: &Bound<'_, PyAny>,
        method: &str,
        source_parts: Option<PathBuf>,
        target_parts: Option<PathBuf>,
        whole_body: bool,
        components: usize,
        kernel: &str,
        seed: u64,
        no_densify: bool,
        max_straight: usize,
        output: Option<PathBuf>,
        force: bool,
    ) -> PyResult<Self> {
        let method = TransferMethod::parse(method).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let kernel = TransferKernel::parse(kernel).map_err(|e| PyValueError::new_err(format!("kernel: {e}")))?;
        if components < 1 {
            return Err(PyValueError::new_err("components: 0, expected at least 1"));
        }
        if max_straight < 1 {
            return Err(PyValueError::new_err("max_straight: 0, expected at least 1"));
        }
        let (src, tgt) = (source.get(), target.get());
        let keys = key_pairs(pairs, src, tgt)?;
        let options = TransferTrainOptions { method, components, kernel, seed, densify: !no_densify, max_straight };
        let cache =
            src.cache_choice().dir.clone().map(|dir| TrainingCache { dir, refresh: src.cache_choice().refresh });
        let (s, t) = (src.subject(), tgt.subject());
        let (trained, notes) = py
            .detach(|| -> anyhow::Result<_> {
                let mut notes = Vec::new();
                let parts = match method {
                    TransferMethod::Baran => None,
                    TransferMethod::Gp => {
                        // The parts' notes are collected here and logged after the GIL is back.
                        let collected = NoteList::default();
                        let sp =
                            choose_parts(source_parts.as_deref(), whole_body, s, "source", "source_parts", &collected)?;
                        let tp =
                            choose_parts(target_parts.as_deref(), whole_body, t, "target", "target_parts", &collected)?;
                        notes.extend(collected.0.into_inner().unwrap_or_else(|e| e.into_inner()));
                        Some((sp, tp))
                    }
                };
                let training = TransferTraining {
                    source: s,
                    target: t,
                    keys: &keys,
                    parts: parts.as_ref().map(|(a, b)| (a, b)),
                    options,
                };
                let mut trained = train_model(&training, cache.as_ref(), &mut |n| notes.push(n))?;
                if let Some(o) = &output {
                    trained.report.set_model(o);
                    let r = serde_json::to_value(&trained.report)?;
                    save_folder(o, &trained.model, Some(&r), force)?;
                }
                Ok((trained, notes))
            })
            .map_err(anyhow_to_py)?;
        crate::progress::log_notes(py, &notes)?;
        let report = serde_json::to_string(&trained.report).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyTransferModel { model: trained.model, report: Some(report), folder: std::sync::Mutex::new(output) })
    }

    /// Reads a model folder written by `surfcap transfer train` or `save`.
    #[staticmethod]
    fn load(py: Python<'_>, dir: PathBuf) -> PyResult<Self> {
        let model = py.detach(|| read_any(&dir)).py_err()?;
        let report = std::fs::read_to_string(dir.join("report.json")).ok();
        Ok(PyTransferModel { model, report, folder: std::sync::Mutex::new(Some(dir)) })
    }

    /// Writes the model folder as `surfcap transfer train -o dir` does (`surfcap transfer apply
    /// dir` and `TransferModel.load` read it). A folder surfcap did not write is replaced only
    /// with `force`.
    #[pyo3(signature = (dir, *, force=false))]
    fn save(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<()> {
        let report: Option<serde_json::Value> = self.report.as_deref().and_then(|r| serde_json::from_str(r).ok());
        py.detach(|| save_folder(&dir, &self.model, report.as_ref(), force)).map_err(anyhow_to_py)?;
        *self.folder.lock().unwrap_or_else(|e| e.into_inner()) = Some(dir);
        Ok(())
    }

    /// `gp` or `baran`.
    #[getter]
    fn method(&self) -> &'static str {
        match self.model {
            SavedTransfer::Gp(_) => "gp",
            SavedTransfer::Baran(_) => "baran",
        }
    }

    #[getter]
    fn source_name(&self) -> String {
        model_shape(&self.model).0.source_name.clone()
    }

    #[getter]
    fn target_name(&self) -> String {
        model_shape(&self.model).0.target_name.clone()
    }

    /// The training report (`TransferTrainReport`), or None for a folder without `report.json`.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.report.as_deref().map(|r| crate::reports::from_json(py, "TransferTrainReport", r)).transpose()
    }

    /// Transfers the sequence `sequence` of `source` (a `Subject` on the model's source mesh)
    /// onto the target, as `surfcap transfer apply`: returns `(Subject, TransferApplyReport)`,
    /// the target playing the motion (one sequence `<sequence>-as-<target>`, `(F, V, 3)` float32)
    /// and the report. `reconstruction` stitch or average; `truth=(subject, sequence)` the true
    /// motion on the target (the report then gives the error against it); `correction`,
    /// `nearest` as the command's. `output=` writes the animation and its report as the command
    /// does.
    #[pyo3(signature = (source, sequence, *, reconstruction="stitch", truth=None, correction=false, nearest=3, output=None, format=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn apply<'py>(
        &self,
        py: Python<'py>,
        source: &Bound<'py, PySubject>,
        sequence: &str,
        reconstruction: &str,
        truth: Option<(Bound<'py, PySubject>, String)>,
        correction: bool,
        nearest: usize,
        output: Option<PathBuf>,
        format: Option<&str>,
        force: bool,
    ) -> PyResult<(Bound<'py, PySubject>, Bound<'py, PyAny>)> {
        let t0 = Instant::now();
        let reconstruction: Reconstruction =
            reconstruction.parse().map_err(|e: String| PyValueError::new_err(format!("reconstruction: {e}")))?;
        if nearest < 1 {
            return Err(PyValueError::new_err("nearest: 0, expected at least 1"));
        }
        let format = format.map(|f| f.parse::<ExportFormat>()).transpose().py_err()?;
        if format.is_some() && output.is_none() {
            return Err(PyValueError::new_err("format: given without output"));
        }
        let src = source.get();
        let label = src.subject().name.clone();
        let spec = format!("{label}:{sequence}");
        let truth_ref = truth.as_ref().map(|(t, q)| (t.get(), q.as_str()));
        let truth_label = truth_ref.map(|(t, _)| t.subject().name.clone()).unwrap_or_default();
        let truth_spec = truth_ref.map(|(_, q)| format!("{truth_label}:{q}")).unwrap_or_default();
        let model_label = self.label();
        let options = ApplyOptions { reconstruction, correction, nearest };
        let progress = PyProgress::new();
        let (animation, report, note) = py
            .detach(|| -> anyhow::Result<_> {
                let motion =
                    MotionOf { subject: src.subject(), label: &label, sequence, option: "sequence", spec: &spec };
                let truth = truth_ref.map(|(t, q)| MotionOf {
                    subject: t.subject(),
                    label: &truth_label,
                    sequence: q,
                    option: "truth",
                    spec: &truth_spec,
                });
                let application = TransferApplication::new(&self.model, &model_label, motion, truth)?;
                let mut outs = OutputSet::new(&[]);
                if let Some(o) = &output {
                    surfcap_synthesis::plan_animation_and_report(&mut outs, format, o, force)?;
                }
                let (subject, mut report) = application.run(&options, t0)?;
                if let Some(o) = &output {
                    let fmt = surfcap_synthesis::animation_output::output_format(format, o);
                    let opts = ExportOptions { force, ..Default::default() };
                    report.written = surfcap_formats::export::export(&subject, fmt, o, opts, &progress)?;
                    surfcap_synthesis::write_report(&surfcap_synthesis::report_path(o), &report)?;
                    outs.commit()?;
                }
                Ok((subject, report, application.note.clone()))
            })
            .map_err(anyhow_to_py)?;
        drop(progress);
        crate::progress::log_notes(py, note.as_slice())?;
        let report = crate::reports::report(py, "TransferApplyReport", &report)?;
        Ok((Bound::new(py, src.derived(animation))?, report))
    }

    fn __repr__(&self) -> String {
        let (meta, ns, nt) = model_shape(&self.model);
        format!(
            "TransferModel({}: {} ({ns} vertices) -> {} ({nt} vertices))",
            self.method(),
            meta.source_name,
            meta.target_name
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyTransferModel>()
}
