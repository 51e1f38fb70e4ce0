//! `surfcap bench glb`: writes a long animation as `.glb` (default: 10 minutes at 30 fps of a
//! 10,000-vertex subject, 18,000 frames) and reports its size, the time, and the peak resident
//! memory before and during the write: the writer streams the file, so it should add little to
//! the subject's own positions.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_mesh::export::{ExportFormat, ExportOptions, export};
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_synth::{WormParams, worm_subject};

use super::peak_rss;

pub(super) fn run(ctx: &crate::Ctx, frames: usize, vertices: usize, output: Option<PathBuf>) -> anyhow::Result<()> {
    // One sequence, as a synthesised animation is: the tube's 500-frame motion repeated.
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
    let s = Subject::new("bench", g.topology().clone(), vec![seq], 30.0, g.up_axis, g.units.clone())?;
    drop(g);
    let tmp = tempfile::tempdir().context("creating a temporary folder")?;
    let out = output.unwrap_or_else(|| tmp.path().join("long.glb"));
    let before = peak_rss();
    let t0 = Instant::now();
    export(&s, ExportFormat::Glb, &out, ExportOptions::default(), &NoProgress)?;
    let seconds = t0.elapsed().as_secs_f64();
    let after = peak_rss();
    let bytes = std::fs::metadata(&out).with_context(|| format!("reading {}", out.display()))?.len();
    let position_bytes = std::mem::size_of_val(s.sequences()[0].positions()) as u64;
    let report = json!({
        "frames": s.n_frames(),
        "vertices": nv,
        "fps": s.fps,
        "glb_bytes": bytes,
        "bytes_per_frame": bytes as f64 / s.n_frames() as f64,
        "position_bytes": position_bytes,
        "write_seconds": seconds,
        "peak_rss_bytes_before_write": before,
        "peak_rss_bytes": after,
    });
    ctx.result(&report, || {
        let mb = |b: Option<u64>| b.map_or("unknown".into(), |b| format!("{:.0} MB", b as f64 / 1e6));
        println!(
            "wrote {} frames x {nv} vertices ({:.1} min at {} fps) as a {:.0} MB glb ({:.0} bytes per frame) in {seconds:.2} s; peak resident memory {} ({} before writing, {:.0} MB of positions)",
            s.n_frames(),
            s.n_frames() as f64 / s.fps / 60.0,
            s.fps,
            bytes as f64 / 1e6,
            bytes as f64 / s.n_frames() as f64,
            mb(after),
            mb(before),
            position_bytes as f64 / 1e6
        );
    });
    Ok(())
}
