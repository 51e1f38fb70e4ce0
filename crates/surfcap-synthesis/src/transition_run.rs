//! One optimal transition between two frames of a subject (thesis 2.5.4 for its segment
//! lengths and warp, Algorithm 2 for its frames): `surfcap transition` and `surfcap.transition`
//! make the same animation and report with this function.
//!
//! The transition table (on the pipeline's chain distances, with `params`) gives the source and
//! destination segment lengths of the pair; the warp is recomputed from the distance matrix and
//! Blend makes one frame per warp cell.

use std::sync::Arc;

use serde::Serialize;
use surfcap_mesh::{FrameLabel, Sequence, Subject};
use surfcap_motion::dtw::Warp;
use surfcap_motion::transition_frames::transition_frames;
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{Pipeline, PoseDistances};

use crate::error::{Error, Result};

/// What a transition is: the report written beside it as `<output>.transition.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionReport {
    /// Source frame i (global): the source segment starts there.
    pub from: usize,
    /// Destination frame j (global): the destination segment ends there.
    pub to: usize,
    /// The same two frames as users write them, `sequence:frame`.
    pub from_frame: String,
    pub to_frame: String,
    /// Source segment length l^i and destination segment length l^j, frames.
    pub source_length: usize,
    pub destination_length: usize,
    /// Frames of the transition: the warp's length L (eq. 2.56).
    pub duration: usize,
    /// The warp's normalised cost (eq. 2.50), recomputed from the distances.
    pub normalised_cost: f64,
    /// The table's cost D(i, j) (eq. 2.55).
    pub table_cost: f64,
    /// Slope constraint p (eq. 2.53); null for none.
    pub slope: Option<usize>,
    /// The warp path as (source frame, destination frame) pairs, global frames.
    pub warp: Vec<(usize, usize)>,
    /// Time spent blending the frames.
    pub blend_seconds: f64,
}

/// A transition: its animation, report and warp, and the distance matrix it was found on.
#[derive(Debug, Clone)]
pub struct Transition {
    /// One sequence named `<from>_to_<to>`, tagged `transition`, in a subject named
    /// `<subject>-transition`.
    pub animation: Subject,
    pub report: TransitionReport,
    pub warp: Warp,
    pub distances: Arc<PoseDistances>,
}

/// The optimal transition from global frame `from` to global frame `to` of the pipeline's
/// subject; `from_name` and `to_name` are the frames as the caller wrote them (in messages and
/// the sequence's name). Refused when the table has no transition for the pair.
pub fn transition(
    pipe: &Pipeline,
    (from, from_name): (usize, &str),
    (to, to_name): (usize, &str),
    params: &TableParams,
) -> Result<Transition> {
    let n = pipe.subject().n_frames();
    if from >= n || to >= n {
        return Err(Error::Request(format!(
            "no transition from {from_name} to {to_name}: the subject has frames 0 to {}",
            n.saturating_sub(1)
        )));
    }
    let table = pipe.table(params)?.value;
    let k = from * table.n + to;
    if !table.cost[k].is_finite() {
        return Err(Error::Request(format!(
            "no transition from {from_name} to {to_name}: the source needs {} frames after it and the destination {} before it, in their own sequences",
            params.l_min, params.l_min
        )));
    }
    let (li, lj) = (table.li[k] as usize, table.lj[k] as usize);
    let distances = pipe.chain_distances()?.value;
    let s = pipe.subject();
    let t0 = std::time::Instant::now();
    let t = transition_frames(s, &distances.values, (from, li), (to, lj), params.slope)?
        .ok_or_else(|| Error::Request("the table's warp could not be recovered".into()))?;
    let blend_seconds = t0.elapsed().as_secs_f64();
    let (frames, warp) = (t.frames, t.warp);
    let nv = s.topology().n_vertices();
    let name = format!("{from_name}_to_{to_name}").replace(':', "_");
    let seq = Sequence::new(name, nv, frames.concat())?
        .with_labels(FrameLabel::original_ends(frames.len()))?
        .with_tags(vec!["transition".into()]);
    let animation = s.derived(format!("{}-transition", s.name), seq)?;
    let index = pipe.subject().frame_index();
    let report = TransitionReport {
        from,
        to,
        from_frame: index.label(from),
        to_frame: index.label(to),
        source_length: li,
        destination_length: lj,
        duration: warp.len,
        normalised_cost: warp.cost,
        table_cost: table.cost[k],
        slope: params.slope,
        warp: warp.path.clone(),
        blend_seconds,
    };
    Ok(Transition { animation, report, warp, distances })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_mesh::NoProgress;
    use surfcap_pipeline::CacheStore;

    fn pipe() -> Pipeline {
        let s = worm_subject(&WormParams { rings: 6, segments: 5, frames: 30, ..Default::default() }).unwrap();
        Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress))
    }

    #[test]
    fn the_report_holds_the_tables_lengths_and_the_warp_ends_at_the_pair() {
        let p = pipe();
        let params = TableParams { l_min: 3, l_max: 6, slope: Some(3) };
        let t = transition(&p, (2, "2"), (20, "20"), &params).unwrap();
        let table = p.table(&params).unwrap().value;
        let k = 2 * table.n + 20;
        assert_eq!(t.report.source_length, table.li[k] as usize);
        assert_eq!(t.report.destination_length, table.lj[k] as usize);
        assert_eq!(t.report.table_cost, table.cost[k]);
        assert_eq!(t.report.warp.first().unwrap().0, 2);
        assert_eq!(t.report.warp.last().unwrap().1, 20);
        assert_eq!(t.animation.n_frames(), t.report.duration);
        assert_eq!(t.animation.sequences()[0].name, "2_to_20");
    }

    #[test]
    fn a_pair_without_room_for_its_segments_is_refused_naming_the_frames() {
        let p = pipe();
        let params = TableParams { l_min: 3, l_max: 6, slope: Some(3) };
        // The last frame of the first sequence has no frames after it for a source segment.
        let e = transition(&p, (29, "walk:29"), (5, "5"), &params).unwrap_err();
        assert!(e.to_string().starts_with("no transition from walk:29 to 5: the source needs 3 frames"), "{e}");
        let n = p.subject().n_frames();
        let e = transition(&p, (n, "past"), (5, "5"), &params).unwrap_err();
        assert!(e.to_string().contains(&format!("the subject has frames 0 to {}", n - 1)), "{e}");
    }
}
