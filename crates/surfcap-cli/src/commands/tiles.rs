//! `surfcap tiles plan | count | run | status | merge`: the all-pairs work of a subject (pose
//! distances, transition table, sparse essential graph) as tile jobs in a work folder, for a
//! shell's `xargs -P`, Ray (tools/ray) or Slurm job arrays (tools/slurm) to run.

use std::path::PathBuf;

use anyhow::Context;
use serde_json::json;
use surfcap_tiles::tile_jobs::{JobOutcome, run_job};
use surfcap_tiles::tile_merge::{merge, status};
use surfcap_tiles::tile_plan::{Stage, WorkParams, create_work, open_work};
use surfcap_tiles::tile_verify::Depth;

use crate::options::{AlphaOpt, DistanceOpts, TableOpts};

#[derive(clap::Subcommand, Debug)]
pub enum Cmd {
    /// Plans the work of a subject cache into a work folder: `plan.json` (the stages and their
    /// job counts) and the empty Zarr arrays. Planning again into the same folder with the same
    /// parameters keeps what is done.
    Plan(PlanArgs),
    /// Prints the number of jobs of a stage (for job arrays and `seq`).
    Count(CountArgs),
    /// Runs one job of a stage (`--index`), every job of a stage (`--all`), or with `--all` and
    /// no `--stage` every stage in order. A job already done is skipped.
    Run(RunArgs),
    /// Lists the done, missing and damaged jobs of every stage, checking every job record and
    /// every chunk against the plan (content hashes; sizes only with --quick). Exits 1 naming
    /// every file that is wrong.
    Status(StatusArgs),
    /// Checks every record and chunk against the plan and that every job is done, then writes
    /// the merged products (`merge.json`, the graph).
    Merge(WorkArgs),
}

#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// A subject cache (`surfcap import -o x.subject`): jobs read only their frames from it.
    pub subject: PathBuf,
    /// The work folder to create (or resume).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Frames per side of a tile (and per block of source rows).
    #[arg(long, default_value_t = surfcap_geometry::distance_matrix::DISTANCE_TILE, value_parser = crate::options::count)]
    pub tile: usize,
    #[command(flatten)]
    pub distance: DistanceOpts,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    /// Transitions kept per frame by the sparse essential graph (the default is the k chosen by
    /// `surfcap eval sparse-graph`).
    #[arg(long, default_value_t = surfcap_motion::sparse_essential_graph::DEFAULT_K, value_parser = crate::options::count)]
    pub k: usize,
    #[command(flatten)]
    pub table: TableOpts,
}

#[derive(clap::Args, Debug)]
pub struct WorkArgs {
    /// A work folder made by `surfcap tiles plan`.
    pub work: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct StatusArgs {
    #[command(flatten)]
    pub work: WorkArgs,
    /// Check the records and the outputs' sizes only, not their content hashes (which reads
    /// every output once).
    #[arg(long)]
    pub quick: bool,
}

#[derive(clap::Args, Debug)]
pub struct CountArgs {
    #[command(flatten)]
    pub work: WorkArgs,
    /// distances, table, scale, candidates or paths.
    #[arg(long)]
    pub stage: String,
}

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub work: WorkArgs,
    /// distances, table, scale, candidates or paths.
    #[arg(long)]
    pub stage: Option<String>,
    /// The job's index in its stage, from 0 (a job array's task id).
    #[arg(long, conflicts_with = "all")]
    pub index: Option<usize>,
    /// Every job of the stage, or of every stage in order without --stage.
    #[arg(long)]
    pub all: bool,
}

pub fn run(ctx: &crate::Ctx, cmd: Cmd) -> anyhow::Result<()> {
    match cmd {
        Cmd::Plan(a) => plan(ctx, a),
        Cmd::Count(a) => {
            let (plan, _, _) = open_work(&a.work.work)?;
            let stage = Stage::parse(&a.stage)?;
            let jobs = plan.jobs(stage);
            ctx.result(&json!({ "stage": stage.name(), "jobs": jobs }), || println!("{jobs}"));
            Ok(())
        }
        Cmd::Run(a) => run_jobs(ctx, a),
        Cmd::Status(a) => {
            let (plan, store, _) = open_work(&a.work.work)?;
            let depth = if a.quick { Depth::Sizes } else { Depth::Contents };
            let check = status(&store, &plan, depth);
            ctx.result(&json!({ "work": a.work.work, "stages": check.stages, "problems": check.problems }), || {
                let list = |v: &[usize]| {
                    let shown: Vec<String> = v.iter().take(10).map(|k| k.to_string()).collect();
                    let more = if v.len() > 10 { ", ..." } else { "" };
                    format!("{}{more}", shown.join(", "))
                };
                for s in &check.stages {
                    let mut line = format!("{:<10} {}/{} done", s.stage.name(), s.done, s.jobs);
                    if !s.missing.is_empty() {
                        line += &format!("; missing {}", list(&s.missing));
                    }
                    if !s.damaged.is_empty() {
                        line += &format!("; damaged {}", list(&s.damaged));
                    }
                    println!("{line}");
                }
            });
            if !check.problems.is_empty() {
                return Err(
                    surfcap_tiles::Error::Damaged { work: a.work.work.clone(), problems: check.problems }.into()
                );
            }
            Ok(())
        }
        Cmd::Merge(a) => {
            let (plan, store, _) = open_work(&a.work)?;
            let report = merge(&store, &plan)?;
            ctx.result(&report, || {
                println!("merged {} frames in tiles of {} (kernel {}):", report.frames, report.tile, report.kernel);
                for s in &report.stages {
                    println!(
                        "  {:<10} {:>5} jobs, {:8.1} s in all, slowest {:6.1} s, peak {:.0} MB",
                        s.stage.name(),
                        s.jobs,
                        s.seconds,
                        s.slowest_job_seconds,
                        s.peak_bytes as f64 / 1e6
                    );
                }
                println!(
                    "  median transition cost {:.6}; sparse essential graph: {} edges",
                    report.d_scale, report.graph_edges
                );
                println!("wrote {}", a.work.join("merge.json").display());
            });
            Ok(())
        }
    }
}

fn plan(ctx: &crate::Ctx, a: PlanArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        surfcap_mesh::cache::is_cache(&a.subject),
        "{}: expected a subject cache (make one with `surfcap import {} -o x.subject`): tile jobs read their frames from it",
        a.subject.display(),
        a.subject.display()
    );
    let frames = surfcap_mesh::cache::CachedFrames::open(&a.subject)?;
    let table = a.table.params(frames.fps)?;
    let params = WorkParams {
        metric: a.distance.metric.name().into(),
        w: a.distance.w,
        l_min: table.l_min,
        l_max: table.l_max,
        slope: table.slope,
        alpha: a.alpha.value(),
        k: a.k,
    };
    let plan = create_work(&a.subject, &a.output, a.tile, params)
        .with_context(|| format!("planning {} into {}", a.subject.display(), a.output.display()))?;
    let memory: Vec<_> = plan.job_memory_bytes.iter().map(|(s, b)| json!({ "stage": s.name(), "bytes": b })).collect();
    ctx.result(&json!({ "work": a.output, "plan": plan, "job_memory": memory }), || {
        println!(
            "planned {} frames of {} triangles in tiles of {} -> {}",
            plan.frames(),
            plan.subject.triangles,
            plan.tile,
            a.output.display()
        );
        for (s, bytes) in &plan.job_memory_bytes {
            println!("  {:<10} {:>5} jobs, each about {:.1} MB", s.name(), plan.jobs(*s), *bytes as f64 / 1e6);
        }
        println!(
            "run: surfcap tiles run {} --all   (or one job: --stage S --index I; see docs/src/tiles.md)",
            a.output.display()
        );
    });
    Ok(())
}

fn run_jobs(ctx: &crate::Ctx, a: RunArgs) -> anyhow::Result<()> {
    let (plan, store, frames) = open_work(&a.work.work)?;
    let stages: Vec<Stage> = match (&a.stage, a.all) {
        (Some(s), _) => vec![Stage::parse(s)?],
        (None, true) => plan.stages.iter().map(|s| s.name).collect(),
        (None, false) => anyhow::bail!("expected --stage S with --index I or --all, or --all alone for every stage"),
    };
    let bar = crate::progress::Bar::new(ctx);
    let mut done = Vec::new();
    for stage in stages {
        let jobs: Box<dyn Iterator<Item = usize>> = match (a.index, a.all) {
            (Some(i), _) => Box::new(std::iter::once(i)),
            (None, true) => Box::new(0..plan.jobs(stage)),
            (None, false) => anyhow::bail!("expected --index I (0..{}) or --all", plan.jobs(stage).saturating_sub(1)),
        };
        for k in jobs {
            let outcome = run_job(&store, &plan, &frames, stage, k, &bar)
                .with_context(|| format!("{}: stage {}, job {k}", a.work.work.display(), stage.name()))?;
            let (skipped, record) = match outcome {
                JobOutcome::Skipped => (true, None),
                JobOutcome::Done(r) => (false, Some(r)),
            };
            if let Some(r) = &record {
                ctx.say(&format!(
                    "{} job {k}: {} ({:.1} s, peak {:.0} MB)",
                    stage.name(),
                    r.span,
                    r.seconds,
                    r.peak_bytes as f64 / 1e6
                ));
            } else {
                ctx.say(&format!("{} job {k}: already done", stage.name()));
            }
            done.push(json!({ "stage": stage.name(), "index": k, "skipped": skipped, "record": record }));
        }
    }
    ctx.result(&json!({ "work": a.work.work, "jobs": done }), || {});
    Ok(())
}
