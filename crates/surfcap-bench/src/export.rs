//! `surfcap-bench export` (alias `surfcap-bench glb`): writes long animations as `.glb`, `.abc`,
//! `.usda` or `.usdc` (default: glb, 10 minutes at 30 fps of a 10,000-vertex subject, 18,000 frames) and
//! reports for each length the file size, the time and the memory the write added above the
//! subject's own positions (the peak resident memory during the write, reset before it through
//! `/proc/self/clear_refs`, minus the resident memory before it). Several lengths
//! (`--frames 1800,3600,9000,18000`) show whether time and memory grow linearly with the length:
//! the writers stream, so the added memory should stay small
//! and the time per frame constant. Both the wall time and the CPU time of the write are given:
//! the wall time includes the final sync to disk, which on a shared machine varies with what
//! else writes.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_builtin::{WormParams, worm_subject};
use surfcap_formats::export::{ExportFormat, ExportOptions, export};
use surfcap_mesh::{NoProgress, Sequence, Subject};

use crate::measure::{cpu_seconds, peak_rss};

/// The resident memory now, from `/proc/self/status`.
fn rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets the peak resident memory to the current one (Linux 4.0+); false where it cannot.
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// One sequence of `frames` frames, as a synthesised animation is: the tube's 500-frame motion
/// repeated.
fn long_subject(frames: usize, vertices: usize) -> anyhow::Result<Subject> {
    let per = 500.min(frames);
    let rings = vertices.saturating_sub(2).div_ceil(25).max(2);
    let g = worm_subject(&WormParams { rings, segments: 25, frames: per, ..Default::default() })?;
    let src = &g.sequences()[0];
    let nv = g.topology().n_vertices();
    let mut positions = Vec::with_capacity(frames * 3 * nv);
    for f in 0..frames {
        positions.extend_from_slice(src.frame(f % per));
    }
    let seq = Sequence::new("long", nv, positions)?;
    Ok(Subject::new("bench", g.topology().clone(), vec![seq], 30.0, g.up_axis, g.units.clone())?)
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// glb, abc, usda or usdc.
    #[arg(long, default_value = "glb")]
    pub format: ExportFormat,
    /// Lengths in frames (at 30 fps), comma-separated.
    #[arg(long, default_value = "18000", value_delimiter = ',', value_parser = crate::options::count)]
    pub frames: Vec<usize>,
    #[arg(long, default_value_t = 10_000, value_parser = crate::options::count)]
    pub vertices: usize,
    /// Keep the file here (one length only; default: a temporary folder, removed afterwards).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let Args { format, frames: lengths, vertices, output } = a;
    // The longest animation in memory (the tube and its copy for the writer); every file on disk.
    let v = vertices as f64;
    let longest = lengths.iter().copied().max().unwrap_or(0) as f64;
    let all: f64 = lengths.iter().map(|&n| n as f64).sum();
    let what = format!(
        "--frames {} --vertices {vertices}",
        lengths.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(",")
    );
    crate::check_size(ctx, what, longest * v * 12.0 * 2.0, all * v * 12.0, "--frames or --vertices")?;
    let ext = match format {
        ExportFormat::Glb => "glb",
        ExportFormat::Abc => "abc",
        ExportFormat::Usda => "usda",
        ExportFormat::Usdc => "usdc",
        other => anyhow::bail!("--format {other:?}: expected glb, abc, usda or usdc (one file per animation)"),
    };
    if output.is_some() && lengths.len() > 1 {
        anyhow::bail!("--output keeps one file: give one length in --frames");
    }
    let tmp = tempfile::tempdir().context("creating a temporary folder")?;
    let mut runs = Vec::new();
    for &frames in &lengths {
        let s = long_subject(frames, vertices)?;
        let nv = s.topology().n_vertices();
        let out = output.clone().unwrap_or_else(|| tmp.path().join(format!("long.{ext}")));
        let reset = reset_peak();
        let before = rss();
        let t0 = Instant::now();
        let c0 = cpu_seconds();
        export(&s, format, &out, ExportOptions::default(), &NoProgress)?;
        let seconds = t0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - c0;
        let peak = peak_rss();
        let bytes = std::fs::metadata(&out).with_context(|| format!("reading {}", out.display()))?.len();
        if output.is_none() {
            std::fs::remove_file(&out).with_context(|| format!("removing {}", out.display()))?;
        }
        let position_bytes = std::mem::size_of_val(s.sequences()[0].positions()) as u64;
        let added = match (reset, before, peak) {
            (true, Some(b), Some(p)) => Some(p.saturating_sub(b)),
            _ => None,
        };
        runs.push(json!({
            "frames": frames,
            "minutes": frames as f64 / s.fps / 60.0,
            "vertices": nv,
            "file_bytes": bytes,
            "bytes_per_frame": bytes as f64 / frames as f64,
            "position_bytes": position_bytes,
            "write_seconds": seconds,
            "milliseconds_per_frame": 1e3 * seconds / frames as f64,
            "cpu_seconds": cpu,
            "cpu_milliseconds_per_frame": 1e3 * cpu / frames as f64,
            "resident_bytes_before_write": before,
            "peak_resident_bytes_during_write": if reset { peak } else { None },
            "added_bytes_during_write": added,
        }));
    }
    let report = json!({ "format": ext, "fps": 30.0, "runs": runs });
    ctx.result(&report, || {
        let mb = |b: Option<u64>| b.map_or("unknown".into(), |b| format!("{:.0} MB", b as f64 / 1e6));
        for r in &runs {
            println!(
                "{ext}: {} frames x {} vertices ({:.1} min at 30 fps): {:.0} MB ({:.0} bytes per frame) in {:.2} s ({:.3} ms per frame; CPU {:.3} ms per frame); memory added by the write {} ({:.0} MB of positions, {} resident before)",
                r["frames"],
                r["vertices"],
                r["minutes"].as_f64().unwrap_or(0.0),
                r["file_bytes"].as_f64().unwrap_or(0.0) / 1e6,
                r["bytes_per_frame"].as_f64().unwrap_or(0.0),
                r["write_seconds"].as_f64().unwrap_or(0.0),
                r["milliseconds_per_frame"].as_f64().unwrap_or(0.0),
                r["cpu_milliseconds_per_frame"].as_f64().unwrap_or(0.0),
                mb(r["added_bytes_during_write"].as_u64()),
                r["position_bytes"].as_f64().unwrap_or(0.0) / 1e6,
                mb(r["resident_bytes_before_write"].as_u64()),
            );
        }
    });
    Ok(())
}
