//! `surfcap-bench smg`: the surface motion graph's speed targets on 2 cores:
//! the shape histograms (Huang et al. 2009, 3.1) of 2,000 frames of 10,000 vertices under
//! 2 minutes, and a path query (4.1-4.2) under 50 ms (the paper: 5.7-15 s in Matlab).
//!
//! The frames are the built-in mannequin of `--vertices` vertices moved by the CMU clips of
//! `surfcap eval smg` (`--set`: its default stand / walk / jog / hit loops, or the locomotion
//! set), cycled to `--frames` frames for the histograms (every frame is voxelised and
//! histogrammed afresh: nothing is shared between repeated frames). The similarity (eq. 2) and
//! the graph are then built on the clips' own frames, as `eval smg` and `smg query` build it by
//! default (self-transitions chosen among the loops a query may play, spanning the key frames,
//! `--loops-per-sequence` per sequence, excluded loops never padding time;
//! `--eq5-self-transitions`: the paper's graph as printed), and every key pair of `eval smg` is
//! queried on an evenly spaced sub-grid of the paper's 20 m x 40 s, as the paper asks (eq. 6
//! optimum) and with the 1%-and-1-frame tolerance. A query's time is given two ways: the
//! targets alone (the walks and loops planned once per key pair, as `eval smg` does) and from
//! scratch (planning included, as one `surfcap smg query` does).

use std::time::Instant;

use serde_json::json;
use surfcap_eval::smg_eval::{
    LOCOMOTION_CONNECTIONS, LOCOMOTION_KEY_PAIRS, STAND_WALK_JOG_HIT_CONNECTIONS, STAND_WALK_JOG_HIT_KEY_PAIRS, grid,
    locomotion_subject, stand_walk_jog_hit_subject,
};
use surfcap_smg::loop_exclusion::{LoopFilter, LoopRule};
use surfcap_smg::motion_frames::MotionFrames;
use surfcap_smg::path_optimisation::{
    PathQuery, Tolerance, frames_shown, optimise_planned, plan_paths, plan_paths_excluding,
};
use surfcap_smg::shape_similarity::{FrameHistograms, HistogramParams, frame_histograms, shape_similarity_matrix};
use surfcap_smg::surface_motion_graph::{GraphInput, LoopChoice, build_graph, build_graph_choosing};

use crate::measure::{peak_rss, verdict};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("the CMU clips"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: std::path::PathBuf,
    /// Mannequin vertices (about: the remeshing lands near it; the default gives just over
    /// 10,000).
    #[arg(long, default_value_t = 10_800, value_parser = |s: &str| crate::options::whole_in(s, 500, 50_000))]
    pub vertices: usize,
    /// Frames histogrammed (the clips cycled).
    #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
    pub frames: usize,
    /// Targets per key pair (about): a sub-grid of the paper's 20 m x 40 s, evenly spaced.
    #[arg(long, default_value_t = 100, value_parser = |s: &str| crate::options::whole_in(s, 1, 800))]
    pub targets: usize,
    /// Transitions per connection to time (1: the paper's), comma-separated.
    #[arg(long, default_value = "1,3", value_delimiter = ',', value_parser = |s: &str| crate::options::whole_in(s, 1, 20))]
    pub transitions: Vec<usize>,
    /// The clips driving the mannequin: `eval smg`'s sets.
    #[arg(long, value_enum, default_value_t = ClipSet::StandWalkJogHit)]
    pub set: ClipSet,
    /// Self-transitions per sequence (without --eq5-self-transitions), as `eval smg`'s option.
    #[arg(long, default_value_t = 2, value_parser = |s: &str| crate::options::whole_in(s, 1, 10))]
    pub loops_per_sequence: usize,
    /// Time the paper's graph as printed (every self-transition by eq. 5 alone, every loop
    /// played) instead of `eval smg`'s default graph.
    #[arg(long)]
    pub eq5_self_transitions: bool,
}

/// The clips driving the mannequin (as `surfcap eval smg --set`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipSet {
    /// Huang et al.'s setting: stand, walk, jog and hit loops (`eval smg`'s default).
    StandWalkJogHit,
    /// CMU subject 16's stand-to-walk, walk, jog, jump and jog-to-stop.
    Locomotion,
}

/// Mean, 95th percentile and maximum.
fn summary(v: &mut [f64]) -> serde_json::Value {
    v.sort_by(f64::total_cmp);
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    let p95 = v.get((0.95 * v.len() as f64).ceil() as usize - 1).copied().unwrap_or(0.0);
    json!({"mean": mean, "p95": p95, "max": v.last().copied().unwrap_or(0.0), "count": v.len()})
}

pub fn run(ctx: &crate::Ctx, a: &Args) -> anyhow::Result<()> {
    // The frames' positions and the all-pairs similarity matrices (f64).
    let (f, v) = (a.frames as f64, a.vertices as f64);
    let what = format!("--frames {} --vertices {}", a.frames, a.vertices);
    crate::check_size(ctx, what, f * v * 12.0 + f * f * 8.0 * 3.0, 0.0, "--frames or --vertices")?;
    ctx.say("building the mannequin and its CMU clips (not timed) ...");
    type Named = &'static [(&'static str, &'static str)];
    let (subject, connections, pairs): (_, Named, Named) = match a.set {
        ClipSet::StandWalkJogHit => (
            stand_walk_jog_hit_subject(&a.data, a.vertices)?,
            &STAND_WALK_JOG_HIT_CONNECTIONS,
            &STAND_WALK_JOG_HIT_KEY_PAIRS,
        ),
        ClipSet::Locomotion => {
            (locomotion_subject(&a.data, a.vertices)?, &LOCOMOTION_CONNECTIONS, &LOCOMOTION_KEY_PAIRS)
        }
    };
    let frames = MotionFrames::from_subject(&subject);
    let real = frames.n_frames();
    anyhow::ensure!(
        a.frames >= real,
        "--frames {}: expected at least the clips' {real} frames (the similarity is built on them)",
        a.frames
    );
    let meshes = frames.meshes();
    let cycled: Vec<_> = (0..a.frames).map(|i| meshes[i % real]).collect();
    let params = HistogramParams::default();
    let rss0 = peak_rss();
    ctx.say(&format!("shape histograms of {} frames of {} vertices ...", a.frames, subject.topology().n_vertices()));
    let t = Instant::now();
    let all = frame_histograms(&cycled, frames.up, params)?;
    let histogram_seconds = t.elapsed().as_secs_f64();
    let rss1 = peak_rss();
    // The clips' own frames: the first `real` of the cycle.
    let own = FrameHistograms { histograms: all.histograms[..real].to_vec(), ..all.clone() };
    drop(all);
    let t = Instant::now();
    let similarity = shape_similarity_matrix(&own)?;
    let similarity_seconds = t.elapsed().as_secs_f64();

    let ground = frames.ground_centroids();
    let seq = |n: &str| {
        frames.names.iter().position(|x| x == n).ok_or_else(|| anyhow::anyhow!("no sequence {n:?} in the clips"))
    };
    let conns: Vec<(usize, usize)> =
        connections.iter().map(|(x, y)| Ok((seq(x)?, seq(y)?))).collect::<anyhow::Result<_>>()?;
    let keys: Vec<(usize, usize)> = pairs
        .iter()
        .map(|(x, y)| Ok((frames.resolve(x)?, frames.resolve(y)?)))
        .collect::<surfcap_smg::error::Result<_>>()?;
    let key_frames: Vec<usize> = keys.iter().flat_map(|&(x, y)| [x, y]).collect();
    // A sub-grid of the paper's, every `step` metres and seconds: about `--targets` targets
    // spread over both axes.
    let step = ((800.0 / a.targets as f64).sqrt().round() as usize).max(1);
    let targets = grid(
        &(1..=20).step_by(step).map(f64::from).collect::<Vec<_>>(),
        &(1..=40).step_by(step).map(f64::from).collect::<Vec<_>>(),
    );

    // `eval smg`'s default graph: self-transitions among the loops the queries may play.
    let rule = (!a.eq5_self_transitions).then(LoopRule::default);
    let filter = rule.map(|r| LoopFilter::new(r, &similarity, &frames.sequences)).transpose()?;
    let mut runs = Vec::new();
    for &k in &a.transitions {
        let t = Instant::now();
        let input = GraphInput {
            sequences: &frames.sequences,
            similarity: &similarity,
            ground: &ground,
            connections: &conns,
            key_frames: &key_frames,
            lengths: 3..=30,
            per_connection: k,
            separation: 15,
        };
        let g = match &filter {
            Some(filter) => build_graph_choosing(
                &input,
                &LoopChoice { filter, key_pairs: &keys, per_sequence: a.loops_per_sequence },
            )?,
            None => build_graph(&input)?,
        };
        let graph_seconds = t.elapsed().as_secs_f64();
        let (mut plans, mut paper, mut goal, mut fresh) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut walks, mut loops, mut unplanned) = (Vec::new(), 0, Vec::new());
        for (&(s, e), (from, to)) in keys.iter().zip(pairs.iter()) {
            let max_paths = PathQuery::new(s, e, 0.0, 1.0).max_paths;
            let t = Instant::now();
            let planned = match &filter {
                Some(filter) => plan_paths_excluding(&g, s, e, max_paths, filter),
                None => plan_paths(&g, s, e, max_paths),
            };
            // Key frames the graph does not join (the paper's graph on the stand / walk / jog /
            // hit clips): no query to time, said so in the result.
            let plan = match planned {
                Ok(p) => p,
                Err(why) => {
                    walks.push(0);
                    unplanned.push(format!("{from} -> {to}: {why}"));
                    continue;
                }
            };
            let plan_seconds = t.elapsed().as_secs_f64();
            plans.push(plan_seconds);
            walks.push(plan.walks());
            loops = plan.loops_in_graph();
            for &(d, secs) in &targets {
                let q = PathQuery::new(s, e, d, frames_shown(secs, frames.fps));
                let t = Instant::now();
                optimise_planned(&g, &ground, &plan, &q)?;
                let query = t.elapsed().as_secs_f64();
                paper.push(query);
                fresh.push(query + plan_seconds);
                let q = PathQuery { tolerance: Some(Tolerance::default()), ..q };
                let t = Instant::now();
                optimise_planned(&g, &ground, &plan, &q)?;
                goal.push(t.elapsed().as_secs_f64());
            }
        }
        let fresh_mean = fresh.iter().sum::<f64>() / fresh.len().max(1) as f64;
        runs.push(json!({
            "transitions_per_connection": k, "graph_nodes": g.nodes.len(), "graph_edges": g.edges.len(),
            "loops": loops, "walks_per_key_pair": walks, "graph_seconds": graph_seconds,
            "key_pairs_not_planned": unplanned,
            "plan_seconds": summary(&mut plans), "query_seconds": summary(&mut paper),
            "query_with_tolerance_seconds": summary(&mut goal), "query_from_scratch_seconds": summary(&mut fresh),
            "query_target_seconds": 0.05, "query_verdict": verdict(fresh_mean, 0.05),
        }));
    }
    let result = json!({
        "set": format!("{:?}", a.set), "self_transitions": if rule.is_some() { "spanning" } else { "eq5" },
        "loops_per_sequence": rule.map(|_| a.loops_per_sequence),
        "vertices": subject.topology().n_vertices(), "histogram_frames": a.frames,
        "histogram_seconds": histogram_seconds, "histogram_target_seconds": 120.0,
        "histogram_verdict": verdict(histogram_seconds, 120.0),
        "histogram_peak_rss_added_bytes": rss1.zip(rss0).map(|(b, a)| b.saturating_sub(a)),
        "similarity_frames": real, "similarity_seconds": similarity_seconds,
        "key_pairs": keys.len(), "targets_per_key_pair": targets.len(), "runs": runs,
        "threads": rayon::current_num_threads(),
    });
    ctx.result(&result, || {
        println!(
            "shape histograms: {} frames of {} vertices in {histogram_seconds:.1} s (target < 120 s: {}); similarity of the clips' {real} frames: {similarity_seconds:.1} s",
            a.frames,
            subject.topology().n_vertices(),
            verdict(histogram_seconds, 120.0)
        );
        for r in &runs {
            let ms = |v: &serde_json::Value, k: &str| 1e3 * v[k].as_f64().unwrap_or(0.0);
            println!(
                "{} transition(s) per connection: {} nodes, {} edges, {} loops, walks per key pair {}; graph {:.2} s",
                r["transitions_per_connection"],
                r["graph_nodes"],
                r["graph_edges"],
                r["loops"],
                r["walks_per_key_pair"],
                r["graph_seconds"].as_f64().unwrap_or(0.0)
            );
            for (name, key) in [
                ("plan (once per key pair)", "plan_seconds"),
                ("query, eq. 6 optimum", "query_seconds"),
                ("query, 1% and 1 frame", "query_with_tolerance_seconds"),
                ("query from scratch", "query_from_scratch_seconds"),
            ] {
                let v = &r[key];
                println!(
                    "  {name:<28} mean {:8.2} ms, p95 {:8.2} ms, max {:8.2} ms",
                    ms(v, "mean"),
                    ms(v, "p95"),
                    ms(v, "max")
                );
            }
            for why in r["key_pairs_not_planned"].as_array().into_iter().flatten() {
                println!("  not timed: {}", why.as_str().unwrap_or(""));
            }
            println!("  target < 50 ms per query from scratch: {}", r["query_verdict"].as_str().unwrap_or(""));
        }
    });
    Ok(())
}
