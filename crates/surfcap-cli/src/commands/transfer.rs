//! `surfcap transfer train | apply`: motion transfer between two subjects by GP regression on
//! body parts (thesis chapter 5; `surfcap-transfer`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use surfcap_formats::export::export;
pub use surfcap_synthesis::transfer_run::Reconstruction;
use surfcap_synthesis::transfer_run::{
    ApplyOptions, MotionOf, TrainingCache, TransferApplication, TransferMethod, TransferTrainOptions, TransferTraining,
    read_key_pairs, train_model, write_model_files,
};
use surfcap_transfer::transfer_model::TransferKernel;
use surfcap_transfer::transfer_model_file::{KIND, read_any};

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
    let keys = read_key_pairs(&a.pairs, &source, &target)?;

    let options = TransferTrainOptions {
        method: if a.method == "baran" { TransferMethod::Baran } else { TransferMethod::Gp },
        components: a.components,
        kernel: a.kernel,
        seed: a.seed,
        densify: !a.no_densify,
        max_straight: a.max_straight,
    };
    let baran = options.method == TransferMethod::Baran;
    let parts = if baran {
        ctx.say(&format!(
            "training Baran et al. {} -> {} on {} key pairs (whole body)",
            source.name,
            target.name,
            keys.len()
        ));
        None
    } else {
        let source_parts = parts_of(ctx, a.source_parts.as_deref(), a.whole_body, &source, "source", "--source-parts")?;
        let target_parts = parts_of(ctx, a.target_parts.as_deref(), a.whole_body, &target, "target", "--target-parts")?;
        ctx.say(&format!(
            "training {} -> {} on {} key pairs, {} parts, {} components, kernel {}",
            source.name,
            target.name,
            keys.len(),
            target_parts.len(),
            a.components,
            a.kernel.name()
        ));
        Some((source_parts, target_parts))
    };
    let training = TransferTraining {
        source: &source,
        target: &target,
        keys: &keys,
        parts: parts.as_ref().map(|(s, t)| (s, t)),
        options,
    };
    let cache = TrainingCache { dir: a.cache.dir()?, refresh: a.cache.no_cache };
    let mut trained = train_model(&training, Some(&cache), &mut |n: String| ctx.note(&n))?;
    write_model_files(&output, &trained.model)?;
    trained.report.set_model(&a.output);
    trained.report.set_total_seconds(t0.elapsed().as_secs_f64());
    let result = serde_json::to_value(&trained.report)?;
    crate::output::write_json(&output.join("report.json"), &trained.report)?;
    ctx.commit(outs)?;
    ctx.result(&result, || {
        if baran {
            println!(
                "{} -> {}: Baran et al. on {} key pairs, {} -> {} vertices, built in {:.2} s -> {}",
                source.name,
                target.name,
                keys.len(),
                result["source_vertices"],
                result["target_vertices"],
                result["fit_seconds"].as_f64().unwrap_or(0.0),
                a.output.display()
            )
        } else {
            print_trained(&result)
        }
    });
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
    let source = open(ctx, &subject_path, &a.source_opts)?;
    let truth_subject = match &truth_arg {
        Some((path, _)) => Some(open(ctx, path, &a.source_opts)?),
        None => None,
    };
    let source_label = subject_path.display().to_string();
    let motion = MotionOf { subject: &source, label: &source_label, sequence, option: "--motion", spec: &a.motion };
    let truth_label = truth_arg.as_ref().map(|(p, _)| p.display().to_string()).unwrap_or_default();
    let truth = match (&truth_arg, &truth_subject, &a.truth) {
        (Some((_, name)), Some(t), Some(spec)) => {
            Some(MotionOf { subject: t, label: &truth_label, sequence: name, option: "--truth", spec })
        }
        _ => None,
    };
    // The model, the motion and the true motion checked before any work.
    let application = TransferApplication::new(&saved, &a.model, motion, truth)?;
    if let Some(n) = &application.note {
        ctx.note(n);
    }
    // Sized before any work: the output has the motion's frames on the target's mesh.
    let shape = application.shape()?;
    a.out.limits.check(
        ctx,
        &a.out.output,
        &Request {
            what: format!("--motion {}", a.motion),
            frames: application.frames() as f64,
            subject: &shape,
            search_bytes: 0,
            format,
        },
    )?;
    let options = ApplyOptions { reconstruction: a.reconstruction, correction: a.correction, nearest: a.nearest };
    let (out_subject, mut report) = application.run(&options, t0)?;
    let bar = crate::progress::Bar::new(ctx);
    let written = export(&out_subject, format, &a.out.output, ctx.export_options(), &bar)?;
    report.written = written;
    surfcap_synthesis::write_report(&surfcap_synthesis::report_path(&a.out.output), &report)?;
    ctx.commit(outs)?;
    let (method, correction) = (report.method, report.correction);
    let (transfer_seconds, setup_seconds) = (report.transfer_seconds, report.setup_seconds);
    let report = serde_json::to_value(&report)?;
    ctx.result(&report, || {
        println!(
            "{} ({} frames) transferred onto {} in {transfer_seconds:.2} s ({}; set-up {setup_seconds:.2} s) -> {}",
            a.motion,
            report["frames"],
            report["target"].as_str().unwrap_or_default(),
            if method == "baran" {
                "Baran et al."
            } else if correction {
                "parts corrected and stitched"
            } else if a.reconstruction == Reconstruction::Stitch {
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
