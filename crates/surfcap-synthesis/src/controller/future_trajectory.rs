//! Future-trajectory features of every move the controller can make, precomputed so that a
//! decision only compares numbers (the trajectory features of motion matching, Clavet 2016,
//! predicted here by the walk model instead of read from the captured clip, since a move is
//! a graph edge and the frames after it may come from another clip).
//!
//! A move leaves a source frame `u` and is either the clip continuing as captured (u + 1, or a
//! looping clip's wrap) or a transition edge u -> v of the essential graph (its Blend's rigid
//! track from the walk model, thesis 3.4.2, then v's clip as captured). Its feature is where
//! the tracked centre is and which way it heads at [`HORIZONS`] later times, in the coordinates
//! where frame `u` is unmoved, relative to u's centre: `(du, dv, cos h, sin h)` per horizon on
//! the ground plane (`cos`, `sin` both 0 where the frame shown is idle and has no heading). A
//! trajectory that reaches the end of a clip that does not loop stays where it ended.
//!
//! The index (our decision, measured by `surfcap-bench play`): the graph's own adjacency. A
//! decision may only take edges that leave the frames about to be shown, so the moves are
//! stored grouped by source frame (compressed rows, their features contiguous) and a decision
//! scans the few hundred rows of the next frames linearly. A k-d tree over all moves, as
//! graph-free motion matching uses to search every frame of the database, would answer
//! "nearest move anywhere" and then have to discard every move that does not leave the
//! current frames: on the 2,000-frame bench graph (about 340 transitions per frame) that is
//! 99.8% of them, so its pruning buys nothing here.
//!
//! Only moves into live frames (from which the walk can go on for ever: [`crate`]'s dead-end
//! analysis, `surfcap_motion::dead_ends`) are stored, so no decision can enter a dead end.

use rayon::prelude::*;
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_motion::dead_ends::live_nodes;
use surfcap_motion::graph::{Edge, Graph};
use surfcap_motion::walk_sequence::{Step, WalkModel};

use super::frame_motion::FrameMotion;

/// Horizons of a feature, in seconds after the move's source frame.
pub const HORIZONS: [f64; 3] = [1.0 / 3.0, 2.0 / 3.0, 1.0];

/// Numbers per feature: (du, dv, cos, sin) per horizon.
pub const FEATURE: usize = 4 * HORIZONS.len();

/// The moves leaving every frame and their features.
#[derive(Debug, Clone)]
pub struct FutureTrajectories {
    /// The horizons in frames.
    pub horizons: [usize; HORIZONS.len()],
    /// `to[offsets[u]..offsets[u + 1]]`: the transitions leaving frame u into live frames.
    offsets: Vec<usize>,
    pub to: Vec<u32>,
    /// Realism cost of each transition: its edge weight over the median transition weight.
    pub realism: Vec<f32>,
    /// Feature of each transition, [`FEATURE`] numbers each.
    pub features: Vec<f32>,
    /// Feature of continuing as captured from each frame.
    pub continuation: Vec<f32>,
    /// Whether the frame after each frame as captured (u + 1 or the wrap) is live.
    pub continues: Vec<bool>,
    /// Whether the walk can go on for ever from each frame.
    pub live: Vec<bool>,
    /// The median transition weight (the realism cost's unit).
    pub median_weight: f64,
}

impl FutureTrajectories {
    /// The moves of `graph` played by `model`, with the frames' headings from `motion`.
    pub fn new(model: &WalkModel, graph: &Graph, motion: &FrameMotion) -> Self {
        let n = model.centres.len();
        let horizons = HORIZONS.map(|h| (h * model.fps).round().max(1.0) as usize);
        // The playable edges: successive frames and wraps, and the transitions with a track.
        let transition = |e: &Edge| matches!(model.step(e.from, e.to), Some(Step::Transition(_)));
        let playable: Vec<Edge> = (0..n as u32)
            .flat_map(|u| {
                let next = model.next(u).map(|(v, _)| Edge { from: u, to: v, weight: 1.0 });
                next.into_iter().chain(graph.out(u as usize).iter().filter(|e| transition(e)).copied())
            })
            .collect();
        let live = live_nodes(&Graph::new(n, playable));
        let mut weights: Vec<f64> =
            graph.edges().iter().filter(|e| transition(e) && live[e.to as usize]).map(|e| e.weight).collect();
        weights.sort_by(f64::total_cmp);
        let median_weight = weights.get(weights.len() / 2).copied().filter(|w| *w > 0.0).unwrap_or(1.0);
        let rows: Vec<(Vec<u32>, Vec<f32>, Vec<f32>)> = (0..n as u32)
            .into_par_iter()
            .map(|u| {
                let (mut to, mut realism, mut features) = (Vec::new(), Vec::new(), Vec::new());
                for e in graph.out(u as usize) {
                    if !live[e.to as usize] {
                        continue;
                    }
                    if let Some(step @ Step::Transition(_)) = model.step(e.from, e.to) {
                        to.push(e.to);
                        realism.push((e.weight / median_weight) as f32);
                        features.extend(feature(model, motion, &horizons, u, Some((step, e.to))));
                    }
                }
                (to, realism, features)
            })
            .collect();
        let continuation: Vec<f32> =
            (0..n as u32).into_par_iter().flat_map_iter(|u| feature(model, motion, &horizons, u, None)).collect();
        let continues = (0..n as u32).map(|u| model.next(u).is_some_and(|(v, _)| live[v as usize])).collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        let (mut to, mut realism, mut features) = (Vec::new(), Vec::new(), Vec::new());
        for (t, r, f) in rows {
            to.extend(t);
            realism.extend(r);
            features.extend(f);
            offsets.push(to.len());
        }
        FutureTrajectories { horizons, offsets, to, realism, features, continuation, continues, live, median_weight }
    }

    /// The positions in [`FutureTrajectories::to`] (and rows of the features) of the transitions
    /// leaving frame `u`.
    pub fn leaving(&self, u: u32) -> std::ops::Range<usize> {
        self.offsets[u as usize]..self.offsets[u as usize + 1]
    }

    /// The feature of transition row `k`.
    pub fn feature(&self, k: usize) -> &[f32] {
        &self.features[k * FEATURE..(k + 1) * FEATURE]
    }

    /// The feature of continuing from frame `u` as captured.
    pub fn continuation(&self, u: u32) -> &[f32] {
        &self.continuation[u as usize * FEATURE..(u as usize + 1) * FEATURE]
    }

    /// Transitions stored (into live frames).
    pub fn n_transitions(&self) -> usize {
        self.to.len()
    }

    /// Bytes the features and rows take.
    pub fn bytes(&self) -> usize {
        4 * (self.features.len() + self.continuation.len() + self.realism.len() + self.to.len())
            + std::mem::size_of::<usize>() * self.offsets.len()
            + 2 * self.live.len()
    }
}

/// The feature of a move from `u`: `first` the transition taken (`None`: continue as captured).
fn feature(
    model: &WalkModel,
    motion: &FrameMotion,
    horizons: &[usize; HORIZONS.len()],
    u: u32,
    first: Option<(Step<'_>, u32)>,
) -> [f32; FEATURE] {
    let (iu, iv, _) = plane_axes(model.up);
    let origin = model.centres[u as usize];
    let last_horizon = horizons[horizons.len() - 1];
    // Centre and heading of every frame shown after u, up to the last horizon.
    let mut shown: Vec<([f64; 3], f64)> = Vec::with_capacity(last_horizon);
    let mut g = PlaneMotion::identity(model.up);
    let mut node = u;
    let take = |step: Step<'_>, v: u32, g: &PlaneMotion, shown: &mut Vec<([f64; 3], f64)>| -> PlaneMotion {
        let g2 = model.advance(step, g, v, |c, _| shown.push((c, f64::NAN)));
        // Inside a transition the body turns from the source's heading to the destination's:
        // every frame it adds heads as its destination does (the Blend ends there).
        let h = motion.heading[v as usize] - g2.theta;
        let from = shown.len().saturating_sub(step_frames(step));
        for s in &mut shown[from..] {
            s.1 = h;
        }
        g2
    };
    if let Some((step, v)) = first {
        g = take(step, v, &g, &mut shown);
        node = v;
    }
    while shown.len() < last_horizon {
        let Some((v, step)) = model.next(node) else { break };
        g = take(step, v, &g, &mut shown);
        node = v;
    }
    let mut out = [0f32; FEATURE];
    for (k, &h) in horizons.iter().enumerate() {
        let (c, heading) = match shown.get(h - 1).or(shown.last()) {
            Some(x) => *x,
            None => (origin, motion.heading[u as usize]),
        };
        out[4 * k] = (c[iu] - origin[iu]) as f32;
        out[4 * k + 1] = (c[iv] - origin[iv]) as f32;
        if heading.is_finite() {
            out[4 * k + 2] = heading.cos() as f32;
            out[4 * k + 3] = heading.sin() as f32;
        }
    }
    out
}

/// Output frames one step adds.
fn step_frames(step: Step<'_>) -> usize {
    match step {
        Step::Original | Step::Wrap(_) => 1,
        Step::Transition(t) => t.duration(),
    }
}
