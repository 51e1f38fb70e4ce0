//! `surfcap export <subject> --format glb|obj|ply|pc2|npy -o <out>`

use std::path::PathBuf;

use anyhow::Context;
use serde_json::json;
use surfcap_mesh::export::{ExportFormat, ExportOptions, export};

use super::{SourceOpts, print_json};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// glb (one file), obj or ply (a folder of frames per sequence), pc2 (a point cache per
    /// sequence + template.obj), npy (the shared-data layout, re-importable).
    #[arg(long, value_parser = parse_format)]
    pub format: ExportFormatArg,
    /// Output file (glb) or folder (the others).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Only these sequences (repeatable; default: all).
    #[arg(long = "sequence")]
    pub sequences: Vec<String>,
    /// Write ascii PLY instead of binary little-endian.
    #[arg(long)]
    pub ascii: bool,
    #[command(flatten)]
    pub source: SourceOpts,
}

#[derive(Debug, Clone, Copy)]
pub struct ExportFormatArg(pub ExportFormat);

fn parse_format(s: &str) -> Result<ExportFormatArg, String> {
    ExportFormat::parse(s).map(ExportFormatArg).ok_or_else(|| format!("{s:?}: expected glb, obj, ply, pc2 or npy"))
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let s = super::open(ctx, &a.subject, &a.source)?.select(&a.sequences)?;
    let bar = crate::progress::Bar::new(ctx);
    let written = export(&s, a.format.0, &a.output, ExportOptions { ply_ascii: a.ascii }, &bar)
        .with_context(|| format!("exporting {:?}", s.name))?;
    if ctx.json {
        print_json(&json!({ "written": written, "frames": s.n_frames(), "sequences": s.sequences().len() }));
    } else {
        for w in &written {
            println!("wrote {}", w.display());
        }
    }
    Ok(())
}
