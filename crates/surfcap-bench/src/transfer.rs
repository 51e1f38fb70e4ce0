//! `surfcap-bench transfer`: the speed targets of motion transfer (thesis chapter 5) on 2 cores:
//! training with 350 pairs, 5 body parts, 20 components per part and fitted hyper-parameters
//! under 10 s; the transfer of a 100-frame motion to a 10,000-vertex target, part correction
//! and stitching included, under 10 s. The subjects are two built-in mannequins (an average
//! body of `--source-vertices` and a heavy one of `--target-vertices`) moved by the same CMU
//! clips; their parts are proposed from the joints. Building the mannequins is not timed.

use std::time::Instant;

use serde_json::json;
use surfcap_builtin::mannequin::BodyShape;
use surfcap_eval::transfer_eval::{CMU_TRAIN, mannequin_cmu_subject};
use surfcap_transfer::body_parts_proposal::{Method, propose};
use surfcap_transfer::motion_transfer::{MotionTransfer, PreparedSubject, TrainOptions};
use surfcap_transfer::shape_reconstruction::{ReconstructionOptions, Reconstructor};

use crate::measure::verdict;
use crate::options::SeedOpt;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("the CMU clips"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: std::path::PathBuf,
    /// Training pairs.
    #[arg(long, default_value_t = 350, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub pairs: usize,
    /// Body parts (torso and limbs).
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub parts: usize,
    /// PCA components per part.
    #[arg(long, default_value_t = 20, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub components: usize,
    /// Frames of the transferred motion.
    #[arg(long, default_value_t = 100, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub frames: usize,
    /// Source mannequin vertices (about).
    #[arg(long, default_value_t = 3000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub source_vertices: usize,
    /// Target mannequin vertices (about: the mannequin's remeshing lands near it; the default
    /// gives just over 10,000).
    #[arg(long, default_value_t = 10800, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub target_vertices: usize,
    #[command(flatten)]
    pub seed: SeedOpt,
}

pub fn run(ctx: &crate::Ctx, a: &Args) -> anyhow::Result<()> {
    // The training pairs' positions (both mannequins) and the transferred frames, f32, with
    // their f64 working copies.
    let (p, sv, tv) = (a.pairs as f64, a.source_vertices as f64, a.target_vertices as f64);
    let what = format!("--pairs {} --frames {}", a.pairs, a.frames);
    let memory = (p * (sv + tv) + a.frames as f64 * (sv + tv)) * 12.0 * 3.0 + a.components as f64 * p * 8.0 * 8.0;
    crate::check_size(ctx, what, memory, 0.0, "--pairs, --frames or --components")?;
    ctx.say("building the two mannequins and their CMU clips (not timed) ...");
    let source = mannequin_cmu_subject(&a.data, "average", &BodyShape::average(), a.source_vertices)?;
    let target = mannequin_cmu_subject(&a.data, "heavy", &BodyShape::heavy(), a.target_vertices)?;
    let (sp, _) = propose(&source, Method::Joints, a.parts, 3)?;
    let (tp, _) = propose(&target, Method::Joints, a.parts, 3)?;
    let train_seqs: Vec<usize> = (0..CMU_TRAIN.len()).collect();
    let frames: Vec<usize> = train_seqs.iter().flat_map(|&k| source.frame_index().range(k)).collect();
    anyhow::ensure!(
        frames.len() >= a.pairs,
        "--pairs {}: expected at most {} (the frames of the training clips)",
        a.pairs,
        frames.len()
    );
    // Every k-th frame so the pairs cover all training clips.
    let pairs: Vec<(usize, usize)> = (0..a.pairs).map(|i| frames[i * frames.len() / a.pairs]).map(|g| (g, g)).collect();
    let pca: Vec<usize> = pairs.iter().map(|p| p.0).collect();

    let t_train = Instant::now();
    let src = PreparedSubject::new(&source, &train_seqs)?;
    let tgt = PreparedSubject::new(&target, &train_seqs)?;
    let mut opts = TrainOptions { components: a.components, ..TrainOptions::default() };
    opts.mapping.fit.seed = a.seed.seed;
    let (model, report) = MotionTransfer::train(&src, &sp, &pca, &tgt, &tp, &pca, &pairs, &opts)?;
    let train_seconds = t_train.elapsed().as_secs_f64();

    // The motion: the first frames of the walk (16_15), repeated when shorter.
    let walk = &source.sequences()[0];
    let motion: Vec<&[f32]> = (0..a.frames).map(|f| walk.frame(f % walk.n_frames())).collect();
    let training: Vec<Vec<f32>> =
        pairs.iter().map(|p| tgt.frame(p.1).map(|f| f.0.to_vec())).collect::<Result<_, _>>()?;
    let t_apply = Instant::now();
    let reconstructor = Reconstructor::new(
        &model,
        target.topology(),
        &training,
        &ReconstructionOptions { correction: true, ..ReconstructionOptions::default() },
    )?;
    let setup_seconds = t_apply.elapsed().as_secs_f64();
    let out = model.transfer(&motion, |p| reconstructor.reconstruct(p).map(|r| r.0))?;
    let apply_seconds = t_apply.elapsed().as_secs_f64();
    anyhow::ensure!(
        out.world.iter().flatten().all(|v| v.is_finite()),
        "the transferred motion has non-finite positions"
    );

    let result = json!({
        "source_vertices": source.topology().n_vertices(), "target_vertices": target.topology().n_vertices(),
        "pairs": a.pairs, "parts": report.parts.len(), "components": a.components,
        "train_seconds": train_seconds, "train_target_seconds": 10.0, "train_verdict": verdict(train_seconds, 10.0),
        "frames": a.frames, "apply_setup_seconds": setup_seconds, "apply_seconds": apply_seconds,
        "apply_target_seconds": 10.0, "apply_verdict": verdict(apply_seconds, 10.0),
        "threads": rayon::current_num_threads(),
    });
    ctx.result(&result, || {
        println!(
            "train: {} pairs, {} parts x {} components, hyper-parameters fitted: {train_seconds:.2} s (target < 10 s: {})",
            a.pairs,
            report.parts.len(),
            a.components,
            verdict(train_seconds, 10.0)
        );
        println!(
            "apply: {} frames onto {} vertices, parts corrected (M = 3) and stitched: {apply_seconds:.2} s, of which set-up {setup_seconds:.2} s (target < 10 s: {})",
            a.frames,
            target.topology().n_vertices(),
            verdict(apply_seconds, 10.0)
        );
    });
    Ok(())
}
