//! Motion transfer evaluation (thesis 5.7, Fig. 5.8-5.10; CVPR 2017 Fig. 7) on pairs of
//! subjects with exact ground truth: the same skeletal clip played by two bodies, so frame f
//! of one is the true partner of frame f of the other.
//!
//! - **Cases**: the KayKit knight to the barbarian, mage and rogue (`kaykit_case`: the same
//!   clips on different bodies and topologies), and built-in mannequins of different shapes
//!   and vertex counts driven by the same CMU clips (`mannequin_case`).
//! - **Learning curves** (5.7.1, Fig. 5.8): every true pair of the training motions pooled,
//!   split 70/30 at random (seeded); for each training-set size n, each method trained on the
//!   first n pairs of the shuffled 70% and measured on them (training error) and on the 30%
//!   (cross-validation error). Error: the RMS per-vertex distance between the transferred
//!   target pose and the true one after a rigid (Procrustes) alignment of the truth onto the
//!   prediction, over all vertices and frames, as a percentage of the target's height (and in
//!   its units). The per-part PCA is fitted to the n training poses only, so nothing of the
//!   test poses is seen in training (the thesis does not say; this is the honest reading).
//! - **Key-seeded curves** (5.7.2, Fig. 5.9): the same, with each training subset starting
//!   from the key poses (5 evenly spaced frames per training sequence).
//! - **Body parts** (5.7.3, Fig. 5.10): GP-NN on the whole body with `parts x m` components
//!   against the parts with `m` each: equal total input and output dimensions.
//! - **Unseen motions**: trained on every pair of the training motions (walks, runs, jumps),
//!   tested on motions absent from training (dodges, cheering, idling; a run-to-stop and a
//!   dance for the mannequins), reported per motion.
//!
//! Methods: GP regression with the NN, SE and linear kernels (`surfcap_transfer::
//! transfer_model`) and Baran et al. 2009 with the training pairs as its key poses
//! (`surfcap_transfer::semantic_deformation_transfer`); the GP methods reconstructed by
//! averaging the overlaps (the regression itself is
//! measured, as the thesis's Fig. 5.7 shows raw outputs "prior to the mesh enhancement").

use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use serde::Serialize;
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_formats::import::{ImportOptions, import};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_transfer::BodyParts;
use surfcap_transfer::body_parts_proposal::{Method as ProposalMethod, propose};
use surfcap_transfer::correspondence_densification::DensifyOptions;
use surfcap_transfer::motion_transfer::{MotionTransfer, PreparedSubject, TrainOptions};
use surfcap_transfer::part_stitching::{EdgeDistortion, average_overlaps, edge_distortion_by_region};
use surfcap_transfer::semantic_deformation_transfer::SemanticDeformationTransfer;
use surfcap_transfer::shape_reconstruction::{ReconstructionOptions, Reconstructor};
use surfcap_transfer::training_pairs::densified_pairs;
use surfcap_transfer::transfer_model::TransferKernel;

use crate::MeanStd;
use crate::error::{Error, Result};

/// The method name of the unseen-motion rows of GP-NN on the whole body (one part, as many
/// components as the parts have together), next to GP-NN on the parts.
pub const WHOLE_BODY_GP_NN: &str = "GP-NN whole body";

/// A pair of subjects with ground truth.
pub struct TransferCase {
    pub name: String,
    pub source: Subject,
    pub target: Subject,
    pub source_parts: BodyParts,
    pub target_parts: BodyParts,
    /// Motions (sequence index in the source, in the target) used for training.
    pub train: Vec<(usize, usize)>,
    /// Motions absent from training.
    pub unseen: Vec<(usize, usize)>,
    /// Whether this is a case built the other way round by [`TransferCase::reversed`].
    pub reversed: bool,
}

impl TransferCase {
    /// The same case the other way round (target to source), as the thesis evaluates both
    /// directions: subjects, parts and motion pairs swapped, named `target -> source`.
    pub fn reversed(&self) -> TransferCase {
        let swap = |v: &[(usize, usize)]| v.iter().map(|&(a, b)| (b, a)).collect();
        TransferCase {
            name: format!("{} -> {}", self.target.name, self.source.name),
            source: self.target.clone(),
            target: self.source.clone(),
            source_parts: self.target_parts.clone(),
            target_parts: self.source_parts.clone(),
            train: swap(&self.train),
            unseen: swap(&self.unseen),
            reversed: !self.reversed,
        }
    }
}

/// A method compared in the curves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    GpNn,
    GpSe,
    Linear,
    /// Baran et al. 2009, with the training pairs as its key poses (whole body).
    Baran,
    /// The baseline every learnt method must beat: the target pose of the training pair whose
    /// source pose is nearest (RMS over the aligned source vertices) to the source pose.
    NearestPose,
}

impl Method {
    pub const ALL: [Method; 5] = [Method::GpNn, Method::GpSe, Method::Linear, Method::Baran, Method::NearestPose];

    pub fn name(self) -> &'static str {
        match self {
            Method::GpNn => "GP-NN",
            Method::GpSe => "GP-SE",
            Method::Linear => "linear",
            Method::Baran => "Baran",
            Method::NearestPose => "nearest pose",
        }
    }

    fn kernel(self) -> Option<TransferKernel> {
        match self {
            Method::GpNn => Some(TransferKernel::NeuralNetwork),
            Method::GpSe => Some(TransferKernel::SquaredExponential),
            Method::Linear => Some(TransferKernel::Linear),
            Method::Baran | Method::NearestPose => None,
        }
    }
}

#[derive(Debug, Clone)]
pub struct TransferEvalOptions {
    /// Training-set sizes of the learning curves (pairs); sizes beyond the training pool are
    /// dropped.
    pub sizes: Vec<usize>,
    pub seed: u64,
    /// PCA components per part (m).
    pub components: usize,
    /// Fraction of the pooled pairs kept for training (0.7 in the thesis).
    pub train_fraction: f64,
    /// Key poses per training sequence for the key-seeded curves (5 in the thesis).
    pub keys_per_sequence: usize,
}

impl Default for TransferEvalOptions {
    fn default() -> Self {
        TransferEvalOptions {
            sizes: vec![10, 25, 50, 100, 200, 350],
            seed: 0,
            components: 20,
            train_fraction: 0.7,
            keys_per_sequence: 5,
        }
    }
}

/// One point of a learning curve: errors as % of the target's height.
#[derive(Debug, Clone, Serialize)]
pub struct CurvePoint {
    pub size: usize,
    pub train_percent: f64,
    pub cv_percent: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Curve {
    pub method: String,
    /// "random" (Fig. 5.8), "key-seeded" (Fig. 5.9), "whole-body" / "parts" (Fig. 5.10).
    pub variant: String,
    pub points: Vec<CurvePoint>,
}

#[derive(Debug, Clone, Serialize)]
pub struct UnseenResult {
    pub method: String,
    /// "keys", "densified" or "all true pairs".
    pub training: String,
    pub training_pairs: usize,
    pub motion: String,
    pub frames: usize,
    pub rms_percent: f64,
    /// The same in the target's units.
    pub rms: f64,
}

/// One way of putting the predicted parts together (5.6), on the motions absent from
/// training, GP-NN trained on every true pair: error against the truth and the edge-length
/// change against the truth at part boundaries (edges touching an overlap) and inside parts.
#[derive(Debug, Clone, Serialize)]
pub struct ReconstructionResult {
    /// "average" (overlap vertices averaged), "stitch" (5.6.2) or "correct + stitch" (5.6.1-5.6.2).
    pub reconstruction: String,
    pub rms_percent: f64,
    /// |l / l_true - 1| over the edges, max and mean over all frames; `None` without overlaps.
    pub boundary_max: Option<f64>,
    pub boundary_mean: Option<f64>,
    pub inside_max: f64,
    pub inside_mean: f64,
    pub boundary_edges: usize,
    pub inside_edges: usize,
}

#[derive(Debug, Clone, Serialize)]
pub struct CaseEval {
    pub name: String,
    /// "forward" (the case as listed: knight to the other character, average mannequin to the
    /// heavy one) or "backward" (the other way round).
    pub direction: String,
    pub source: String,
    pub target: String,
    pub source_vertices: usize,
    pub target_vertices: usize,
    pub parts: Vec<String>,
    pub target_height: f64,
    pub units: String,
    pub train_motions: Vec<String>,
    pub unseen_motions: Vec<String>,
    /// Pooled true pairs, and how many of them are kept for cross-validation.
    pub pool_pairs: usize,
    pub test_pairs: usize,
    pub curves: Vec<Curve>,
    pub unseen: Vec<UnseenResult>,
    /// Key pairs (5 per training motion) and the pairs their densification gave.
    pub key_pairs: usize,
    pub densified_pairs: usize,
    /// |source frame - target frame| of the densified pairs, whose truth is equality (frames).
    pub densify_frame_error: MeanStd,
    /// Reconstruction of the motions absent from training (5.6), GP-NN on every true pair.
    pub reconstruction: Vec<ReconstructionResult>,
    pub seconds: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct TransferEval {
    pub cases: Vec<CaseEval>,
    pub seconds: f64,
}

/// The body parts a case uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaseParts {
    /// One part: the whole body.
    WholeBody,
    /// Five parts proposed for each subject (`surfcap_transfer::body_parts_proposal`, method
    /// auto: the joints of the KayKit rigs and of the mannequins) with overlaps of this many
    /// edge rings.
    Proposed { overlap_rings: usize },
}

impl CaseParts {
    fn make(self, source: &Subject, target: &Subject) -> Result<(BodyParts, BodyParts)> {
        match self {
            CaseParts::WholeBody => Ok((
                BodyParts::whole_body(source.topology().n_vertices()),
                BodyParts::whole_body(target.topology().n_vertices()),
            )),
            CaseParts::Proposed { overlap_rings } => {
                let one = |s: &Subject| {
                    propose(s, ProposalMethod::Auto, 5, overlap_rings)
                        .map(|p| p.0)
                        .map_err(|e| Error::Unsuitable(format!("{}: proposing body parts: {e}", s.name)))
                };
                Ok((one(source)?, one(target)?))
            }
        }
    }
}

/// Imports KayKit clips `<character>_<clip>` as one subject.
pub fn kaykit_subject(data: &Path, character: &str, clips: &[&str]) -> Result<Subject> {
    let paths: Vec<PathBuf> =
        clips.iter().map(|c| data.join("kaykit_adventurers").join(format!("{character}_{c}"))).collect();
    Ok(import(&paths, &ImportOptions { name: Some(character.to_string()), ..Default::default() }, &NoProgress)?.subject)
}

/// The KayKit clips every character has, split into training motions (walks, runs, jumps) and
/// motions absent from training (dodge, cheer, idle).
pub const KAYKIT_TRAIN: [&str; 9] = [
    "Walking_A",
    "Walking_B",
    "Walking_C",
    "Walking_Backwards",
    "Running_A",
    "Running_B",
    "Running_Strafe_Left",
    "Running_Strafe_Right",
    "Jump_Full_Short",
];
pub const KAYKIT_UNSEEN: [&str; 3] = ["Dodge_Left", "Cheer", "Idle"];

/// The knight to `target` (barbarian, mage or rogue), with the given parts (or the whole body).
pub fn kaykit_case(data: &Path, target: &str, parts: CaseParts) -> Result<TransferCase> {
    let clips: Vec<&str> = KAYKIT_TRAIN.iter().chain(&KAYKIT_UNSEEN).copied().collect();
    let source = kaykit_subject(data, "knight", &clips)?;
    let target_s = kaykit_subject(data, target, &clips)?;
    let (source_parts, target_parts) = parts.make(&source, &target_s)?;
    let n_train = KAYKIT_TRAIN.len();
    Ok(TransferCase {
        name: format!("knight -> {target}"),
        source,
        target: target_s,
        source_parts,
        target_parts,
        train: (0..n_train).map(|k| (k, k)).collect(),
        unseen: (n_train..clips.len()).map(|k| (k, k)).collect(),
        reversed: false,
    })
}

/// CMU clips (in `cmu_bvh`) the mannequin cases train on (walks, turns, a run, a jump) and
/// those they never see (a run to a sudden stop, a dance).
pub const CMU_TRAIN: [&str; 6] = ["16_15", "16_17", "16_19", "16_31", "16_36", "16_07"];
pub const CMU_UNSEEN: [&str; 2] = ["16_57", "05_18"];

/// A built-in mannequin of `shape` and about `vertices` vertices moved by the CMU clips.
pub fn mannequin_cmu_subject(data: &Path, name: &str, shape: &BodyShape, vertices: usize) -> Result<Subject> {
    let m = mannequin(shape, vertices)?;
    let mut clips = Vec::new();
    for c in CMU_TRAIN.iter().chain(&CMU_UNSEEN) {
        let path = data.join("cmu_bvh").join(format!("{c}.bvh"));
        let bvh = read_bvh(&path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        clips.push(Clip::from_bvh(&path, &bvh, &m, mpu)?);
    }
    Ok(mannequin_subject(name, &m, &clips, 30.0)?)
}

/// Two built-in mannequins of different shapes and vertex counts moved by the same CMU clips.
pub fn mannequin_case(
    data: &Path,
    source: (&str, &BodyShape, usize),
    target: (&str, &BodyShape, usize),
    parts: CaseParts,
) -> Result<TransferCase> {
    let s = mannequin_cmu_subject(data, source.0, source.1, source.2)?;
    let t = mannequin_cmu_subject(data, target.0, target.1, target.2)?;
    let (source_parts, target_parts) = parts.make(&s, &t)?;
    let n_train = CMU_TRAIN.len();
    Ok(TransferCase {
        name: format!("{} -> {}", source.0, target.0),
        source: s,
        target: t,
        source_parts,
        target_parts,
        train: (0..n_train).map(|k| (k, k)).collect(),
        unseen: (n_train..n_train + CMU_UNSEEN.len()).map(|k| (k, k)).collect(),
        reversed: false,
    })
}

/// RMS per-vertex distance after aligning `truth` onto `pred` (rotation + translation).
pub use surfcap_transfer::pose_representation::aligned_rms;

/// Height of a pose along the subject's up axis.
fn height(s: &Subject, pose: &[f32]) -> f64 {
    let (lo, hi) = surfcap_mesh::bounding_box(pose);
    let k = s.up_axis.axis_and_sign().0;
    (hi[k] - lo[k]) as f64
}

/// A case with both subjects prepared (aligned), what every fit of it shares.
struct Bench<'a> {
    case: &'a TransferCase,
    src: PreparedSubject,
    tgt: PreparedSubject,
    seed: u64,
}

impl Bench<'_> {
    fn train(
        &self,
        parts: (&BodyParts, &BodyParts),
        pairs: &[(usize, usize)],
        pca_s: &[usize],
        pca_t: &[usize],
        opts: &TrainOptions,
    ) -> surfcap_transfer::Result<MotionTransfer> {
        Ok(MotionTransfer::train(&self.src, parts.0, pca_s, &self.tgt, parts.1, pca_t, pairs, opts)?.0)
    }

    /// GP-NN trained on `pairs`, the source frames `test` transferred and reconstructed three
    /// ways, each against the true target frames `truth`.
    fn reconstructions(
        &self,
        parts: (&BodyParts, &BodyParts),
        components: usize,
        pairs: &[(usize, usize)],
        test: &[usize],
        truth: &[usize],
        height: f64,
    ) -> Result<Vec<ReconstructionResult>> {
        let unsuitable =
            |e: surfcap_transfer::Error| Error::Unsuitable(format!("{}: reconstruction: {e}", self.case.name));
        let mut frames_t: Vec<usize> = pairs.iter().map(|p| p.1).collect();
        frames_t.sort_unstable();
        frames_t.dedup();
        let mut frames_s: Vec<usize> = pairs.iter().map(|p| p.0).collect();
        frames_s.sort_unstable();
        frames_s.dedup();
        let mut opts = TrainOptions { components, ..TrainOptions::default() };
        opts.mapping.fit.seed = self.seed;
        let model = self.train(parts, pairs, &frames_s, &frames_t, &opts).map_err(unsuitable)?;
        let poses: Vec<&[f32]> = test
            .iter()
            .map(|&g| self.src.frame(g).map(|f| f.0))
            .collect::<std::result::Result<_, _>>()
            .map_err(unsuitable)?;
        let predicted = model.predict_parts(&poses).map_err(unsuitable)?;
        let training: Vec<Vec<f32>> = frames_t
            .iter()
            .map(|&g| self.tgt.frame(g).map(|f| f.0.to_vec()))
            .collect::<std::result::Result<_, _>>()
            .map_err(unsuitable)?;
        let topology = self.case.target.topology();
        let mut out = Vec::new();
        for name in ["average", "stitch", "correct + stitch"] {
            let rebuilt: Vec<Vec<f32>> = match name {
                "average" => {
                    predicted.iter().map(|p| average_overlaps(parts.1, p, false)).collect::<std::result::Result<_, _>>()
                }
                _ => {
                    let ro = ReconstructionOptions { correction: name != "stitch", ..ReconstructionOptions::default() };
                    let r = Reconstructor::new(&model, topology, &training, &ro).map_err(unsuitable)?;
                    predicted.iter().map(|p| r.reconstruct(p).map(|x| x.0)).collect()
                }
            }
            .map_err(unsuitable)?;
            let rms = rms_of(&self.tgt, &rebuilt, truth)?;
            let mut d = Vec::new();
            for (pose, &g) in rebuilt.iter().zip(truth) {
                // Edge lengths do not depend on where the pose is: no alignment needed.
                let t = self.tgt.frame(g).map_err(unsuitable)?.0;
                d.push(edge_distortion_by_region(topology, parts.1, pose, t).map_err(unsuitable)?);
            }
            let max = |f: &dyn Fn(&EdgeDistortion) -> f64| d.iter().map(f).fold(0.0f64, f64::max);
            let mean = |f: &dyn Fn(&EdgeDistortion) -> f64| d.iter().map(f).sum::<f64>() / d.len().max(1) as f64;
            let has_boundary = d.first().is_some_and(|e| e.boundary_edges > 0);
            out.push(ReconstructionResult {
                reconstruction: name.into(),
                rms_percent: 100.0 * rms / height,
                boundary_max: has_boundary.then(|| max(&|e| e.boundary_max)),
                boundary_mean: has_boundary.then(|| mean(&|e| e.boundary_mean)),
                inside_max: max(&|e| e.inside_max),
                inside_mean: mean(&|e| e.inside_mean),
                boundary_edges: d.first().map_or(0, |e| e.boundary_edges),
                inside_edges: d.first().map_or(0, |e| e.inside_edges),
            });
        }
        Ok(out)
    }

    /// Trains `method` on `pairs` (global frames) with `parts` and `components` per part, and
    /// predicts the target's aligned poses for the source frames `test` (global).
    fn fit_predict(
        &self,
        method: Method,
        parts: (&BodyParts, &BodyParts),
        components: usize,
        pairs: &[(usize, usize)],
        test: &[usize],
    ) -> Result<Vec<Vec<f32>>> {
        let unsuitable =
            |e: surfcap_transfer::Error| Error::Unsuitable(format!("{}: {}: {e}", self.case.name, method.name()));
        if method == Method::NearestPose {
            // The nearest training source pose (aligned, plain RMS), its partner's target pose.
            return test
                .iter()
                .map(|&g| {
                    let (pose, _) = self.src.frame(g).map_err(unsuitable)?;
                    let Some(&first) = pairs.first() else {
                        return Err(Error::Unsuitable(format!("{}: nearest pose: no training pair", self.case.name)));
                    };
                    let mut best = (f64::INFINITY, first);
                    for &p in pairs {
                        let (q, _) = self.src.frame(p.0).map_err(unsuitable)?;
                        let d: f64 = pose.iter().zip(q).map(|(a, b)| ((a - b) as f64).powi(2)).sum();
                        if d < best.0 {
                            best = (d, p);
                        }
                    }
                    Ok(self.tgt.frame(best.1.1).map_err(unsuitable)?.0.to_vec())
                })
                .collect();
        }
        let Some(kernel) = method.kernel() else {
            // Baran et al.: the training pairs are its key poses; no parts, no PCA.
            let keys = |p: &PreparedSubject, f: &dyn Fn(&(usize, usize)) -> usize| -> Result<Vec<Vec<f32>>> {
                pairs.iter().map(|x| p.frame(f(x)).map(|v| v.0.to_vec()).map_err(unsuitable)).collect()
            };
            let sdt = SemanticDeformationTransfer::new(
                self.case.source.topology(),
                &keys(&self.src, &|x| x.0)?,
                self.case.target.topology(),
                &keys(&self.tgt, &|x| x.1)?,
            )
            .map_err(unsuitable)?;
            return test
                .iter()
                .map(|&g| {
                    let (pose, _) = self.src.frame(g).map_err(unsuitable)?;
                    sdt.transfer(pose).map_err(unsuitable)
                })
                .collect();
        };
        let distinct = |f: &dyn Fn(&(usize, usize)) -> usize| {
            let mut v: Vec<usize> = pairs.iter().map(f).collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let (pca_s, pca_t) = (distinct(&|p| p.0), distinct(&|p| p.1));
        let mut opts = TrainOptions { components, ..TrainOptions::default() };
        opts.mapping.kernel = kernel;
        opts.mapping.fit.seed = self.seed;
        let (model, _) = MotionTransfer::train(&self.src, parts.0, &pca_s, &self.tgt, parts.1, &pca_t, pairs, &opts)
            .map_err(unsuitable)?;
        let poses: Vec<&[f32]> = test
            .iter()
            .map(|&g| self.src.frame(g).map(|f| f.0))
            .collect::<std::result::Result<_, _>>()
            .map_err(unsuitable)?;
        let predicted = model.predict_parts(&poses).map_err(unsuitable)?;
        predicted.iter().map(|p| average_overlaps(parts.1, p, false).map_err(unsuitable)).collect()
    }
}

/// RMS over frames and vertices (as `sqrt(mean of squared per-frame RMS)`).
fn rms_of(tgt: &PreparedSubject, predicted: &[Vec<f32>], truth: &[usize]) -> Result<f64> {
    let mut s = 0.0;
    for (p, &g) in predicted.iter().zip(truth) {
        let (t, _) = tgt.frame(g).map_err(|e| Error::Unsuitable(e.to_string()))?;
        s += aligned_rms(p, t).powi(2);
    }
    Ok((s / predicted.len().max(1) as f64).sqrt())
}

/// Evaluates one case.
pub fn transfer_case_eval(case: &TransferCase, opts: &TransferEvalOptions) -> Result<CaseEval> {
    let t0 = Instant::now();
    if !(opts.train_fraction > 0.0 && opts.train_fraction < 1.0) {
        return Err(Error::parameter(
            "--train-fraction",
            Some(opts.train_fraction.to_string()),
            "expected a number in (0, 1)",
        ));
    }
    let seqs_s: Vec<usize> = case.train.iter().chain(&case.unseen).map(|p| p.0).collect();
    let seqs_t: Vec<usize> = case.train.iter().chain(&case.unseen).map(|p| p.1).collect();
    let src = PreparedSubject::new(&case.source, &seqs_s).map_err(|e| Error::Unsuitable(e.to_string()))?;
    let tgt = PreparedSubject::new(&case.target, &seqs_t).map_err(|e| Error::Unsuitable(e.to_string()))?;
    let bench = Bench { case, src, tgt, seed: opts.seed };
    let tgt = &bench.tgt;
    let true_pairs = |(a, b): (usize, usize)| -> Result<Vec<(usize, usize)>> {
        let (ra, rb) = (case.source.frame_index().range(a), case.target.frame_index().range(b));
        if ra.len() != rb.len() {
            return Err(Error::Unsuitable(format!(
                "{}: {} has {} frames but {} has {}: ground-truth pairs need the same clip on both",
                case.name,
                case.source.sequences()[a].name,
                ra.len(),
                case.target.sequences()[b].name,
                rb.len()
            )));
        }
        Ok(ra.zip(rb).collect())
    };
    let mut pool = Vec::new();
    let mut keys = Vec::new();
    for &m in &case.train {
        let p = true_pairs(m)?;
        let k = opts.keys_per_sequence.min(p.len());
        for i in 0..k {
            let at = if k == 1 { 0 } else { i * (p.len() - 1) / (k - 1) };
            keys.push(p[at]);
        }
        pool.extend(p);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    pool.shuffle(&mut rng);
    let n_train = ((pool.len() as f64) * opts.train_fraction).round() as usize;
    let (train_pool, test_pool) = pool.split_at(n_train);
    // Key poses that fell into the test part stay there: the key-seeded subsets start from the
    // keys that are in the training part.
    let keys_in_train: Vec<(usize, usize)> = keys.iter().copied().filter(|k| train_pool.contains(k)).collect();
    let rest: Vec<(usize, usize)> = train_pool.iter().copied().filter(|p| !keys_in_train.contains(p)).collect();
    let sizes: Vec<usize> = opts.sizes.iter().copied().filter(|&n| n >= 2 && n <= train_pool.len()).collect();
    let test_src: Vec<usize> = test_pool.iter().map(|p| p.0).collect();
    let test_tgt: Vec<usize> = test_pool.iter().map(|p| p.1).collect();
    let h = height(&case.target, &tgt.reference);
    let pct = |x: f64| 100.0 * x / h;

    let parts = (&case.source_parts, &case.target_parts);
    let whole = (
        BodyParts::whole_body(case.source.topology().n_vertices()),
        BodyParts::whole_body(case.target.topology().n_vertices()),
    );
    let mut curves = Vec::new();
    let point =
        |method: Method, parts: (&BodyParts, &BodyParts), m: usize, subset: &[(usize, usize)]| -> Result<CurvePoint> {
            let s: Vec<usize> = subset.iter().map(|p| p.0).collect();
            let t: Vec<usize> = subset.iter().map(|p| p.1).collect();
            let on_train = bench.fit_predict(method, parts, m, subset, &s)?;
            let on_test = bench.fit_predict(method, parts, m, subset, &test_src)?;
            Ok(CurvePoint {
                size: subset.len(),
                train_percent: pct(rms_of(tgt, &on_train, &t)?),
                cv_percent: pct(rms_of(tgt, &on_test, &test_tgt)?),
            })
        };
    for method in Method::ALL {
        let mut random = Vec::new();
        let mut seeded = Vec::new();
        for &n in &sizes {
            random.push(point(method, parts, opts.components, &train_pool[..n])?);
            let mut subset: Vec<(usize, usize)> = keys_in_train.iter().copied().take(n).collect();
            subset.extend(rest.iter().copied().take(n - subset.len()));
            seeded.push(point(method, parts, opts.components, &subset)?);
        }
        curves.push(Curve { method: method.name().into(), variant: "random".into(), points: random });
        curves.push(Curve { method: method.name().into(), variant: "key-seeded".into(), points: seeded });
    }
    if case.target_parts.len() > 1 {
        let m_whole = opts.components * case.target_parts.len();
        let points = sizes
            .iter()
            .map(|&n| point(Method::GpNn, (&whole.0, &whole.1), m_whole, &train_pool[..n]))
            .collect::<Result<Vec<_>>>()?;
        curves.push(Curve { method: Method::GpNn.name().into(), variant: "whole-body".into(), points });
    }

    // Motions absent from training, for three training sets built from the training motions:
    // the key pairs only (5 per motion, what Baran et al. use), the key pairs densified by the
    // constrained DTW of 5.5.1 (no ground truth used), and every true pair.
    let all_train: Vec<(usize, usize)> = {
        let mut v = pool.clone();
        v.sort_unstable();
        v
    };
    let densified = {
        let d = DensifyOptions::default();
        densified_pairs(&bench.src, parts.0, &bench.tgt, parts.1, &keys, opts.components, &d)
            .map_err(|e| Error::Unsuitable(format!("{}: densifying the key pairs: {e}", case.name)))?
    };
    let densify_error = {
        // The true partner of source frame g is the target frame at the same offset.
        let errs: Vec<f64> = densified
            .0
            .iter()
            .map(|&(gs, gt)| {
                let (ss, fs) = bench.src.locate(gs).expect("prepared");
                let (st, ft) = bench.tgt.locate(gt).expect("prepared");
                debug_assert_eq!(ss, st);
                (fs as f64 - ft as f64).abs()
            })
            .collect();
        MeanStd::of(&errs)
    };
    let training_sets: [(&str, &[(usize, usize)]); 3] =
        [("keys", &keys), ("densified", &densified.0), ("all true pairs", &all_train)];
    let unseen_frames: Vec<(usize, Vec<(usize, usize)>)> =
        case.unseen.iter().map(|&(a, b)| true_pairs((a, b)).map(|p| (b, p))).collect::<Result<_>>()?;
    let all_s: Vec<usize> = unseen_frames.iter().flat_map(|(_, p)| p.iter().map(|x| x.0)).collect();
    let mut unseen = Vec::new();
    // One row per unseen motion of a prediction over all of them (`all_s`, motion after motion).
    let mut rows = |method: &str, set: &str, pairs: &[(usize, usize)], pred: &[Vec<f32>]| -> Result<()> {
        let mut at = 0;
        for (b, p) in &unseen_frames {
            let t: Vec<usize> = p.iter().map(|x| x.1).collect();
            let rms = rms_of(tgt, &pred[at..at + p.len()], &t)?;
            at += p.len();
            unseen.push(UnseenResult {
                method: method.into(),
                training: set.into(),
                training_pairs: pairs.len(),
                motion: case.target.sequences()[*b].name.clone(),
                frames: p.len(),
                rms_percent: pct(rms),
                rms,
            });
        }
        Ok(())
    };
    for method in Method::ALL {
        for (set, pairs) in training_sets {
            let pred = bench.fit_predict(method, parts, opts.components, pairs, &all_s)?;
            rows(method.name(), set, pairs, &pred)?;
        }
    }
    // Whether the parts help on unseen motions: GP-NN on the whole body with as many
    // components in all as the parts have together.
    if case.target_parts.len() > 1 {
        let m_whole = opts.components * case.target_parts.len();
        for (set, pairs) in training_sets {
            let pred = bench.fit_predict(Method::GpNn, (&whole.0, &whole.1), m_whole, pairs, &all_s)?;
            rows(WHOLE_BODY_GP_NN, set, pairs, &pred)?;
        }
    }
    let all_t: Vec<usize> = unseen_frames.iter().flat_map(|(_, p)| p.iter().map(|x| x.1)).collect();
    let reconstruction = bench.reconstructions(parts, opts.components, &all_train, &all_s, &all_t, h)?;
    Ok(CaseEval {
        name: case.name.clone(),
        direction: if case.reversed { "backward" } else { "forward" }.into(),
        source: case.source.name.clone(),
        target: case.target.name.clone(),
        source_vertices: case.source.topology().n_vertices(),
        target_vertices: case.target.topology().n_vertices(),
        parts: case.target_parts.names().iter().map(|s| s.to_string()).collect(),
        target_height: h,
        units: case.target.units.symbol().to_string(),
        train_motions: case.train.iter().map(|&(_, b)| case.target.sequences()[b].name.clone()).collect(),
        unseen_motions: case.unseen.iter().map(|&(_, b)| case.target.sequences()[b].name.clone()).collect(),
        pool_pairs: pool.len(),
        test_pairs: test_pool.len(),
        curves,
        unseen,
        key_pairs: keys.len(),
        densified_pairs: densified.0.len(),
        densify_frame_error: densify_error,
        reconstruction,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// One left-out pose of a leave-one-out run.
#[derive(Debug, Clone, Serialize)]
pub struct LeftOut {
    pub pose: usize,
    /// Per method: RMS per-vertex error, % of the target's height.
    pub percent: Vec<(String, f64)>,
}

/// Leave-one-out over a handful of corresponding poses (Sumner's cat and lion: 9 pose pairs,
/// each lion pose made from its cat pose by deformation transfer): each pose transferred by
/// models trained on the others, against the true target pose. GP-NN and linear on the whole
/// body (as many components as the training poses allow) and Baran et al.
#[derive(Debug, Clone, Serialize)]
pub struct LeaveOneOutEval {
    pub name: String,
    pub source_vertices: usize,
    pub target_vertices: usize,
    pub poses: Vec<LeftOut>,
    /// Per method, the mean over the left-out poses.
    pub mean_percent: Vec<(String, f64)>,
    /// The error of the nearest target training pose (the floor a method that only picks a
    /// training pose would reach).
    pub nearest_training_percent: f64,
}

/// The cat and lion poses as two one-sequence subjects.
pub fn catlion_subjects(data: &Path) -> Result<(Subject, Subject)> {
    let one = |name: &str| -> Result<Subject> {
        let path = data.join("sumner2004-catlion").join(name);
        // Poses, not a motion: the rate only matters for the time base of written files.
        let opts = ImportOptions { name: Some(name.into()), fps: Some(1.0), ..Default::default() };
        Ok(import(&[path], &opts, &NoProgress)?.subject)
    };
    Ok((one("cat")?, one("lion")?))
}

/// Leave-one-out transfer between two subjects whose sequence 0 frames correspond one to one.
pub fn leave_one_out_eval(name: &str, source: &Subject, target: &Subject, seed: u64) -> Result<LeaveOneOutEval> {
    let n = source.sequences()[0].n_frames();
    if n != target.sequences()[0].n_frames() || n < 3 {
        return Err(Error::Unsuitable(format!(
            "{name}: {} and {} poses: expected the same number, at least 3",
            n,
            target.sequences()[0].n_frames()
        )));
    }
    let whole =
        (BodyParts::whole_body(source.topology().n_vertices()), BodyParts::whole_body(target.topology().n_vertices()));
    let case = TransferCase {
        name: name.into(),
        source: source.clone(),
        target: target.clone(),
        source_parts: whole.0.clone(),
        target_parts: whole.1.clone(),
        train: vec![(0, 0)],
        unseen: vec![],
        reversed: false,
    };
    let src = PreparedSubject::new(source, &[0]).map_err(|e| Error::Unsuitable(e.to_string()))?;
    let tgt = PreparedSubject::new(target, &[0]).map_err(|e| Error::Unsuitable(e.to_string()))?;
    let bench = Bench { case: &case, src, tgt, seed };
    let h = height(target, &bench.tgt.reference);
    let methods = [Method::GpNn, Method::Linear, Method::Baran];
    let mut poses = Vec::new();
    let mut nearest = 0.0;
    for i in 0..n {
        let train: Vec<(usize, usize)> = (0..n).filter(|&j| j != i).map(|j| (j, j)).collect();
        let mut percent = Vec::new();
        for m in methods {
            let pred = bench.fit_predict(m, (&whole.0, &whole.1), n, &train, &[i])?;
            percent.push((m.name().to_string(), 100.0 * rms_of(&bench.tgt, &pred, &[i])? / h));
        }
        let truth = bench.tgt.frame(i).map_err(|e| Error::Unsuitable(e.to_string()))?.0;
        let best = train
            .iter()
            .map(|&(_, j)| aligned_rms(bench.tgt.frame(j).expect("prepared").0, truth))
            .fold(f64::INFINITY, f64::min);
        nearest += 100.0 * best / h / n as f64;
        poses.push(LeftOut { pose: i, percent });
    }
    let mean_percent = methods
        .iter()
        .enumerate()
        .map(|(k, m)| (m.name().to_string(), poses.iter().map(|p| p.percent[k].1).sum::<f64>() / n as f64))
        .collect();
    Ok(LeaveOneOutEval {
        name: name.into(),
        source_vertices: source.topology().n_vertices(),
        target_vertices: target.topology().n_vertices(),
        poses,
        mean_percent,
        nearest_training_percent: nearest,
    })
}

/// Evaluates every case.
pub fn transfer_eval(cases: &[TransferCase], opts: &TransferEvalOptions) -> Result<TransferEval> {
    let t0 = Instant::now();
    let cases = cases.iter().map(|c| transfer_case_eval(c, opts)).collect::<Result<Vec<_>>>()?;
    Ok(TransferEval { cases, seconds: t0.elapsed().as_secs_f64() })
}
