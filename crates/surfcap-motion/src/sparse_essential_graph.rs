//! The sparse essential graph: thesis 3.3.1's essential graph (the union of
//! the shortest-path trees of every node) built on a sparse digraph instead of the complete
//! one, so that it scales to hours of capture.
//!
//! 1. Per frame, its `k` cheapest transitions of Algorithm 1's weights plus the original edge to
//!    the next frame ([`cheapest_transitions`]), from one row of weights at a time
//!    ([`edge_weight_row`](crate::edge_weights::edge_weight_row) makes a row from a row of the
//!    transition table): the N x N matrix is never needed, so the rows can come from tiles read
//!    row-block by row-block. E <= N (k + 1) edges.
//! 2. One heap Dijkstra per source on that graph ([`sparse_shortest_paths`], O(E + V log V)
//!    each, O(V (E + V log V)) in all instead of the dense build's O(V^3)), sources in parallel,
//!    and tileable by source rows: rows 0..500 in one process and 500..1000 in another give the
//!    same rows as one run.
//! 3. The union of the trees' (predecessor, node) edges ([`essential_from_trees`], streaming over
//!    the rows, memory O(E)).
//!
//! Ties are decided as in [`crate::essential_graph`]: among equal distances the node of smaller
//! index is settled first, and a predecessor is replaced only by a strictly cheaper path; the
//! k cheapest edges break equal weights by the lower destination. So the result does not depend
//! on the number of threads, and with k >= N - 1 (every finite edge kept) the graph and the costs
//! are bit-identical to the exact build's (same sums in the same settling order). With a smaller
//! k a shortest path may need a dropped edge: costs can only rise, and `surfcap eval
//! sparse-graph` measures by how much.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::Range;

use rayon::prelude::*;
use surfcap_mesh::{FrameIndex, Progress};

use crate::edge_weights::EdgeWeights;
use crate::error::{Error, Result};
use crate::essential_graph::EssentialGraph;
use crate::graph::{Cost, Edge, Graph};

/// No predecessor (the source, and nodes it does not reach).
pub const NO_PRED: u32 = u32::MAX;

/// The k the CLI and the pipeline use by default, chosen by `surfcap eval sparse-graph`
/// on the mannequin moved by every CMU clip at 50 fps (1,878 frames, alpha 0.05).
/// Our rule (the smallest k with at least 99% of the all-pairs shortest-path costs
/// within 1% of the exact graph's and no query more than 1% worse) is met by no k up to 512:
/// there the exact graph keeps about 300 transitions per frame, as most pairs' cheapest path is
/// their own direct transition, so dropping transitions raises most pair costs (within 1%: 16%
/// of the pairs at k = 16, 28% at 64, 79% at 512; mean ratio 2.13, 1.46, 1.04). What the
/// queries need comes much earlier: from k = 16 every key pose keeps its time to the frame and
/// path following its curve within a centimetre of the exact graph's error, with no pair made
/// unreachable; k = 64 is the smallest measured k that also keeps every key pose's realism cost
/// within 1.5 times the exact graph's (at most 1.43x; 2.6x at k = 16). Hence 64: about 41
/// essential edges per frame instead of 302, built in 1.9 s instead of 13 s there. The exact
/// graph stays the default kind wherever it is feasible.
pub const DEFAULT_K: usize = 64;

/// Frame `i`'s edges of the sparse graph from `row`, row `i` of Algorithm 1's weights
/// (`EdgeWeights::weight[i * n..(i + 1) * n]`, infinity where there is no edge): its `k`
/// cheapest finite edges (equal weights: the lower destination first) plus the original edge
/// `i -> i + 1` when `i + 1` follows `i` in its sequence (never twice). Sorted by destination.
///
/// # Panics
/// When `row` is not `index.len()` long (a caller's mistake).
pub fn cheapest_transitions(row: &[f64], i: usize, index: &FrameIndex, k: usize) -> Vec<Edge> {
    assert_eq!(row.len(), index.len(), "a row of weights has one entry per frame");
    let edge = |j: usize| Edge { from: i as u32, to: j as u32, weight: row[j] };
    let mut finite: Vec<usize> = (0..row.len()).filter(|&j| j != i && row[j].is_finite()).collect();
    let order = |a: &usize, b: &usize| row[*a].total_cmp(&row[*b]).then(a.cmp(b));
    if finite.len() > k {
        if k == 0 {
            finite.clear();
        } else {
            finite.select_nth_unstable_by(k - 1, order);
            finite.truncate(k);
        }
    }
    let next = i + 1;
    if next < row.len() && EdgeWeights::is_original(index, i, next) && row[next].is_finite() && !finite.contains(&next)
    {
        finite.push(next);
    }
    finite.sort_unstable();
    finite.into_iter().map(edge).collect()
}

/// The sparse graph of `w`: every frame's [`cheapest_transitions`] (rows in parallel).
pub fn sparse_transition_graph(w: &EdgeWeights, index: &FrameIndex, k: usize) -> Graph {
    let n = w.n;
    let edges: Vec<Edge> = (0..n)
        .into_par_iter()
        .flat_map_iter(|i| cheapest_transitions(&w.weight[i * n..(i + 1) * n], i, index, k))
        .collect();
    Graph::new(n, edges)
}

/// Shortest-path rows of some sources: `costs[r * n + v]` and `preds[r * n + v]` for source
/// `sources.start + r` (infinity and [`NO_PRED`] where `v` is unreachable; the source has cost 0
/// and no predecessor).
#[derive(Debug, Clone, PartialEq)]
pub struct SourceRows {
    pub sources: Range<usize>,
    pub n: usize,
    pub costs: Vec<f64>,
    pub preds: Vec<u32>,
}

impl SourceRows {
    /// The predecessor row of every source, with its source.
    pub fn pred_rows(&self) -> impl Iterator<Item = (usize, &[u32])> {
        self.sources.clone().zip(self.preds.chunks_exact(self.n.max(1)))
    }
}

/// Heap Dijkstra from `source` on `graph` into `dist` and `pred` (settling order: distance, then
/// index; a predecessor replaced only by a strictly cheaper path).
fn heap_dijkstra(graph: &Graph, source: usize, dist: &mut [f64], pred: &mut [u32], done: &mut [bool]) {
    dist.fill(f64::INFINITY);
    pred.fill(NO_PRED);
    done.fill(false);
    dist[source] = 0.0;
    let mut heap = BinaryHeap::new();
    heap.push(Reverse((Cost(0.0), source)));
    while let Some(Reverse((Cost(d), u))) = heap.pop() {
        if done[u] || d > dist[u] {
            continue;
        }
        done[u] = true;
        for e in graph.out(u) {
            let v = e.to as usize;
            if done[v] {
                continue;
            }
            let nd = d + e.weight;
            if nd < dist[v] {
                dist[v] = nd;
                pred[v] = u as u32;
                heap.push(Reverse((Cost(nd), v)));
            }
        }
    }
}

/// Shortest paths from each source in `sources` (a range of `0..graph.n`), one heap Dijkstra
/// per source, sources in parallel; the rows do not depend on the thread count nor on which
/// other sources are computed with them.
///
/// # Panics
/// When `sources` reaches past the graph's nodes (a caller's mistake).
pub fn sparse_shortest_paths(graph: &Graph, sources: Range<usize>, progress: &dyn Progress) -> SourceRows {
    let n = graph.n;
    assert!(sources.start <= sources.end && sources.end <= n, "sources {sources:?} of a {n}-node graph");
    let rows = sources.len();
    let mut costs = vec![f64::INFINITY; rows * n];
    let mut preds = vec![NO_PRED; rows * n];
    progress.start("sparse shortest paths", rows as u64);
    if n > 0 {
        costs.par_chunks_mut(n).zip(preds.par_chunks_mut(n)).enumerate().for_each_init(
            || vec![false; n],
            |done, (r, (dist, pred))| {
                heap_dijkstra(graph, sources.start + r, dist, pred, done);
                progress.advance(1);
            },
        );
    }
    progress.finish();
    SourceRows { sources, n, costs, preds }
}

/// The union of shortest-path trees of `graph` (each `(source, predecessors)` row as
/// [`sparse_shortest_paths`] gives them, in any order and from any number of tiles): every edge
/// `pred -> node` with its weight in `graph`. Memory O(E) whatever the number of rows.
pub fn essential_from_trees<'a>(graph: &Graph, rows: impl IntoIterator<Item = (usize, &'a [u32])>) -> Result<Graph> {
    let n = graph.n;
    let mut kept = vec![false; graph.edges().len()];
    for (source, pred) in rows {
        if pred.len() != n {
            return Err(Error::TreeRowSize { root: source, len: pred.len(), frames: n });
        }
        for (node, &p) in pred.iter().enumerate() {
            if p == NO_PRED {
                continue;
            }
            let k = graph.find(p as usize, node).ok_or(Error::TreeEdgeMissing { root: source, pred: p, node })?;
            kept[k] = true;
        }
    }
    let edges = graph.edges().iter().zip(&kept).filter(|(_, k)| **k).map(|(e, _)| *e).collect();
    Ok(Graph::new(n, edges))
}

/// The sparse essential graph of `w` held in memory (all N x N costs): the sparse graph of
/// every frame's `k` cheapest transitions plus the original edges, the shortest paths from
/// every source on it, and the union of their trees. For subjects too large for N x N rows,
/// call the three steps on row tiles.
pub fn sparse_essential_graph(
    w: &EdgeWeights,
    index: &FrameIndex,
    k: usize,
    progress: &dyn Progress,
) -> EssentialGraph {
    let sparse = sparse_transition_graph(w, index, k);
    let rows = sparse_shortest_paths(&sparse, 0..w.n, progress);
    let graph = essential_from_trees(&sparse, rows.pred_rows()).expect("the trees of this graph use its edges");
    EssentialGraph { graph, costs: rows.costs }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edge_weights::Alpha;
    use crate::essential_graph::essential_graph;
    use surfcap_mesh::NoProgress;

    /// Algorithm 1-like weights on sequences of `counts` frames: originals alpha, transitions
    /// pseudo-random in [0.1, 1.1), some missing, a few exact ties.
    fn weights(counts: &[usize], seed: u64) -> (EdgeWeights, FrameIndex) {
        let index = FrameIndex::new(counts.iter().copied());
        let n = index.len();
        let mut x = seed;
        let mut weight = vec![f64::INFINITY; n * n];
        for i in 0..n {
            for j in 0..n {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let r = (x >> 11) as f64 / (1u64 << 53) as f64;
                weight[i * n + j] = if i == j {
                    f64::INFINITY
                } else if EdgeWeights::is_original(&index, i, j) {
                    0.05
                } else if r < 0.1 {
                    f64::INFINITY
                } else if r < 0.2 {
                    0.5 // ties
                } else {
                    0.1 + r
                };
            }
        }
        (EdgeWeights { n, alpha: Alpha::new(0.05).unwrap(), d_scale: 1.0, weight }, index)
    }

    #[test]
    fn cheapest_transitions_keep_k_plus_the_original_edge() {
        let index = FrameIndex::new([3, 3]);
        let inf = f64::INFINITY;
        // Row of frame 1: 0.05 to 2 (original), ties at 0.3 to 0 and 4, then 0.2 to 5.
        let row = [0.3, inf, 0.05, 0.4, 0.3, 0.2];
        let to = |k| cheapest_transitions(&row, 1, &index, k).iter().map(|e| e.to).collect::<Vec<_>>();
        assert_eq!(to(0), vec![2], "the original edge always");
        assert_eq!(to(1), vec![2], "the cheapest is the original: not twice");
        assert_eq!(to(2), vec![2, 5]);
        assert_eq!(to(3), vec![0, 2, 5], "tie at 0.3: the lower destination");
        assert_eq!(to(4), vec![0, 2, 4, 5]);
        assert_eq!(to(10), vec![0, 2, 3, 4, 5], "only finite edges");
        let e = cheapest_transitions(&row, 1, &index, 1);
        assert_eq!(e, vec![Edge { from: 1, to: 2, weight: 0.05 }]);
        // The last frame of a sequence has no original edge to the next sequence's first.
        let row2 = [0.3, 0.2, inf, 0.9, 0.1, 0.2];
        let e = cheapest_transitions(&row2, 2, &index, 1);
        assert_eq!(e.iter().map(|e| e.to).collect::<Vec<_>>(), vec![4]);
    }

    #[test]
    fn with_every_edge_kept_it_is_the_exact_essential_graph_bit_for_bit() {
        for (counts, seed) in [(vec![7, 5, 9], 1u64), (vec![12, 1, 6, 4], 7), (vec![20], 3)] {
            let (w, index) = weights(&counts, seed);
            let exact = essential_graph(&w, &NoProgress);
            let sparse = sparse_essential_graph(&w, &index, w.n - 1, &NoProgress);
            assert_eq!(sparse.graph, exact.graph, "{counts:?}");
            assert!(sparse.costs.iter().zip(&exact.costs).all(|(a, b)| a.to_bits() == b.to_bits()), "{counts:?}");
        }
    }

    #[test]
    fn with_few_edges_costs_only_rise_and_every_path_stays_in_the_sparse_graph() {
        let (w, index) = weights(&[10, 8, 12], 11);
        let n = w.n;
        let exact = essential_graph(&w, &NoProgress);
        let mut lost = 0;
        for k in [0, 1, 2, 4] {
            let s = sparse_essential_graph(&w, &index, k, &NoProgress);
            assert!(s.costs.iter().zip(&exact.costs).all(|(s, e)| s >= e), "k = {k}");
            lost += s.costs.iter().zip(&exact.costs).filter(|(s, e)| s > e).count();
            // The essential graph keeps every cost of the sparse graph it came from.
            let sparse = sparse_transition_graph(&w, &index, k);
            assert!(s.graph.edges().len() <= sparse.edges().len());
            assert!(s.graph.edges().iter().all(|e| sparse.find(e.from as usize, e.to as usize).is_some()));
            for src in 0..n {
                assert_eq!(s.graph.shortest_paths_from(src), &s.costs[src * n..(src + 1) * n]);
            }
        }
        assert!(lost > 0, "small k loses some shortest paths on this graph");
    }

    #[test]
    fn the_same_whatever_the_thread_count_and_row_tiles_union_to_one_run() {
        let (w, index) = weights(&[15, 9, 11, 5], 5);
        let n = w.n;
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let g = sparse_transition_graph(&w, &index, 3);
                (
                    g.clone(),
                    sparse_shortest_paths(&g, 0..n, &NoProgress),
                    sparse_essential_graph(&w, &index, 3, &NoProgress),
                )
            })
        };
        let (g1, rows1, e1) = run(1);
        let (g2, rows2, e2) = run(2);
        assert_eq!(g1, g2);
        assert_eq!(rows1, rows2);
        assert_eq!(e1.graph, e2.graph);
        assert_eq!(e1.costs, e2.costs);
        // Tiles of source rows, computed apart (in another order) and unioned.
        let tiles: Vec<SourceRows> =
            [17..n, 0..9, 9..17].into_iter().map(|r| sparse_shortest_paths(&g1, r, &NoProgress)).collect();
        let mut costs = vec![0.0; n * n];
        for t in &tiles {
            costs[t.sources.start * n..t.sources.end * n].copy_from_slice(&t.costs);
        }
        assert_eq!(costs, rows1.costs);
        let unioned = essential_from_trees(&g1, tiles.iter().flat_map(|t| t.pred_rows())).unwrap();
        assert_eq!(unioned, e1.graph);
    }

    #[test]
    fn trees_of_another_graph_are_refused() {
        let (w, index) = weights(&[6, 6], 2);
        let small = sparse_transition_graph(&w, &index, 0);
        let full = sparse_transition_graph(&w, &index, w.n);
        let rows = sparse_shortest_paths(&full, 0..w.n, &NoProgress);
        let err = essential_from_trees(&small, rows.pred_rows()).unwrap_err();
        assert!(matches!(err, Error::TreeEdgeMissing { .. }), "{err}");
        let short = vec![NO_PRED; 3];
        let err = essential_from_trees(&small, [(0, short.as_slice())]).unwrap_err();
        assert!(err.to_string().contains("3 predecessors, expected 12"), "{err}");
    }
}
