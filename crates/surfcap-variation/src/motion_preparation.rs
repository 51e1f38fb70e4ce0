//! Preparation of the training sequences (thesis 6.4 and 6.5.2): what a GPDM per body part
//! learns from.
//!
//! - **Rigid alignment** (6.4.1): every frame Procrustes-aligned (rotation + translation) onto
//!   the reference pose, the first frame of the reference sequence; the relative rigid
//!   displacement between successive frames kept as 6 numbers `(dT, log dR)` in the previous
//!   frame's body coordinates (exact log, as in chapter 5's `pose_representation`).
//! - **Temporal pre-alignment** (6.5.2, 6.8: "temporally aligned to *Walk* with dynamic time
//!   warping"): every sequence is re-timed onto the reference sequence's frames, so all
//!   training sequences have the reference's frame count and frame i of each is at the same
//!   phase of the motion. Each keeps its time map (for every reference frame, the time in its
//!   own frames), so a variant is brought back to the sequence's own timing and frame count.
//!   Poses between two captured frames are interpolated linearly (consecutive frames differ
//!   little), placements by translation lerp and rotation slerp; the displacements are
//!   recomputed from the re-timed placements (a jog re-timed onto a walk's frames covers more
//!   ground per frame).
//! - **Blends** (6.7): a pair of sequences blended frame by frame at weight w with the
//!   non-linear interpolation of chapter 2 (eq. 2.45-2.49) on the aligned poses, their
//!   displacements blended linearly, their time maps and frame counts too.
//! - **Body parts** (6.4.2): each part's vertices (overlaps included) of the aligned pose,
//!   stacked as one vector per frame; the root part (torso) gets the 6 displacement numbers
//!   appended, each scaled to the torso's mean coordinate spread (see
//!   [`displacement_scales`]).

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use surfcap_geometry::foot_contacts::foot_contacts;
use surfcap_geometry::ground_contacts::{ContactParams, ground_contacts};
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_learn::Mat;
use surfcap_mesh::{Subject, Topology, UpAxis};
use surfcap_motion::sequence_time_alignment::{
    TimeAlignmentParams, align_sequences, resample_placements, resample_poses,
};
use surfcap_transfer::BodyParts;
use surfcap_transfer::pose_representation::{Placement, align_motion};

use crate::error::{Error, Result};

/// How sequences are re-timed onto the reference sequence.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TimeAlignment {
    /// Frame i of the reference is time `i (n - 1) / (N - 1)` of a sequence of n frames: the
    /// two are only stretched to one length.
    Uniform,
    /// Slope-constrained DTW of the aligned poses (surfcap-motion's `sequence_time_alignment`,
    /// thesis 6.5.2), guided by foot contacts when the body parts name legs (6.8: "dynamic
    /// time warping guided with feet contact annotation"); `contact_weight` 0 ignores them.
    Dtw { contact_weight: f64 },
}

impl Default for TimeAlignment {
    fn default() -> Self {
        TimeAlignment::Dtw { contact_weight: 1.0 }
    }
}

/// Where a training sequence comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum SequenceOrigin {
    /// A sequence of the subject.
    Captured { sequence: String },
    /// Two captured sequences blended non-linearly: `(1 - w) a + w b` (6.7).
    Blend { a: String, b: String, w: f64 },
}

/// One training sequence, re-timed onto the reference's frames.
#[derive(Debug, Clone)]
pub struct TrainingSequence {
    /// The subject's sequence name, or `a+b@w` for a blend.
    pub name: String,
    pub origin: SequenceOrigin,
    /// Frames at its own timing.
    pub own_frames: usize,
    /// Per reference frame, the time in its own frames (non-decreasing, first 0, last
    /// `own_frames - 1`).
    pub times: Vec<f64>,
    /// Per reference frame, the pose aligned onto the reference pose.
    pub aligned: Vec<Vec<f32>>,
    /// Where its first frame is in the world.
    pub first_placement: Placement,
    /// Per reference frame, where the frame is in the world (the path a variant can be put
    /// on, `VariantPath::Source`).
    pub path: Vec<Placement>,
    /// Per reference frame, the rigid displacement from the previous one (zero for the first).
    pub displacements: Vec<[f64; 6]>,
}

/// All training sequences of one motion type, ready for [`crate::variation_model`].
#[derive(Debug, Clone)]
pub struct PreparedMotions {
    /// The reference pose (first frame of the reference sequence): every pose is aligned onto
    /// it, and stitching is factorised on it.
    pub reference_pose: Vec<f32>,
    /// The reference sequence's name.
    pub reference: String,
    pub sequences: Vec<TrainingSequence>,
}

/// Options of [`prepare`].
#[derive(Debug, Clone)]
pub struct PreparationOptions {
    /// The sequence the others are re-timed onto (index into the chosen sequences).
    pub reference: usize,
    pub time_alignment: TimeAlignment,
    /// Pairs of chosen sequences (indices) to blend, and the weights (6.7: W = {0.5}).
    pub blend_pairs: Vec<(usize, usize)>,
    pub blend_weights: Vec<f64>,
}

impl Default for PreparationOptions {
    fn default() -> Self {
        PreparationOptions {
            reference: 0,
            time_alignment: TimeAlignment::default(),
            blend_pairs: Vec::new(),
            blend_weights: vec![0.5],
        }
    }
}

/// The times of a uniform stretch of `own` frames onto `n` reference frames.
pub fn uniform_times(own: usize, n: usize) -> Vec<f64> {
    if n < 2 {
        return vec![0.0; n];
    }
    (0..n).map(|i| i as f64 * (own - 1) as f64 / (n - 1) as f64).collect()
}

/// Interpolated poses at fractional frame times (linear between the two neighbouring frames;
/// surfcap-motion's `resample_poses`).
pub fn poses_at(frames: &[&[f32]], times: &[f64]) -> Result<Vec<Vec<f32>>> {
    Ok(resample_poses(frames, times)?)
}

/// Interpolated placements at fractional frame times: translation lerp, rotation along the
/// geodesic (surfcap-motion's `resample_placements`).
pub fn placements_at(placements: &[Placement], times: &[f64]) -> Result<Vec<Placement>> {
    let pairs: Vec<(Matrix3<f64>, Vector3<f64>)> = placements.iter().map(|p| (p.rotation, p.translation)).collect();
    Ok(resample_placements(&pairs, times)?
        .into_iter()
        .map(|(rotation, translation)| Placement { rotation, translation })
        .collect())
}

/// The vertices of the feet for contact detection: the parts named after a leg or a foot
/// (`leg...`, `foot...`, any case), as `surfcap parts propose` names them. Other parts files
/// give none: the time alignment then uses the poses alone.
pub fn feet_of(parts: &BodyParts) -> Vec<Vec<u32>> {
    parts
        .parts
        .iter()
        .filter(|p| {
            let n = p.name.to_ascii_lowercase();
            n.starts_with("leg") || n.starts_with("foot")
        })
        .map(|p| p.vertices.clone())
        .collect()
}

/// Per-frame foot contact signals of one sequence (`[frame][foot]`), from its world frames.
fn contact_signals(frames: &[&[f32]], fps: f64, up: UpAxis, feet: &[Vec<u32>]) -> Result<Vec<Vec<f64>>> {
    let nv = frames[0].len() / 3;
    let flat: Vec<f32> = frames.iter().flat_map(|f| f.iter().copied()).collect();
    let contacts = ground_contacts(&flat, nv, fps, up, &ContactParams::default());
    Ok(foot_contacts(&contacts, nv, feet)?.by_frame())
}

/// The displacement of each placement from the previous one (zero for the first), eq. 5.3.
pub fn displacements_of(placements: &[Placement]) -> Vec<[f64; 6]> {
    (0..placements.len())
        .map(|i| if i == 0 { [0.0; 6] } else { placements[i - 1].displacement_to(&placements[i]) })
        .collect()
}

/// Prepares `sequences` (indices of the subject's sequences, at least one, each of at least
/// two frames) for learning.
pub fn prepare(
    subject: &Subject,
    sequences: &[usize],
    parts: &BodyParts,
    opts: &PreparationOptions,
) -> Result<PreparedMotions> {
    if sequences.is_empty() {
        return Err(Error::Invalid("no sequences to learn: expected at least one".into()));
    }
    let all = subject.sequences();
    for &q in sequences {
        let s = all.get(q).ok_or_else(|| {
            Error::Invalid(format!("sequence {q}: the subject {:?} has {} sequences", subject.name, all.len()))
        })?;
        if s.n_frames() < 2 {
            return Err(Error::Invalid(format!(
                "sequence {:?} has {} frame: expected at least 2 to learn a motion",
                s.name,
                s.n_frames()
            )));
        }
    }
    let r = *sequences.get(opts.reference).ok_or_else(|| {
        Error::Invalid(format!("reference {}: only {} sequences are learnt", opts.reference, sequences.len()))
    })?;
    let reference_pose = all[r].frame(0).to_vec();
    let n_ref = all[r].n_frames();
    let frames_of = |q: usize| -> Vec<&[f32]> { (0..all[q].n_frames()).map(|f| all[q].frame(f)).collect() };
    let motions: Vec<_> = sequences.iter().map(|&q| align_motion(&reference_pose, &frames_of(q))).collect();
    let feet = feet_of(parts);
    let contacts: Option<Vec<Vec<Vec<f64>>>> = match opts.time_alignment {
        TimeAlignment::Dtw { contact_weight } if contact_weight > 0.0 && !feet.is_empty() => Some(
            sequences
                .iter()
                .map(|&q| contact_signals(&frames_of(q), subject.fps, subject.up_axis, &feet))
                .collect::<Result<_>>()?,
        ),
        _ => None,
    };
    let ri = opts.reference;
    let mut out: Vec<TrainingSequence> = Vec::with_capacity(sequences.len());
    for (k, &q) in sequences.iter().enumerate() {
        let s = &all[q];
        let motion = &motions[k];
        let aligned_refs: Vec<&[f32]> = motion.aligned.iter().map(|p| p.as_slice()).collect();
        let times = match opts.time_alignment {
            TimeAlignment::Uniform => uniform_times(s.n_frames(), n_ref),
            TimeAlignment::Dtw { .. } if k == ri => uniform_times(s.n_frames(), n_ref),
            TimeAlignment::Dtw { contact_weight } => {
                let reference: Vec<&[f32]> = motions[ri].aligned.iter().map(|p| p.as_slice()).collect();
                let pair = contacts.as_ref().map(|c| (c[ri].as_slice(), c[k].as_slice()));
                let params = TimeAlignmentParams { contact_weight, ..TimeAlignmentParams::default() };
                align_sequences(&reference, &aligned_refs, pair, &params)
                    .map_err(|e| {
                        Error::Invalid(format!(
                            "{:?} cannot be aligned in time to the reference {:?}: {e}",
                            s.name, all[r].name
                        ))
                    })?
                    .time_map
                    .times()
                    .to_vec()
            }
        };
        let aligned = poses_at(&aligned_refs, &times)?;
        let placements = placements_at(&motion.placements, &times)?;
        out.push(TrainingSequence {
            name: s.name.clone(),
            origin: SequenceOrigin::Captured { sequence: s.name.clone() },
            own_frames: s.n_frames(),
            displacements: displacements_of(&placements),
            first_placement: placements[0],
            path: placements,
            times,
            aligned,
        });
    }
    let mut blends = Vec::new();
    for &(a, b) in &opts.blend_pairs {
        if a >= out.len() || b >= out.len() || a == b {
            return Err(Error::Invalid(format!(
                "blend pair ({a}, {b}): expected two different sequences among the {} learnt",
                out.len()
            )));
        }
        for &w in &opts.blend_weights {
            if !(w > 0.0 && w < 1.0) {
                return Err(Error::Invalid(format!("blend weight {w}: expected a value strictly between 0 and 1")));
            }
            blends.push(blend_sequences(subject.topology(), subject.up_axis, &out[a], &out[b], w)?);
        }
    }
    out.extend(blends);
    Ok(PreparedMotions { reference_pose, reference: all[r].name.clone(), sequences: out })
}

/// The name of the blend of `a` and `b` at `w`.
pub fn blend_name(a: &str, b: &str, w: f64) -> String {
    format!("{a}+{b}@{w}")
}

/// Two re-timed sequences blended frame by frame at weight `w` (thesis 6.7: `Y_w = (1 - w) Y_1
/// + w Y_2`, non-linearly: eq. 2.45-2.49 on the aligned poses). Displacements are blended
/// linearly (they are small per-frame motions), as are the time maps, mapped to the blend's
/// own frame count `round((1 - w) n_a + w n_b)`.
pub fn blend_sequences(
    topology: &Topology,
    up: UpAxis,
    a: &TrainingSequence,
    b: &TrainingSequence,
    w: f64,
) -> Result<TrainingSequence> {
    if a.aligned.len() != b.aligned.len() {
        return Err(Error::Invalid(format!(
            "blend of {:?} ({} frames) and {:?} ({} frames): expected sequences re-timed to one length",
            a.name,
            a.aligned.len(),
            b.name,
            b.aligned.len()
        )));
    }
    let aligned: Vec<Vec<f32>> = a
        .aligned
        .par_iter()
        .zip(&b.aligned)
        .map(|(pa, pb)| Ok(NonlinearInterpolator::new(topology, pa, pb, up)?.at(w, StretchInterpolation::Linear)))
        .collect::<Result<_>>()?;
    let displacements: Vec<[f64; 6]> = a
        .displacements
        .iter()
        .zip(&b.displacements)
        .map(|(x, y)| std::array::from_fn(|k| (1.0 - w) * x[k] + w * y[k]))
        .collect();
    let own_frames = (((1.0 - w) * a.own_frames as f64 + w * b.own_frames as f64).round() as usize).max(2);
    let span = |s: &TrainingSequence| (s.own_frames - 1).max(1) as f64;
    let mut times: Vec<f64> = a
        .times
        .iter()
        .zip(&b.times)
        .map(|(ta, tb)| ((1.0 - w) * ta / span(a) + w * tb / span(b)) * (own_frames - 1) as f64)
        .collect();
    pin_ends(&mut times, own_frames);
    Ok(TrainingSequence {
        name: blend_name(&a.name, &b.name, w),
        origin: SequenceOrigin::Blend { a: a.name.clone(), b: b.name.clone(), w },
        own_frames,
        times,
        aligned,
        first_placement: a.first_placement,
        path: integrate(&a.first_placement, &displacements),
        displacements,
    })
}

/// The placements reached from `start` by the displacements (the first one is `start`).
pub fn integrate(start: &Placement, displacements: &[[f64; 6]]) -> Vec<Placement> {
    let mut p = *start;
    displacements
        .iter()
        .enumerate()
        .map(|(i, d)| {
            if i > 0 {
                p = p.moved_by(d);
            }
            p
        })
        .collect()
}

/// Pins a time map's first time at 0 and its last at `own_frames - 1` (round-off of an
/// interpolated map).
pub fn pin_ends(times: &mut [f64], own_frames: usize) {
    if let Some(t) = times.first_mut() {
        *t = 0.0;
    }
    if let Some(t) = times.last_mut() {
        *t = (own_frames - 1) as f64;
    }
}

/// Scales of the six displacement numbers appended to the torso's vector: each is multiplied
/// so its spread over the training frames equals the torso coordinates' mean spread (a
/// constant column, e.g. the zero travel of an in-place clip, is left at 1). The thesis
/// appends them as they are; next to hundreds of vertex coordinates in metres, centimetres of
/// travel per frame and hundredths of a radian would be noise the isotropic kernel cannot
/// tell from it. Scaling does not change the GP's mean prediction of a column, only how much
/// the displacement weighs in the latent space.
pub fn displacement_scales(torso: &[Vec<f64>], displacements: &[[f64; 6]]) -> [f64; 6] {
    let n = torso.len().max(1) as f64;
    let d = torso.first().map_or(0, Vec::len);
    let mut spread = 0.0;
    for j in 0..d {
        let m = torso.iter().map(|r| r[j]).sum::<f64>() / n;
        spread += torso.iter().map(|r| (r[j] - m).powi(2)).sum::<f64>() / n;
    }
    let torso_sd = (spread / d.max(1) as f64).sqrt();
    std::array::from_fn(|k| {
        let m = displacements.iter().map(|x| x[k]).sum::<f64>() / n;
        let sd = (displacements.iter().map(|x| (x[k] - m).powi(2)).sum::<f64>() / n).sqrt();
        if sd > 1e-12 * (1.0 + torso_sd) && torso_sd > 0.0 { torso_sd / sd } else { 1.0 }
    })
}

/// Part `k`'s vector of every frame of `poses` (its vertices' coordinates, overlaps included).
pub fn part_vectors(parts: &BodyParts, k: usize, poses: &[Vec<f32>]) -> Vec<Vec<f64>> {
    let verts = &parts.parts[k].vertices;
    poses
        .iter()
        .map(|p| verts.iter().flat_map(|&v| (0..3).map(move |c| p[3 * v as usize + c] as f64)).collect())
        .collect()
}

/// The training matrix of part `k`: one row per frame of every sequence (concatenated), the
/// root part's rows with the scaled displacement appended.
pub fn part_matrix(prepared: &PreparedMotions, parts: &BodyParts, k: usize, scales: Option<&[f64; 6]>) -> Mat<f64> {
    let rows: Vec<Vec<f64>> = prepared
        .sequences
        .iter()
        .flat_map(|s| {
            let mut v = part_vectors(parts, k, &s.aligned);
            if let Some(sc) = scales {
                for (r, d) in v.iter_mut().zip(&s.displacements) {
                    r.extend((0..6).map(|c| d[c] * sc[c]));
                }
            }
            v
        })
        .collect();
    let cols = rows.first().map_or(0, Vec::len);
    Mat::from_fn(rows.len(), cols, |i, j| rows[i][j])
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_geometry::rotation_log_exp::{exp_rotation, log_rotation};

    #[test]
    fn uniform_times_span_the_own_frames() {
        let t = uniform_times(5, 9);
        assert_eq!(t.len(), 9);
        assert_eq!(t[0], 0.0);
        assert_eq!(t[8], 4.0);
        assert!((t[4] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn poses_and_placements_interpolate_between_neighbours() {
        let f0 = [0.0f32, 0.0, 0.0];
        let f1 = [2.0f32, 4.0, 6.0];
        let p = poses_at(&[&f0, &f1], &[0.0, 0.25, 1.0]).unwrap();
        assert!(poses_at(&[&f0, &f1], &[7.0]).is_err(), "a time after the last frame");
        assert_eq!(p[0], vec![0.0, 0.0, 0.0]);
        assert_eq!(p[1], vec![0.5, 1.0, 1.5]);
        assert_eq!(p[2], vec![2.0, 4.0, 6.0]);
        let a = Placement::identity();
        let b = Placement {
            rotation: exp_rotation(&Vector3::new(0.0, 0.0, 1.0)),
            translation: Vector3::new(2.0, 0.0, 0.0),
        };
        let m = placements_at(&[a, b], &[0.5]).unwrap()[0];
        assert!((log_rotation(&m.rotation) - Vector3::new(0.0, 0.0, 0.5)).norm() < 1e-12);
        assert!((m.translation - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        let d = displacements_of(&[a, b]);
        assert_eq!(d[0], [0.0; 6]);
        assert!((d[1][0] - 2.0).abs() < 1e-12 && (d[1][5] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn displacement_scales_match_the_torso_spread_and_leave_constants() {
        let torso = vec![vec![0.0, 0.0], vec![2.0, 2.0]];
        let disp = [[0.1, 0.0, 0.0, 0.0, 0.0, 0.0], [0.3, 0.0, 0.0, 0.0, 0.0, 0.0]];
        let s = displacement_scales(&torso, &disp);
        // Torso sd 1, first column sd 0.1.
        assert!((s[0] - 10.0).abs() < 1e-9, "{s:?}");
        assert_eq!(s[1], 1.0);
    }
}
