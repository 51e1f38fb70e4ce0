//! Motion transfer as runs a front end calls (thesis chapter 5, `surfcap-transfer`): a model
//! trained from a source subject, a target subject and their key pairs (GP regression on body
//! parts, or Baran et al. 2009's semantic deformation transfer), with its report
//! ([`TransferTrainReport`]); and a motion of the source transferred onto the target with a
//! trained model, checked before any work ([`TransferApplication::new`]), with its report
//! ([`TransferApplyReport`]: the error against the true motion when there is one, next to the
//! nearest training pose's, and the edge-length change at part boundaries and inside parts).
//! Nothing here prints or writes the animation: the front end writes what the run returns.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use surfcap_mesh::{FrameLabel, Sequence, Subject, Topology};
use surfcap_transfer::BodyParts;
use surfcap_transfer::baran_transfer::BaranTransfer;
use surfcap_transfer::correspondence_densification::DensifyOptions;
use surfcap_transfer::motion_transfer::{PartReport, TrainOptions};
use surfcap_transfer::pairs_file::{KeyPair, parse_pairs};
use surfcap_transfer::part_stitching::{EdgeDistortion, StitchReport, average_overlaps, edge_distortion_by_region};
use surfcap_transfer::pose_representation::aligned_rms;
use surfcap_transfer::shape_reconstruction::{ReconstructionOptions, Reconstructor};
use surfcap_transfer::transfer_model::TransferKernel;
use surfcap_transfer::transfer_model_file::{
    SavedBaran, SavedModel, SavedTransfer, SubjectsMeta, mesh_fingerprint, write_baran_model, write_model,
};
use surfcap_transfer::transfer_training::{TrainingRequest, train_cached, train_transfer};

use crate::error::{Error, Result, refuse};

/// How a model is learnt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TransferMethod {
    /// GP regression on body parts (thesis chapter 5).
    Gp,
    /// Baran et al. 2009, semantic deformation transfer: the key pairs are its key poses, whole
    /// body.
    Baran,
}

impl TransferMethod {
    /// `gp` or `baran`.
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "gp" => Ok(TransferMethod::Gp),
            "baran" => Ok(TransferMethod::Baran),
            _ => refuse!("method {s:?}: expected gp or baran"),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            TransferMethod::Gp => "gp",
            TransferMethod::Baran => "baran",
        }
    }
}

/// The options of a training (`surfcap transfer train`'s, with its defaults).
#[derive(Debug, Clone)]
pub struct TransferTrainOptions {
    pub method: TransferMethod,
    /// PCA components per part (thesis 5.4.3: 20).
    pub components: usize,
    pub kernel: TransferKernel,
    /// Seed of the hyper-parameter fits' restarts.
    pub seed: u64,
    /// Densify the key pairs (thesis 5.5.1) into one pair per frame of each pair of sequences.
    pub densify: bool,
    /// Densification: at most this many consecutive frames of one sequence matched to one frame
    /// of the other.
    pub max_straight: usize,
}

impl Default for TransferTrainOptions {
    fn default() -> Self {
        TransferTrainOptions {
            method: TransferMethod::Gp,
            components: 20,
            kernel: TransferKernel::NeuralNetwork,
            seed: 0,
            densify: true,
            max_straight: 3,
        }
    }
}

/// A pair of sequences the key pairs use, in a training report.
#[derive(Debug, Clone, Serialize)]
pub struct SequencePairReport {
    pub source_sequence: String,
    pub target_sequence: String,
    pub keys: usize,
    pub pairs: usize,
    pub densified: bool,
    pub mean_cost: Option<f64>,
}

/// The report of a GP training (`report.json` of the model folder).
#[derive(Debug, Clone, Serialize)]
pub struct GpTrainReport {
    /// The model folder, once written.
    pub model: Option<PathBuf>,
    pub source: String,
    pub target: String,
    /// Training pairs (after densification) and key pairs.
    pub pairs: usize,
    pub key_pairs: usize,
    pub densified: bool,
    pub sequence_pairs: Vec<SequencePairReport>,
    pub source_sequences: Vec<String>,
    pub target_sequences: Vec<String>,
    pub method: &'static str,
    pub kernel: &'static str,
    pub components: usize,
    pub parts: Vec<PartReport>,
    pub displacement: surfcap_transfer::transfer_model::MappingFit,
    pub fit_seconds: f64,
    pub total_seconds: f64,
    /// Whether the model was read from the derived cache.
    pub cached: bool,
}

/// The report of a Baran et al. training.
#[derive(Debug, Clone, Serialize)]
pub struct BaranTrainReport {
    pub model: Option<PathBuf>,
    pub method: &'static str,
    pub source: String,
    pub target: String,
    pub pairs: usize,
    pub key_pairs: usize,
    pub densified: bool,
    pub source_vertices: usize,
    pub target_vertices: usize,
    pub fit_seconds: f64,
    pub total_seconds: f64,
    pub cached: bool,
}

/// The report of a training, either method.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum TransferTrainReport {
    Gp(Box<GpTrainReport>),
    Baran(BaranTrainReport),
}

impl TransferTrainReport {
    /// Names the model folder written.
    pub fn set_model(&mut self, dir: &Path) {
        match self {
            TransferTrainReport::Gp(r) => r.model = Some(dir.to_path_buf()),
            TransferTrainReport::Baran(r) => r.model = Some(dir.to_path_buf()),
        }
    }

    /// Sets the seconds from the run's start (a front end counts its reading of the inputs).
    pub fn set_total_seconds(&mut self, seconds: f64) {
        match self {
            TransferTrainReport::Gp(r) => r.total_seconds = seconds,
            TransferTrainReport::Baran(r) => r.total_seconds = seconds,
        }
    }
}

/// A trained model with its report.
pub struct TrainedModel {
    pub model: SavedTransfer,
    pub report: TransferTrainReport,
}

/// What a training is made from: both subjects, the key pairs (read with
/// [`surfcap_transfer::pairs_file::parse_pairs`]), and for the GP method both subjects' body
/// parts (with the same part names; `surfcap_transfer::body_parts_choice::choose_parts`).
pub struct TransferTraining<'a> {
    pub source: &'a Subject,
    pub target: &'a Subject,
    pub keys: &'a [KeyPair],
    pub parts: Option<(&'a BodyParts, &'a BodyParts)>,
    pub options: TransferTrainOptions,
}

/// Reads the key pairs file `path` (a CSV, one `source sequence:frame, target sequence:frame`
/// per line, [`parse_pairs`]) between `source` and `target`.
pub fn read_key_pairs(path: &Path, source: &Subject, target: &Subject) -> Result<Vec<KeyPair>> {
    let text = String::from_utf8(surfcap_mesh::read_regular_file(path)?)
        .map_err(|_| Error::Request(format!("{}: not UTF-8 text: expected a CSV of frame pairs", path.display())))?;
    Ok(parse_pairs(&text, &path.display().to_string(), source, target)?)
}

/// Where a GP training is cached: the derived-cache folder and whether to train again.
#[derive(Debug, Clone)]
pub struct TrainingCache {
    pub dir: PathBuf,
    pub refresh: bool,
}

/// Trains a model (through `cache` for the GP method when given). Notes (a cache entry not
/// used, a sequence pair with a single key kept as it is) go to `note`.
pub fn train_model(
    t: &TransferTraining<'_>,
    cache: Option<&TrainingCache>,
    note: &mut dyn FnMut(String),
) -> Result<TrainedModel> {
    let t0 = Instant::now();
    let (source, target) = (t.source, t.target);
    let key_pairs: Vec<(usize, usize)> = t.keys.iter().map(|k| (k.source, k.target)).collect();
    if t.options.method == TransferMethod::Baran {
        let t_fit = Instant::now();
        let model = BaranTransfer::train(source, target, &key_pairs)?;
        let fit_seconds = t_fit.elapsed().as_secs_f64();
        let report = TransferTrainReport::Baran(BaranTrainReport {
            model: None,
            method: "baran",
            source: source.name.clone(),
            target: target.name.clone(),
            pairs: key_pairs.len(),
            key_pairs: t.keys.len(),
            densified: false,
            source_vertices: model.source_vertices(),
            target_vertices: model.target_vertices(),
            fit_seconds,
            total_seconds: t0.elapsed().as_secs_f64(),
            cached: false,
        });
        let subjects = SubjectsMeta::new(source, target);
        return Ok(TrainedModel { model: SavedTransfer::Baran(Box::new(SavedBaran { model, subjects })), report });
    }
    let Some((source_parts, target_parts)) = t.parts else {
        refuse!("the GP transfer learns per body part: expected the source's and the target's parts")
    };
    let o = &t.options;
    let mut options = TrainOptions { components: o.components, ..TrainOptions::default() };
    options.mapping.kernel = o.kernel;
    options.mapping.fit.seed = o.seed;
    let req = TrainingRequest {
        source,
        target,
        source_parts,
        target_parts,
        keys: &key_pairs,
        options,
        densify: o.densify.then(|| DensifyOptions { max_straight: o.max_straight, ..DensifyOptions::default() }),
    };
    let trained = match cache {
        Some(c) => train_cached(&req, &c.dir, c.refresh, note)?,
        None => train_transfer(&req)?,
    };
    let s = &trained.summary;
    for g in s.groups.iter().filter(|g| !g.densified) {
        note(format!(
            "{} -> {}: a single key pair, kept as it is (densification needs at least two per pair of sequences)",
            source.sequences()[g.source_sequence].name,
            target.sequences()[g.target_sequence].name
        ));
    }
    let report = TransferTrainReport::Gp(Box::new(GpTrainReport {
        model: None,
        source: source.name.clone(),
        target: target.name.clone(),
        pairs: s.pairs.len(),
        key_pairs: t.keys.len(),
        densified: o.densify,
        sequence_pairs: s
            .groups
            .iter()
            .map(|g| SequencePairReport {
                source_sequence: source.sequences()[g.source_sequence].name.clone(),
                target_sequence: target.sequences()[g.target_sequence].name.clone(),
                keys: g.keys,
                pairs: g.pairs,
                densified: g.densified,
                mean_cost: g.mean_cost,
            })
            .collect(),
        source_sequences: s.source_sequences.iter().map(|&k| source.sequences()[k].name.clone()).collect(),
        target_sequences: s.target_sequences.iter().map(|&k| target.sequences()[k].name.clone()).collect(),
        method: "gp",
        kernel: o.kernel.name(),
        components: o.components,
        parts: s.report.parts.clone(),
        displacement: s.report.displacement.clone(),
        fit_seconds: s.fit_seconds,
        total_seconds: t0.elapsed().as_secs_f64(),
        cached: trained.from_cache,
    }));
    let model = SavedTransfer::Gp(Box::new(SavedModel {
        model: trained.model,
        subjects: trained.subjects,
        target_training: trained.target_training,
    }));
    Ok(TrainedModel { model, report })
}

/// Writes a model's files into `dir`, a folder the caller has claimed (`model.json` and the
/// pose arrays, as `surfcap transfer train` writes them; `surfcap transfer apply` and
/// `surfcap_transfer::transfer_model_file::read_any` read them).
pub fn write_model_files(dir: &Path, model: &SavedTransfer) -> Result<()> {
    match model {
        SavedTransfer::Gp(m) => write_model(dir, &m.model, &m.subjects, &m.target_training)?,
        SavedTransfer::Baran(b) => write_baran_model(dir, &b.model, &b.subjects)?,
    }
    Ok(())
}

/// The vertex counts of a model's source and target, and what it remembers of them.
pub fn model_shape(model: &SavedTransfer) -> (&SubjectsMeta, usize, usize) {
    match model {
        SavedTransfer::Gp(m) => (&m.subjects, m.model.source.reference.len() / 3, m.model.target.reference.len() / 3),
        SavedTransfer::Baran(b) => (&b.subjects, b.model.source_vertices(), b.model.target_vertices()),
    }
}

/// How the predicted parts become one mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reconstruction {
    /// The parts stitched along the cheapest cuts inside their overlaps with a Poisson merge
    /// (thesis 5.6.2; with `correction`, 5.6.1 first).
    Stitch,
    /// Every vertex the mean of its copies.
    Average,
}

impl std::str::FromStr for Reconstruction {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "stitch" => Ok(Reconstruction::Stitch),
            "average" => Ok(Reconstruction::Average),
            _ => Err(format!("{s:?}: expected stitch or average")),
        }
    }
}

/// The options of an application (`surfcap transfer apply`'s, with its defaults).
#[derive(Debug, Clone, Copy)]
pub struct ApplyOptions {
    pub reconstruction: Reconstruction,
    /// Before stitching, correct each part against its nearest training meshes (5.6.1).
    pub correction: bool,
    /// Training meshes each part correction blends (M of 5.6.1).
    pub nearest: usize,
}

impl Default for ApplyOptions {
    fn default() -> Self {
        ApplyOptions { reconstruction: Reconstruction::Stitch, correction: false, nearest: 3 }
    }
}

/// A motion to transfer or its true partner: a subject, what names it in messages (its path on
/// the command line) and one of its sequences.
#[derive(Clone, Copy)]
pub struct MotionOf<'a> {
    pub subject: &'a Subject,
    pub label: &'a str,
    pub sequence: &'a str,
    /// The option it came from (`--motion`, `--truth`), named in errors.
    pub option: &'a str,
    /// The argument as the user wrote it (`SUBJECT:SEQUENCE`), in the report.
    pub spec: &'a str,
}

/// A transfer checked before any work: the model, the motion and the true motion fit together.
pub struct TransferApplication<'a> {
    model: &'a SavedTransfer,
    model_label: PathBuf,
    motion: MotionOf<'a>,
    sequence: &'a Sequence,
    truth: Option<(MotionOf<'a>, &'a Sequence)>,
    topology: Topology,
    /// A note for the user (the motion's frame rate is not the model's), if any.
    pub note: Option<String>,
}

/// The sequence `name` of `m.subject`, or an error listing its sequences.
fn sequence_of<'a>(m: &MotionOf<'a>) -> Result<&'a Sequence> {
    m.subject.sequence(m.sequence).map(|(_, q)| q).ok_or_else(|| {
        let known: Vec<&str> = m.subject.sequences().iter().map(|q| q.name.as_str()).collect();
        Error::Request(format!(
            "{}: {} has no sequence {:?}; it has {}",
            m.option,
            m.label,
            m.sequence,
            known.join(", ")
        ))
    })
}

impl<'a> TransferApplication<'a> {
    /// Checks that `motion` is on the model's source mesh, and `truth` (when given) on its
    /// target mesh with as many frames. `model_label` names the model in messages and reports.
    pub fn new(
        model: &'a SavedTransfer,
        model_label: &Path,
        motion: MotionOf<'a>,
        truth: Option<MotionOf<'a>>,
    ) -> Result<Self> {
        let (meta, nv_source, nv) = model_shape(model);
        let source = motion.subject;
        if source.topology().n_vertices() != nv_source {
            refuse!(
                "{}: {} vertices, but the model {} was trained on a source of {nv_source} vertices ({}): expected a motion of that subject",
                motion.label,
                source.topology().n_vertices(),
                model_label.display(),
                meta.source_name
            );
        }
        if mesh_fingerprint(source.topology()) != meta.source_mesh {
            refuse!(
                "{}: its mesh has the model's {nv_source} vertices but other triangles than the source {} was trained on: expected a motion of that subject",
                motion.label,
                meta.source_name
            );
        }
        let note = ((source.fps - meta.source_fps).abs() > 1e-9 * source.fps.abs().max(1.0)).then(|| {
            format!(
                "{} plays at {} fps and the model's source at {} fps: the displacement per frame is learnt at the model's rate, so the travel scales by their ratio",
                motion.label, source.fps, meta.source_fps
            )
        });
        let sequence = sequence_of(&motion)?;
        let topology = Topology::new(nv, meta.target_triangles.clone(), None)?;
        let truth = match truth {
            None => None,
            Some(t) => {
                let s = t.subject;
                if s.topology().n_vertices() != nv || mesh_fingerprint(s.topology()) != mesh_fingerprint(&topology) {
                    refuse!(
                        "{} {}: {} vertices and its own triangles, but the model's target {} has {nv} vertices and other triangles: expected a motion of the target",
                        t.option,
                        t.label,
                        s.topology().n_vertices(),
                        meta.target_name
                    );
                }
                let q = sequence_of(&t)?;
                if q.n_frames() != sequence.n_frames() {
                    refuse!(
                        "{} {}:{}: {} frames, but the motion {} has {}: expected the true partner of every frame",
                        t.option,
                        t.label,
                        t.sequence,
                        q.n_frames(),
                        motion.spec,
                        sequence.n_frames()
                    );
                }
                Some((t, q))
            }
        };
        Ok(TransferApplication {
            model,
            model_label: model_label.to_path_buf(),
            motion,
            sequence,
            truth,
            topology,
            note,
        })
    }

    /// The frames the output will have.
    pub fn frames(&self) -> usize {
        self.sequence.n_frames()
    }

    /// A one-frame subject of the output's mesh and time base, for sizing the output before any
    /// work.
    pub fn shape(&self) -> Result<Subject> {
        let (meta, _, nv) = model_shape(self.model);
        let reference = match self.model {
            SavedTransfer::Gp(m) => m.model.target.reference.clone(),
            SavedTransfer::Baran(b) => b.model.target_keys[0].clone(),
        };
        Ok(Subject::new(
            meta.target_name.clone(),
            self.topology.clone(),
            vec![Sequence::new("size", nv, reference)?],
            meta.target_fps,
            meta.target_up_axis,
            meta.target_units.clone(),
        )?)
    }

    /// Transfers the motion: the target subject playing it (one sequence
    /// `<sequence>-as-<target>`, every frame labelled synthetic) and the report (`written`
    /// empty: the front end names what it writes). `started` is when the run began (the
    /// report's total seconds count from it).
    pub fn run(&self, options: &ApplyOptions, started: Instant) -> Result<(Subject, TransferApplyReport)> {
        let (meta, _, nv) = model_shape(self.model);
        let seq = self.sequence;
        let topology = &self.topology;
        let frames: Vec<&[f32]> = (0..seq.n_frames()).map(|f| seq.frame(f)).collect();
        let t_setup = Instant::now();
        let stitching = options.reconstruction == Reconstruction::Stitch;
        let mut cuts = Vec::new();
        let (method, correction, out, setup_seconds, transfer_seconds, target_parts, training) = match self.model {
            SavedTransfer::Gp(saved) => {
                let model = &saved.model;
                let correction = stitching && options.correction;
                let reconstructor = if stitching {
                    let opts = ReconstructionOptions { correction, m_nearest: options.nearest };
                    Some(Reconstructor::new(model, topology, &saved.target_training, &opts)?)
                } else {
                    None
                };
                let setup_seconds = t_setup.elapsed().as_secs_f64();
                let t_transfer = Instant::now();
                let out = model.transfer(&frames, |p| match &reconstructor {
                    Some(r) => {
                        let (pose, report) = r.reconstruct(p)?;
                        cuts.push(report);
                        Ok(pose)
                    }
                    None => average_overlaps(&model.target.parts, p, false),
                })?;
                let parts = model.target.parts.clone();
                let training = &saved.target_training;
                ("gp", correction, out, setup_seconds, t_transfer.elapsed().as_secs_f64(), parts, training)
            }
            SavedTransfer::Baran(b) => {
                let sdt = b.model.build()?;
                let setup_seconds = t_setup.elapsed().as_secs_f64();
                let t_transfer = Instant::now();
                let out = b.model.transfer(&sdt, &frames)?;
                let parts = BodyParts::whole_body(nv);
                ("baran", false, out, setup_seconds, t_transfer.elapsed().as_secs_f64(), parts, &b.model.target_keys)
            }
        };
        // Against the true motion when there is one: the error next to the nearest training
        // pose's (the floor of any method that only picks a training pose), and the edge-length
        // change |l / l_true - 1| at part boundaries and inside parts. Without it the edge
        // measure is dropped: against the rest pose it mostly measures the motion's own
        // stretching.
        let (accuracy, edges) = match &self.truth {
            Some((t, q)) => {
                let (lo, hi) = surfcap_mesh::bounding_box(q.frame(0));
                let k = meta.target_up_axis.axis_and_sign().0;
                let height = (hi[k] - lo[k]) as f64;
                let pct = |x: f64| if height > 0.0 { 100.0 * x / height } else { f64::NAN };
                let mut err = 0.0;
                let mut nearest = 0.0;
                let mut seams = Vec::new();
                for (f, pose) in out.aligned.iter().enumerate() {
                    let truth = q.frame(f);
                    err += aligned_rms(pose, truth).powi(2);
                    let best = training.iter().map(|p| aligned_rms(truth, p)).fold(f64::INFINITY, f64::min);
                    nearest += best.powi(2);
                    seams.push(edge_distortion_by_region(topology, &target_parts, pose, truth)?);
                }
                let n = out.aligned.len().max(1) as f64;
                let (err, nearest) = ((err / n).sqrt(), (nearest / n).sqrt());
                let max_of = |f: &dyn Fn(&EdgeDistortion) -> f64| seams.iter().map(f).fold(0.0f64, f64::max);
                let has_boundary = seams.iter().any(|e| e.boundary_edges > 0);
                (
                    Some(TransferAccuracy {
                        truth: t.spec.to_string(),
                        target_height: height,
                        rms: err,
                        rms_percent: pct(err),
                        nearest_training_pose_rms: nearest,
                        nearest_training_pose_percent: pct(nearest),
                        nearest_training_poses: training.len(),
                        method,
                    }),
                    EdgeLengthDistortion {
                        boundary_edges: Some(seams.first().map_or(0, |e| e.boundary_edges)),
                        inside_edges: Some(seams.first().map_or(0, |e| e.inside_edges)),
                        boundary_max: has_boundary.then(|| max_of(&|e| e.boundary_max)),
                        inside_max: Some(max_of(&|e| e.inside_max)),
                        boundary_mean: has_boundary.then(|| mean(seams.iter().map(|e| e.boundary_mean))),
                        inside_mean: Some(mean(seams.iter().map(|e| e.inside_mean))),
                        against: "the true motion (--truth): |l / l_true - 1| per edge and frame",
                    },
                )
            }
            None => (
                None,
                EdgeLengthDistortion {
                    boundary_edges: None,
                    inside_edges: None,
                    boundary_max: None,
                    inside_max: None,
                    boundary_mean: None,
                    inside_mean: None,
                    against: "dropped: no --truth (against the rest pose it measures the motion's own stretching of short edges)",
                },
            ),
        };
        let name = format!("{}-as-{}", seq.name, meta.target_name);
        let positions: Vec<f32> = out.world.iter().flatten().copied().collect();
        let out_seq = Sequence::new(name.clone(), nv, positions)?
            .with_labels(vec![FrameLabel::Synthetic; seq.n_frames()])?
            .with_tags(vec!["transfer".into()]);
        let subject = Subject::new(
            name,
            topology.clone(),
            vec![out_seq],
            meta.target_fps,
            meta.target_up_axis,
            meta.target_units.clone(),
        )?;
        let report = TransferApplyReport {
            model: self.model_label.clone(),
            method,
            motion: self.motion.spec.to_string(),
            source: meta.source_name.clone(),
            target: meta.target_name.clone(),
            frames: seq.n_frames(),
            reconstruction: if method == "baran" {
                "baran"
            } else if stitching {
                "stitch"
            } else {
                "average"
            },
            correction,
            nearest: options.nearest,
            parts: target_parts.names().iter().map(|n| n.to_string()).collect(),
            accuracy,
            edge_length_distortion: edges,
            setup_seconds,
            transfer_seconds,
            total_seconds: started.elapsed().as_secs_f64(),
            per_frame: PerFrameReport { displacement: out.displacements, cuts },
            written: Vec::new(),
        };
        Ok((subject, report))
    }
}

fn mean(values: impl IntoIterator<Item = f64>) -> f64 {
    let (sum, n) = values.into_iter().fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// The error of a transfer against the true motion (RMS per vertex after a rigid alignment),
/// next to the nearest training pose's.
#[derive(Debug, Clone, Serialize)]
pub struct TransferAccuracy {
    /// The true motion as the user named it.
    pub truth: String,
    pub target_height: f64,
    pub rms: f64,
    /// % of the target's height.
    pub rms_percent: f64,
    pub nearest_training_pose_rms: f64,
    pub nearest_training_pose_percent: f64,
    pub nearest_training_poses: usize,
    pub method: &'static str,
}

/// The edge-length change |l / l_true - 1| at part boundaries and inside parts (all `None`
/// without a true motion).
#[derive(Debug, Clone, Serialize)]
pub struct EdgeLengthDistortion {
    pub boundary_edges: Option<usize>,
    pub inside_edges: Option<usize>,
    pub boundary_max: Option<f64>,
    pub inside_max: Option<f64>,
    pub boundary_mean: Option<f64>,
    pub inside_mean: Option<f64>,
    pub against: &'static str,
}

/// Per frame: the predicted rigid displacement (eq. 5.3) and the stitching's cuts.
#[derive(Debug, Clone, Serialize)]
pub struct PerFrameReport {
    pub displacement: Vec<[f64; 6]>,
    pub cuts: Vec<StitchReport>,
}

/// The report of `surfcap transfer apply`.
#[derive(Debug, Clone, Serialize)]
pub struct TransferApplyReport {
    pub model: PathBuf,
    pub method: &'static str,
    pub motion: String,
    pub source: String,
    pub target: String,
    pub frames: usize,
    pub reconstruction: &'static str,
    pub correction: bool,
    pub nearest: usize,
    pub parts: Vec<String>,
    pub accuracy: Option<TransferAccuracy>,
    pub edge_length_distortion: EdgeLengthDistortion,
    pub setup_seconds: f64,
    pub transfer_seconds: f64,
    pub total_seconds: f64,
    pub per_frame: PerFrameReport,
    pub written: Vec<PathBuf>,
}
