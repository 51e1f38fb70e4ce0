//! `surfcap eval stream <subject>`: the compact stream (`surfcap_formats::stream`) of a subject
//! coded in memory and decoded back: bytes per frame (all bytes over the frames, header and
//! topology included; key and predicted frames apart), the bit rate in Mbps at 30 fps and at the
//! subject's rate, the error of the decoded positions against the source (largest and RMS vertex
//! distance, in the subject's unit and in % of its height: its first frame's extent along the up
//! axis), coding and decoding times, and the same subject as glb morph targets (surfcap's glb
//! export) for comparison.

use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_formats::stream::{StreamFile, encode_stream};
use surfcap_formats::stream_predict::Prediction;

use crate::options::SubjectArgs;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub subject: SubjectArgs,
    /// Only these sequences (repeatable; default: all).
    #[arg(long = "sequence")]
    pub sequences: Vec<String>,
    /// Bits per coordinate on the grid over the animation's bounding box (4 to 30).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(4..=30))]
    pub stream_bits: u32,
    /// Instead of --stream-bits, the largest vertex error allowed, in % of the subject's height.
    #[arg(long, value_name = "PERCENT")]
    pub stream_error: Option<f64>,
    /// A key frame every this many frames of a sequence, and at its start.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u64).range(1..))]
    pub stream_key_interval: u64,
}

/// Mbps of `bytes_per_frame` played at `fps`.
fn mbps(bytes_per_frame: f64, fps: f64) -> f64 {
    bytes_per_frame * 8.0 * fps / 1e6
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let s = a.subject.open(ctx)?.select(&a.sequences)?;
    let opts = crate::commands::export::stream_options(&s, a.stream_bits, a.stream_error, a.stream_key_interval)?;
    let frames = s.n_frames();
    let n = s.topology().n_vertices();
    let t0 = Instant::now();
    let (bytes, summary) = encode_stream(&s, &opts);
    let encode_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let decoded = StreamFile::parse(&bytes).and_then(|f| f.decode()).context("decoding the stream just coded")?;
    let decode_s = t1.elapsed().as_secs_f64();
    // Error: per vertex, the distance between the source and the decoded position.
    let source = s.sequences().iter().flat_map(|q| q.positions().iter().copied());
    let (mut max, mut sum2) = (0.0f64, 0.0f64);
    for (p, d) in source.collect::<Vec<f32>>().chunks_exact(3).zip(decoded.chunks_exact(3)) {
        let e2: f64 = (0..3).map(|k| (f64::from(p[k]) - f64::from(d[k])).powi(2)).sum();
        max = max.max(e2.sqrt());
        sum2 += e2;
    }
    let rms = (sum2 / (frames * n).max(1) as f64).sqrt();
    let height = surfcap_eval::variation_eval::subject_height(s.sequences()[0].frame(0), s.up_axis);
    let pct = |x: f64| if height > 0.0 { 100.0 * x / height } else { f64::NAN };
    let mut glb = Vec::new();
    surfcap_formats::glb::write_glb(&mut glb, &s).context("writing the glb for comparison")?;
    let per_frame = bytes.len() as f64 / frames as f64;
    let glb_per_frame = glb.len() as f64 / frames as f64;
    let mean = |k: &dyn Fn(Prediction) -> bool| {
        let v: Vec<usize> =
            summary.frame_bytes.iter().zip(&summary.predictions).filter(|(_, p)| k(**p)).map(|(b, _)| *b).collect();
        (v.len(), v.iter().sum::<usize>() as f64 / v.len().max(1) as f64)
    };
    let (keys, key_mean) = mean(&|p| p == Prediction::Key);
    let (predicted, predicted_mean) = mean(&|p| p != Prediction::Key);
    let unit = s.units.symbol().to_string();
    let report = json!({
        "subject": s.name,
        "frames": frames,
        "vertices": n,
        "fps": s.fps,
        "bits": summary.quantiser.bits,
        "key_interval": opts.key_interval,
        "bytes": bytes.len(),
        "header_bytes": summary.header_bytes,
        "bytes_per_frame": per_frame,
        "key_frames": keys,
        "key_frame_bytes": key_mean,
        "predicted_frames": predicted,
        "predicted_frame_bytes": predicted_mean,
        "mbps_at_30_fps": mbps(per_frame, 30.0),
        "mbps_at_subject_fps": mbps(per_frame, s.fps),
        "unit": unit,
        "height": height,
        "max_error": max,
        "rms_error": rms,
        "max_error_percent_of_height": pct(max),
        "rms_error_percent_of_height": pct(rms),
        "grid_error_bound": summary.quantiser.max_error(),
        "encode_seconds": encode_s,
        "decode_seconds": decode_s,
        "glb_bytes": glb.len(),
        "glb_bytes_per_frame": glb_per_frame,
        "glb_mbps_at_30_fps": mbps(glb_per_frame, 30.0),
    });
    ctx.result(&report, || {
        println!(
            "{}: {frames} frames of {n} vertices at {} fps, {} bits per coordinate, a key frame every {} frames",
            s.name, s.fps, summary.quantiser.bits, opts.key_interval
        );
        println!(
            "stream: {} bytes, {per_frame:.0} bytes per frame ({keys} key frames of {key_mean:.0} bytes, {predicted} predicted of {predicted_mean:.0}), {:.3} Mbps at 30 fps ({:.3} at {} fps)",
            bytes.len(),
            mbps(per_frame, 30.0),
            mbps(per_frame, s.fps),
            s.fps
        );
        println!(
            "error: max {max:.3e} {unit} ({:.4}% of the height {height:.3} {unit}), RMS {rms:.3e} {unit} ({:.4}%)",
            pct(max),
            pct(rms)
        );
        println!(
            "glb morph targets: {} bytes, {glb_per_frame:.0} bytes per frame, {:.3} Mbps at 30 fps: the stream is {:.1}x smaller",
            glb.len(),
            mbps(glb_per_frame, 30.0),
            glb_per_frame / per_frame
        );
        println!("coded in {encode_s:.2} s, decoded in {decode_s:.2} s");
    });
    Ok(())
}
