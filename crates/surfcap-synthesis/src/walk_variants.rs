//! Learned variants shown on a walk's repeated runs (thesis chapter 6 applied to a synthesised
//! walk): each time the walk plays frames it has already shown, a variant sampled from a
//! variation model (`surfcap vary train`) is shown instead of the same poses again; transitions
//! are still blended and the walk is placed as without.

use std::path::{Path, PathBuf};

use serde::Serialize;
use surfcap_mesh::Progress;
use surfcap_pipeline::frame_variants::FrameVariants;
use surfcap_pipeline::walk_playback::walk_passes;
use surfcap_variation::VariationModel;
use surfcap_variation::foot_skate_cleanup::CleanupReport;
use surfcap_variation::variation_sampling::{SamplingOptions, sample_variants, variants_on_source_path};

use crate::error::{Context, Result, refuse};
use crate::prepared::Prepared;
use crate::words::count_of;

/// Variants asked for: the model folder they are sampled from, and the seed of their sampling
/// (same seed, same animation).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Variation {
    pub seed: u64,
    /// The folder `surfcap vary train SUBJECT -o DIR` writes, trained on the subject's sequences.
    pub model: PathBuf,
}

impl Variation {
    /// Refuses, before any search, a model folder that is not there or that is the output.
    pub fn check(&self, output: Option<&Path>) -> Result<()> {
        if let Some(output) = output {
            surfcap_mesh::output_path::check_not_input(output, &[&self.model])?;
        }
        if !self.model.is_dir() {
            refuse!(
                "--variation-model {}: expected the folder of a variation model (`surfcap vary train SUBJECT -o DIR`)",
                self.model.display()
            );
        }
        Ok(())
    }
}

/// Most variants sampled per sequence for one walk: further repeats cycle through them
/// ([`FrameVariants`] shows variant (p - 1) mod K on pass p), which keeps sampling time
/// bounded (about 5 s a variant on 2 cores for a 117-frame walk of 1,500 vertices).
pub const MAX_VARIANTS_PER_SEQUENCE: usize = 5;

/// What the foot-skate clean-up did to one variant shown on a walk.
#[derive(Debug, Clone, Serialize)]
pub struct VariantCleanup {
    pub sequence: String,
    pub variant: usize,
    #[serde(flatten)]
    pub report: CleanupReport,
}

/// The learned variants shown on a walk's repeated runs: for each sequence of the subject the
/// walk plays more than once, as many variants as its largest pass ([`walk_passes`]), at most
/// [`MAX_VARIANTS_PER_SEQUENCE`], sampled from the model (thesis 6.6) with the seed and put on
/// the sequence's own path (`variants_on_source_path`: only the body's poses vary, so the walk's
/// placement, which the search solved, holds), their planted feet pinned by the foot-skate
/// clean-up as `vary sample` pins them (the variants' sliding before and after is returned).
/// A sequence the model has not learnt keeps its captured frames, with a note.
pub fn variants_for_walk(
    prep: &Prepared,
    variation: &Variation,
    walk: &[u32],
    progress: &dyn Progress,
) -> Result<(FrameVariants, Vec<VariantCleanup>)> {
    let (seed, model_dir) = (variation.seed, variation.model.as_path());
    let s = prep.subject();
    let needed = walk_passes(s, &prep.model, walk)?;
    let mut fv = FrameVariants::new(s);
    let mut cleanups = Vec::new();
    if needed.iter().all(|&n| n == 0) {
        return Ok((fv, cleanups));
    }
    let model =
        VariationModel::load(model_dir).with_context(|| format!("--variation-model {}", model_dir.display()))?;
    if model.topology.n_vertices() != s.topology().n_vertices()
        || model.topology.triangles() != s.topology().triangles()
    {
        refuse!(
            "--variation-model {}: trained on a mesh of {} vertices and {} triangles, but {:?} has {} and {}: expected a model trained on this subject (surfcap vary train)",
            model_dir.display(),
            model.topology.n_vertices(),
            model.topology.triangles().len(),
            s.name,
            s.topology().n_vertices(),
            s.topology().triangles().len()
        );
    }
    // The clean-up is made on the frames shown (on the source's path), not on the sampled ones.
    let opts = SamplingOptions { foot_skate_cleanup: false, ..SamplingOptions::default() };
    for (q, seq) in s.sequences().iter().enumerate() {
        if needed[q] == 0 {
            continue;
        }
        let Ok(j) = model.sequence_index(&seq.name) else {
            progress.note(&format!(
                "{:?} is not in the variation model {}: its {} repeated passes play the captured frames",
                seq.name,
                model_dir.display(),
                needed[q]
            ));
            continue;
        };
        if model.sequences[j].own_frames != seq.n_frames() {
            refuse!(
                "--variation-model {}: its {:?} has {} frames, the subject's {}: expected a model trained on this subject",
                model_dir.display(),
                seq.name,
                model.sequences[j].own_frames,
                seq.n_frames()
            );
        }
        let count = needed[q].min(MAX_VARIANTS_PER_SEQUENCE);
        progress.start(&format!("sampling {} of {} (seed {seed})", count_of(count, "variant"), seq.name), 1);
        let (variants, _) = sample_variants(&model, &seq.name, count, seed, &opts)
            .with_context(|| format!("sampling variants of {}", seq.name))?;
        progress.advance(1);
        progress.finish();
        let source: Vec<&[f32]> = (0..seq.n_frames()).map(|f| seq.frame(f)).collect();
        let mut placed = Vec::with_capacity(variants.len());
        for (k, (frames, report)) in
            variants_on_source_path(&model, j, &variants, &source, true)?.into_iter().enumerate()
        {
            placed.push(frames.into_iter().flatten().collect::<Vec<f32>>());
            if let Some(report) = report {
                cleanups.push(VariantCleanup { sequence: seq.name.clone(), variant: k, report });
            }
        }
        fv.add(&seq.name, placed)?;
    }
    Ok((fv, cleanups))
}
