//! `surfcap eval ...`: the numbers the issues ask for, reproducible by anyone.

use std::path::{Path, PathBuf};

use surfcap_eval::{
    GpdmEvalOptions, GraphComparisonOptions, InterpolationOptions, PoseMetricOptions, RootMotionOptions,
    TransitionCostsOptions, VariationEvalOptions, transfer_eval::TransferEvalOptions,
};
use surfcap_geometry::pose_interpolation::StretchInterpolation;
use surfcap_geometry::root_motion_from_contacts::ContactParams;

use crate::options::{CacheOpts, Positive, SourceOpts, TableOpts, open};
use crate::output::write_json;

mod appearance;
mod gpdm;
mod graphs;
mod interchange;
mod interpolation;
mod pose_metric;
mod root_motion;
mod smg;
mod sparse_graph;
mod transfer;
mod transitions;
mod vary;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Linear vs non-linear interpolation at lambda = 0.5 (thesis 2.4, Fig. 2.8): edge-length
    /// distortion and volume change, relative to the linear blend of the inputs' own measures.
    Interpolation {
        /// A subject cache, or any source `surfcap import` reads.
        subject: PathBuf,
        /// Pose pairs as FROM,TO (each sequence:frame or a global frame), repeatable.
        #[arg(long = "pair", required = true)]
        pairs: Vec<String>,
        /// Interpolation parameter.
        #[arg(long, default_value_t = 0.5, value_parser = crate::options::fraction)]
        lambda: f64,
        /// Stretch interpolation: linear (eq. 2.45) or log (eq. 2.46).
        #[arg(long, default_value = "linear")]
        stretch: StretchInterpolation,
        /// Also write interpolation.json and distortion.svg/png (both measures over lambda in
        /// 0, 0.1, ..., 1, linear dashed, non-linear solid) into this folder.
        #[arg(short, long)]
        output: Option<PathBuf>,
        #[command(flatten)]
        source: SourceOpts,
    },
    /// Standard transitions vs DTW vs DTW + variable segment lengths for several slopes (thesis
    /// 2.5.5, Fig. 2.15): mean and standard deviation of normalised costs, and plots of costs and
    /// durations over a sample of frame pairs.
    Transitions {
        /// A subject cache, or any source `surfcap import` reads.
        subject: PathBuf,
        /// Slope constraints to compare.
        #[arg(long, value_delimiter = ',', default_value = "2,3,4,5", value_parser = crate::options::count)]
        slopes: Vec<usize>,
        /// Fixed segment length of the standard and DTW-only transitions (default: one second).
        #[arg(long, value_parser = crate::options::count)]
        fixed: Option<usize>,
        /// Frame pairs in the plots.
        #[arg(long, default_value_t = 100, value_parser = crate::options::count)]
        plot_pairs: usize,
        /// Folder for the report and the plots.
        #[arg(short, long, default_value = "transitions-eval")]
        output: PathBuf,
        #[command(flatten)]
        cache: CacheOpts,
        #[command(flatten)]
        source: SourceOpts,
    },
    /// Essential graph vs motion graph for several alphas (thesis 3.3.3, Fig. 3.2 and 3.8):
    /// densities and the mean and standard deviation of all-pairs shortest-path costs, with plots.
    Graphs {
        /// A subject cache, or any source `surfcap import` reads.
        subject: PathBuf,
        /// Values of alpha.
        #[arg(long = "alpha", value_delimiter = ',', default_value = "0.01,0.02,0.03,0.05,0.1,0.2")]
        alphas: Vec<Positive>,
        /// Frame pairs in the shortest-path plots.
        #[arg(long, default_value_t = 200, value_parser = crate::options::count)]
        plot_pairs: usize,
        /// Folder for the report (graphs.json) and the plots.
        #[arg(short, long, default_value = "graphs-eval")]
        output: PathBuf,
        #[command(flatten)]
        table: TableOpts,
        #[command(flatten)]
        cache: CacheOpts,
        #[command(flatten)]
        source: SourceOpts,
    },
    /// A Gaussian-process dynamical model of the subject's motion (thesis 6.4-6.5): learning
    /// curve, latent trajectories with HMC variations, training-frame error vs PCA (Fig. 6.4).
    Gpdm {
        /// A subject cache, or any source `surfcap import` reads.
        subject: PathBuf,
        /// Sequences to learn (comma-separated; default: all, sharing one latent space, 6.5.2).
        #[arg(long, value_delimiter = ',')]
        sequences: Vec<String>,
        /// Vertices describing a frame (evenly spaced over the mesh).
        #[arg(long, default_value_t = 300, value_parser = crate::options::count)]
        vertices: usize,
        /// Frames at most (longer subjects are subsampled in time by one stride).
        #[arg(long, default_value_t = 400, value_parser = |s: &str| crate::options::at_least(s, 4))]
        max_frames: usize,
        /// Latent dimension d.
        #[arg(long, default_value_t = 3, value_parser = crate::options::count)]
        latent_dim: usize,
        /// HMC latent trajectories to sample (0: none).
        #[arg(long, default_value_t = 3)]
        samples: usize,
        /// L-BFGS iterations at most (default 400).
        #[arg(long, value_parser = crate::options::count)]
        iterations: Option<usize>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Folder for gpdm.json, the plots, latent.npy and the model.
        #[arg(short, long, default_value = "gpdm-eval")]
        output: PathBuf,
        #[command(flatten)]
        source: SourceOpts,
    },
    /// Our pose distance and the Euclidean one against the skeleton ground truth (thesis 2.3.2,
    /// Fig. 2.5-2.7): Pearson and distance correlation, Mantel test, Mantel correlogram plot.
    PoseMetric {
        /// A subject whose sequences carry ground-truth joint matrices.
        subject: PathBuf,
        /// Frames used (evenly spaced over the global index when the subject has more).
        #[arg(long, default_value_t = 200, value_parser = |s: &str| crate::options::at_least(s, 2))]
        max_frames: usize,
        /// Permutations of the Mantel test.
        #[arg(long, default_value_t = 10000, value_parser = crate::options::count)]
        permutations: usize,
        /// Distance classes of the correlogram.
        #[arg(long, default_value_t = 10, value_parser = crate::options::count)]
        classes: usize,
        /// Seed of the permutations.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Folder for the report (JSON) and the correlogram plot (SVG, PNG).
        #[arg(short, long, default_value = "pose-metric")]
        output: PathBuf,
        #[command(flatten)]
        cache: CacheOpts,
        #[command(flatten)]
        source: SourceOpts,
    },
    /// Root motion recovered from ground contacts against ground truth (issue 16): BVH clips
    /// with real root travel drive the mannequin, the horizontal travel is stripped (pelvis
    /// height and heading kept) and recovered; error of the trajectory, of the final position
    /// (% of the distance walked) and of the heading, per clip.
    RootMotion {
        /// BVH files with real root travel (CMU joint names), e.g. ../shared/data/cmu_bvh/16_*.bvh.
        #[arg(long, num_args = 1.., required = true)]
        bvh: Vec<PathBuf>,
        /// Target vertex count of the mannequin (1000 to 20000).
        #[arg(long, default_value_t = 2000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
        vertices: usize,
        /// Contact height, as a fraction of the subject's height above the ground.
        #[arg(long, default_value_t = ContactParams::default().height, value_parser = crate::options::positive)]
        contact_height: f64,
        /// Contact stillness, as a fraction of the subject's height per second: how closely the
        /// planted vertices move together.
        #[arg(long, default_value_t = ContactParams::default().speed, value_parser = crate::options::positive)]
        contact_speed: f64,
        /// Largest vertical speed of a contact vertex, as a fraction of the subject's height per
        /// second.
        #[arg(long, default_value_t = ContactParams::default().vertical_speed, value_parser = crate::options::positive)]
        contact_vertical_speed: f64,
        /// Folder for the report (root-motion.json).
        #[arg(short, long, default_value = "root-motion-eval")]
        output: PathBuf,
    },
    /// Motion transfer against ground truth (thesis 5.7, Fig. 5.8-5.10): learning curves of
    /// GP-NN, GP-SE and linear regression (random and key-seeded training subsets, with and
    /// without body parts) and motions absent from training, on the KayKit knight to the
    /// barbarian, mage and rogue and on two mannequins driven by the same CMU clips.
    Transfer {
        /// The shared data folder (KayKit characters and CMU clips).
        #[arg(long, default_value = "../shared/data")]
        data: PathBuf,
        /// Cases: barbarian, mage, rogue (the KayKit knight to each), mannequins (an average
        /// mannequin of 3,000 vertices to a heavy one of 5,000) and catlion (Sumner's 9 cat and
        /// lion poses, leave-one-out).
        #[arg(long, value_delimiter = ',', default_value = "barbarian,mage,rogue,mannequins,catlion")]
        cases: Vec<String>,
        /// Training-set sizes of the learning curves (pairs).
        #[arg(long, value_delimiter = ',', default_value = "10,25,50,100,200,350", value_parser = |s: &str| crate::options::at_least(s, 2))]
        sizes: Vec<usize>,
        /// PCA components per part.
        #[arg(long, default_value_t = 20, value_parser = |s: &str| crate::options::at_least(s, 1))]
        components: usize,
        /// Seed of the 70/30 split and the fits' restarts.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Evaluate on the whole body only (one part), instead of five proposed parts (plus the
        /// whole-body comparison curve).
        #[arg(long)]
        whole_body: bool,
        /// Overlap of the proposed parts, in edge rings.
        #[arg(long, default_value_t = 2, value_parser = |s: &str| crate::options::at_least(s, 1))]
        overlap_rings: usize,
        #[arg(short, long, default_value = "transfer-eval")]
        output: PathBuf,
    },
    /// Huang et al. 2009's Table 1 (issue 17): the surface motion graph of the CMU-driven
    /// mannequin (walk, jog, jump, stop; walk and jog loops), 800 targets (1-20 m x 1-40 s) per
    /// key-frame pair: distance and time errors, smoothness at the transitions, CPU time.
    Smg {
        /// The shared data folder (CMU clips).
        #[arg(long, default_value = "../shared/data")]
        data: PathBuf,
        /// Vertices of the mannequin (1000 to 20000).
        #[arg(long, default_value_t = 2000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
        vertices: usize,
        /// Re-mesh every frame on its own first (seeded), so no two frames share vertices or
        /// triangles: the input Huang et al.'s engine is made for.
        #[arg(long, value_name = "SEED")]
        remeshed: Option<u64>,
        /// Transitions per connection: 1 is the paper's; more adds the next best windows whose
        /// switches lie at least 15 frames apart (an extension).
        #[arg(long, default_value_t = 1, value_parser = |s: &str| crate::options::whole_in(s, 1, 20))]
        transitions: usize,
        /// Evaluate this subject or frame set instead of the CMU mannequin (with --connect and
        /// --pair).
        #[arg(long)]
        input: Option<PathBuf>,
        /// The higher-level graph of --input: FROM:TO sequence pairs.
        #[arg(long = "connect", value_delimiter = ',')]
        connect: Vec<String>,
        /// Key-frame pairs: FROM,TO as sequence:frame (repeatable); needed with --input, and on
        /// the mannequin they replace its four.
        #[arg(long = "pair")]
        pairs: Vec<String>,
        /// Target distances, subject units (Huang et al.: 1 to 20 m).
        #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20", value_parser = crate::options::non_negative)]
        distances: Vec<f64>,
        /// Target times, seconds (Huang et al.: 1 to 40 s); every distance with every time is a
        /// query.
        #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26,27,28,29,30,31,32,33,34,35,36,37,38,39,40", value_parser = crate::options::positive)]
        seconds: Vec<f64>,
        /// Skip the essential graph's run beside the surface motion graph (on by default when
        /// the frames share one topology).
        #[arg(long)]
        no_compare: bool,
        #[command(flatten)]
        source: SourceOpts,
        #[command(flatten)]
        cache: CacheOpts,
        /// Folder for the report (smg.json).
        #[arg(short, long, default_value = "smg-eval")]
        output: PathBuf,
    },
    /// The sparse essential graph against the exact one (issue 21 item 4) on the mannequin
    /// moved by every CMU clip (about 1,900 frames at 50 fps): per k, the all-pairs
    /// shortest-path costs within 1% of the exact ones, the mean cost ratio, pairs made
    /// unreachable, edges and build times; path-following and key-pose queries on both graphs;
    /// the smallest k meeting the rule (sparse-graph.json, plots).
    SparseGraph {
        /// The shared data folder (CMU clips).
        #[arg(long, default_value = "../shared/data")]
        data: PathBuf,
        /// Vertices of the mannequin (1000 to 20000).
        #[arg(long, default_value_t = 1000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
        vertices: usize,
        /// Frame rate the clips are resampled to (50: about 1,900 frames).
        #[arg(long, default_value_t = 50.0, value_parser = crate::options::positive)]
        fps: f64,
        /// Values of k (transitions kept per frame).
        #[arg(long = "k", value_delimiter = ',', default_value = "2,4,8,16,32,64", value_parser = crate::options::count)]
        ks: Vec<usize>,
        /// Tolerance alpha of the edge weights.
        #[arg(long, default_value = "0.05")]
        alpha: Positive,
        #[command(flatten)]
        table: TableOpts,
        #[command(flatten)]
        cache: CacheOpts,
        /// Folder for the report (sparse-graph.json) and the plots.
        #[arg(short, long, default_value = "sparse-graph-eval")]
        output: PathBuf,
    },
    /// Eigen appearance maps on generated textures with ground truth (thesis 4.5-4.6, Fig.
    /// 4.5-4.6, 4.9-4.12): flow end-point error, Poisson vs direct warping, compactness vs naive
    /// PCA in the texture and image domains, generalisation with held-out frames, completion of
    /// occlusion holes, an interpolation example; tables, plots and example images.
    Appearance {
        /// The shared data folder (its leeperrysmith_head: template.obj and Map-COL.jpg).
        #[arg(long, default_value = "../shared/data")]
        data: PathBuf,
        /// Use this folder of `surfcap appearance generate` instead of generating one.
        #[arg(long, conflicts_with_all = ["frames", "size"])]
        frames_dir: Option<PathBuf>,
        /// Frames to generate.
        #[arg(long, default_value_t = 100, value_parser = |s: &str| crate::options::at_least(s, 6))]
        frames: usize,
        /// Width of the generated textures in texels.
        #[arg(long, default_value_t = 256, value_parser = |s: &str| crate::options::whole_in(s, 16, 4096))]
        size: usize,
        /// Generate the frames without the moving light (constant shading): the flow then sees
        /// only the drift (with the light, TV-L1 follows the shading and the model suffers).
        #[arg(long, conflicts_with = "frames_dir")]
        no_lighting: bool,
        /// Seed of the generated frames and of the held-out split.
        #[arg(long, default_value_t = 7)]
        seed: u64,
        /// Total eigen maps K of the compactness sweep (those of at least the training frames are
        /// dropped; all the model has is always added).
        #[arg(long, value_delimiter = ',', default_value = "3,6,12,24,48", value_parser = crate::options::count)]
        components: Vec<usize>,
        /// Fractions of the frames held out of training (generalisation).
        #[arg(long, value_delimiter = ',', default_value = "0,0.2,0.4,0.6", value_parser = crate::options::fraction)]
        held_out: Vec<f64>,
        /// Frames rendered for the image domain (evenly spaced; per held-out fraction, the
        /// first held-out ones); 0: texture domain only.
        #[arg(long, default_value_t = 10)]
        image_frames: usize,
        /// Virtual cameras on a ring around the mesh.
        #[arg(long, default_value_t = 8, value_parser = crate::options::count)]
        views: usize,
        /// Width and height of the renders, pixels.
        #[arg(long, default_value_t = 256, value_parser = |s: &str| crate::options::whole_in(s, 16, 4096))]
        image_size: usize,
        /// Frames whose forward flow is also estimated at full resolution for the end-point error
        /// (with --flow-scale above 0).
        #[arg(long, default_value_t = 0)]
        full_resolution_flows: usize,
        #[command(flatten)]
        flow: crate::options::FlowArgs,
        #[command(flatten)]
        cache: CacheOpts,
        /// Folder for appearance.json, the plots and the example images (and the generated
        /// frames, in frames/).
        #[arg(short, long, default_value = "appearance-eval")]
        output: PathBuf,
    },
    /// Motion variation (thesis chapter 6, issue 19): one variation model per case (a GPDM per
    /// body part, the first two clips blended at w = 0.5 and learnt too): reconstruction error
    /// of training and held-out frames against PCA (Fig. 6.4), guided vs direct latent
    /// interpolation against the mesh blend at w = 0.25 (Fig. 6.7), and per captured sequence
    /// seeded variants checked against five criteria; exits 1 when one is missed.
    Vary {
        /// The shared data folder (CMU clips and the KayKit knight).
        #[arg(long, default_value = "../shared/data")]
        data: PathBuf,
        /// Only one case: cmu (the mannequin driven by CMU clips) or kaykit (the knight).
        #[arg(long)]
        only: Option<String>,
        /// CMU clips of the cmu case (in cmu_bvh; the first is the reference, the first two
        /// are blended).
        #[arg(long, value_delimiter = ',', default_value = "16_15,16_36,16_17,16_19,16_07")]
        cmu_clips: Vec<String>,
        /// KayKit knight clips of the kaykit case (the first is the reference, the first two
        /// are blended).
        #[arg(long, value_delimiter = ',', default_value = "Walking_A,Running_A,Walking_B,Walking_C,Running_B")]
        kaykit_clips: Vec<String>,
        /// Target vertex count of the mannequin (1000 to 20000).
        #[arg(long, default_value_t = 1500, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
        vertices: usize,
        /// Variants per captured sequence.
        #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::at_least(s, 2))]
        variants: usize,
        /// Seed of the variants.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// L-BFGS iterations at most of every GPDM (default 400).
        #[arg(long, value_parser = crate::options::count)]
        iterations: Option<usize>,
        /// Where the variants go in the world, the world criteria judged there: source (the
        /// source's path, `vary sample`'s default) or sampled (the torso GP's displacements,
        /// thesis 6.6.2).
        #[arg(long, default_value = "source")]
        path: crate::options::PathArg,
        /// Radius of the moving average over sampled latent trajectories (`vary sample
        /// --smoothing`).
        #[arg(long, default_value_t = 2)]
        smoothing: usize,
        /// Folder for vary.json and the plots.
        #[arg(short, long, default_value = "vary-eval")]
        output: PathBuf,
    },
    /// Round trips through Alembic and USD (issue 22): every sequence of the data folder
    /// imported, exported as .abc and .usda, imported back and compared (positions to the bit,
    /// topology and UVs, names, labels, rate, up axis, units), with sizes and times.
    Interchange {
        /// The data folder (datasets as sub-folders).
        #[arg(long, default_value = "../shared/data")]
        data: PathBuf,
        /// Only these datasets (folder names, comma-separated; default: all).
        #[arg(long, value_delimiter = ',')]
        datasets: Vec<String>,
        /// Formats to go through.
        #[arg(long, value_delimiter = ',', default_value = "abc,usda")]
        formats: Vec<surfcap_formats::export::ExportFormat>,
        /// Folder for the report (interchange.json); the exported files go to a temporary
        /// folder and are removed once read back.
        #[arg(short, long, default_value = "interchange-eval")]
        output: PathBuf,
    },
}

/// Refuses an output that overlaps the subject, then makes it an evaluation folder of `kind`.
fn claim(ctx: &crate::Ctx, output: &Path, subject: &Path, kind: &str) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(output, &[subject])?;
    ctx.claim_dir(output, kind)?;
    Ok(())
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    match &a.what {
        What::Interpolation { subject, output: Some(o), .. } => claim(ctx, o, subject, "eval-interpolation")?,
        What::Interpolation { output: None, .. } => {}
        What::Transitions { subject, output, .. } => claim(ctx, output, subject, "eval-transitions")?,
        What::Graphs { subject, output, .. } => claim(ctx, output, subject, "eval-graphs")?,
        What::Gpdm { subject, output, .. } => claim(ctx, output, subject, "eval-gpdm")?,
        What::PoseMetric { subject, output, .. } => claim(ctx, output, subject, "eval-pose-metric")?,
        What::RootMotion { bvh, output, .. } => {
            let inputs: Vec<&Path> = bvh.iter().map(PathBuf::as_path).collect();
            surfcap_mesh::output_path::check_not_input(output, &inputs)?;
            ctx.claim_dir(output, "eval-root-motion")?;
        }
        What::Transfer { data, output, .. } => {
            surfcap_mesh::output_path::check_not_input(output, &[data])?;
            ctx.claim_dir(output, "eval-transfer")?;
        }
        What::Smg { data, input, output, .. } => {
            let mut inputs: Vec<&Path> = vec![data];
            inputs.extend(input.as_deref());
            surfcap_mesh::output_path::check_not_input(output, &inputs)?;
            ctx.claim_dir(output, "eval-smg")?;
        }
        What::Interchange { data, output, .. } => {
            surfcap_mesh::output_path::check_not_input(output, &[data])?;
            ctx.claim_dir(output, "eval-interchange")?;
        }
        What::SparseGraph { data, output, .. } => {
            surfcap_mesh::output_path::check_not_input(output, &[data])?;
            ctx.claim_dir(output, "eval-sparse-graph")?;
        }
        What::Vary { data, output, .. } => {
            surfcap_mesh::output_path::check_not_input(output, &[data])?;
            ctx.claim_dir(output, "eval-vary")?;
        }
        What::Appearance { data, frames_dir, output, .. } => {
            let mut inputs: Vec<&Path> = vec![data];
            inputs.extend(frames_dir.as_deref());
            surfcap_mesh::output_path::check_not_input(output, &inputs)?;
            ctx.claim_dir(output, "eval-appearance")?;
        }
    }
    match a.what {
        What::Interpolation { subject, pairs, lambda, stretch, output, source } => {
            let opts = InterpolationOptions { pairs, lambda, stretch, sweeps: output.is_some() };
            interpolation::run(ctx, &open(ctx, &subject, &source)?, &opts, output.as_deref())
        }
        What::Transitions { subject, slopes, fixed, plot_pairs, output, cache, source } => {
            let opts = TransitionCostsOptions { slopes, fixed, plot_pairs };
            transitions::run(ctx, cache.pipeline(ctx, open(ctx, &subject, &source)?), &opts, &output)
        }
        What::Graphs { subject, alphas, plot_pairs, output, table, cache, source } => {
            anyhow::ensure!(!alphas.is_empty(), "--alpha: expected at least one value");
            let s = open(ctx, &subject, &source)?;
            let alphas = alphas.iter().map(|a| a.0).collect();
            let opts = GraphComparisonOptions { alphas, plot_pairs, table: table.params(s.fps)? };
            graphs::run(ctx, cache.pipeline(ctx, s), &opts, &output)
        }
        What::Gpdm {
            subject,
            sequences,
            vertices,
            max_frames,
            latent_dim,
            samples,
            iterations,
            seed,
            output,
            source,
        } => {
            let opts = GpdmEvalOptions { sequences, vertices, max_frames, latent_dim, samples, seed, iterations };
            gpdm::run(ctx, &open(ctx, &subject, &source)?, &opts, &output)
        }
        What::PoseMetric { subject, max_frames, permutations, classes, seed, output, cache, source } => {
            let opts = PoseMetricOptions { max_frames, permutations, classes, seed };
            pose_metric::run(ctx, &open(ctx, &subject, &source)?, &cache, &opts, &output)
        }
        What::RootMotion { bvh, vertices, contact_height, contact_speed, contact_vertical_speed, output } => {
            let opts = RootMotionOptions {
                bvh,
                vertices,
                contacts: ContactParams {
                    height: contact_height,
                    speed: contact_speed,
                    vertical_speed: contact_vertical_speed,
                },
            };
            root_motion::run(ctx, &opts, &output)
        }
        What::Smg {
            data,
            vertices,
            remeshed,
            transitions,
            input,
            connect,
            pairs,
            distances,
            seconds,
            no_compare,
            source,
            cache,
            output,
        } => {
            let (input, pairs) = match input {
                Some(i) => (Some(smg::Input { path: i, connect, pairs, source }), Vec::new()),
                None => (None, pairs),
            };
            let opts =
                smg::Options { vertices, remeshed, transitions, distances, seconds, pairs, compare: !no_compare };
            smg::run(ctx, &data, opts, input, &cache, &output)
        }
        What::Appearance {
            data,
            frames_dir,
            frames,
            size,
            no_lighting,
            seed,
            components,
            held_out,
            image_frames,
            views,
            image_size,
            full_resolution_flows,
            flow,
            cache,
            output,
        } => {
            let source = match frames_dir {
                Some(d) => appearance::Frames::Existing(d),
                None => appearance::Frames::Generate { data, frames, size, seed, lighting: !no_lighting },
            };
            let opts = surfcap_eval::AppearanceEvalOptions {
                components,
                held_out,
                seed,
                image_frames,
                views,
                image_size,
                ..Default::default()
            };
            appearance::run(ctx, source, &opts, &flow, full_resolution_flows, &cache, &output)
        }
        What::Vary {
            data,
            only,
            cmu_clips,
            kaykit_clips,
            vertices,
            variants,
            seed,
            iterations,
            path,
            smoothing,
            output,
        } => {
            use surfcap_eval::variation_eval::{cmu_case, kaykit_case};
            let (cmu, kaykit) = match only.as_deref() {
                None => (true, true),
                Some("cmu") => (true, false),
                Some("kaykit") => (false, true),
                Some(other) => anyhow::bail!("--only {other}: expected cmu or kaykit"),
            };
            let mut cases = Vec::new();
            if cmu {
                cases.push(cmu_case(&data, vertices, &cmu_clips)?);
            }
            if kaykit {
                cases.push(kaykit_case(&data, &kaykit_clips)?);
            }
            let mut opts = VariationEvalOptions { variants, seed, iterations, ..Default::default() };
            opts.sampling.path = path.0;
            opts.sampling.smoothing = smoothing;
            vary::run(ctx, cases, &opts, &output)
        }
        What::SparseGraph { data, vertices, fps, ks, alpha, table, cache, output } => {
            let opts = sparse_graph::Options { vertices, fps, ks, alpha: alpha.0, table };
            sparse_graph::run(ctx, &data, opts, &cache, &output)
        }
        What::Interchange { data, datasets, formats, output } => {
            interchange::run(ctx, data, datasets, formats, &output)
        }
        What::Transfer { data, cases, sizes, components, seed, whole_body, overlap_rings, output } => {
            use surfcap_eval::transfer_eval::{CaseParts, kaykit_case, mannequin_case};
            let parts = if whole_body { CaseParts::WholeBody } else { CaseParts::Proposed { overlap_rings } };
            use surfcap_builtin::mannequin::BodyShape;
            let opts = TransferEvalOptions { sizes, seed, components, ..TransferEvalOptions::default() };
            let mut built = Vec::new();
            let mut catlion = None;
            for c in &cases {
                if c == "catlion" {
                    catlion = Some(surfcap_eval::transfer_eval::catlion_subjects(&data)?);
                    continue;
                }
                built.push(match c.as_str() {
                    "barbarian" | "mage" | "rogue" => kaykit_case(&data, c, parts)?,
                    "mannequins" => mannequin_case(
                        &data,
                        ("mannequin-average-3k", &BodyShape::average(), 3000),
                        ("mannequin-heavy-5k", &BodyShape::heavy(), 5000),
                        parts,
                    )?,
                    other => anyhow::bail!("--cases {other}: expected barbarian, mage, rogue, mannequins or catlion"),
                });
            }
            transfer::run(ctx, built, catlion, &opts, &output)
        }
    }
}

/// Writes an evaluation's report to `dir/name`: `result` as JSON with the files the command
/// wrote beside it added under `files_key`. Returns the report and its path.
fn save_report<T: serde::Serialize>(
    dir: &Path,
    name: &str,
    result: &T,
    files_key: &str,
    files: &[PathBuf],
) -> anyhow::Result<(serde_json::Value, PathBuf)> {
    let mut report = serde_json::to_value(result)?;
    report[files_key] = serde_json::to_value(files)?;
    let path = dir.join(name);
    write_json(&path, &report)?;
    Ok((report, path))
}

/// `wrote <report>, <plot>, <plot>...`
fn print_wrote(report: &Path, plots: &[PathBuf]) {
    let files: Vec<String> =
        std::iter::once(report).chain(plots.iter().map(PathBuf::as_path)).map(|p| p.display().to_string()).collect();
    println!("wrote {}", files.join(", "));
}
