//! The evaluation of eigen appearance maps (thesis 4.5-4.6, Boukhayma 2017) on a sequence with
//! ground truth ([`AppearanceSequence`]: the degraded frames, the clean frames, the hole masks
//! and, where known, the true flow), as `surfcap eval appearance` runs it. Two benchmarks
//! implement it: the smooth one (`surfcap_appearance::generated_frames`: drift of a few
//! texels, a moving light, blur and noise) and the capture-like one ([`CaptureSequence`],
//! `surfcap_appearance::capture_benchmark`: camera-ring renders re-projected into the atlas
//! through calibration and tracking error).
//!
//! 1. **Flow accuracy** (4.4.1, where the true flow is known): mean end-point error, over the
//!    active texels, of the forward
//!    flows of the Poisson build (reference to every frame, read back through the caller's
//!    estimator, which caches them) against the true flow `true_flow(reference, k)`, beside the
//!    error of a zero flow (the drift itself); optionally for a few frames with a second
//!    estimator (e.g. full resolution).
//!    On the capture-like benchmark the true flow is the one between the frames' true content
//!    displacements (`surfcap_appearance::content_displacement`), over the texels where the
//!    reference's is defined.
//!
//!    **Warps against the truth** (where the benchmark knows each texel's content
//!    displacement: the capture-like one): how far each capture error alone moves the content
//!    and how far the cameras' displacements spread (ghosting); the Poisson model's backward
//!    warps, with the sweep's numbers of eigen warps, against the true backward flows; the
//!    variance of the textures left after aligning them; the model built on the true flows
//!    (one alignment, to the frame closest to the mean) and the splits of K with no warp, a
//!    third and half of K, with either flows.
//! 2. **Poisson vs direct warping** (Fig. 4.5-4.6): the model built with each warping;
//!    reconstruction of the training frames with every component, MSE and SSIM in the texture
//!    domain against the input frames and the clean ones; the same over the component sweep.
//! 3. **Compactness** (4.5.1, Fig. 4.9-4.10): for each total number of eigen maps K, ours (two
//!    thirds eigen textures, one third eigen warps, [`split_components`]) against naive PCA
//!    with K eigen textures ([`NaiveTexturePca`]): texture domain over the active texels against
//!    the input frame the model was built from (as the thesis) and the clean frame; image domain
//!    over the silhouette, the mesh rendered with the reconstruction and with the input texture
//!    from `views` cameras on a ring ([`cameras_around_mesh`]), averaged over the views, on
//!    `image_frames` evenly spaced training frames.
//! 4. **Generalisation** (4.5.2, Fig. 4.11-4.12): for each held-out fraction, that share of the
//!    frames (the first ones of one seeded permutation, so the held-out sets are nested and the
//!    same seed gives the same split) is left out, the model built on the rest, and each
//!    held-out frame projected: forward flow from the model's reference texture, aligned by the
//!    model's warping, backward flow, projection, instantiation (4.4.3). Naive PCA projects the
//!    texture. At fraction 0 every frame is projected through the full model (the training
//!    reconstruction by projection).
//! 5. **Completion** (4.6.2): the frames with an occlusion hole are left out of every model (as
//!    the thesis omits incomplete frames); each is completed by the full model
//!    ([`AppearanceModel::complete`]) and compared inside the hole with the clean frame,
//!    beside the model's mean texture and the holed input.
//! 6. **Interpolation** (4.6.1): two training frames blended at w = 0.5 by the model and by the
//!    linear blend of their textures, as an image.
//!
//! Every model uses the frames without holes only; frames run in parallel and every mean is a
//! fixed-order sum, so the numbers do not depend on the thread count.

use std::time::Instant;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rayon::prelude::*;
use serde::Serialize;
use surfcap_appearance::appearance_model::MaskedFlowEstimator;
use surfcap_appearance::capture_benchmark::{CaptureBenchmark, CaptureFrame, ErrorCauses};
use surfcap_appearance::content_displacement::{ContentDisplacement, flow_between};
use surfcap_appearance::generated_frames::GeneratedFrames;
use surfcap_appearance::image_similarity::{Similarity, similarity};
use surfcap_appearance::mesh_rasteriser::{Camera, Lens, Render, cameras_around_mesh, render_views};
use surfcap_appearance::{
    AppearanceModel, AppearanceOptions, BuildReport, FlowField, NaiveTexturePca, TexelMask, TextureImage,
    TextureWarper, Warping, build_appearance_model,
};
use surfcap_mesh::{Progress, Topology};

use crate::error::{Error, Result};

pub use surfcap_appearance::appearance_model::split_components;

/// A sequence the evaluation runs on: per-frame input textures and their clean truth on one
/// UV-mapped mesh, the frames with an occlusion hole, and the true flow between two frames
/// where the benchmark knows it.
pub trait AppearanceSequence: Sync {
    /// Where the frames come from (a folder), for messages.
    fn source(&self) -> String;
    /// Where the mesh comes from, for messages.
    fn mesh_source(&self) -> String;
    fn frames(&self) -> usize;
    fn width(&self) -> usize;
    fn height(&self) -> usize;
    /// The mesh (topology with its UV atlas, and the positions).
    fn mesh(&self) -> Result<(Topology, Vec<f32>)>;
    /// A name per frame (file stems).
    fn names(&self) -> Vec<String>;
    /// Frame `k`'s input texture and its clean truth.
    fn frame_and_clean(&self, k: usize) -> Result<(TextureImage, TextureImage)>;
    /// Frames with a hole, increasing.
    fn hole_frames(&self) -> Vec<usize>;
    /// Frame `k`'s hole mask (true in the hole), if it has one.
    fn hole(&self, k: usize) -> Option<Vec<bool>>;
    /// The true flow `from` -> `to` (`None`: unknown).
    fn true_flow(&self, from: usize, to: usize) -> Option<Result<FlowField>>;
    /// The texels where the true flow from frame `k` is known (`None`: every active texel).
    fn flow_defined(&self, _k: usize) -> Option<&[bool]> {
        None
    }
    /// How far each capture error moves the texels' content, where the benchmark knows it.
    fn displacement_causes(&self) -> Option<&[CauseRow]> {
        None
    }
}

impl AppearanceSequence for GeneratedFrames {
    fn source(&self) -> String {
        self.dir().display().to_string()
    }
    fn mesh_source(&self) -> String {
        self.dir().join(&self.header().mesh).display().to_string()
    }
    fn frames(&self) -> usize {
        GeneratedFrames::frames(self)
    }
    fn width(&self) -> usize {
        GeneratedFrames::width(self)
    }
    fn height(&self) -> usize {
        GeneratedFrames::height(self)
    }
    fn mesh(&self) -> Result<(Topology, Vec<f32>)> {
        Ok(GeneratedFrames::mesh(self)?)
    }
    fn names(&self) -> Vec<String> {
        self.header().frame_files.iter().map(|n| n.strip_suffix(".png").unwrap_or(n).to_string()).collect()
    }
    fn frame_and_clean(&self, k: usize) -> Result<(TextureImage, TextureImage)> {
        Ok((self.frame(k)?, self.clean(k)?))
    }
    fn hole_frames(&self) -> Vec<usize> {
        self.header().hole_frames.clone()
    }
    fn hole(&self, k: usize) -> Option<Vec<bool>> {
        GeneratedFrames::hole(self, k)
    }
    fn true_flow(&self, from: usize, to: usize) -> Option<Result<FlowField>> {
        Some(GeneratedFrames::true_flow(self, from, to).map_err(Error::from))
    }
}

/// The capture-like benchmark's frames, made in memory.
pub struct CaptureSequence {
    /// Where the mesh and texture came from, for messages.
    pub source: String,
    pub topology: Topology,
    /// The mesh at rest (the atlas's shape).
    pub positions: Vec<f32>,
    pub frames: Vec<CaptureFrame>,
    /// The true displacement of every frame's content, all capture errors included.
    pub displacements: Vec<ContentDisplacement>,
    /// The displacement of each error alone and of none, mean over the frames.
    pub causes: Vec<CauseRow>,
}

/// How far one capture error (or all, or none) moves the re-projected content: means over the
/// frames of the per-frame means over the active texels where the displacement is defined.
#[derive(Debug, Clone, Serialize)]
pub struct CauseRow {
    /// `all`, `calibration`, `tracking` or `none` (resampling and the charts' dilated ring only).
    pub cause: String,
    /// Mean length of the cosine-weighted mean displacement, texels.
    pub displacement: f64,
    /// Mean spread of the cameras' displacements about it (ghosting), texels.
    pub spread: f64,
    /// The same as medians over the texels (mean over the frames): the means are pulled by
    /// the few texels whose samples show content from far away in the atlas.
    pub median_displacement: f64,
    pub median_spread: f64,
    /// Share of the active texels where it is defined.
    pub defined_share: f64,
}

impl CaptureSequence {
    /// Every frame of `benchmark` (in parallel; each frame is independent of the others).
    pub fn generate(
        benchmark: &CaptureBenchmark,
        topology: &Topology,
        positions: &[f32],
        source: &str,
        progress: &dyn Progress,
    ) -> Result<CaptureSequence> {
        let n = benchmark.options().frames;
        progress.start("capture benchmark: rendering, re-projecting, true displacements", n as u64);
        let causes = [
            ("all", ErrorCauses::BOTH),
            ("calibration", ErrorCauses::CALIBRATION),
            ("tracking", ErrorCauses::TRACKING),
            ("none", ErrorCauses::NONE),
        ];
        let active = benchmark.mask().len().max(1) as f64;
        type Made = (CaptureFrame, ContentDisplacement, Vec<[f64; 5]>);
        let made: Vec<Made> = (0..n)
            .into_par_iter()
            .map(|k| {
                let f = benchmark.frame(k)?;
                let all = benchmark.content_displacement(k, ErrorCauses::BOTH)?;
                let mut rows = Vec::new();
                for (_, c) in &causes {
                    let one;
                    let d = if *c == ErrorCauses::BOTH {
                        &all
                    } else {
                        one = benchmark.content_displacement(k, *c)?;
                        &one
                    };
                    let (size, spread, m) = d.summary();
                    let (median_size, median_spread) = d.medians();
                    rows.push([size, spread, m as f64 / active, median_size, median_spread]);
                }
                progress.advance(1);
                Ok((f, all, rows))
            })
            .collect::<Result<_>>()?;
        progress.finish();
        let nf = n.max(1) as f64;
        let causes = causes
            .iter()
            .enumerate()
            .map(|(j, (name, _))| CauseRow {
                cause: name.to_string(),
                displacement: made.iter().map(|m| m.2[j][0]).sum::<f64>() / nf,
                spread: made.iter().map(|m| m.2[j][1]).sum::<f64>() / nf,
                defined_share: made.iter().map(|m| m.2[j][2]).sum::<f64>() / nf,
                median_displacement: made.iter().map(|m| m.2[j][3]).sum::<f64>() / nf,
                median_spread: made.iter().map(|m| m.2[j][4]).sum::<f64>() / nf,
            })
            .collect();
        let (frames, displacements): (Vec<_>, Vec<_>) = made.into_iter().map(|m| (m.0, m.1)).unzip();
        Ok(CaptureSequence {
            source: source.to_string(),
            topology: topology.clone(),
            positions: positions.to_vec(),
            frames,
            displacements,
            causes,
        })
    }
}

impl AppearanceSequence for CaptureSequence {
    fn source(&self) -> String {
        self.source.clone()
    }
    fn mesh_source(&self) -> String {
        self.source.clone()
    }
    fn frames(&self) -> usize {
        self.frames.len()
    }
    fn width(&self) -> usize {
        self.frames.first().map_or(0, |f| f.frame.width())
    }
    fn height(&self) -> usize {
        self.frames.first().map_or(0, |f| f.frame.height())
    }
    fn mesh(&self) -> Result<(Topology, Vec<f32>)> {
        Ok((self.topology.clone(), self.positions.clone()))
    }
    fn names(&self) -> Vec<String> {
        let digits = self.frames.len().saturating_sub(1).to_string().len().max(3);
        (0..self.frames.len()).map(|k| format!("frame_{k:0digits$}")).collect()
    }
    fn frame_and_clean(&self, k: usize) -> Result<(TextureImage, TextureImage)> {
        let f = self.frames.get(k).ok_or_else(|| {
            Error::Unsuitable(format!("{}: frame {k} of a capture benchmark of {}", self.source, self.frames.len()))
        })?;
        Ok((f.frame.clone(), f.clean.clone()))
    }
    fn hole_frames(&self) -> Vec<usize> {
        (0..self.frames.len()).filter(|&k| self.frames[k].hole.is_some()).collect()
    }
    fn hole(&self, k: usize) -> Option<Vec<bool>> {
        self.frames.get(k)?.hole.clone()
    }
    fn true_flow(&self, from: usize, to: usize) -> Option<Result<FlowField>> {
        let (a, b) = (self.displacements.get(from)?, self.displacements.get(to)?);
        Some(flow_between(a, b).map_err(Error::from))
    }
    fn flow_defined(&self, k: usize) -> Option<&[bool]> {
        self.displacements.get(k).map(|d| d.defined.as_slice())
    }
    fn displacement_causes(&self) -> Option<&[CauseRow]> {
        Some(&self.causes)
    }
}

/// What the evaluation measures and how.
#[derive(Debug, Clone, Serialize)]
pub struct AppearanceEvalOptions {
    /// Total numbers of eigen maps K of the compactness sweep (those above the number of
    /// training frames less one are dropped; that largest K is always added).
    pub components: Vec<usize>,
    /// Held-out fractions of the generalisation (each in [0, 1)).
    pub held_out: Vec<f64>,
    /// Seed of the held-out split.
    pub seed: u64,
    /// Training frames rendered for the image domain (evenly spaced), and held-out frames
    /// rendered per fraction (the first of the permutation); 0: no image domain.
    pub image_frames: usize,
    /// Virtual cameras on a ring around the mesh.
    pub views: usize,
    /// Width and height of the renders, pixels.
    pub image_size: usize,
    /// Weight of the intensity term of the Poisson warp (eq. 4.1-4.3).
    pub lambda: f64,
    /// Rings of texels around the atlas's covered texels (the active texels).
    pub dilation: usize,
    /// Alignments the medoid shift may run (Algorithm 4).
    pub medoid_iterations: usize,
    /// Frames whose forward flow is also measured with the second estimator.
    pub second_flow_frames: usize,
}

impl Default for AppearanceEvalOptions {
    fn default() -> Self {
        AppearanceEvalOptions {
            components: vec![3, 6, 12, 24, 48],
            held_out: vec![0.0, 0.2, 0.4, 0.6],
            seed: 7,
            image_frames: 10,
            views: 8,
            image_size: 256,
            lambda: 0.02,
            dilation: 1,
            medoid_iterations: 5,
            second_flow_frames: 0,
        }
    }
}

/// End-point errors of one set of flows (texels, mean over frames of the per-frame mean over
/// the active texels).
#[derive(Debug, Clone, Serialize)]
pub struct EndPointErrors {
    pub frames: usize,
    pub mean: f64,
    pub median: f64,
    pub max: f64,
    /// The same frames' error of a zero flow: the mean size of the true flow.
    pub zero_flow_mean: f64,
}

/// 1. The forward flows of the build against the truth.
#[derive(Debug, Clone, Serialize)]
pub struct FlowAccuracy {
    /// The estimator's description (e.g. its finest scale), as the caller gives it.
    pub estimator: String,
    pub reference: String,
    /// `None` when the benchmark does not know the true flow (a folder of frames).
    pub errors: Option<EndPointErrors>,
    /// The second estimator's description and errors on the first frames, when run.
    pub second_estimator: Option<String>,
    pub second: Option<EndPointErrors>,
}

/// A reconstruction's similarity to the input frame and to the clean (ground-truth) frame.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Scores {
    pub input: Similarity,
    pub clean: Similarity,
}

/// 2. One model of the warping comparison.
#[derive(Debug, Clone, Serialize)]
pub struct WarpingRow {
    pub warping: Warping,
    pub reference: String,
    pub eigen_textures: usize,
    pub eigen_warps: usize,
    /// Texture domain, every component, mean over the training frames.
    pub all_components: Scores,
    pub build_seconds: f64,
}

/// Image-domain similarity of ours and naive PCA (mean over views and frames).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ImageScores {
    pub ours: Similarity,
    pub naive: Similarity,
}

/// 3. One K of the compactness sweep.
#[derive(Debug, Clone, Serialize)]
pub struct CompactnessRow {
    /// Total eigen maps.
    pub components: usize,
    pub eigen_textures: usize,
    pub eigen_warps: usize,
    /// Ours with Poisson warping, texture domain (mean over the training frames).
    pub ours: Scores,
    /// Ours with direct warping.
    pub ours_direct: Scores,
    /// Naive PCA with `components` eigen textures.
    pub naive: Scores,
    /// Image domain against renders of the input textures, on the image frames.
    pub image: Option<ImageScores>,
}

/// 4. One held-out fraction.
#[derive(Debug, Clone, Serialize)]
pub struct GeneralisationRow {
    pub held_out_fraction: f64,
    pub training_frames: usize,
    /// Frames projected (the held-out ones; every frame at fraction 0).
    pub test_frames: Vec<String>,
    pub reference: String,
    /// Texture domain, mean over the test frames.
    pub ours: Scores,
    pub naive: Scores,
    /// Image domain (against renders of the input textures) on the first test frames.
    pub image: Option<ImageScores>,
    pub image_frames: usize,
    pub build_seconds: f64,
}

/// 5. One frame with a hole: similarity to the clean frame over the hole's active texels.
#[derive(Debug, Clone, Serialize)]
pub struct CompletionRow {
    pub frame: String,
    pub hole_texels: usize,
    pub completed: Similarity,
    pub mean_texture: Similarity,
    pub holed_input: Similarity,
}

/// 5. Completion of every frame with a hole by the full model.
#[derive(Debug, Clone, Serialize)]
pub struct Completion {
    pub frames: Vec<CompletionRow>,
    /// Means over the frames (`None` without hole frames).
    pub completed: Option<Similarity>,
    pub mean_texture: Option<Similarity>,
    pub holed_input: Option<Similarity>,
}

/// The backward warps of the Poisson model with a number of eigen warps against the true
/// backward flows.
#[derive(Debug, Clone, Serialize)]
pub struct BackwardWarpRow {
    /// Eigen warps used (all of them: the estimated flows themselves).
    pub eigen_warps: usize,
    /// Mean end-point error over the training frames (the reference left out), texels.
    pub end_point_error: f64,
    /// The per-frame median over the texels, mean over the frames.
    pub median_end_point_error: f64,
}

/// Ours at one split of K between eigen textures and eigen warps.
#[derive(Debug, Clone, Serialize)]
pub struct SplitRow {
    pub components: usize,
    pub eigen_textures: usize,
    pub eigen_warps: usize,
    /// Estimated flows (the model of the compactness sweep).
    pub ours: Scores,
    /// The model built on the true flows.
    pub true_warps: Scores,
}

/// 1b. The warps against the truth, where the benchmark knows where each texel's content came
/// from (the capture-like one): how far each capture error moves it, how well the estimated
/// backward warps and their eigen-warp reconstructions follow the true ones, and what ours
/// scores with the true flows in place of the estimated ones and with other splits of K.
#[derive(Debug, Clone, Serialize)]
pub struct WarpTruth {
    pub causes: Vec<CauseRow>,
    pub reference: String,
    pub backward: Vec<BackwardWarpRow>,
    /// The mean length of the true backward flows (the error of a zero flow), texels.
    pub backward_zero_flow: f64,
    pub backward_zero_flow_median: f64,
    /// The model built on the true flows (one alignment, to the frame closest to the mean).
    pub true_warps_reference: String,
    pub true_warps_all_components: Scores,
    /// Share of the variance of the input textures (about their mean) left after aligning them
    /// with the estimated flows and with the true ones (Poisson warping).
    pub aligned_variance_share: f64,
    pub true_aligned_variance_share: f64,
    pub splits: Vec<SplitRow>,
}

/// Wall-clock seconds of each part.
#[derive(Debug, Clone, Default, Serialize)]
pub struct EvalTimings {
    pub reading: f64,
    pub builds: f64,
    pub flow_accuracy: f64,
    pub compactness_texture: f64,
    pub warp_truth: f64,
    pub compactness_image: f64,
    pub generalisation: f64,
    pub completion: f64,
    pub total: f64,
}

/// The evaluation's result: everything the report holds, and the example images.
#[derive(Debug, Serialize)]
pub struct AppearanceEval {
    pub frames: usize,
    pub width: usize,
    pub height: usize,
    pub active_texels: usize,
    /// Frames every model may use (those without a hole).
    pub complete_frames: usize,
    pub hole_frames: Vec<String>,
    /// The input frames against their clean truth (texture domain, mean over the frames without
    /// a hole): how far the benchmark's degradation takes them.
    pub input_vs_clean: Similarity,
    pub options: AppearanceEvalOptions,
    /// Frames of the image domain of the compactness sweep.
    pub image_frames: Vec<String>,
    pub flow: FlowAccuracy,
    /// The warps against the truth (`None` unless the benchmark knows each texel's content
    /// displacement).
    pub warp_truth: Option<WarpTruth>,
    pub warping: Vec<WarpingRow>,
    pub build: BuildReport,
    pub compactness: Vec<CompactnessRow>,
    pub generalisation: Vec<GeneralisationRow>,
    pub completion: Completion,
    /// The interpolation example's two frames (blended at w = 0.5).
    pub interpolation_frames: Option<(String, String)>,
    pub seconds: EvalTimings,
    /// Example images, each a row of textures side by side: `reconstruction` (ours at a few K
    /// and the input), `interpolation` (frame a, linear blend, ours, frame b), `completion`
    /// (holed input, completed, clean) and `renders` (one view: input, ours, naive).
    #[serde(skip)]
    pub images: Vec<(String, TextureImage)>,
}

/// The mean of several similarities (fixed order).
fn mean_similarity(v: &[Similarity]) -> Similarity {
    let n = v.len().max(1) as f64;
    Similarity { mse: v.iter().map(|s| s.mse).sum::<f64>() / n, ssim: v.iter().map(|s| s.ssim).sum::<f64>() / n }
}

fn mean_scores(v: &[Scores]) -> Scores {
    let input: Vec<Similarity> = v.iter().map(|s| s.input).collect();
    let clean: Vec<Similarity> = v.iter().map(|s| s.clean).collect();
    Scores { input: mean_similarity(&input), clean: mean_similarity(&clean) }
}

/// The frames, clean frames and mask of a generated sequence, read once.
struct Data<'a> {
    frames: &'a dyn AppearanceSequence,
    names: Vec<String>,
    inputs: Vec<TextureImage>,
    cleans: Vec<TextureImage>,
    mask: TexelMask,
    active: Vec<bool>,
    topology: Topology,
    positions: Vec<f32>,
}

impl Data<'_> {
    fn scores(&self, recon: &TextureImage, k: usize) -> Result<Scores> {
        Ok(Scores {
            input: similarity(recon, &self.inputs[k], &self.active)?,
            clean: similarity(recon, &self.cleans[k], &self.active)?,
        })
    }
}

/// A built model with what projecting into it needs.
struct Built {
    model: AppearanceModel,
    report: BuildReport,
    /// Sequence frame of each training frame.
    frames: Vec<usize>,
    seconds: f64,
}

impl Built {
    fn reference(&self) -> usize {
        self.frames[self.model.reference()]
    }
}

fn build(
    data: &Data<'_>,
    frames: &[usize],
    warping: Warping,
    opts: &AppearanceEvalOptions,
    flow: &MaskedFlowEstimator<'_>,
    progress: &dyn Progress,
) -> Result<Built> {
    let t = Instant::now();
    let textures: Vec<TextureImage> = frames.iter().map(|&k| data.inputs[k].clone()).collect();
    let names: Vec<String> = frames.iter().map(|&k| data.names[k].clone()).collect();
    let options = AppearanceOptions {
        lambda: opts.lambda,
        warping,
        max_medoid_iterations: opts.medoid_iterations,
        ..AppearanceOptions::default()
    };
    let mask = &data.mask;
    let estimate = |r: &TextureImage, t: &TextureImage| flow(r, t, mask);
    let (model, report) = build_appearance_model(&textures, &names, mask, &options, &estimate, progress)?;
    Ok(Built { model, report, frames: frames.to_vec(), seconds: t.elapsed().as_secs_f64() })
}

/// End-point errors of `flow(reference, k)` against the truth over `frames` (the reference
/// skipped).
fn flow_errors(
    data: &Data<'_>,
    reference: usize,
    frames: &[usize],
    flow: &MaskedFlowEstimator<'_>,
    progress: &dyn Progress,
    label: &str,
) -> Result<EndPointErrors> {
    let targets: Vec<usize> = frames.iter().copied().filter(|&k| k != reference).collect();
    progress.start(label, targets.len() as u64);
    let defined = data.frames.flow_defined(reference);
    let active = |i: usize| data.mask.is_active(i) && defined.is_none_or(|d| d[i]);
    let pairs: Vec<(f64, f64)> = targets
        .par_iter()
        .map(|&k| {
            let est = flow(&data.inputs[reference], &data.inputs[k], &data.mask)?;
            let truth = data.frames.true_flow(reference, k).ok_or_else(|| {
                Error::Unsuitable(format!("{}: the benchmark does not know the true flow", data.frames.source()))
            })??;
            let zero = FlowField::zeros(truth.width, truth.height);
            progress.advance(1);
            Ok((est.end_point_error(&truth, active), zero.end_point_error(&truth, active)))
        })
        .collect::<Result<_>>()?;
    progress.finish();
    let mut e: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let n = e.len().max(1) as f64;
    let mean = e.iter().sum::<f64>() / n;
    let zero_flow_mean = pairs.iter().map(|p| p.1).sum::<f64>() / n;
    e.sort_by(f64::total_cmp);
    let median = if e.is_empty() { 0.0 } else { e[e.len() / 2] };
    Ok(EndPointErrors { frames: e.len(), mean, median, max: e.last().copied().unwrap_or(0.0), zero_flow_mean })
}

/// Sum over frames of the squared distance of each vector from the vectors' mean.
fn total_variance(vectors: &[Vec<f32>]) -> f64 {
    let n = vectors.first().map_or(0, Vec::len);
    let f = vectors.len().max(1) as f64;
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mean = vectors.iter().map(|v| v[i] as f64).sum::<f64>() / f;
            vectors.iter().map(|v| (v[i] as f64 - mean).powi(2)).sum::<f64>()
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// The warps against the truth (see [`WarpTruth`]).
fn warp_truth(
    data: &Data<'_>,
    complete: &[usize],
    poisson: &Built,
    ks: &[usize],
    causes: &[CauseRow],
    opts: &AppearanceEvalOptions,
    progress: &dyn Progress,
) -> Result<WarpTruth> {
    let n = complete.len();
    let reference = poisson.reference();
    let truth_of = |from: usize, to: usize| -> Result<FlowField> {
        data.frames.true_flow(from, to).ok_or_else(|| {
            Error::Unsuitable(format!("{}: the benchmark does not know the true flow", data.frames.source()))
        })?
    };
    let keep_of = |k: usize| {
        let defined = data.frames.flow_defined(k);
        move |i: usize| data.mask.is_active(i) && defined.is_none_or(|d| d[i])
    };
    // Backward warps with each number of eigen warps of the sweep, and all of them.
    let mut counts: Vec<usize> = ks.iter().map(|&k| split_components(k).1).collect();
    counts.push(poisson.model.n_warps());
    counts.sort_unstable();
    counts.dedup();
    progress.start("warps against the truth: backward warps", n as u64);
    let others: Vec<usize> = (0..n).filter(|&i| complete[i] != reference).collect();
    let per_frame: Vec<(Vec<[f64; 2]>, [f64; 2])> = others
        .par_iter()
        .map(|&i| {
            let k = complete[i];
            let truth = truth_of(k, reference)?;
            let keep = keep_of(k);
            let (_, wc) = poisson.model.frame_coefficients(i)?;
            let errs = counts
                .iter()
                .map(|&kw| Ok(end_point_errors(&poisson.model.backward_warp(&wc[..kw.min(wc.len())])?, &truth, keep)))
                .collect::<Result<Vec<_>>>()?;
            let zero = end_point_errors(&FlowField::zeros(truth.width, truth.height), &truth, keep);
            progress.advance(1);
            Ok((errs, zero))
        })
        .collect::<Result<_>>()?;
    progress.finish();
    let m = others.len().max(1) as f64;
    let backward = counts
        .iter()
        .enumerate()
        .map(|(j, &kw)| BackwardWarpRow {
            eigen_warps: kw,
            end_point_error: per_frame.iter().map(|p| p.0[j][0]).sum::<f64>() / m,
            median_end_point_error: per_frame.iter().map(|p| p.0[j][1]).sum::<f64>() / m,
        })
        .collect();
    let backward_zero_flow = per_frame.iter().map(|p| p.1[0]).sum::<f64>() / m;
    let backward_zero_flow_median = per_frame.iter().map(|p| p.1[1]).sum::<f64>() / m;

    // The model on the true flows: each texture is found among the inputs by its texels; a
    // flow to a texture that is not an input (an aligned one) goes to the reference, the first
    // texture of the one alignment's forward flows.
    let find = |t: &TextureImage| complete.iter().copied().find(|&k| data.inputs[k].data() == t.data());
    let last_reference = std::sync::Mutex::new(None::<usize>);
    let oracle = |a: &TextureImage, b: &TextureImage, _: &TexelMask| -> surfcap_appearance::Result<FlowField> {
        let bad = |what: &str| surfcap_appearance::Error::Invalid(format!("true flows: {what}"));
        let ka = find(a).ok_or_else(|| bad("a texture that is not an input"))?;
        let kb = match find(b) {
            Some(kb) => {
                *last_reference.lock().expect("not poisoned") = Some(ka);
                kb
            }
            None => last_reference
                .lock()
                .expect("not poisoned")
                .ok_or_else(|| bad("an aligned texture before any alignment"))?,
        };
        truth_of(ka, kb).map_err(|e| bad(&e.to_string()))
    };
    let one_alignment = AppearanceEvalOptions { medoid_iterations: 1, ..opts.clone() };
    let true_model = build(data, complete, Warping::Poisson, &one_alignment, &oracle, progress)?;
    let sweep = |built: &Built, kt: usize, kw: usize| -> Result<Scores> {
        let rows: Vec<Scores> = (0..n)
            .into_par_iter()
            .map(|i| {
                let (tc, wc) = built.model.frame_coefficients(i)?;
                let recon = built.model.instantiate(&tc[..kt.min(tc.len())], &wc[..kw.min(wc.len())])?;
                data.scores(&recon, complete[i])
            })
            .collect::<Result<_>>()?;
        Ok(mean_scores(&rows))
    };
    let true_warps_all_components = sweep(&true_model, usize::MAX, usize::MAX)?;
    // Variance left after alignment: the aligned textures are the models' texture data.
    let inputs: Vec<Vec<f32>> = complete.iter().map(|&k| active_vector_of(&data.inputs[k], &data.mask)).collect();
    let input_variance = total_variance(&inputs).max(f64::MIN_POSITIVE);
    let aligned_variance = |built: &Built| -> Result<f64> {
        let aligned: Vec<Vec<f32>> = (0..n)
            .map(|i| {
                let (tc, _) = built.model.frame_coefficients(i)?;
                Ok(active_vector_of(&built.model.aligned_texture(tc)?, &data.mask))
            })
            .collect::<Result<_>>()?;
        Ok(total_variance(&aligned) / input_variance)
    };
    let aligned_variance_share = aligned_variance(poisson)?;
    let true_aligned_variance_share = aligned_variance(&true_model)?;
    // Splits of K: no warp, the default third, half.
    progress.start("warps against the truth: splits of K", ks.len() as u64);
    let mut splits = Vec::new();
    for &k in ks {
        let mut kws = vec![0, split_components(k).1, k / 2];
        kws.dedup();
        for kw in kws {
            let kt = k - kw;
            splits.push(SplitRow {
                components: k,
                eigen_textures: kt,
                eigen_warps: kw,
                ours: sweep(poisson, kt, kw)?,
                true_warps: sweep(&true_model, kt, kw)?,
            });
        }
        progress.advance(1);
    }
    progress.finish();
    Ok(WarpTruth {
        causes: causes.to_vec(),
        reference: data.names[reference].clone(),
        backward,
        backward_zero_flow,
        backward_zero_flow_median,
        true_warps_reference: data.names[true_model.reference()].clone(),
        true_warps_all_components,
        aligned_variance_share,
        true_aligned_variance_share,
        splits,
    })
}

/// Mean and median end-point error of `flow` against `truth` over the texels `keep` selects.
fn end_point_errors(flow: &FlowField, truth: &FlowField, keep: impl Fn(usize) -> bool) -> [f64; 2] {
    let mut e: Vec<f64> = (0..flow.u.len())
        .filter(|&i| keep(i))
        .map(|i| ((flow.u[i] - truth.u[i]) as f64).hypot((flow.v[i] - truth.v[i]) as f64))
        .collect();
    if e.is_empty() {
        return [0.0, 0.0];
    }
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    e.sort_by(f64::total_cmp);
    [mean, e[e.len() / 2]]
}

/// The active texels of a texture, channel after channel.
fn active_vector_of(t: &TextureImage, mask: &TexelMask) -> Vec<f32> {
    (0..t.channels()).flat_map(|c| mask.gather(t.plane(c))).collect()
}

/// Renders of a texture from every camera.
fn renders(data: &Data<'_>, texture: &TextureImage, cameras: &[Camera]) -> Result<Vec<Render>> {
    Ok(render_views(&data.topology, &data.positions, texture, cameras)?)
}

/// Similarity of renders to the reference renders over the union of their silhouettes, mean
/// over the views.
fn image_similarity(reference: &[Render], renders: &[Render]) -> Result<Similarity> {
    let per_view: Vec<Similarity> = reference
        .iter()
        .zip(renders)
        .map(|(a, b)| {
            let mask: Vec<bool> = a.mask.iter().zip(&b.mask).map(|(x, y)| *x || *y).collect();
            Ok(similarity(&b.image, &a.image, &mask)?)
        })
        .collect::<Result<_>>()?;
    Ok(mean_similarity(&per_view))
}

/// Evenly spaced picks of `n` of `items` (all when there are fewer).
fn evenly_spaced(items: &[usize], n: usize) -> Vec<usize> {
    if n >= items.len() {
        return items.to_vec();
    }
    (0..n).map(|i| items[i * items.len() / n]).collect()
}

/// Images side by side (same height and channels).
fn side_by_side(images: &[&TextureImage]) -> Result<TextureImage> {
    let h = images[0].height();
    let c = images[0].channels();
    let w: usize = images.iter().map(|i| i.width()).sum();
    let mut out = TextureImage::zeros(w, h, c);
    let mut x0 = 0;
    for img in images {
        for ch in 0..c {
            let src = img.plane(ch);
            let dst = out.plane_mut(ch);
            for y in 0..h {
                dst[y * w + x0..y * w + x0 + img.width()].copy_from_slice(&src[y * img.width()..(y + 1) * img.width()]);
            }
        }
        x0 += img.width();
    }
    Ok(out)
}

/// A held-out frame projected into the model (4.4.3) and instantiated with every component:
/// forward flow from the reference texture, aligned by `warper` (the model's warping),
/// backward flow, projection. The model's own reference frame keeps a zero warp, as in the
/// build.
fn project_frame(
    built: &Built,
    data: &Data<'_>,
    warper: &TextureWarper,
    k: usize,
    flow: &MaskedFlowEstimator<'_>,
) -> Result<TextureImage> {
    let texture = &data.inputs[k];
    let reference = &data.inputs[built.reference()];
    let (aligned, backward) = if k == built.reference() {
        (texture.clone(), FlowField::zeros(texture.width(), texture.height()))
    } else {
        let forward = flow(reference, texture, &data.mask)?;
        let aligned = warper.warp(texture, &forward)?;
        let backward = flow(texture, &aligned, &data.mask)?;
        (aligned, backward)
    };
    let (tc, wc) = built.model.project(&aligned, &backward)?;
    Ok(built.model.instantiate(&tc, &wc)?)
}

/// Runs the evaluation on `frames` (see the module documentation). `flow` is the estimator of
/// every build and projection (`flow(reference, target, domain)`), `flow_name` its description
/// for the report; `second_flow` an optional other estimator measured on the first
/// `second_flow_frames` frames.
pub fn appearance_eval(
    frames: &dyn AppearanceSequence,
    opts: &AppearanceEvalOptions,
    flow: &MaskedFlowEstimator<'_>,
    flow_name: &str,
    second_flow: Option<(&MaskedFlowEstimator<'_>, &str)>,
    progress: &dyn Progress,
) -> Result<AppearanceEval> {
    let start = Instant::now();
    let mut seconds = EvalTimings::default();
    if let Some(f) = opts.held_out.iter().find(|f| !(0.0..1.0).contains(*f)) {
        return Err(Error::parameter("--held-out", Some(f.to_string()), "expected fractions in [0, 1)"));
    }
    if opts.views == 0 || opts.image_size < 8 {
        return Err(Error::parameter(
            "--views",
            Some(format!("{} at {} pixels", opts.views, opts.image_size)),
            "expected at least one view of at least 8 pixels",
        ));
    }
    let f = frames.frames();
    let (w, h) = (frames.width(), frames.height());
    let (topology, positions) = frames.mesh()?;
    let atlas = topology
        .uv()
        .ok_or_else(|| Error::Unsuitable(format!("{}: the mesh has no UV atlas", frames.mesh_source())))?;
    let mask = TexelMask::from_atlas(atlas, w, h, opts.dilation)?;
    let active: Vec<bool> = (0..w * h).map(|i| mask.is_active(i)).collect();
    let t = Instant::now();
    progress.start("reading the generated frames", f as u64);
    let read: Vec<(TextureImage, TextureImage)> = (0..f)
        .into_par_iter()
        .map(|k| {
            let pair = frames.frame_and_clean(k)?;
            progress.advance(1);
            Ok(pair)
        })
        .collect::<Result<_>>()?;
    progress.finish();
    let (inputs, cleans): (Vec<_>, Vec<_>) = read.into_iter().unzip();
    seconds.reading = t.elapsed().as_secs_f64();
    let names: Vec<String> = frames.names();
    let data = Data { frames, names, inputs, cleans, mask, active, topology, positions };
    let hole_frames = frames.hole_frames();
    let complete: Vec<usize> = (0..f).filter(|k| !hole_frames.contains(k)).collect();
    if complete.len() < 3 {
        return Err(Error::Unsuitable(format!(
            "{}: {} frames without a hole: the evaluation needs at least 3",
            frames.source(),
            complete.len()
        )));
    }
    let n = complete.len();
    let input_vs_clean = mean_similarity(
        &complete
            .par_iter()
            .map(|&k| Ok(similarity(&data.inputs[k], &data.cleans[k], &data.active)?))
            .collect::<Result<Vec<_>>>()?,
    );

    // 2. The full models, Poisson and direct (they share the medoid shift's direct search and
    // so its forward flows).
    let t = Instant::now();
    let poisson = build(&data, &complete, Warping::Poisson, opts, flow, progress)?;
    let direct = build(&data, &complete, Warping::Direct, opts, flow, progress)?;
    seconds.builds = t.elapsed().as_secs_f64();

    // 1. Flow accuracy of the Poisson build's forward flows.
    let t = Instant::now();
    let reference = poisson.reference();
    let knows_flow = frames.true_flow(reference, reference).is_some();
    let errors = if knows_flow {
        Some(flow_errors(&data, reference, &complete, flow, progress, "forward flows against the truth")?)
    } else {
        None
    };
    let (second_estimator, second) = match second_flow {
        Some((est, name)) if opts.second_flow_frames > 0 && knows_flow => {
            let some: Vec<usize> = evenly_spaced(
                &complete.iter().copied().filter(|&k| k != reference).collect::<Vec<_>>(),
                opts.second_flow_frames,
            );
            let e = flow_errors(&data, reference, &some, est, progress, &format!("forward flows ({name})"))?;
            (Some(name.to_string()), Some(e))
        }
        _ => (None, None),
    };
    let flow_accuracy = FlowAccuracy {
        estimator: flow_name.to_string(),
        reference: data.names[reference].clone(),
        errors,
        second_estimator,
        second,
    };
    seconds.flow_accuracy = t.elapsed().as_secs_f64();

    // 3. Compactness: the sweep of K, texture domain on every training frame.
    let t = Instant::now();
    let mut ks: Vec<usize> = opts.components.iter().copied().filter(|&k| k >= 1 && k < n - 1).collect();
    ks.push(n - 1);
    ks.sort_unstable();
    ks.dedup();
    let naive = NaiveTexturePca::new(
        &complete.iter().map(|&k| data.inputs[k].clone()).collect::<Vec<_>>(),
        &data.mask,
        usize::MAX,
    )?;
    // Ours at K = (kt, kw), and with every component; rows of [K][frame].
    let sweep = |built: &Built, kt: usize, kw: usize| -> Result<Vec<Scores>> {
        (0..n)
            .into_par_iter()
            .map(|i| {
                let (tc, wc) = built.model.frame_coefficients(i)?;
                let recon = built.model.instantiate(&tc[..kt.min(tc.len())], &wc[..kw.min(wc.len())])?;
                data.scores(&recon, complete[i])
            })
            .collect()
    };
    let mut warping = Vec::new();
    for built in [&poisson, &direct] {
        let all = sweep(built, usize::MAX, usize::MAX)?;
        warping.push(WarpingRow {
            warping: built.model.warping(),
            reference: data.names[built.reference()].clone(),
            eigen_textures: built.model.n_textures(),
            eigen_warps: built.model.n_warps(),
            all_components: mean_scores(&all),
            build_seconds: built.seconds,
        });
    }
    progress.start("compactness: texture domain", ks.len() as u64);
    let mut compactness = Vec::new();
    for &k in &ks {
        let (kt, kw) = split_components(k);
        let ours = mean_scores(&sweep(&poisson, kt, kw)?);
        let ours_direct = mean_scores(&sweep(&direct, kt, kw)?);
        let naive_scores: Vec<Scores> = (0..n)
            .into_par_iter()
            .map(|i| data.scores(&naive.reconstruct(i, k)?, complete[i]))
            .collect::<Result<_>>()?;
        compactness.push(CompactnessRow {
            components: k,
            eigen_textures: kt,
            eigen_warps: kw,
            ours,
            ours_direct,
            naive: mean_scores(&naive_scores),
            image: None,
        });
        progress.advance(1);
    }
    progress.finish();
    seconds.compactness_texture = t.elapsed().as_secs_f64();

    // 1b. The warps against the truth.
    let t = Instant::now();
    let warp_truth = match frames.displacement_causes() {
        Some(causes) => Some(warp_truth(&data, &complete, &poisson, &ks, causes, opts, progress)?),
        None => None,
    };
    seconds.warp_truth = t.elapsed().as_secs_f64();

    // 3. Compactness, image domain on evenly spaced training frames.
    let t = Instant::now();
    let lens = Lens { fov_y_deg: 40.0, width: opts.image_size, height: opts.image_size };
    let cameras = cameras_around_mesh(&data.positions, [0.0, 1.0, 0.0], opts.views, 10.0, lens);
    let image_slots: Vec<usize> =
        if opts.image_frames == 0 { Vec::new() } else { evenly_spaced(&(0..n).collect::<Vec<_>>(), opts.image_frames) };
    let mut images = Vec::new();
    if !image_slots.is_empty() {
        progress.start("compactness: image domain", (ks.len() * image_slots.len()) as u64);
        let truth: Vec<Vec<Render>> =
            image_slots.iter().map(|&i| renders(&data, &data.inputs[complete[i]], &cameras)).collect::<Result<_>>()?;
        for (row, &k) in compactness.iter_mut().zip(&ks) {
            let (kt, kw) = split_components(k);
            let mut ours = Vec::new();
            let mut naive_s = Vec::new();
            for (j, &i) in image_slots.iter().enumerate() {
                let (tc, wc) = poisson.model.frame_coefficients(i)?;
                let recon = poisson.model.instantiate(&tc[..kt.min(tc.len())], &wc[..kw.min(wc.len())])?;
                let ours_r = renders(&data, &recon, &cameras)?;
                ours.push(image_similarity(&truth[j], &ours_r)?);
                let naive_r = renders(&data, &naive.reconstruct(i, k)?, &cameras)?;
                naive_s.push(image_similarity(&truth[j], &naive_r)?);
                if j == 0 && k == ks[ks.len() / 2] {
                    let row = side_by_side(&[&truth[0][0].image, &ours_r[0].image, &naive_r[0].image])?;
                    images.push((format!("renders-K{k}"), row));
                }
                progress.advance(1);
            }
            row.image = Some(ImageScores { ours: mean_similarity(&ours), naive: mean_similarity(&naive_s) });
        }
        progress.finish();
    }
    seconds.compactness_image = t.elapsed().as_secs_f64();
    // Fig. 4.8: one frame with few, some and every eigen map, beside its input.
    {
        let i = n / 2;
        let (tc, wc) = poisson.model.frame_coefficients(i)?;
        let mut row = Vec::new();
        for &k in [ks[0], ks[ks.len() / 2], ks[ks.len() - 1]].iter() {
            let (kt, kw) = split_components(k);
            row.push(poisson.model.instantiate(&tc[..kt.min(tc.len())], &wc[..kw.min(wc.len())])?);
        }
        row.push(data.inputs[complete[i]].clone());
        let refs: Vec<&TextureImage> = row.iter().collect();
        images.push((
            format!("reconstruction-{}-K{}-{}-{}", data.names[complete[i]], ks[0], ks[ks.len() / 2], ks[ks.len() - 1]),
            side_by_side(&refs)?,
        ));
    }

    // 4. Generalisation: nested held-out sets from one seeded permutation.
    let t = Instant::now();
    let mut order: Vec<usize> = complete.clone();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed));
    let mut generalisation = Vec::new();
    for &fraction in &opts.held_out {
        let held = (fraction * n as f64).round() as usize;
        let held = held.min(n - 2);
        let tb = Instant::now();
        let (built, test): (Option<Built>, Vec<usize>) = if held == 0 {
            (None, complete.clone())
        } else {
            let mut test: Vec<usize> = order[..held].to_vec();
            test.sort_unstable();
            let train: Vec<usize> = complete.iter().copied().filter(|k| !test.contains(k)).collect();
            (Some(build(&data, &train, Warping::Poisson, opts, flow, progress)?), test)
        };
        let build_seconds = tb.elapsed().as_secs_f64();
        let model = built.as_ref().unwrap_or(&poisson);
        let naive_model = match &built {
            Some(b) => Some(NaiveTexturePca::new(
                &b.frames.iter().map(|&k| data.inputs[k].clone()).collect::<Vec<_>>(),
                &data.mask,
                usize::MAX,
            )?),
            None => None,
        };
        let naive_model = naive_model.as_ref().unwrap_or(&naive);
        let warper = TextureWarper::new(model.model.warping(), &data.mask, model.model.lambda())?;
        progress.start(&format!("generalisation: {} held-out frames projected", test.len()), test.len() as u64);
        let projected: Vec<(TextureImage, TextureImage)> = test
            .par_iter()
            .map(|&k| {
                let ours = project_frame(model, &data, &warper, k, flow)?;
                let naive_r = naive_model.reconstruct_texture(&data.inputs[k], usize::MAX)?;
                progress.advance(1);
                Ok((ours, naive_r))
            })
            .collect::<Result<_>>()?;
        progress.finish();
        let scores: Vec<(Scores, Scores)> = projected
            .par_iter()
            .zip(&test)
            .map(|((o, p), &k)| Ok((data.scores(o, k)?, data.scores(p, k)?)))
            .collect::<Result<_>>()?;
        let ours: Vec<Scores> = scores.iter().map(|s| s.0).collect();
        let naive_s: Vec<Scores> = scores.iter().map(|s| s.1).collect();
        let shown = opts.image_frames.min(test.len());
        let image = if shown == 0 {
            None
        } else {
            let picks = evenly_spaced(&(0..test.len()).collect::<Vec<_>>(), shown);
            let mut o = Vec::new();
            let mut p = Vec::new();
            for &j in &picks {
                let truth = renders(&data, &data.inputs[test[j]], &cameras)?;
                o.push(image_similarity(&truth, &renders(&data, &projected[j].0, &cameras)?)?);
                p.push(image_similarity(&truth, &renders(&data, &projected[j].1, &cameras)?)?);
            }
            Some(ImageScores { ours: mean_similarity(&o), naive: mean_similarity(&p) })
        };
        generalisation.push(GeneralisationRow {
            held_out_fraction: fraction,
            training_frames: model.frames.len(),
            test_frames: test.iter().map(|&k| data.names[k].clone()).collect(),
            reference: data.names[model.reference()].clone(),
            ours: mean_scores(&ours),
            naive: mean_scores(&naive_s),
            image,
            image_frames: shown,
            build_seconds: if built.is_some() { build_seconds } else { 0.0 },
        });
    }
    seconds.generalisation = t.elapsed().as_secs_f64();

    // 5. Completion of the hole frames by the full model.
    let t = Instant::now();
    progress.start("completing the frames with holes", hole_frames.len() as u64);
    let mean_texture = poisson.model.instantiate(&[], &[])?;
    let completed: Vec<(CompletionRow, TextureImage)> = hole_frames
        .par_iter()
        .map(|&k| {
            let hole = frames.hole(k).ok_or_else(|| {
                Error::Unsuitable(format!("frame {}: listed as holed but without a hole layer", data.names[k]))
            })?;
            let observed: Vec<bool> = hole.iter().map(|&x| !x).collect();
            let inside: Vec<bool> = hole.iter().zip(&data.active).map(|(x, a)| *x && *a).collect();
            let done = poisson.model.complete(&data.inputs[k], &observed, flow)?;
            let row = CompletionRow {
                frame: data.names[k].clone(),
                hole_texels: inside.iter().filter(|&&x| x).count(),
                completed: similarity(&done, &data.cleans[k], &inside)?,
                mean_texture: similarity(&mean_texture, &data.cleans[k], &inside)?,
                holed_input: similarity(&data.inputs[k], &data.cleans[k], &inside)?,
            };
            progress.advance(1);
            Ok((row, done))
        })
        .collect::<Result<_>>()?;
    progress.finish();
    if let Some((row, done)) = completed.first() {
        let k = hole_frames[0];
        images.push((format!("completion-{}", row.frame), side_by_side(&[&data.inputs[k], done, &data.cleans[k]])?));
    }
    let rows: Vec<CompletionRow> = completed.into_iter().map(|c| c.0).collect();
    let mean_of = |f: fn(&CompletionRow) -> Similarity| {
        (!rows.is_empty()).then(|| mean_similarity(&rows.iter().map(f).collect::<Vec<_>>()))
    };
    let completion = Completion {
        completed: mean_of(|r| r.completed),
        mean_texture: mean_of(|r| r.mean_texture),
        holed_input: mean_of(|r| r.holed_input),
        frames: rows,
    };
    seconds.completion = t.elapsed().as_secs_f64();

    // 6. Interpolation example: the first training frame and the middle one.
    let (a, b) = (0, n / 2);
    let ours = poisson.model.interpolate(&[(a, 0.5), (b, 0.5)])?;
    let (ia, ib) = (&data.inputs[complete[a]], &data.inputs[complete[b]]);
    let mut linear = ia.clone();
    linear.data_mut().iter_mut().zip(ib.data()).for_each(|(x, y)| *x = 0.5 * (*x + y));
    images.push((
        format!("interpolation-{}-{}", data.names[complete[a]], data.names[complete[b]]),
        side_by_side(&[ia, &linear, &ours, ib])?,
    ));

    seconds.total = start.elapsed().as_secs_f64();
    Ok(AppearanceEval {
        frames: f,
        width: w,
        height: h,
        active_texels: data.mask.len(),
        complete_frames: n,
        hole_frames: hole_frames.iter().map(|&k| data.names[k].clone()).collect(),
        input_vs_clean,
        options: opts.clone(),
        image_frames: image_slots.iter().map(|&i| data.names[complete[i]].clone()).collect(),
        flow: flow_accuracy,
        warp_truth,
        warping,
        build: poisson.report.clone(),
        compactness,
        generalisation,
        completion,
        interpolation_frames: Some((data.names[complete[a]].clone(), data.names[complete[b]].clone())),
        seconds,
        images,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_spaced_picks_spread_over_the_items() {
        assert_eq!(evenly_spaced(&[10, 11, 12, 13, 14, 15, 16, 17], 4), vec![10, 12, 14, 16]);
        assert_eq!(evenly_spaced(&[1, 2], 5), vec![1, 2]);
    }

    #[test]
    fn images_are_put_side_by_side() {
        let a = TextureImage::from_planes(2, 1, 1, vec![1.0, 2.0]).unwrap();
        let b = TextureImage::from_planes(1, 1, 1, vec![3.0]).unwrap();
        let r = side_by_side(&[&a, &b]).unwrap();
        assert_eq!((r.width(), r.height()), (3, 1));
        assert_eq!(r.data(), &[1.0, 2.0, 3.0]);
    }
}
