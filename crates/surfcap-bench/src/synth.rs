//! `surfcap-bench synth`: constrained synthesis on a real-geometry graph: build times and query
//! latencies.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use crate::options::{AlphaOpt, CacheOpts, SeedOpt, TableOpts};

/// `surfcap-bench synth`: graph build and query latency on a procedural subject.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
    frames: usize,
    #[arg(long, default_value_t = 1000, value_parser = crate::options::count)]
    vertices: usize,
    #[command(flatten)]
    alpha: AlphaOpt,
    #[command(flatten)]
    seed: SeedOpt,
    /// Cache folder for the distance matrix and transition table (default: a temporary one,
    /// so every phase is measured).
    #[arg(long)]
    cache_dir: Option<PathBuf>,
    /// Transitions the path search tries per frame (default: `surfcap synth path`'s).
    #[arg(long, value_parser = crate::options::count)]
    branching: Option<usize>,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let Args { frames, vertices, alpha, seed, cache_dir, branching } = a;
    // The subject's positions, then the distance matrix and the transition table's matrices.
    let (f, v) = (frames as f64, vertices as f64);
    let what = format!("--frames {frames} --vertices {vertices}");
    crate::check_size(ctx, what, f * v * 12.0 + f * f * 8.0 * 4.0, f * f * 8.0 * 3.0, "--frames or --vertices")?;
    let (alpha, seed) = (alpha.value(), seed.seed);
    use rand::{Rng, SeedableRng};
    use surfcap_motion::path_following::{Curve, PathSearch, follow_path};
    use surfcap_motion::timed_walk::TimedGraph;
    anyhow::ensure!(frames >= 200, "--frames {frames}: expected at least 200");
    let t0 = Instant::now();
    let s = gaits_subject(frames, vertices, seed)?;
    let build_secs = t0.elapsed().as_secs_f64();
    let tmp = tempfile::TempDir::new()?;
    let params = surfcap_pipeline::GraphParams {
        table: TableOpts::default().params(s.fps)?,
        kind: surfcap_pipeline::GraphKind::Essential,
        alpha,
    };
    let cache = CacheOpts { cache_dir: Some(cache_dir.unwrap_or_else(|| tmp.path().into())), no_cache: false };
    let pipe = cache.pipeline(ctx, s)?;
    let t1 = Instant::now();
    let _ = pipe.chain_distances()?;
    let dist_secs = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let _ = pipe.table(&params.table)?;
    let table_secs = t2.elapsed().as_secs_f64();
    let prep = surfcap_synthesis::Prepared::new(pipe, params, None)?;
    let graph_secs = prep.seconds;
    let n = prep.graph.n;
    // 15 m S-path.
    let points: Vec<[f64; 3]> = (0..=272)
        .map(|k| {
            let x = k as f64 * 0.05;
            [x, 0.0, 1.5 * (2.0 * std::f64::consts::PI * x / 14.0).sin()]
        })
        .collect();
    let curve = Curve::new(points, vec![0, 2])?;
    let mut search = PathSearch::for_fps(prep.subject().fps);
    search.branching = branching.unwrap_or(search.branching);
    let t3 = Instant::now();
    let path = follow_path(&prep.model, &prep.graph, &curve, &[], None, &search)?;
    let path_secs = t3.elapsed().as_secs_f64();
    let path_err = path.errors.iter().sum::<f64>() / path.errors.len() as f64;
    // Ten key poses, 60 frames apart, and one distance-and-time query.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let t4 = Instant::now();
    let tg = TimedGraph::new(&prep.graph, &prep.model);
    let timed_secs = t4.elapsed().as_secs_f64();
    let longest = tg.longest_edge();
    // Key frames where transitions both arrive and leave (the first frames of a sequence cannot
    // be reached from anywhere else, its last ones lead nowhere else).
    let mut arrive = vec![false; n];
    let mut leave = vec![false; n];
    for e in prep.graph.edges() {
        if let Some(surfcap_motion::walk_sequence::Step::Transition(_)) = prep.model.step(e.from, e.to) {
            leave[e.from as usize] = true;
            arrive[e.to as usize] = true;
        }
    }
    let hubs: Vec<u32> = (0..n as u32).filter(|&u| arrive[u as usize] && leave[u as usize]).collect();
    anyhow::ensure!(hubs.len() >= 2, "the graph has fewer than two frames with transitions in and out");
    let keys: Vec<u32> = (0..10).map(|_| hubs[rng.random_range(0..hubs.len())]).collect();
    let t5 = Instant::now();
    let mut now = 0i64;
    let mut key_err = 0i64;
    for (k, w) in keys.windows(2).enumerate() {
        let want = 60 * (k as i64 + 1);
        let walk = tg.walk_with_duration(w[0], w[1], want - now, longest)?;
        now += walk.frames as i64;
        key_err += (now - want).abs();
    }
    let key_secs = t5.elapsed().as_secs_f64();
    let (a, b) = (hubs[rng.random_range(0..hubs.len())], hubs[rng.random_range(0..hubs.len())]);
    let t6 = Instant::now();
    let (reach, _) = tg.walk_with_distance_and_time(a, b, 10.0, 300, (0.3, 10.0), longest)?;
    let reach_secs = t6.elapsed().as_secs_f64();
    let report = json!({
        "frames": n, "vertices": prep.subject().topology().n_vertices(), "alpha": alpha, "threads": rayon::current_num_threads(),
        "subject_seconds": build_secs, "distance_seconds": dist_secs, "table_seconds": table_secs,
        "graph_and_walk_model_seconds": graph_secs, "timed_graph_seconds": timed_secs,
        "edges": prep.graph.edges().len(), "transitions": prep.model.n_transitions(),
        "path": { "seconds": path_secs, "mean_error": path_err, "frames": path.errors.len(), "branching": search.branching, "expanded": path.expanded },
        "keyposes": { "seconds": key_secs, "mean_abs_error_frames": key_err as f64 / 9.0 },
        "reach": { "seconds": reach_secs, "distance": reach.distance, "frames": reach.frames, "target_distance": 10.0, "target_frames": 300 },
    });
    ctx.result(&report, || {
        println!(
            "{n} frames x {} vertices, {} threads: distances {dist_secs:.1} s, transition table {table_secs:.1} s, essential graph + walk model {graph_secs:.1} s ({} edges)",
            prep.subject().topology().n_vertices(),
            rayon::current_num_threads(),
            prep.graph.edges().len()
        );
        println!(
            "query latency: 15 m S-path {path_secs:.2} s (mean error {path_err:.3} m), ten key poses {key_secs:.2} s (mean error {:.2} frames), distance and time {reach_secs:.2} s ({:.2} m in {} frames for 10 m in 300)",
            key_err as f64 / 9.0,
            reach.distance,
            reach.frames
        );
    });
    Ok(())
}

/// The bench subject: the procedural mannequin of about `vertices` vertices walking, jogging,
/// turning left and right, jumping and idling (clips of each gait's default duration at 30 fps,
/// seeds `seed`, `seed + 1`, ...) until it has exactly `frames` frames (the last clip cut).
pub(crate) fn gaits_subject(frames: usize, vertices: usize, seed: u64) -> anyhow::Result<surfcap_mesh::Subject> {
    use surfcap_builtin::locomotion::Gait;
    use surfcap_builtin::mannequin::{BodyShape, mannequin};
    use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
    let m = mannequin(&BodyShape::average(), vertices)?;
    let gaits = [Gait::Walk, Gait::Jog, Gait::TurnLeft, Gait::TurnRight, Gait::Jump, Gait::Idle];
    let mut clips = Vec::new();
    let mut total = 0;
    for k in 0.. {
        if total >= frames {
            break;
        }
        let g = gaits[k % gaits.len()];
        let mut c = Clip::procedural(&m, g, 30.0, g.duration(), seed + k as u64)?;
        c.name = format!("{}_{k}", c.name);
        // The last clip is cut so the graph has exactly `frames` nodes.
        c.poses.truncate(frames - total);
        total += c.poses.len();
        clips.push(c);
    }
    Ok(mannequin_subject("bench", &m, &clips, 30.0)?)
}
