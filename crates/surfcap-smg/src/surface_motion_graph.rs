//! The two-level surface motion graph (Huang et al. 2009, section 3.3).
//!
//! The higher level is the user's: which sequences may follow which (`X -> Y`, `X -> X` for a
//! loop in a cyclic motion), and the key frames. The lower level is built from it:
//! 1. every sequence is an edge between its first and last frames;
//! 2. each higher-level edge `X -> Y` gets its optimal transition (eq. 5,
//!    [`crate::temporal_shape_similarity::optimal_transition`]), or its `per_connection` best
//!    (an extension, see [`crate::temporal_shape_similarity::best_transitions`]);
//! 3. the transitions' ends and the key frames become nodes, splitting the sequence edges into
//!    sub-sequences, and the transitions are inserted as edges.
//!
//! [`build_graph_choosing`] departs from step 2 for self-transitions only (`X -> X`): each is
//! chosen among the loops a query may play, spanning the sequence's cross transitions and key
//! frames ([`crate::self_transition_choice`]), after the cross transitions (eq. 5 as printed).
//! Eq. 5 alone picks a clip's stillest 3 frames as its loop, which no query may repeat, and may
//! put the loop where no path between the key frames passes.
//!
//! What each edge contributes to a path (section 4.1), made explicit:
//! - a sub-sequence from frame `p` to frame `q` of one sequence adds the frames `p+1 ... q`
//!   (`q - p` frames), the distance travelled between them (the centroid projected on the ground,
//!   eq. 8) and no transition cost;
//! - a transition from `x` (last frame of X played) to `y` (first frame of Y played) adds the
//!   frame `y` (1 frame), its cost `S'` (eq. 7) and no distance: the concatenation matches the
//!   centroids at the switch (4.2.3), so nothing is travelled across it.
//!
//! A path starting at a key frame counts that frame too: `t(F) = 1 + sum of the edges' frames`.

use std::collections::BTreeMap;
use std::ops::Range;

use crate::error::{Error, Result};
use crate::loop_exclusion::LoopFilter;
use crate::self_transition_choice::{Span, spanning_self_transitions};
use crate::temporal_shape_similarity::{Transition, best_transitions};

/// What one lower-level edge is.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EdgeKind {
    /// Frames `from + 1 ..= to` (global indices) of one sequence.
    Segment { sequence: usize },
    /// A switch from sequence `from_sequence` to `to_sequence` (eq. 5's transition).
    Transition { from_sequence: usize, to_sequence: usize, window: usize },
}

/// A lower-level edge between two nodes.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Edge {
    pub from: usize,
    pub to: usize,
    pub kind: EdgeKind,
    /// Frames the edge adds to a path.
    pub frames: usize,
    /// Ground distance travelled along it.
    pub distance: f64,
    /// Transition cost (0 for a sub-sequence).
    pub cost: f64,
}

/// The lower-level graph: nodes are global frames.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SurfaceMotionGraph {
    /// The global frame of each node, in increasing order.
    pub nodes: Vec<usize>,
    pub edges: Vec<Edge>,
    /// The transition of each higher-level edge `(X, Y)` that has one.
    pub transitions: Vec<(usize, usize, Transition)>,
    /// Higher-level edges without a transition (sequences too short for any window).
    pub missing: Vec<(usize, usize)>,
}

impl SurfaceMotionGraph {
    /// The node of a global frame.
    pub fn node_of(&self, frame: usize) -> Option<usize> {
        self.nodes.binary_search(&frame).ok()
    }

    /// The edges leaving each node, in edge order.
    pub fn out_edges(&self) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); self.nodes.len()];
        for (i, e) in self.edges.iter().enumerate() {
            out[e.from].push(i);
        }
        out
    }
}

/// What the graph is built from.
pub struct GraphInput<'a> {
    /// Each sequence's global frames, disjoint and in order.
    pub sequences: &'a [Range<usize>],
    /// The `frames x frames` shape similarity matrix (eq. 2-3).
    pub similarity: &'a [f64],
    /// Each frame's centroid projected on the ground plane.
    pub ground: &'a [[f64; 2]],
    /// The higher-level graph: sequence pairs `(X, Y)` that may connect.
    pub connections: &'a [(usize, usize)],
    /// Key frames (global) that must be nodes.
    pub key_frames: &'a [usize],
    /// Window lengths searched for the transitions.
    pub lengths: std::ops::RangeInclusive<usize>,
    /// Transitions per connection: 1 is the paper's; more is an extension
    /// ([`crate::temporal_shape_similarity::best_transitions`]), their switches at least
    /// `separation` frames apart.
    pub per_connection: usize,
    pub separation: usize,
}

/// How [`build_graph_choosing`] chooses self-transitions: among the loops `filter` lets pad
/// time, spanning the key frames of `key_pairs` (global `(start, end)` frames) and the cross
/// transitions.
pub struct LoopChoice<'a> {
    pub filter: &'a LoopFilter<'a>,
    pub key_pairs: &'a [(usize, usize)],
    /// Self-transitions per sequence (at least 1): the spanning one, then the cheapest
    /// admissible loops inside it ([`crate::self_transition_choice`]); `per_connection` then
    /// counts the cross transitions only.
    pub per_sequence: usize,
}

/// Builds the lower-level graph as the paper does (see the module documentation).
pub fn build_graph(input: &GraphInput<'_>) -> Result<SurfaceMotionGraph> {
    build(input, None)
}

/// Builds the lower-level graph with the self-transitions chosen among the loops a query may
/// play, spanning the sequence's cross transitions and key frames (an extension of eq. 5, see
/// the module documentation and [`crate::self_transition_choice`]); the cross transitions are
/// eq. 5's.
pub fn build_graph_choosing(input: &GraphInput<'_>, loops: &LoopChoice<'_>) -> Result<SurfaceMotionGraph> {
    build(input, Some(loops))
}

fn build(input: &GraphInput<'_>, loops: Option<&LoopChoice<'_>>) -> Result<SurfaceMotionGraph> {
    let frames = input.ground.len();
    let mut end = 0;
    for (k, s) in input.sequences.iter().enumerate() {
        if s.start < end || s.end > frames || s.is_empty() {
            return Err(Error::Invalid(format!(
                "sequence {k} has frames {s:?}: expected non-empty, in order, within 0..{frames}"
            )));
        }
        end = s.end;
    }
    let sequence_of = |f: usize| input.sequences.iter().position(|s| s.contains(&f));
    let mut nodes: Vec<usize> = input.sequences.iter().flat_map(|s| [s.start, s.end - 1]).collect();
    for &k in input.key_frames {
        if sequence_of(k).is_none() {
            return Err(Error::Invalid(format!("key frame {k} is in no sequence")));
        }
        nodes.push(k);
    }
    let mut transitions = Vec::new();
    let mut missing = Vec::new();
    for &(x, y) in input.connections {
        if input.sequences.get(x).is_none() || input.sequences.get(y).is_none() {
            return Err(Error::Invalid(format!(
                "connection {x} -> {y}: expected sequences below {}",
                input.sequences.len()
            )));
        }
    }
    // With a loop choice, the cross transitions first: the self-transitions span them.
    let order: Vec<(usize, usize)> = match loops {
        None => input.connections.to_vec(),
        Some(_) => {
            let (same, cross): (Vec<_>, Vec<_>) = input.connections.iter().partition(|(x, y)| x == y);
            cross.into_iter().chain(same).collect()
        }
    };
    for (x, y) in order {
        let (sx, sy) = (input.sequences[x].clone(), input.sequences[y].clone());
        let found = match loops {
            Some(choice) if x == y => {
                let span = span_of(x, &sx, &transitions, choice.key_pairs);
                spanning_self_transitions(
                    input.similarity,
                    frames,
                    sx.clone(),
                    input.lengths.clone(),
                    &choice.filter.span_variation(x),
                    &span,
                    choice.per_sequence,
                    input.separation,
                )?
            }
            _ => best_transitions(
                input.similarity,
                frames,
                sx.clone(),
                sy.clone(),
                input.lengths.clone(),
                input.per_connection,
                input.separation,
            )?,
        };
        if found.is_empty() {
            missing.push((x, y));
        }
        for t in found {
            nodes.push(sx.start + t.last_x);
            nodes.push(sy.start + t.first_y);
            transitions.push((x, y, t));
        }
    }
    // Reported in the order of the connections given.
    if loops.is_some() {
        let rank = |x: usize, y: usize| input.connections.iter().position(|&c| c == (x, y));
        transitions.sort_by_key(|&(x, y, _)| rank(x, y));
        missing.sort_by_key(|&(x, y)| rank(x, y));
    }
    nodes.sort_unstable();
    nodes.dedup();
    let index: BTreeMap<usize, usize> = nodes.iter().enumerate().map(|(i, &f)| (f, i)).collect();
    let step = |f: usize| {
        let (a, b) = (input.ground[f], input.ground[f + 1]);
        ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
    };
    let mut edges = Vec::new();
    for (k, s) in input.sequences.iter().enumerate() {
        let inside: Vec<usize> = nodes.iter().copied().filter(|f| s.contains(f)).collect();
        for w in inside.windows(2) {
            edges.push(Edge {
                from: index[&w[0]],
                to: index[&w[1]],
                kind: EdgeKind::Segment { sequence: k },
                frames: w[1] - w[0],
                distance: (w[0]..w[1]).map(step).sum(),
                cost: 0.0,
            });
        }
    }
    for &(x, y, t) in &transitions {
        let (from, to) = (input.sequences[x].start + t.last_x, input.sequences[y].start + t.first_y);
        edges.push(Edge {
            from: index[&from],
            to: index[&to],
            kind: EdgeKind::Transition { from_sequence: x, to_sequence: y, window: t.length },
            frames: 1,
            distance: 0.0,
            cost: t.cost,
        });
    }
    Ok(SurfaceMotionGraph { nodes, edges, transitions, missing })
}

/// What the self-transition of sequence `k` (global frames `seq`) must span, within the
/// sequence: the first frames played after the cross transitions into it and the start key
/// frames in it (entries), the last frames played before the cross transitions out of it and
/// the end key frames in it (exits).
fn span_of(k: usize, seq: &Range<usize>, cross: &[(usize, usize, Transition)], key_pairs: &[(usize, usize)]) -> Span {
    let mut span = Span::default();
    for &(x, y, t) in cross.iter().filter(|(x, y, _)| x != y) {
        if y == k {
            span.entries.push(t.first_y);
        }
        if x == k {
            span.exits.push(t.last_x);
        }
    }
    for &(a, b) in key_pairs {
        if seq.contains(&a) {
            span.entries.push(a - seq.start);
        }
        if seq.contains(&b) {
            span.exits.push(b - seq.start);
        }
    }
    span
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sequences_split_at_transitions_and_key_frames() {
        // Two sequences of 10 frames walking 1 unit per frame along x; frames 3-5 of X match
        // frames 6-8 of Y.
        let f = 20;
        let mut s = vec![1.0; f * f];
        for i in 0..f {
            s[i * f + i] = 0.0;
        }
        for k in 0..3 {
            s[(3 + k) * f + 16 + k] = 0.0;
            s[(16 + k) * f + 3 + k] = 0.0;
        }
        let ground: Vec<[f64; 2]> = (0..f).map(|i| [i as f64, 0.0]).collect();
        let seqs = [0..10, 10..20];
        let g = build_graph(&GraphInput {
            sequences: &seqs,
            similarity: &s,
            ground: &ground,
            connections: &[(0, 1)],
            key_frames: &[2],
            lengths: 3..=3,
            per_connection: 1,
            separation: 0,
        })
        .unwrap();
        // Nodes: 0, 9, 10, 19, key 2, transition 4 -> 18 (Y's first frame 8 + 10).
        assert_eq!(g.nodes, vec![0, 2, 4, 9, 10, 18, 19]);
        let seg: Vec<(usize, usize, usize)> =
            g.edges.iter().map(|e| (g.nodes[e.from], g.nodes[e.to], e.frames)).collect();
        assert_eq!(seg, vec![(0, 2, 2), (2, 4, 2), (4, 9, 5), (10, 18, 8), (18, 19, 1), (4, 18, 1)]);
        assert_eq!(g.edges[2].distance, 5.0);
        assert_eq!((g.edges[5].cost, g.edges[5].distance), (0.0, 0.0));
        let e = build_graph(&GraphInput {
            sequences: &seqs,
            similarity: &s,
            ground: &ground,
            connections: &[(0, 2)],
            key_frames: &[],
            lengths: 3..=3,
            per_connection: 1,
            separation: 0,
        })
        .unwrap_err();
        assert!(e.to_string().contains("below 2"), "{e}");
    }
}
