//! `surfcap transfer train | apply`: motion transfer between two subjects by GP regression on
//! body parts (thesis chapter 5; `surfcap-transfer`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;
use surfcap_formats::export::export;
use surfcap_mesh::{FrameLabel, Sequence, Subject, Topology};
use surfcap_transfer::correspondence_densification::DensifyOptions;
use surfcap_transfer::motion_transfer::TrainOptions;
use surfcap_transfer::pairs_file::parse_pairs;
use surfcap_transfer::part_stitching::{average_overlaps, edge_distortion_by_region};
use surfcap_transfer::shape_reconstruction::{ReconstructionOptions, Reconstructor};
use surfcap_transfer::transfer_model::TransferKernel;
use surfcap_transfer::transfer_model_file::{KIND, mesh_fingerprint, read_model, write_model};
use surfcap_transfer::transfer_training::{TrainingRequest, train_cached};

use crate::body_parts::parts_of;
use crate::limits::Request;
use crate::options::{CacheOpts, OutOpts, SourceOpts, open};

#[derive(clap::Subcommand, Debug)]
pub enum Cmd {
    /// Learn the transfer from a source subject to a target subject from pairs of
    /// corresponding frames (thesis 5.4-5.5), saved as a model folder.
    Train(TrainArgs),
    /// Transfer a motion of the source subject onto the target with a trained model (5.6).
    Apply(ApplyArgs),
}

#[derive(clap::Args, Debug)]
pub struct TrainArgs {
    /// The source subject (a subject cache or any source `surfcap import` reads).
    #[arg(long)]
    pub source: PathBuf,
    /// The target subject.
    #[arg(long)]
    pub target: PathBuf,
    /// CSV of corresponding frames, one `source sequence:frame, target sequence:frame` per line
    /// (ranges `walk:0-29, walk:0-29` pair frames one to one; `#` comments).
    #[arg(long)]
    pub pairs: PathBuf,
    /// Body parts of the source (a parts file, see docs/formats.md, "Body parts files"); default: five parts
    /// proposed from the subject (its joints, its separate meshes or the rigidity of its
    /// motion), as `surfcap parts propose` does.
    #[arg(long)]
    pub source_parts: Option<PathBuf>,
    /// Body parts of the target, with the same part names as the source's.
    #[arg(long)]
    pub target_parts: Option<PathBuf>,
    /// One part, the whole body, for a subject without a parts file (thesis Fig. 5.10's
    /// baseline).
    #[arg(long)]
    pub whole_body: bool,
    /// PCA components per part (thesis 5.4.3: 20).
    #[arg(long, default_value_t = 20, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub components: usize,
    /// GP kernel: nn (thesis eq. 5.13), se or linear (eq. 5.14).
    #[arg(long, default_value = "nn", value_parser = |s: &str| TransferKernel::parse(s).map_err(|e| e.to_string()))]
    pub kernel: TransferKernel,
    /// Seed of the hyper-parameter fits' restarts.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Train on the key pairs only, without densifying them (thesis 5.5.1) into one pair per
    /// frame of each pair of sequences.
    #[arg(long)]
    pub no_densify: bool,
    /// Densification: at most this many consecutive frames of one sequence matched to one
    /// frame of the other (thesis: 3).
    #[arg(long, default_value_t = 3, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub max_straight: usize,
    /// The model folder to write.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source_opts: SourceOpts,
}

#[derive(clap::Args, Debug)]
pub struct ApplyArgs {
    /// A model folder written by `surfcap transfer train`.
    pub model: PathBuf,
    /// The motion to transfer: `SUBJECT:SEQUENCE`, a source-subject path and one of its
    /// sequences (any motion of the source, seen in training or not).
    #[arg(long)]
    pub motion: String,
    /// How the predicted parts become one mesh: stitch (thesis 5.6.2: the parts stitched along
    /// the cheapest cuts inside their overlaps with a Poisson merge; `--correction` adds 5.6.1)
    /// or average (every vertex the mean of its copies).
    #[arg(long, default_value = "stitch")]
    pub reconstruction: Reconstruction,
    /// Before stitching, correct each part against its nearest training meshes (thesis 5.6.1).
    /// Off by default: on the motions of `surfcap eval transfer` absent from training it never
    /// lowered the error against the truth (KayKit 2.06 / 2.07 / 2.37% with it, 2.06 / 2.07 /
    /// 2.35% without; mannequin dance 4.71% against 4.45%) and raised the largest edge-length
    /// change inside parts (109% to 298% on the barbarian).
    #[arg(long)]
    pub correction: bool,
    /// Training meshes each part correction blends (M of 5.6.1; 3 in the thesis).
    #[arg(long, default_value_t = 3, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub nearest: usize,
    #[command(flatten)]
    pub out: OutOpts,
    #[command(flatten)]
    pub source_opts: SourceOpts,
}

/// See [`ApplyArgs::reconstruction`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reconstruction {
    Stitch,
    Average,
}

impl std::str::FromStr for Reconstruction {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "stitch" => Ok(Reconstruction::Stitch),
            "average" => Ok(Reconstruction::Average),
            _ => Err(format!("{s:?}: expected stitch or average")),
        }
    }
}

pub fn run(ctx: &crate::Ctx, cmd: Cmd) -> anyhow::Result<()> {
    match cmd {
        Cmd::Train(a) => train(ctx, a),
        Cmd::Apply(a) => apply(ctx, a),
    }
}

fn train(ctx: &crate::Ctx, a: TrainArgs) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = vec![&a.source, &a.target, &a.pairs];
    inputs.extend(a.source_parts.as_deref());
    inputs.extend(a.target_parts.as_deref());
    let (outs, output) = ctx.claim_dir(&a.output, KIND, &inputs)?;
    let t0 = Instant::now();
    let source = open(ctx, &a.source, &a.source_opts)?;
    let target = open(ctx, &a.target, &a.source_opts)?;
    let text = String::from_utf8(surfcap_mesh::read_regular_file(&a.pairs)?)
        .map_err(|_| anyhow::anyhow!("{}: not UTF-8 text: expected a CSV of frame pairs", a.pairs.display()))?;
    let keys = parse_pairs(&text, &a.pairs.display().to_string(), &source, &target)?;
    let source_parts = parts_of(ctx, a.source_parts.as_deref(), a.whole_body, &source, "source", "--source-parts")?;
    let target_parts = parts_of(ctx, a.target_parts.as_deref(), a.whole_body, &target, "target", "--target-parts")?;

    let key_pairs: Vec<(usize, usize)> = keys.iter().map(|k| (k.source, k.target)).collect();
    let mut options = TrainOptions { components: a.components, ..TrainOptions::default() };
    options.mapping.kernel = a.kernel;
    options.mapping.fit.seed = a.seed;
    let req = TrainingRequest {
        source: &source,
        target: &target,
        source_parts: &source_parts,
        target_parts: &target_parts,
        keys: &key_pairs,
        options,
        densify: (!a.no_densify).then(|| DensifyOptions { max_straight: a.max_straight, ..DensifyOptions::default() }),
    };
    ctx.say(&format!(
        "training {} -> {} on {} key pairs, {} parts, {} components, kernel {}",
        source.name,
        target.name,
        key_pairs.len(),
        target_parts.len(),
        a.components,
        a.kernel.name()
    ));
    let trained = train_cached(&req, &a.cache.dir()?, a.cache.no_cache, &mut |n: String| ctx.note(&n))?;
    let t = &trained.summary;
    for g in t.groups.iter().filter(|g| !g.densified) {
        ctx.note(&format!(
            "{} -> {}: a single key pair, kept as it is (densification needs at least two per pair of sequences)",
            source.sequences()[g.source_sequence].name,
            target.sequences()[g.target_sequence].name
        ));
    }
    write_model(&output, &trained.model, &trained.subjects, &trained.target_training)?;
    let groups: Vec<serde_json::Value> = t
        .groups
        .iter()
        .map(|g| {
            json!({
                "source_sequence": source.sequences()[g.source_sequence].name,
                "target_sequence": target.sequences()[g.target_sequence].name,
                "keys": g.keys, "pairs": g.pairs, "densified": g.densified, "mean_cost": g.mean_cost,
            })
        })
        .collect();
    let result = json!({
        "model": a.output, "source": source.name, "target": target.name,
        "pairs": t.pairs.len(), "key_pairs": keys.len(), "densified": !a.no_densify, "sequence_pairs": groups,
        "source_sequences": t.source_sequences.iter().map(|&k| source.sequences()[k].name.clone()).collect::<Vec<_>>(),
        "target_sequences": t.target_sequences.iter().map(|&k| target.sequences()[k].name.clone()).collect::<Vec<_>>(),
        "kernel": a.kernel.name(), "components": a.components,
        "parts": t.report.parts, "displacement": t.report.displacement,
        "fit_seconds": t.fit_seconds, "total_seconds": t0.elapsed().as_secs_f64(), "cached": trained.from_cache,
    });
    crate::output::write_json(&output.join("report.json"), &result)?;
    ctx.commit(outs)?;
    ctx.result(&result, || print_trained(&result));
    Ok(())
}

/// The human summary of a training, from its report.
fn print_trained(r: &serde_json::Value) {
    let cached = r["cached"].as_bool().unwrap_or(false);
    println!(
        "{} -> {}: {} pairs ({} key pairs{}), {} parts, {} -> {}",
        r["source"].as_str().unwrap_or_default(),
        r["target"].as_str().unwrap_or_default(),
        r["pairs"],
        r["key_pairs"],
        if r["densified"] == true { ", densified" } else { "" },
        r["parts"].as_array().map_or(0, Vec::len),
        if cached {
            "from the cache".to_string()
        } else {
            format!("fitted in {:.2} s", r["fit_seconds"].as_f64().unwrap_or(0.0))
        },
        r["model"].as_str().unwrap_or_default()
    );
    for p in r["parts"].as_array().into_iter().flatten() {
        println!(
            "  {:<12} {:>6} -> {:>6} vertices, {:>2} -> {:>2} components ({:.1}% of the target part's variance)",
            p["name"].as_str().unwrap_or_default(),
            p["source_vertices"],
            p["target_vertices"],
            p["source_components"],
            p["target_components"],
            100.0 * p["target_explained_variance"].as_f64().unwrap_or(0.0)
        );
    }
}

fn apply(ctx: &crate::Ctx, a: ApplyArgs) -> anyhow::Result<()> {
    let (subject_path, sequence) = a.motion.rsplit_once(':').ok_or_else(|| {
        anyhow::anyhow!(
            "--motion {:?}: expected SUBJECT:SEQUENCE (a source-subject path and a sequence name)",
            a.motion
        )
    })?;
    let subject_path = PathBuf::from(subject_path);
    let format = a.out.format();
    // The animation (its sidecar when a file) and the report, planned before any work.
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&[&a.model, &subject_path]);
    surfcap_formats::export::plan_export(&mut outs, format, &a.out.output, ctx.force)?;
    outs.side_file(&surfcap_synthesis::report_path(&a.out.output), surfcap_synthesis::REPORT_KIND)?;
    let t0 = Instant::now();
    let saved = read_model(&a.model)?;
    let model = &saved.model;
    let source = open(ctx, &subject_path, &a.source_opts)?;
    let nv_source = model.source.reference.len() / 3;
    if source.topology().n_vertices() != nv_source {
        anyhow::bail!(
            "{}: {} vertices, but the model {} was trained on a source of {nv_source} vertices ({}): expected a motion of that subject",
            subject_path.display(),
            source.topology().n_vertices(),
            a.model.display(),
            saved.subjects.source_name
        );
    }
    if mesh_fingerprint(source.topology()) != saved.subjects.source_mesh {
        anyhow::bail!(
            "{}: its mesh has the model's {nv_source} vertices but other triangles than the source {} was trained on: expected a motion of that subject",
            subject_path.display(),
            saved.subjects.source_name
        );
    }
    if (source.fps - saved.subjects.source_fps).abs() > 1e-9 * source.fps.abs().max(1.0) {
        ctx.note(&format!(
            "{} plays at {} fps and the model's source at {} fps: the displacement per frame is learnt at the model's rate, so the travel scales by their ratio",
            subject_path.display(),
            source.fps,
            saved.subjects.source_fps
        ));
    }
    let (_, seq) = source.sequence(sequence).ok_or_else(|| {
        let known: Vec<&str> = source.sequences().iter().map(|q| q.name.as_str()).collect();
        anyhow::anyhow!(
            "--motion: {} has no sequence {sequence:?}; it has {}",
            subject_path.display(),
            known.join(", ")
        )
    })?;
    let meta = &saved.subjects;
    let nv = model.target.reference.len() / 3;
    let topology = Topology::new(nv, meta.target_triangles.clone(), None)?;
    // Sized before any work: the output has the motion's frames on the target's mesh.
    let shape = Subject::new(
        meta.target_name.clone(),
        topology.clone(),
        vec![Sequence::new("size", nv, model.target.reference.clone())?],
        meta.target_fps,
        meta.target_up_axis,
        meta.target_units.clone(),
    )?;
    a.out.limits.check(
        ctx,
        &a.out.output,
        &Request {
            what: format!("--motion {}", a.motion),
            frames: seq.n_frames() as f64,
            subject: &shape,
            search_bytes: 0,
            format,
        },
    )?;
    let frames: Vec<&[f32]> = (0..seq.n_frames()).map(|f| seq.frame(f)).collect();
    let t_setup = Instant::now();
    let stitching = a.reconstruction == Reconstruction::Stitch;
    let correction = stitching && a.correction;
    let reconstructor = if stitching {
        let opts = ReconstructionOptions { correction, m_nearest: a.nearest };
        Some(Reconstructor::new(model, &topology, &saved.target_training, &opts)?)
    } else {
        None
    };
    let setup_seconds = t_setup.elapsed().as_secs_f64();
    let t_transfer = Instant::now();
    let mut cuts = Vec::new();
    let out = model.transfer(&frames, |p| match &reconstructor {
        Some(r) => {
            let (pose, report) = r.reconstruct(p)?;
            cuts.push(report);
            Ok(pose)
        }
        None => average_overlaps(&model.target.parts, p, false),
    })?;
    let transfer_seconds = t_transfer.elapsed().as_secs_f64();
    // Seams: edge-length change against the target's reference pose, on edges at part
    // boundaries and inside parts (no ground truth here: the reference is the rest shape).
    let mut seams = Vec::new();
    for pose in &out.aligned {
        seams.push(edge_distortion_by_region(&topology, &model.target.parts, pose, &model.target.reference)?);
    }
    let max_of = |f: &dyn Fn(&surfcap_transfer::part_stitching::EdgeDistortion) -> f64| {
        seams.iter().map(f).fold(0.0f64, f64::max)
    };
    let has_boundary = seams.iter().any(|e| e.boundary_edges > 0);
    let seam_summary = json!({
        "boundary_edges": seams.first().map_or(0, |e| e.boundary_edges),
        "inside_edges": seams.first().map_or(0, |e| e.inside_edges),
        "boundary_max": has_boundary.then(|| max_of(&|e| e.boundary_max)), "inside_max": max_of(&|e| e.inside_max),
        "boundary_mean": has_boundary.then(|| crate::output::mean(seams.iter().map(|e| e.boundary_mean))),
        "inside_mean": crate::output::mean(seams.iter().map(|e| e.inside_mean)),
        "against": "the target's reference pose",
    });
    let name = format!("{}-as-{}", seq.name, meta.target_name);
    let positions: Vec<f32> = out.world.iter().flatten().copied().collect();
    let out_seq = Sequence::new(name.clone(), nv, positions)?
        .with_labels(vec![FrameLabel::Synthetic; seq.n_frames()])?
        .with_tags(vec!["transfer".into()]);
    let out_subject = Subject::new(
        name.clone(),
        topology,
        vec![out_seq],
        meta.target_fps,
        meta.target_up_axis,
        meta.target_units.clone(),
    )?;
    let bar = crate::progress::Bar::new(ctx);
    let written = export(&out_subject, format, &a.out.output, ctx.export_options(), &bar)?;
    let report = json!({
        "model": a.model, "motion": a.motion, "source": meta.source_name, "target": meta.target_name,
        "frames": seq.n_frames(),
        "reconstruction": if stitching { "stitch" } else { "average" }, "correction": correction,
        "nearest": a.nearest,
        "parts": model.target.parts.names(),
        "edge_length_distortion": seam_summary,
        "setup_seconds": setup_seconds, "transfer_seconds": transfer_seconds,
        "total_seconds": t0.elapsed().as_secs_f64(),
        "per_frame": { "displacement": out.displacements, "cuts": cuts },
        "written": written,
    });
    surfcap_synthesis::write_report(&surfcap_synthesis::report_path(&a.out.output), &report)?;
    ctx.commit(outs)?;
    ctx.result(&report, || {
        println!(
            "{} ({} frames) transferred onto {} in {transfer_seconds:.2} s ({}; set-up {setup_seconds:.2} s) -> {}",
            a.motion,
            seq.n_frames(),
            meta.target_name,
            if correction {
                "parts corrected and stitched"
            } else if stitching {
                "parts stitched"
            } else {
                "overlaps averaged"
            },
            a.out.output.display()
        );
        if has_boundary {
            println!(
                "  edge-length change against the target's rest pose: at part boundaries max {:.1}%, inside parts max {:.1}%",
                100.0 * max_of(&|e| e.boundary_max),
                100.0 * max_of(&|e| e.inside_max)
            );
        }
    });
    Ok(())
}
