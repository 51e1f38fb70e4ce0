//! `surfcap report <subject> -o dir/ --include ...`: one static HTML page of what exists for a
//! subject (`crate::html_report` writes it).

use std::path::PathBuf;

use serde_json::json;

use crate::html_report::write_report;
use crate::options::{CacheOpts, SourceOpts, open};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// Output folder (index.html, plots/, anim/, data/).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Evaluation folders or files to add: .json (tables), .svg/.png (plots), .glb (animations,
    /// with their .report.json); folders are searched for all of these.
    #[arg(long, value_delimiter = ',')]
    pub include: Vec<PathBuf>,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let mut inputs = vec![a.subject.as_path()];
    inputs.extend(a.include.iter().map(|p| p.as_path()));
    surfcap_mesh::output_path::check_not_input(&a.output, &inputs)?;
    let s = open(ctx, &a.subject, &a.source)?;
    let pipe = a.cache.pipeline(ctx, s);
    let w = write_report(&pipe, &a.subject, &a.output, &a.include, ctx.force)?;
    let result = json!({ "index": w.index, "plots": w.plots, "animations": w.animations, "tables": w.tables });
    ctx.result(&result, || {
        println!(
            "wrote {} ({} plots, {} tables, {} animations); open it in a browser, or play its animations with: surfcap view {}",
            w.index.display(),
            w.plots,
            w.tables,
            w.animations,
            a.output.display()
        )
    });
    Ok(())
}
