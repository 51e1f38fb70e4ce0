//! `surfcap-bench scale`: the tiled all-pairs work at the size of a capture
//! day. Builds a 20,000-frame built-in tube of 10,000 triangles (ten sequences of 2,000 frames,
//! each its own seeded motion), plans it in tiles, runs a sample of real tile jobs in child
//! processes (`surfcap tiles run`, so each job's peak memory is its own process's), and projects
//! from their measured cost the wall time and memory of the whole job on this machine and on N
//! workers. Then it runs the whole tiled pipeline end to end on a 5,000-frame tube through the
//! same commands, in one child process, and reports its wall time and peak memory.
//!
//! Projection model, per stage (stages are barriers; jobs of a stage are independent):
//! - distances: every off-diagonal tile costs what the sampled off-diagonal tile cost (same
//!   pairs x triangles), a diagonal one what the sampled diagonal tile cost; edge tiles are
//!   smaller and counted as full (an upper bound);
//! - table: every tile as the sampled one (the DTW work does not depend on the values);
//! - scale, candidates, paths: measured on the end-to-end run and scaled by their complexity
//!   (scale: reads the table twice, x (n / n_e2e)^2; candidates: a block of rows x n, per job
//!   x n / n_e2e; paths: per job one Dijkstra per source, O(E + V log V) with E = V (k + 1),
//!   x n / n_e2e, the log factor ignored) and by their job counts.
//!
//! On N workers a stage takes ceil(jobs / N) times its slowest job kind; the wall time is the sum
//! over stages. Memory per job: the peak measured in the sampled job's own process (distances,
//! table), else the plan's estimate from the job's inputs (the end-to-end run is one process,
//! whose peak covers every stage before).

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_builtin::{WormParams, worm_subject};
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_tiles::tile_merge::MergeReport;
use surfcap_tiles::tile_plan::{Plan, Stage, open_work};
use surfcap_tiles::tile_store::JobRecord;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Frames of the projected subject.
    #[arg(long, default_value_t = 20_000, value_parser = crate::options::count)]
    pub frames: usize,
    /// Triangles of the projected subject (and of the end-to-end run unless --e2e-triangles).
    #[arg(long, default_value_t = 10_000, value_parser = crate::options::count)]
    pub triangles: usize,
    /// Frames per side of a tile.
    #[arg(long, default_value_t = surfcap_geometry::distance_matrix::DISTANCE_TILE, value_parser = crate::options::count)]
    pub tile: usize,
    /// Worker counts to project for (each a 2-core machine like this one).
    #[arg(long, default_value = "1,8,32", value_delimiter = ',', value_parser = crate::options::count)]
    pub workers: Vec<usize>,
    /// Frames of the end-to-end run (0: skip it).
    #[arg(long, default_value_t = 5_000)]
    pub e2e_frames: usize,
    /// Triangles of the end-to-end run (default: 2,000, so that the run takes minutes; its
    /// distance stage scales linearly with them).
    #[arg(long, default_value_t = 2_000, value_parser = crate::options::count)]
    pub e2e_triangles: usize,
    /// Keep the subjects and work folders here instead of a temporary folder.
    #[arg(long)]
    pub keep: Option<std::path::PathBuf>,
}

/// A tube of `frames` frames in ten sequences (or fewer for short subjects), `triangles`
/// triangles, each sequence its own seeded motion.
fn tube(frames: usize, triangles: usize) -> anyhow::Result<Subject> {
    let segments = 40usize;
    let rings = (triangles / (2 * segments)).max(2);
    let sequences = 10usize.min(frames.max(1));
    let mut seqs = Vec::new();
    let mut topo = None;
    let mut first = None;
    for k in 0..sequences {
        let len = frames / sequences + usize::from(k < frames % sequences);
        let w = worm_subject(&WormParams { rings, segments, frames: len, seed: k as u64, ..Default::default() })?;
        let nv = w.topology().n_vertices();
        seqs.push(Sequence::new(format!("take{k:02}"), nv, w.sequences()[0].positions().to_vec())?);
        topo.get_or_insert_with(|| w.topology().clone());
        first.get_or_insert(w);
    }
    let w = first.expect("at least one sequence");
    Ok(Subject::new("tube", topo.expect("a topology"), seqs, 30.0, w.up_axis, w.units.clone())?)
}

/// Runs `surfcap tiles ...` in a child process (this program's hidden `tiles`, the same
/// command); its stderr is passed through on failure.
fn surfcap_tiles(args: &[&str]) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("finding the surfcap-bench executable")?;
    let out = Command::new(&exe).arg("--quiet").arg("tiles").args(args).output().context("running surfcap tiles")?;
    anyhow::ensure!(
        out.status.success(),
        "surfcap tiles {} failed: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr).trim()
    );
    Ok(())
}

fn record(work: &Path, stage: Stage, index: usize) -> anyhow::Result<JobRecord> {
    let (_, store, _) = open_work(work)?;
    store.record(stage, index)?.with_context(|| format!("job {} {index} left no record", stage.name()))
}

fn make_subject(dir: &Path, name: &str, frames: usize, triangles: usize) -> anyhow::Result<std::path::PathBuf> {
    let path = dir.join(name);
    if !path.join("subject.json").is_file() {
        let s = tube(frames, triangles)?;
        surfcap_mesh::cache::write_cache(&path, &s, false, &NoProgress)?;
    }
    Ok(path)
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    // The subject (f32 positions, about half as many vertices as triangles) and the Zarr
    // matrix (f32) on disk; each worker's tiles of deformation gradients in memory.
    let (f, t) = ((a.frames.max(a.e2e_frames)) as f64, a.triangles.max(a.e2e_triangles) as f64);
    let what = format!("--frames {} --triangles {} --e2e-frames {}", a.frames, a.triangles, a.e2e_frames);
    let disk = f * t * 6.0 + f * f * 4.0 * 2.0;
    crate::check_size(ctx, what, f * t * 6.0 * 2.0 + a.tile as f64 * t * 72.0 * 2.0, disk, "--frames or --triangles")?;
    let tmp = tempfile::tempdir()?;
    let dir = a.keep.clone().unwrap_or_else(|| tmp.path().to_path_buf());
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let t0 = Instant::now();
    let big = make_subject(&dir, &format!("tube{}x{}.subject", a.frames, a.triangles), a.frames, a.triangles)?;
    ctx.say(&format!(
        "built the {}-frame tube of {} triangles ({:.0} s)",
        a.frames,
        a.triangles,
        t0.elapsed().as_secs_f64()
    ));
    let work = dir.join(format!("work{}", a.frames));
    let tile = a.tile.to_string();
    surfcap_tiles(&[
        "plan",
        big.to_str().context("a UTF-8 path")?,
        "-o",
        work.to_str().context("a UTF-8 path")?,
        "--tile",
        &tile,
    ])?;
    let (plan, _, _) = open_work(&work)?;
    // Sample: the diagonal tile (0, 0), the off-diagonal tile (0, 1), then the table tile (0, 0),
    // whose halo lies in those two.
    let w = work.to_str().context("a UTF-8 path")?;
    let mut samples = Vec::new();
    for (stage, index) in [(Stage::Distances, 0usize), (Stage::Distances, 1), (Stage::Table, 0)] {
        if index >= plan.jobs(stage) {
            continue;
        }
        ctx.say(&format!("sample: {} job {index} ...", stage.name()));
        surfcap_tiles(&["run", w, "--stage", stage.name(), "--index", &index.to_string()])?;
        let r = record(&work, stage, index)?;
        ctx.say(&format!("  {} in {:.1} s, peak {:.0} MB", r.span, r.seconds, r.peak_bytes as f64 / 1e6));
        samples.push(r);
    }
    let e2e = if a.e2e_frames > 0 {
        let small = make_subject(
            &dir,
            &format!("tube{}x{}.subject", a.e2e_frames, a.e2e_triangles),
            a.e2e_frames,
            a.e2e_triangles,
        )?;
        let work5 = dir.join(format!("work{}", a.e2e_frames));
        let w5 = work5.to_str().context("a UTF-8 path")?;
        surfcap_tiles(&["plan", small.to_str().context("a UTF-8 path")?, "-o", w5, "--tile", &tile])?;
        ctx.say(&format!(
            "end to end: {} frames of {} triangles, every stage in one process ...",
            a.e2e_frames, a.e2e_triangles
        ));
        let t = Instant::now();
        surfcap_tiles(&["run", w5, "--all"])?;
        surfcap_tiles(&["merge", w5])?;
        let wall = t.elapsed().as_secs_f64();
        let report: MergeReport = serde_json::from_slice(&std::fs::read(work5.join("merge.json"))?)?;
        let peak = report.stages.iter().map(|s| s.peak_bytes).max().unwrap_or(0);
        let (plan5, _, _) = open_work(&work5)?;
        Some((plan5, report, wall, peak))
    } else {
        None
    };
    let projection = project(&plan, &samples, e2e.as_ref().map(|(p, r, _, _)| (p, r)), &a.workers);
    let pairs_rate = samples
        .iter()
        .filter(|r| r.stage == Stage::Distances && r.index == 1)
        .map(|r| r.details["triangle_pairs"].as_f64().unwrap_or(0.0) / r.seconds)
        .next()
        .unwrap_or(0.0);
    let kernel = samples.first().map_or(String::new(), |r| r.kernel.clone());
    let result = json!({
        "frames": a.frames, "triangles": plan.subject.triangles, "tile": a.tile,
        "jobs": plan.stages, "samples": samples, "kernel": kernel,
        "measured_triangle_pairs_per_second": pairs_rate,
        "projection": projection,
        "end_to_end": e2e.as_ref().map(|(p, r, wall, peak)| json!({
            "frames": p.frames(), "triangles": p.subject.triangles, "wall_seconds": wall,
            "peak_bytes": peak, "merge": r,
        })),
    });
    ctx.result(&result, || {
        println!(
            "{} frames x {} triangles in tiles of {}: {} distance, {} table jobs; kernel {kernel}, {:.0} M triangle pairs/s measured",
            a.frames,
            plan.subject.triangles,
            a.tile,
            plan.jobs(Stage::Distances),
            plan.jobs(Stage::Table),
            pairs_rate / 1e6
        );
        for p in projection.iter() {
            println!(
                "  {:>3} workers: {:8.0} s ({:.1} h); largest job {:.0} MB, slowest job {:.0} s",
                p["workers"],
                p["wall_seconds"].as_f64().unwrap_or(0.0),
                p["wall_seconds"].as_f64().unwrap_or(0.0) / 3600.0,
                p["largest_job_bytes"].as_f64().unwrap_or(0.0) / 1e6,
                p["slowest_job_seconds"].as_f64().unwrap_or(0.0)
            );
        }
        if let Some((p, _, wall, peak)) = &e2e {
            println!(
                "  end to end, {} frames x {} triangles, one process: {:.0} s, peak {:.2} GB",
                p.frames(),
                p.subject.triangles,
                wall,
                *peak as f64 / 1e9
            );
        }
    });
    Ok(())
}

/// Per stage: (jobs, seconds per job, bytes per job) at the projected size.
fn stage_costs(
    plan: &Plan,
    samples: &[JobRecord],
    e2e: Option<(&Plan, &MergeReport)>,
) -> Vec<(Stage, usize, f64, u64)> {
    let n = plan.frames() as f64;
    let mut out = Vec::new();
    let sample = |stage: Stage, index: usize| samples.iter().find(|r| r.stage == stage && r.index == index);
    let blocks = plan.frames().div_ceil(plan.tile);
    if let (Some(diag), Some(off)) = (sample(Stage::Distances, 0), sample(Stage::Distances, 1)) {
        let jobs = plan.jobs(Stage::Distances);
        // blocks diagonal tiles, the rest off-diagonal: report the mean per job.
        let total = blocks as f64 * diag.seconds + (jobs - blocks) as f64 * off.seconds;
        out.push((Stage::Distances, jobs, total / jobs as f64, diag.peak_bytes.max(off.peak_bytes)));
    }
    if let Some(t) = sample(Stage::Table, 0) {
        out.push((Stage::Table, plan.jobs(Stage::Table), t.seconds, t.peak_bytes));
    }
    if let Some((p5, r5)) = e2e {
        let ratio = n / p5.frames() as f64;
        for s in &r5.stages {
            if matches!(s.stage, Stage::Distances | Stage::Table) {
                continue;
            }
            let per_job = s.seconds / s.jobs.max(1) as f64;
            let seconds = match s.stage {
                Stage::Scale => per_job * ratio * ratio,
                _ => per_job * ratio,
            };
            // The end-to-end run is one process: its peak is that of every stage so far, so
            // these stages' memory is the plan's estimate from their inputs at this size.
            let bytes = plan.job_memory_bytes.iter().find(|(st, _)| *st == s.stage).map_or(0, |b| b.1 as u64);
            out.push((s.stage, plan.jobs(s.stage), seconds, bytes));
        }
    }
    out
}

fn project(
    plan: &Plan,
    samples: &[JobRecord],
    e2e: Option<(&Plan, &MergeReport)>,
    workers: &[usize],
) -> Vec<serde_json::Value> {
    let costs = stage_costs(plan, samples, e2e);
    workers
        .iter()
        .map(|&w| {
            let stages: Vec<serde_json::Value> = costs
                .iter()
                .map(|&(stage, jobs, seconds, bytes)| {
                    let wall = jobs.div_ceil(w) as f64 * seconds;
                    json!({ "stage": stage.name(), "jobs": jobs, "seconds_per_job": seconds, "bytes_per_job": bytes, "wall_seconds": wall })
                })
                .collect();
            let wall: f64 = stages.iter().map(|s| s["wall_seconds"].as_f64().unwrap_or(0.0)).sum();
            let largest = costs.iter().map(|c| c.3).max().unwrap_or(0);
            let slowest = costs.iter().map(|c| c.2).fold(0.0, f64::max);
            json!({ "workers": w, "wall_seconds": wall, "stages": stages, "largest_job_bytes": largest, "slowest_job_seconds": slowest })
        })
        .collect()
}
