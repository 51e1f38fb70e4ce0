//! `surfcap report <subject> -o dir/ --include ...`: one static HTML page of what exists for a
//! subject (`crate::html_report` writes it).

use std::path::PathBuf;

use serde_json::json;

use crate::html_report::write_report;
use crate::options::{CacheOpts, SubjectArgs};

#[derive(clap::Args, Debug)]
pub struct Args {
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
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let mut inputs = vec![a.subject.path.as_path()];
    inputs.extend(a.include.iter().map(|p| p.as_path()));
    // The report folder is built in its temporary and replaces the output whole at the end.
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&inputs);
    outs.dir(&a.output, "report", ctx.force || crate::html_report::is_earlier_report(&a.output))?;
    let s = a.subject.open(ctx)?;
    let pipe = a.cache.pipeline(ctx, s)?;
    let w = write_report(&pipe, &a.subject.path, &a.output, &a.include, ctx.force)?;
    ctx.commit(outs)?;
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
