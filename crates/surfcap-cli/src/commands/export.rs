//! `surfcap export <subject> --format glb|obj|ply|pc2|npy|usda|abc|stream -o <out>`

use std::path::PathBuf;

use anyhow::Context;
use serde_json::json;
use surfcap_formats::export::{ExportFormat, ExportOptions, export};

use crate::options::SubjectArgs;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// glb (one file), obj or ply (a folder of frames per sequence), pc2 (a point cache per
    /// sequence + template.obj), npy (the shared-data layout, re-importable), usda (one USD
    /// text file: a time-sampled mesh per sequence), usdc (the same stage in USD's binary crate
    /// format), abc (one Alembic archive: an Xform and a
    /// PolyMesh per sequence), stream (one .scstream file: quantised, predicted and deflated
    /// positions, a few bytes per vertex per frame; see --stream-bits).
    #[arg(long)]
    pub format: ExportFormat,
    /// Output file (glb, usda, usdc, abc, stream) or folder (the others).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Only these sequences (repeatable; default: all).
    #[arg(long = "sequence")]
    pub sequences: Vec<String>,
    /// Write ascii PLY instead of binary little-endian.
    #[arg(long)]
    pub ascii: bool,
    // ---- stream: the compact stream's coding ----
    /// stream: bits per coordinate on the grid over the animation's bounding box (4 to 30);
    /// more bits, smaller error and larger stream.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(4..=30))]
    pub stream_bits: u32,
    /// stream: instead of --stream-bits, the largest vertex error allowed, in % of the subject's
    /// height (its first frame's extent along the up axis): the fewest bits meeting it.
    #[arg(long, value_name = "PERCENT")]
    pub stream_error: Option<f64>,
    /// stream: a key frame (decodable on its own, for seeking) every this many frames of a
    /// sequence, and at its start.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u64).range(1..))]
    pub stream_key_interval: u64,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    // Every output (the file and its sidecar, or the folder) planned before any work.
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&[&a.subject.path]);
    surfcap_formats::export::plan_export(&mut outs, a.format, &a.output, ctx.force)?;
    // A frame set (every frame its own topology) goes to the formats that hold that: abc, obj.
    if surfcap_mesh::frame_set_cache::is_frame_set(&a.subject.path) {
        if !a.sequences.is_empty() {
            anyhow::bail!("--sequence: a frame set is exported whole");
        }
        let bar = crate::progress::Bar::new(ctx);
        let set = surfcap_mesh::frame_set_cache::read_frame_set(&a.subject.path, &bar)?;
        let written = surfcap_formats::export::export_frame_set(&set, a.format, &a.output, ctx.export_options(), &bar)
            .with_context(|| format!("exporting {:?}", set.name))?;
        ctx.commit(outs)?;
        ctx.result(
            &json!({ "written": written, "frames": set.frame_count(), "sequences": set.sequences().len() }),
            || ctx.wrote(&written),
        );
        return Ok(());
    }
    let s = a.subject.open(ctx)?.select(&a.sequences)?;
    let bar = crate::progress::Bar::new(ctx);
    // ---- stream: the compact stream with its options ----
    if a.format == ExportFormat::Stream {
        let opts = stream_options(&s, a.stream_bits, a.stream_error, a.stream_key_interval)?;
        let written = surfcap_formats::export::export_stream(&s, &a.output, &opts, &bar)
            .with_context(|| format!("exporting {:?}", s.name))?;
        ctx.commit(outs)?;
        ctx.result(&json!({ "written": written, "frames": s.n_frames(), "sequences": s.sequences().len() }), || {
            ctx.wrote(&written)
        });
        return Ok(());
    }
    let written = export(&s, a.format, &a.output, ExportOptions { ply_ascii: a.ascii, ..ctx.export_options() }, &bar)
        .with_context(|| format!("exporting {:?}", s.name))?;
    ctx.commit(outs)?;
    ctx.result(&json!({ "written": written, "frames": s.n_frames(), "sequences": s.sequences().len() }), || {
        ctx.wrote(&written)
    });
    Ok(())
}

/// The stream's coding from the command's options: `error` (% of the subject's height) turned
/// into the subject's units.
pub fn stream_options(
    s: &surfcap_mesh::Subject,
    bits: u32,
    error: Option<f64>,
    key_interval: u64,
) -> anyhow::Result<surfcap_formats::stream::StreamOptions> {
    let max_error = match error {
        None => None,
        Some(e) if !(e.is_finite() && e > 0.0) => {
            anyhow::bail!("--stream-error {e}: expected a percentage of the height above 0")
        }
        Some(e) => {
            let h = surfcap_eval::variation_eval::subject_height(s.sequences()[0].frame(0), s.up_axis);
            if h <= 0.0 {
                anyhow::bail!(
                    "--stream-error: the subject's first frame is flat along its up axis: give --stream-bits"
                );
            }
            Some(e / 100.0 * h)
        }
    };
    Ok(surfcap_formats::stream::StreamOptions { bits, max_error, key_interval: key_interval as usize })
}
