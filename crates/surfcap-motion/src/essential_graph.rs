//! The essential graph (thesis 3.3.1): the union of the shortest-path trees rooted at every
//! node of the complete digraph whose edge weights are those of Algorithm 1. Every pair of
//! frames keeps a path as cheap as in the complete digraph, with only the edges some optimal
//! path needs.
//!
//! Cost: the thesis builds it in O(V^4). Here one dense Dijkstra per source (O(V^2): the graph
//! is complete, so an array beats a heap), run in parallel over sources: O(V^3) in all, with the
//! predecessor of every node in every tree; the union of the trees is the set of (predecessor,
//! node) edges. Ties between equal-cost paths: Dijkstra settles the unsettled node of smallest
//! index among equal distances and a predecessor is replaced only by a strictly cheaper one, so
//! the graph is the same whatever the number of threads.
//!
//! That tie rule is surfcap's reading ([`TieRule::Strict`]): with its reading of eq. 3.2 (no
//! same-sequence "skip" edge that only matches the original frames, `edge_weights`) exact ties
//! are rare. Eq. 3.2 read literally gives every forward same-sequence pair an edge of weight
//! min(alpha (j - i), D + alpha L) ([`with_skip_edges`]); such an edge ties with the chain of
//! original frames, and which one survives is then decided by rounding unless the rule says:
//! [`TieRule::FirstFound`] counts paths within [`TIE_TOLERANCE`] relative as equal and keeps
//! the one found first (through the node settled first: the direct edge). Offered to show what
//! that reading changes (`surfcap eval graphs --tie-rule literal`).

use rayon::prelude::*;
use surfcap_mesh::Progress;

use crate::edge_weights::EdgeWeights;
use crate::graph::{Edge, Graph};
use surfcap_mesh::FrameIndex;

const NO_PRED: u32 = crate::sparse_essential_graph::NO_PRED;

/// The essential graph and the all-pairs shortest-path costs of the complete digraph.
#[derive(Debug, Clone)]
pub struct EssentialGraph {
    pub graph: Graph,
    /// Row-major N x N shortest-path costs (infinity where no path; 0 on the diagonal).
    pub costs: Vec<f64>,
}

/// Relative cost difference under which [`TieRule::FirstFound`] counts two paths as equal.
pub const TIE_TOLERANCE: f64 = 1e-12;

/// How the shortest-path trees decide between paths of equal cost.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TieRule {
    /// A predecessor is replaced only by a strictly cheaper path (surfcap's rule).
    #[default]
    Strict,
    /// Paths within [`TIE_TOLERANCE`] relative cost are equal and the first found is kept.
    FirstFound,
}

/// Eq. 3.2 read literally: `w` with every forward same-sequence pair (i, j > i + 1) given the
/// weight min(alpha (j - i), D + alpha L), where surfcap's reading leaves no edge unless the
/// transition is strictly cheaper than the original frames.
pub fn with_skip_edges(w: &EdgeWeights, index: &FrameIndex) -> EdgeWeights {
    let mut out = w.clone();
    let (n, alpha) = (w.n, w.alpha.get());
    for s in 0..index.n_sequences() {
        let range = index.range(s);
        for i in range.clone() {
            for j in i + 2..range.end {
                let k = i * n + j;
                out.weight[k] = out.weight[k].min(alpha * (j - i) as f64);
            }
        }
    }
    out
}

/// Dense Dijkstra from `source`: costs and predecessors. A node's predecessor is replaced by
/// a path cheaper by more than `tol` relative (0: by any amount).
fn dense_dijkstra(w: &EdgeWeights, source: usize, dist: &mut [f64], pred: &mut [u32], tol: f64) {
    let n = w.n;
    let mut done = vec![false; n];
    dist.fill(f64::INFINITY);
    pred.fill(NO_PRED);
    dist[source] = 0.0;
    let mut u = source;
    loop {
        done[u] = true;
        let row = &w.weight[u * n..(u + 1) * n];
        let du = dist[u];
        // Relax u's edges and find the next node to settle in the same pass.
        let (mut next, mut best) = (usize::MAX, f64::INFINITY);
        for v in 0..n {
            if done[v] {
                continue;
            }
            let nd = du + row[v];
            if nd < dist[v] && (tol == 0.0 || dist[v].is_infinite() || nd < dist[v] * (1.0 - tol)) {
                dist[v] = nd;
                pred[v] = u as u32;
            }
            if dist[v] < best {
                best = dist[v];
                next = v;
            }
        }
        if next == usize::MAX {
            break;
        }
        u = next;
    }
}

/// Builds the essential graph of the complete digraph `w` (surfcap's tie rule).
pub fn essential_graph(w: &EdgeWeights, progress: &dyn Progress) -> EssentialGraph {
    essential_graph_with(w, TieRule::Strict, progress)
}

/// [`essential_graph`] with the rule deciding between equal-cost paths.
pub fn essential_graph_with(w: &EdgeWeights, ties: TieRule, progress: &dyn Progress) -> EssentialGraph {
    let tol = match ties {
        TieRule::Strict => 0.0,
        TieRule::FirstFound => TIE_TOLERANCE,
    };
    let n = w.n;
    let mut costs = vec![f64::INFINITY; n * n];
    let mut preds = vec![NO_PRED; n * n];
    progress.start("essential graph", n as u64);
    costs.par_chunks_mut(n).zip(preds.par_chunks_mut(n)).enumerate().for_each(|(s, (dist, pred))| {
        dense_dijkstra(w, s, dist, pred, tol);
        progress.advance(1);
    });
    progress.finish();
    let mut in_tree = vec![false; n * n];
    for pred in preds.chunks_exact(n) {
        for (v, &p) in pred.iter().enumerate() {
            if p != NO_PRED {
                in_tree[p as usize * n + v] = true;
            }
        }
    }
    let edges = in_tree
        .iter()
        .enumerate()
        .filter(|(_, t)| **t)
        .map(|(k, _)| Edge { from: (k / n) as u32, to: (k % n) as u32, weight: w.weight[k] })
        .collect();
    EssentialGraph { graph: Graph::new(n, edges), costs }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edge_weights::Alpha;
    use surfcap_mesh::NoProgress;

    /// A small example in the spirit of thesis 3.3.3 (Fig. 3.3-3.7, whose cost matrix is only
    /// drawn), derived by hand: sequences A = a0..a3 and B = b0..b2, alpha = 1 (original steps
    /// cost 1), every transition 5 except a1 -> b1 = 1.5, a0 -> b2 = 2 and b2 -> a0 = 4. In the
    /// A-to-B block the only local minimum is a1 -> b1 (a0 -> b2 has the cheaper neighbour
    /// a1 -> b1), so the motion graph goes a0 -> a1 -> b1 -> b2 for 1 + 1.5 + 1 = 3.5, while
    /// the essential graph keeps the direct a0 -> b2 for 2.
    #[test]
    fn the_essential_graph_beats_the_motion_graph_on_a_hand_made_example() {
        use crate::motion_graph::motion_graph;
        use surfcap_mesh::FrameIndex;
        let index = FrameIndex::new([4, 3]);
        let n = 7;
        let (a, b) = (|k: usize| k, |k: usize| 4 + k);
        let mut weight = vec![5.0; n * n];
        for i in 0..n {
            weight[i * n + i] = f64::INFINITY;
        }
        for i in [0, 1, 2, 4, 5] {
            weight[i * n + i + 1] = 1.0;
        }
        weight[a(1) * n + b(1)] = 1.5;
        weight[a(0) * n + b(2)] = 2.0;
        weight[b(2) * n + a(0)] = 4.0;
        let w = EdgeWeights { n, alpha: Alpha::new(1.0).unwrap(), d_scale: 1.0, weight };
        let eg = essential_graph(&w, &NoProgress);
        let mg = motion_graph(&w, &index);
        let has = |g: &Graph, x: usize, y: usize| g.edges().iter().any(|e| (e.from as usize, e.to as usize) == (x, y));
        assert!(has(&mg.graph, a(1), b(1)) && !has(&mg.graph, a(0), b(2)));
        assert!(has(&eg.graph, a(0), b(2)));
        assert_eq!(eg.costs[a(0) * n + b(2)], 2.0);
        assert_eq!(mg.graph.shortest_paths_from(a(0))[b(2)], 3.5);
        // Never lower in the motion graph, for any pair.
        let mg_costs = mg.graph.all_pairs();
        assert!(mg_costs.iter().zip(&eg.costs).all(|(m, e)| m >= e));
    }

    /// One sequence of 6 frames whose transitions all cost more than playing on: surfcap's
    /// reading keeps the chain of original frames only; eq. 3.2 read literally with the
    /// first-found tie rule keeps a direct edge from every frame to every later one (each ties
    /// with the chain and is found first); the path costs agree to rounding.
    #[test]
    fn the_literal_reading_keeps_the_skip_edges_that_tie_with_the_chain() {
        use surfcap_mesh::FrameIndex;
        let (n, alpha) = (6, 0.05);
        let index = FrameIndex::new([n]);
        let mut weight = vec![10.0; n * n];
        for i in 0..n {
            weight[i * n + i] = f64::INFINITY;
            for j in i + 1..n {
                weight[i * n + j] = if j == i + 1 { alpha } else { f64::INFINITY };
            }
        }
        let w = EdgeWeights { n, alpha: Alpha::new(alpha).unwrap(), d_scale: 1.0, weight };
        let ours = essential_graph(&w, &NoProgress);
        let forward = |g: &Graph| g.edges().iter().filter(|e| e.to > e.from).count();
        assert_eq!(forward(&ours.graph), n - 1, "the chain only");
        assert_eq!(essential_graph_with(&w, TieRule::FirstFound, &NoProgress).graph.edges(), ours.graph.edges());
        let skip = with_skip_edges(&w, &index);
        assert!((skip.at(0, 5) - 5.0 * alpha).abs() < 1e-15 && skip.at(5, 0) == 10.0);
        let literal = essential_graph_with(&skip, TieRule::FirstFound, &NoProgress);
        assert_eq!(forward(&literal.graph), n * (n - 1) / 2, "a direct edge to every later frame");
        for (a, b) in ours.costs.iter().zip(&literal.costs) {
            assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{a} vs {b}");
        }
    }

    /// A complete digraph with pseudo-random weights: the essential graph keeps every pair's
    /// shortest-path cost, is no larger than the complete graph, and dropping any of its edges
    /// makes some pair dearer (every edge is essential).
    #[test]
    fn keeps_every_shortest_path_and_only_needed_edges() {
        let n = 30;
        let mut x = 12345u64;
        let mut weight = vec![f64::INFINITY; n * n];
        for i in 0..n {
            for j in 0..n {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                if i != j {
                    weight[i * n + j] = 0.1 + (x >> 11) as f64 / (1u64 << 53) as f64;
                }
            }
        }
        let w = EdgeWeights { n, alpha: Alpha::new(1.0).unwrap(), d_scale: 1.0, weight };
        let eg = essential_graph(&w, &NoProgress);
        let complete: Vec<Edge> = (0..n * n)
            .filter(|k| k / n != k % n)
            .map(|k| Edge { from: (k / n) as u32, to: (k % n) as u32, weight: w.weight[k] })
            .collect();
        let complete = Graph::new(n, complete);
        assert!(eg.graph.edges().len() < complete.edges().len());
        for s in 0..n {
            let want = complete.shortest_paths_from(s);
            assert_eq!(&eg.costs[s * n..(s + 1) * n], want.as_slice());
            let got = eg.graph.shortest_paths_from(s);
            for v in 0..n {
                assert!((got[v] - want[v]).abs() <= 1e-12 * want[v].max(1.0), "{s}->{v}");
            }
        }
        for (k, drop) in eg.graph.edges().iter().enumerate() {
            let rest: Vec<Edge> =
                eg.graph.edges().iter().enumerate().filter(|&(q, _)| q != k).map(|(_, e)| *e).collect();
            let g = Graph::new(n, rest);
            let worse = (0..n).any(|s| {
                let d = g.shortest_paths_from(s);
                (0..n).any(|v| d[v] > eg.costs[s * n + v] + 1e-12)
            });
            assert!(worse, "edge {drop:?} is in no shortest path");
        }
    }
}
