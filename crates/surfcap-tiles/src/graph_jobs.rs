//! The jobs of the sparse essential graph's stages
//! (`surfcap_motion::sparse_essential_graph`), by blocks of source rows:
//! - `candidates`: rows i of Algorithm 1's weights made from rows of the table (D / median + alpha
//!   L), a looping clip's wrap edge (its last frame into its start, found by the `scale` stage)
//!   weighted as a successive step, each frame's k cheapest transitions plus its original edge
//!   (`candidates/edges_<b>.npy`);
//! - `paths`: the sparse graph assembled from every block's candidates (E <= N (k + 1) edges),
//!   one Dijkstra per source of the block; the costs into `paths/costs.zarr`, the trees' edges
//!   into `paths/tree_<b>.npy`.
//!
//! The merge takes the union of the trees: the graph equals the in-memory
//! `sparse_essential_graph` of the same weights (same rows, same ties).

use surfcap_mesh::Progress;
use surfcap_mesh::cache::CachedFrames;
use surfcap_mesh::npy::{read_npy, write_npy};
use surfcap_motion::edge_weights::edge_weight_row;
use surfcap_motion::graph::{Edge, Graph};
use surfcap_motion::sparse_essential_graph::{NO_PRED, cheapest_transitions, sparse_shortest_paths};

use crate::error::{Error, Result};
use crate::tile_jobs::{JobResult, frames_text, read_scale};
use crate::tile_plan::{Plan, Stage};
use crate::tile_store::{Matrix, OutputHash, Store};

/// The file of `candidates` job `block`'s edges.
pub fn edges_file(block: usize) -> String {
    format!("candidates/edges_{block}.npy")
}

/// The file of `paths` job `block`'s tree edges.
pub fn tree_file(block: usize) -> String {
    format!("paths/tree_{block}.npy")
}

/// Runs job `index` of the `candidates` or `paths` stage.
pub fn run(
    store: &Store,
    plan: &Plan,
    subject: &CachedFrames,
    stage: Stage,
    index: usize,
    progress: &dyn Progress,
) -> Result<JobResult> {
    let text = format!("sources {}", frames_text(subject, &plan.row_block(index)));
    let (details, outputs) = match stage {
        Stage::Candidates => candidates(store, plan, subject, index)?,
        Stage::Paths => paths(store, plan, index, progress)?,
        _ => return Err(Error::Job(format!("stage {}: not a graph stage", stage.name()))),
    };
    Ok((text, String::new(), details, outputs))
}

fn candidates(
    store: &Store,
    plan: &Plan,
    subject: &CachedFrames,
    block: usize,
) -> Result<(serde_json::Value, Vec<OutputHash>)> {
    let n = plan.frames();
    let rows = plan.row_block(block);
    let scale = read_scale(store)?;
    if let Some(w) = scale.wrap_edges.iter().find(|w| w.last as usize >= n || w.first as usize >= n) {
        return Err(Error::Job(format!(
            "{}: wrap edge {} -> {}: expected frames below {n}",
            store.file(crate::tile_jobs::SCALE_FILE).display(),
            w.last,
            w.first
        )));
    }
    let cost = store.read_f64(Matrix::TableCost, rows.clone(), 0..n)?;
    let len = store.read_u32(Matrix::TableLen, rows.clone(), 0..n)?;
    let mut w = vec![0.0; n];
    let mut flat = Vec::new();
    let mut edges = 0usize;
    for (r, i) in rows.enumerate() {
        let (c, l) = (&cost[r * n..(r + 1) * n], &len[r * n..(r + 1) * n]);
        if let Some(j) = c.iter().position(|x| x.is_nan() || *x < 0.0) {
            return Err(Error::Job(format!(
                "transition cost ({}, {}) is {}: expected a cost >= 0 or inf",
                subject.index.label(i),
                subject.index.label(j),
                c[j]
            )));
        }
        edge_weight_row(c, l, i, &subject.index, plan.params.alpha, scale.d_scale, &mut w);
        // A looping clip plays its last frame into its start as a successive step
        // (`surfcap_motion::clip_loops::add_wrap_edges`, as the one-machine graph's weights).
        for wrap in scale.wrap_edges.iter().filter(|w| w.last as usize == i) {
            w[wrap.first as usize] = plan.params.alpha.get();
        }
        for e in cheapest_transitions(&w, i, &subject.index, plan.params.k) {
            flat.extend([e.from as f64, e.to as f64, e.weight]);
            edges += 1;
        }
    }
    let mut bytes = Vec::new();
    write_npy(&mut bytes, &[edges, 3], &flat)
        .map_err(|e| surfcap_mesh::Error::io(&store.file(&edges_file(block)), "encode", e))?;
    let out = store.write_file(&edges_file(block), &bytes)?;
    Ok((serde_json::json!({ "edges": edges }), vec![out]))
}

/// The sparse graph from every block's candidates.
pub fn sparse_graph(store: &Store, plan: &Plan) -> Result<Graph> {
    let n = plan.frames();
    let mut edges = Vec::new();
    for b in 0..plan.jobs(Stage::Candidates) {
        let p = store.file(&edges_file(b));
        if !p.is_file() {
            return Err(Error::Job(format!("{}: missing: run the candidates stage's job {b} first", p.display())));
        }
        let a = read_npy::<f64>(&p)?;
        for e in a.data.chunks_exact(3) {
            let frame = |x: f64| (x >= 0.0 && x.fract() == 0.0 && x < n as f64).then_some(x as usize);
            let (Some(from), Some(to), true) = (frame(e[0]), frame(e[1]), e[2] >= 0.0) else {
                return Err(Error::Job(format!(
                    "{}: edge {} -> {} of weight {}: expected frames 0..{n} and a weight >= 0",
                    p.display(),
                    e[0],
                    e[1],
                    e[2]
                )));
            };
            edges.push(Edge { from: from as u32, to: to as u32, weight: e[2] });
        }
    }
    Ok(Graph::new(n, edges))
}

fn paths(
    store: &Store,
    plan: &Plan,
    block: usize,
    progress: &dyn Progress,
) -> Result<(serde_json::Value, Vec<OutputHash>)> {
    let n = plan.frames();
    let graph = sparse_graph(store, plan)?;
    let rows = plan.row_block(block);
    let sp = sparse_shortest_paths(&graph, rows.clone(), progress);
    let t = plan.tile;
    let mut outputs = Vec::new();
    for cj in 0..n.div_ceil(t) {
        let cols = cj * t..((cj + 1) * t).min(n);
        let values: Vec<f64> =
            (0..rows.len()).flat_map(|r| sp.costs[r * n + cols.start..r * n + cols.end].iter().copied()).collect();
        outputs.push(store.write_chunk_f64(Matrix::PathCosts, block, cj, rows.len(), cols.len(), &values)?);
    }
    let mut tree: Vec<(u32, u32)> = sp
        .pred_rows()
        .flat_map(|(_, pred)| pred.iter().enumerate().filter(|(_, p)| **p != NO_PRED).map(|(v, &p)| (p, v as u32)))
        .collect();
    tree.sort_unstable();
    tree.dedup();
    let flat: Vec<u32> = tree.iter().flat_map(|&(a, b)| [a, b]).collect();
    let mut bytes = Vec::new();
    write_npy(&mut bytes, &[tree.len(), 2], &flat)
        .map_err(|e| surfcap_mesh::Error::io(&store.file(&tree_file(block)), "encode", e))?;
    outputs.push(store.write_file(&tree_file(block), &bytes)?);
    let unreachable = sp.costs.iter().filter(|c| c.is_infinite()).count();
    Ok((
        serde_json::json!({ "graph_edges": graph.edges().len(), "tree_edges": tree.len(), "unreachable_pairs": unreachable }),
        outputs,
    ))
}

/// The sparse essential graph: the union of every block's tree edges, weighted as in the sparse
/// graph.
pub fn merged_graph(store: &Store, plan: &Plan) -> Result<Graph> {
    let graph = sparse_graph(store, plan)?;
    let mut kept = vec![false; graph.edges().len()];
    for b in 0..plan.jobs(Stage::Paths) {
        let p = store.file(&tree_file(b));
        let a = read_npy::<u32>(&p)?;
        for e in a.data.chunks_exact(2) {
            let k = graph.find(e[0] as usize, e[1] as usize).ok_or_else(|| {
                Error::Job(format!(
                    "{}: tree edge {} -> {} is not an edge of the sparse graph",
                    p.display(),
                    e[0],
                    e[1]
                ))
            })?;
            kept[k] = true;
        }
    }
    let edges = graph.edges().iter().zip(&kept).filter(|(_, k)| **k).map(|(e, _)| *e).collect();
    Ok(Graph::new(plan.frames(), edges))
}
