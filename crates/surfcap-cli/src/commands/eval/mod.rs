//! `surfcap eval ...`: the evaluations that produce the numbers of the thesis's tables and
//! figures (and of the papers surfcap compares with), reproducible by anyone. One file per
//! evaluation, each its arguments and its `run`; this file only lists them.

mod appearance;
mod folder;
mod gpdm;
mod graphs;
mod interchange;
mod interpolation;
mod play;
mod pose_metric;
mod root_motion;
mod smg;
mod sparse_graph;
mod stream;
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
    Interpolation(interpolation::Args),
    /// Standard transitions vs DTW vs DTW + variable segment lengths for several slopes (thesis
    /// 2.5.5, Fig. 2.15): mean and standard deviation of normalised costs, and plots of costs and
    /// durations over a sample of frame pairs.
    Transitions(transitions::Args),
    /// Essential graph vs motion graph for several alphas (thesis 3.3.3, Fig. 3.2 and 3.8):
    /// densities and the mean and standard deviation of all-pairs shortest-path costs, with plots.
    Graphs(graphs::Args),
    /// A Gaussian-process dynamical model of the subject's motion (thesis 6.4-6.5): learning
    /// curve, latent trajectories with HMC variations, training-frame error vs PCA (Fig. 6.4).
    Gpdm(gpdm::Args),
    /// Our pose distance and the Euclidean one against the skeleton ground truth (thesis 2.3.2,
    /// Fig. 2.5-2.7): Pearson and distance correlation, Mantel test, Mantel correlogram plot.
    PoseMetric(pose_metric::Args),
    /// Root motion recovered from ground contacts against ground truth: BVH clips
    /// with real root travel drive the mannequin, the horizontal travel is stripped (pelvis
    /// height and heading kept) and recovered; error of the trajectory, of the final position
    /// (% of the distance walked) and of the heading, per clip.
    RootMotion(root_motion::Args),
    /// Motion transfer against ground truth (thesis 5.7, Fig. 5.8-5.10): learning curves of
    /// GP-NN, GP-SE and linear regression (random and key-seeded training subsets, with and
    /// without body parts) and motions absent from training, on the KayKit knight to the
    /// barbarian, mage and rogue and on two mannequins driven by the same CMU clips.
    Transfer(transfer::Args),
    /// Huang et al. 2009's Table 1: the surface motion graph and the essential graph side by
    /// side on the mannequin driven by CMU stand, walk, jog and hit loops, 800 targets (1-20 m x
    /// 1-40 s) per key-frame pair: targets met or unreachable (and why), distance and time
    /// errors, smoothness at the transitions, CPU time.
    Smg(smg::Args),
    /// The sparse essential graph against the exact one on the mannequin
    /// moved by every CMU clip (about 1,900 frames at 50 fps): per k, the all-pairs
    /// shortest-path costs within 1% of the exact ones, the mean cost ratio, pairs made
    /// unreachable, edges and build times; path-following and key-pose queries on both graphs;
    /// the smallest k meeting the rule (sparse-graph.json, plots).
    SparseGraph(sparse_graph::Args),
    /// Eigen appearance maps on generated textures with ground truth (thesis 4.5-4.6, Fig.
    /// 4.5-4.6, 4.9-4.12): flow end-point error, Poisson vs direct warping, compactness vs naive
    /// PCA in the texture and image domains, generalisation with held-out frames, completion of
    /// occlusion holes, an interpolation example; tables, plots and example images.
    Appearance(appearance::Args),
    /// Motion variation (thesis chapter 6): one variation model per case (a GPDM per
    /// body part, the first two clips blended at w = 0.5 and learnt too): reconstruction error
    /// of training and held-out frames against PCA (Fig. 6.4), guided vs direct latent
    /// interpolation against the mesh blend at w = 0.25 (Fig. 6.7), and per captured sequence
    /// seeded variants checked against five criteria; exits 1 when one is missed.
    Vary(vary::Args),
    /// Round trips through Alembic and USD: every sequence of the data folder
    /// imported, exported as .abc and .usda, imported back and compared (positions to the bit,
    /// topology and UVs, names, labels, rate, up axis, units), with sizes and times.
    Interchange(interchange::Args),
    /// The compact stream of a subject (quantised, predicted, deflated): bytes per frame, Mbps
    /// at 30 fps, error against the source in its unit and % of height, against glb morph
    /// targets.
    Stream(stream::Args),
    /// The interactive controller on scripted inputs (straight run, turn left, stop and idle,
    /// zig-zag, circle) on the CMU-driven mannequin, the KayKit knight with root motion from
    /// contacts and a Vlasic capture: heading and speed errors, response latency, foot sliding,
    /// transitions, against offline path following on the same trajectories.
    Play(play::Args),
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    match a.what {
        What::Interpolation(a) => interpolation::run(ctx, a),
        What::Transitions(a) => transitions::run(ctx, a),
        What::Graphs(a) => graphs::run(ctx, a),
        What::Gpdm(a) => gpdm::run(ctx, a),
        What::PoseMetric(a) => pose_metric::run(ctx, a),
        What::RootMotion(a) => root_motion::run(ctx, a),
        What::Transfer(a) => transfer::run(ctx, a),
        What::Smg(a) => smg::run(ctx, a),
        What::SparseGraph(a) => sparse_graph::run(ctx, a),
        What::Appearance(a) => appearance::run(ctx, a),
        What::Vary(a) => vary::run(ctx, a),
        What::Interchange(a) => interchange::run(ctx, a),
        What::Stream(a) => stream::run(ctx, a),
        What::Play(a) => play::run(ctx, a),
    }
}
