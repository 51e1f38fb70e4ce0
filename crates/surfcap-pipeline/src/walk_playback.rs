//! Plays a walk found in a graph into a mesh sequence (thesis Algorithm 3), with what the
//! reports say about it: frame counts by label, transitions, the runs of original frames, and
//! the tracked centre of every output frame.

use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::{FrameLabel, Sequence, Subject};
use surfcap_motion::transition_frames::FrameMix;
use surfcap_motion::walk_sequence::{Step, WalkModel, tracked_centre, walk_sequence};

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
    /// its transition blends them by: what a per-frame texture follows (issue 20 item 8).
    pub mix: Vec<FrameMix>,
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
    let s = pipe.subject();
    let model = pipe.walk_model(p, tracked)?;
    let d = pipe.chain_distances()?;
    let t0 = Instant::now();
    let ws = walk_sequence(s, &model.value, &d.value.values, walk, start)?;
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
        blend_seconds,
    })
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
    use surfcap_mesh::NoProgress;
    use surfcap_motion::transition_table::TableParams;
    use surfcap_synth::{WormParams, worm_subject};

    #[test]
    fn a_walk_with_one_transition_plays_with_its_labels_and_segments() {
        let s = worm_subject(&WormParams { rings: 8, segments: 6, frames: 24, ..Default::default() }).unwrap();
        let pipe = Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress));
        let p = GraphParams {
            table: TableParams { l_min: 3, l_max: 6, slope: Some(3) },
            kind: GraphKind::Essential,
            alpha: 0.05,
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
