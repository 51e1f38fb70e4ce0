//! A weighted digraph over a subject's frames (the essential graph and the motion graph share
//! it): edges sorted by (from, to), shortest paths by Dijkstra with a binary heap, density
//! (thesis eq. 3.4) and strongly connected components (for the motion graph's dead ends).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// One directed edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    pub from: u32,
    pub to: u32,
    pub weight: f64,
}

/// A digraph on nodes 0..n.
#[derive(Debug, Clone, PartialEq)]
pub struct Graph {
    pub n: usize,
    edges: Vec<Edge>,
    /// `edges[offsets[i]..offsets[i + 1]]` leave node i.
    offsets: Vec<usize>,
}

/// A totally ordered f64 for the heap (weights are finite and non-negative).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cost(pub(crate) f64);

impl Eq for Cost {}

impl PartialOrd for Cost {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Cost {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

impl Graph {
    /// The graph of these edges (any order; duplicates keep the cheapest).
    pub fn new(n: usize, mut edges: Vec<Edge>) -> Self {
        edges.sort_by(|a, b| (a.from, a.to).cmp(&(b.from, b.to)).then(a.weight.total_cmp(&b.weight)));
        edges.dedup_by(|b, a| a.from == b.from && a.to == b.to);
        let mut offsets = vec![0usize; n + 1];
        for e in &edges {
            offsets[e.from as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        Graph { n, edges, offsets }
    }

    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    pub fn out(&self, i: usize) -> &[Edge] {
        &self.edges[self.offsets[i]..self.offsets[i + 1]]
    }

    /// The position in [`Graph::edges`] of the edge `from` -> `to`, if there is one (binary
    /// search among `from`'s edges, which are sorted by destination).
    pub fn find(&self, from: usize, to: usize) -> Option<usize> {
        if from >= self.n {
            return None;
        }
        self.out(from).binary_search_by(|e| (e.to as usize).cmp(&to)).ok().map(|k| self.offsets[from] + k)
    }

    /// Thesis eq. 3.4: |E| / (|V| (|V| - 1)).
    pub fn density(&self) -> f64 {
        if self.n < 2 { 0.0 } else { self.edges.len() as f64 / (self.n as f64 * (self.n - 1) as f64) }
    }

    /// Shortest-path costs from `source` to every node (infinity where unreachable), Dijkstra
    /// with a binary heap; ties settle the node of smaller index first.
    pub fn shortest_paths_from(&self, source: usize) -> Vec<f64> {
        let mut dist = vec![f64::INFINITY; self.n];
        let mut heap = BinaryHeap::new();
        dist[source] = 0.0;
        heap.push(Reverse((Cost(0.0), source)));
        while let Some(Reverse((Cost(d), u))) = heap.pop() {
            if d > dist[u] {
                continue;
            }
            for e in self.out(u) {
                let nd = d + e.weight;
                if nd < dist[e.to as usize] {
                    dist[e.to as usize] = nd;
                    heap.push(Reverse((Cost(nd), e.to as usize)));
                }
            }
        }
        dist
    }

    /// All-pairs shortest-path costs, row-major N x N (one Dijkstra per source, in parallel).
    pub fn all_pairs(&self) -> Vec<f64> {
        use rayon::prelude::*;
        let mut out = vec![0.0; self.n * self.n];
        if self.n > 0 {
            out.par_chunks_mut(self.n)
                .enumerate()
                .for_each(|(s, row)| row.copy_from_slice(&self.shortest_paths_from(s)));
        }
        out
    }

    /// Strongly connected components (Tarjan's algorithm, iterative): a component label per
    /// node, labels in order of discovery.
    pub fn strongly_connected_components(&self) -> Vec<u32> {
        const NONE: u32 = u32::MAX;
        let n = self.n;
        let (mut index, mut low, mut comp) = (vec![NONE; n], vec![0u32; n], vec![NONE; n]);
        let mut on_stack = vec![false; n];
        let (mut stack, mut call): (Vec<usize>, Vec<(usize, usize)>) = (Vec::new(), Vec::new());
        let (mut next_index, mut next_comp) = (0u32, 0u32);
        for root in 0..n {
            if index[root] != NONE {
                continue;
            }
            call.push((root, 0));
            while let Some(&mut (v, ref mut k)) = call.last_mut() {
                if *k == 0 {
                    index[v] = next_index;
                    low[v] = next_index;
                    next_index += 1;
                    stack.push(v);
                    on_stack[v] = true;
                }
                let out = self.out(v);
                if *k < out.len() {
                    let w = out[*k].to as usize;
                    *k += 1;
                    if index[w] == NONE {
                        call.push((w, 0));
                    } else if on_stack[w] {
                        low[v] = low[v].min(index[w]);
                    }
                    continue;
                }
                call.pop();
                if let Some(&(parent, _)) = call.last() {
                    low[parent] = low[parent].min(low[v]);
                }
                if low[v] == index[v] {
                    while let Some(w) = stack.pop() {
                        on_stack[w] = false;
                        comp[w] = next_comp;
                        if w == v {
                            break;
                        }
                    }
                    next_comp += 1;
                }
            }
        }
        comp
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(from: u32, to: u32, weight: f64) -> Edge {
        Edge { from, to, weight }
    }

    #[test]
    fn dijkstra_density_and_components() {
        // 0 -> 1 -> 2 -> 0 is a cycle; 3 only leaves (a dead end's mirror); 2 -> 4 dead end.
        let g = Graph::new(
            5,
            vec![e(1, 2, 1.0), e(0, 1, 1.0), e(2, 0, 1.0), e(0, 2, 5.0), e(3, 0, 1.0), e(2, 4, 2.0), e(0, 1, 3.0)],
        );
        assert_eq!(g.edges().len(), 6, "duplicate kept cheapest");
        assert_eq!(g.out(0), &[e(0, 1, 1.0), e(0, 2, 5.0)]);
        assert_eq!(g.shortest_paths_from(0), vec![0.0, 1.0, 2.0, f64::INFINITY, 4.0]);
        assert!((g.density() - 6.0 / 20.0).abs() < 1e-15);
        let c = g.strongly_connected_components();
        assert!(c[0] == c[1] && c[1] == c[2]);
        assert!(c[3] != c[0] && c[4] != c[0] && c[3] != c[4]);
    }
}
