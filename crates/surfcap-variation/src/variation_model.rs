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
    /// Per reference frame, where the sequence's frame is in the world.
    pub path: Vec<surfcap_transfer::pose_representation::Placement>,
}

impl From<&TrainingSequence> for LearntSequence {
    fn from(s: &TrainingSequence) -> Self {
        LearntSequence {
            name: s.name.clone(),
            origin: s.origin.clone(),
            own_frames: s.own_frames,
            times: s.times.clone(),
            first_placement: s.first_placement,
            path: s.path.clone(),
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
        let prepared = prepare(subject, sequences, parts, &opts.preparation)?;
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
                if len != frames || s.times.len() != frames || s.path.len() != frames {
                    return Err(Error::Model(format!(
                        "sequence {:?}: {len} latent points of part {:?}, {} times and {} placements: expected {frames} (the reference's frames)",
                        s.name,
                        m.parts.parts[k].name,
                        s.times.len(),
                        s.path.len()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion_parametrisation::sample_blend_variants;
    use crate::variation_sampling::{SamplingOptions, sample_variants};
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_mesh::NoProgress;
    use surfcap_transfer::body_parts::Part;

    fn worm() -> Subject {
        worm_subject(&WormParams { rings: 8, segments: 6, frames: 16, ..WormParams::default() }).unwrap()
    }

    /// Head and tail halves overlapping over two rings.
    fn halves(s: &Subject) -> BodyParts {
        let n = s.topology().n_vertices() as u32;
        let ring = 6u32;
        let cut = n / 2;
        let head: Vec<u32> = (0..(cut + ring).min(n)).collect();
        let tail: Vec<u32> = (cut.saturating_sub(ring)..n).collect();
        BodyParts::new(
            n as usize,
            vec![
                Part { name: "head".into(), parent: None, vertices: head },
                Part { name: "tail".into(), parent: Some("head".into()), vertices: tail },
            ],
        )
        .unwrap()
    }

    fn quick() -> TrainOptions {
        let mut o = TrainOptions::default();
        o.gpdm.lbfgs.max_iters = 30;
        o.gpdm.lbfgs.max_evals = 40;
        o
    }

    fn sampling() -> SamplingOptions {
        SamplingOptions { warmup: 20, thin: 2, ..SamplingOptions::default() }
    }

    #[test]
    fn a_tiny_model_samples_variants_of_the_sequence_length_reproducibly() {
        let s = worm();
        let parts = halves(&s);
        let m = VariationModel::train(&s, &[0, 1], &parts, &quick(), &NoProgress).unwrap();
        assert_eq!(m.part_models.len(), 2);
        assert_eq!(m.sequences.len(), 2);
        assert_eq!(m.frames, s.sequences()[0].n_frames());
        let name = s.sequences()[1].name.clone();
        let (v, chains) = sample_variants(&m, &name, 2, 5, &sampling()).unwrap();
        assert_eq!((v.len(), chains.len()), (2, 2));
        for x in &v {
            assert_eq!(x.world.len(), s.sequences()[1].n_frames());
            assert!(x.world.iter().flatten().all(|c| c.is_finite()));
        }
        assert_ne!(v[0].world, v[1].world, "two variants of one seed are identical");
        let (again, _) = sample_variants(&m, &name, 2, 5, &sampling()).unwrap();
        assert_eq!(v[1].world, again[1].world, "same seed, different variants");
        let (other, _) = sample_variants(&m, &name, 2, 6, &sampling()).unwrap();
        assert_ne!(v[0].world, other[0].world, "another seed gave the same variant");
        // The learnt trajectory put on the source's path gives the source back.
        let lat = m.learnt_latents(1).unwrap();
        let (aligned, displacements) = crate::variation_sampling::reconstruct_aligned(&m, &lat).unwrap();
        let learnt = crate::variation_sampling::Variant {
            latents: lat,
            aligned,
            displacements,
            world: Vec::new(),
            before_cleanup: None,
            cleanup: None,
        };
        let src = &s.sequences()[1];
        let frames: Vec<&[f32]> = (0..src.n_frames()).map(|f| src.frame(f)).collect();
        let on_path = crate::variation_sampling::variant_on_source_path(&m, 1, &learnt, &frames).unwrap();
        let err = on_path
            .iter()
            .zip(&frames)
            .flat_map(|(a, b)| a.iter().zip(b.iter()))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(err < 0.01, "the learnt trajectory on the source's path is {err} m from it");
        assert!(crate::variation_sampling::variant_on_source_path(&m, 1, &learnt, &frames[1..]).is_err());
        let e = sample_variants(&m, "nope", 1, 0, &sampling()).unwrap_err().to_string();
        assert!(e.contains("nope") && e.contains(&name), "{e}");
    }

    #[test]
    fn training_and_sampling_do_not_depend_on_the_thread_count() {
        let s = worm();
        let parts = halves(&s);
        let name = s.sequences()[0].name.clone();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let m = VariationModel::train(&s, &[0, 1], &parts, &quick(), &NoProgress).unwrap();
                let (v, _) = sample_variants(&m, &name, 2, 11, &sampling()).unwrap();
                (m.part_models.iter().map(|g| g.latent().to_owned()).collect::<Vec<_>>(), v)
            })
        };
        let (l1, v1) = run(1);
        let (l2, v2) = run(2);
        assert_eq!(l1, l2, "latents differ between 1 and 2 threads");
        for (a, b) in v1.iter().zip(&v2) {
            assert_eq!(a.world, b.world, "variants differ between 1 and 2 threads");
        }
    }

    #[test]
    fn a_saved_model_loads_back_and_names_a_damaged_file() {
        let s = worm();
        let m = VariationModel::train(&s, &[0, 1], &halves(&s), &quick(), &NoProgress).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model");
        m.save(&path, false).unwrap();
        let back = VariationModel::load(&path).unwrap();
        let name = &s.sequences()[0].name;
        let (a, _) = sample_variants(&m, name, 1, 3, &sampling()).unwrap();
        let (b, _) = sample_variants(&back, name, 1, 3, &sampling()).unwrap();
        assert_eq!(a[0].world, b[0].world);
        let npy = path.join("part_1_frames.npy");
        let bytes = std::fs::read(&npy).unwrap();
        std::fs::write(&npy, &bytes[..bytes.len() - 16]).unwrap();
        let e = format!("{:#}", anyhow_chain(VariationModel::load(&path).err().unwrap()));
        assert!(e.contains("part_1_frames.npy"), "{e}");
        std::fs::write(&npy, &bytes).unwrap();
        let json = path.join("model.json");
        let text = std::fs::read_to_string(&json).unwrap().replace("surfcap-variation-model", "something-else");
        std::fs::write(&json, text).unwrap();
        let e = VariationModel::load(&path).err().unwrap().to_string();
        assert!(e.contains("model.json") && e.contains("surfcap-variation-model"), "{e}");
    }

    /// Repeated or empty names in a model file are refused naming the file and the field.
    #[test]
    fn repeated_names_in_a_model_file_name_the_file() {
        let s = worm();
        let m = VariationModel::train(&s, &[0, 1], &halves(&s), &quick(), &NoProgress).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model");
        m.save(&path, false).unwrap();
        let json = path.join("model.json");
        let good: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        type Edit = fn(&mut serde_json::Value);
        let edits: [(Edit, &str); 3] = [
            (|v| v["sequences"][1]["name"] = v["sequences"][0]["name"].clone(), "sequences 0 and 1 are both named"),
            (|v| v["sequences"][0]["name"] = "".into(), "sequence 0 has an empty name"),
            (|v| v["parts"]["parts"][1]["name"] = v["parts"]["parts"][0]["name"].clone(), "appears twice"),
        ];
        for (edit, want) in edits {
            let mut v = good.clone();
            edit(&mut v);
            std::fs::write(&json, serde_json::to_vec(&v).unwrap()).unwrap();
            let e = VariationModel::load(&path).err().unwrap().to_string();
            assert!(e.starts_with(&json.display().to_string()) && e.contains(want), "{e}");
        }
    }

    fn anyhow_chain(e: Error) -> String {
        let mut s = e.to_string();
        let mut src = std::error::Error::source(&e);
        while let Some(x) = src {
            s.push_str(": ");
            s.push_str(&x.to_string());
            src = x.source();
        }
        s
    }

    #[test]
    fn blends_join_training_and_give_variants_at_any_weight() {
        let s = worm();
        let mut o = quick();
        o.preparation.blend_pairs = vec![(0, 1)];
        o.preparation.blend_weights = vec![0.5];
        let m = VariationModel::train(&s, &[0, 1], &halves(&s), &o, &NoProgress).unwrap();
        assert_eq!(m.sequences.len(), 3);
        let (a, b) = (&s.sequences()[0].name, &s.sequences()[1].name);
        assert_eq!(m.sequences[2].name, format!("{a}+{b}@0.5"));
        let (v, info) = sample_blend_variants(&m, a, b, 0.25, 2, 1, &sampling()).unwrap();
        assert_eq!((info.lower.sequence, info.upper.sequence), (0, 2));
        assert_eq!(v.len(), 2);
        assert!(v[0].world.iter().flatten().all(|c| c.is_finite()));
        assert!(sample_blend_variants(&m, a, b, 1.5, 1, 1, &sampling()).is_err());
    }
}
