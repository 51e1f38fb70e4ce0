//! surfcap motion layer: optimal transitions between frames, the essential graph, walks and
//! constrained search (thesis 2.5, 3.3-3.5). Frames are global frame indices of a subject; pose
//! distances come as an N x N row-major matrix (surfcap-geometry's distance matrix). One
//! algorithm per module:
//!
//! - Transitions (thesis 2.5): [`dtw`] with the slope constraint and warp recovery (eq.
//!   2.50-2.54; the readings of its first step and of its normalisation, sum then divide or the
//!   exact least ratio, as [`dtw::DtwReading`]); the all-pairs [`transition_table`] with variable segment lengths sharing one DP per
//!   (source start, destination start) (eq. 2.55-2.57), assembled from tiles
//!   ([`transition_tiles`]: a block of source x end frames from its halo of distances, each DTW
//!   table cut at the tile's last column, candidates scanned in the whole table's order, so tiles
//!   give the same bits; `TABLE_TILE` 1,024); standard and fixed-length baselines; [`blend`]
//!   (Algorithm 2: recurring motion-plane alignment, non-linear interpolation, centre-of-mass
//!   integration; `blend_placements` is its rigid part alone).
//! - Graphs (thesis 3.3): [`edge_weights`] (Algorithm 1, D scaled by its median; `edge_weight_row`
//!   is its one definition, row by row; the tolerance alpha an `Alpha`, checked where it is made); the [`essential_graph`] (union of shortest-path trees,
//!   dense Dijkstra per source, O(V^3), parallel; eq. 3.2 read literally with its ties kept as
//!   direct edges, `essential_graph_with` and `with_skip_edges`, beside surfcap's reading); the [`sparse_essential_graph`] (per frame its k
//!   cheapest transitions plus the original edge, one heap Dijkstra per source, O(E + V log V),
//!   tileable by source rows; with k >= N - 1 bit-identical to the exact build, same tie rules);
//!   the Kovar [`motion_graph`] (local minima per sequence-pair block, largest strongly connected
//!   component); a sparse digraph with Dijkstra and density ([`graph`]); [`dead_ends`]: the frames
//!   from which a walk can go on as long as needed (those reaching a cycle), the only ones path
//!   following enters.
//! - Walks (thesis 3.4-3.5): [`walk_sequence`] (Algorithm 3; every output frame records what it is
//!   made of, [`transition_frames::FrameMix`]: source and destination frame and Blend's ramp
//!   weight, which per-frame textures follow); substitutes for repeated frames
//!   (`walk_sequence_with` over a [`repeat_passes::FrameSource`]: each run of original frames gets
//!   a pass, 0 the first time its frames are shown, then one more than any earlier run sharing a
//!   frame; transitions interpolate the frames shown on either side with Blend's placements from
//!   the captured ones; each output frame records a `FramePlay`); the walk model predicting a
//!   walk's centre-of-mass track from per-transition rigid tracks; [`path_following`] (eq. 3.5,
//!   windowed depth-first branch-and-bound over arc length, tag restrictions); [`timed_walk`]
//!   (key-pose timing 3.5.2 and Huang et al.'s distance+time: bidirectional layered search over
//!   node-major time layers, long edges pulled a block of layers at a time, every split of the
//!   join judged by the true distance+time cost).
//! - Looping clips: [`clip_loops`] (last pose within the clip's own largest step of the first,
//!   in the body frame; the wrap edge last -> first played as a successive frame that carries
//!   the travel on; segment bounds that fit the shortest clip).
//! - Travel: [`clip_travel`] (net displacement and path length of a clip's centre, whether it is in
//!   place), [`subject_placement`] (whether a subject travels: transitions re-place one that
//!   does, keep the captured placement of one that does not) and [`in_place_root_motion`] (in-place clips moved by their recovered root motion).
//! - [`sequence_time_alignment`] (thesis 6.4/6.5.2): a sequence re-timed onto a reference by
//!   slope-constrained DTW, endpoints pinned, over the mean per-vertex distance scaled by its median
//!   plus a weighted foot-contact mismatch; a monotone, smoothed `TimeMap` and its inverse; poses
//!   resampled linearly, rigid placements along the rotation geodesic.
//!
//! The transition table runs one row per source frame in parallel (rayon).

pub mod blend;
pub mod clip_loops;
pub mod clip_travel;
pub mod dead_ends;
pub mod dtw;
pub mod edge_weights;
pub mod error;
pub mod essential_graph;
pub mod graph;
pub mod in_place_root_motion;
pub mod motion_graph;
pub mod path_following;
pub mod repeat_passes;
pub mod sequence_time_alignment;
pub mod sparse_essential_graph;
pub mod subject_placement;
pub mod timed_walk;
pub mod transition_frames;
pub mod transition_table;
pub mod transition_tiles;
pub mod walk_sequence;

pub use error::{Error, Result};

/// Segment length bounds from the frame rate (thesis 2.5.3: a third of a second to two seconds):
/// ceil(fps / 3) ..= round(2 fps), i.e. 8..48 at 24 fps and 10..60 at 30 fps as in the thesis. At
/// 50 fps this gives 17..100 where the thesis used 15..100 (its own choice, not a third of a
/// second); callers can pass other bounds.
pub fn segment_bounds(fps: f64) -> (usize, usize) {
    let lo = (fps / 3.0).ceil().max(2.0) as usize;
    let hi = (2.0 * fps).round().max(lo as f64) as usize;
    (lo, hi)
}

#[cfg(test)]
mod tests {
    #[test]
    fn bounds_match_the_thesis() {
        assert_eq!(super::segment_bounds(24.0), (8, 48));
        assert_eq!(super::segment_bounds(30.0), (10, 60));
        assert_eq!(super::segment_bounds(50.0), (17, 100)); // the thesis chose 15 there
    }
}
