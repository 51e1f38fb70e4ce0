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
use surfcap_mesh::{FrameIndex, FrameLabel, Subject, UpAxis};

use crate::blend::{Lambda, blend_placements_from, centre};
use crate::dtw::{Slope, dtw_window};
use crate::error::{Error, Result};
use crate::graph::Graph;
use crate::repeat_passes::{Captured, FramePlay, FrameSource, earlier_plays, run_passes};
use crate::subject_placement::{Placement, captured_placements, subject_travel};
use crate::transition_frames::{FrameMix, Segment, transition_frames_played};
use crate::transition_table::TransitionTable;

/// The rigid track of one transition edge u -> v, in the coordinates where frame u is unmoved.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionTrack {
    /// Source segment u .. u + li, destination segment v + 1 - lj ..= v (global frames).
    pub li: u32,
    pub lj: u32,
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
    /// The last frame of a looping clip to its start ([`crate::clip_loops`]): one frame, like
    /// a successive frame, with the placement moved by this motion (the start's placement in
    /// the coordinates where the last frame is unmoved) so that the clip's travel carries on.
    Wrap(&'a PlaneMotion),
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
    /// Wrap edges of looping clips in the graph: last frame -> (start, its placement).
    wraps: HashMap<u32, (u32, PlaneMotion)>,
    /// The DTW slope constraint the tracks were computed with (their warps are recomputed, not
    /// stored: a dense graph has hundreds of thousands of transitions and plays a few).
    slope: Slope,
    /// How transitions place the subject: re-placed by Algorithm 2 when it travels, as
    /// captured when it does not ([`crate::subject_placement`]).
    placement: Placement,
}

impl WalkModel {
    /// Precomputes the tracks of every transition edge of `graph` (in parallel): each needs the
    /// DTW warp of its transition (from the distance matrix `d`) and one alignment angle per warp
    /// cell, but no pose interpolation.
    ///
    /// `tracked`: the vertices whose centre the model follows (all vertices when `None`). Inside
    /// a transition the tracked centre is the lambda-mix of the two moved frames' tracked
    /// centres: exact for the whole mesh (the non-linear interpolation keeps the mixed centre of
    /// mass), a close approximation for a vertex subset. `loops`: the subject's looping clips
    /// ([`crate::clip_loops::clip_loops`]), whose wrap edges the graph may hold.
    pub fn new(
        subject: &Subject,
        loops: &[crate::clip_loops::ClipLoop],
        graph: &Graph,
        table: &TransitionTable,
        d: &[f64],
        slope: Slope,
        tracked: Option<&[usize]>,
    ) -> Self {
        let index = subject.frame_index().clone();
        let n = table.n;
        let frame = |g: usize| subject.frame(g).expect("graph nodes are frames of the subject");
        let centres = frame_centres(subject, tracked);
        let mass: Vec<[f64; 3]> = match tracked {
            None => centres.clone(),
            Some(_) => (0..subject.n_frames()).map(|g| centre(frame(g))).collect(),
        };
        // Eq. 2.3 angles of every pair from three matrix products instead of one pass over the
        // vertices per warp cell.
        let gram = alignment_gram(subject, None);
        let up = subject.up_axis;
        let placement = subject_travel(subject).placement;
        // Wrap edges of looping clips that the graph holds.
        let wraps: HashMap<u32, (u32, PlaneMotion)> = loops
            .iter()
            .filter(|l| graph.find(l.last as usize, l.first as usize).is_some())
            .map(|l| (l.last, (l.first, crate::clip_loops::wrap_placement(subject, l))))
            .collect();
        let edges: Vec<(u32, u32)> = graph
            .edges()
            .iter()
            .filter(|e| !is_successive(&index, e.from as usize, e.to as usize))
            .filter(|e| wraps.get(&e.from).is_none_or(|w| w.0 != e.to))
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
                let (cs, cd) = (&mass[s0..s0 + li], &mass[d0..=v as usize]);
                let steps = match placement {
                    Placement::Aligned => {
                        blend_placements_from(up, cs, cd, &offsets, Lambda::Ramp, |n, m| gram.theta(s0 + n, d0 + m))
                    }
                    Placement::Captured => captured_placements(up, cs, cd, &offsets, Lambda::Ramp),
                };
                let last = steps.last()?;
                let mix = |st: &crate::blend::BlendStep| -> [f64; 3] {
                    let a = st.src.apply_point(centres[u as usize + st.n]);
                    let b = st.dst.apply_point(centres[d0 + st.m]);
                    std::array::from_fn(|k| (1.0 - st.lambda) * a[k] + st.lambda * b[k])
                };
                let inner = if steps.len() > 2 { steps[1..steps.len() - 1].iter().map(mix).collect() } else { vec![] };
                Some(((u, v), TransitionTrack { li: li as u32, lj: lj as u32, centres: inner, end: last.dst }))
            })
            .collect();
        WalkModel {
            up,
            fps: subject.fps,
            index,
            centres,
            tracks: tracks.into_iter().flatten().collect(),
            wraps,
            slope,
            placement,
        }
    }

    /// The DTW warp of transition u -> v as (source, destination) offsets into its segments
    /// u .. u + li and v + 1 - lj ..= v, recomputed from the distance matrix `d` the model was
    /// built from (the same deterministic DTW, so the same warp).
    pub fn warp(&self, d: &[f64], u: u32, v: u32) -> Option<Vec<(usize, usize)>> {
        let t = self.tracks.get(&(u, v))?;
        let (li, lj) = (t.li as usize, t.lj as usize);
        let w = dtw_window(d, self.centres.len(), u as usize, li, v as usize, lj, self.slope)?;
        let d0 = v as usize + 1 - lj;
        Some(w.path.iter().map(|&(a, b)| (a - u as usize, b - d0)).collect())
    }

    /// What the edge u -> v does, or `None` when it is not playable.
    pub fn step(&self, u: u32, v: u32) -> Option<Step<'_>> {
        if is_successive(&self.index, u as usize, v as usize) {
            Some(Step::Original)
        } else if let Some((w, g)) = self.wraps.get(&u)
            && *w == v
        {
            Some(Step::Wrap(g))
        } else {
            self.tracks.get(&(u, v)).map(Step::Transition)
        }
    }

    /// The frame that follows `u` as captured: u + 1 in its sequence, or the start of a looping
    /// clip after its last frame (the wrap); `None` at the end of a clip that does not loop.
    pub fn next(&self, u: u32) -> Option<(u32, Step<'_>)> {
        if is_successive(&self.index, u as usize, u as usize + 1) {
            Some((u + 1, Step::Original))
        } else {
            self.wraps.get(&u).map(|(v, g)| (*v, Step::Wrap(g)))
        }
    }

    /// The wrap edges (last frame, start) of the looping clips the model plays, sorted.
    pub fn wraps(&self) -> Vec<(u32, u32)> {
        let mut w: Vec<(u32, u32)> = self.wraps.iter().map(|(u, (v, _))| (*u, *v)).collect();
        w.sort();
        w
    }

    pub fn n_transitions(&self) -> usize {
        self.tracks.len()
    }

    /// How the transitions place the subject ([`crate::subject_placement`]).
    pub fn placement(&self) -> Placement {
        self.placement
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
            Step::Wrap(end) => {
                let g2 = g.after(end);
                emit(g2.apply_point(self.centres[v as usize]), true);
                g2
            }
        }
    }

    /// Predicted centre of mass of every output frame of `walk` placed by `start`.
    pub fn walk_centres(&self, walk: &[u32], start: &PlaneMotion) -> Result<Vec<[f64; 3]>> {
        let first = *walk.first().ok_or(Error::EmptyWalk)?;
        let mut out = vec![start.apply_point(self.centres[first as usize])];
        let mut g = *start;
        for (at, w) in walk.windows(2).enumerate() {
            let step = self.step(w[0], w[1]).ok_or(Error::NotAnEdge { at, from: w[0], to: w[1] })?;
            g = self.advance(step, &g, w[1], |c, _| out.push(c));
        }
        Ok(out)
    }

    /// Duration of a walk in frame intervals.
    pub fn walk_duration(&self, walk: &[u32]) -> Result<usize> {
        let mut t = 0;
        for (at, w) in walk.windows(2).enumerate() {
            t += match self.step(w[0], w[1]).ok_or(Error::NotAnEdge { at, from: w[0], to: w[1] })? {
                Step::Original | Step::Wrap(_) => 1,
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

    /// The transition tracks as rows of three numbers, for an on-disk cache (`.npy` [R, 3]),
    /// tracks in (u, v) order, each as: `[u, v, C]`, `[li, lj, 0]`, `[end theta, end t0,
    /// end t1]`, then its C inner centres; then every wrap edge of a looping clip in u order, as
    /// `[u, v, 0]`, `[0, 0, 0]`, `[theta, t0, t1]` (segment lengths 0, which no transition has,
    /// mark a wrap). Frame numbers are exact in f64.
    pub fn tracks_to_rows(&self) -> Vec<f64> {
        let mut keys: Vec<&(u32, u32)> = self.tracks.keys().collect();
        keys.sort();
        let mut rows = Vec::new();
        for &(u, v) in keys {
            let t = &self.tracks[&(u, v)];
            rows.extend([u as f64, v as f64, t.centres.len() as f64]);
            rows.extend([t.li as f64, t.lj as f64, 0.0]);
            rows.extend([t.end.theta, t.end.t[0], t.end.t[1]]);
            for c in &t.centres {
                rows.extend(c);
            }
        }
        for (u, v) in self.wraps() {
            let g = &self.wraps[&u].1;
            rows.extend([u as f64, v as f64, 0.0, 0.0, 0.0, 0.0, g.theta, g.t[0], g.t[1]]);
        }
        rows
    }

    /// The model of [`WalkModel::new`] from rows written by [`WalkModel::tracks_to_rows`] for
    /// the same subject and tracked vertices. Errors name the first row that does not fit (a
    /// cache written for another subject, or damaged).
    pub fn from_rows(subject: &Subject, rows: &[f64], tracked: Option<&[usize]>, slope: Slope) -> Result<Self> {
        let nf = subject.n_frames();
        if !rows.len().is_multiple_of(3) {
            return Err(Error::RowsNotTriples { numbers: rows.len() });
        }
        let rows: Vec<[f64; 3]> = rows.chunks_exact(3).map(|r| [r[0], r[1], r[2]]).collect();
        let frame = |x: f64, at: usize| -> Result<u32> {
            if x.fract() == 0.0 && x >= 0.0 && (x as usize) < nf {
                Ok(x as u32)
            } else {
                Err(Error::RowNotAFrame { row: at, value: x, frames: nf })
            }
        };
        let count = |x: f64, at: usize| -> Result<usize> {
            if x.fract() == 0.0 && x >= 0.0 && x <= (rows.len() - at) as f64 {
                Ok(x as usize)
            } else {
                Err(Error::RowNotACount { row: at, value: x })
            }
        };
        let mut tracks = HashMap::new();
        let mut wraps = HashMap::new();
        let mut at = 0;
        while at < rows.len() {
            if at + 3 > rows.len() {
                return Err(Error::TrackHeaderCutShort { row: at, left: rows.len() - at });
            }
            let [u, v, nc] = rows[at];
            let [li, lj, _] = rows[at + 1];
            let [theta, t0, t1] = rows[at + 2];
            let (u, v, nc) = (frame(u, at)?, frame(v, at)?, count(nc, at)?);
            let (li, lj) = (count(li, at + 1)? as u32, count(lj, at + 1)? as u32);
            if ![theta, t0, t1].iter().all(|x| x.is_finite()) || at + 3 + nc > rows.len() {
                return Err(Error::TrackCutShort { row: at, from: u, to: v });
            }
            let centres: Vec<[f64; 3]> = rows[at + 3..at + 3 + nc].to_vec();
            if centres.iter().flatten().any(|x| !x.is_finite()) {
                return Err(Error::TrackNonFiniteCentre { row: at, from: u, to: v });
            }
            let end = PlaneMotion { theta, t: [t0, t1], up: subject.up_axis };
            if li == 0 && lj == 0 && nc == 0 {
                wraps.insert(u, (v, end));
            } else {
                tracks.insert((u, v), TransitionTrack { li, lj, centres, end });
            }
            at += 3 + nc;
        }
        let index = subject.frame_index().clone();
        let centres = frame_centres(subject, tracked);
        let placement = subject_travel(subject).placement;
        Ok(WalkModel { up: subject.up_axis, fps: subject.fps, index, centres, tracks, wraps, slope, placement })
    }
}

/// The tracked centre of every frame of the subject.
fn frame_centres(subject: &Subject, tracked: Option<&[usize]>) -> Vec<[f64; 3]> {
    (0..subject.n_frames()).map(|g| tracked_centre(subject.frame(g).expect("frames of the subject"), tracked)).collect()
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
    /// The captured frames each output frame is made from, with the blend weight.
    pub mix: Vec<FrameMix>,
    /// How each output frame was played: a repeat of a frame shown before, from a substitute.
    pub plays: Vec<FramePlay>,
    pub n_transitions: usize,
}

impl WalkSequence {
    pub fn n_frames(&self) -> usize {
        self.labels.len()
    }
}

/// Algorithm 3: the mesh sequence of `walk` placed by `start`, with frames labelled original or
/// synthetic. Transitions are blended non-linearly (thesis 2.4.3) along their DTW warps
/// (recomputed from `d`, the distance matrix the model was built from).
pub fn walk_sequence(
    subject: &Subject,
    model: &WalkModel,
    d: &[f64],
    walk: &[u32],
    start: &PlaneMotion,
) -> Result<WalkSequence> {
    walk_sequence_with(subject, model, d, walk, start, &Captured)
}

/// [`walk_sequence`] showing, on each run of original frames, what `source` gives for the run's
/// pass ([`run_passes`]: 0 the first time the walk shows those frames, then one more per
/// repetition) in the captured frames' stead (thesis 6.6). Every rigid placement is the
/// captured walk's: a substitute frame is moved as its captured frame is, and a transition is
/// placed by Blend on the captured frames while interpolating the frames shown on either side
/// ([`crate::transition_frames::transition_frames_played`]), so the junctions meet the poses
/// actually played and the walk's centre track is the one the searches solved for, up to the
/// substitutes' own deviation. With [`Captured`] (or any source that substitutes nothing) the
/// output is [`walk_sequence`]'s to the bit.
pub fn walk_sequence_with(
    subject: &Subject,
    model: &WalkModel,
    d: &[f64],
    walk: &[u32],
    start: &PlaneMotion,
    source: &dyn FrameSource,
) -> Result<WalkSequence> {
    let first = *walk.first().ok_or(Error::EmptyWalk)?;
    let mut steps = Vec::with_capacity(walk.len().saturating_sub(1));
    for (at, w) in walk.windows(2).enumerate() {
        steps.push(model.step(w[0], w[1]).ok_or(Error::NotAnEdge { at, from: w[0], to: w[1] })?);
    }
    let passes = run_passes(walk, |k| matches!(steps[k], Step::Transition(_)));
    let earlier = earlier_plays(walk);
    let expected = 3 * subject.topology().n_vertices();
    // The frame shown for global frame g on `pass`, with its variant (`None`: as captured);
    // `None` altogether when g is not a frame of the subject.
    let shown = |pass: usize, g: usize| -> Result<Option<(Option<u32>, &[f32])>> {
        let Some(captured) = subject.frame(g) else { return Ok(None) };
        match source.substitute(pass, g as u32) {
            None => Ok(Some((None, captured))),
            Some(sub) if sub.positions.len() == expected => Ok(Some((Some(sub.variant), sub.positions))),
            Some(sub) => Err(Error::SubstituteSize {
                frame: subject.frame_index().label(g),
                pass,
                variant: sub.variant,
                numbers: sub.positions.len(),
                expected,
            }),
        }
    };
    let node = |k: usize| -> Result<(Option<u32>, &[f32])> {
        Ok(shown(passes[k], walk[k] as usize)?.expect("walk nodes are frames of the subject"))
    };
    let mut out = WalkSequence {
        positions: Vec::new(),
        labels: Vec::new(),
        nodes: Vec::new(),
        mix: Vec::new(),
        plays: Vec::new(),
        n_transitions: 0,
    };
    let push = |out: &mut WalkSequence, p: &[f32], g: &PlaneMotion, label, node: Option<u32>, mix: FrameMix, play| {
        let start = out.positions.len();
        out.positions.extend_from_slice(p);
        g.apply(&mut out.positions[start..]);
        out.labels.push(label);
        out.nodes.push(node);
        out.mix.push(mix);
        out.plays.push(play);
    };
    let original = |k: usize, variant: Option<u32>| FramePlay { earlier: earlier[k], from: variant, to: variant };
    let mut g = *start;
    let (variant, p) = node(0)?;
    push(&mut out, p, &g, FrameLabel::Original, Some(first), FrameMix::original(first), original(0, variant));
    for (at, (w, step)) in walk.windows(2).zip(&steps).enumerate() {
        let (u, v) = (w[0], w[1]);
        let (variant, p) = node(at + 1)?;
        match step {
            Step::Original => {
                push(&mut out, p, &g, FrameLabel::Original, Some(v), FrameMix::original(v), original(at + 1, variant))
            }
            Step::Wrap(end) => {
                g = g.after(end);
                push(&mut out, p, &g, FrameLabel::Original, Some(v), FrameMix::original(v), original(at + 1, variant))
            }
            Step::Transition(t) => {
                let not_an_edge = Error::NotAnEdge { at, from: u, to: v };
                // The frames shown on either side: the source segment from the pass of the run
                // left, the destination segment from the pass of the run entered.
                let (s0, d0) = (u as usize, (v + 1 - t.lj) as usize);
                let segment = |pass: usize, range: std::ops::Range<usize>| {
                    range
                        .map(|g| shown(pass, g)?.ok_or(not_an_edge.clone()))
                        .collect::<Result<Vec<(Option<u32>, &[f32])>>>()
                };
                let src = segment(passes[at], s0..s0 + t.li as usize)?;
                let dst = segment(passes[at + 1], d0..v as usize + 1)?;
                let ends = ((u as usize, t.li as usize), (v as usize, t.lj as usize));
                let tf =
                    transition_frames_played(subject, d, ends.0, ends.1, model.slope, model.placement, |seg, g| {
                        match seg {
                            Segment::Source => src.get(g.wrapping_sub(s0)),
                            Segment::Destination => dst.get(g.wrapping_sub(d0)),
                        }
                        .map(|f| f.1)
                    })?
                    .ok_or(not_an_edge)?;
                let (s, mix) = (&tf.frames, tf.mix());
                for (f, m) in s.iter().zip(&mix).take(s.len().saturating_sub(1)).skip(1) {
                    let play =
                        FramePlay { earlier: 0, from: src[m.from as usize - s0].0, to: dst[m.to as usize - d0].0 };
                    push(&mut out, f, &g, FrameLabel::Synthetic, None, *m, play);
                }
                g = g.after(&t.end);
                push(&mut out, p, &g, FrameLabel::Original, Some(v), FrameMix::original(v), original(at + 1, variant));
                out.n_transitions += 1;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::clip_loops::clip_loops;
    use crate::edge_weights::{Alpha, edge_weights};
    use crate::essential_graph::essential_graph;
    use crate::transition_table::{TableParams, transition_table};
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    use surfcap_mesh::{NoProgress, Sequence};

    /// The built-in tube (two crawling sequences), its essential graph and walk model.
    pub(crate) fn setup() -> (Subject, Graph, WalkModel, Vec<f64>) {
        let s = worm_subject(&WormParams { rings: 10, segments: 8, frames: 30, ..Default::default() }).unwrap();
        let d = distance_matrix(&s, &DistanceParams::default(), &NoProgress);
        let p = TableParams { l_min: 4, l_max: 8, slope: Some(3) };
        let table = transition_table(&d.values, s.frame_index(), &p, &NoProgress).unwrap();
        let w = edge_weights(&table, s.frame_index(), Alpha::new(0.05).unwrap()).unwrap();
        let g = essential_graph(&w, &NoProgress).graph;
        let model = WalkModel::new(&s, &clip_loops(&s), &g, &table, &d.values, p.slope, None);
        (s, g, model, d.values)
    }

    #[test]
    fn tracks_round_trip_through_rows_and_damaged_rows_are_refused() {
        let (s, _, model, _) = setup();
        let rows = model.tracks_to_rows();
        let back = WalkModel::from_rows(&s, &rows, None, model.slope).unwrap();
        assert_eq!(back.tracks, model.tracks);
        assert_eq!(back.centres, model.centres);
        let slope = model.slope;
        assert!(
            WalkModel::from_rows(&s, &rows[..rows.len() - 3], None, slope).unwrap_err().to_string().contains("row ")
        );
        let mut bad = rows.clone();
        bad[0] = s.n_frames() as f64;
        assert!(WalkModel::from_rows(&s, &bad, None, slope).unwrap_err().to_string().contains("row 0"));
        assert!(WalkModel::from_rows(&s, &rows[..4], None, slope).is_err());
    }

    /// The crawling tube travels: its transitions re-place the destination (Algorithm 2). The
    /// same crawl held in place (every frame moved back over its first centre) does not: every
    /// transition keeps the captured placement, so each original frame of a walk through
    /// transitions is the captured frame, unmoved.
    #[test]
    fn a_travelling_subject_is_re_placed_and_one_held_in_place_keeps_its_placement() {
        let (s, g, model, _) = setup();
        assert_eq!(model.placement(), Placement::Aligned);
        let id = PlaneMotion::identity(s.up_axis);
        let re_placed =
            g.edges().iter().any(|e| matches!(model.step(e.from, e.to), Some(Step::Transition(t)) if t.end != id));
        assert!(re_placed, "some transition re-places the crawl");
        let held: Vec<Sequence> = s
            .sequences()
            .iter()
            .map(|q| {
                let c0 = centre(q.frame(0));
                let mut positions = Vec::new();
                for f in 0..q.n_frames() {
                    let mut p = q.frame(f).to_vec();
                    let c = centre(&p);
                    for v in p.chunks_exact_mut(3) {
                        v[0] -= (c[0] - c0[0]) as f32;
                        v[2] -= (c[2] - c0[2]) as f32;
                    }
                    positions.extend(p);
                }
                Sequence::new(q.name.clone(), q.n_vertices(), positions).unwrap()
            })
            .collect();
        let h = Subject::new("held", s.topology().clone(), held, s.fps, s.up_axis, s.units.clone()).unwrap();
        let dh = distance_matrix(&h, &DistanceParams::default(), &NoProgress).values;
        let p = TableParams { l_min: 4, l_max: 8, slope: Some(3) };
        let table = transition_table(&dh, h.frame_index(), &p, &NoProgress).unwrap();
        let w = edge_weights(&table, h.frame_index(), Alpha::new(0.05).unwrap()).unwrap();
        let gh = essential_graph(&w, &NoProgress).graph;
        let mh = WalkModel::new(&h, &clip_loops(&h), &gh, &table, &dh, p.slope, None);
        assert_eq!(mh.placement(), Placement::Captured);
        let (u, v) = gh
            .edges()
            .iter()
            .map(|e| (e.from, e.to))
            .find(|&(a, b)| {
                a >= 1
                    && matches!(mh.step(a - 1, a), Some(Step::Original))
                    && matches!(mh.step(a, b), Some(Step::Transition(t)) if t.end == id)
            })
            .expect("a transition edge");
        let walk = vec![u - 1, u, v];
        let out = walk_sequence(&h, &mh, &dh, &walk, &id).unwrap();
        let nv = h.topology().n_vertices();
        let last = &out.positions[out.positions.len() - 3 * nv..];
        assert_eq!(last, h.frame(v as usize).unwrap(), "the destination where it was captured");
        assert_eq!(&out.positions[..3 * nv], h.frame(u as usize - 1).unwrap());
    }

    /// Two one-cycle clips of a gliding, bobbing quad (8 frames each, 0.1 m per frame along x
    /// with a bob of period 8): both loop, the graph holds their wrap edges, and a walk through
    /// a wrap keeps gliding 0.1 m per frame in the model, in the played frames and through the
    /// model's cache rows; a path three clips long is followed through the wraps.
    #[test]
    fn looping_clips_play_their_wrap_as_a_step_that_carries_the_travel_on() {
        use crate::clip_loops::add_wrap_edges;
        use surfcap_mesh::{Sequence, Topology, Units, UpAxis};
        let clip = |phase: f64| -> Vec<f32> {
            (0..8)
                .flat_map(|f| {
                    let (x, b) =
                        (0.1 * f as f32, (0.2 * (std::f64::consts::TAU * (f as f64 / 8.0 + phase)).sin()) as f32);
                    [x, 0.0, 0.0, x + 0.3, b, 0.0, x + 0.3, 0.0, 0.3, x, 0.1, 0.3]
                })
                .collect()
        };
        let topology = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], None).unwrap();
        let seqs = vec![Sequence::new("a", 4, clip(0.0)).unwrap(), Sequence::new("b", 4, clip(0.3)).unwrap()];
        let s = Subject::new("quad", topology, seqs, 30.0, UpAxis::parse("+y").unwrap(), Units::metres()).unwrap();
        let loops = clip_loops(&s);
        assert_eq!(loops.iter().map(|l| (l.last, l.first)).collect::<Vec<_>>(), vec![(7, 0), (15, 8)]);
        let d = distance_matrix(&s, &DistanceParams::default(), &NoProgress);
        let p = TableParams { l_min: 2, l_max: 3, slope: Some(3) };
        let table = transition_table(&d.values, s.frame_index(), &p, &NoProgress).unwrap();
        let mut w = edge_weights(&table, s.frame_index(), Alpha::new(0.05).unwrap()).unwrap();
        add_wrap_edges(&mut w, &loops);
        let g = essential_graph(&w, &NoProgress).graph;
        let model = WalkModel::new(&s, &clip_loops(&s), &g, &table, &d.values, p.slope, None);
        assert_eq!(model.wraps(), vec![(7, 0), (15, 8)]);
        assert!(
            matches!(model.next(7), Some((0, Step::Wrap(_)))) && matches!(model.next(3), Some((4, Step::Original)))
        );
        let walk: Vec<u32> = (0..8).chain(0..8).chain(0..3).collect();
        let start = PlaneMotion::identity(s.up_axis);
        let centres = model.walk_centres(&walk, &start).unwrap();
        for (k, c) in centres.windows(2).enumerate() {
            assert!((c[1][0] - c[0][0] - 0.1).abs() < 1e-6 && (c[1][2] - c[0][2]).abs() < 1e-6, "step {k}: {c:?}");
        }
        assert_eq!(model.walk_duration(&walk).unwrap(), walk.len() - 1);
        let played = walk_sequence(&s, &model, &d.values, &walk, &start).unwrap();
        assert_eq!(played.n_frames(), walk.len());
        assert!(played.labels.iter().all(|l| *l == FrameLabel::Original));
        let (first, last) = (&played.positions[..12], &played.positions[played.positions.len() - 12..]);
        assert!((last[0] - first[0] - 0.1 * 18.0).abs() < 1e-4, "{} after 18 steps", last[0] - first[0]);
        let back = WalkModel::from_rows(&s, &model.tracks_to_rows(), None, p.slope).unwrap();
        assert_eq!(back.wraps(), model.wraps());
        assert_eq!(back.walk_centres(&walk, &start).unwrap(), centres);
        use crate::path_following::{Curve, PathSearch, follow_path};
        let curve = Curve::new(vec![[0.0, 0.0, 0.0], [2.4, 0.0, 0.0]], vec![0, 2]).unwrap();
        let search = PathSearch { window: 0.4, ..PathSearch::for_fps(30.0) };
        let r = follow_path(&model, &g, &curve, &[], None, &search).unwrap();
        assert!(r.travelled >= curve.length());
        assert!(r.walk.windows(2).any(|w| matches!(model.step(w[0], w[1]), Some(Step::Wrap(_)))), "{:?}", r.walk);
    }

    #[test]
    fn the_model_predicts_the_played_centres_and_labels_follow_algorithm_3() {
        let (s, g, model, d) = setup();
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
        let out = walk_sequence(&s, &model, &d, &walk, &start).unwrap();
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
        // Each frame says what it is made of: an original frame is its node, a blended one
        // mixes the frame just before its transition's span with weights rising in (0, 1).
        assert_eq!(out.mix.len(), out.n_frames());
        let mut last_weight = 0.0;
        for (k, m) in out.mix.iter().enumerate() {
            match out.nodes[k] {
                Some(node) => {
                    assert_eq!(*m, FrameMix::original(node));
                    last_weight = 0.0;
                }
                None => {
                    assert!(
                        m.weight > last_weight && m.weight < 1.0,
                        "frame {k}: weight {} after {last_weight}",
                        m.weight
                    );
                    assert!(m.from < n && m.to < n && m.from != m.to);
                    last_weight = m.weight;
                }
            }
        }
        let mut first = s.frame(walk[0] as usize).unwrap().to_vec();
        start.apply(&mut first);
        let d0 = first.iter().zip(&out.positions[..3 * nv]).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
        assert!(d0 < 1e-5);
        // A source whose substitutes are the captured frames themselves plays the same walk to
        // the bit (every placement is the captured frame's), and records them as variants.
        struct Itself<'a>(&'a Subject);
        impl FrameSource for Itself<'_> {
            fn substitute(&self, pass: usize, frame: u32) -> Option<crate::repeat_passes::Substitute<'_>> {
                let positions = self.0.frame(frame as usize)?;
                Some(crate::repeat_passes::Substitute { variant: pass as u32 + 7, positions })
            }
        }
        let same = walk_sequence_with(&s, &model, &d, &walk, &start, &Itself(&s)).unwrap();
        assert_eq!(same.positions, out.positions);
        assert!(same.plays.iter().all(|p| p.from == Some(7) && p.to == Some(7)));
        assert!(out.plays.iter().all(|p| *p == FramePlay::default()), "no repeats in this walk");
        // A substitute of the wrong size is refused, naming its frame.
        struct Short<'a>(&'a Subject);
        impl FrameSource for Short<'_> {
            fn substitute(&self, _: usize, frame: u32) -> Option<crate::repeat_passes::Substitute<'_>> {
                let positions = &self.0.frame(frame as usize)?[3..];
                Some(crate::repeat_passes::Substitute { variant: 0, positions })
            }
        }
        let e = walk_sequence_with(&s, &model, &d, &walk, &start, &Short(&s)).unwrap_err().to_string();
        assert!(e.contains(&s.frame_index().label(walk[0] as usize)) && e.contains("expected"), "{e}");
        // A step that is not an edge is refused with its position.
        let bad = [walk[0], walk[0] + 5];
        assert!(matches!(walk_sequence(&s, &model, &d, &bad, &start), Err(Error::NotAnEdge { at: 0, .. })));
    }
}
