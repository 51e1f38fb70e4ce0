//! `surfcap-bench play`: the interactive controller's decision latency (target: p99 under 2 ms
//! on 2,000 frames, single-threaded, so a decision fits a 60 fps frame with room to spare).
//!
//! The subject is `surfcap-bench synth`'s (the procedural mannequin's six gaits, exactly
//! --frames frames at 30 fps). The controller is driven at 60 Hz for --seconds by seeded random
//! inputs (every 0.5 to 2 s a new ground velocity: a random direction at a walking or running
//! speed, or a stop), on one thread. Measured: the precomputation (frame motion and the moves'
//! future-trajectory features), every decision's latency (the asked trajectory and the scan),
//! every 60 Hz step's latency without meshes (with the graph's moves only, and with parametric
//! blending) and with meshes and blending (transitions and blends interpolated as they are
//! queued), and, for comparison, the same decisions scanning every move of the graph (what a
//! search without the graph's adjacency as its index would scan).

use std::time::Instant;

use rand::{Rng, SeedableRng};
use serde_json::json;
use surfcap_synthesis::controller::future_trajectory::FutureTrajectories;
use surfcap_synthesis::controller::move_choice::{Ahead, GaitAsked, LocalGoal, choose_move};
use surfcap_synthesis::controller::{Controller, ControllerOptions, FrameMotion, Input};

use crate::options::{AlphaOpt, CacheOpts, SeedOpt, TableOpts};

/// `surfcap-bench play`: decision latency of the interactive controller.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
    frames: usize,
    #[arg(long, default_value_t = 1000, value_parser = crate::options::count)]
    vertices: usize,
    /// Seconds of play (at 60 Hz).
    #[arg(long, default_value_t = 60.0, value_parser = crate::options::positive)]
    seconds: f64,
    #[command(flatten)]
    alpha: AlphaOpt,
    #[command(flatten)]
    seed: SeedOpt,
    /// Cache folder for the distance matrix and transition table (default: a temporary one).
    #[arg(long)]
    cache_dir: Option<std::path::PathBuf>,
}

/// The value at quantile `q` of `v` (sorted here).
fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Seeded random inputs: (time from which it holds, input).
fn inputs(seed: u64, seconds: f64, walk: f64, run: f64) -> Vec<(f64, Input)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut t = 0.0;
    while t < seconds {
        let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let input = match rng.random_range(0..5) {
            0 => Input::stop(),
            1 | 2 => Input::velocity([run * a.cos(), run * a.sin()]),
            _ => Input::velocity([walk * a.cos(), walk * a.sin()]),
        };
        out.push((t, input));
        t += rng.random_range(0.5..2.0);
    }
    out
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let Args { frames, vertices, seconds, alpha, seed, cache_dir } = a;
    let (f, v) = (frames as f64, vertices as f64);
    let what = format!("--frames {frames} --vertices {vertices}");
    crate::check_size(ctx, what, f * v * 12.0 + f * f * 8.0 * 4.0, f * f * 8.0 * 3.0, "--frames or --vertices")?;
    anyhow::ensure!(frames >= 200, "--frames {frames}: expected at least 200");
    let s = crate::synth::gaits_subject(frames, vertices, seed.seed)?;
    let tmp = tempfile::TempDir::new()?;
    let params = surfcap_pipeline::GraphParams {
        table: TableOpts::default().params(s.fps)?,
        kind: surfcap_pipeline::GraphKind::Essential,
        alpha: alpha.value(),
    };
    let cache = CacheOpts { cache_dir: Some(cache_dir.unwrap_or_else(|| tmp.path().into())), no_cache: false };
    let pipe = cache.pipeline(ctx, s)?;
    let prep = surfcap_synthesis::Prepared::new(pipe, params, None)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| measure(ctx, &prep, seconds, seed.seed))
}

fn measure(ctx: &crate::Ctx, prep: &surfcap_synthesis::Prepared, seconds: f64, seed: u64) -> anyhow::Result<()> {
    use std::sync::Arc;
    let t0 = Instant::now();
    let motion = Arc::new(FrameMotion::new(prep.subject(), &prep.model.centres));
    let index = Arc::new(FutureTrajectories::new(&prep.model, &prep.graph, &motion));
    let precompute = t0.elapsed().as_secs_f64();
    let walk = motion.typical_speed(surfcap_synthesis::controller::Gait::Walk).unwrap_or(1.0);
    let run = motion.typical_speed(surfcap_synthesis::controller::Gait::Run).unwrap_or(2.0 * walk);
    let script = inputs(seed, seconds, walk, run);
    let dt = 1.0 / 60.0;
    let steps = (seconds / dt).round() as usize;
    let mut results = Vec::new();
    // Without meshes, with the graph's moves only and with parametric blending; with meshes,
    // with blending.
    for (meshes, parametric) in [(false, false), (false, true), (true, true)] {
        let options = ControllerOptions { meshes, parametric, ..Default::default() };
        let mut c = Controller::with_index(prep, index.clone(), motion.clone(), options)?;
        let (mut decisions, mut step_times, mut candidates) = (Vec::new(), Vec::new(), Vec::new());
        let mut full_scan = Vec::new();
        let mut k = 0;
        for i in 0..steps {
            let t = i as f64 * dt;
            while k + 1 < script.len() && script[k + 1].0 <= t {
                k += 1;
            }
            let t1 = Instant::now();
            let out = c.step(&script[k].1, dt)?;
            step_times.push(t1.elapsed().as_secs_f64());
            for d in &out.decisions {
                decisions.push(d.seconds);
                candidates.push(d.candidates as f64);
                if !meshes && !parametric {
                    full_scan.push(scan_everything(&index, &motion, d.frame));
                }
            }
        }
        let (transitions, realism) = c.transitions();
        let n_decisions = decisions.len();
        let mean_candidates = candidates.iter().sum::<f64>() / candidates.len().max(1) as f64;
        results.push(json!({
            "meshes": meshes,
            "parametric": parametric,
            "blended_frames": c.blended(),
            "decisions": n_decisions,
            "frames_shown": c.shown(),
            "transitions": transitions,
            "realism_cost": realism,
            "candidates_mean": mean_candidates,
            "candidates_max": quantile(&mut candidates, 1.0),
            "decision_ms": { "p50": 1e3 * quantile(&mut decisions, 0.5), "p99": 1e3 * quantile(&mut decisions, 0.99), "max": 1e3 * quantile(&mut decisions, 1.0) },
            "step_ms": { "p50": 1e3 * quantile(&mut step_times, 0.5), "p99": 1e3 * quantile(&mut step_times, 0.99), "max": 1e3 * quantile(&mut step_times, 1.0) },
            "scan_every_move_ms": if meshes || parametric { serde_json::Value::Null } else {
                json!({ "p50": 1e3 * quantile(&mut full_scan, 0.5), "p99": 1e3 * quantile(&mut full_scan, 0.99) })
            },
        }));
    }
    let report = json!({
        "frames": prep.graph.n,
        "vertices": prep.subject().topology().n_vertices(),
        "threads": rayon::current_num_threads(),
        "graph_edges": prep.graph.edges().len(),
        "moves": index.n_transitions(),
        "index_bytes": index.bytes(),
        "precompute_seconds": precompute,
        "seconds_played": seconds,
        "inputs": script.len(),
        "runs": results,
    });
    ctx.result(&report, || {
        println!(
            "{} frames x {} vertices, 1 thread: {} moves into live frames ({} edges), features precomputed in {:.2} s ({:.1} MB)",
            prep.graph.n,
            prep.subject().topology().n_vertices(),
            index.n_transitions(),
            prep.graph.edges().len(),
            precompute,
            index.bytes() as f64 / 1e6
        );
        for r in &results {
            let ms = |k: &str, q: &str| r[k][q].as_f64().unwrap_or(f64::NAN);
            println!(
                "{} meshes, {}: {} decisions over {seconds} s ({} inputs), {:.0} moves compared on average (max {:.0}); \
                 decision p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms; 60 Hz step p99 {:.3} ms, max {:.3} ms; {} transitions, \
                 {} frames blended",
                if r["meshes"].as_bool() == Some(true) { "with" } else { "without" },
                if r["parametric"].as_bool() == Some(true) { "parametric blending" } else { "graph moves only" },
                r["decisions"],
                script.len(),
                r["candidates_mean"].as_f64().unwrap_or(0.0),
                r["candidates_max"].as_f64().unwrap_or(0.0),
                ms("decision_ms", "p50"),
                ms("decision_ms", "p99"),
                ms("decision_ms", "max"),
                ms("step_ms", "p99"),
                ms("step_ms", "max"),
                r["transitions"],
                r["blended_frames"]
            );
            if r["scan_every_move_ms"].is_object() {
                println!(
                    "  the same decisions scanning every move of the graph (no index): p50 {:.3} ms, p99 {:.3} ms",
                    ms("scan_every_move_ms", "p50"),
                    ms("scan_every_move_ms", "p99")
                );
            }
        }
    });
    Ok(())
}

/// Seconds to score every move of the graph against a standing goal from `frame` (the scan a
/// search without an index over the graph's adjacency would do).
fn scan_everything(index: &FutureTrajectories, motion: &FrameMotion, frame: u32) -> f64 {
    let n = index.live.len() as u32;
    let frames: Vec<u32> = (0..n).collect();
    let centres = vec![[0.0, 0.0]; frames.len()];
    let horizon = index.horizons[index.horizons.len() - 1];
    let goal = LocalGoal { positions: vec![[0.0, 0.0]; horizon + 1], facing: vec![0.0; horizon + 1] };
    let t0 = Instant::now();
    let c = choose_move(
        index,
        motion,
        &Ahead { frames: &frames, centres: &centres },
        &goal,
        GaitAsked::Any,
        &Default::default(),
    );
    let secs = t0.elapsed().as_secs_f64();
    std::hint::black_box((c, frame));
    secs
}
