//! `surfcap bench load`: time and peak resident memory of loading a subject. The load runs in a
//! child process so that its peak memory is its own (not that of generating the test data).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_synth::{WormParams, worm_subject};

use crate::options::TableOpts;
use crate::output::print_json;

mod learn;

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
        #[arg(long, default_value_t = 2000)]
        frames: usize,
        #[arg(long, default_value_t = 10000)]
        vertices: usize,
        /// Repetitions (the best and the median are reported).
        #[arg(long, default_value_t = 3)]
        repeat: usize,
        /// Measure in this process (used by the parent run).
        #[arg(long, hide = true)]
        in_process: bool,
        /// Frame rate for sources that do not give one.
        #[arg(long)]
        fps: Option<f64>,
    },
    /// All-pairs deformation distance matrix: triangle pairs per second, against the machine's
    /// dense f64 matrix-multiply rate (thesis eq. 2.13).
    Distance {
        /// A subject; default: the built-in tube with --frames frames of about --triangles triangles.
        #[arg(long)]
        subject: Option<PathBuf>,
        #[arg(long, default_value_t = 175)]
        frames: usize,
        #[arg(long, default_value_t = 20000)]
        triangles: usize,
        /// Frame rate for sources that do not give one.
        #[arg(long)]
        fps: Option<f64>,
    },
    /// All-pairs transition table (thesis 2.5.3-2.5.4) and its speed-up over one DTW per segment
    /// length pair, measured on a sample of frame pairs.
    Transitions {
        /// A subject; default: the built-in tube, two sequences, --frames frames in all.
        #[arg(long)]
        subject: Option<PathBuf>,
        #[arg(long, default_value_t = 350)]
        frames: usize,
        /// Frame pairs timed with the naive loop.
        #[arg(long, default_value_t = 12)]
        sample: usize,
        #[command(flatten)]
        table: TableOpts,
        /// Frame rate for sources that do not give one.
        #[arg(long)]
        fps: Option<f64>,
    },
    /// Essential and motion graph build time for --frames nodes (thesis 3.3; target: 2,000
    /// nodes in under 60 s on 2 cores, after the transition table). The table is seeded random
    /// (costs and durations): the build's work does not depend on the values.
    Graph {
        #[arg(long, default_value_t = 2000)]
        frames: usize,
        /// Sequences the frames are split into.
        #[arg(long, default_value_t = 20)]
        sequences: usize,
        #[arg(long, default_value_t = 0.05)]
        alpha: f64,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Constrained synthesis on a real-geometry graph of --frames nodes (the procedural
    /// mannequin, six gaits with varied seeds): transition table, essential graph and walk-model
    /// build times, then the latency of one query of each kind: a 15 m S-path, ten key poses,
    /// and a distance-and-time query (target: under 1 s each).
    Synth(SynthBench),
    /// The learning toolkit's speed targets (thesis chapters 5-6): GP fit and prediction on
    /// 2,000 x 20 points (< 5 s), a GPDM fit on 400 frames x ~3,000 coordinates (< 60 s), 20 HMC
    /// trajectory samples of 100 frames (< 30 s).
    Learn(learn::LearnArgs),
    /// One non-linear interpolation (thesis eq. 2.45-2.49): factorisation and per-lambda times.
    Interpolate {
        /// A subject cache or source.
        subject: PathBuf,
        #[arg(long)]
        from: String,
        #[arg(long)]
        to: String,
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Frame rate for sources that do not give one.
        #[arg(long)]
        fps: Option<f64>,
    },
}

/// Opens a benchmark's subject without progress output (the timings are printed instead).
fn open_quietly(path: &std::path::Path, fps: Option<f64>) -> anyhow::Result<Subject> {
    let opts = surfcap_mesh::import::ImportOptions { fps, ..Default::default() };
    Ok(surfcap_mesh::import::open_subject(path, &opts, &NoProgress)?.subject)
}

/// Rate of a 1000 x 1000 f64 matrix product on all cores (faer), in FLOP/s: the reference
/// "peak" that the distance benchmark's arithmetic rate is compared with.
fn gemm_rate() -> f64 {
    let n = 1000;
    let a = faer::Mat::<f64>::from_fn(n, n, |i, j| ((i * 31 + j * 17) % 101) as f64 / 101.0);
    let b = a.clone();
    let _ = &a * &b;
    let t0 = Instant::now();
    let reps = 5;
    for _ in 0..reps {
        std::hint::black_box(&a * &b);
    }
    2.0 * (n * n * n) as f64 * reps as f64 / t0.elapsed().as_secs_f64()
}

/// Floating-point operations per triangle pair in `deformation_distance`, counted from the
/// code: 27 mul + 18 add (rotations), 15 mul + 13 add (dot products), 4 mul + 1 add (m),
/// 5 for h, 2 div, 5 for the trace, 8 for the stretch term and sum; sqrt and acos counted as one
/// each. An estimate for the "fraction of peak" figure, not a measurement.
const FLOPS_PER_TRIANGLE_PAIR: f64 = 100.0;

fn distance_bench(
    ctx: &crate::Ctx,
    subject: Option<PathBuf>,
    frames: usize,
    triangles: usize,
    fps: Option<f64>,
) -> anyhow::Result<()> {
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    let s = match subject {
        Some(p) => open_quietly(&p, fps)?,
        None => {
            let segments = 25usize;
            let rings = (triangles / (2 * segments)).max(2);
            let w = worm_subject(&WormParams { rings, segments, frames: frames.div_ceil(2), ..Default::default() })?;
            let nv = w.topology().n_vertices();
            let mut all = Vec::new();
            for q in w.sequences() {
                all.extend_from_slice(q.positions());
            }
            all.truncate(frames * 3 * nv);
            let seq = Sequence::new("all", nv, all)?;
            w.derived("bench", seq)?
        }
    };
    let n = s.n_frames();
    let m = s.topology().n_triangles();
    let bar = crate::progress::Bar::new(ctx);
    let t0 = Instant::now();
    let d = distance_matrix(&s, &DistanceParams::default(), &bar);
    let secs = t0.elapsed().as_secs_f64();
    let pairs = (n * (n - 1) / 2) as f64 * m as f64;
    let rate = pairs / secs;
    let peak = gemm_rate();
    let report = json!({
        "frames": n, "triangles": m, "seconds": secs, "triangle_pairs_per_second": rate,
        "threads": rayon::current_num_threads(),
        "estimated_flops_per_triangle_pair": FLOPS_PER_TRIANGLE_PAIR,
        "gemm_flops_per_second": peak,
        "fraction_of_gemm_rate": rate * FLOPS_PER_TRIANGLE_PAIR / peak,
        "max_skipped_triangles": d.max_skipped_triangles,
        "peak_rss_bytes": peak_rss(),
    });
    ctx.result(&report, || {
        println!(
            "{n} x {n} deformation distances, {m} triangles: {secs:.2} s, {:.1} M triangle pairs/s on {} threads; \
             ~{:.1} GFLOP/s = {:.1}% of the machine's dense f64 GEMM rate ({:.1} GFLOP/s); peak memory {:.0} MB",
            rate / 1e6,
            rayon::current_num_threads(),
            rate * FLOPS_PER_TRIANGLE_PAIR / 1e9,
            100.0 * rate * FLOPS_PER_TRIANGLE_PAIR / peak,
            peak / 1e9,
            peak_rss().unwrap_or(0) as f64 / 1e6
        );
    });
    Ok(())
}

fn transitions_bench(
    ctx: &crate::Ctx,
    subject: Option<PathBuf>,
    frames: usize,
    sample: usize,
    table: &TableOpts,
    fps: Option<f64>,
) -> anyhow::Result<()> {
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    use surfcap_motion::transition_table::{SegmentRoom, naive_transition, transition_table};
    let s = match subject {
        Some(p) => open_quietly(&p, fps)?,
        None => worm_subject(&WormParams { frames: frames.div_ceil(2), ..Default::default() })?,
    };
    let p = table.params(s.fps)?;
    let bar = crate::progress::Bar::new(ctx);
    let t0 = Instant::now();
    let d = distance_matrix(&s, &DistanceParams::default(), &bar);
    let dist_secs = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let t = transition_table(&d.values, s.frame_index(), &p, &bar);
    let table_secs = t1.elapsed().as_secs_f64();
    let n = t.n;
    let candidates: Vec<usize> = (0..n * n).filter(|&k| t.cost[k].is_finite()).collect();
    anyhow::ensure!(!candidates.is_empty(), "no frame pair has room for a transition");
    // Pairs spread over the whole table (a fixed multiplicative hash of the sample index): evenly
    // spaced row-major picks would all sit at the start of their rows, where windows are short.
    let picks: Vec<usize> = (0..sample.max(1) as u64)
        .map(|k| candidates[(k.wrapping_mul(2_654_435_761) % candidates.len() as u64) as usize])
        .collect();
    let room = SegmentRoom::new(s.frame_index());
    let t2 = Instant::now();
    let mut mismatches = 0;
    for &k in &picks {
        let naive = naive_transition(&d.values, &room, k / n, k % n, &p);
        if naive.is_none_or(|(c, ..)| (c - t.cost[k]).abs() > 1e-9 * c.abs().max(1.0)) {
            mismatches += 1;
        }
    }
    let per_pair = t2.elapsed().as_secs_f64() / picks.len() as f64;
    let naive_total = per_pair * candidates.len() as f64;
    let report = json!({
        "frames": n, "fps": s.fps, "l_min": p.l_min, "l_max": p.l_max, "slope": p.slope,
        "distance_seconds": dist_secs, "table_seconds": table_secs,
        "pairs_with_transitions": candidates.len(), "naive_seconds_per_pair": per_pair,
        "naive_seconds_estimated": naive_total, "speed_up": naive_total / table_secs,
        "naive_pairs_checked": picks.len(), "naive_mismatches": mismatches, "threads": rayon::current_num_threads(),
    });
    ctx.result(&report, || {
        println!(
            "{n} frames at {} fps, segments {}..{}, slope {}: table {table_secs:.2} s on {} threads (distances {dist_secs:.2} s); \
             naive one-DTW-per-length: {:.3} s per pair on {} sampled pairs (all agree: {}), ~{:.0} s for all {} pairs: speed-up {:.0}x",
            s.fps,
            p.l_min,
            p.l_max,
            p.slope.map_or("inf".into(), |p| p.to_string()),
            rayon::current_num_threads(),
            per_pair,
            picks.len(),
            mismatches == 0,
            naive_total,
            candidates.len(),
            naive_total / table_secs
        );
    });
    Ok(())
}

fn interpolate_bench(
    ctx: &crate::Ctx,
    subject: PathBuf,
    from: &str,
    to: &str,
    repeat: usize,
    fps: Option<f64>,
) -> anyhow::Result<()> {
    use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
    let s = open_quietly(&subject, fps)?;
    let (gi, gj) = (s.resolve_frame(from)?, s.resolve_frame(to)?);
    let (pi, pj) = (s.frame(gi).expect("resolved"), s.frame(gj).expect("resolved"));
    let mut setup = Vec::new();
    let mut solve = Vec::new();
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        let it = NonlinearInterpolator::new(s.topology(), pi, pj, s.up_axis).map_err(|e| anyhow::anyhow!("{e}"))?;
        setup.push(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        std::hint::black_box(it.at(0.5, StretchInterpolation::Linear));
        solve.push(t1.elapsed().as_secs_f64());
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (su, so) = (med(&mut setup), med(&mut solve));
    let report = json!({
        "vertices": s.topology().n_vertices(), "triangles": s.topology().n_triangles(),
        "setup_seconds_median": su, "lambda_seconds_median": so, "total_seconds_median": su + so,
        "runs": repeat.max(1),
    });
    ctx.result(&report, || {
        println!(
            "non-linear interpolation, {} vertices: set-up (alignment, polar factors, 1 symbolic + 2 numeric Cholesky) \
             {:.1} ms, one lambda (2 x Poisson solves) {:.1} ms, total {:.1} ms (medians of {})",
            s.topology().n_vertices(),
            su * 1e3,
            so * 1e3,
            (su + so) * 1e3,
            repeat.max(1)
        );
    });
    Ok(())
}

/// Peak resident set size of this process (Linux `VmHWM`), in bytes.
fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A subject of `frames` frames (split in sequences of 500) with about `vertices` vertices.
fn generated(frames: usize, vertices: usize) -> anyhow::Result<Subject> {
    let segments = 25usize;
    let rings = vertices.saturating_sub(2).div_ceil(segments).max(2);
    let per_seq = 500usize.min(frames.max(1));
    let base = worm_subject(&WormParams { rings, segments, frames: per_seq, ..Default::default() })?;
    let nv = base.topology().n_vertices();
    let mut seqs = Vec::new();
    let mut left = frames;
    let mut k = 0;
    while left > 0 {
        let n = left.min(per_seq);
        let src = &base.sequences()[k % 2];
        let p = src.positions()[..n * 3 * nv].to_vec();
        seqs.push(Sequence::new(format!("{}_{k}", src.name), nv, p)?);
        left -= n;
        k += 1;
    }
    Ok(Subject::new("bench", base.topology().clone(), seqs, 30.0, base.up_axis, base.units.clone())?)
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (subject, frames, vertices, repeat, in_process, fps) = match a.what {
        What::Load { subject, frames, vertices, repeat, in_process, fps } => {
            (subject, frames, vertices, repeat, in_process, fps)
        }
        What::Distance { subject, frames, triangles, fps } => {
            return distance_bench(ctx, subject, frames, triangles, fps);
        }
        What::Transitions { subject, frames, sample, table, fps } => {
            return transitions_bench(ctx, subject, frames, sample, &table, fps);
        }
        What::Interpolate { subject, from, to, repeat, fps } => {
            return interpolate_bench(ctx, subject, &from, &to, repeat, fps);
        }
        What::Graph { frames, sequences, alpha, seed } => return graph_bench(ctx, frames, sequences, alpha, seed),
        What::Learn(l) => return learn::run(ctx, &l),
        What::Synth(b) => {
            return synth_bench(ctx, b);
        }
    };
    if in_process {
        let path = subject.context("--in-process needs --subject")?;
        let opts = surfcap_mesh::import::ImportOptions { fps, ..Default::default() };
        let t0 = Instant::now();
        let s = surfcap_mesh::import::open_subject(&path, &opts, &NoProgress)?.subject;
        let secs = t0.elapsed().as_secs_f64();
        let bytes = s.sequences().iter().map(|q| std::mem::size_of_val(q.positions())).sum::<usize>();
        print_json(&json!({
            "seconds": secs,
            "peak_rss_bytes": peak_rss(),
            "position_bytes": bytes,
            "frames": s.n_frames(),
            "vertices": s.topology().n_vertices(),
        }));
        return Ok(());
    }
    let tmp;
    let path = match subject {
        Some(p) => p,
        None => {
            tmp = tempfile::tempdir().context("creating a temporary folder")?;
            let p = tmp.path().join("bench.subject");
            let s = generated(frames, vertices)?;
            surfcap_mesh::cache::write_cache(&p, &s, &NoProgress)?;
            p
        }
    };
    let exe = std::env::current_exe().context("finding the surfcap executable")?;
    let mut runs = Vec::new();
    for _ in 0..repeat.max(1) {
        let mut cmd = std::process::Command::new(&exe);
        cmd.args(["bench", "load", "--in-process", "--subject"]).arg(&path);
        if let Some(f) = fps {
            cmd.arg("--fps").arg(f.to_string());
        }
        let out = cmd.output().context("running the measuring child process")?;
        anyhow::ensure!(out.status.success(), "loading failed: {}", String::from_utf8_lossy(&out.stderr).trim());
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).context("reading the child's report")?;
        runs.push(v);
    }
    let mut secs: Vec<f64> = runs.iter().map(|r| r["seconds"].as_f64().unwrap_or(f64::NAN)).collect();
    secs.sort_by(f64::total_cmp);
    let peak = runs.iter().filter_map(|r| r["peak_rss_bytes"].as_u64()).max();
    let r0 = &runs[0];
    let report = json!({
        "subject": path,
        "frames": r0["frames"],
        "vertices": r0["vertices"],
        "position_bytes": r0["position_bytes"],
        "load_seconds_best": secs[0],
        "load_seconds_median": secs[secs.len() / 2],
        "peak_rss_bytes": peak,
        "runs": runs.len(),
    });
    ctx.result(&report, || {
        let mb = |b: Option<u64>| b.map_or("unknown".into(), |b| format!("{:.0} MB", b as f64 / 1e6));
        println!(
            "loaded {} frames x {} vertices ({} of positions): best {:.3} s, median {:.3} s over {} runs; peak resident memory {}",
            r0["frames"],
            r0["vertices"],
            mb(r0["position_bytes"].as_u64()),
            secs[0],
            secs[secs.len() / 2],
            runs.len(),
            mb(peak)
        );
    });
    Ok(())
}

fn graph_bench(ctx: &crate::Ctx, frames: usize, sequences: usize, alpha: f64, seed: u64) -> anyhow::Result<()> {
    use surfcap_motion::edge_weights::edge_weights;
    use surfcap_motion::essential_graph::essential_graph;
    use surfcap_motion::motion_graph::motion_graph;
    use surfcap_motion::transition_table::TransitionTable;
    anyhow::ensure!(
        sequences >= 1 && frames >= 2 * sequences,
        "--frames {frames} --sequences {sequences}: expected at least two frames per sequence"
    );
    surfcap_pipeline::pipeline::check_alpha(alpha)?;
    let index =
        surfcap_mesh::FrameIndex::new((0..sequences).map(|k| frames / sequences + usize::from(k < frames % sequences)));
    let n = frames;
    // A seeded, platform-independent stream for the table's values (as surfcap-eval's Mantel test).
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let cost: Vec<f64> = (0..n * n).map(|_| rng.random_range(0.5..1.5)).collect();
    let len: Vec<u32> = (0..n * n).map(|_| rng.random_range(10..60)).collect();
    let table = TransitionTable { n, cost, len, li: vec![10; n * n], lj: vec![10; n * n] };
    let t0 = Instant::now();
    let w = edge_weights(&table, &index, alpha);
    let t_weights = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let eg = essential_graph(&w, &crate::progress::Bar::new(ctx));
    let t_essential = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let mg = motion_graph(&w, &index);
    let t_motion = t2.elapsed().as_secs_f64();
    let report = json!({
        "frames": n, "sequences": sequences, "alpha": alpha, "threads": rayon::current_num_threads(),
        "edge_weights_seconds": t_weights, "essential_graph_seconds": t_essential, "motion_graph_seconds": t_motion,
        "essential_edges": eg.graph.edges().len(), "essential_density": eg.graph.density(),
        "motion_edges": mg.graph.edges().len(), "motion_density": mg.graph.density(),
    });
    ctx.result(&report, || {
        println!(
            "{n} nodes ({sequences} sequences), {} threads: edge weights {t_weights:.2} s, essential graph {t_essential:.2} s ({} edges, density {:.4}), motion graph {t_motion:.2} s ({} edges)",
            rayon::current_num_threads(),
            eg.graph.edges().len(),
            eg.graph.density(),
            mg.graph.edges().len()
        );
    });
    Ok(())
}

/// `bench synth`: graph build and query latency on a procedural subject.
#[derive(clap::Args, Debug)]
pub struct SynthBench {
    #[arg(long, default_value_t = 2000)]
    frames: usize,
    #[arg(long, default_value_t = 1000)]
    vertices: usize,
    #[arg(long, default_value_t = 0.05)]
    alpha: f64,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Cache folder for the distance matrix and transition table (default: a temporary one,
    /// so every phase is measured).
    #[arg(long)]
    cache_dir: Option<PathBuf>,
    /// Transitions the path search tries per frame (default: `surfcap synth path`'s).
    #[arg(long)]
    branching: Option<usize>,
}

fn synth_bench(ctx: &crate::Ctx, b: SynthBench) -> anyhow::Result<()> {
    let SynthBench { frames, vertices, alpha, seed, cache_dir, branching } = b;
    use rand::{Rng, SeedableRng};
    use surfcap_motion::path_following::{Curve, PathSearch, follow_path};
    use surfcap_motion::timed_walk::TimedGraph;
    use surfcap_synth::locomotion::Gait;
    use surfcap_synth::mannequin::{BodyShape, mannequin};
    use surfcap_synth::mannequin_subject::{Clip, mannequin_subject};
    anyhow::ensure!(frames >= 200, "--frames {frames}: expected at least 200");
    let t0 = Instant::now();
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
        // The last clip is cut so the graph has exactly --frames nodes.
        c.poses.truncate(frames - total);
        total += c.poses.len();
        clips.push(c);
    }
    let s = mannequin_subject("bench", &m, &clips, 30.0)?;
    let build_secs = t0.elapsed().as_secs_f64();
    let tmp = tempfile::TempDir::new()?;
    let store = surfcap_pipeline::CacheStore::in_folder(cache_dir.unwrap_or_else(|| tmp.path().into()), false);
    let params = surfcap_pipeline::GraphParams {
        table: TableOpts::default().params(s.fps)?,
        kind: surfcap_pipeline::GraphKind::Essential,
        alpha,
    };
    let pipe = surfcap_pipeline::Pipeline::new(s, store, Box::new(crate::progress::Bar::new(ctx)));
    let t1 = Instant::now();
    let _ = pipe.chain_distances()?;
    let dist_secs = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let _ = pipe.table(&params.table)?;
    let table_secs = t2.elapsed().as_secs_f64();
    let prep = crate::synthesis::Prepared::new(pipe, params, None)?;
    let graph_secs = prep.seconds;
    let n = prep.graph.n;
    // 15 m S-path.
    let points: Vec<[f64; 3]> = (0..=272)
        .map(|k| {
            let x = k as f64 * 0.05;
            [x, 0.0, 1.5 * (2.0 * std::f64::consts::PI * x / 14.0).sin()]
        })
        .collect();
    let curve = Curve::new(points, vec![0, 2]).map_err(anyhow::Error::msg)?;
    let mut search = PathSearch::for_fps(prep.subject().fps);
    search.branching = branching.unwrap_or(search.branching);
    let t3 = Instant::now();
    let path = follow_path(&prep.model, &prep.graph, &curve, &[], None, &search).map_err(anyhow::Error::msg)?;
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
        let walk = tg.walk_with_duration(w[0], w[1], want - now, longest).map_err(anyhow::Error::msg)?;
        now += walk.frames as i64;
        key_err += (now - want).abs();
    }
    let key_secs = t5.elapsed().as_secs_f64();
    let (a, b) = (hubs[rng.random_range(0..hubs.len())], hubs[rng.random_range(0..hubs.len())]);
    let t6 = Instant::now();
    let (reach, _) =
        tg.walk_with_distance_and_time(a, b, 10.0, 300, (0.3, 10.0), longest).map_err(anyhow::Error::msg)?;
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
