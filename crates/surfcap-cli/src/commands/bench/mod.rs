//! `surfcap bench ...`: speed and memory measurements, one file per benchmark. Speed targets live
//! here, never in timed tests (the machines are shared).

use std::path::PathBuf;

use surfcap_mesh::{NoProgress, Subject};

use crate::options::{Positive, TableOpts};

mod appearance;
mod distance;
mod export;
mod graph;
mod interpolate;
mod learn;
mod load;
mod scale;
mod smg;
mod synth;
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
    /// Load a subject (given, or generated with --frames x --vertices) and report time and memory.
    Load {
        /// A subject cache or source to load; default: a generated subject of the given size.
        #[arg(long)]
        subject: Option<PathBuf>,
        #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
        frames: usize,
        #[arg(long, default_value_t = 10000, value_parser = crate::options::count)]
        vertices: usize,
        /// Repetitions (the best and the median are reported).
        #[arg(long, default_value_t = 3, value_parser = crate::options::count)]
        repeat: usize,
        /// Measure in this process (used by the parent run).
        #[arg(long, hide = true)]
        in_process: bool,
        /// Frame rate for sources that do not give one.
        #[arg(long, value_parser = crate::options::positive)]
        fps: Option<f64>,
    },
    /// All-pairs deformation distance matrix: triangle pairs per second, against the machine's
    /// dense f64 matrix-multiply rate (thesis eq. 2.13), and peak memory before and after it.
    Distance {
        /// A subject; default: the built-in tube with --frames frames of about --triangles triangles.
        #[arg(long)]
        subject: Option<PathBuf>,
        #[arg(long, default_value_t = 175, value_parser = crate::options::count)]
        frames: usize,
        #[arg(long, default_value_t = 20000, value_parser = crate::options::count)]
        triangles: usize,
        /// Frame rate for sources that do not give one.
        #[arg(long, value_parser = crate::options::positive)]
        fps: Option<f64>,
    },
    /// All-pairs transition table (thesis 2.5.3-2.5.4) and its speed-up over one DTW per segment
    /// length pair, measured on a sample of frame pairs.
    Transitions {
        /// A subject; default: the built-in tube, two sequences, --frames frames in all.
        #[arg(long)]
        subject: Option<PathBuf>,
        #[arg(long, default_value_t = 350, value_parser = crate::options::count)]
        frames: usize,
        /// Frame pairs timed with the naive loop.
        #[arg(long, default_value_t = 12, value_parser = crate::options::count)]
        sample: usize,
        #[command(flatten)]
        table: TableOpts,
        /// Frame rate for sources that do not give one.
        #[arg(long, value_parser = crate::options::positive)]
        fps: Option<f64>,
    },
    /// Essential and motion graph build time for --frames nodes (thesis 3.3; target: 2,000
    /// nodes in under 60 s on 2 cores, after the transition table). The table is seeded random
    /// (costs and durations): the build's work does not depend on the values.
    Graph {
        #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
        frames: usize,
        /// Sequences the frames are split into.
        #[arg(long, default_value_t = 20, value_parser = crate::options::count)]
        sequences: usize,
        #[arg(long, default_value = "0.05")]
        alpha: Positive,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Constrained synthesis on a real-geometry graph of --frames nodes (the procedural
    /// mannequin, six gaits with varied seeds): transition table, essential graph and walk-model
    /// build times, then the latency of one query of each kind: a 15 m S-path, ten key poses,
    /// and a distance-and-time query (target: under 1 s each).
    Synth(synth::SynthBench),
    /// The surface motion graph's speed targets (Huang et al. 2009, issue 17): shape histograms
    /// of 2,000 frames of 10,000 vertices (< 2 min) and a path query (< 50 ms), on the
    /// CMU-driven mannequin.
    Smg(smg::SmgArgs),
    /// Eigen appearance maps (issue 20 item 9): flow between two 1024 x 1024 maps, the model
    /// of 100 maps (time and peak memory), instantiating one map.
    Appearance(appearance::AppearanceArgs),
    /// The learning toolkit's speed targets (thesis chapters 5-6): GP fit and prediction on
    /// 2,000 x 20 points (< 5 s), a GPDM fit on 400 frames x ~3,000 coordinates (< 60 s), 20 HMC
    /// trajectory samples of 100 frames (< 30 s).
    Learn(learn::LearnArgs),
    /// Motion transfer's speed targets (issue 18): training on 350 pairs with 5 parts and 20
    /// components, hyper-parameters fitted (< 10 s), and a 100-frame transfer onto a
    /// 10,000-vertex mannequin with part correction and stitching (< 10 s).
    Transfer(transfer::TransferArgs),
    /// Motion variation's speed targets (issue 19 item 7): training on 4 sequences of about 100
    /// frames (the CMU-driven mannequin's walk, turns and jog; 5 parts) under 2 minutes, and
    /// sampling 5 variants under 30 s.
    Vary(vary::VaryArgs),
    /// The tiled all-pairs work at 20,000 frames: sampled tile jobs, the projection on N
    /// workers, and a 5,000-frame run end to end (issue 21).
    Scale(scale::ScaleArgs),
    /// Write long animations as .glb, .abc or .usda (default: glb, 10 minutes at 30 fps of a
    /// 10,000-vertex tube, 18,000 frames): file size, time and the memory the write adds, for
    /// each length (`--frames 1800,3600,9000,18000` shows that both grow linearly).
    #[command(alias = "glb")]
    Export {
        /// glb, abc or usda.
        #[arg(long, default_value = "glb")]
        format: surfcap_formats::export::ExportFormat,
        /// Lengths in frames (at 30 fps), comma-separated.
        #[arg(long, default_value = "18000", value_delimiter = ',', value_parser = crate::options::count)]
        frames: Vec<usize>,
        #[arg(long, default_value_t = 10_000, value_parser = crate::options::count)]
        vertices: usize,
        /// Keep the file here (one length only; default: a temporary folder, removed afterwards).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// One non-linear interpolation (thesis eq. 2.45-2.49): factorisation and per-lambda times.
    Interpolate {
        /// A subject cache or source.
        subject: PathBuf,
        #[arg(long)]
        from: String,
        #[arg(long)]
        to: String,
        #[arg(long, default_value_t = 5, value_parser = crate::options::count)]
        repeat: usize,
        /// Frame rate for sources that do not give one.
        #[arg(long, value_parser = crate::options::positive)]
        fps: Option<f64>,
    },
}

/// Opens a benchmark's subject without progress output (the timings are printed instead).
pub(super) fn open_quietly(path: &std::path::Path, fps: Option<f64>) -> anyhow::Result<Subject> {
    let opts = surfcap_formats::import::ImportOptions { fps, ..Default::default() };
    Ok(surfcap_formats::import::open_subject(path, &opts, &NoProgress)?.subject)
}

/// Peak resident set size of this process (Linux `VmHWM`), in bytes.
pub(super) fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    match a.what {
        What::Load { subject, frames, vertices, repeat, in_process, fps } => {
            load::run(ctx, subject, frames, vertices, repeat, in_process, fps)
        }
        What::Distance { subject, frames, triangles, fps } => distance::run(ctx, subject, frames, triangles, fps),
        What::Transitions { subject, frames, sample, table, fps } => {
            transitions::run(ctx, subject, frames, sample, &table, fps)
        }
        What::Interpolate { subject, from, to, repeat, fps } => interpolate::run(ctx, subject, &from, &to, repeat, fps),
        What::Graph { frames, sequences, alpha, seed } => graph::run(ctx, frames, sequences, alpha.0, seed),
        What::Export { format, frames, vertices, output } => export::run(ctx, format, &frames, vertices, output),
        What::Learn(l) => learn::run(ctx, &l),
        What::Transfer(t) => transfer::run(ctx, &t),
        What::Vary(v) => vary::run(ctx, &v),
        What::Scale(s) => scale::run(ctx, s),
        What::Synth(b) => synth::run(ctx, b),
        What::Smg(b) => smg::run(ctx, &b),
        What::Appearance(b) => appearance::run(ctx, &b),
    }
}
