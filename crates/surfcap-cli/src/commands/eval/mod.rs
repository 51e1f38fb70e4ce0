//! `surfcap eval ...`: the numbers the issues ask for, reproducible by anyone.

use std::path::PathBuf;

use anyhow::Context;
use serde_json::json;
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_geometry::shape_distortion::{edge_length_distortion, volume_change};

use crate::options::{CacheOpts, SourceOpts, TableOpts, open};
use crate::output::print_json;

mod gpdm;
mod graphs;
mod pose_metric;
mod transitions;

/// Options of `eval pose-metric`.
pub struct PoseMetricOpts {
    pub max_frames: usize,
    pub permutations: usize,
    pub classes: usize,
    pub seed: u64,
    pub output: PathBuf,
    pub cache: CacheOpts,
}

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
        #[arg(long, default_value_t = 0.5)]
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
        #[arg(long, value_delimiter = ',', default_value = "2,3,4,5")]
        slopes: Vec<usize>,
        /// Fixed segment length of the standard and DTW-only transitions (default: one second).
        #[arg(long)]
        fixed: Option<usize>,
        /// Frame pairs in the plots.
        #[arg(long, default_value_t = 100)]
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
        alphas: Vec<f64>,
        /// Frame pairs in the shortest-path plots.
        #[arg(long, default_value_t = 200)]
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
        #[arg(long, default_value_t = 300)]
        vertices: usize,
        /// Frames at most (longer subjects are subsampled in time by one stride).
        #[arg(long, default_value_t = 400)]
        max_frames: usize,
        /// Latent dimension d.
        #[arg(long, default_value_t = 3)]
        latent_dim: usize,
        /// HMC latent trajectories to sample (0: none).
        #[arg(long, default_value_t = 3)]
        samples: usize,
        /// L-BFGS iterations at most (default 400).
        #[arg(long)]
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
        #[arg(long, default_value_t = 200)]
        max_frames: usize,
        /// Permutations of the Mantel test.
        #[arg(long, default_value_t = 10000)]
        permutations: usize,
        /// Distance classes of the correlogram.
        #[arg(long, default_value_t = 10)]
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
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (subject, pairs, lambda, stretch, output, source) = match a.what {
        What::Interpolation { subject, pairs, lambda, stretch, output, source } => {
            (subject, pairs, lambda, stretch, output, source)
        }
        What::Transitions { subject, slopes, fixed, plot_pairs, output, cache, source } => {
            let opts = transitions::Opts { slopes, fixed, plot_pairs, output, cache };
            return transitions::run(ctx, &subject, &source, &opts);
        }
        What::Graphs { subject, alphas, plot_pairs, output, table, cache, source } => {
            let opts = graphs::EvalOpts { alphas, plot_pairs, output, table, cache };
            return graphs::eval(ctx, &subject, &source, &opts);
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
            let opts = gpdm::Opts { sequences, vertices, max_frames, latent_dim, samples, seed, iterations, output };
            return gpdm::run(ctx, &subject, &source, &opts);
        }
        What::PoseMetric { subject, max_frames, permutations, classes, seed, output, cache, source } => {
            let opts = PoseMetricOpts { max_frames, permutations, classes, seed, output, cache };
            return pose_metric::run(ctx, &subject, &source, &opts);
        }
    };
    let s = open(ctx, &subject, &source)?;
    let topo = s.topology();
    let mut rows = Vec::new();
    // Per pair: (lambda, linear edge distortion, non-linear edge distortion, linear volume
    // change, non-linear volume change) over lambda = 0, 0.1, ..., 1, when plots are asked for.
    let mut sweeps: Vec<(String, Vec<[f64; 5]>)> = Vec::new();
    for pair in &pairs {
        let (from, to) = pair.split_once(',').ok_or_else(|| anyhow::anyhow!("--pair {pair:?}: expected FROM,TO"))?;
        let (gi, gj) = (s.resolve_frame(from)?, s.resolve_frame(to)?);
        let pi = s.frame(gi).expect("resolved");
        let t0 = std::time::Instant::now();
        let interp = NonlinearInterpolator::new(topo, pi, s.frame(gj).expect("resolved"), s.up_axis)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let nonlinear = interp.at(lambda, stretch);
        let secs = t0.elapsed().as_secs_f64();
        let linear = interp.linear(lambda);
        let pj = interp.aligned_target();
        let row = json!({
            "pair": pair,
            "lambda": lambda,
            "linear": { "edge_distortion": edge_length_distortion(topo, pi, pj, &linear, lambda), "volume_change": volume_change(topo, pi, pj, &linear, lambda) },
            "nonlinear": { "edge_distortion": edge_length_distortion(topo, pi, pj, &nonlinear, lambda), "volume_change": volume_change(topo, pi, pj, &nonlinear, lambda) },
            "nonlinear_seconds": secs,
        });
        rows.push(row);
        if output.is_some() {
            let sweep = (0..=10)
                .map(|k| {
                    let l = k as f64 / 10.0;
                    let (lin, non) = (interp.linear(l), interp.at(l, stretch));
                    [
                        l,
                        edge_length_distortion(topo, pi, pj, &lin, l),
                        edge_length_distortion(topo, pi, pj, &non, l),
                        volume_change(topo, pi, pj, &lin, l),
                        volume_change(topo, pi, pj, &non, l),
                    ]
                })
                .collect();
            sweeps.push((pair.clone(), sweep));
        }
    }
    if let Some(dir) = &output {
        write_interpolation_plots(dir, &s.name, &rows, &sweeps)?;
    }
    if ctx.json {
        print_json(&json!({ "subject": s.name, "rows": rows }));
        return Ok(());
    }
    println!(
        "subject {} ({} vertices, {} triangles), lambda = {lambda}",
        s.name,
        topo.n_vertices(),
        topo.n_triangles()
    );
    println!(
        "{:<28} {:>14} {:>14} {:>14} {:>14} {:>9}",
        "pair", "edge lin.", "edge nonlin.", "volume lin.", "volume nonlin.", "time"
    );
    for r in &rows {
        println!(
            "{:<28} {:>14.5} {:>14.5} {:>14.5} {:>14.5} {:>8.3}s",
            r["pair"].as_str().unwrap_or(""),
            r["linear"]["edge_distortion"].as_f64().unwrap_or(f64::NAN),
            r["nonlinear"]["edge_distortion"].as_f64().unwrap_or(f64::NAN),
            r["linear"]["volume_change"].as_f64().unwrap_or(f64::NAN),
            r["nonlinear"]["volume_change"].as_f64().unwrap_or(f64::NAN),
            r["nonlinear_seconds"].as_f64().unwrap_or(f64::NAN),
        );
    }
    Ok(())
}

/// `interpolation.json` and `distortion.svg/png`: each measure over lambda, one colour per pair,
/// linear dashed and non-linear solid (thesis Fig. 2.8 reads them at lambda = 0.5).
fn write_interpolation_plots(
    dir: &std::path::Path,
    name: &str,
    rows: &[serde_json::Value],
    sweeps: &[(String, Vec<[f64; 5]>)],
) -> anyhow::Result<()> {
    use surfcap_plot::{LineChart, Series, write_line_chart};
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let palette = [(31, 95, 191), (208, 48, 48), (46, 158, 68), (224, 138, 0), (120, 60, 170)];
    for (stem, title, lin, non) in
        [("distortion", "edge-length distortion over lambda", 1, 2), ("volume", "volume change over lambda", 3, 4)]
    {
        let mut series = Vec::new();
        for (k, (pair, sweep)) in sweeps.iter().enumerate() {
            let color = palette[k % palette.len()];
            for (col, dashed, kind) in [(lin, true, "linear"), (non, false, "non-linear")] {
                series.push(Series {
                    name: format!("{pair} {kind}"),
                    points: sweep.iter().map(|r| (r[0], r[col])).collect(),
                    color,
                    dashed,
                    markers: false,
                });
            }
        }
        let chart = LineChart {
            title: format!("{name}: {title}"),
            x_label: "lambda".into(),
            y_label: if stem == "volume" { "relative volume change".into() } else { "relative edge distortion".into() },
            series,
        };
        write_line_chart(&dir.join(stem), &chart)?;
    }
    let v = json!({ "subject": name, "rows": rows, "sweeps": sweeps.iter().map(|(p, s)| json!({ "pair": p, "lambda_linear_edge_nonlinear_edge_linear_volume_nonlinear_volume": s })).collect::<Vec<_>>() });
    let path = dir.join("interpolation.json");
    surfcap_mesh::atomic::write_file(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &v).map_err(std::io::Error::other)
    })?;
    Ok(())
}
