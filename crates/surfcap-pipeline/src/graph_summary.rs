//! What `surfcap graph build` writes about a graph over the frames (thesis 3.3): its edges as
//! arrays (`edges.npy` u32 `[E, 2]` from, to; `weights.npy` f64 `[E]`) and its numbers
//! (`graph.json`: nodes, frames with edges, original and transition edges, density, the
//! parameters it was built with), for every front end (the command line writes them, Python
//! returns them).

use std::path::Path;

use serde::Serialize;
use surfcap_mesh::Subject;
use surfcap_mesh::npy::write_npy;
use surfcap_motion::dtw::Slope;
use surfcap_motion::edge_weights::{Alpha, EdgeWeights};
use surfcap_motion::graph::Graph;

use crate::error::Result;
use crate::graph_kind::GraphKind;
use crate::pipeline::GraphParams;

/// The files a graph folder holds.
pub const GRAPH_FILES: [&str; 3] = ["edges.npy", "weights.npy", "graph.json"];

/// `graph.json`: a graph's numbers.
#[derive(Debug, Clone, Serialize)]
pub struct GraphSummary {
    pub subject: String,
    pub kind: GraphKind,
    pub alpha: Alpha,
    pub nodes: usize,
    /// Frames with at least one edge out.
    pub frames_in_graph: usize,
    pub edges: usize,
    /// Edges between successive frames of a sequence.
    pub original_edges: usize,
    pub transition_edges: usize,
    pub density: f64,
    pub l_min: usize,
    pub l_max: usize,
    pub slope: Slope,
    /// Time to build or read the graph.
    pub seconds: f64,
    /// Whether it was read from the cache.
    pub cached: bool,
    pub files: [&'static str; 3],
}

impl GraphSummary {
    /// The numbers of `g`, built over `s`'s frames with `p` in `seconds` (`cached`: read from
    /// the cache).
    pub fn of(g: &Graph, s: &Subject, p: &GraphParams, seconds: f64, cached: bool) -> Self {
        let original = g
            .edges()
            .iter()
            .filter(|e| EdgeWeights::is_original(s.frame_index(), e.from as usize, e.to as usize))
            .count();
        GraphSummary {
            subject: s.name.clone(),
            kind: p.kind,
            alpha: p.alpha,
            nodes: g.n,
            frames_in_graph: (0..g.n).filter(|&i| !g.out(i).is_empty()).count(),
            edges: g.edges().len(),
            original_edges: original,
            transition_edges: g.edges().len() - original,
            density: g.density(),
            l_min: p.table.l_min,
            l_max: p.table.l_max,
            slope: p.table.slope,
            seconds,
            cached,
            files: GRAPH_FILES,
        }
    }
}

/// The edges as arrays: `(from, to)` pairs row after row (`[E, 2]`) and their weights (`[E]`),
/// in the graph's edge order (sorted by from, to).
pub fn edge_arrays(g: &Graph) -> (Vec<u32>, Vec<f64>) {
    (g.edges().iter().flat_map(|e| [e.from, e.to]).collect(), g.edges().iter().map(|e| e.weight).collect())
}

/// Writes `edges.npy`, `weights.npy` and `graph.json` into `dir` (each atomically).
pub fn write_graph(dir: &Path, g: &Graph, summary: &GraphSummary) -> Result<()> {
    let (ends, weights) = edge_arrays(g);
    let n = g.edges().len();
    surfcap_mesh::atomic::write_file(&dir.join(GRAPH_FILES[0]), |o| write_npy(o, &[n, 2], &ends))?;
    surfcap_mesh::atomic::write_file(&dir.join(GRAPH_FILES[1]), |o| write_npy(o, &[n], &weights))?;
    surfcap_mesh::atomic::write_file(&dir.join(GRAPH_FILES[2]), |w| {
        serde_json::to_writer_pretty(&mut *w, summary).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(())
}
