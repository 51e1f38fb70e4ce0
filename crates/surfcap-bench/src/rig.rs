//! `surfcap-bench rig`: Smooth Skinning Decomposition with Rigid Bones on a real subject (default
//! the crane, vlasic2008), for each bone count: the decomposition time, the reconstruction error
//! (RMS and max, in the subject's units and % of height) and the skinned glb's size. With
//! `--segment-frames N` it also measures a rig per segment of N frames (HoloEdit's choice) beside
//! one rig for the whole subject: the error, the total size of the segments' files and the time.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_skinning::SsdrOptions;

use crate::measure::FpsOpt;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The subject (default: vlasic2008/crane in $SURFCAP_DATA, else in the shared/data folder
    /// beside the checkout).
    #[arg(long)]
    pub subject: Option<PathBuf>,
    /// Bone counts, comma-separated.
    #[arg(long, default_value = "8,16,32", value_delimiter = ',', value_parser = |s: &str| crate::options::whole_in(s, 1, surfcap_skinning::ssdr::MAX_BONES))]
    pub bones: Vec<usize>,
    #[arg(long, default_value_t = 4, value_parser = |s: &str| crate::options::whole_in(s, 1, surfcap_skinning::ssdr::MAX_INFLUENCES))]
    pub max_influences: usize,
    #[arg(long, default_value_t = 20, value_parser = |s: &str| crate::options::whole_in(s, 0, 1000))]
    pub iterations: usize,
    /// Also rig every segment of this many frames on its own, and compare.
    #[arg(long, value_parser = |s: &str| crate::options::whole_in(s, 2, 1_000_000))]
    pub segment_frames: Option<usize>,
    #[command(flatten)]
    pub fps: FpsOpt,
}

/// The frames `range` of a sequence as a subject of their own.
fn segment(s: &Subject, seq: &Sequence, range: std::ops::Range<usize>) -> anyhow::Result<Subject> {
    let nv = s.topology().n_vertices();
    let pos: Vec<f32> = range.clone().flat_map(|f| seq.frame(f).iter().copied()).collect();
    let name = format!("{}_{}-{}", seq.name, range.start, range.end - 1);
    let part = Sequence::new(name, nv, pos)?;
    Ok(Subject::new(s.name.clone(), s.topology().clone(), vec![part], s.fps, s.up_axis, s.units.clone())?)
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let path = a.subject.clone().unwrap_or_else(|| crate::options::default_data_dir().join("vlasic2008").join("crane"));
    let s = a.fps.open_quietly(&path)?;
    let (nv, nf) = (s.topology().n_vertices(), s.n_frames());
    crate::check_size(ctx, path.display().to_string(), (nf * nv) as f64 * 8.0 * 6.0, 0.0, "the subject's frames")?;
    let unit = s.units.symbol().to_string();
    ctx.say(&format!("{}: {nf} frames of {nv} vertices, {} threads", path.display(), rayon::current_num_threads()));
    let mut rows = Vec::new();
    for &bones in &a.bones {
        let opts =
            SsdrOptions { bones, max_influences: a.max_influences, iterations: a.iterations, ..Default::default() };
        let r = surfcap_synthesis::rig_run::rig_subject(&s, &opts, &NoProgress)?.report;
        ctx.say(&format!(
            "{bones} bones, one rig: decomposition {:.2} s; RMS {:.5} {unit} ({:.3}% of height), max {:.4} {unit} ({:.2}%); {} bytes (morph-target glb {} bytes)",
            r.decomposition_seconds, r.rms, r.rms_percent_of_height, r.max, r.max_percent_of_height, r.bytes, r.morph_glb_bytes
        ));
        let mut row = json!({
            "bones": bones, "rig": "one per subject", "seconds": r.decomposition_seconds, "rms": r.rms,
            "rms_percent_of_height": r.rms_percent_of_height, "max": r.max, "max_percent_of_height": r.max_percent_of_height,
            "bytes": r.bytes, "morph_glb_bytes": r.morph_glb_bytes, "units": unit,
        });
        if let Some(n) = a.segment_frames {
            let t = Instant::now();
            let (mut sq, mut max, mut bytes, mut count, mut segments) = (0.0, 0.0f64, 0u64, 0usize, 0usize);
            for seq in s.sequences() {
                let mut start = 0;
                while start < seq.n_frames() {
                    let end = (start + n).min(seq.n_frames());
                    let sub = segment(&s, seq, start..end)?;
                    let rs = surfcap_synthesis::rig_run::rig_subject(&sub, &opts, &NoProgress)?.report;
                    sq += rs.per_frame.iter().map(|f| f.rms * f.rms).sum::<f64>();
                    max = max.max(rs.max);
                    bytes += rs.bytes;
                    count += rs.per_frame.len();
                    segments += 1;
                    start = end;
                }
            }
            let secs = t.elapsed().as_secs_f64();
            let rms = (sq / count.max(1) as f64).sqrt();
            let pct = 100.0 * rms / r.height;
            ctx.say(&format!(
                "{bones} bones, a rig per {n} frames ({segments} segments): {secs:.2} s in all; RMS {rms:.5} {unit} ({pct:.3}% of height), max {max:.4} {unit}; {bytes} bytes in all"
            ));
            row["segments"] = json!({
                "segment_frames": n, "segments": segments, "seconds": secs, "rms": rms,
                "rms_percent_of_height": pct, "max": max, "bytes": bytes,
            });
        }
        rows.push(row);
    }
    ctx.result(&json!({ "subject": path, "frames": nf, "vertices": nv, "threads": rayon::current_num_threads(), "rows": rows }), || {});
    Ok(())
}
