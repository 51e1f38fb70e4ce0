//! Plays a walk found in a graph into a mesh sequence (thesis Algorithm 3), with what the
//! reports say about it: frame counts by label, transitions, the runs of original frames, and
//! the tracked centre of every output frame; optionally with substitutes (learned variants,
//! [`crate::frame_variants`]) shown when the walk repeats frames (thesis 6.1: endless motion that does not repeat itself).

use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::{FrameLabel, Sequence, Subject};
use surfcap_motion::repeat_passes::{Captured, FramePlay, FrameSource, run_passes};
use surfcap_motion::transition_frames::FrameMix;
use surfcap_motion::walk_sequence::{Step, WalkModel, tracked_centre, walk_sequence_with};

use crate::error::{Error, Result};
use crate::pipeline::{GraphParams, Pipeline};

/// A run of original frames of one sequence, or a transition between two frames, in the
/// user's `sequence:frame` terms.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum WalkSegment {
    Run { sequence: String, first: usize, last: usize },
    Transition { transition: String },
}

/// A played walk.
#[derive(Debug, Clone)]
pub struct PlayedWalk {
    /// The frames, labelled original or synthetic, tagged `synthesised`.
    pub sequence: Sequence,
    /// The tracked centre of every output frame, from the played positions.
    pub centres: Vec<[f64; 3]>,
    pub original_frames: usize,
    pub synthetic_frames: usize,
    pub transitions: usize,
    pub segments: Vec<WalkSegment>,
    /// The captured frames (global numbers) each output frame is made from, with the weight
    /// its transition blends them by: what a per-frame texture follows (thesis 4: textures of synthesised frames).
    pub mix: Vec<FrameMix>,
    /// How each output frame was played: a repeat of a captured frame shown before, the
    /// variants it shows.
    pub plays: Vec<FramePlay>,
    /// Time spent blending the transitions.
    pub blend_seconds: f64,
}

impl PlayedWalk {
    pub fn frames(&self) -> usize {
        self.original_frames + self.synthetic_frames
    }
}

/// Plays `walk` (global frames, consecutive ones joined by edges of the graph of `p`) placed by
/// `start`, as the sequence `name`: original frames as captured, transitions blended along
/// their DTW warps (recomputed from the chain's distance matrix), the centre of `tracked`
/// (all vertices when `None`) measured on every output frame.
pub fn play_walk(
    pipe: &Pipeline,
    p: &GraphParams,
    tracked: Option<&[usize]>,
    walk: &[u32],
    start: &PlaneMotion,
    name: &str,
) -> Result<PlayedWalk> {
    play_walk_with(pipe, p, tracked, walk, start, name, &Captured)
}

/// [`play_walk`] showing what `source` gives in the captured frames' stead on each repetition
/// of a run of frames (e.g. [`crate::frame_variants::FrameVariants`]), every frame placed as its
/// captured frame is (`surfcap_motion::walk_sequence::walk_sequence_with`).
pub fn play_walk_with(
    pipe: &Pipeline,
    p: &GraphParams,
    tracked: Option<&[usize]>,
    walk: &[u32],
    start: &PlaneMotion,
    name: &str,
    source: &dyn FrameSource,
) -> Result<PlayedWalk> {
    let s = pipe.subject();
    let model = pipe.walk_model(p, tracked)?;
    let d = pipe.chain_distances()?;
    let t0 = Instant::now();
    let ws = walk_sequence_with(s, &model.value, &d.value.values, walk, start, source)?;
    let blend_seconds = t0.elapsed().as_secs_f64();
    let nv = s.topology().n_vertices();
    let centres = ws.positions.chunks_exact(3 * nv).map(|f| tracked_centre(f, tracked)).collect();
    let original_frames = ws.labels.iter().filter(|l| **l == FrameLabel::Original).count();
    let synthetic_frames = ws.labels.len() - original_frames;
    let sequence = Sequence::new(name, nv, ws.positions)?.with_labels(ws.labels)?.with_tags(vec!["synthesised".into()]);
    Ok(PlayedWalk {
        sequence,
        centres,
        original_frames,
        synthetic_frames,
        transitions: ws.n_transitions,
        segments: walk_segments(s, &model.value, walk)?,
        mix: ws.mix,
        plays: ws.plays,
        blend_seconds,
    })
}

/// What a played walk repeated and how much of it variants showed (a report's `variation`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RepeatSummary {
    /// Output frames.
    pub frames: usize,
    /// Original output frames showing a captured frame the walk had shown before.
    pub repeats: usize,
    /// Output frames made (at least in part) from a variant.
    pub played_as_variants: usize,
    /// Per sequence of the subject that a variant was shown for.
    pub sequences: Vec<SequenceVariation>,
}

/// The variants shown for one sequence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SequenceVariation {
    pub sequence: String,
    /// Output frames made (at least in part) from a variant of this sequence.
    pub frames_as_variants: usize,
    /// The distinct variants shown, in increasing order.
    pub variants: Vec<u32>,
}

impl PlayedWalk {
    /// The walk's repeats and the variants shown, per sequence of `subject` (the subject it
    /// was played from).
    pub fn repeat_summary(&self, subject: &Subject) -> RepeatSummary {
        let nq = subject.sequences().len();
        let mut frames = vec![0; nq];
        let mut variants: Vec<Vec<u32>> = vec![Vec::new(); nq];
        for (m, play) in self.mix.iter().zip(&self.plays) {
            let mut shown = [None; 2];
            for (k, (g, v)) in [(m.from, play.from), (m.to, play.to)].into_iter().enumerate() {
                if let (Some(v), Some((q, _))) = (v, subject.frame_index().locate(g as usize)) {
                    shown[k] = Some(q);
                    if !variants[q].contains(&v) {
                        variants[q].push(v);
                    }
                }
            }
            for (k, q) in shown.iter().enumerate() {
                if let Some(q) = *q
                    && (k == 0 || shown[0] != Some(q))
                {
                    frames[q] += 1;
                }
            }
        }
        RepeatSummary {
            frames: self.plays.len(),
            repeats: self.plays.iter().filter(|p| p.is_repeat()).count(),
            played_as_variants: self.plays.iter().filter(|p| p.is_variant()).count(),
            sequences: (0..nq)
                .filter(|&q| frames[q] > 0)
                .map(|q| {
                    variants[q].sort_unstable();
                    SequenceVariation {
                        sequence: subject.sequences()[q].name.clone(),
                        frames_as_variants: frames[q],
                        variants: variants[q].clone(),
                    }
                })
                .collect(),
        }
    }
}

/// Per sequence of the subject, the largest pass (`surfcap_motion::repeat_passes::run_passes`)
/// at which `walk` shows its frames: how many variants of it the walk can use before they come
/// round again (0: the walk never repeats its frames).
pub fn walk_passes(s: &Subject, model: &WalkModel, walk: &[u32]) -> Result<Vec<usize>> {
    let mut transition = Vec::with_capacity(walk.len().saturating_sub(1));
    for (at, w) in walk.windows(2).enumerate() {
        let step = model.step(w[0], w[1]).ok_or(surfcap_motion::Error::NotAnEdge { at, from: w[0], to: w[1] })?;
        transition.push(matches!(step, Step::Transition(_)));
    }
    let mut out = vec![0; s.sequences().len()];
    for (&g, pass) in walk.iter().zip(run_passes(walk, |k| transition[k])) {
        let (q, _) = s
            .frame_index()
            .locate(g as usize)
            .ok_or_else(|| Error::Request(format!("walk node {g}: the subject has {} frames", s.n_frames())))?;
        out[q] = out[q].max(pass);
    }
    Ok(out)
}

/// The walk as runs of original frames and the transitions between them.
pub fn walk_segments(s: &Subject, model: &WalkModel, walk: &[u32]) -> Result<Vec<WalkSegment>> {
    let name = |g: u32| -> Result<(String, usize)> {
        let (q, f) = s
            .frame_index()
            .locate(g as usize)
            .ok_or_else(|| Error::Request(format!("walk node {g}: the subject has {} frames", s.n_frames())))?;
        Ok((s.sequences()[q].name.clone(), f))
    };
    let mut out = Vec::new();
    let mut run_start = 0;
    for k in 1..=walk.len() {
        let ends_run = k == walk.len() || matches!(model.step(walk[k - 1], walk[k]), Some(Step::Transition(_)));
        if ends_run {
            let (sequence, first) = name(walk[run_start])?;
            let (_, last) = name(walk[k - 1])?;
            out.push(WalkSegment::Run { sequence, first, last });
            if k < walk.len() {
                let (qa, fa) = name(walk[k - 1])?;
                let (qb, fb) = name(walk[k])?;
                out.push(WalkSegment::Transition { transition: format!("{qa}:{fa} -> {qb}:{fb}") });
            }
            run_start = k;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph_kind::GraphKind;
    use crate::pipeline::CacheStore;
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_mesh::NoProgress;
    use surfcap_motion::transition_table::TableParams;

    #[test]
    fn a_walk_with_one_transition_plays_with_its_labels_and_segments() {
        let s = worm_subject(&WormParams { rings: 8, segments: 6, frames: 24, ..Default::default() }).unwrap();
        let pipe = Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress));
        let p = GraphParams {
            table: TableParams { l_min: 3, l_max: 6, slope: Some(3) },
            kind: GraphKind::Essential,
            alpha: surfcap_motion::edge_weights::Alpha::new(0.05).unwrap(),
        };
        let graph = pipe.graph(&p).unwrap();
        let model = pipe.walk_model(&p, None).unwrap();
        let (u, v) = graph
            .value
            .edges()
            .iter()
            .map(|e| (e.from, e.to))
            .find(|&(a, b)| a >= 1 && matches!(model.value.step(a, b), Some(Step::Transition(_))))
            .expect("a transition edge");
        let walk = vec![u - 1, u, v];
        let up = pipe.subject().up_axis;
        let played = play_walk(&pipe, &p, None, &walk, &PlaneMotion::identity(up), "w").unwrap();
        assert_eq!(played.transitions, 1);
        assert_eq!(played.original_frames, 3);
        assert_eq!(played.frames(), played.sequence.n_frames());
        assert_eq!(played.centres.len(), played.frames());
        assert!(played.synthetic_frames > 0);
        assert_eq!(played.sequence.tags, vec!["synthesised".to_string()]);
        assert_eq!(played.segments.len(), 3);
        assert!(matches!(&played.segments[1], WalkSegment::Transition { transition } if transition.contains(" -> ")));
        let json = serde_json::to_value(&played.segments[0]).unwrap();
        assert!(json["sequence"].is_string() && json["first"].is_u64() && json["last"].is_u64());
        // An empty walk is refused.
        assert!(play_walk(&pipe, &p, None, &[], &PlaneMotion::identity(up), "w").is_err());
    }
}
