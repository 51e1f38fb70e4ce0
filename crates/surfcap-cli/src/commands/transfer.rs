//! `surfcap transfer train | apply`: motion transfer between two subjects by GP regression on
//! body parts (thesis chapter 5; `surfcap-transfer`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;
use surfcap_formats::export::export;
use surfcap_mesh::{FrameLabel, Sequence, Subject, Topology};
use surfcap_transfer::BodyParts;
use surfcap_transfer::baran_transfer::BaranTransfer;
use surfcap_transfer::correspondence_densification::DensifyOptions;
use surfcap_transfer::motion_transfer::TrainOptions;
use surfcap_transfer::pairs_file::parse_pairs;
use surfcap_transfer::part_stitching::{EdgeDistortion, average_overlaps, edge_distortion_by_region};
use surfcap_transfer::shape_reconstruction::{ReconstructionOptions, Reconstructor};
use surfcap_transfer::transfer_model::TransferKernel;
use surfcap_transfer::transfer_model_file::{
    KIND, SavedTransfer, SubjectsMeta, mesh_fingerprint, read_any, write_baran_model, write_model,
};
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
    /// Method: gp (GP regression on body parts, thesis ch. 5) or baran (Baran et al. 2009,
    /// semantic deformation transfer: the key pairs are its key poses, whole body; the part,
    /// component, kernel and densification options do not apply).
    #[arg(long, default_value = "gp", value_parser = ["gp", "baran"])]
    pub method: String,
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
    /// The true motion on the target, `SUBJECT:SEQUENCE` (a target-subject path and one of its
    /// sequences, as many frames as the motion): the report then gives the error against it
    /// (RMS per-vertex after a rigid alignment, % of the target's height) next to the nearest
    /// training pose's, and the edge-length change relative to the true motion's edges.
    /// Without it the edge-length measure is dropped (against the rest pose it mostly measures
    /// how the motion itself stretches short edges).
    #[arg(long)]
    pub truth: Option<String>,
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

    let key_pairs: Vec<(usize, usize)> = keys.iter().map(|k| (k.source, k.target)).collect();
    if a.method == "baran" {
        ctx.say(&format!(
            "training Baran et al. {} -> {} on {} key pairs (whole body)",
            source.name,
            target.name,
            key_pairs.len()
        ));
        let t_fit = Instant::now();
        let model = BaranTransfer::train(&source, &target, &key_pairs)?;
        let fit_seconds = t_fit.elapsed().as_secs_f64();
        write_baran_model(&output, &model, &SubjectsMeta::new(&source, &target))?;
        let result = json!({
            "model": a.output, "method": "baran", "source": source.name, "target": target.name,
            "pairs": key_pairs.len(), "key_pairs": keys.len(), "densified": false,
            "source_vertices": model.source_vertices(), "target_vertices": model.target_vertices(),
            "fit_seconds": fit_seconds, "total_seconds": t0.elapsed().as_secs_f64(), "cached": false,
        });
        crate::output::write_json(&output.join("report.json"), &result)?;
        ctx.commit(outs)?;
        ctx.result(&result, || {
            println!(
                "{} -> {}: Baran et al. on {} key pairs, {} -> {} vertices, built in {fit_seconds:.2} s -> {}",
                source.name,
                target.name,
                key_pairs.len(),
                model.source_vertices(),
                model.target_vertices(),
                a.output.display()
            )
        });
        return Ok(());
    }
    let source_parts = parts_of(ctx, a.source_parts.as_deref(), a.whole_body, &source, "source", "--source-parts")?;
    let target_parts = parts_of(ctx, a.target_parts.as_deref(), a.whole_body, &target, "target", "--target-parts")?;
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
        "method": "gp", "kernel": a.kernel.name(), "components": a.components,
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

/// Splits `SUBJECT:SEQUENCE` (`option` names it in the error).
fn subject_and_sequence<'a>(text: &'a str, option: &str, side: &str) -> anyhow::Result<(PathBuf, &'a str)> {
    let (path, sequence) = text.rsplit_once(':').ok_or_else(|| {
        anyhow::anyhow!("{option} {text:?}: expected SUBJECT:SEQUENCE (a {side}-subject path and a sequence name)")
    })?;
    Ok((PathBuf::from(path), sequence))
}

/// The sequence `name` of `subject` (read from `path`), or an error listing its sequences.
fn sequence_of<'a>(subject: &'a Subject, path: &Path, name: &str, option: &str) -> anyhow::Result<&'a Sequence> {
    subject.sequence(name).map(|(_, q)| q).ok_or_else(|| {
        let known: Vec<&str> = subject.sequences().iter().map(|q| q.name.as_str()).collect();
        anyhow::anyhow!("{option}: {} has no sequence {name:?}; it has {}", path.display(), known.join(", "))
    })
}

fn apply(ctx: &crate::Ctx, a: ApplyArgs) -> anyhow::Result<()> {
    let (subject_path, sequence) = subject_and_sequence(&a.motion, "--motion", "source")?;
    let truth_arg = a.truth.as_deref().map(|t| subject_and_sequence(t, "--truth", "target")).transpose()?;
    let format = a.out.format();
    // The animation (its sidecar when a file) and the report, planned before any work.
    let mut inputs: Vec<&Path> = vec![&a.model, &subject_path];
    if let Some((p, _)) = &truth_arg {
        inputs.push(p);
    }
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&inputs);
    surfcap_formats::export::plan_export(&mut outs, format, &a.out.output, ctx.force)?;
    outs.side_file(&surfcap_synthesis::report_path(&a.out.output), surfcap_synthesis::REPORT_KIND)?;
    let t0 = Instant::now();
    let saved = read_any(&a.model)?;
    let (meta, nv_source, nv) = match &saved {
        SavedTransfer::Gp(m) => (&m.subjects, m.model.source.reference.len() / 3, m.model.target.reference.len() / 3),
        SavedTransfer::Baran(b) => (&b.subjects, b.model.source_vertices(), b.model.target_vertices()),
    };
    let source = open(ctx, &subject_path, &a.source_opts)?;
    if source.topology().n_vertices() != nv_source {
        anyhow::bail!(
            "{}: {} vertices, but the model {} was trained on a source of {nv_source} vertices ({}): expected a motion of that subject",
            subject_path.display(),
            source.topology().n_vertices(),
            a.model.display(),
            meta.source_name
        );
    }
    if mesh_fingerprint(source.topology()) != meta.source_mesh {
        anyhow::bail!(
            "{}: its mesh has the model's {nv_source} vertices but other triangles than the source {} was trained on: expected a motion of that subject",
            subject_path.display(),
            meta.source_name
        );
    }
    if (source.fps - meta.source_fps).abs() > 1e-9 * source.fps.abs().max(1.0) {
        ctx.note(&format!(
            "{} plays at {} fps and the model's source at {} fps: the displacement per frame is learnt at the model's rate, so the travel scales by their ratio",
            subject_path.display(),
            source.fps,
            meta.source_fps
        ));
    }
    let seq = sequence_of(&source, &subject_path, sequence, "--motion")?;
    let topology = Topology::new(nv, meta.target_triangles.clone(), None)?;
    // The true motion, checked before any work: the target's mesh, the motion's frames.
    let truth_subject = match &truth_arg {
        Some((path, _)) => Some(open(ctx, path, &a.source_opts)?),
        None => None,
    };
    let truth: Option<&Sequence> = match (&truth_arg, &truth_subject) {
        (Some((path, name)), Some(t)) => {
            if t.topology().n_vertices() != nv || mesh_fingerprint(t.topology()) != mesh_fingerprint(&topology) {
                anyhow::bail!(
                    "--truth {}: {} vertices and its own triangles, but the model's target {} has {nv} vertices and other triangles: expected a motion of the target",
                    path.display(),
                    t.topology().n_vertices(),
                    meta.target_name
                );
            }
            let q = sequence_of(t, path, name, "--truth")?;
            if q.n_frames() != seq.n_frames() {
                anyhow::bail!(
                    "--truth {}:{name}: {} frames, but the motion {} has {}: expected the true partner of every frame",
                    path.display(),
                    q.n_frames(),
                    a.motion,
                    seq.n_frames()
                );
            }
            Some(q)
        }
        _ => None,
    };
    let reference = match &saved {
        SavedTransfer::Gp(m) => m.model.target.reference.clone(),
        SavedTransfer::Baran(b) => b.model.target_keys[0].clone(),
    };
    // Sized before any work: the output has the motion's frames on the target's mesh.
    let shape = Subject::new(
        meta.target_name.clone(),
        topology.clone(),
        vec![Sequence::new("size", nv, reference)?],
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
    let mut cuts = Vec::new();
    let (method, correction, out, setup_seconds, transfer_seconds, target_parts, training) = match &saved {
        SavedTransfer::Gp(saved) => {
            let model = &saved.model;
            let correction = stitching && a.correction;
            let reconstructor = if stitching {
                let opts = ReconstructionOptions { correction, m_nearest: a.nearest };
                Some(Reconstructor::new(model, &topology, &saved.target_training, &opts)?)
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
            ("gp", correction, out, setup_seconds, t_transfer.elapsed().as_secs_f64(), parts, &saved.target_training)
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
    // change |l / l_true - 1| at part boundaries and inside parts. Without it the edge measure
    // is dropped: against the rest pose it mostly measures the motion's own stretching.
    let (accuracy, seam_summary) = match truth {
        Some(q) => {
            let (lo, hi) = surfcap_mesh::bounding_box(q.frame(0));
            let k = meta.target_up_axis.axis_and_sign().0;
            let height = (hi[k] - lo[k]) as f64;
            let pct = |x: f64| if height > 0.0 { 100.0 * x / height } else { f64::NAN };
            let mut err = 0.0;
            let mut nearest = 0.0;
            let mut seams = Vec::new();
            for (f, pose) in out.aligned.iter().enumerate() {
                let t = q.frame(f);
                err += surfcap_eval::transfer_eval::aligned_rms(pose, t).powi(2);
                let best = training
                    .iter()
                    .map(|p| surfcap_eval::transfer_eval::aligned_rms(t, p))
                    .fold(f64::INFINITY, f64::min);
                nearest += best.powi(2);
                seams.push(edge_distortion_by_region(&topology, &target_parts, pose, t)?);
            }
            let n = out.aligned.len().max(1) as f64;
            let (err, nearest) = ((err / n).sqrt(), (nearest / n).sqrt());
            let max_of = |f: &dyn Fn(&EdgeDistortion) -> f64| seams.iter().map(f).fold(0.0f64, f64::max);
            let has_boundary = seams.iter().any(|e| e.boundary_edges > 0);
            (
                json!({
                    "truth": a.truth, "target_height": height,
                    "rms": err, "rms_percent": pct(err),
                    "nearest_training_pose_rms": nearest, "nearest_training_pose_percent": pct(nearest),
                    "nearest_training_poses": training.len(),
                    "method": method,
                }),
                json!({
                    "boundary_edges": seams.first().map_or(0, |e| e.boundary_edges),
                    "inside_edges": seams.first().map_or(0, |e| e.inside_edges),
                    "boundary_max": has_boundary.then(|| max_of(&|e| e.boundary_max)), "inside_max": max_of(&|e| e.inside_max),
                    "boundary_mean": has_boundary.then(|| crate::output::mean(seams.iter().map(|e| e.boundary_mean))),
                    "inside_mean": crate::output::mean(seams.iter().map(|e| e.inside_mean)),
                    "against": "the true motion (--truth): |l / l_true - 1| per edge and frame",
                }),
            )
        }
        None => (
            serde_json::Value::Null,
            json!({
                "boundary_edges": null, "inside_edges": null,
                "boundary_max": null, "inside_max": null, "boundary_mean": null, "inside_mean": null,
                "against": "dropped: no --truth (against the rest pose it measures the motion's own stretching of short edges)",
            }),
        ),
    };
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
        "model": a.model, "method": method, "motion": a.motion, "source": meta.source_name, "target": meta.target_name,
        "frames": seq.n_frames(),
        "reconstruction": if method == "baran" { "baran" } else if stitching { "stitch" } else { "average" },
        "correction": correction,
        "nearest": a.nearest,
        "parts": target_parts.names(),
        "accuracy": accuracy,
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
            if method == "baran" {
                "Baran et al."
            } else if correction {
                "parts corrected and stitched"
            } else if stitching {
                "parts stitched"
            } else {
                "overlaps averaged"
            },
            a.out.output.display()
        );
        let e = &report["edge_length_distortion"];
        if !report["accuracy"].is_null() {
            let acc = &report["accuracy"];
            println!(
                "  against the true motion: {:.2}% of the target's height (nearest of the {} training poses: {:.2}%)",
                acc["rms_percent"].as_f64().unwrap_or(f64::NAN),
                acc["nearest_training_poses"],
                acc["nearest_training_pose_percent"].as_f64().unwrap_or(f64::NAN)
            );
            let boundary = e["boundary_max"]
                .as_f64()
                .map_or("no part boundaries".to_string(), |b| format!("at part boundaries max {:.1}%", 100.0 * b));
            println!(
                "  edge-length change against the true motion: {boundary}, inside parts max {:.1}%",
                100.0 * e["inside_max"].as_f64().unwrap_or(f64::NAN)
            );
        }
    });
    Ok(())
}
