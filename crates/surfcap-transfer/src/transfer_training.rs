//! A transfer trained from the user's key pairs, as one derived product (thesis 5.3-5.5): the
//! sequences the keys use are aligned, the keys densified per pair of sequences (5.5.1, unless
//! asked not to), the part spaces and GPs fitted (5.4, 5.5.2), and the target's aligned
//! training poses kept for the part correction (5.6.1).
//!
//! The product is cached on disk like the derived matrices: a folder
//! `transfer-model-<16 hex>` in the cache folder, keyed by everything it depends on (both
//! subjects' geometry, names, rates and the target's units, the key pairs, both parts and every
//! option, and a layout version), holding the model files of [`crate::transfer_model_file`] and
//! `training.json` (what [`TrainedTransfer`] says besides the model), with its content hash in
//! `transfer-model-<16 hex>.b3`. A repeat of the same training reads it; an entry that does not
//! read, or whose files do not match their hash, is trained again and replaced.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use surfcap_mesh::Subject;
use surfcap_mesh::cache_entry::{self, EntryRead};
use surfcap_mesh::derived_cache::{DerivedCache, subject_hash};

use crate::body_parts::BodyParts;
use crate::correspondence_densification::DensifyOptions;
use crate::error::Result;
use crate::motion_transfer::{MotionTransfer, PreparedSubject, TrainOptions, TrainReport};
use crate::training_pairs::{FramePair, GroupReport, densified_pairs};
use crate::transfer_model_file::{KIND, SubjectsMeta, read_model, write_model};

/// What a training is made from.
pub struct TrainingRequest<'a> {
    pub source: &'a Subject,
    pub target: &'a Subject,
    pub source_parts: &'a BodyParts,
    pub target_parts: &'a BodyParts,
    /// Key pairs (global frames of the source, of the target).
    pub keys: &'a [FramePair],
    pub options: TrainOptions,
    /// Densify the keys of each pair of sequences (`None`: train on the keys).
    pub densify: Option<DensifyOptions>,
}

/// What training says besides the model (cached as `training.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrainingSummary {
    pub report: TrainReport,
    /// The training pairs (global frames), after densification.
    pub pairs: Vec<FramePair>,
    /// Per pair of sequences: keys, pairs, whether densified (empty without densification).
    pub groups: Vec<GroupReport>,
    /// Sequence indices of each subject the keys use, in order of first use.
    pub source_sequences: Vec<usize>,
    pub target_sequences: Vec<usize>,
    /// Seconds spent fitting the part spaces and GPs.
    pub fit_seconds: f64,
}

/// A trained transfer.
pub struct TrainedTransfer {
    pub model: MotionTransfer,
    pub subjects: SubjectsMeta,
    /// The target's aligned training poses (the examples of the part correction).
    pub target_training: Vec<Vec<f32>>,
    pub summary: TrainingSummary,
    /// Whether it was read from the cache.
    pub from_cache: bool,
}

/// The sequences of `s` that `frames` fall in, in order of first use.
fn sequences_of(s: &Subject, frames: impl Iterator<Item = usize>) -> Vec<usize> {
    let mut seen = Vec::new();
    for k in frames.filter_map(|g| s.frame_index().locate(g).map(|l| l.0)) {
        if !seen.contains(&k) {
            seen.push(k);
        }
    }
    seen
}

/// Trains, with no cache.
pub fn train_transfer(req: &TrainingRequest<'_>) -> Result<TrainedTransfer> {
    let (source, target) = (req.source, req.target);
    let source_sequences = sequences_of(source, req.keys.iter().map(|k| k.0));
    let target_sequences = sequences_of(target, req.keys.iter().map(|k| k.1));
    let src = PreparedSubject::new(source, &source_sequences)?;
    let tgt = PreparedSubject::new(target, &target_sequences)?;
    // Every frame of the sequences the keys use feeds the PCA.
    let pca_src: Vec<usize> = source_sequences.iter().flat_map(|&k| source.frame_index().range(k)).collect();
    let pca_tgt: Vec<usize> = target_sequences.iter().flat_map(|&k| target.frame_index().range(k)).collect();
    let (pairs, groups) = match &req.densify {
        None => (req.keys.to_vec(), Vec::new()),
        Some(d) => {
            densified_pairs(&src, req.source_parts, &tgt, req.target_parts, req.keys, req.options.components, d)?
        }
    };
    let t_fit = Instant::now();
    let (model, report) = MotionTransfer::train(
        &src,
        req.source_parts,
        &pca_src,
        &tgt,
        req.target_parts,
        &pca_tgt,
        &pairs,
        &req.options,
    )?;
    let fit_seconds = t_fit.elapsed().as_secs_f64();
    let mut distinct: Vec<usize> = pairs.iter().map(|p| p.1).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let target_training = distinct.iter().map(|&g| tgt.frame(g).map(|f| f.0.to_vec())).collect::<Result<_>>()?;
    Ok(TrainedTransfer {
        model,
        subjects: SubjectsMeta::new(source, target),
        target_training,
        summary: TrainingSummary { report, pairs, groups, source_sequences, target_sequences, fit_seconds },
        from_cache: false,
    })
}

/// The cache folder of this training in `cache_dir`.
pub fn cache_entry(cache_dir: &Path, req: &TrainingRequest<'_>) -> PathBuf {
    // `version` changes with what training computes or the entry holds.
    let params = serde_json::json!({
        "version": 1,
        "target": subject_hash(req.target).to_hex().to_string(),
        "names": [&req.source.name, &req.target.name], "fps": [req.source.fps, req.target.fps],
        "target_units": req.target.units,
        "keys": req.keys, "source_parts": req.source_parts, "target_parts": req.target_parts,
        "options": req.options, "densify": req.densify,
    });
    DerivedCache::new(cache_dir)
        .path("transfer-model", &subject_hash(req.source), &params.to_string())
        .with_extension("")
}

/// Reads a cache entry written by [`train_cached`].
fn read_entry(entry: &Path) -> Result<TrainedTransfer> {
    let saved = read_model(entry)?;
    let path = entry.join("training.json");
    let bytes = surfcap_mesh::read_regular_file(&path)?;
    let summary: TrainingSummary = serde_json::from_slice(&bytes)
        .map_err(|e| crate::Error::Invalid(format!("{}: {e}: expected a training summary", path.display())))?;
    Ok(TrainedTransfer {
        model: saved.model,
        subjects: saved.subjects,
        target_training: saved.target_training,
        summary,
        from_cache: true,
    })
}

/// Trains through the cache folder `cache_dir`: a good entry is read (unless `refresh`), else
/// the training runs and is stored. Notes (an entry not used, one not stored, a name that was
/// not an entry) go to `note`.
///
/// The folder and its entries are handled as [`surfcap_mesh::cache_entry`] says: a cache folder
/// other users can write is refused (an error), an entry is used only when it is a real folder
/// of this user's holding surfcap's marker and files matching its content hash, and storing
/// replaces only such an earlier entry, or a symlink or other non-folder name (removed as a
/// name, its target never touched); never anything else, and never by force.
pub fn train_cached(
    req: &TrainingRequest<'_>,
    cache_dir: &Path,
    refresh: bool,
    note: &mut dyn FnMut(String),
) -> Result<TrainedTransfer> {
    cache_entry::check_folder(cache_dir)?;
    let entry = cache_entry(cache_dir, req);
    if !refresh {
        let problem = match cache_entry::check_folder_entry(&entry, KIND) {
            EntryRead::Missing => None,
            EntryRead::Unusable(e) => Some(e.to_string()),
            EntryRead::Read(()) => match read_entry(&entry) {
                Ok(t) => return Ok(t),
                Err(e) => Some(e.to_string()),
            },
        };
        if let Some(problem) = problem {
            note(format!("cached model {} not used ({problem}); training again", entry.display()));
        }
    }
    let trained = train_transfer(req)?;
    let stored = cache_entry::store_folder_entry(
        &entry,
        KIND,
        |dir| {
            write_model(dir, &trained.model, &trained.subjects, &trained.target_training).map_err(|e| {
                surfcap_mesh::Error::io(dir, "write the cached model", std::io::Error::other(e.to_string()))
            })?;
            let summary = serde_json::to_vec(&trained.summary).map_err(std::io::Error::other);
            surfcap_mesh::atomic::write_file(&dir.join("training.json"), |w| w.write_all(&summary?))
        },
        &mut *note,
    );
    if let Err(e) = stored {
        note(format!("the model could not be cached in {} ({e})", entry.display()));
    }
    Ok(trained)
}
