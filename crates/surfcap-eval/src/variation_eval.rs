//! Motion variation synthesis evaluated (thesis chapter 6, 6.5-6.8), on a
//! subject's sequences of one motion type with one [`VariationModel`] (a GPDM per body part,
//! the first two sequences blended at w = 0.5 and added to training, 6.7):
//!
//! 1. **Reconstruction (Fig. 6.4)**: per part and overall, the mean per-vertex distance between
//!    the training frames (aligned body-frame poses, re-timed onto the reference) and the GPDM's
//!    reconstruction GP mean at the learnt latents (eq. 6.12), against PCA of each part's
//!    training rows with as many components as latent dimensions (d = 3). The reconstruction GP
//!    nearly interpolates its training frames (as the transfer evaluation found), so the same comparison is
//!    made on **held-out frames**: a second set of GPDMs learns only the even frames of every
//!    prepared sequence (its own displacement scales, eq. 6.1-6.7 unchanged) and the odd frames
//!    with two neighbours are reconstructed. A held-out frame needs a latent point: it is the
//!    midpoint of the learnt latents of its two neighbouring training frames in time (the
//!    GPDM's dynamics make successive latents close, and this uses nothing of the held-out
//!    frame; optimising the latent to fit the held-out frame would use its own pose and
//!    favour the GPDM). PCA projects the held-out rows on the components of the training rows
//!    (which does use the frame: PCA's held-out error is a lower bound on what it would do
//!    without it). "Overall" stitches the parts' reconstructions into one mesh (the stitcher of
//!    chapter 5 that the variants go through) and compares every vertex, for both methods.
//! 2. **Guided latent interpolation (Fig. 6.7)**: the ground truth is the non-linear mesh blend
//!    (eq. 2.45-2.49) of the first two prepared sequences at w = 0.25; direct interpolation of
//!    their learnt latent trajectories at 0.25 is compared with interpolation between the two
//!    learnt trajectories around 0.25 (the first sequence and the learnt w = 0.5 blend), both
//!    through the reconstruction GPs and the stitching; mean per-vertex distance per frame (body
//!    frame, the reference's frames) and overall.
//! 3. **Variation statistics**: for every captured training sequence, `variants` seeded
//!    variants ([`sample_variants`], the library's default HMC options), each judged on five
//!    criteria, with the thresholds stated in [`Criteria`].
//!
//! Datasets: the built-in mannequin driven by CMU subject 16's walk, jog, left and right turns
//! and forward jump ([`cmu_case`]) and the KayKit knight's in-place walks and runs
//! ([`kaykit_case`]: zero travel, six separate body-part meshes, which the parts proposal and
//! the stitcher take as parts without overlap).

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_geometry::root_motion_from_contacts::ContactParams;
use surfcap_geometry::shape_distortion::edge_length_distortion;
use surfcap_learn::Mat;
use surfcap_learn::gpdm::{Gpdm, GpdmOptions};
use surfcap_learn::pca::{Pca, PcaMethod};
use surfcap_mesh::{NoProgress, Subject, Topology, UpAxis};
use surfcap_transfer::BodyParts;
use surfcap_transfer::body_parts_proposal::{Method as ProposalMethod, propose};
use surfcap_transfer::part_stitching::Stitcher;
use surfcap_variation::VariationModel;
use surfcap_variation::foot_skate_cleanup::CleanupReport;
use surfcap_variation::motion_parametrisation::{blend_ladder, bounding_rungs, interpolate_latents};
use surfcap_variation::motion_preparation::{
    PreparationOptions, PreparedMotions, SequenceOrigin, TimeAlignment, TrainingSequence, blend_sequences,
    displacement_scales, part_matrix, part_vectors, prepare,
};
use surfcap_variation::variation_model::TrainOptions;
use surfcap_variation::variation_sampling::{
    ChainStart, ChainSummary, SamplingOptions, VariantPath, clean_up_variants, in_place_ground, place_variant,
    reconstruct_aligned, sample_variants,
};

use crate::error::{Error, Result};

/// CMU clips (in `cmu_bvh`) of the CMU case: walk, jog (the pair blended), left turn, right
/// turn, forward jump.
pub const CMU_CLIPS: [&str; 5] = ["16_15", "16_36", "16_17", "16_19", "16_07"];
/// KayKit knight clips of the KayKit case: the pair blended first.
pub const KAYKIT_CLIPS: [&str; 5] = ["Walking_A", "Running_A", "Walking_B", "Walking_C", "Running_B"];

/// A subject whose sequences are all learnt by one model: the first is the reference (every
/// sequence is re-timed onto it), the first two are blended (6.7).
pub struct VariationCase {
    pub name: String,
    pub subject: Subject,
    pub parts: BodyParts,
}

/// Five body parts proposed for the subject (two rings of overlap), as the transfer evaluation
/// and `surfcap parts propose` make them.
fn proposed_parts(s: &Subject) -> Result<BodyParts> {
    propose(s, ProposalMethod::Auto, 5, 2)
        .map(|p| p.0)
        .map_err(|e| Error::Unsuitable(format!("{}: proposing body parts: {e}", s.name)))
}

/// The average mannequin of about `vertices` vertices driven by CMU `clips` (at least two: the
/// first two are blended).
pub fn cmu_case(data: &Path, vertices: usize, clips: &[String]) -> Result<VariationCase> {
    if clips.len() < 2 {
        return Err(Error::parameter("--cmu-clips", None, "expected at least two clips (the first two are blended)"));
    }
    let m = mannequin(&BodyShape::average(), vertices)?;
    let mut made = Vec::new();
    for c in clips {
        let path = data.join("cmu_bvh").join(format!("{c}.bvh"));
        let bvh = read_bvh(&path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        made.push(Clip::from_bvh(&path, &bvh, &m, mpu)?);
    }
    let subject = mannequin_subject("cmu-locomotion", &m, &made, 30.0)?;
    let parts = proposed_parts(&subject)?;
    Ok(VariationCase { name: "cmu".into(), subject, parts })
}

/// The KayKit knight's `clips` (`kaykit_adventurers/knight_<clip>`, at least two: the first two
/// are blended), as they are: in place, six separate meshes.
pub fn kaykit_case(data: &Path, clips: &[String]) -> Result<VariationCase> {
    if clips.len() < 2 {
        return Err(Error::parameter(
            "--kaykit-clips",
            None,
            "expected at least two clips (the first two are blended)",
        ));
    }
    let names: Vec<&str> = clips.iter().map(String::as_str).collect();
    let subject = crate::transfer_eval::kaykit_subject(data, "knight", &names)?;
    let parts = proposed_parts(&subject)?;
    Ok(VariationCase { name: "kaykit".into(), subject, parts })
}

/// Options of [`variation_eval`] (`surfcap eval vary`).
#[derive(Debug, Clone)]
pub struct VariationEvalOptions {
    /// Variants per captured sequence (at least 2, so that criterion (v) has a pair).
    pub variants: usize,
    pub seed: u64,
    /// L-BFGS iterations at most of every GPDM (`None`: the library's default, 400).
    pub iterations: Option<usize>,
    /// Weight of the blend of the first two sequences added to training (6.7: 0.5).
    pub trained_blend_weight: f64,
    /// Weight of the blend that is the ground truth of Fig. 6.7 (0.25).
    pub blend_weight: f64,
    pub sampling: SamplingOptions,
    pub criteria: Criteria,
}

impl Default for VariationEvalOptions {
    fn default() -> Self {
        VariationEvalOptions {
            variants: 5,
            seed: 0,
            iterations: None,
            trained_blend_weight: 0.5,
            blend_weight: 0.25,
            sampling: SamplingOptions::default(),
            criteria: Criteria::default(),
        }
    }
}

/// The thresholds of the variation criteria. Lengths are mean per-vertex distances; `H` is the
/// subject's height (extent of the reference pose along the up axis).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Criteria {
    /// (i) A variant differs from its source: its distance to the source, in the body frame
    /// (aligned poses on the reference's frames) and in the world (own timing), is above
    /// `max(floor_factor x the learnt trajectory's own reconstruction error, min_floor x H)`:
    /// the reconstruction error is what the model gets wrong anyway, so a variant must move
    /// further than that from its source.
    pub floor_factor: f64,
    /// Fraction of H below which two motions count as the same (also criterion (v)).
    pub min_floor: f64,
    /// (ii) A variant is closer (body frame) to its source's learnt reconstruction than to any
    /// other learnt training sequence's (the blends included). No threshold.
    /// (iii) Edge distortion (mean over frames and edges of |l / l0 - 1|, l0 the reference
    /// pose's lengths) of every variant at most (1 + tolerance) x the source's captured frames';
    /// (iv) likewise foot sliding ([`foot_sliding`]).
    pub tolerance: f64,
}

impl Default for Criteria {
    fn default() -> Self {
        Criteria { floor_factor: 2.0, min_floor: 0.001, tolerance: 0.1 }
    }
}

/// A learnt sequence.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceInfo {
    pub name: String,
    /// Frames at its own timing (the learnt sequences all have the reference's).
    pub own_frames: usize,
    pub blend: bool,
}

/// One GPDM fit.
#[derive(Debug, Clone, Serialize)]
pub struct FitSummary {
    pub part: String,
    pub vertices: usize,
    pub iterations: usize,
    pub converged: bool,
    pub objective: f64,
    pub seconds: f64,
}

/// Mean per-vertex reconstruction errors of one part (or of the stitched mesh), Fig. 6.4.
#[derive(Debug, Clone, Serialize)]
pub struct ReconstructionErrors {
    pub part: String,
    pub gpdm_training: f64,
    pub pca_training: f64,
    pub gpdm_held_out: f64,
    pub pca_held_out: f64,
}

/// Fig. 6.4: per part, and the stitched mesh ("overall").
#[derive(Debug, Clone, Serialize)]
pub struct Reconstruction {
    pub latent_dim: usize,
    pub training_frames: usize,
    pub parts: Vec<ReconstructionErrors>,
    pub overall: ReconstructionErrors,
    /// The held-out model: frames it learnt and frames reconstructed, its fits.
    pub held_out_training_frames: usize,
    pub held_out_frames: usize,
    pub held_out_fits: Vec<FitSummary>,
    pub held_out_latent: &'static str,
}

/// Fig. 6.7: direct vs guided latent interpolation against the non-linear mesh blend.
#[derive(Debug, Clone, Serialize)]
pub struct BlendEval {
    pub a: String,
    pub b: String,
    pub w: f64,
    /// The learnt trajectories the guided interpolation goes between (names and weights).
    pub guided_between: [(String, f64); 2],
    /// Mean per-vertex distance to the ground truth per frame (reference frames), body frame.
    pub direct: Vec<f64>,
    pub guided: Vec<f64>,
    pub direct_mean: f64,
    pub guided_mean: f64,
}

/// Pass or fail of the five criteria of one sequence's variants.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Passes {
    pub differs: bool,
    pub closest_to_source: bool,
    pub edge_distortion: bool,
    pub foot_sliding: bool,
    pub distinct: bool,
}

impl Passes {
    pub fn all(&self) -> bool {
        self.differs && self.closest_to_source && self.edge_distortion && self.foot_sliding && self.distinct
    }
    /// Criteria failed.
    pub fn missed(&self) -> usize {
        [self.differs, self.closest_to_source, self.edge_distortion, self.foot_sliding, self.distinct]
            .iter()
            .filter(|p| !**p)
            .count()
    }
}

/// Foot sliding of a motion ([`foot_sliding`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct FootSliding {
    /// Mean horizontal speed of the planted vertices, subject units per second.
    pub speed: f64,
    /// Fraction of frame steps with a planted foot.
    pub contact_fraction: f64,
}

/// The variants of one captured sequence against the criteria.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceVariation {
    pub sequence: String,
    pub variants: usize,
    /// The learnt trajectory's own reconstruction error (body frame; world, own timing).
    pub learnt_error_body: f64,
    pub learnt_error_world: f64,
    pub floor_body: f64,
    pub floor_world: f64,
    /// Per variant: distance to the source (body frame, world).
    pub distance_body: Vec<f64>,
    pub distance_world: Vec<f64>,
    /// Per variant: the nearest other learnt training sequence and the distance to it, body
    /// frame (criterion ii compares it with the distance to the source's learnt reconstruction,
    /// `distance_learnt`).
    pub distance_learnt: Vec<f64>,
    pub nearest_other: Vec<(String, f64)>,
    /// Edge distortion: the source's captured frames, its learnt reconstruction, each variant.
    pub edge_distortion_input: f64,
    pub edge_distortion_learnt: f64,
    pub edge_distortion: Vec<f64>,
    /// Edge distortion of each variant's world frames (after the foot-skate clean-up when
    /// it is on): (iii) is judged on these and on the body-frame poses.
    pub edge_distortion_world: Vec<f64>,
    /// What the sliding is measured against: "the world" for a travelling capture, "the
    /// capture's ground travel" for an in-place one (see [`sliding_ground`]).
    pub sliding_against: &'static str,
    pub sliding_input: FootSliding,
    pub sliding_learnt: FootSliding,
    pub sliding: Vec<FootSliding>,
    /// Per variant, the sliding before the foot-skate clean-up (empty when it is off) and
    /// what the clean-up did (the pinned vertices' drift from their pins before and after).
    pub sliding_before_cleanup: Vec<FootSliding>,
    pub cleanup: Vec<CleanupReport>,
    /// Smallest distance between two variants (body frame).
    pub min_pair_distance: f64,
    pub passes: Passes,
    pub chains: Vec<ChainSummary>,
    pub seconds: f64,
}

/// The latent trajectories of one part, for a Fig. 6.5-like plot.
#[derive(Debug, Clone)]
pub struct PartLatents {
    pub part: String,
    /// Every learnt sequence's trajectory.
    pub learnt: Vec<(String, Mat<f64>)>,
    /// The variants of the reference (first) sequence.
    pub variants: Vec<Mat<f64>>,
}

/// One case's results.
#[derive(Debug, Clone, Serialize)]
pub struct CaseEval {
    pub name: String,
    pub subject: String,
    pub vertices: usize,
    /// Subject height H (units).
    pub height: f64,
    pub units: String,
    pub parts: Vec<String>,
    pub sequences: Vec<SequenceInfo>,
    pub reference_frames: usize,
    pub train_seconds: f64,
    pub fits: Vec<FitSummary>,
    pub reconstruction: Reconstruction,
    pub blend: BlendEval,
    pub variation: Vec<SequenceVariation>,
    /// Criteria failed over all sequences.
    pub missed: usize,
    pub seconds: f64,
    #[serde(skip)]
    pub latents: Vec<PartLatents>,
}

/// The sampling options as reported.
#[derive(Debug, Clone, Serialize)]
pub struct SamplingSettings {
    /// Where the variants go in the world (the world criteria are judged there).
    pub path: VariantPath,
    pub start: ChainStart,
    pub smoothing: usize,
    /// Radius of the moving average over each variant's deviation from the learnt motion
    /// (`surfcap_variation::pose_deviation_smoothing`).
    pub deviation_smoothing: usize,
    pub warmup: usize,
    pub thin: usize,
    pub max_leapfrog: usize,
    pub foot_skate_cleanup: bool,
    /// Whether the clean-up moved the whole body with the planted feet.
    pub move_root: bool,
    /// Whether sampled poses took the learnt motion's stretch (`surfcap_variation::learnt_stretch`).
    pub learnt_stretch: bool,
    /// Whether the clean-up carried the pins with the body (`FootSkateParams::carry_pins`).
    pub carry_pins: bool,
}

/// Result of [`variation_eval`]; serialised, the report `vary.json` without `written`.
#[derive(Debug, Clone, Serialize)]
pub struct VariationEval {
    pub variants: usize,
    pub seed: u64,
    pub iterations: Option<usize>,
    pub trained_blend_weight: f64,
    pub blend_weight: f64,
    pub sampling: SamplingSettings,
    pub criteria: Criteria,
    pub cases: Vec<CaseEval>,
    pub missed: usize,
    pub seconds: f64,
}

/// Mean distance between corresponding vertices of two poses.
pub fn pose_distance(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len() / 3;
    a.chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(p, q)| (0..3).map(|k| ((p[k] - q[k]) as f64).powi(2)).sum::<f64>().sqrt())
        .sum::<f64>()
        / n.max(1) as f64
}

/// Mean per-vertex distance between two motions of one frame count.
pub fn motion_distance<A: AsRef<[f32]> + Sync, B: AsRef<[f32]> + Sync>(a: &[A], b: &[B]) -> f64 {
    let n = a.len().min(b.len()).max(1);
    // Collected, then summed in order: the same bits on any number of threads.
    let d: Vec<f64> = a.par_iter().zip(b).map(|(x, y)| pose_distance(x.as_ref(), y.as_ref())).collect();
    d.iter().sum::<f64>() / n as f64
}

/// Mean per-vertex distance between the vertex columns (the first `3 x vertices`) of two row
/// matrices.
fn rows_vertex_error(a: &Mat<f64>, b: &Mat<f64>, vertices: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..a.nrows() {
        for v in 0..vertices {
            sum += (0..3).map(|k| (a[(i, 3 * v + k)] - b[(i, 3 * v + k)]).powi(2)).sum::<f64>().sqrt();
        }
    }
    sum / (a.nrows() * vertices).max(1) as f64
}

fn height_of(p: &[f32], up: UpAxis) -> impl Fn(u32) -> f64 + '_ {
    let (axis, sign) = up.axis_and_sign();
    move |v| sign * p[3 * v as usize + axis] as f64
}

/// Extent of a pose along the up axis.
pub fn subject_height(pose: &[f32], up: UpAxis) -> f64 {
    let h = height_of(pose, up);
    let (lo, hi) = (0..(pose.len() / 3) as u32).map(&h).fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    (hi - lo).max(0.0)
}

/// The feet: the vertices of every part whose name starts with `leg` (what `surfcap parts
/// propose` and the KayKit parts name them).
pub fn feet_vertices(parts: &BodyParts) -> Result<Vec<Vec<u32>>> {
    let feet = surfcap_variation::motion_preparation::feet_of(parts);
    if feet.is_empty() {
        return Err(Error::Unsuitable(format!(
            "no leg among the body parts ({}): foot sliding needs parts named leg_*",
            parts.names().join(", ")
        )));
    }
    Ok(feet)
}

/// Foot sliding of a motion in the world, by the shared contact detection (surfcap-geometry's
/// `ground_contacts` and `foot_sliding`): the contact-weighted mean horizontal speed of the
/// planted vertices (the group root motion treats as planted at each step), with the ground
/// and the subject's height taken from the motion itself.
pub fn foot_sliding(frames: &[&[f32]], fps: f64, up: UpAxis, feet: &[Vec<u32>]) -> Result<FootSliding> {
    let nv = frames.first().map_or(0, |f| f.len() / 3);
    let flat: Vec<f32> = frames.iter().flat_map(|f| f.iter().copied()).collect();
    let params = ContactParams::default();
    let contacts = surfcap_geometry::ground_contacts::ground_contacts(&flat, nv, fps, up, &params);
    let r = surfcap_geometry::foot_sliding::foot_sliding(&flat, nv, fps, up, &contacts, &params, feet)
        .map_err(|e| Error::Unsuitable(format!("foot sliding: {e}")))?;
    Ok(FootSliding {
        speed: r.mean_speed,
        contact_fraction: r.contact_steps as f64 / frames.len().saturating_sub(1).max(1) as f64,
    })
}

/// The ground under a capture authored in place (the KayKit clips): per frame, the travel its
/// own foot contacts give (surfcap-variation's `in_place_ground`: the root motion recovered
/// from contacts, when the capture's centre does not travel); `None` for a capture that
/// travels. Such a capture's planted feet move backwards at the walking speed in the world;
/// measured on this ground, as a walk on a treadmill is, they are planted. The ground comes
/// from the capture alone, so its variants are measured on the same ground: not on travel
/// recovered from their own contacts.
pub fn sliding_ground(frames: &[&[f32]], fps: f64, up: UpAxis, height: f64) -> Option<Vec<[f64; 2]>> {
    let owned: Vec<Vec<f32>> = frames.iter().map(|f| f.to_vec()).collect();
    in_place_ground(&owned, fps, up, height)
}

/// [`foot_sliding`] of a motion moved along the ground by `ground` (one offset per frame, the
/// two ground axes), or as it is.
pub fn foot_sliding_on(
    frames: &[&[f32]],
    fps: f64,
    up: UpAxis,
    feet: &[Vec<u32>],
    ground: Option<&[[f64; 2]]>,
) -> Result<FootSliding> {
    let Some(g) = ground else { return foot_sliding(frames, fps, up, feet) };
    if g.len() != frames.len() {
        return Err(Error::Unsuitable(format!(
            "foot sliding: a ground travel of {} frames for a motion of {}",
            g.len(),
            frames.len()
        )));
    }
    let (u, v, _) = surfcap_geometry::motion_plane_alignment::plane_axes(up);
    let moved: Vec<Vec<f32>> = frames
        .iter()
        .zip(g)
        .map(|(f, o)| {
            let mut p = f.to_vec();
            for q in p.chunks_exact_mut(3) {
                q[u] += o[0] as f32;
                q[v] += o[1] as f32;
            }
            p
        })
        .collect();
    foot_sliding(&refs(&moved), fps, up, feet)
}

/// Mean over frames of the edge-length distortion against `rest` (mean |l / l0 - 1|).
pub fn edge_distortion(topology: &Topology, rest: &[f32], frames: &[&[f32]]) -> f64 {
    let n = frames.len().max(1) as f64;
    let d: Vec<f64> = frames.par_iter().map(|p| edge_length_distortion(topology, rest, rest, p, 0.0)).collect();
    d.iter().sum::<f64>() / n
}

fn refs(v: &[Vec<f32>]) -> Vec<&[f32]> {
    v.iter().map(Vec::as_slice).collect()
}

fn gpdm_options(o: &VariationEvalOptions) -> GpdmOptions {
    let mut g = GpdmOptions::default();
    if let Some(n) = o.iterations {
        g.lbfgs.max_iters = n;
        g.lbfgs.max_evals = n + n / 4;
    }
    g
}

fn stitch_error(e: surfcap_transfer::Error) -> Error {
    Error::Unsuitable(format!("stitching the parts: {e}"))
}

/// Every `step`-th frame of every prepared sequence from `start`, keeping only those for which
/// `keep(i, n)` holds.
fn select_frames(prepared: &PreparedMotions, keep: impl Fn(usize, usize) -> bool) -> PreparedMotions {
    let sequences = prepared
        .sequences
        .iter()
        .map(|s| {
            let n = s.aligned.len();
            let idx: Vec<usize> = (0..n).filter(|&i| keep(i, n)).collect();
            TrainingSequence {
                name: s.name.clone(),
                origin: s.origin.clone(),
                own_frames: s.own_frames,
                times: idx.iter().map(|&i| s.times[i]).collect(),
                aligned: idx.iter().map(|&i| s.aligned[i].clone()).collect(),
                path: idx.iter().map(|&i| s.path[i]).collect(),
                first_placement: s.first_placement,
                displacements: idx.iter().map(|&i| s.displacements[i]).collect(),
            }
        })
        .collect();
    PreparedMotions {
        reference_pose: prepared.reference_pose.clone(),
        reference: prepared.reference.clone(),
        sequences,
    }
}

/// Per part, the PCA reconstruction of `test` rows from a d-component PCA of `train` rows.
fn pca_reconstruction(train: &Mat<f64>, test: &Mat<f64>, d: usize) -> Result<Mat<f64>> {
    let pca = Pca::fit(train.as_ref(), d.min(train.nrows() - 1).max(1), PcaMethod::Auto)
        .map_err(Error::learn("fitting PCA"))?;
    let c = pca.project(test.as_ref()).map_err(Error::learn("projecting on PCA"))?;
    pca.reconstruct(c.as_ref()).map_err(Error::learn("reconstructing from PCA"))
}

/// The stitched mesh of every row of per-part reconstructions (rows in the same order for
/// every part), and its mean per-vertex distance to `truth`.
fn stitched_error(stitcher: &Stitcher, parts: &BodyParts, per_part: &[Mat<f64>], truth: &[&[f32]]) -> Result<f64> {
    let errs: Vec<f64> = (0..truth.len())
        .into_par_iter()
        .map(|i| {
            let pos: Vec<Vec<f32>> = parts
                .parts
                .iter()
                .zip(per_part)
                .map(|(p, m)| (0..3 * p.vertices.len()).map(|c| m[(i, c)] as f32).collect())
                .collect();
            let (mesh, _) = stitcher.stitch(&pos).map_err(stitch_error)?;
            Ok(pose_distance(&mesh, truth[i]))
        })
        .collect::<Result<_>>()?;
    Ok(errs.iter().sum::<f64>() / errs.len().max(1) as f64)
}

/// One part's held-out errors (GPDM, PCA), reconstructions (GPDM, PCA) and fit.
type HeldOutPart = (f64, f64, Mat<f64>, Mat<f64>, FitSummary);

/// A stitched body-frame motion and its displacements.
type AlignedMotion = (Vec<Vec<f32>>, Vec<[f64; 6]>);

/// Fig. 6.4 on training frames (the model's own) and held-out frames (a model of the even
/// frames).
fn reconstruction(
    model: &VariationModel,
    prepared: &PreparedMotions,
    parts: &BodyParts,
    stitcher: &Stitcher,
    learnt: &[Vec<Vec<f32>>],
    o: &VariationEvalOptions,
) -> Result<Reconstruction> {
    let d = model.part_models[0].latent_dim();
    // Training frames: the GPDM at its learnt latents vs PCA of its own training rows.
    let training: Vec<(f64, f64, Mat<f64>)> = model
        .part_models
        .par_iter()
        .zip(&parts.parts)
        .map(|(g, p)| {
            let y = &g.spec().y;
            let (rec, _) = g.reconstruct(g.latent()).map_err(Error::learn("reconstructing the training frames"))?;
            let prec = pca_reconstruction(y, y, d)?;
            let nv = p.vertices.len();
            Ok((rows_vertex_error(&rec, y, nv), rows_vertex_error(&prec, y, nv), prec))
        })
        .collect::<Result<_>>()?;
    let truth: Vec<&[f32]> = prepared.sequences.iter().flat_map(|s| s.aligned.iter().map(Vec::as_slice)).collect();
    let learnt_all: Vec<&[f32]> = learnt.iter().flat_map(|s| s.iter().map(Vec::as_slice)).collect();
    let gpdm_overall = motion_distance(&learnt_all, &truth);
    let pca_parts: Vec<Mat<f64>> = training.iter().map(|t| t.2.clone()).collect();
    let pca_overall = stitched_error(stitcher, parts, &pca_parts, &truth)?;

    // Held-out frames: a model of the even frames; the interior odd frames reconstructed.
    let even = select_frames(prepared, |i, _| i % 2 == 0);
    let odd = select_frames(prepared, |i, n| i % 2 == 1 && i + 1 < n);
    let root = parts.root();
    let torso: Vec<Vec<f64>> = even.sequences.iter().flat_map(|s| part_vectors(parts, root, &s.aligned)).collect();
    let disp: Vec<[f64; 6]> = even.sequences.iter().flat_map(|s| s.displacements.iter().copied()).collect();
    let scales = displacement_scales(&torso, &disp);
    let lengths: Vec<usize> = even.sequences.iter().map(|s| s.aligned.len()).collect();
    let gopts = gpdm_options(o);
    let held: Vec<HeldOutPart> = (0..parts.len())
        .into_par_iter()
        .map(|k| {
            let t0 = Instant::now();
            let sc = (k == root).then_some(&scales);
            let y = part_matrix(&even, parts, k, sc);
            let test = part_matrix(&odd, parts, k, sc);
            let mut at = 0;
            let seqs: Vec<_> = lengths
                .iter()
                .map(|&l| {
                    let r = y.as_ref().subrows(at, l);
                    at += l;
                    r
                })
                .collect();
            let (g, fit) = Gpdm::fit(&seqs, &gopts).map_err(Error::learn("fitting the held-out GPDM"))?;
            // Odd frame i = 2m + 1 lies between even frames m and m + 1 of its sequence.
            let mut xs = Vec::new();
            for (j, s) in odd.sequences.iter().enumerate() {
                let x = g.sequence_latent(j).expect("one latent block per sequence");
                for m in 0..s.aligned.len() {
                    xs.push((0..d).map(|c| 0.5 * (x[(m, c)] + x[(m + 1, c)])).collect::<Vec<f64>>());
                }
            }
            let xm = Mat::from_fn(xs.len(), d, |i, c| xs[i][c]);
            let (rec, _) = g.reconstruct(xm.as_ref()).map_err(Error::learn("reconstructing held-out frames"))?;
            let prec = pca_reconstruction(&y, &test, d)?;
            let nv = parts.parts[k].vertices.len();
            let fs = FitSummary {
                part: parts.parts[k].name.clone(),
                vertices: nv,
                iterations: fit.iters,
                converged: fit.converged,
                objective: fit.objective,
                seconds: t0.elapsed().as_secs_f64(),
            };
            Ok((rows_vertex_error(&rec, &test, nv), rows_vertex_error(&prec, &test, nv), rec, prec, fs))
        })
        .collect::<Result<_>>()?;
    let odd_truth: Vec<&[f32]> = odd.sequences.iter().flat_map(|s| s.aligned.iter().map(Vec::as_slice)).collect();
    let g_parts: Vec<Mat<f64>> = held.iter().map(|h| h.2.clone()).collect();
    let p_parts: Vec<Mat<f64>> = held.iter().map(|h| h.3.clone()).collect();
    let overall = ReconstructionErrors {
        part: "overall (stitched)".into(),
        gpdm_training: gpdm_overall,
        pca_training: pca_overall,
        gpdm_held_out: stitched_error(stitcher, parts, &g_parts, &odd_truth)?,
        pca_held_out: stitched_error(stitcher, parts, &p_parts, &odd_truth)?,
    };
    Ok(Reconstruction {
        latent_dim: d,
        training_frames: truth.len(),
        parts: parts
            .parts
            .iter()
            .zip(&training)
            .zip(&held)
            .map(|((p, t), h)| ReconstructionErrors {
                part: p.name.clone(),
                gpdm_training: t.0,
                pca_training: t.1,
                gpdm_held_out: h.0,
                pca_held_out: h.1,
            })
            .collect(),
        overall,
        held_out_training_frames: lengths.iter().sum(),
        held_out_frames: odd_truth.len(),
        held_out_fits: held.into_iter().map(|h| h.4).collect(),
        held_out_latent: "midpoint of the learnt latents of the two neighbouring training (even) frames",
    })
}

/// Fig. 6.7 on the first two sequences.
fn blend_eval(
    model: &VariationModel,
    prepared: &PreparedMotions,
    subject: &Subject,
    o: &VariationEvalOptions,
) -> Result<BlendEval> {
    let (a, b) = (&model.sequences[0].name, &model.sequences[1].name);
    let w = o.blend_weight;
    let ladder = blend_ladder(model, a, b)?;
    let (r0, r1) = (ladder[0], ladder[ladder.len() - 1]);
    let (g0, g1) = bounding_rungs(&ladder, w)?;
    let latents = |j: usize| model.learnt_latents(j).map_err(Error::from);
    let direct = interpolate_latents(&latents(r0.sequence)?, &latents(r1.sequence)?, r0, r1, w);
    let guided = interpolate_latents(&latents(g0.sequence)?, &latents(g1.sequence)?, g0, g1, w);
    let (pd, _) = reconstruct_aligned(model, &direct)?;
    let (pg, _) = reconstruct_aligned(model, &guided)?;
    let truth =
        blend_sequences(subject.topology(), subject.up_axis, &prepared.sequences[0], &prepared.sequences[1], w)?;
    let per_frame =
        |p: &[Vec<f32>]| -> Vec<f64> { p.iter().zip(&truth.aligned).map(|(x, y)| pose_distance(x, y)).collect() };
    let (direct, guided) = (per_frame(&pd), per_frame(&pg));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    Ok(BlendEval {
        a: a.clone(),
        b: b.clone(),
        w,
        guided_between: [
            (model.sequences[g0.sequence].name.clone(), g0.w),
            (model.sequences[g1.sequence].name.clone(), g1.w),
        ],
        direct_mean: mean(&direct),
        guided_mean: mean(&guided),
        direct,
        guided,
    })
}

/// Everything of one case: the model, Fig. 6.4, Fig. 6.7 and the variation statistics.
pub fn case_eval(case: &VariationCase, o: &VariationEvalOptions) -> Result<CaseEval> {
    let t0 = Instant::now();
    let s = &case.subject;
    if s.sequences().len() < 2 {
        return Err(Error::Unsuitable(format!(
            "{}: {} sequence: expected at least two (the first two are blended)",
            s.name,
            s.sequences().len()
        )));
    }
    let sequences: Vec<usize> = (0..s.sequences().len()).collect();
    let preparation = PreparationOptions {
        reference: 0,
        time_alignment: TimeAlignment::default(),
        blend_pairs: vec![(0, 1)],
        blend_weights: vec![o.trained_blend_weight],
    };
    let train = TrainOptions { preparation: preparation.clone(), gpdm: gpdm_options(o) };
    let model = VariationModel::train(s, &sequences, &case.parts, &train, &NoProgress)?;
    let train_seconds = t0.elapsed().as_secs_f64();
    let prepared = prepare(s, &sequences, &case.parts, &preparation)?;
    let (topology, up, rest) = (s.topology(), s.up_axis, &prepared.reference_pose);
    let height = subject_height(rest, up);
    let stitcher = Stitcher::new(topology, rest, &case.parts).map_err(stitch_error)?;
    // Every learnt sequence's reconstruction at its learnt latents (body frame).
    let learnt: Vec<AlignedMotion> = (0..model.sequences.len())
        .map(|j| reconstruct_aligned(&model, &model.learnt_latents(j)?))
        .collect::<Result<_, surfcap_variation::Error>>()?;
    let learnt_poses: Vec<Vec<Vec<f32>>> = learnt.iter().map(|l| l.0.clone()).collect();
    let reconstruction = reconstruction(&model, &prepared, &case.parts, &stitcher, &learnt_poses, o)?;
    let blend = blend_eval(&model, &prepared, s, o)?;

    let c = &o.criteria;
    let feet = feet_vertices(&case.parts)?;
    let min_floor = c.min_floor * height;
    let mut variation = Vec::new();
    let mut latents: Vec<PartLatents> = case
        .parts
        .parts
        .iter()
        .enumerate()
        .map(|(k, p)| PartLatents {
            part: p.name.clone(),
            learnt: model
                .sequences
                .iter()
                .enumerate()
                .map(|(j, q)| (q.name.clone(), model.part_models[k].sequence_latent(j).expect("a block").to_owned()))
                .collect(),
            variants: Vec::new(),
        })
        .collect();
    for (j, q) in model.sequences.iter().enumerate() {
        if !matches!(q.origin, SequenceOrigin::Captured { .. }) {
            continue;
        }
        let t1 = Instant::now();
        // Sampled as they are, then cleaned on the capture's ground (for an in-place capture,
        // the ground the sliding is measured on, `sliding_ground`; none for a travelling one).
        let as_sampled = SamplingOptions { foot_skate_cleanup: false, ..o.sampling };
        let (mut variants, chains) = sample_variants(&model, &q.name, o.variants, o.seed, &as_sampled)?;
        let captured = &s.sequences()[j];
        if o.sampling.foot_skate_cleanup {
            let owned: Vec<Vec<f32>> = (0..captured.n_frames()).map(|f| captured.frame(f).to_vec()).collect();
            clean_up_variants(&model, &mut variants, &owned, &o.sampling)?;
        }
        if j == 0 {
            for v in &variants {
                for (pl, x) in latents.iter_mut().zip(&v.latents) {
                    pl.variants.push(x.clone());
                }
            }
        }
        let world_src: Vec<&[f32]> = (0..captured.n_frames()).map(|f| captured.frame(f)).collect();
        let body_src = refs(&prepared.sequences[j].aligned);
        let (lp, ld) = &learnt[j];
        // The learnt motion placed as the variants are, so the world floor of (i) compares like
        // with like.
        let learnt_world =
            place_variant(&model, o.sampling.path, lp, ld, &q.first_placement, &q.path, &q.times, q.own_frames)?;
        let learnt_error_body = motion_distance(lp, &body_src);
        let learnt_error_world = motion_distance(&learnt_world, &world_src);
        let floor_body = (c.floor_factor * learnt_error_body).max(min_floor);
        let floor_world = (c.floor_factor * learnt_error_world).max(min_floor);
        let distance_body: Vec<f64> = variants.iter().map(|v| motion_distance(&v.aligned, &body_src)).collect();
        let distance_world: Vec<f64> = variants.iter().map(|v| motion_distance(&v.world, &world_src)).collect();
        let mut distance_learnt = Vec::new();
        let mut nearest_other = Vec::new();
        for v in &variants {
            let d: Vec<f64> = learnt_poses.iter().map(|l| motion_distance(&v.aligned, l)).collect();
            distance_learnt.push(d[j]);
            let (k, dk) = d
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != j)
                .min_by(|x, y| x.1.total_cmp(y.1))
                .map(|(k, x)| (k, *x))
                .expect("at least two learnt sequences");
            nearest_other.push((model.sequences[k].name.clone(), dk));
        }
        let edge_distortion_input = edge_distortion(topology, rest, &world_src);
        let edge_distortion_learnt = edge_distortion(topology, rest, &refs(lp));
        let edge: Vec<f64> = variants.iter().map(|v| edge_distortion(topology, rest, &refs(&v.aligned))).collect();
        let edge_world: Vec<f64> = variants.iter().map(|v| edge_distortion(topology, rest, &refs(&v.world))).collect();
        let ground = sliding_ground(&world_src, s.fps, up, height);
        let slide = |f: &[&[f32]]| foot_sliding_on(f, s.fps, up, &feet, ground.as_deref());
        let sliding_input = slide(&world_src)?;
        let sliding_learnt = slide(&refs(&learnt_world))?;
        let sliding: Vec<FootSliding> = variants.iter().map(|v| slide(&refs(&v.world))).collect::<Result<_>>()?;
        let sliding_before_cleanup: Vec<FootSliding> = variants
            .iter()
            .filter_map(|v| v.before_cleanup.as_ref())
            .map(|w| slide(&refs(w)))
            .collect::<Result<_>>()?;
        let cleanup: Vec<CleanupReport> = variants.iter().filter_map(|v| v.cleanup).collect();
        let mut min_pair = f64::INFINITY;
        for x in 0..variants.len() {
            for y in x + 1..variants.len() {
                min_pair = min_pair.min(motion_distance(&variants[x].aligned, &variants[y].aligned));
            }
        }
        let limit = 1.0 + c.tolerance;
        let passes = Passes {
            differs: distance_body.iter().all(|&d| d > floor_body) && distance_world.iter().all(|&d| d > floor_world),
            closest_to_source: distance_learnt.iter().zip(&nearest_other).all(|(d, n)| *d < n.1),
            edge_distortion: edge.iter().chain(&edge_world).all(|&e| e <= limit * edge_distortion_input),
            foot_sliding: sliding.iter().all(|f| f.speed <= limit * sliding_input.speed),
            distinct: min_pair > min_floor,
        };
        variation.push(SequenceVariation {
            sequence: q.name.clone(),
            variants: variants.len(),
            learnt_error_body,
            learnt_error_world,
            floor_body,
            floor_world,
            distance_body,
            distance_world,
            distance_learnt,
            nearest_other,
            edge_distortion_input,
            edge_distortion_learnt,
            edge_distortion: edge,
            edge_distortion_world: edge_world,
            sliding_against: if ground.is_some() { "the capture's ground travel" } else { "the world" },
            sliding_input,
            sliding_learnt,
            sliding,
            sliding_before_cleanup,
            cleanup,
            min_pair_distance: min_pair,
            passes,
            chains,
            seconds: t1.elapsed().as_secs_f64(),
        });
    }
    let missed = variation.iter().map(|v| v.passes.missed()).sum();
    Ok(CaseEval {
        name: case.name.clone(),
        subject: s.name.clone(),
        vertices: topology.n_vertices(),
        height,
        units: s.units.symbol().to_string(),
        parts: case.parts.names().iter().map(|n| n.to_string()).collect(),
        sequences: model
            .sequences
            .iter()
            .map(|q| SequenceInfo {
                name: q.name.clone(),
                own_frames: q.own_frames,
                blend: matches!(q.origin, SequenceOrigin::Blend { .. }),
            })
            .collect(),
        reference_frames: model.frames,
        train_seconds,
        fits: model
            .fits
            .iter()
            .map(|f| FitSummary {
                part: f.part.clone(),
                vertices: f.vertices,
                iterations: f.fit.iters,
                converged: f.fit.converged,
                objective: f.fit.objective,
                seconds: f.seconds,
            })
            .collect(),
        reconstruction,
        blend,
        variation,
        missed,
        seconds: t0.elapsed().as_secs_f64(),
        latents,
    })
}

/// Checks the options, then evaluates every case.
pub fn variation_eval(cases: &[VariationCase], o: &VariationEvalOptions) -> Result<VariationEval> {
    let t0 = Instant::now();
    if o.variants < 2 {
        return Err(Error::parameter(
            "--variants",
            Some(o.variants.to_string()),
            "expected at least 2 (no two variants may be identical)",
        ));
    }
    if o.iterations == Some(0) {
        return Err(Error::parameter("--iterations", Some("0".into()), "expected at least 1"));
    }
    let inside = |w: f64| w > 0.0 && w < 1.0;
    if !inside(o.blend_weight) || !inside(o.trained_blend_weight) {
        return Err(Error::parameter("--blend-weight", Some(o.blend_weight.to_string()), "expected a value in (0, 1)"));
    }
    let cases = cases.iter().map(|c| case_eval(c, o)).collect::<Result<Vec<_>>>()?;
    Ok(VariationEval {
        variants: o.variants,
        seed: o.seed,
        iterations: o.iterations,
        trained_blend_weight: o.trained_blend_weight,
        blend_weight: o.blend_weight,
        sampling: SamplingSettings {
            path: o.sampling.path,
            start: o.sampling.start,
            smoothing: o.sampling.smoothing,
            deviation_smoothing: o.sampling.deviation_smoothing,
            warmup: o.sampling.warmup,
            thin: o.sampling.thin,
            max_leapfrog: o.sampling.max_leapfrog,
            foot_skate_cleanup: o.sampling.foot_skate_cleanup,
            move_root: o.sampling.move_root,
            learnt_stretch: o.sampling.learnt_stretch,
            carry_pins: o.sampling.carry_pins,
        },
        criteria: o.criteria,
        missed: cases.iter().map(|c| c.missed).sum(),
        cases,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_and_heights() {
        let a = [0.0f32, 0.0, 0.0, 1.0, 2.0, 0.0];
        let b = [3.0f32, 4.0, 0.0, 1.0, 2.0, 0.0];
        assert!((pose_distance(&a, &b) - 2.5).abs() < 1e-12);
        assert!((subject_height(&a, UpAxis::PosY) - 2.0).abs() < 1e-12);
        assert!((subject_height(&a, UpAxis::NegY) - 2.0).abs() < 1e-12);
    }
}
