//! A trained transfer from one subject to another and its use on a new motion (thesis 5.3:
//! training, then "mapping each pose of the source sequence to a corresponding pose in the
//! space of the target subject"; 5.6: reconstruction).
//!
//! Training (the expensive part, done once and saved): both subjects' sequences aligned
//! ([`crate::pose_representation`]), a per-part PCA per subject, one GP per part and one for
//! the rigid displacement ([`crate::transfer_model`]) over the training pairs (dense pairs
//! from [`crate::correspondence_densification`], or the user's key pairs).
//!
//! Use (per frame, cheap): the source frame aligned to the source reference, its parts
//! encoded, each target part predicted (eq. 5.17) and decoded, the parts put back together
//! by a reconstruction the caller chooses (correction and stitching of 5.6.1-5.6.2, or the
//! average of the overlaps), and the target moved by the predicted displacements accumulated
//! from the target's reference placement: "all motions start at the same space location and
//! with the same initial orientation" (5.4.1), so the first transferred frame sits where the
//! target's reference pose is.

use std::collections::BTreeMap;

use faer::Mat;
use serde::{Deserialize, Serialize};
use surfcap_mesh::Subject;

use crate::body_parts::BodyParts;
use crate::error::{Error, Result};
use crate::pose_representation::{AlignedMotion, PartSpace, Placement, align_motion};
use crate::transfer_model::{MappingFit, MappingOptions, PoseMapping, fit_all};

/// One subject's sequences in the pose representation.
#[derive(Debug, Clone)]
pub struct PreparedSubject {
    /// The pose every frame is aligned onto (the first frame of the first prepared sequence).
    pub reference: Vec<f32>,
    /// Aligned motion per sequence index of the subject (only the prepared ones).
    pub motions: BTreeMap<usize, AlignedMotion>,
    /// Global frame -> (sequence, frame) of the subject.
    index: surfcap_mesh::FrameIndex,
}

impl PreparedSubject {
    /// Aligns the given sequences of `subject` (indices; the first gives the reference).
    pub fn new(subject: &Subject, sequences: &[usize]) -> Result<PreparedSubject> {
        let first = *sequences.first().ok_or_else(|| Error::Invalid("no sequence to prepare".into()))?;
        let reference = subject.sequences()[first].frame(0).to_vec();
        PreparedSubject::with_reference(subject, sequences, reference)
    }

    /// As [`PreparedSubject::new`] with a given reference pose.
    pub fn with_reference(subject: &Subject, sequences: &[usize], reference: Vec<f32>) -> Result<PreparedSubject> {
        let mut motions = BTreeMap::new();
        for &s in sequences {
            let seq = subject.sequences().get(s).ok_or_else(|| {
                Error::Invalid(format!("sequence {s}: the subject has {} sequences", subject.sequences().len()))
            })?;
            let frames: Vec<&[f32]> = (0..seq.n_frames()).map(|f| seq.frame(f)).collect();
            motions.insert(s, align_motion(&reference, &frames));
        }
        Ok(PreparedSubject { reference, motions, index: subject.frame_index().clone() })
    }

    /// The aligned pose and displacement of a global frame (which must be prepared).
    pub fn frame(&self, global: usize) -> Result<(&[f32], [f64; 6])> {
        let (s, f) = self
            .index
            .locate(global)
            .ok_or_else(|| Error::Invalid(format!("frame {global} is not a frame of the subject")))?;
        let m = self.motions.get(&s).ok_or_else(|| {
            Error::Invalid(format!("frame {}: its sequence was not prepared", self.index.label(global)))
        })?;
        Ok((&m.aligned[f], m.displacements[f]))
    }

    /// Every prepared frame's aligned pose.
    pub fn all_poses(&self) -> Vec<&[f32]> {
        self.motions.values().flat_map(|m| m.aligned.iter().map(|p| p.as_slice())).collect()
    }

    /// The (sequence, frame) of a global frame.
    pub fn locate(&self, global: usize) -> Option<(usize, usize)> {
        self.index.locate(global)
    }

    /// The global frames of sequence `k`.
    pub fn range(&self, k: usize) -> std::ops::Range<usize> {
        self.index.range(k)
    }

    /// `sequence:frame` of a global frame.
    pub fn label(&self, global: usize) -> String {
        self.index.label(global)
    }
}

/// Options of [`MotionTransfer::train`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct TrainOptions {
    /// PCA components per part (`m` of 5.4.3; 20 in the thesis).
    pub components: usize,
    pub mapping: MappingOptions,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions { components: 20, mapping: MappingOptions::default() }
    }
}

/// One subject's side of a trained transfer.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SubjectSpace {
    pub reference: Vec<f32>,
    pub parts: BodyParts,
    pub space: PartSpace,
}

impl SubjectSpace {
    /// A new pose aligned to this side's reference.
    pub fn align(&self, pose: &[f32]) -> (Vec<f32>, Placement) {
        crate::pose_representation::align_to_reference(&self.reference, pose)
    }
}

/// What training did, per part and for the displacement.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrainReport {
    pub pairs: usize,
    /// Per target part: name, vertices, source and target components, explained variance of
    /// the target PCA, and the fit.
    pub parts: Vec<PartReport>,
    pub displacement: MappingFit,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PartReport {
    pub name: String,
    pub source_vertices: usize,
    pub target_vertices: usize,
    pub source_components: usize,
    pub target_components: usize,
    /// Fraction of the target part's training variance its components keep.
    pub target_explained_variance: f64,
    pub fit: MappingFit,
}

/// A trained transfer from a source subject to a target subject.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MotionTransfer {
    pub source: SubjectSpace,
    pub target: SubjectSpace,
    /// For each target part, the index of the source part of the same name.
    pub source_part_of: Vec<usize>,
    /// One mapping per target part.
    pub part_maps: Vec<PoseMapping>,
    pub displacement_map: PoseMapping,
    pub options: TrainOptions,
}

/// A transferred motion: the target's aligned poses and its world poses.
#[derive(Debug, Clone)]
pub struct TransferredMotion {
    /// Per frame, each target part's predicted positions (part vertex order).
    pub parts: Vec<Vec<Vec<f32>>>,
    /// Per frame, the reconstructed target pose in the target's aligned (body) frame.
    pub aligned: Vec<Vec<f32>>,
    /// Per frame, the predicted rigid displacement from the previous frame (eq. 5.3).
    pub displacements: Vec<[f64; 6]>,
    /// Per frame, the target pose in the world: aligned poses moved by the accumulated
    /// displacements from the target's reference placement.
    pub world: Vec<Vec<f32>>,
}

impl TransferredMotion {
    /// The motion with its world frames: each aligned pose moved by the displacements
    /// accumulated from the reference placement (the first frame's displacement is not applied).
    pub fn placed(parts: Vec<Vec<Vec<f32>>>, aligned: Vec<Vec<f32>>, displacements: Vec<[f64; 6]>) -> Self {
        let mut placement = Placement::identity();
        let mut world = Vec::with_capacity(aligned.len());
        for (f, pose) in aligned.iter().enumerate() {
            if f > 0 {
                placement = placement.moved_by(&displacements[f]);
            }
            world.push(placement.apply(pose));
        }
        TransferredMotion { parts, aligned, displacements, world }
    }
}

/// The aligned poses of global frames.
fn poses_of<'a>(p: &'a PreparedSubject, frames: &[usize]) -> Result<Vec<&'a [f32]>> {
    frames.iter().map(|&g| p.frame(g).map(|f| f.0)).collect()
}

/// Matches target parts to source parts by name.
pub fn match_parts(source: &BodyParts, target: &BodyParts) -> Result<Vec<usize>> {
    let mut out = Vec::new();
    for p in &target.parts {
        match source.index(&p.name) {
            Some(k) => out.push(k),
            None => {
                return Err(Error::Parts(format!(
                    "the target's part \"{}\" has no source part of that name (source parts: {}; target parts: {}): both subjects need the same part names",
                    p.name,
                    source.names().join(", "),
                    target.names().join(", ")
                )));
            }
        }
    }
    if source.len() != target.len() {
        return Err(Error::Parts(format!(
            "the source has {} parts ({}) and the target {} ({}): both subjects need the same parts",
            source.len(),
            source.names().join(", "),
            target.len(),
            target.names().join(", ")
        )));
    }
    Ok(out)
}

impl MotionTransfer {
    /// Trains from frame pairs `(source global frame, target global frame)`. The per-part PCA
    /// of each subject is fitted to `pca_source` / `pca_target` (global frames; typically
    /// every frame of the training sequences).
    #[allow(clippy::too_many_arguments)]
    pub fn train(
        source: &PreparedSubject,
        source_parts: &BodyParts,
        pca_source: &[usize],
        target: &PreparedSubject,
        target_parts: &BodyParts,
        pca_target: &[usize],
        pairs: &[(usize, usize)],
        opts: &TrainOptions,
    ) -> Result<(MotionTransfer, TrainReport)> {
        if pairs.len() < 2 {
            return Err(Error::Invalid(format!("{} training pairs: expected at least 2", pairs.len())));
        }
        if opts.components == 0 {
            return Err(Error::Invalid("0 PCA components per part: expected at least 1".into()));
        }
        let source_part_of = match_parts(source_parts, target_parts)?;
        let source_space = PartSpace::fit(source_parts, &poses_of(source, pca_source)?, opts.components)?;
        let target_space = PartSpace::fit(target_parts, &poses_of(target, pca_target)?, opts.components)?;

        let src: Vec<(&[f32], [f64; 6])> = pairs.iter().map(|&(s, _)| source.frame(s)).collect::<Result<_>>()?;
        let tgt: Vec<(&[f32], [f64; 6])> = pairs.iter().map(|&(_, t)| target.frame(t)).collect::<Result<_>>()?;
        let src_poses: Vec<&[f32]> = src.iter().map(|p| p.0).collect();
        let tgt_poses: Vec<&[f32]> = tgt.iter().map(|p| p.0).collect();

        let mut problems = Vec::new();
        for (k, &sk) in source_part_of.iter().enumerate() {
            problems.push((source_space.encode(sk, &src_poses)?, target_space.encode(k, &tgt_poses)?));
        }
        let n = pairs.len();
        problems.push((Mat::from_fn(n, 6, |i, j| src[i].1[j]), Mat::from_fn(n, 6, |i, j| tgt[i].1[j])));
        let mut fitted = fit_all(problems, &opts.mapping)?;
        let (displacement_map, displacement_fit) = fitted.pop().expect("the displacement problem was pushed last");
        let mut part_maps = Vec::new();
        let mut part_reports = Vec::new();
        for (k, (map, fit)) in fitted.into_iter().enumerate() {
            let pca = &target_space.pcas[k];
            part_reports.push(PartReport {
                name: target_parts.parts[k].name.clone(),
                source_vertices: source_parts.parts[source_part_of[k]].vertices.len(),
                target_vertices: target_parts.parts[k].vertices.len(),
                source_components: source_space.dimension(source_part_of[k]),
                target_components: target_space.dimension(k),
                target_explained_variance: pca.explained_variance_ratio().iter().sum(),
                fit,
            });
            part_maps.push(map);
        }
        let model = MotionTransfer {
            source: SubjectSpace {
                reference: source.reference.clone(),
                parts: source_parts.clone(),
                space: source_space,
            },
            target: SubjectSpace {
                reference: target.reference.clone(),
                parts: target_parts.clone(),
                space: target_space,
            },
            source_part_of,
            part_maps,
            displacement_map,
            options: *opts,
        };
        Ok((model, TrainReport { pairs: n, parts: part_reports, displacement: displacement_fit }))
    }

    /// Predicts each target part (positions in part vertex order, target body frame) for
    /// aligned source poses: per frame, per part.
    pub fn predict_parts(&self, source_aligned: &[&[f32]]) -> Result<Vec<Vec<Vec<f32>>>> {
        let mut per_part = Vec::new();
        for (k, map) in self.part_maps.iter().enumerate() {
            let x = self.source.space.encode(self.source_part_of[k], source_aligned)?;
            let y = map.predict(&x)?;
            let rows: Vec<Vec<f32>> = (0..y.nrows())
                .map(|i| {
                    let c: Vec<f64> = (0..y.ncols()).map(|j| y[(i, j)]).collect();
                    self.target.space.decode(k, &c)
                })
                .collect::<Result<_>>()?;
            per_part.push(rows);
        }
        Ok((0..source_aligned.len()).map(|f| per_part.iter().map(|p| p[f].clone()).collect()).collect())
    }

    /// Predicts the target's displacement for each source displacement.
    pub fn predict_displacements(&self, source: &[[f64; 6]]) -> Result<Vec<[f64; 6]>> {
        if source.is_empty() {
            return Ok(Vec::new());
        }
        let x = Mat::from_fn(source.len(), 6, |i, j| source[i][j]);
        let y = self.displacement_map.predict(&x)?;
        Ok((0..y.nrows()).map(|i| std::array::from_fn(|j| y[(i, j)])).collect())
    }

    /// Transfers a source motion (consecutive frames of one sequence, world positions),
    /// putting each frame's predicted parts together with `reconstruct` (parts -> aligned
    /// whole target pose).
    pub fn transfer(
        &self,
        source_frames: &[&[f32]],
        mut reconstruct: impl FnMut(&[Vec<f32>]) -> Result<Vec<f32>>,
    ) -> Result<TransferredMotion> {
        let n_source = self.source.reference.len();
        if let Some(bad) = source_frames.iter().position(|f| f.len() != n_source) {
            return Err(Error::Invalid(format!(
                "source frame {bad} has {} vertices: expected {} (the source subject's)",
                source_frames[bad].len() / 3,
                n_source / 3
            )));
        }
        let motion = align_motion(&self.source.reference, source_frames);
        let refs: Vec<&[f32]> = motion.aligned.iter().map(|p| p.as_slice()).collect();
        let parts = self.predict_parts(&refs)?;
        let mut displacements = self.predict_displacements(&motion.displacements)?;
        // The first frame has no previous frame: no displacement (the GP's value at a zero
        // input is not one).
        if let Some(d) = displacements.first_mut() {
            *d = [0.0; 6];
        }
        let aligned: Vec<Vec<f32>> = parts.iter().map(|p| reconstruct(p)).collect::<Result<_>>()?;
        Ok(TransferredMotion::placed(parts, aligned, displacements))
    }
}
