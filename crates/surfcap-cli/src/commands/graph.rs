//! `surfcap graph build <subject> --kind essential|sparse-essential|motion --alpha A`: the essential graph (exact or sparse) or
//! the motion-graph baseline over a subject's frames (thesis 3.3), cached.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_mesh::Subject;
use surfcap_mesh::npy::write_npy;
use surfcap_motion::edge_weights::EdgeWeights;
use surfcap_motion::graph::Graph;

use crate::options::{GraphOpts, open};
use crate::output::{count_of, write_json};

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

/// Counts of original (successive-frame) and transition edges.
fn edge_kinds(g: &Graph, s: &Subject) -> (usize, usize) {
    let original =
        g.edges().iter().filter(|e| EdgeWeights::is_original(s.frame_index(), e.from as usize, e.to as usize)).count();
    (original, g.edges().len() - original)
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
    let (original, transitions) = edge_kinds(g, s);
    let ends: Vec<u32> = g.edges().iter().flat_map(|e| [e.from, e.to]).collect();
    let weights: Vec<f64> = g.edges().iter().map(|e| e.weight).collect();
    surfcap_mesh::atomic::write_file(&output.join("edges.npy"), |o| write_npy(o, &[g.edges().len(), 2], &ends))?;
    surfcap_mesh::atomic::write_file(&output.join("weights.npy"), |o| write_npy(o, &[g.edges().len()], &weights))?;
    let frames_in_graph = (0..g.n).filter(|&i| !g.out(i).is_empty()).count();
    let alpha = p.alpha;
    let report = json!({
        "subject": s.name, "kind": p.kind, "alpha": alpha, "nodes": g.n, "frames_in_graph": frames_in_graph,
        "edges": g.edges().len(), "original_edges": original, "transition_edges": transitions,
        "density": g.density(), "l_min": p.table.l_min, "l_max": p.table.l_max, "slope": p.table.slope,
        "seconds": secs, "cached": fetched.from_cache, "files": ["edges.npy", "weights.npy", "graph.json"],
    });
    write_json(&output.join("graph.json"), &report)?;
    ctx.commit(outs)?;
    ctx.result(&report, || {
        println!(
            "{} graph of {:?}, alpha {alpha}: {} ({frames_in_graph} with edges), {} ({original} original, {}), density {:.5} -> {} ({}, {secs:.2} s)",
            p.kind,
            s.name,
            count_of(g.n, "frame"),
            count_of(g.edges().len(), "edge"),
            count_of(transitions, "transition"),
            g.density(),
            output.display(),
            if fetched.from_cache { "from cache" } else { "computed" }
        )
    });
    Ok(())
}
