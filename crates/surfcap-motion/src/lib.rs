//! surfcap motion layer (thesis 2.5 and 3.3): optimal transitions between frames, the
//! essential graph and the motion-graph baseline.
//!
//! Frames are global frame indices of a subject; pose distances come as an N x N row-major
//! matrix (surfcap-geometry's distance matrix).

pub mod blend;
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
