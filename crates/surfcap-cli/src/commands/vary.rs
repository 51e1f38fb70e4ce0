//! `surfcap vary train | sample`: motion variation synthesis (thesis chapter 6;
//! `surfcap-variation`). `train` learns one GPDM per body part over a few sequences of one
//! motion type of a subject (6.4-6.5, optionally with non-linear blends of pairs, 6.7) and
//! writes the model folder; `sample` draws variants of a learnt sequence or of a blend at any
//! weight (6.6-6.7) by Hybrid Monte Carlo, one glb per variant, with a report measuring each
//! against the learnt motion it varies.

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use surfcap_synthesis::variant_samples::{SampleRequest, Varied, sample_variants_to_folder};
use surfcap_synthesis::variation_training::{
    MODEL_KIND, TrainReport, TrainRequest, check_train_request, learnt_names, train_plan, train_variation_model,
};
use surfcap_variation::motion_preparation::SequenceOrigin;
use surfcap_variation::variation_sampling::{ChainStart, SamplingOptions};

use crate::body_parts::parts_of;
use crate::options::{SourceOpts, open, whole_in};
use crate::output::count_of;

#[derive(clap::Subcommand, Debug)]
pub enum Cmd {
    /// Learn a variation model from sequences of one motion type of a subject (thesis 6.4-6.5:
    /// one GPDM per body part, the sequences sharing one latent space), saved as a folder.
    Train(TrainArgs),
    /// Sample variants of a learnt sequence (thesis 6.6) or of a blend of two at any weight
    /// (6.7): one glb per variant and `report.json` in the output folder.
    Sample(SampleArgs),
}

#[derive(clap::Args, Debug)]
pub struct TrainArgs {
    /// The subject (a subject cache or any source `surfcap import` reads).
    pub subject: PathBuf,
    /// The sequences to learn, comma-separated (one motion type: walks and turns, or jumps;
    /// default: every sequence of the subject).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    /// The sequence every other is re-timed onto (thesis 6.5.2; default: the first of
    /// --sequences). Its frame count is every learnt trajectory's.
    #[arg(long)]
    pub reference: Option<String>,
    /// Body parts (a parts file, see README "Body parts"); default: five parts proposed from the
    /// subject, as `surfcap parts propose` does (thesis 6.4.2: P = 5).
    #[arg(long)]
    pub parts: Option<PathBuf>,
    /// Pairs of --sequences blended non-linearly and added to training (thesis 6.7), `A:B`,
    /// comma-separated or repeated: `vary sample --blend A:B:W` then interpolates between
    /// learnt trajectories W apart.
    #[arg(long, value_delimiter = ',')]
    pub blend: Vec<BlendPair>,
    /// Weights of the blends of every --blend pair, comma-separated, each strictly between 0
    /// and 1 (thesis 6.7: W = {0.5}).
    #[arg(long, value_delimiter = ',', default_value = "0.5", value_parser = inner_weight, requires = "blend")]
    pub blend_weights: Vec<f64>,
    /// Latent dimension of every part's GPDM (thesis: 3).
    #[arg(long, default_value_t = 3, value_parser = |s: &str| whole_in(s, 1, 10))]
    pub latent_dim: usize,
    /// Most L-BFGS iterations of every part's GPDM fit, 1 to 10000. The fits converge in a few
    /// hundred (the default 400 follows thesis 6.5); 10000 bounds the time while leaving 25
    /// times the default.
    #[arg(long, default_value_t = 400, value_parser = |s: &str| whole_in(s, 1, 10_000))]
    pub iterations: usize,
    /// The model folder to write.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub source_opts: SourceOpts,
}

#[derive(clap::Args, Debug)]
pub struct SampleArgs {
    /// A model folder written by `surfcap vary train`.
    pub model: PathBuf,
    /// The learnt sequence to vary.
    #[arg(long, required_unless_present = "blend", conflicts_with = "blend")]
    pub sequence: Option<String>,
    /// Variants of the blend of two learnt sequences at a weight in [0, 1], `A:B:W` (thesis
    /// 6.7: variants of the two nearest learnt trajectories interpolated in the latent space).
    #[arg(long)]
    pub blend: Option<BlendAt>,
    /// Variants to sample.
    #[arg(long, default_value_t = 5, value_parser = |s: &str| whole_in(s, 1, 1000))]
    pub count: usize,
    /// Seed of the HMC chains (the same seed gives the same files, whatever the thread count).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Where each part's chain starts: learnt (the learnt trajectory; surfcap's default) or mean
    /// (the dynamics' mean prediction from its first point, thesis 6.6.1).
    #[arg(long, default_value = "learnt")]
    pub start: StartArg,
    /// Where the variants go in the world: source (each pose placed where the source's frame
    /// is: the body varies, the path is the captured one; surfcap's default, the sampled
    /// displacements made the feet slide) or sampled (the torso GP's displacements integrated,
    /// thesis 6.6.2).
    #[arg(long, default_value = "source")]
    pub path: crate::options::PathArg,
    /// Radius in frames of the moving average over each sampled latent trajectory (0: none;
    /// the one-step HMC samples jitter from frame to frame).
    #[arg(long, default_value_t = 2, value_parser = |s: &str| whole_in(s, 0, 1000))]
    pub smoothing: usize,
    /// Radius in frames of the moving average over each variant's deviation from the learnt
    /// motion (body frame, per vertex; 0: none). The reconstruction GP's poses jitter off the
    /// learnt trajectories even when the latent ones are smooth, and planted feet then slide;
    /// averaging the deviation keeps the learnt motion's own timing.
    #[arg(long, default_value_t = 4, value_parser = |s: &str| whole_in(s, 0, 1000))]
    pub deviation_smoothing: usize,
    /// HMC warm-up iterations (step size and path length tuning). The chain moves away from
    /// the learnt motion while it tunes: more iterations, variants further from their source.
    #[arg(long, default_value_t = 20, value_parser = |s: &str| whole_in(s, 1, 100_000))]
    pub warmup: usize,
    /// HMC iterations between two variants (more: less correlated variants, and later ones
    /// further from their source).
    #[arg(long, default_value_t = 2, value_parser = |s: &str| whole_in(s, 1, 10_000))]
    pub thin: usize,
    /// Most leapfrog steps per HMC iteration. The work of a part's chain, (--warmup + --count x
    /// --thin) x --max-leapfrog leapfrog steps, may be at most 2,000,000 (over 2,000 times
    /// the defaults' 900): larger requests are refused before any work.
    #[arg(long, default_value_t = 30, value_parser = |s: &str| whole_in(s, 1, 10_000))]
    pub max_leapfrog: usize,
    /// Leave the planted feet as sampled: no foot-skate clean-up (by default the planted
    /// vertices found by the shared contact detection are pinned at their position mid-contact
    /// and the legs deformed to meet them, blended in and out around each contact).
    #[arg(long)]
    pub no_foot_skate_cleanup: bool,
    /// Keep the hips where they are in the foot-skate clean-up, the legs alone reaching the
    /// pins (by default the whole body moves along the ground with the planted feet, Kovar et
    /// al. 2002's root adjustment, so a planted foot is reached without stretching its leg).
    #[arg(long, conflicts_with = "no_foot_skate_cleanup")]
    pub hold_hips: bool,
    /// Use the stitched reconstruction-GP means as they are: by default every triangle of a
    /// sampled pose keeps its rotation and takes the learnt motion's stretch at the same frame
    /// (one Poisson solve per frame), as linear blends of training poses shrink the surface.
    #[arg(long)]
    pub no_learnt_stretch: bool,
    /// In the foot-skate clean-up, pin each step where the foot comes down and let the body
    /// go on with its planted feet (the legs keep their lengths; the body then leaves the
    /// source's path, by 2.1-2.4 m over the 4.5 m CMU walks of `surfcap eval vary`). By default
    /// each step is pinned where the foot is mid-contact, on the source's path.
    #[arg(long, conflicts_with_all = ["no_foot_skate_cleanup", "hold_hips"])]
    pub carry_pins: bool,
    /// The output folder: `<name>-variant-<k>.glb` per variant and `report.json`.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Value parser: a blend weight strictly between 0 and 1 (0 and 1 are the sequences).
fn inner_weight(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(w) if w > 0.0 && w < 1.0 => Ok(w),
        _ => Err("expected a number strictly between 0 and 1 (0 and 1 are the two sequences themselves)".into()),
    }
}

/// `A:B`: two sequences to blend.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BlendPair {
    pub a: String,
    pub b: String,
}

impl FromStr for BlendPair {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.split_once(':') {
            Some((a, b)) if !a.is_empty() && !b.is_empty() && !b.contains(':') => {
                Ok(BlendPair { a: a.into(), b: b.into() })
            }
            _ => Err(format!("{s:?}: expected A:B, two sequence names")),
        }
    }
}

/// `A:B:W`: the blend of two learnt sequences at weight W in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub struct BlendAt {
    pub a: String,
    pub b: String,
    pub w: f64,
}

impl FromStr for BlendAt {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("{s:?}: expected A:B:W, two learnt sequences and a weight in [0, 1]");
        let (pair, w) = s.rsplit_once(':').ok_or_else(bad)?;
        let pair: BlendPair = pair.parse().map_err(|_| bad())?;
        let w = crate::options::fraction(w).map_err(|e| format!("{s:?}: the weight {w:?}: {e}"))?;
        Ok(BlendAt { a: pair.a, b: pair.b, w })
    }
}

/// See [`SampleArgs::start`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StartArg(pub ChainStart);

impl FromStr for StartArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ChainStart::parse(s).map(StartArg).ok_or_else(|| format!("{s:?}: expected learnt or mean"))
    }
}

pub fn run(ctx: &crate::Ctx, cmd: Cmd) -> anyhow::Result<()> {
    match cmd {
        Cmd::Train(a) => train(ctx, a),
        Cmd::Sample(a) => sample(ctx, a),
    }
}

fn train(ctx: &crate::Ctx, a: TrainArgs) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = vec![&a.subject];
    inputs.extend(a.parts.as_deref());
    // The model folder is built in its temporary and put in place, marker included, only when
    // the training succeeded: a failed run leaves the folder as it was.
    let (outs, _) = ctx.claim_dir(&a.output, MODEL_KIND, &inputs)?;
    let t0 = Instant::now();
    let subject = open(ctx, &a.subject, &a.source_opts)?;
    let request = TrainRequest {
        subject_path: a.subject.clone(),
        sequences: a.sequences.clone(),
        reference: a.reference.clone(),
        blends: a.blend.iter().map(|p| (p.a.clone(), p.b.clone())).collect(),
        blend_weights: a.blend_weights.clone(),
        latent_dim: a.latent_dim,
        iterations: a.iterations,
        output: a.output.clone(),
        force: ctx.force,
    };
    check_train_request(&request)?;
    let bar = crate::progress::Bar::new(ctx);
    let names = learnt_names(&subject, &request, &bar);
    let (chosen, options) = train_plan(&subject, &request, &names)?;
    let parts = parts_of(ctx, a.parts.as_deref(), false, &subject, "", "--parts")?;
    ctx.say(&format!(
        "learning {} of {} (+ {}), {} parts, d = {}, reference {}",
        count_of(names.len(), "sequence"),
        subject.name,
        count_of(if a.blend.is_empty() { 0 } else { a.blend.len() * a.blend_weights.len() }, "blend"),
        parts.len(),
        a.latent_dim,
        names[options.preparation.reference]
    ));
    let report = train_variation_model(&subject, &request, &chosen, &parts, &options, t0, &bar)?;
    drop(bar);
    ctx.commit(outs)?;
    ctx.result(&report, || print_trained(&report));
    Ok(())
}

/// The human summary of a training.
fn print_trained(r: &TrainReport) {
    println!(
        "{}: {} of {} reference frames ({}), {} parts, d = {}: learnt in {:.1} s -> {}",
        r.subject,
        count_of(r.sequences.len(), "sequence"),
        r.frames,
        r.reference,
        r.parts.len(),
        r.latent_dim,
        r.train_seconds,
        r.model.as_deref().unwrap_or(Path::new("memory")).display()
    );
    for s in &r.sequences {
        let origin = match &s.origin {
            SequenceOrigin::Blend { a, b, w } => format!("blend of {a} and {b} at {w}"),
            SequenceOrigin::Captured { .. } => "captured".into(),
        };
        println!("  sequence {:<24} {:>5} frames  {origin}", s.name, s.frames);
    }
    println!(
        "  {:<12} {:>8} {:>6} {:>11} {:>14} {:>14}  {:<27} {:<35} {:>7}",
        "part",
        "vertices",
        "dims",
        "iterations",
        "objective",
        "(start)",
        "alpha (eq. 6.4)",
        "beta (eq. 6.6)",
        "seconds"
    );
    let list = |v: &[f64]| v.iter().map(|x| format!("{x:.2e}")).collect::<Vec<_>>().join(" ");
    for p in &r.parts {
        println!(
            "  {:<12} {:>8} {:>6} {:>5}{} {:>14.1} {:>14.1}  {:<27} {:<35} {:>7.1}",
            p.part,
            p.vertices,
            p.dimensions,
            p.iterations,
            if p.converged { " conv." } else { "      " },
            p.objective,
            p.objective_start,
            list(&p.alpha),
            list(&p.beta),
            p.seconds
        );
    }
}

fn sample(ctx: &crate::Ctx, a: SampleArgs) -> anyhow::Result<()> {
    let varied = match (&a.sequence, &a.blend) {
        (Some(name), _) => Varied::Sequence(name.clone()),
        (None, Some(b)) => Varied::Blend { a: b.a.clone(), b: b.b.clone(), w: b.w },
        (None, None) => anyhow::bail!("expected --sequence NAME or --blend A:B:W"),
    };
    let request = SampleRequest {
        model: a.model.clone(),
        varied,
        count: a.count,
        seed: a.seed,
        options: SamplingOptions {
            start: a.start.0,
            path: a.path.0,
            smoothing: a.smoothing,
            deviation_smoothing: a.deviation_smoothing,
            warmup: a.warmup,
            thin: a.thin,
            max_leapfrog: a.max_leapfrog,
            foot_skate_cleanup: !a.no_foot_skate_cleanup,
            move_root: !a.hold_hips && !a.no_foot_skate_cleanup,
            learnt_stretch: !a.no_learnt_stretch,
            carry_pins: a.carry_pins,
        },
        output: a.output.clone(),
        force: ctx.force,
    };
    let bar = crate::progress::Bar::new(ctx);
    let o = sample_variants_to_folder(&request, &bar)?;
    drop(bar);
    let r = &o.report;
    ctx.result(r, || {
        println!(
            "{} of {} sampled in {:.1} s (seed {}) -> {}",
            count_of(a.count, "variant"),
            o.name,
            r.sample_seconds,
            a.seed,
            a.output.display()
        );
        let unit = &o.unit;
        for v in &r.variants {
            println!(
                "  {:<28} {:>4} frames: {:.4} {unit} per vertex from the learnt motion (body frame), ends {:.3} {unit} from its end",
                v.sequence, v.frames, v.body_frame_distance, v.end_distance
            );
            if let Some(c) = &v.cleanup {
                println!(
                    "    foot skate: sliding {:.3} -> {:.3} {unit}/s, {} contacts pinned, pinned vertices {:.4} -> {:.4} {unit} from their pins (largest correction {:.3} {unit}: body moved up to {:.3} {unit}, legs and feet against it up to {:.3} {unit})",
                    c.sliding_before,
                    c.sliding_after,
                    c.plants,
                    c.pinned_drift_before,
                    c.pinned_drift_after,
                    c.largest_correction,
                    c.largest_body_shift,
                    c.largest_leg_correction
                );
            }
        }
        for c in &r.chains {
            println!(
                "  chain {:<12} acceptance {:.2}, step {:.2e}, {} leapfrog steps, {} divergences, {:.1} s",
                c.part, c.acceptance_rate, c.step_size, c.leapfrog_steps, c.divergences, c.seconds
            );
        }
        if let Some(view) = &r.view {
            println!("view them next to the source: {view}");
        }
    });
    Ok(())
}
