//! surfcap's data model: a [`Subject`] is one triangle [`Topology`], named [`Sequence`]s of
//! vertex positions (contiguous f32), fps, up axis, units, tags, frame labels and optional
//! ground-truth joints; a [`FrameSet`] is the same for frames that each have their own topology;
//! a [`FrameIndex`] maps global frame numbers to (sequence, frame). Beside the model: the subject
//! cache ([`cache`]) and the frame-set cache ([`frame_set_cache`]) that later commands read, the
//! cache of derived matrices ([`derived_cache`]), output safety ([`output_path`], [`atomic`],
//! [`temporaries`]: refuse to overwrite what surfcap did not write, write under a temporary
//! name and rename), [`regular_file`] opening of inputs, and [`Progress`].
//!
//! The `.npy` layer ([`npy`]) lives here, not with the file formats: the caches are folders of
//! `.npy` arrays, and the format crate (`surfcap-formats`, which depends on this one) reuses it
//! for its npy sources, so there is one npy reader and no cycle.
//!
//! Depends on no other surfcap crate (serde, npyz, rayon, blake3 and libc only); every other
//! crate depends on it. No function here panics on bad input, prints, or exits: errors are
//! [`Error`]s that name the file, the line or frame, and what was expected.

pub mod atomic;
pub mod cache;
mod cache_description;
pub mod connected_components;
pub mod derived_cache;
pub mod error;
pub mod frame_index;
pub mod frame_set;
pub mod frame_set_cache;
pub mod frame_textures;
pub mod natural_order;
pub mod npy;
pub mod output_path;
pub mod progress;
pub mod regular_file;
pub mod subject;
pub mod temporaries;
pub mod topology;
pub mod uv_vertices;

pub use connected_components::{Components, connected_components};
pub use error::{Error, ErrorKind, Location, Result};
pub use frame_index::FrameIndex;
pub use frame_set::{Correspondence, Frame, FrameSet, FrameSetSequence};
pub use frame_textures::FrameTextures;
pub use progress::{NoProgress, Progress};
pub use regular_file::read_regular_file;
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
