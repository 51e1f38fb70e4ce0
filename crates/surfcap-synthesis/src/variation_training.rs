//! A variation model learnt from sequences of one motion type of a subject (thesis 6.4-6.5:
//! one GPDM per body part, the sequences sharing one latent space, optionally with non-linear
//! blends of pairs, 6.7), saved as a model folder with its report (`report.json`: the
//! sequences learnt and every part's fit).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use surfcap_learn::gpdm::GpdmOptions;
use surfcap_mesh::{Progress, Subject};
use surfcap_transfer::BodyParts;
use surfcap_variation::VariationModel;
use surfcap_variation::motion_preparation::{PreparationOptions, SequenceOrigin, TimeAlignment};
use surfcap_variation::variation_model::TrainOptions;
use surfcap_variation::variation_model_file::KIND;

use crate::animation_output::write_report;
use crate::error::{Error, Result, refuse};

/// A training request on an opened subject.
#[derive(Debug, Clone)]
pub struct TrainRequest {
    /// Where the subject was read from (messages, and the report's `subject_path`).
    pub subject_path: PathBuf,
    /// The sequences to learn (empty: every sequence of the subject, with a note).
    pub sequences: Vec<String>,
    /// The sequence every other is re-timed onto (default: the first).
    pub reference: Option<String>,
    /// Pairs of learnt sequences blended and added to training, and the blend weights.
    pub blends: Vec<(String, String)>,
    pub blend_weights: Vec<f64>,
    /// Latent dimension of every part's GPDM and most L-BFGS iterations of its fit.
    pub latent_dim: usize,
    pub iterations: usize,
    /// The model folder to write; `force` lets it replace a folder surfcap did not write.
    pub output: PathBuf,
    pub force: bool,
}

/// One learnt sequence.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceReport {
    pub name: String,
    pub origin: SequenceOrigin,
    pub frames: usize,
}

/// One part's GPDM fit.
#[derive(Debug, Clone, Serialize)]
pub struct PartReport {
    pub part: String,
    pub vertices: usize,
    pub dimensions: usize,
    pub iterations: usize,
    pub evaluations: usize,
    pub converged: bool,
    pub objective_start: f64,
    pub objective: f64,
    /// Eq. 6.4's and eq. 6.6's hyper-parameters.
    pub alpha: [f64; 3],
    pub beta: [f64; 4],
    pub seconds: f64,
}

/// The report of a training (`report.json` in the model folder).
#[derive(Debug, Clone, Serialize)]
pub struct TrainReport {
    /// The model folder (none while the model is only in memory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<PathBuf>,
    pub subject: String,
    pub subject_path: PathBuf,
    pub vertices: usize,
    pub reference: String,
    pub frames: usize,
    pub latent_dim: usize,
    pub max_iterations: usize,
    pub sequences: Vec<SequenceReport>,
    pub parts: Vec<PartReport>,
    pub train_seconds: f64,
    pub total_seconds: f64,
    pub threads: usize,
}

/// The indices of `names` in `subject`, or an error listing its sequences.
fn sequence_indices(subject: &Subject, path: &Path, names: &[String]) -> Result<Vec<usize>> {
    let known = || subject.sequences().iter().map(|q| q.name.as_str()).collect::<Vec<_>>().join(", ");
    let mut out = Vec::with_capacity(names.len());
    for n in names {
        let Some((k, _)) = subject.sequence(n) else {
            refuse!("--sequences: {} has no sequence {n:?}; it has {}", path.display(), known())
        };
        if out.contains(&k) {
            refuse!("--sequences: {n:?} is given twice: expected each sequence once");
        }
        out.push(k);
    }
    Ok(out)
}

/// The sequences a request learns: the ones named, else every sequence of the subject (a note
/// says so: a variation model is meant for one motion type).
pub fn learnt_names(subject: &Subject, r: &TrainRequest, progress: &dyn Progress) -> Vec<String> {
    if !r.sequences.is_empty() {
        return r.sequences.clone();
    }
    let all: Vec<String> = subject.sequences().iter().map(|q| q.name.clone()).collect();
    progress.note(&format!(
        "no --sequences given, so every sequence of {} is learnt ({}); a variation model is meant for one motion type",
        subject.name,
        all.join(", ")
    ));
    all
}

/// The sequences of `names` (their indices in `subject`) and the training options of a
/// request (the reference and blend pairs as positions in `names`), refused before any work
/// when a name is not the subject's or not learnt.
pub fn train_plan(subject: &Subject, r: &TrainRequest, names: &[String]) -> Result<(Vec<usize>, TrainOptions)> {
    let chosen = sequence_indices(subject, &r.subject_path, names)?;
    let position = |n: &str, what: &str| {
        names.iter().position(|x| x == n).ok_or_else(|| {
            Error::Request(format!("{what}: {n:?} is not one of the learnt sequences ({})", names.join(", ")))
        })
    };
    let reference = match &r.reference {
        Some(name) => position(name, "--reference")?,
        None => 0,
    };
    let mut blend_pairs = Vec::with_capacity(r.blends.len());
    for (a, b) in &r.blends {
        let pair = (position(a, "--blend")?, position(b, "--blend")?);
        if pair.0 == pair.1 {
            refuse!("--blend {a}:{b}: expected two different sequences");
        }
        blend_pairs.push(pair);
    }
    let mut gpdm = GpdmOptions { latent_dim: r.latent_dim, ..GpdmOptions::default() };
    gpdm.lbfgs.max_iters = r.iterations;
    gpdm.lbfgs.max_evals = gpdm.lbfgs.max_evals.max(r.iterations + r.iterations / 4);
    let options = TrainOptions {
        preparation: PreparationOptions {
            reference,
            time_alignment: TimeAlignment::Uniform,
            blend_pairs,
            blend_weights: r.blend_weights.clone(),
        },
        gpdm,
    };
    Ok((chosen, options))
}

/// Learns the model of the sequences `chosen` ([`train_plan`]) on `parts` with `options`,
/// saves it and its report in the request's folder. `started` is when the request began (the
/// report's `total_seconds` counts from it).
pub fn train_variation_model(
    subject: &Subject,
    r: &TrainRequest,
    chosen: &[usize],
    parts: &BodyParts,
    options: &TrainOptions,
    started: Instant,
    progress: &dyn Progress,
) -> Result<TrainReport> {
    let (model, mut report) = learn_variation_model(subject, r, chosen, parts, options, progress)?;
    report.total_seconds = started.elapsed().as_secs_f64();
    report.model = Some(r.output.clone());
    save_variation_model(&model, &report, &r.output, &r.subject_path, r.force)?;
    Ok(report)
}

/// Learns the model of the sequences `chosen` ([`train_plan`]) on `parts` with `options`, in
/// memory, with its report (no model folder yet; `total_seconds` is the training's, for the
/// caller to replace by the whole request's). The request's `output` and `force` are not used.
pub fn learn_variation_model(
    subject: &Subject,
    r: &TrainRequest,
    chosen: &[usize],
    parts: &BodyParts,
    options: &TrainOptions,
    progress: &dyn Progress,
) -> Result<(VariationModel, TrainReport)> {
    let t_train = Instant::now();
    let model = VariationModel::train(subject, chosen, parts, options, progress)?;
    let train_seconds = t_train.elapsed().as_secs_f64();
    let report = TrainReport {
        model: None,
        subject: model.subject.clone(),
        subject_path: std::fs::canonicalize(&r.subject_path).unwrap_or_else(|_| r.subject_path.clone()),
        vertices: model.topology.n_vertices(),
        reference: model.reference.clone(),
        frames: model.frames,
        latent_dim: r.latent_dim,
        max_iterations: r.iterations,
        sequences: model
            .sequences
            .iter()
            .map(|s| SequenceReport { name: s.name.clone(), origin: s.origin.clone(), frames: s.own_frames })
            .collect(),
        parts: model
            .fits
            .iter()
            .map(|f| PartReport {
                part: f.part.clone(),
                vertices: f.vertices,
                dimensions: f.dimensions,
                iterations: f.fit.iters,
                evaluations: f.fit.evals,
                converged: f.fit.converged,
                objective_start: f.fit.initial_objective,
                objective: f.fit.objective,
                alpha: f.alpha,
                beta: f.beta,
                seconds: f.seconds,
            })
            .collect(),
        train_seconds,
        total_seconds: train_seconds,
        threads: rayon::current_num_threads(),
    };
    Ok((model, report))
}

/// Saves a learnt model and its report (`report.json`) in the folder `output`, together: in the
/// caller's output set when it planned the folder, else in one of their own (a failed save
/// leaves the place as it was). `subject_path` is the input the folder must not replace;
/// `force` lets it replace a folder surfcap did not write.
pub fn save_variation_model(
    model: &VariationModel,
    report: &TrainReport,
    output: &Path,
    subject_path: &Path,
    force: bool,
) -> Result<()> {
    let own = if surfcap_mesh::output_set::is_planned(output) {
        None
    } else {
        let mut set = surfcap_mesh::output_set::OutputSet::new(&[subject_path]);
        set.dir(output, KIND, force)?;
        Some(set)
    };
    model.save(output, force)?;
    let report = TrainReport { model: Some(output.to_path_buf()), ..report.clone() };
    write_report(&output.join("report.json"), &report)?;
    if let Some(set) = own {
        set.commit()?;
    }
    Ok(())
}

/// Checks a request's numbers as `surfcap vary train` does before any work: the latent
/// dimension (1 to [`MAX_LATENT_DIM`]), the iterations (1 to [`MAX_ITERATIONS`]) and every
/// blend weight strictly between 0 and 1.
pub fn check_train_request(r: &TrainRequest) -> Result<()> {
    if !(1..=MAX_LATENT_DIM).contains(&r.latent_dim) {
        refuse!("--latent-dim {}: expected a whole number from 1 to {MAX_LATENT_DIM}", r.latent_dim);
    }
    if !(1..=MAX_ITERATIONS).contains(&r.iterations) {
        refuse!("--iterations {}: expected a whole number from 1 to {MAX_ITERATIONS}", r.iterations);
    }
    for &w in &r.blend_weights {
        if !(w > 0.0 && w < 1.0) {
            refuse!(
                "--blend-weights {w}: expected a number strictly between 0 and 1 (0 and 1 are the two sequences themselves)"
            );
        }
    }
    if !r.blend_weights.is_empty() && r.blends.is_empty() && r.blend_weights != [0.5] {
        refuse!("--blend-weights needs --blend: the weights are those of the blended pairs");
    }
    Ok(())
}

/// Largest latent dimension of a part's GPDM.
pub const MAX_LATENT_DIM: usize = 10;
/// Most L-BFGS iterations of a part's fit (25 times the default 400).
pub const MAX_ITERATIONS: usize = 10_000;

/// The folder kind of a model folder (its marker).
pub const MODEL_KIND: &str = KIND;

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> TrainRequest {
        TrainRequest {
            subject_path: PathBuf::from("walk.subject"),
            sequences: vec![],
            reference: None,
            blends: vec![],
            blend_weights: vec![0.5],
            latent_dim: 3,
            iterations: 400,
            output: PathBuf::new(),
            force: false,
        }
    }

    #[test]
    fn a_training_outside_the_commands_ranges_is_refused_naming_the_option() {
        assert!(check_train_request(&request()).is_ok());
        let m = check_train_request(&TrainRequest { latent_dim: 11, ..request() }).unwrap_err().to_string();
        assert_eq!(m, "--latent-dim 11: expected a whole number from 1 to 10");
        let m = check_train_request(&TrainRequest { iterations: 0, ..request() }).unwrap_err().to_string();
        assert_eq!(m, "--iterations 0: expected a whole number from 1 to 10000");
        let blend = TrainRequest { blends: vec![("a".into(), "b".into())], blend_weights: vec![0.5, 1.0], ..request() };
        let m = check_train_request(&blend).unwrap_err().to_string();
        assert!(m.starts_with("--blend-weights 1: expected a number strictly between 0 and 1"), "{m}");
        let m = check_train_request(&TrainRequest { blend_weights: vec![0.25], ..request() }).unwrap_err().to_string();
        assert!(m.starts_with("--blend-weights needs --blend"), "{m}");
    }
}
