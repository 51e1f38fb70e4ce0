//! `surfcap-bench vary`: the speed targets of motion variation (thesis chapter 6) on 2 cores:
//! training on 4 sequences of about 100 frames each under 2 minutes, sampling 5 variants under
//! 30 s. The subject is the built-in mannequin of `--vertices` vertices moved by four CMU
//! clips of subject 16 (16_15 walk 117 frames, 16_17 turn left 129, 16_19 turn right 102,
//! 16_36 jog 47, at 30 fps), the walk the reference every sequence is re-timed onto; five
//! parts proposed from the joints (not timed, as building the mannequin). Training is
//! `VariationModel::train` as `surfcap vary train` runs it (preparation and one GPDM fit per
//! part, the CLI's default of at most 400 L-BFGS iterations); sampling is `sample_variants` as
//! `surfcap vary sample --sequence 16_15 --count 5` runs it (HMC per part, reconstruction,
//! stitching, placement and re-timing of every variant; writing the glbs is not included).

use std::path::Path;
use std::time::Instant;

use serde_json::json;
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_transfer::body_parts_file::DEFAULT_OVERLAP_RINGS;
use surfcap_transfer::body_parts_proposal::{Method, propose};
use surfcap_variation::VariationModel;
use surfcap_variation::variation_model::TrainOptions;
use surfcap_variation::variation_sampling::{SamplingOptions, sample_variants};

use crate::measure::{cpu_seconds, load_average, verdict};
use crate::options::SeedOpt;

/// The CMU clips of the benchmark: walk, turn left, turn right, jog.
pub const CLIPS: [&str; 4] = ["16_15", "16_17", "16_19", "16_36"];

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("the CMU clips"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: std::path::PathBuf,
    /// Mannequin vertices (about: the remeshing lands near it).
    #[arg(long, default_value_t = 3000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Variants sampled.
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::whole_in(s, 1, 1000))]
    pub count: usize,
    /// Most L-BFGS iterations of every part's GPDM fit (`vary train --iterations`).
    #[arg(long, default_value_t = 400, value_parser = |s: &str| crate::options::whole_in(s, 1, 10_000))]
    pub iterations: usize,
    #[command(flatten)]
    pub seed: SeedOpt,
}

/// The mannequin of about `vertices` vertices moved by [`CLIPS`] (30 fps, metres).
fn cmu_subject(data: &Path, vertices: usize) -> anyhow::Result<Subject> {
    let m = mannequin(&BodyShape::average(), vertices)?;
    let mut clips = Vec::new();
    for c in CLIPS {
        let path = data.join("cmu_bvh").join(format!("{c}.bvh"));
        let bvh = read_bvh(&path)?;
        clips.push(Clip::from_bvh(&path, &bvh, &m, bvh.guess_metres_per_unit().0)?);
    }
    Ok(mannequin_subject("cmu-locomotion", &m, &clips, 30.0)?)
}

pub fn run(ctx: &crate::Ctx, a: &Args) -> anyhow::Result<()> {
    ctx.say("building the mannequin and its CMU clips, proposing its parts (not timed) ...");
    let subject = cmu_subject(&a.data, a.vertices)?;
    let (parts, _) = propose(&subject, Method::Joints, 5, DEFAULT_OVERLAP_RINGS)?;
    let frames: Vec<usize> = subject.sequences().iter().map(|q| q.n_frames()).collect();
    let mut options = TrainOptions::default();
    options.gpdm.lbfgs.max_iters = a.iterations;
    options.gpdm.lbfgs.max_evals = options.gpdm.lbfgs.max_evals.max(a.iterations + a.iterations / 4);
    ctx.say(&format!(
        "training on {} sequences ({} frames) of {} vertices, {} parts ...",
        frames.len(),
        frames.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(" + "),
        subject.topology().n_vertices(),
        parts.len()
    ));
    let all: Vec<usize> = (0..subject.sequences().len()).collect();
    let load_before = load_average();
    let (t, c) = (Instant::now(), cpu_seconds());
    let model = VariationModel::train(&subject, &all, &parts, &options, &NoProgress)?;
    let train_seconds = t.elapsed().as_secs_f64();
    let train_cpu = cpu_seconds() - c;
    let walk = subject.sequences()[0].name.clone();
    ctx.say(&format!("sampling {} variants of {walk} ...", a.count));
    let (t, c) = (Instant::now(), cpu_seconds());
    let (variants, chains) = sample_variants(&model, &walk, a.count, a.seed.seed, &SamplingOptions::default())?;
    let sample_seconds = t.elapsed().as_secs_f64();
    let sample_cpu = cpu_seconds() - c;
    let load_after = load_average();
    anyhow::ensure!(
        variants.iter().all(|v| v.world.iter().flatten().all(|x| x.is_finite())),
        "a sampled variant has non-finite positions"
    );
    let fits: Vec<serde_json::Value> = model
        .fits
        .iter()
        .map(|f| {
            json!({"part": f.part, "dimensions": f.dimensions, "iterations": f.fit.iters,
                   "converged": f.fit.converged, "seconds": f.seconds})
        })
        .collect();
    let result = json!({
        "threads": rayon::current_num_threads(),
        "vertices": subject.topology().n_vertices(),
        "clips": CLIPS, "frames": frames, "reference_frames": model.frames,
        "parts": fits, "max_iterations": a.iterations,
        "train_seconds": train_seconds, "train_cpu_seconds": train_cpu, "train_target_seconds": 120.0,
        "train_verdict": verdict(train_seconds, 120.0),
        "variants": a.count, "variant_frames": variants.first().map_or(0, |v| v.world.len()),
        "sample_seconds": sample_seconds, "sample_cpu_seconds": sample_cpu, "sample_target_seconds": 30.0,
        "sample_verdict": verdict(sample_seconds, 30.0),
        "chains": chains,
        "load_average": [load_before, load_after],
    });
    ctx.result(&result, || {
        println!(
            "train: {} sequences ({} frames, re-timed onto the walk's {}), {} vertices, {} parts, at most {} iterations: {train_seconds:.1} s, {train_cpu:.1} s of CPU (target < 120 s: {})",
            frames.len(),
            frames.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(" + "),
            model.frames,
            subject.topology().n_vertices(),
            model.fits.len(),
            a.iterations,
            verdict(train_seconds, 120.0)
        );
        for f in &model.fits {
            println!(
                "  {:<12} {:>6} dims, {:>3} iterations{}, {:.1} s",
                f.part,
                f.dimensions,
                f.fit.iters,
                if f.fit.converged { " (converged)" } else { "" },
                f.seconds
            );
        }
        println!(
            "sample: {} variants of {walk} ({} frames each): {sample_seconds:.1} s, {sample_cpu:.1} s of CPU (target < 30 s: {})",
            a.count,
            variants.first().map_or(0, |v| v.world.len()),
            verdict(sample_seconds, 30.0)
        );
        let load = |x: Option<f64>| x.map_or("?".to_string(), |l| format!("{l:.1}"));
        println!(
            "threads: {}; load average {} before, {} after (above the core count, other work shared the cores)",
            rayon::current_num_threads(),
            load(load_before),
            load(load_after)
        );
    });
    Ok(())
}
