//! Walk to sequence (thesis 3.4.2, Algorithm 3): a walk in a graph over a subject's frames
//! becomes one mesh sequence: runs of original frames, and a Blend (Algorithm 2) for every
//! transition edge, with motion-plane alignment at every junction.
//!
//! Readings:
//! - Every node of the walk appears once in the output. An original edge u -> u + 1 adds frame
//!   u + 1; a transition edge u -> v of duration L adds the Blend's frames S(2..L-1) (S(1) is
//!   frame u itself, already in the output) and then frame v: it lasts L - 1 frame intervals.
//! - After a transition, Algorithm 3 re-aligns the destination's sequence onto S(end) with
//!   Align(S(end), M_v) and the centre offset. S(end) is M_v moved by the Blend's accumulated
//!   destination motion (lambda = 1 there), so that motion *is* the new placement; we compose it
//!   exactly instead of re-estimating it from the interpolated mesh.
//! - Blend's output is equivariant under a ground-plane motion of its source and invariant under
//!   one of its destination (its first step fully aligns the destination), so each transition's
//!   rigid track is computed once, in its source frame's own coordinates ([`WalkModel`]), and a
//!   walk's centre-of-mass trajectory is predicted by composing them without blending a single
//!   pose: the constrained searches (3.5) run on this model.

use std::collections::HashMap;

use rayon::prelude::*;
use surfcap_geometry::distance_matrix::alignment_gram;
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_geometry::poisson_reconstruction::PoissonError;
use surfcap_mesh::{FrameIndex, FrameLabel, Subject, UpAxis};

use crate::blend::{Lambda, Mixing, blend, blend_placements_from, centre};
use crate::dtw::{Slope, dtw_window};
use crate::graph::Graph;
use crate::transition_table::TransitionTable;

/// The rigid track of one transition edge u -> v, in the coordinates where frame u is unmoved.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionTrack {
    /// Source segment u .. u + li, destination segment v + 1 - lj ..= v (global frames).
    pub li: u32,
    pub lj: u32,
    /// The DTW warp (global source, global destination frame) of the transition, L cells.
    pub warp: Vec<(u32, u32)>,
    /// Centres of mass of the Blend's frames S(2..L-1).
    pub centres: Vec<[f64; 3]>,
    /// Where frame v (and the rest of its sequence) is placed after the transition.
    pub end: PlaneMotion,
}

impl TransitionTrack {
    /// Frame intervals from u to v (L - 1).
    pub fn duration(&self) -> usize {
        self.centres.len() + 1
    }
}

/// What taking an edge does.
#[derive(Debug, Clone, Copy)]
pub enum Step<'a> {
    /// u -> u + 1 in one sequence: one frame, placement unchanged.
    Original,
    Transition(&'a TransitionTrack),
}

/// Per-frame centres of mass and the rigid tracks of every transition edge of a graph.
#[derive(Debug, Clone)]
pub struct WalkModel {
    pub up: UpAxis,
    pub fps: f64,
    pub index: FrameIndex,
    /// Centre of mass of every global frame, as captured.
    pub centres: Vec<[f64; 3]>,
    tracks: HashMap<(u32, u32), TransitionTrack>,
}

/// Why a walk cannot be played.
#[derive(Debug, Clone, PartialEq)]
pub enum WalkError {
    Empty,
    /// Step `at` (u -> v) is neither successive frames nor a transition of the graph.
    NotAnEdge {
        at: usize,
        from: u32,
        to: u32,
    },
    Poisson(String),
}

impl std::fmt::Display for WalkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WalkError::Empty => write!(f, "the walk has no nodes"),
            WalkError::NotAnEdge { at, from, to } => write!(
                f,
                "step {at} of the walk, frame {from} -> {to}, is neither a successive-frame step nor a transition of the graph"
            ),
            WalkError::Poisson(e) => write!(f, "blending a transition: {e}"),
        }
    }
}

impl std::error::Error for WalkError {}

impl From<PoissonError> for WalkError {
    fn from(e: PoissonError) -> Self {
        WalkError::Poisson(e.to_string())
    }
}

impl WalkModel {
    /// Precomputes the tracks of every transition edge of `graph` (in parallel): each needs the
    /// DTW warp of its transition (from the distance matrix `d`) and one alignment angle per warp
    /// cell, but no pose interpolation.
    ///
    /// `tracked`: the vertices whose centre the model follows (all vertices when `None`). Inside
    /// a transition the tracked centre is the lambda-mix of the two moved frames' tracked
    /// centres: exact for the whole mesh (the non-linear interpolation keeps the mixed centre of
    /// mass), a close approximation for a vertex subset.
    pub fn new(
        subject: &Subject,
        graph: &Graph,
        table: &TransitionTable,
        d: &[f64],
        slope: Slope,
        tracked: Option<&[usize]>,
    ) -> Self {
        let index = subject.frame_index().clone();
        let n = table.n;
        let frame = |g: usize| subject.frame(g).expect("graph nodes are frames of the subject");
        let centres: Vec<[f64; 3]> = (0..subject.n_frames()).map(|g| tracked_centre(frame(g), tracked)).collect();
        let mass: Vec<[f64; 3]> = match tracked {
            None => centres.clone(),
            Some(_) => (0..subject.n_frames()).map(|g| centre(frame(g))).collect(),
        };
        // Eq. 2.3 angles of every pair from three matrix products instead of one pass over the
        // vertices per warp cell.
        let gram = alignment_gram(subject, None);
        let up = subject.up_axis;
        let edges: Vec<(u32, u32)> = graph
            .edges()
            .iter()
            .filter(|e| !is_successive(&index, e.from as usize, e.to as usize))
            .map(|e| (e.from, e.to))
            .collect();
        let tracks: Vec<Option<((u32, u32), TransitionTrack)>> = edges
            .par_iter()
            .map(|&(u, v)| {
                let k = u as usize * n + v as usize;
                let (li, lj) = (table.li[k] as usize, table.lj[k] as usize);
                if !table.cost[k].is_finite() {
                    return None;
                }
                let warp = dtw_window(d, n, u as usize, li, v as usize, lj, slope)?;
                let (s0, d0) = (u as usize, v as usize + 1 - lj);
                let offsets: Vec<(usize, usize)> = warp.path.iter().map(|&(a, b)| (a - s0, b - d0)).collect();
                let steps = blend_placements_from(
                    up,
                    &mass[s0..s0 + li],
                    &mass[d0..=v as usize],
                    &offsets,
                    Lambda::Ramp,
                    |n, m| gram.theta(s0 + n, d0 + m),
                );
                let last = steps.last()?;
                let mix = |st: &crate::blend::BlendStep| -> [f64; 3] {
                    let a = st.src.apply_point(centres[u as usize + st.n]);
                    let b = st.dst.apply_point(centres[d0 + st.m]);
                    std::array::from_fn(|k| (1.0 - st.lambda) * a[k] + st.lambda * b[k])
                };
                let inner = if steps.len() > 2 { steps[1..steps.len() - 1].iter().map(mix).collect() } else { vec![] };
                let warp = warp.path.iter().map(|&(a, b)| (a as u32, b as u32)).collect();
                Some(((u, v), TransitionTrack { li: li as u32, lj: lj as u32, warp, centres: inner, end: last.dst }))
            })
            .collect();
        WalkModel { up, fps: subject.fps, index, centres, tracks: tracks.into_iter().flatten().collect() }
    }

    /// What the edge u -> v does, or `None` when it is not playable.
    pub fn step(&self, u: u32, v: u32) -> Option<Step<'_>> {
        if is_successive(&self.index, u as usize, v as usize) {
            Some(Step::Original)
        } else {
            self.tracks.get(&(u, v)).map(Step::Transition)
        }
    }

    pub fn n_transitions(&self) -> usize {
        self.tracks.len()
    }

    /// Calls `emit(centre, is_original)` for every frame edge u -> v adds to a walk placed by
    /// `g`, and returns the placement after it.
    pub fn advance(
        &self,
        step: Step<'_>,
        g: &PlaneMotion,
        v: u32,
        mut emit: impl FnMut([f64; 3], bool),
    ) -> PlaneMotion {
        match step {
            Step::Original => {
                emit(g.apply_point(self.centres[v as usize]), true);
                *g
            }
            Step::Transition(t) => {
                for c in &t.centres {
                    emit(g.apply_point(*c), false);
                }
                let g2 = g.after(&t.end);
                emit(g2.apply_point(self.centres[v as usize]), true);
                g2
            }
        }
    }

    /// Predicted centre of mass of every output frame of `walk` placed by `start`.
    pub fn walk_centres(&self, walk: &[u32], start: &PlaneMotion) -> Result<Vec<[f64; 3]>, WalkError> {
        let first = *walk.first().ok_or(WalkError::Empty)?;
        let mut out = vec![start.apply_point(self.centres[first as usize])];
        let mut g = *start;
        for (at, w) in walk.windows(2).enumerate() {
            let step = self.step(w[0], w[1]).ok_or(WalkError::NotAnEdge { at, from: w[0], to: w[1] })?;
            g = self.advance(step, &g, w[1], |c, _| out.push(c));
        }
        Ok(out)
    }

    /// Duration of a walk in frame intervals.
    pub fn walk_duration(&self, walk: &[u32]) -> Result<usize, WalkError> {
        let mut t = 0;
        for (at, w) in walk.windows(2).enumerate() {
            t += match self.step(w[0], w[1]).ok_or(WalkError::NotAnEdge { at, from: w[0], to: w[1] })? {
                Step::Original => 1,
                Step::Transition(tr) => tr.duration(),
            };
        }
        Ok(t)
    }

    /// Index of the ground-plane axes.
    pub fn plane(&self) -> (usize, usize) {
        let (u, v, _) = plane_axes(self.up);
        (u, v)
    }
}

/// Centre of the `tracked` vertices of a frame (of all vertices when `None`).
pub fn tracked_centre(p: &[f32], tracked: Option<&[usize]>) -> [f64; 3] {
    let Some(ids) = tracked else { return centre(p) };
    let mut c = [0.0; 3];
    for &k in ids {
        for a in 0..3 {
            c[a] += p[3 * k + a] as f64;
        }
    }
    c.map(|x| x / ids.len().max(1) as f64)
}

fn is_successive(index: &FrameIndex, u: usize, v: usize) -> bool {
    v == u + 1 && index.locate(u).map(|l| l.0) == index.locate(v).map(|l| l.0)
}

/// A walk played as a mesh sequence.
#[derive(Debug, Clone)]
pub struct WalkSequence {
    /// `[frames][vertices][3]` positions.
    pub positions: Vec<f32>,
    pub labels: Vec<FrameLabel>,
    /// The walk node each output frame shows, `None` for the inside of a transition.
    pub nodes: Vec<Option<u32>>,
    pub n_transitions: usize,
}

impl WalkSequence {
    pub fn n_frames(&self) -> usize {
        self.labels.len()
    }
}

/// Algorithm 3: the mesh sequence of `walk` placed by `start`, with frames labelled original or
/// synthetic. Transitions are blended non-linearly (thesis 2.4.3) along their DTW warps.
pub fn walk_sequence(
    subject: &Subject,
    model: &WalkModel,
    walk: &[u32],
    start: &PlaneMotion,
) -> Result<WalkSequence, WalkError> {
    let first = *walk.first().ok_or(WalkError::Empty)?;
    let frame = |g: u32| subject.frame(g as usize).expect("walk nodes are frames of the subject");
    let mut out = WalkSequence { positions: Vec::new(), labels: Vec::new(), nodes: Vec::new(), n_transitions: 0 };
    let push = |out: &mut WalkSequence, p: &[f32], g: &PlaneMotion, label, node| {
        let start = out.positions.len();
        out.positions.extend_from_slice(p);
        g.apply(&mut out.positions[start..]);
        out.labels.push(label);
        out.nodes.push(node);
    };
    let mut g = *start;
    push(&mut out, frame(first), &g, FrameLabel::Original, Some(first));
    for (at, w) in walk.windows(2).enumerate() {
        let (u, v) = (w[0], w[1]);
        match model.step(u, v).ok_or(WalkError::NotAnEdge { at, from: u, to: v })? {
            Step::Original => push(&mut out, frame(v), &g, FrameLabel::Original, Some(v)),
            Step::Transition(t) => {
                let src: Vec<&[f32]> = (u..u + t.li).map(frame).collect();
                let d0 = v + 1 - t.lj;
                let dst: Vec<&[f32]> = (d0..=v).map(frame).collect();
                let offsets: Vec<(usize, usize)> =
                    t.warp.iter().map(|&(a, b)| ((a - u) as usize, (b - d0) as usize)).collect();
                let s = blend(subject.topology(), model.up, &src, &dst, &offsets, Lambda::Ramp, Mixing::Nonlinear)?;
                for f in &s[1..s.len().saturating_sub(1)] {
                    push(&mut out, f, &g, FrameLabel::Synthetic, None);
                }
                g = g.after(&t.end);
                push(&mut out, frame(v), &g, FrameLabel::Original, Some(v));
                out.n_transitions += 1;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::edge_weights::edge_weights;
    use crate::essential_graph::essential_graph;
    use crate::transition_table::{TableParams, transition_table};
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    use surfcap_mesh::NoProgress;
    use surfcap_synth::{WormParams, worm_subject};

    /// The built-in tube (two crawling sequences), its essential graph and walk model.
    pub(crate) fn setup() -> (Subject, Graph, WalkModel) {
        let s = worm_subject(&WormParams { rings: 10, segments: 8, frames: 30, ..Default::default() }).unwrap();
        let d = distance_matrix(&s, &DistanceParams::default(), &NoProgress);
        let p = TableParams { l_min: 4, l_max: 8, slope: Some(3) };
        let table = transition_table(&d.values, s.frame_index(), &p, &NoProgress);
        let w = edge_weights(&table, s.frame_index(), 0.05);
        let g = essential_graph(&w, &NoProgress).graph;
        let model = WalkModel::new(&s, &g, &table, &d.values, p.slope, None);
        (s, g, model)
    }

    #[test]
    fn the_model_predicts_the_played_centres_and_labels_follow_algorithm_3() {
        let (s, g, model) = setup();
        assert!(model.n_transitions() > 0);
        let n = s.n_frames() as u32;
        // Two transitions, each entered after a few original frames.
        let (u, v) = g
            .edges()
            .iter()
            .map(|e| (e.from, e.to))
            .find(|&(a, b)| matches!(model.step(a, b), Some(Step::Transition(_))) && a >= 2 && b + 3 < n)
            .expect("a transition edge");
        // Then a second transition after a run of original frames, when there is one.
        let second = g.edges().iter().map(|e| (e.from, e.to)).find(|&(a, b)| {
            a > v
                && (v..a).all(|k| matches!(model.step(k, k + 1), Some(Step::Original)))
                && matches!(model.step(a, b), Some(Step::Transition(_)))
        });
        let mut walk: Vec<u32> = (u - 2..=u).collect();
        match second {
            Some((x, y)) => {
                walk.extend(v..=x);
                walk.push(y);
            }
            None => walk.extend(v..=v + 2),
        }
        let start = PlaneMotion { theta: 0.8, t: [1.0, -2.0], up: s.up_axis };
        let out = walk_sequence(&s, &model, &walk, &start).unwrap();
        let predicted = model.walk_centres(&walk, &start).unwrap();
        assert_eq!(out.n_frames(), predicted.len());
        assert_eq!(out.n_frames(), model.walk_duration(&walk).unwrap() + 1);
        let nv = s.topology().n_vertices();
        for (k, f) in out.positions.chunks_exact(3 * nv).enumerate() {
            let c = centre(f);
            let e = (0..3).map(|a| (c[a] - predicted[k][a]).abs()).fold(0.0, f64::max);
            assert!(e < 1e-4, "frame {k}: centre {c:?} vs predicted {:?}", predicted[k]);
        }
        // Original frames are the walk's nodes, placed by the running alignment; the first one
        // is the start placement of node walk[0].
        let originals: Vec<u32> = out.nodes.iter().flatten().copied().collect();
        assert_eq!(originals, walk);
        assert_eq!(out.labels.iter().filter(|l| **l == FrameLabel::Original).count(), walk.len());
        assert!(out.n_transitions >= 1);
        let mut first = s.frame(walk[0] as usize).unwrap().to_vec();
        start.apply(&mut first);
        let d0 = first.iter().zip(&out.positions[..3 * nv]).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
        assert!(d0 < 1e-5);
        // A step that is not an edge is refused with its position.
        let bad = [walk[0], walk[0] + 5];
        assert!(matches!(walk_sequence(&s, &model, &bad, &start), Err(WalkError::NotAnEdge { at: 0, .. })));
    }
}
