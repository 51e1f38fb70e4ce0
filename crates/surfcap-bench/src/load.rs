//! `surfcap-bench load`: time and peak resident memory of loading a subject. The load runs in a
//! child process so that its peak memory is its own (not that of generating the test data).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_builtin::{WormParams, worm_subject};
use surfcap_mesh::{NoProgress, Sequence, Subject};

use crate::measure::{FpsOpt, peak_rss};
use crate::output::print_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache or source to load; default: a generated subject of the given size.
    #[arg(long)]
    pub subject: Option<PathBuf>,
    #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
    pub frames: usize,
    #[arg(long, default_value_t = 10000, value_parser = crate::options::count)]
    pub vertices: usize,
    /// Repetitions, 1 to 100 (the best and the median are reported).
    #[arg(long, default_value_t = 3, value_parser = |s: &str| crate::options::whole_in(s, 1, 100))]
    pub repeat: usize,
    /// Measure in this process (used by the parent run).
    #[arg(long, hide = true)]
    pub in_process: bool,
    #[command(flatten)]
    pub fps: FpsOpt,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let Args { subject, frames, vertices, repeat, in_process, fps } = a;
    if in_process {
        let path = subject.context("--in-process needs --subject")?;
        let t0 = Instant::now();
        let s = fps.open_quietly(&path)?;
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
    if subject.is_none() {
        // The generated subject: its positions in memory and in its cache.
        let (f, v) = (frames as f64, vertices as f64);
        let what = format!("--frames {frames} --vertices {vertices}");
        crate::check_size(ctx, what, (f + 500.0) * v * 12.0, f * v * 12.0, "--frames or --vertices")?;
    }
    let tmp;
    let path = match subject {
        Some(p) => p,
        None => {
            tmp = tempfile::tempdir().context("creating a temporary folder")?;
            let p = tmp.path().join("bench.subject");
            let s = generated(frames, vertices)?;
            surfcap_mesh::cache::write_cache(&p, &s, false, &NoProgress)?;
            p
        }
    };
    let exe = std::env::current_exe().context("finding the surfcap-bench executable")?;
    let mut runs = Vec::new();
    for _ in 0..repeat.max(1) {
        let mut cmd = std::process::Command::new(&exe);
        cmd.args(["load", "--in-process", "--subject"]).arg(&path);
        if let Some(f) = fps.fps {
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
