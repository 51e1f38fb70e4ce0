//! surfcap data layer: a [`Subject`] is one triangle [`Topology`], named [`Sequence`]s of vertex
//! positions (contiguous f32), fps, up axis, units, tags, frame labels and optional ground-truth
//! joints; a [`FrameIndex`] maps global frame numbers to (sequence, frame).
//!
//! Readers and writers for OBJ, PLY, npy, PC2 and glb live in [`io`]; [`import`] turns files into
//! subjects; [`cache`] is the fast on-disk form later commands read; [`export`] writes subjects
//! for other tools. No function here panics on bad input, prints, or exits: errors are
//! [`Error`]s that name the file, the line or frame, and what was expected.

pub mod atomic;
pub mod cache;
pub mod connected_components;
pub mod derived_cache;
pub mod error;
pub mod export;
pub mod frame_index;
pub mod frame_set;
pub mod frame_set_cache;
pub mod frame_textures;
pub mod import;
pub mod io;
pub mod manifest;
pub mod natural_order;
pub mod output_path;
pub mod progress;
pub mod subject;
pub mod temporaries;
pub mod topology;
pub mod uv_vertices;

pub use connected_components::{Components, connected_components};
pub use error::{Error, ErrorKind, Location, Result};
pub use frame_index::FrameIndex;
pub use frame_set::{Correspondence, Frame, FrameSet, FrameSetSequence};
pub use frame_textures::FrameTextures;
pub use io::regular_file::read_regular_file;
pub use progress::{NoProgress, Progress};
pub use subject::{FrameLabel, JointTrack, Sequence, Subject, Units, UpAxis};
pub use topology::{Topology, UvAtlas};
pub use uv_vertices::UvVertices;

/// Axis-aligned bounding box (min, max) of `[n][3]` positions; zeros for no positions.
pub fn bounding_box(positions: &[f32]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in positions.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if positions.len() < 3 {
        return ([0.0; 3], [0.0; 3]);
    }
    (lo, hi)
}
