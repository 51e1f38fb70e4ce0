//! `surfcap-bench`: speed and memory measurements of surfcap, one subcommand per benchmark,
//! each in its own file (its arguments and its `run`). Speed targets live here, never in timed
//! tests (the machines are shared). A library so that tests parse command lines with [`Cli`];
//! the binary (`src/main.rs`) calls [`main`].
//!
//! The front-end pieces (output context, progress bars, option groups, the exit codes and the
//! `--json` error reports) are surfcap-cli's, so a benchmark reports as the `surfcap` commands do.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use surfcap_cli::{Ctx, GlobalOpts, NegativeValues};
// The CLI's shared modules, under the names the benchmarks use (`crate::options::count`).
use surfcap_cli::{options, output, progress};

mod appearance;
mod cache;
mod distance;
mod export;
mod graph;
mod interpolate;
mod learn;
mod load;
mod measure;
mod play;
mod rig;
mod scale;
mod smg;
mod synth;
mod transfer;
mod transitions;
mod vary;

/// Measure surfcap's speed and memory against its targets (on 2 cores unless said otherwise):
/// loading, distances, transitions, graphs, synthesis queries, the surface motion graph,
/// appearance, learning, transfer, variation, the tiled all-pairs work, the cache and export.
#[derive(Parser, Debug)]
#[command(name = "surfcap-bench", version, long_about = None, negative_values = true)]
pub struct Cli {
    #[command(flatten)]
    globals: GlobalOpts,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Load a subject (given, or generated with --frames x --vertices) and report time and memory.
    Load(load::Args),
    /// All-pairs deformation distance matrix: triangle pairs per second, against the machine's
    /// dense f64 matrix-multiply rate (thesis eq. 2.13), and peak memory before and after it.
    Distance(distance::Args),
    /// All-pairs transition table (thesis 2.5.3-2.5.4) and its speed-up over one DTW per segment
    /// length pair, measured on a sample of frame pairs.
    Transitions(transitions::Args),
    /// Essential and motion graph build time for --frames nodes (thesis 3.3; target: 2,000
    /// nodes in under 60 s on 2 cores, after the transition table). The table is seeded random
    /// (costs and durations): the build's work does not depend on the values.
    Graph(graph::Args),
    /// Constrained synthesis on a real-geometry graph of --frames nodes (the procedural
    /// mannequin, six gaits with varied seeds): transition table, essential graph and walk-model
    /// build times, then the latency of one query of each kind: a 15 m S-path, ten key poses,
    /// and a distance-and-time query (target: under 1 s each).
    Synth(synth::Args),
    /// The surface motion graph's speed targets (Huang et al. 2009): shape histograms of 2,000
    /// frames of 10,000 vertices (< 2 min) and a path query (< 50 ms), on the CMU-driven
    /// mannequin.
    Smg(smg::Args),
    /// Eigen appearance maps (thesis chapter 4): flow between two 1024 x 1024 maps (< 5 s), the
    /// model of 100 maps (< 5 min, peak memory < 8 GB), instantiating one map (< 1 s).
    Appearance(appearance::Args),
    /// The learning toolkit's speed targets (thesis chapters 5-6): GP fit and prediction on
    /// 2,000 x 20 points (< 5 s), a GPDM fit on 400 frames x ~3,000 coordinates (< 60 s), 20 HMC
    /// trajectory samples of 100 frames (< 30 s).
    Learn(learn::Args),
    /// Motion transfer's speed targets (thesis chapter 5): training on 350 pairs with 5 parts
    /// and 20 components, hyper-parameters fitted (< 10 s), and a 100-frame transfer onto a
    /// 10,000-vertex mannequin with part correction and stitching (< 10 s).
    Transfer(transfer::Args),
    /// Motion variation's speed targets (thesis chapter 6): training on 4 sequences of about
    /// 100 frames (the CMU-driven mannequin's walk, turns and jog; 5 parts) under 2 minutes,
    /// and sampling 5 variants under 30 s.
    Vary(vary::Args),
    /// The tiled all-pairs work at 20,000 frames: sampled tile jobs, the projection on N
    /// workers, and a 5,000-frame run end to end.
    Scale(scale::Args),
    /// What verifying a cache entry's content hash costs on reading: the crane's distance
    /// matrix and a 2,000-frame transition table, read with and without the hash (ms, GB/s).
    Cache(cache::Args),
    /// Write long animations as .glb, .abc or .usda (default: glb, 10 minutes at 30 fps of a
    /// 10,000-vertex tube, 18,000 frames): file size, time and the memory the write adds, for
    /// each length (`--frames 1800,3600,9000,18000` shows that both grow linearly).
    #[command(alias = "glb")]
    Export(export::Args),
    /// One non-linear interpolation (thesis eq. 2.45-2.49): factorisation and per-lambda times.
    Interpolate(interpolate::Args),
    /// The interactive controller (motion matching on the essential graph): decision latency
    /// on --frames nodes, single-threaded (target: p99 under 2 ms on 2,000 frames), the 60 Hz
    /// step's latency with and without meshes, and the moves' precomputation.
    Play(play::Args),
    /// Skinned rigs (Smooth Skinning Decomposition with Rigid Bones) of a real subject (default
    /// the crane) at several bone counts: decomposition time, error, glb size; with
    /// --segment-frames also a rig per segment beside one rig for the whole subject.
    Rig(rig::Args),
    /// `surfcap tiles`, for `scale`'s child processes (each tile job's peak memory its own).
    #[command(subcommand, hide = true)]
    Tiles(surfcap_cli::commands::tiles::Cmd),
}

impl surfcap_cli::Front for Cli {
    const NAME: &'static str = "surfcap-bench";

    fn globals(&self) -> &GlobalOpts {
        &self.globals
    }

    fn run(self, ctx: &Ctx) -> anyhow::Result<()> {
        match self.command {
            Command::Load(a) => load::run(ctx, a),
            Command::Distance(a) => distance::run(ctx, a),
            Command::Transitions(a) => transitions::run(ctx, a),
            Command::Graph(a) => graph::run(ctx, a),
            Command::Synth(a) => synth::run(ctx, a),
            Command::Smg(a) => smg::run(ctx, &a),
            Command::Appearance(a) => appearance::run(ctx, &a),
            Command::Learn(a) => learn::run(ctx, &a),
            Command::Transfer(a) => transfer::run(ctx, &a),
            Command::Vary(a) => vary::run(ctx, &a),
            Command::Scale(a) => scale::run(ctx, a),
            Command::Cache(a) => cache::run(ctx, a),
            Command::Export(a) => export::run(ctx, a),
            Command::Interpolate(a) => interpolate::run(ctx, a),
            Command::Play(a) => play::run(ctx, a),
            Command::Rig(a) => rig::run(ctx, a),
            Command::Tiles(c) => surfcap_cli::commands::tiles::run(ctx, c),
        }
    }
}

/// Refuses a benchmark whose memory or files, estimated from its arguments before any work
/// (each benchmark sizes itself in its own file: bytes as `f64`, so huge counts saturate), exceed
/// `--max-memory` (default half the memory available) or `--max-disk` (default the free space
/// of the temporary folder, where the benchmarks write), naming the size and what to lower.
fn check_size(ctx: &Ctx, what: String, memory: f64, disk: f64, lower: &str) -> anyhow::Result<()> {
    use surfcap_mesh::sizing::{Estimate, bytes};
    let e = Estimate { what, memory: bytes(&[memory], 1), disk: bytes(&[disk], 1), lower: lower.into() };
    ctx.check_size(&e, Some(&std::env::temp_dir()))
}

/// Runs the benchmarks' program on the process's arguments and returns its exit code.
pub fn main() -> ExitCode {
    surfcap_cli::run_front::<Cli>()
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// `surfcap-bench --help` opens with what the program measures, not the package's one-line
    /// description.
    #[test]
    fn the_summary_names_what_is_measured() {
        let about = super::Cli::command().get_about().map(|a| a.to_string()).unwrap_or_default();
        assert!(about.starts_with("Measure surfcap's speed and memory"), "{about}");
        assert!(about.contains("synthesis queries") && about.contains("appearance"), "{about}");
    }
}
