//! Sampling variants of a learnt sequence (thesis 6.6, eq. 6.8-6.13).
//!
//! For every body part independently: the learnt sequence's first latent point `x_1`, the
//! mean-prediction trajectory from it (eq. 6.8-6.10) as the start of a Hybrid Monte Carlo
//! chain over whole trajectories (6.6.2), every `thin`-th sample after warm-up a variant. The
//! part's pose at each latent point is the reconstruction GP's mean (eq. 6.12); the parts are
//! stitched (6.6.2, the cheapest closed cut in every overlap and one Poisson merge, chapter 5's
//! stitcher) and the frames moved by the displacements the torso's GP gives, from the
//! sequence's first placement. The variant is finally brought back from the reference's
//! frames to the sequence's own timing and frame count through its time map.
//!
//! Decisions where the thesis is loose:
//! - **Pose noise**: eq. 6.11 samples `y ~ N(mu_Y, sigma_Y^2 I)`, an independent draw per
//!   coordinate and frame: a rough surface that flickers from frame to frame. The mean
//!   (eq. 6.12) is used; the variation comes from the sampled latent trajectories (and from
//!   the parts being sampled independently), which is what Fig. 6.5 shows.
//! - **Seeds**: each part's chain has its own stream, derived from the seed, the sequence's
//!   name and the part's index, so a variant does not depend on the number of threads or on
//!   which other sequences are sampled.
//! - **Where the chain starts**: 6.6.1 starts it from the mean prediction, the dynamics GP's
//!   mean simulated from `x_1`. On the CMU-driven mannequin (walk, turns, jog; 5 parts of a
//!   1,500-vertex body) that prediction drifts from the learnt walk: its poses are 8.3 cm (mean
//!   per vertex, body frame) from the learnt trajectory's, while the learnt trajectory's are
//!   0.3 cm from the captured walk, so every variant was a variant of a different motion. The
//!   chain therefore starts at the learnt trajectory by default ([`ChainStart::Learnt`]); the
//!   density sampled is the same (the product of eq. 6.8's one-step predictives), only the
//!   start differs. [`ChainStart::MeanPrediction`] keeps the thesis's start. Weighing the
//!   dynamics by D / d (Wang et al. 2008's balanced GPDM) was tried against the drift and
//!   collapsed the latent trajectories (step size 1e-18, identical variants, reconstruction
//!   9.4 cm): the thesis's weight stays.
//! - **Where a variant goes** ([`VariantPath`]): 6.6.2 moves every frame by the displacement
//!   the torso's GP gives and integrates them. Measured with `surfcap eval vary`, that path
//!   drifts (0.3-0.5 m over 4 m CMU walks and turns) and the feet slide: the planted vertices of
//!   the variants moved 1.3-2.9 m/s against 0.09-0.29 m/s for the captures (the shared contact
//!   detection). By default a variant's pose of reference frame i is therefore placed where the
//!   source's frame i is ([`VariantPath::Source`]): the body varies, the path is the
//!   captured one. [`VariantPath::Sampled`] keeps the thesis's placement.
//! - **How far a variant goes**: the chain starts at the learnt trajectory and every
//!   iteration takes it further; a variant is drawn after `warmup + k thin` iterations. With
//!   100 and 5 (surfcap's former defaults) the variants of KayKit Walking_B were 26-30 mm
//!   (mean per vertex) from its learnt walk and as near to Walking_C's, so they no longer
//!   read as Walking_B (criterion (ii) of `surfcap eval vary`); the chains' acceptance and
//!   step sizes were the same with 20 warm-up iterations. The defaults are 20 and 2: variants
//!   15-32 mm from their learnt motion, 6-14 times the floor below which a variant counts as
//!   a copy (docs/results/variation.md).
//! - **Smoothing**: the chain samples the product of one-step predictives, so each sampled
//!   point carries its own dynamics noise and the poses jitter from frame to frame (the
//!   learnt trajectories do not). A triangular moving average of radius 2 frames is applied
//!   to each sampled trajectory (`smoothing`, 0 turns it off; measured with `surfcap eval
//!   vary`, see docs/results/variation.md).
//! - **Deviation smoothing**: off the learnt trajectories the reconstruction GP's mean answers
//!   sharply to where a latent point is, so the stitched poses jitter even with smooth latent
//!   trajectories (the feet of the CMU walk's variants: 47 mm frame-to-frame second difference
//!   against 8 mm in the capture, 35 mm with the latent trajectories smoothed over 8 frames on
//!   each side) and planted feet slide at 0.7-3.1 m/s. Each variant's body-frame deviation from
//!   the learnt motion is averaged over time instead ([`crate::pose_deviation_smoothing`],
//!   `deviation_smoothing` in the options, radius 4 by default): the learnt motion's own
//!   frame-to-frame change is kept, the variant's difference from it made slow. Measured with
//!   `surfcap eval vary` (docs/results/variation.md): sliding before the clean-up went to
//!   0.13-1.34 m/s and every criterion is met on both cases.
//! - **Surface stretch**: the reconstruction GP's mean blends training poses linearly in
//!   vertex space, which shrinks and stretches the surface between them (thesis 2.4); each
//!   triangle of a sampled pose keeps its rotation and takes the learnt motion's stretch at the
//!   same frame, through one Poisson solve ([`crate::learnt_stretch`], `learnt_stretch` in the
//!   options, on by default). Re-timing to the sequence's own frames blends neighbouring frames
//!   linearly again, so the world frames are given the stretch of the learnt motion placed and
//!   re-timed alike. Measured with `surfcap eval vary` (docs/results/variation.md): the body-
//!   frame poses' edge distortion went from up to 11% above the captures' to within 5%.
//! - **Foot skate**: varied leg poses on the source's path still let the planted feet drift
//!   (`surfcap eval vary`: 6-10x the captures' foot sliding on CMU clips, docs/results/
//!   variation.md), so every variant's world frames go through the foot-skate clean-up
//!   ([`crate::foot_skate_cleanup`], `foot_skate_cleanup` in the options, on by default, the
//!   root moved with the planted feet unless `move_root` is off, and never moved by
//!   [`variants_on_source_path`], which keeps a synthesised walk on its path); for a source
//!   authored in place its ground is the travel its learnt motion's contacts give ([`sample_variants`]) or
//!   the captured source's ([`clean_up_variants`] given the capture, as `surfcap eval vary`
//!   and [`variants_on_source_path`] do).
//! - **Frame 0** keeps the learnt `x_1`: every variant starts in the source's first pose, so a
//!   variant can replace its source inside a longer animation.

use rayon::prelude::*;
use serde::Serialize;
use surfcap_learn::Mat;
use surfcap_learn::hybrid_monte_carlo::HmcOptions;
use surfcap_motion::sequence_time_alignment::TimeMap;
use surfcap_transfer::pose_representation::Placement;

use crate::error::{Error, Result};
use crate::foot_skate_cleanup::{CleanupReport, FootSkateCleanup, FootSkateParams};
use crate::learnt_stretch::LearntStretch;
use crate::motion_preparation::poses_at;
use crate::pose_deviation_smoothing::{smooth_deviation, triangular_window};
use crate::variation_model::VariationModel;

/// Where each part's HMC chain starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ChainStart {
    /// The learnt latent trajectory of the sequence (surfcap's default, see the module doc).
    Learnt,
    /// The mean prediction from its first point, eq. 6.8-6.10 (the thesis's 6.6.1).
    MeanPrediction,
}

impl ChainStart {
    /// `learnt` (or `learned`) or `mean`, as the command line and the Python bindings take it.
    pub fn parse(s: &str) -> Option<ChainStart> {
        match s {
            "learnt" | "learned" => Some(ChainStart::Learnt),
            "mean" => Some(ChainStart::MeanPrediction),
            _ => None,
        }
    }
}

/// Where a variant's frames go in the world.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum VariantPath {
    /// Each body-frame pose placed where the source's frame of the same reference frame is:
    /// the body varies, the path is the source's (surfcap's default, see the module doc).
    Source,
    /// The displacements the torso's GP gives, integrated from the source's first placement
    /// (thesis 6.6.2).
    Sampled,
    /// The source's rotations and height, the travel along the ground recovered from the
    /// variant's own foot contacts (surfcap-geometry's `root_motion_from_contacts`), so that
    /// its planted feet stay put.
    Contacts,
}

impl VariantPath {
    /// `source`, `sampled` or `contacts`, as the command line and the Python bindings take it.
    pub fn parse(s: &str) -> Option<VariantPath> {
        match s {
            "source" => Some(VariantPath::Source),
            "sampled" => Some(VariantPath::Sampled),
            "contacts" => Some(VariantPath::Contacts),
            _ => None,
        }
    }
}

/// Options of [`sample_variants`].
#[derive(Debug, Clone, Copy)]
pub struct SamplingOptions {
    pub start: ChainStart,
    pub path: VariantPath,
    /// Radius (frames) of the triangular moving average applied to each sampled latent
    /// trajectory, its first point kept (0: none); see the module doc.
    pub smoothing: usize,
    /// Radius (frames) of the triangular moving average applied to each variant's body-frame
    /// deviation from the learnt motion, frame 0 kept (0: none;
    /// [`crate::pose_deviation_smoothing`]; 4 by default, see the module doc).
    pub deviation_smoothing: usize,
    /// HMC warm-up iterations (step size and path length tuning). The chain moves away from
    /// its start while it tunes, so this also sets how far the variants wander from the
    /// learnt trajectory (see the module doc's "How far a variant goes").
    pub warmup: usize,
    /// Iterations between two variants (a larger value gives less correlated variants, and
    /// later ones further from the start).
    pub thin: usize,
    /// Upper bound on leapfrog steps per HMC iteration.
    pub max_leapfrog: usize,
    /// Pin the planted feet of every variant ([`crate::foot_skate_cleanup`]; on by default,
    /// see the module doc).
    pub foot_skate_cleanup: bool,
    /// With the clean-up, move the whole body with the planted feet as well
    /// ([`FootSkateParams::move_root`]; on by default). Part of the clean-up: without
    /// `foot_skate_cleanup` it has no effect.
    pub move_root: bool,
    /// Give every triangle of a sampled pose the learnt motion's stretch at the same frame,
    /// under the triangle's own rotation ([`crate::learnt_stretch`]; on by default, see the
    /// module doc). Off, the stitched reconstruction-GP mean is used as it is.
    pub learnt_stretch: bool,
    /// With the clean-up and the root moved, pin each plant where its foot comes down and let
    /// the body go on with its planted feet ([`FootSkateParams::carry_pins`]; off by default:
    /// the body then leaves its source's path, see the field).
    pub carry_pins: bool,
}

impl Default for SamplingOptions {
    fn default() -> Self {
        SamplingOptions {
            start: ChainStart::Learnt,
            path: VariantPath::Source,
            smoothing: 2,
            deviation_smoothing: 4,
            warmup: 20,
            thin: 2,
            max_leapfrog: 30,
            foot_skate_cleanup: true,
            move_root: true,
            learnt_stretch: true,
            carry_pins: false,
        }
    }
}

/// The HMC chain of one part.
#[derive(Debug, Clone, Serialize)]
pub struct ChainSummary {
    pub part: String,
    pub acceptance_rate: f64,
    pub step_size: f64,
    pub leapfrog_steps: usize,
    pub divergences: usize,
    pub seed: u64,
    pub seconds: f64,
}

/// One variant: its latent trajectories, its aligned poses on the reference's frames and its
/// world frames at the sequence's own timing.
#[derive(Debug, Clone)]
pub struct Variant {
    /// Per part, the latent trajectory (reference frames x d).
    pub latents: Vec<Mat<f64>>,
    /// Per reference frame, the stitched pose in the body frame.
    pub aligned: Vec<Vec<f32>>,
    /// Per reference frame, the displacement from the previous one.
    pub displacements: Vec<[f64; 6]>,
    /// The frames in the world, at the sequence's own timing (its frame count); with the
    /// foot-skate clean-up, the cleaned frames.
    pub world: Vec<Vec<f32>>,
    /// With the foot-skate clean-up: the frames before it, and what it did.
    pub before_cleanup: Option<Vec<Vec<f32>>>,
    pub cleanup: Option<CleanupReport>,
}

/// Per variant, one latent trajectory per part.
pub type LatentVariants = Vec<Vec<Mat<f64>>>;

/// Stitched body-frame poses and the displacements between them.
pub type BodyMotion = (Vec<Vec<f32>>, Vec<[f64; 6]>);

/// A splitmix64 step: well-mixed seeds for independent streams.
pub fn mix_seed(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of part `k`'s chain for sequence `name` (FNV-1a of the name, mixed).
pub fn chain_seed(seed: u64, name: &str, k: usize) -> u64 {
    let h = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
    mix_seed(mix_seed(seed ^ h).wrapping_add(k as u64))
}

/// `x` with every column averaged over `2 r + 1` frames with triangular weights (the ends
/// renormalised), its first row (the fixed `x_1`) kept.
pub fn smoothed(x: &Mat<f64>, r: usize) -> Mat<f64> {
    let n = x.nrows();
    if r == 0 || n < 3 {
        return x.clone();
    }
    Mat::from_fn(n, x.ncols(), |i, j| {
        if i == 0 {
            return x[(0, j)];
        }
        let (mut s, mut w) = (0.0, 0.0);
        for (k, wk) in triangular_window(i, n, r) {
            s += wk * x[(k, j)];
            w += wk;
        }
        s / w
    })
}

/// `count` latent variants of learnt sequence `j`: `[variant][part]` trajectories, and each
/// part's chain.
pub fn sample_latent_variants(
    model: &VariationModel,
    j: usize,
    count: usize,
    seed: u64,
    opts: &SamplingOptions,
) -> Result<(LatentVariants, Vec<ChainSummary>)> {
    let seq = model
        .sequences
        .get(j)
        .ok_or_else(|| Error::Invalid(format!("sequence {j}: the model has {}", model.sequences.len())))?;
    if count == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    if opts.thin == 0 {
        return Err(Error::Invalid("thin 0: expected at least 1 iteration between variants".into()));
    }
    let per_part: Vec<(Vec<Mat<f64>>, ChainSummary)> = model
        .part_models
        .par_iter()
        .enumerate()
        .map(|(k, g)| {
            let t0 = std::time::Instant::now();
            let learnt = g
                .sequence_latent(j)
                .ok_or_else(|| Error::Invalid(format!("sequence {j} is not in part {k}'s model")))?;
            let x1: Vec<f64> = (0..learnt.ncols()).map(|c| learnt[(0, c)]).collect();
            let s = chain_seed(seed, &seq.name, k);
            let hmc = HmcOptions {
                warmup: opts.warmup,
                samples: count,
                thin: opts.thin,
                max_leapfrog: opts.max_leapfrog,
                seed: s,
                ..HmcOptions::default()
            };
            let start = match opts.start {
                ChainStart::Learnt => learnt.to_owned(),
                ChainStart::MeanPrediction => g.mean_trajectory(&x1, learnt.nrows())?,
            };
            let (mut trajs, chain) = g.sample_trajectories_from(start.as_ref(), &hmc)?;
            for t in &mut trajs {
                *t = smoothed(t, opts.smoothing);
            }
            let summary = ChainSummary {
                part: model.parts.parts[k].name.clone(),
                acceptance_rate: chain.acceptance_rate,
                step_size: chain.step_size,
                leapfrog_steps: chain.leapfrog_steps,
                divergences: chain.divergences,
                seed: s,
                seconds: t0.elapsed().as_secs_f64(),
            };
            Ok((trajs, summary))
        })
        .collect::<Result<_>>()?;
    let mut variants: Vec<Vec<Mat<f64>>> = (0..count).map(|_| Vec::with_capacity(per_part.len())).collect();
    let mut chains = Vec::with_capacity(per_part.len());
    for (trajs, summary) in per_part {
        if trajs.len() != count {
            return Err(Error::Invalid(format!(
                "part {:?}: {} trajectories sampled, expected {count}",
                summary.part,
                trajs.len()
            )));
        }
        for (v, t) in variants.iter_mut().zip(trajs) {
            v.push(t);
        }
        chains.push(summary);
    }
    Ok((variants, chains))
}

/// The stitched body-frame poses and displacements of per-part latent trajectories (one
/// trajectory per part, all of one length): eq. 6.12 per part, then stitching.
pub fn reconstruct_aligned(model: &VariationModel, latents: &[Mat<f64>]) -> Result<BodyMotion> {
    if latents.len() != model.part_models.len() {
        return Err(Error::Invalid(format!(
            "{} latent trajectories: expected one per body part ({})",
            latents.len(),
            model.part_models.len()
        )));
    }
    let n = latents[0].nrows();
    if latents.iter().any(|x| x.nrows() != n) || n == 0 {
        return Err(Error::Invalid(
            "latent trajectories of different or zero lengths: expected one length for every part".into(),
        ));
    }
    let root = model.parts.root();
    let means: Vec<Mat<f64>> = model
        .part_models
        .par_iter()
        .zip(latents)
        .map(|(g, x)| Ok(g.reconstruct(x.as_ref())?.0))
        .collect::<Result<_>>()?;
    let sc = model.displacement_scales;
    let displacements: Vec<[f64; 6]> = (0..n)
        .map(|i| {
            if i == 0 {
                return [0.0; 6];
            }
            let m = &means[root];
            let c0 = m.ncols() - 6;
            std::array::from_fn(|c| m[(i, c0 + c)] / sc[c])
        })
        .collect();
    let poses: Vec<Vec<f32>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let parts: Vec<Vec<f32>> = model
                .parts
                .parts
                .iter()
                .enumerate()
                .map(|(k, p)| (0..3 * p.vertices.len()).map(|c| means[k][(i, c)] as f32).collect())
                .collect();
            Ok(model.stitcher().stitch(&parts)?.0)
        })
        .collect::<Result<_>>()?;
    Ok((poses, displacements))
}

/// For every own frame of a sequence, the reference time at which it is reached: the inverse
/// of its time map `times` (reference frame -> own time, first 0, last `own_frames - 1`).
pub fn inverse_times(times: &[f64], own_frames: usize) -> Result<Vec<f64>> {
    let map = TimeMap::new(times.to_vec())?;
    if map.other_frames() != own_frames {
        return Err(Error::Invalid(format!(
            "a time map ending at frame {}: expected {} frames",
            map.other_frames().saturating_sub(1),
            own_frames
        )));
    }
    Ok(map.inverse().times().to_vec())
}

/// Body-frame poses moved into the world from `start` by the displacements, then re-timed from
/// the reference's frames to `own_frames` frames through the time map `times`.
pub fn place_and_retime(
    aligned: &[Vec<f32>],
    displacements: &[[f64; 6]],
    start: &Placement,
    times: &[f64],
    own_frames: usize,
) -> Result<Vec<Vec<f32>>> {
    let mut placement = *start;
    let world: Vec<Vec<f32>> = aligned
        .iter()
        .zip(displacements)
        .enumerate()
        .map(|(i, (pose, d))| {
            if i > 0 {
                placement = placement.moved_by(d);
            }
            placement.apply(pose)
        })
        .collect();
    let refs: Vec<&[f32]> = world.iter().map(|p| p.as_slice()).collect();
    poses_at(&refs, &inverse_times(times, own_frames)?)
}

/// A variant's poses put on its source's own path: every own frame `f` of the variant (its
/// body-frame pose re-timed to the source's frames) placed where the source's frame `f` is,
/// `world = R_f aligned + t_f` with the source frame's placement onto the model's reference
/// pose. Only the body's poses vary, not the path: what synthesis uses (`synth --vary`), whose
/// searches already placed every source frame on the path asked for. `source` holds the
/// source sequence's frames (world positions; its own frame count).
pub fn variant_on_source_path(
    model: &VariationModel,
    j: usize,
    variant: &Variant,
    source: &[&[f32]],
) -> Result<Vec<Vec<f32>>> {
    let seq = model
        .sequences
        .get(j)
        .ok_or_else(|| Error::Invalid(format!("sequence {j}: the model has {}", model.sequences.len())))?;
    if source.len() != seq.own_frames {
        return Err(Error::Invalid(format!(
            "{} source frames for {:?}: expected its {} frames",
            source.len(),
            seq.name,
            seq.own_frames
        )));
    }
    let n = model.reference_pose.len();
    if let Some(f) = source.iter().position(|p| p.len() != n) {
        return Err(Error::Invalid(format!(
            "{}:{f} has {} vertices: expected {}",
            seq.name,
            source[f].len() / 3,
            n / 3
        )));
    }
    let placements: Vec<Placement> = source
        .par_iter()
        .map(|p| surfcap_transfer::pose_representation::align_to_reference(&model.reference_pose, p).1)
        .collect();
    let refs: Vec<&[f32]> = variant.aligned.iter().map(|p| p.as_slice()).collect();
    let aligned = poses_at(&refs, &inverse_times(&seq.times, seq.own_frames)?)?;
    Ok(aligned.iter().zip(&placements).map(|(p, pl)| pl.apply(p)).collect())
}

/// Body-frame poses (reference frames) each placed by the placement of its frame, then re-timed
/// to `own_frames` frames through the time map `times`.
pub fn place_on_path(
    aligned: &[Vec<f32>],
    path: &[Placement],
    times: &[f64],
    own_frames: usize,
) -> Result<Vec<Vec<f32>>> {
    if path.len() != aligned.len() {
        return Err(Error::Invalid(format!(
            "{} placements for {} poses: expected one per pose",
            path.len(),
            aligned.len()
        )));
    }
    let world: Vec<Vec<f32>> = aligned.iter().zip(path).map(|(p, pl)| pl.apply(p)).collect();
    let refs: Vec<&[f32]> = world.iter().map(|p| p.as_slice()).collect();
    poses_at(&refs, &inverse_times(times, own_frames)?)
}

/// Body-frame poses placed with the path's rotations and heights only (the ground position of
/// the path's first frame), re-timed to `own_frames`, then moved along the ground by the root
/// motion their own foot contacts give ([`VariantPath::Contacts`]).
pub fn place_by_contacts(
    model: &VariationModel,
    aligned: &[Vec<f32>],
    path: &[Placement],
    times: &[f64],
    own_frames: usize,
) -> Result<Vec<Vec<f32>>> {
    let Some(first) = path.first() else { return Err(Error::Invalid("an empty path".into())) };
    let (_, _, w) = surfcap_geometry::motion_plane_alignment::plane_axes(model.up_axis);
    let lifted: Vec<Placement> = path
        .iter()
        .map(|p| {
            let mut t = first.translation;
            t[w] = p.translation[w];
            Placement { rotation: p.rotation, translation: t }
        })
        .collect();
    let in_place = place_on_path(aligned, &lifted, times, own_frames)?;
    let nv = model.reference_pose.len() / 3;
    let mut flat: Vec<f32> = in_place.into_iter().flatten().collect();
    let params = surfcap_geometry::ground_contacts::ContactParams::default();
    let motion = surfcap_geometry::root_motion_from_contacts::root_motion_from_contacts(
        &flat,
        nv,
        model.fps,
        model.up_axis,
        &params,
    );
    surfcap_geometry::root_motion_from_contacts::apply_root_motion(&mut flat, nv, model.up_axis, &motion);
    Ok(flat.chunks_exact(3 * nv).map(<[f32]>::to_vec).collect())
}

/// `count` variants of the learnt sequence `name` for `seed` (6.6).
pub fn sample_variants(
    model: &VariationModel,
    name: &str,
    count: usize,
    seed: u64,
    opts: &SamplingOptions,
) -> Result<(Vec<Variant>, Vec<ChainSummary>)> {
    let j = model.sequence_index(name)?;
    let (latents, chains) = sample_latent_variants(model, j, count, seed, opts)?;
    let seq = &model.sequences[j];
    let place = |aligned: &[Vec<f32>], displacements: &[[f64; 6]]| {
        place_variant(
            model,
            opts.path,
            aligned,
            displacements,
            &seq.first_placement,
            &seq.path,
            &seq.times,
            seq.own_frames,
        )
    };
    let variants = variants_from_latents(model, latents, &model.learnt_latents(j)?, opts, place)?;
    Ok((variants, chains))
}

/// Variants from their sampled latent trajectories (`[variant][part]`): reconstructed and
/// stitched, their deviation from `learnt`'s poses smoothed over `opts.deviation_smoothing`
/// frames, given the stretch of `learnt` (the latent trajectories they vary) when
/// `opts.learnt_stretch` is on, put in the world by `place`, and cleaned of foot skate when
/// `opts.foot_skate_cleanup` is on (on the ground of `learnt` placed likewise).
pub(crate) fn variants_from_latents(
    model: &VariationModel,
    latents: LatentVariants,
    learnt: &[Mat<f64>],
    opts: &SamplingOptions,
    place: impl Fn(&[Vec<f32>], &[[f64; 6]]) -> Result<Vec<Vec<f32>>>,
) -> Result<Vec<Variant>> {
    let learnt = if opts.foot_skate_cleanup || opts.learnt_stretch || opts.deviation_smoothing > 0 {
        Some(reconstruct_aligned(model, learnt)?)
    } else {
        None
    };
    let stretch = match &learnt {
        Some(_) if opts.learnt_stretch => Some(LearntStretch::new(&model.topology, &model.reference_pose)?),
        _ => None,
    };
    let learnt_world = learnt.as_ref().map(|(la, ld)| place(la, ld)).transpose()?;
    let mut variants: Vec<Variant> = latents
        .into_iter()
        .map(|lat| {
            let (mut aligned, displacements) = reconstruct_aligned(model, &lat)?;
            if let Some((la, _)) = &learnt {
                smooth_deviation(&mut aligned, la, opts.deviation_smoothing)?;
            }
            let world = match (&stretch, &learnt, &learnt_world) {
                (Some(fix), Some((la, _)), Some(lw)) => {
                    aligned = fix.apply_all(&aligned, la)?;
                    // Re-timing blends neighbouring frames linearly: the stretch is given
                    // again, from the learnt motion placed and re-timed alike.
                    fix.apply_all(&place(&aligned, &displacements)?, lw)?
                }
                _ => place(&aligned, &displacements)?,
            };
            Ok(Variant { latents: lat, aligned, displacements, world, before_cleanup: None, cleanup: None })
        })
        .collect::<Result<_>>()?;
    if let (true, Some(lw)) = (opts.foot_skate_cleanup, &learnt_world) {
        clean_up_variants(model, &mut variants, lw, opts)?;
    }
    Ok(variants)
}

/// Body-frame poses (reference frames) put in the world by `path` (see [`VariantPath`]) and
/// re-timed to `own_frames` through `times`.
#[allow(clippy::too_many_arguments)]
pub fn place_variant(
    model: &VariationModel,
    path: VariantPath,
    aligned: &[Vec<f32>],
    displacements: &[[f64; 6]],
    start: &Placement,
    placements: &[Placement],
    times: &[f64],
    own_frames: usize,
) -> Result<Vec<Vec<f32>>> {
    match path {
        VariantPath::Sampled => place_and_retime(aligned, displacements, start, times, own_frames),
        VariantPath::Source => place_on_path(aligned, placements, times, own_frames),
        VariantPath::Contacts => place_by_contacts(model, aligned, placements, times, own_frames),
    }
}

/// The ground's travel under a motion authored in place, per frame along the two ground axes:
/// the root motion its own foot contacts give (surfcap-geometry's `root_motion_from_contacts`)
/// when its centre's net travel is under surfcap-motion's in-place threshold
/// (`IN_PLACE_HEIGHTS_PER_SECOND` x the subject's height per second), `None` when it travels.
/// `height` is the subject's height, `frames` the motion's world frames.
pub fn in_place_ground(frames: &[Vec<f32>], fps: f64, up: surfcap_mesh::UpAxis, height: f64) -> Option<Vec<[f64; 2]>> {
    let nv = frames.first().map_or(0, |f| f.len() / 3);
    if nv == 0 || frames.len() < 2 {
        return None;
    }
    let centre = |p: &[f32]| -> [f64; 3] {
        let s = p.chunks_exact(3).fold([0.0; 3], |a, q| [a[0] + q[0] as f64, a[1] + q[1] as f64, a[2] + q[2] as f64]);
        [s[0] / nv as f64, s[1] / nv as f64, s[2] / nv as f64]
    };
    let centres = [centre(&frames[0]), centre(&frames[frames.len() - 1])];
    let (net, _) = surfcap_motion::clip_travel::horizontal_travel(&centres, up);
    let seconds = (frames.len() - 1) as f64 / fps;
    if net >= surfcap_motion::clip_travel::IN_PLACE_HEIGHTS_PER_SECOND * height * seconds.max(1.0) {
        return None;
    }
    let flat: Vec<f32> = frames.iter().flatten().copied().collect();
    let params = surfcap_geometry::ground_contacts::ContactParams::default();
    let motion = surfcap_geometry::root_motion_from_contacts::root_motion_from_contacts(&flat, nv, fps, up, &params);
    Some(motion.offsets)
}

/// The extent of a pose along the up axis.
pub fn pose_height(pose: &[f32], up: surfcap_mesh::UpAxis) -> f64 {
    let (axis, sign) = up.axis_and_sign();
    let (lo, hi) = pose
        .chunks_exact(3)
        .map(|p| sign * p[axis] as f64)
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    (hi - lo).max(0.0)
}

/// Pins the planted feet of every variant ([`crate::foot_skate_cleanup`], default settings but
/// `opts.move_root` and `opts.carry_pins`, the legs being the parts named `leg*`/`foot*`),
/// keeping the frames before in
/// `before_cleanup`. `learnt_world` is the motion the variants vary, in the world with their
/// frame count: the learnt motion placed as they are ([`sample_variants`]), or the captured
/// source when it is at hand (`surfcap eval vary`: the ground its sliding is measured on).
/// When it is in place ([`in_place_ground`]) its ground travel is the ground the feet are
/// pinned to. A model without legs is left as it is.
pub fn clean_up_variants(
    model: &VariationModel,
    variants: &mut [Variant],
    learnt_world: &[Vec<f32>],
    opts: &SamplingOptions,
) -> Result<()> {
    if variants.is_empty() {
        return Ok(());
    }
    let params =
        FootSkateParams { move_root: opts.move_root, carry_pins: opts.carry_pins, ..FootSkateParams::default() };
    let Some(cleanup) = model_cleanup(model, params)? else { return Ok(()) };
    let height = pose_height(&model.reference_pose, model.up_axis);
    let ground = in_place_ground(learnt_world, model.fps, model.up_axis, height);
    for v in variants {
        if let Some(g) = &ground
            && g.len() != v.world.len()
        {
            return Err(Error::Invalid(format!(
                "the learnt motion has {} frames and its variant {}: expected one timing",
                g.len(),
                v.world.len()
            )));
        }
        let (cleaned, report) = cleanup.clean(&v.world, model.fps, ground.as_deref())?;
        v.before_cleanup = Some(std::mem::replace(&mut v.world, cleaned));
        v.cleanup = Some(report);
    }
    Ok(())
}

/// The foot-skate clean-up of a model's mesh with `params`, the legs being the parts named
/// `leg*`/`foot*`; `None` for a model without legs.
fn model_cleanup(model: &VariationModel, params: FootSkateParams) -> Result<Option<FootSkateCleanup>> {
    let legs = crate::motion_preparation::feet_of(&model.parts);
    if legs.is_empty() {
        return Ok(None);
    }
    Ok(Some(FootSkateCleanup::new(&model.topology, &model.reference_pose, model.up_axis, &legs, params)?))
}

/// A variant's frames and what the foot-skate clean-up did to them (`None` when not cleaned).
pub type CleanedVariant = (Vec<Vec<f32>>, Option<CleanupReport>);

/// Variants put on their source sequence `j`'s own path ([`variant_on_source_path`], what
/// synthesis shows), each with its planted feet pinned ([`crate::foot_skate_cleanup`]) when
/// `cleanup` is set and the model has legs: the clean-up [`sample_variants`] gives, on the
/// frames synthesis plays, except that the hips are held (`move_root` off). Synthesis placed
/// the walk to follow the user's path; moving the whole body with the planted feet would carry
/// it off that path (by 2.8 m on a 12 m line in
/// `surfcap-synthesis/tests/path_with_appearance_and_variants.rs`), so only the legs bend.
/// For a source authored in place the feet are pinned to the ground its own contacts give
/// ([`in_place_ground`] of `source`). Returns per variant its frames and what the clean-up did.
pub fn variants_on_source_path(
    model: &VariationModel,
    j: usize,
    variants: &[Variant],
    source: &[&[f32]],
    cleanup: bool,
) -> Result<Vec<CleanedVariant>> {
    let placed: Vec<Vec<Vec<f32>>> =
        variants.iter().map(|v| variant_on_source_path(model, j, v, source)).collect::<Result<_>>()?;
    // The hips held: see the doc comment (the path stays the user's).
    let fixer = if cleanup {
        model_cleanup(model, FootSkateParams { move_root: false, ..FootSkateParams::default() })?
    } else {
        None
    };
    let Some(fixer) = fixer else { return Ok(placed.into_iter().map(|p| (p, None)).collect()) };
    let owned: Vec<Vec<f32>> = source.iter().map(|p| p.to_vec()).collect();
    let height = pose_height(&model.reference_pose, model.up_axis);
    let ground = in_place_ground(&owned, model.fps, model.up_axis, height);
    placed
        .into_iter()
        .map(|p| {
            let (cleaned, report) = fixer.clean(&p, model.fps, ground.as_deref())?;
            Ok((cleaned, Some(report)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_undo_the_time_map() {
        // Own sequence of 5 frames stretched onto 9 reference frames.
        let times: Vec<f64> = (0..9).map(|i| i as f64 * 0.5).collect();
        let inv = inverse_times(&times, 5).unwrap();
        assert_eq!(inv, vec![0.0, 2.0, 4.0, 6.0, 8.0]);
        assert!(inverse_times(&times, 6).is_err(), "a map of 5 frames used for 6");
    }

    #[test]
    fn chain_seeds_differ_by_part_sequence_and_seed() {
        let a = chain_seed(1, "walk", 0);
        assert_ne!(a, chain_seed(1, "walk", 1));
        assert_ne!(a, chain_seed(1, "jog", 0));
        assert_ne!(a, chain_seed(2, "walk", 0));
        assert_eq!(a, chain_seed(1, "walk", 0));
    }

    #[test]
    fn placement_integrates_displacements_then_retimes() {
        let aligned = vec![vec![0.0f32, 0.0, 0.0]; 3];
        let d = [[0.0; 6], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]];
        let w = place_and_retime(&aligned, &d, &Placement::identity(), &[0.0, 1.0, 2.0], 3).unwrap();
        assert_eq!(w, vec![vec![0.0, 0.0, 0.0], vec![1.0, 0.0, 0.0], vec![2.0, 0.0, 0.0]]);
        // Own timing of 5 frames: every half reference frame.
        let w = place_and_retime(&aligned, &d, &Placement::identity(), &[0.0, 2.0, 4.0], 5).unwrap();
        assert_eq!(w[1], vec![0.5, 0.0, 0.0]);
        assert_eq!(w[4], vec![2.0, 0.0, 0.0]);
    }
}
