//! The motion variation model (thesis 6.5): one GPDM per body part (eq. 6.1-6.7), all learnt
//! from the same prepared sequences so their latent spaces hold one trajectory per sequence
//! (6.5.2), plus what turning parts back into a mesh needs (the reference pose the stitching
//! is factorised on, the displacement scales, each sequence's placement and timing).
//!
//! Parts are fitted in parallel, each independently (the thesis's "independent models"); a
//! fit is deterministic, so the model does not depend on the number of threads.

use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use surfcap_learn::Mat;
use surfcap_learn::gpdm::{Gpdm, GpdmFitReport, GpdmOptions};
use surfcap_mesh::{Progress, Subject, Topology, UpAxis};
use surfcap_transfer::BodyParts;
use surfcap_transfer::part_stitching::Stitcher;

use crate::error::{Error, Result};
use crate::motion_preparation::{
    PreparationOptions, PreparedMotions, TrainingSequence, displacement_scales, part_matrix, part_vectors, prepare,
};

/// Options of [`VariationModel::train`].
#[derive(Debug, Clone, Default)]
pub struct TrainOptions {
    pub preparation: PreparationOptions,
    /// The GPDM of every part (thesis: d = 3).
    pub gpdm: GpdmOptions,
}

/// What training did, per part.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PartFit {
    pub part: String,
    /// Vertices of the part (overlaps included).
    pub vertices: usize,
    /// Values per frame (3 per vertex, + 6 for the root part's displacement).
    pub dimensions: usize,
    pub fit: GpdmFitReport,
    /// The thesis's hyper-parameters: alpha (eq. 6.4) and beta (eq. 6.6).
    pub alpha: [f64; 3],
    pub beta: [f64; 4],
    pub seconds: f64,
}

/// A learnt sequence as the model keeps it (its frames are in the GPDMs).
#[derive(Debug, Clone)]
pub struct LearntSequence {
    pub name: String,
    pub origin: crate::motion_preparation::SequenceOrigin,
    pub own_frames: usize,
    /// Per reference frame, the time in its own frames.
    pub times: Vec<f64>,
    pub first_placement: surfcap_transfer::pose_representation::Placement,
}

impl From<&TrainingSequence> for LearntSequence {
    fn from(s: &TrainingSequence) -> Self {
        LearntSequence {
            name: s.name.clone(),
            origin: s.origin.clone(),
            own_frames: s.own_frames,
            times: s.times.clone(),
            first_placement: s.first_placement,
        }
    }
}

/// A learnt variation model of one subject's motions of one type.
pub struct VariationModel {
    pub subject: String,
    pub topology: Topology,
    pub up_axis: UpAxis,
    pub fps: f64,
    pub units: surfcap_mesh::Units,
    pub parts: BodyParts,
    /// The pose every frame was aligned onto (first frame of the reference sequence).
    pub reference_pose: Vec<f32>,
    pub reference: String,
    pub sequences: Vec<LearntSequence>,
    /// One GPDM per part, in the order of `parts.parts`.
    pub part_models: Vec<Gpdm>,
    /// Scales of the displacement appended to the root part's vector.
    pub displacement_scales: [f64; 6],
    pub fits: Vec<PartFit>,
    /// Frames per learnt sequence (the reference's frame count).
    pub frames: usize,
    stitcher: Stitcher,
}

impl VariationModel {
    /// Prepares `sequences` of `subject` (6.4) and fits one GPDM per part (6.5).
    pub fn train(
        subject: &Subject,
        sequences: &[usize],
        parts: &BodyParts,
        opts: &TrainOptions,
        progress: &dyn Progress,
    ) -> Result<VariationModel> {
        parts.check_fits(subject.topology())?;
        progress.start("preparing the sequences", 1);
        let prepared = prepare(subject, sequences, &opts.preparation)?;
        progress.finish();
        let root = parts.root();
        let torso: Vec<Vec<f64>> =
            prepared.sequences.iter().flat_map(|s| part_vectors(parts, root, &s.aligned)).collect();
        let disp: Vec<[f64; 6]> = prepared.sequences.iter().flat_map(|s| s.displacements.iter().copied()).collect();
        let scales = displacement_scales(&torso, &disp);
        let lengths: Vec<usize> = prepared.sequences.iter().map(|s| s.aligned.len()).collect();
        progress.start("fitting a GPDM per body part", parts.len() as u64);
        let fitted: Vec<(Gpdm, PartFit)> = (0..parts.len())
            .into_par_iter()
            .map(|k| {
                let t0 = std::time::Instant::now();
                let y = part_matrix(&prepared, parts, k, (k == root).then_some(&scales));
                let seqs = split_rows(y.as_ref(), &lengths);
                let (g, fit) = Gpdm::fit(&seqs, &opts.gpdm)?;
                let (alpha, beta) = g.thesis_parameters();
                progress.advance(1);
                Ok((
                    g,
                    PartFit {
                        part: parts.parts[k].name.clone(),
                        vertices: parts.parts[k].vertices.len(),
                        dimensions: y.ncols(),
                        fit,
                        alpha,
                        beta,
                        seconds: t0.elapsed().as_secs_f64(),
                    },
                ))
            })
            .collect::<Result<_>>()?;
        progress.finish();
        let (part_models, fits): (Vec<Gpdm>, Vec<PartFit>) = fitted.into_iter().unzip();
        VariationModel::assemble(subject, parts.clone(), &prepared, part_models, scales, fits)
    }

    fn assemble(
        subject: &Subject,
        parts: BodyParts,
        prepared: &PreparedMotions,
        part_models: Vec<Gpdm>,
        displacement_scales: [f64; 6],
        fits: Vec<PartFit>,
    ) -> Result<VariationModel> {
        VariationModel::from_parts(ModelParts {
            subject: subject.name.clone(),
            topology: subject.topology().clone(),
            up_axis: subject.up_axis,
            fps: subject.fps,
            units: subject.units.clone(),
            parts,
            reference_pose: prepared.reference_pose.clone(),
            reference: prepared.reference.clone(),
            sequences: prepared.sequences.iter().map(LearntSequence::from).collect(),
            part_models,
            displacement_scales,
            fits,
        })
    }

    /// A model from its pieces (as read from disk), checking they fit together and
    /// factorising the stitching on the reference pose.
    pub fn from_parts(m: ModelParts) -> Result<VariationModel> {
        let n = m.topology.n_vertices();
        if m.reference_pose.len() != 3 * n {
            return Err(Error::Model(format!(
                "the reference pose has {} coordinates: expected 3 x {n} for the topology",
                m.reference_pose.len()
            )));
        }
        if m.part_models.len() != m.parts.len() || m.fits.len() != m.parts.len() {
            return Err(Error::Model(format!(
                "{} part models and {} fit reports for {} body parts: expected one of each per part",
                m.part_models.len(),
                m.fits.len(),
                m.parts.len()
            )));
        }
        let root = m.parts.root();
        let frames = m.sequences.first().map_or(0, |s| s.times.len());
        for (k, g) in m.part_models.iter().enumerate() {
            let d = 3 * m.parts.parts[k].vertices.len() + if k == root { 6 } else { 0 };
            let n_seq = g.sequence_count();
            if g.output_dim() != d || n_seq != m.sequences.len() {
                return Err(Error::Model(format!(
                    "part {:?}: its GPDM has {} values per frame and {n_seq} sequences: expected {d} and {}",
                    m.parts.parts[k].name,
                    g.output_dim(),
                    m.sequences.len()
                )));
            }
            for (j, s) in m.sequences.iter().enumerate() {
                let len = g.sequence_latent(j).map_or(0, |x| x.nrows());
                if len != frames || s.times.len() != frames {
                    return Err(Error::Model(format!(
                        "sequence {:?}: {len} latent points of part {:?} and {} times: expected {frames} (the reference's frames)",
                        s.name,
                        m.parts.parts[k].name,
                        s.times.len()
                    )));
                }
            }
        }
        let stitcher = Stitcher::new(&m.topology, &m.reference_pose, &m.parts)?;
        Ok(VariationModel {
            subject: m.subject,
            topology: m.topology,
            up_axis: m.up_axis,
            fps: m.fps,
            units: m.units,
            parts: m.parts,
            reference_pose: m.reference_pose,
            reference: m.reference,
            sequences: m.sequences,
            part_models: m.part_models,
            displacement_scales: m.displacement_scales,
            fits: m.fits,
            frames,
            stitcher,
        })
    }

    /// The index of the learnt sequence `name`, or an error listing them.
    pub fn sequence_index(&self, name: &str) -> Result<usize> {
        self.sequences.iter().position(|s| s.name == name).ok_or_else(|| {
            Error::Invalid(format!(
                "no learnt sequence {name:?}: the model has {}",
                self.sequences.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", ")
            ))
        })
    }

    /// The learnt latent trajectory of sequence `j` for every part.
    pub fn learnt_latents(&self, j: usize) -> Result<Vec<Mat<f64>>> {
        self.part_models
            .iter()
            .map(|g| {
                g.sequence_latent(j)
                    .map(|x| x.to_owned())
                    .ok_or_else(|| Error::Invalid(format!("sequence {j}: the model has {}", self.sequences.len())))
            })
            .collect()
    }

    pub(crate) fn stitcher(&self) -> &Stitcher {
        &self.stitcher
    }
}

/// The pieces of a [`VariationModel`], as [`crate::variation_model_file`] reads them.
pub struct ModelParts {
    pub subject: String,
    pub topology: Topology,
    pub up_axis: UpAxis,
    pub fps: f64,
    pub units: surfcap_mesh::Units,
    pub parts: BodyParts,
    pub reference_pose: Vec<f32>,
    pub reference: String,
    pub sequences: Vec<LearntSequence>,
    pub part_models: Vec<Gpdm>,
    pub displacement_scales: [f64; 6],
    pub fits: Vec<PartFit>,
}

/// The rows of `y` split into consecutive blocks of `lengths`.
fn split_rows<'a>(y: MatRef<'a, f64>, lengths: &[usize]) -> Vec<MatRef<'a, f64>> {
    let mut at = 0;
    lengths
        .iter()
        .map(|&l| {
            let r = y.subrows(at, l);
            at += l;
            r
        })
        .collect()
}
