//! `surfcap info <subject>`

use std::path::PathBuf;

use crate::options::{SourceOpts, open};
use crate::subject_summary::{describe, print_summary};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    #[command(flatten)]
    pub source: SourceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let s = open(ctx, &a.subject, &a.source)?;
    let d = describe(&s);
    ctx.result(&d, || print_summary(&s, &d));
    Ok(())
}
