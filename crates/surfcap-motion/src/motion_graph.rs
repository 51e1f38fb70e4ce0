//! The motion graph baseline (Kovar et al. 2002, as the thesis compares in 3.3.3): the original
//! sequences' successive-frame edges plus one transition at every local minimum of each
//! sequence-pair block of the transition cost matrix, with no threshold (the thesis drops it "to
//! obtain a highly connected motion graph"), weighted like the essential graph (Algorithm 1), so
//! that both structures are compared on the same costs. Dead ends are handled as Kovar does:
//! the graph is pruned to its largest strongly connected component, so that every kept frame
//! can reach every other.
//!
//! Local minima: of the edge weights E (the thesis compares "the same transition cost for both
//! methods"), over the 8 neighbours inside the block of sequences (A, B); cells without an edge
//! count as infinitely dear, original successive-frame pairs are neither candidates nor
//! neighbours (their weight, alpha, is playback, not a transition cost). On a plateau of equal
//! values only the first cell in row-major order is a minimum.

use surfcap_mesh::FrameIndex;

use crate::edge_weights::EdgeWeights;
use crate::graph::{Edge, Graph};

/// The motion graph, pruned to its largest strongly connected component.
#[derive(Debug, Clone)]
pub struct MotionGraph {
    pub graph: Graph,
    /// Whether each frame is in the kept component.
    pub kept: Vec<bool>,
    /// Transition edges (local minima) before pruning.
    pub transitions: usize,
}

pub fn motion_graph(w: &EdgeWeights, index: &FrameIndex) -> MotionGraph {
    let n = w.n;
    let mut edges = Vec::new();
    for s in 0..index.n_sequences() {
        let r = index.range(s);
        for i in r.start..r.end.saturating_sub(1) {
            edges.push(Edge { from: i as u32, to: i as u32 + 1, weight: w.at(i, i + 1) });
        }
    }
    let mut transitions = 0;
    for a in 0..index.n_sequences() {
        for b in 0..index.n_sequences() {
            let (ra, rb) = (index.range(a), index.range(b));
            for i in ra.clone() {
                for j in rb.clone() {
                    let v = w.at(i, j);
                    if !v.is_finite() || EdgeWeights::is_original(index, i, j) {
                        continue;
                    }
                    let mut minimum = true;
                    'scan: for di in -1i32..=1 {
                        for dj in -1i32..=1 {
                            // Off the block (including below 0, which wraps past it) or itself.
                            let (ii, jj) = (i.wrapping_add_signed(di as isize), j.wrapping_add_signed(dj as isize));
                            if (di, dj) == (0, 0) || !ra.contains(&ii) || !rb.contains(&jj) {
                                continue;
                            }
                            if EdgeWeights::is_original(index, ii, jj) {
                                continue;
                            }
                            let u = w.at(ii, jj);
                            let earlier = (di, dj) < (0, 0);
                            if u < v || (earlier && u == v) {
                                minimum = false;
                                break 'scan;
                            }
                        }
                    }
                    if minimum {
                        edges.push(Edge { from: i as u32, to: j as u32, weight: v });
                        transitions += 1;
                    }
                }
            }
        }
    }
    let full = Graph::new(n, edges);
    let comp = full.strongly_connected_components();
    // The largest component; on equal sizes, the one holding the smallest frame.
    let mut size = vec![0usize; n];
    for &c in &comp {
        size[c as usize] += 1;
    }
    let largest = comp.iter().copied().max_by(|&a, &b| size[a as usize].cmp(&size[b as usize]).then(b.cmp(&a)));
    let kept: Vec<bool> = comp.iter().map(|&c| Some(c) == largest).collect();
    let edges = full.edges().iter().filter(|e| kept[e.from as usize] && kept[e.to as usize]).copied().collect();
    MotionGraph { graph: Graph::new(n, edges), kept, transitions }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edge_weights::Alpha;

    #[test]
    fn local_minima_and_dead_ends() {
        // Two sequences of 4 frames; no transition is possible except two, one from the end
        // of sequence 0 to the start of 1 and one back, each with a dearer neighbour.
        let index = FrameIndex::new([4, 4]);
        let n = 8;
        let mut weight = vec![f64::INFINITY; n * n];
        weight[3 * n + 5] = 2.5; // 3 -> 5, not a minimum (3 -> 4 is its cheaper neighbour)
        for i in [0, 1, 2, 4, 5, 6] {
            weight[i * n + i + 1] = 1.0;
        }
        weight[3 * n + 4] = 2.0; // 3 -> 4
        weight[6 * n + 1] = 2.0; // 6 -> 1
        let w = EdgeWeights { n, alpha: Alpha::new(1.0).unwrap(), d_scale: 1.0, weight };
        let mg = motion_graph(&w, &index);
        let has = |a: u32, b: u32| mg.graph.edges().iter().any(|e| e.from == a && e.to == b);
        assert!(has(3, 4) && has(6, 1));
        // Frame 0 is entered by nothing and 7 leaves to nothing: both pruned.
        assert_eq!(mg.kept, vec![false, true, true, true, true, true, true, false]);
        assert!(!has(0, 1) && !has(6, 7));
        assert_eq!(mg.transitions, 2);
        // Distinct weights everywhere: each block's smallest transition is a minimum.
        let weight =
            (0..n * n).map(|k| if k / n == k % n { f64::INFINITY } else { 10.0 + ((k * 37) % 61) as f64 }).collect();
        let w = EdgeWeights { n, alpha: Alpha::new(1.0).unwrap(), d_scale: 1.0, weight };
        let mg = motion_graph(&w, &index);
        for (a, b) in [(0..4, 0..4), (0..4, 4..8), (4..8, 0..4), (4..8, 4..8)] {
            let best = a
                .clone()
                .flat_map(|i| b.clone().map(move |j| (i, j)))
                .filter(|&(i, j)| i != j && !EdgeWeights::is_original(&index, i, j))
                .min_by(|x, y| w.at(x.0, x.1).total_cmp(&w.at(y.0, y.1)))
                .unwrap();
            assert!(mg.graph.edges().iter().any(|e| (e.from as usize, e.to as usize) == best), "{best:?}");
        }
    }
}
