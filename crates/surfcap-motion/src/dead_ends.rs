//! The frames from which a walk can go on for as long as needed (no dead ends).
//!
//! The last frame of every sequence has no successive frame, and a frame near it whose only
//! transitions lead to such frames is as bad: a search that enters one is stuck a few frames
//! later. A walk of any length exists from a node exactly when the node can reach a cycle, i.e.
//! a node of a strongly connected component with more than one node (or a self-loop). Kovar et
//! al. keep only the largest component; keeping every node that reaches a cycle loses none of
//! the essential graph's edges between such nodes (an edge into a dead end is the only kind
//! dropped).

use crate::graph::Graph;

/// Whether each node of `graph` can reach a cycle (reverse reachability from the nodes of the
/// non-trivial strongly connected components), O(V + E).
pub fn live_nodes(graph: &Graph) -> Vec<bool> {
    let n = graph.n;
    let comp = graph.strongly_connected_components();
    let mut size = vec![0usize; n];
    for &c in &comp {
        size[c as usize] += 1;
    }
    let mut live: Vec<bool> = (0..n).map(|u| size[comp[u] as usize] > 1).collect();
    for e in graph.edges().iter().filter(|e| e.from == e.to) {
        live[e.from as usize] = true;
    }
    // Predecessors in CSR form, then a breadth-first search backwards from the cyclic nodes.
    let mut start = vec![0usize; n + 1];
    for e in graph.edges() {
        start[e.to as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut pred = vec![0u32; graph.edges().len()];
    for e in graph.edges() {
        pred[fill[e.to as usize]] = e.from;
        fill[e.to as usize] += 1;
    }
    let mut queue: Vec<usize> = (0..n).filter(|&u| live[u]).collect();
    while let Some(v) = queue.pop() {
        for &u in &pred[start[v]..start[v + 1]] {
            if !live[u as usize] {
                live[u as usize] = true;
                queue.push(u as usize);
            }
        }
    }
    live
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::Edge;

    fn graph(n: usize, edges: &[(u32, u32)]) -> Graph {
        Graph::new(n, edges.iter().map(|&(from, to)| Edge { from, to, weight: 1.0 }).collect())
    }

    #[test]
    fn only_nodes_that_reach_a_cycle_are_live() {
        // Two sequences 0..4 and 4..8 played forward; 2 -> 5 and 6 -> 1 close a cycle
        // (1 2 5 6); 7 and 3 are sequence ends, 0 -> 3 leads only to a dead end.
        let g = graph(8, &[(0, 1), (1, 2), (2, 3), (4, 5), (5, 6), (6, 7), (2, 5), (6, 1), (0, 3)]);
        assert_eq!(live_nodes(&g), vec![true, true, true, false, true, true, true, false]);
    }

    #[test]
    fn a_chain_is_dead_and_a_self_loop_is_live() {
        assert_eq!(live_nodes(&graph(3, &[(0, 1), (1, 2)])), vec![false; 3]);
        assert_eq!(live_nodes(&graph(3, &[(0, 1), (1, 1), (2, 0)])), vec![true; 3]);
        assert!(live_nodes(&graph(0, &[])).is_empty());
    }
}
