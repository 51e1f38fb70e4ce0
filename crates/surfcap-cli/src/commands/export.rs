//! `surfcap export <subject> --format glb|obj|ply|pc2|npy|usda -o <out>`

use std::path::PathBuf;

use anyhow::Context;
use serde_json::json;
use surfcap_formats::export::{ExportFormat, ExportOptions, export};

use crate::options::SubjectArgs;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// glb (one file), obj or ply (a folder of frames per sequence), pc2 (a point cache per
    /// sequence + template.obj), npy (the shared-data layout, re-importable), usda (one USD
    /// text file: a time-sampled mesh per sequence), abc (one Alembic archive: an Xform and a
    /// PolyMesh per sequence).
    #[arg(long)]
    pub format: ExportFormat,
    /// Output file (glb, usda, abc) or folder (the others).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Only these sequences (repeatable; default: all).
    #[arg(long = "sequence")]
    pub sequences: Vec<String>,
    /// Write ascii PLY instead of binary little-endian.
    #[arg(long)]
    pub ascii: bool,
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
    let written = export(&s, a.format, &a.output, ExportOptions { ply_ascii: a.ascii, ..ctx.export_options() }, &bar)
        .with_context(|| format!("exporting {:?}", s.name))?;
    ctx.commit(outs)?;
    ctx.result(&json!({ "written": written, "frames": s.n_frames(), "sequences": s.sequences().len() }), || {
        ctx.wrote(&written)
    });
    Ok(())
}
