//! `surfcap graph build <subject> --kind essential|sparse-essential|motion --alpha A`: the essential graph (exact or sparse) or
//! the motion-graph baseline over a subject's frames (thesis 3.3), cached.

use std::path::PathBuf;
use std::time::Instant;

use surfcap_pipeline::{GraphSummary, write_graph};

use crate::options::{GraphOpts, open};
use crate::output::count_of;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Build a graph over all frames and write edges.npy (u32 [E, 2]), weights.npy (f64 [E])
    /// and graph.json (density, edge counts).
    Build {
        /// A subject cache, or any source `surfcap import` reads.
        subject: PathBuf,
        /// Output folder.
        #[arg(short, long, default_value = "graph")]
        output: PathBuf,
        #[command(flatten)]
        graph: GraphOpts,
    },
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let What::Build { subject, output, graph } = a.what;
    let (outs, output) = ctx.claim_dir(&output, "graph", &[&subject])?;
    let s = open(ctx, &subject, &graph.source)?;
    let pipe = graph.cache.pipeline(ctx, s)?;
    let p = graph.params_for(&pipe)?;
    let t0 = Instant::now();
    let fetched = pipe.graph(&p)?;
    let secs = t0.elapsed().as_secs_f64();
    let (g, s) = (&fetched.value, pipe.subject());
    let report = GraphSummary::of(g, s, &p, secs, fetched.from_cache);
    write_graph(&output, g, &report)?;
    ctx.commit(outs)?;
    let (alpha, frames_in_graph, original) = (p.alpha, report.frames_in_graph, report.original_edges);
    ctx.result(&report, || {
        println!(
            "{} graph of {:?}, alpha {alpha}: {} ({frames_in_graph} with edges), {} ({original} original, {}), density {:.5} -> {} ({}, {secs:.2} s)",
            p.kind,
            s.name,
            count_of(g.n, "frame"),
            count_of(g.edges().len(), "edge"),
            count_of(report.transition_edges, "transition"),
            g.density(),
            output.display(),
            if fetched.from_cache { "from cache" } else { "computed" }
        )
    });
    Ok(())
}
