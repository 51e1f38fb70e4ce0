//! `surfcap.VariationModel`: motion variation synthesis (thesis chapter 6), as `surfcap vary
//! train | sample`. `train` learns one GPDM per body part over sequences of one motion type of a
//! subject (optionally with non-linear blends of pairs, 6.7); `sample` draws variants of a learnt
//! sequence or of a blend at any weight by Hybrid Monte Carlo (6.6-6.7), each a `Subject`, with
//! the command's report. The same seed gives the same variants as the command, to the bit.
//!
//! Both calls are the command's library calls (`surfcap_synthesis::variation_training` and
//! `variant_samples`): the same checks, messages and numbers. A model folder `save` writes is
//! one `surfcap vary sample` reads, and `load` reads what `surfcap vary train` writes.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use surfcap_synthesis::variant_samples::{Varied, sample_variants_of, write_variants};
use surfcap_synthesis::variation_training::{
    TrainReport, TrainRequest, check_train_request, learn_variation_model, learnt_names, save_variation_model,
    train_plan,
};
use surfcap_transfer::body_parts_choice::choose_parts;
use surfcap_variation::VariationModel;
use surfcap_variation::variation_sampling::{ChainStart, SamplingOptions, VariantPath};

use crate::errors::IntoPyResult;
use crate::progress::PyProgress;
use crate::subject::{CacheChoice, PySubject};

/// A learnt variation model: in memory after `train`, or read from a folder by `load`.
#[pyclass(frozen, name = "VariationModel", module = "surfcap")]
pub struct PyVariationModel {
    model: Arc<VariationModel>,
    /// The folder it was read from or saved to (the sample report's `model`).
    folder: std::sync::Mutex<Option<PathBuf>>,
    /// The training's report (`report.json` of the folder), as JSON text.
    report: std::sync::Mutex<Option<String>>,
    /// Where the variants' derived products are cached (the training subject's choice).
    cache: CacheChoice,
}

impl PyVariationModel {
    fn folder(&self) -> Option<PathBuf> {
        self.folder.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// A blend pair `(A, B)`.
fn blend_pairs(blend: Option<Vec<(String, String)>>) -> Vec<(String, String)> {
    blend.unwrap_or_default()
}

#[pymethods]
impl PyVariationModel {
    /// Learns a variation model from `sequences` of `subject` (one motion type; default every
    /// sequence, with a note), as `surfcap vary train`: `reference` the sequence every other is
    /// re-timed onto (default the first), `parts` a body-parts file (default five parts proposed
    /// from the subject), `blend` pairs `(A, B)` of learnt sequences blended non-linearly at each
    /// of `blend_weights` (strictly between 0 and 1) and added to training, `latent_dim` (1-10)
    /// and `iterations` (1-10000) of every part's GPDM. With `output`, the model folder is
    /// written as the command writes it (`force`: replace a folder surfcap did not write).
    /// The training's report is `model.report` (`surfcap.reports.VariationTrainReport`).
    #[staticmethod]
    #[pyo3(signature = (subject, sequences=None, *, reference=None, parts=None, blend=None, blend_weights=vec![0.5], latent_dim=3, iterations=400, output=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn train(
        py: Python<'_>,
        subject: &PySubject,
        sequences: Option<Vec<String>>,
        reference: Option<String>,
        parts: Option<PathBuf>,
        blend: Option<Vec<(String, String)>>,
        blend_weights: Vec<f64>,
        latent_dim: usize,
        iterations: usize,
        output: Option<PathBuf>,
        force: bool,
    ) -> PyResult<Self> {
        let t0 = Instant::now();
        let s = subject.subject();
        let request = TrainRequest {
            // The subject's name stands for its file in messages and in the report.
            subject_path: PathBuf::from(&s.name),
            sequences: sequences.unwrap_or_default(),
            reference,
            blends: blend_pairs(blend),
            blend_weights,
            latent_dim,
            iterations,
            output: output.clone().unwrap_or_default(),
            force,
        };
        check_train_request(&request).py_err()?;
        // The model folder is planned before any work (a refusal costs nothing) and put in
        // place, report included, only when the training succeeded.
        let set = match &output {
            Some(out) => {
                let mut set = surfcap_mesh::output_set::OutputSet::new(&[]);
                set.dir(out, surfcap_synthesis::variation_training::MODEL_KIND, force).py_err()?;
                Some(set)
            }
            None => None,
        };
        let progress = PyProgress::new();
        let names = learnt_names(s, &request, &progress);
        let (chosen, options) = train_plan(s, &request, &names).py_err()?;
        let body = choose_parts(parts.as_deref(), false, s, "", "--parts", &progress).py_err()?;
        let (model, report) = py
            .detach(|| -> surfcap_synthesis::error::Result<(VariationModel, TrainReport)> {
                let (model, mut report) = learn_variation_model(s, &request, &chosen, &body, &options, &progress)?;
                report.total_seconds = t0.elapsed().as_secs_f64();
                if let Some(out) = &output {
                    report.model = Some(out.clone());
                    save_variation_model(&model, &report, out, &request.subject_path, force)?;
                }
                Ok((model, report))
            })
            .py_err()?;
        drop(progress);
        if let Some(set) = set {
            set.commit().py_err()?;
        }

        let text = serde_json::to_string(&report).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyVariationModel {
            model: Arc::new(model),
            folder: std::sync::Mutex::new(output),
            report: std::sync::Mutex::new(Some(text)),
            cache: subject.cache_choice().clone(),
        })
    }

    /// Reads a model folder written by `surfcap vary train` (or `save`). Its variants'
    /// derived products are cached in `cache_dir` (default: the command line's folder;
    /// `cache=False`: memory only).
    #[staticmethod]
    #[pyo3(signature = (path, *, cache_dir=None, cache=true))]
    fn load(py: Python<'_>, path: PathBuf, cache_dir: Option<PathBuf>, cache: bool) -> PyResult<Self> {
        let model = py.detach(|| VariationModel::load(&path)).py_err()?;
        // The training's report, when the folder has one (the command writes it).
        let report = std::fs::read_to_string(path.join("report.json")).ok().and_then(|t| {
            let mut v: serde_json::Value = serde_json::from_str(&t).ok()?;
            // (without the stamp every file surfcap writes begins with)
            let fields = v.as_object_mut()?;
            fields.remove("written_by");
            fields.remove("output_kind");
            serde_json::to_string(&v).ok()
        });
        Ok(PyVariationModel {
            model: Arc::new(model),
            folder: std::sync::Mutex::new(Some(path)),
            report: std::sync::Mutex::new(report),
            cache: CacheChoice::new(cache_dir, cache, false),
        })
    }

    /// Writes the model folder as `surfcap vary train` does (`model.json`, the parts' arrays and
    /// `report.json`), which `surfcap vary sample` and `load` read. Nothing surfcap did not write
    /// is replaced unless `force`; a failed save leaves the place as it was.
    #[pyo3(signature = (path, *, force=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, force: bool) -> PyResult<()> {
        let text = self.report.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let model = &self.model;
        py.detach(|| -> PyResult<()> {
            let mut set = surfcap_mesh::output_set::OutputSet::new(&[]);
            set.dir(&path, surfcap_synthesis::variation_training::MODEL_KIND, force).py_err()?;
            model.save(&path, force).py_err()?;
            if let Some(t) = &text {
                // The training's report, its folder now this one.
                let mut v: serde_json::Value =
                    serde_json::from_str(t).map_err(|e| PyValueError::new_err(e.to_string()))?;
                v["model"] = serde_json::json!(path);
                surfcap_synthesis::animation_output::write_report(&path.join("report.json"), &v).py_err()?;
            }
            set.commit().py_err()?;
            Ok(())
        })?;
        *self.folder.lock().unwrap_or_else(|e| e.into_inner()) = Some(path);
        Ok(())
    }

    /// The training's report (`surfcap.reports.VariationTrainReport`: the sequences learnt and
    /// every part's fit), or None for a folder without one.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let text = self.report.lock().unwrap_or_else(|e| e.into_inner()).clone();
        text.map(|t| crate::reports::from_json(py, "VariationTrainReport", &t)).transpose()
    }

    /// The name of the subject the model was learnt from.
    #[getter]
    fn subject(&self) -> String {
        self.model.subject.clone()
    }

    /// The learnt sequences (captured and blended), in order.
    #[getter]
    fn sequences(&self) -> Vec<String> {
        self.model.sequences.iter().map(|s| s.name.clone()).collect()
    }

    /// The sequence every other was re-timed onto.
    #[getter]
    fn reference(&self) -> String {
        self.model.reference.clone()
    }

    /// Frames of every learnt trajectory (the reference's frame count).
    #[getter]
    fn frames(&self) -> usize {
        self.model.frames
    }

    /// The body parts' names, one GPDM each.
    #[getter]
    fn parts(&self) -> Vec<String> {
        self.model.parts.names().iter().map(|s| s.to_string()).collect()
    }

    #[getter]
    fn n_vertices(&self) -> usize {
        self.model.topology.n_vertices()
    }

    #[getter]
    fn fps(&self) -> f64 {
        self.model.fps
    }

    /// The folder the model was read from or saved to, or None.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.folder()
    }

    /// Samples `count` variants of the learnt `sequence`, or of `blend` = `(A, B, W)` (two learnt
    /// sequences and a weight in [0, 1]), as `surfcap vary sample` with `seed` (the same seed
    /// gives the same variants as the command, whatever the thread count). `start` is `"learnt"`
    /// or `"mean"`, `path` `"source"`, `"sampled"` or `"contacts"`; `smoothing`, `deviation_smoothing`, `warmup`,
    /// `thin`, `max_leapfrog`, `no_foot_skate_cleanup`, `hold_hips`, `no_learnt_stretch` and
    /// `carry_pins` as the command's options.
    /// With `output`, the folder is written as the command writes it (one glb per variant and
    /// `report.json`). Returns `(variants, report)`: one `Subject` per variant (one sequence
    /// `<name>~<k>`, `(F, V, 3)` float32 positions) and a `surfcap.reports.VariationSampleReport`.
    #[pyo3(signature = (sequence=None, *, blend=None, count=5, seed=0, start="learnt", path="source", smoothing=2, deviation_smoothing=4, warmup=20, thin=2, max_leapfrog=30, no_foot_skate_cleanup=false, hold_hips=false, no_learnt_stretch=false, carry_pins=false, output=None, force=false))]
    #[allow(clippy::too_many_arguments)]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        sequence: Option<String>,
        blend: Option<(String, String, f64)>,
        count: usize,
        seed: u64,
        start: &str,
        path: &str,
        smoothing: usize,
        deviation_smoothing: usize,
        warmup: usize,
        thin: usize,
        max_leapfrog: usize,
        no_foot_skate_cleanup: bool,
        hold_hips: bool,
        no_learnt_stretch: bool,
        carry_pins: bool,
        output: Option<PathBuf>,
        force: bool,
    ) -> PyResult<(Vec<PySubject>, Bound<'py, PyAny>)> {
        if carry_pins && (hold_hips || no_foot_skate_cleanup) {
            return Err(PyValueError::new_err(
                "carry_pins with hold_hips or no_foot_skate_cleanup: carried pins move the body with the planted feet, \
                 which needs the clean-up with the hips free",
            ));
        }
        let varied = match (sequence, blend) {
            (Some(s), None) => Varied::Sequence(s),
            (None, Some((a, b, w))) => {
                if !(0.0..=1.0).contains(&w) {
                    return Err(PyValueError::new_err(format!("blend: the weight {w}: expected a number from 0 to 1")));
                }
                Varied::Blend { a, b, w }
            }
            (Some(_), Some(_)) => {
                return Err(PyTypeError::new_err("sequence and blend: give one, not both"));
            }
            (None, None) => return Err(PyTypeError::new_err("expected sequence=NAME or blend=(A, B, W)")),
        };
        let start = ChainStart::parse(start)
            .ok_or_else(|| PyValueError::new_err(format!("start: {start:?}: expected learnt or mean")))?;
        let path = VariantPath::parse(path)
            .ok_or_else(|| PyValueError::new_err(format!("path: {path:?}: expected source, contacts or sampled")))?;
        let options = SamplingOptions {
            start,
            path,
            smoothing,
            deviation_smoothing,
            warmup,
            thin,
            max_leapfrog,
            foot_skate_cleanup: !no_foot_skate_cleanup,
            move_root: !hold_hips && !no_foot_skate_cleanup,
            learnt_stretch: !no_learnt_stretch,
            carry_pins,
        };
        let folder = self.folder();
        let model = &self.model;
        let progress = PyProgress::new();
        let sampled = py
            .detach(|| -> surfcap_synthesis::error::Result<_> {
                let mut s = sample_variants_of(model, folder.as_deref(), &varied, count, seed, &options, &progress)?;
                if let Some(out) = &output {
                    let inputs: Vec<&Path> = folder.iter().map(PathBuf::as_path).collect();
                    write_variants(&mut s, out, &inputs, force, &progress)?;
                }
                Ok(s)
            })
            .py_err()?;
        drop(progress);
        let report = crate::reports::report(py, "VariationSampleReport", &sampled.report)?;
        let variants = sampled.variants.into_iter().map(|s| PySubject::new(s, self.cache.clone())).collect();
        Ok((variants, report))
    }

    fn __repr__(&self) -> String {
        let m = &self.model;
        format!(
            "VariationModel({:?}: {} learnt sequences ({}), {} frames each, {} parts, {} vertices)",
            m.subject,
            m.sequences.len(),
            m.sequences.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", "),
            m.frames,
            m.parts.len(),
            m.topology.n_vertices()
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyVariationModel>()
}
