//! surfcap's data model, shared by every other crate, with no file format in it (those are in
//! `surfcap-formats`).
//!
//! - A [`Subject`] is one triangle [`Topology`], named [`Sequence`]s of vertex positions
//!   (contiguous f32), fps, up axis, units, tags, frame labels (original or synthetic) and optional
//!   ground-truth joints; a [`FrameIndex`] maps global frame numbers to (sequence, frame) and holds
//!   the sequences' names, so every layer names a frame `sequence:frame`. Connected components.
//! - A [`FrameSet`] is the input of Huang et al. 2009's surface motion graph: every frame has its
//!   own `Topology` and f32 positions (and optional UVs), validated on construction, named through
//!   the same `FrameIndex`, convertible from and into a `Subject`; `FrameSetSequence::from_frames`
//!   serves any reader that yields per-frame (topology, positions).
//! - `FrameTextures`: encoded PNG bytes per distinct texture and a texture index per frame (so this
//!   crate needs no image library); `UvVertices`: one vertex per (vertex, UV) pair, the mesh's own
//!   vertices first, for glTF and the viewer.
//! - Caches: the subject cache (`x.subject`: `subject.json` + `.npy` arrays, opened without
//!   parsing source files; `CachedFrames` reads only some frames, for tile jobs), the frame set
//!   folder (`x.frames`, written atomically with its marker, read back with every offset and index
//!   checked), and the derived-matrix cache (`.npy` files keyed by a BLAKE3 hash of the subject's
//!   geometry and the product's parameters; 240 MB hash in about 0.1 s). One header reader serves
//!   both caches. Layouts: `docs/formats.md`.
//! - Output safety: atomic writes (a temporary sibling `.NAME.tmp-PID`, then rename); where an
//!   output may go (resolved to its real place, refused when it overlaps an input, replacing only a
//!   regular file, an empty folder or surfcap's own marked folder of the same kind unless forced);
//!   the live temporaries, a process-wide registry a front end empties on SIGINT/SIGTERM, and stale
//!   temporaries of dead processes swept before the next write (`libc::kill(pid, 0)` says whether
//!   the writer is alive). Every input is opened as a regular file, so a FIFO, folder, socket or
//!   device is refused by name, never read or waited on. Output sets (`output_set`): every output
//!   of a command (main file, sidecar, report, folder) planned and checked before work, staged,
//!   and committed together or not at all, each place re-checked at the swap; side files replace
//!   only surfcap's own (stamped `"written_by": "surfcap"`), and a signal handler learns whether
//!   a commit completed the outputs.
//! - `Progress`: how libraries report progress without printing; the front end draws it.
//! - Sizing ([`sizing`]): a request's memory and disk estimated before any work and checked
//!   against the front end's limits; fallible allocation where a size comes from input.
//! - Reachability ([`reachability`]): the words both synthesis engines (the surface motion graph
//!   and the essential graph's timed searches) use for a target no walk can meet, and which
//!   loops may pad time; here because neither engine's crate may depend on the other.
//!
//! No function here panics on bad input, prints or exits: errors are [`Error`]s that name the file,
//! the line or frame, and what was expected. `npyz` parses `.npy` headers and decodes data in
//! chunks into an exact-size vector, so a 240 MB array costs 240 MB; frames and sequences are read
//! in parallel (rayon).
//!
//! The `.npy` layer ([`npy`]) lives here, not with the file formats: the caches are folders of
//! `.npy` arrays, and `surfcap-formats` (which depends on this crate) reuses it for its npy
//! sources, so there is one npy reader and no cycle.
//!
//! Depends on no other surfcap crate (serde, npyz, rayon, blake3 and libc only); every other crate
//! depends on it.

pub mod atomic;
pub mod cache;
mod cache_description;
pub mod cache_entry;
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
pub mod output_set;
pub mod progress;
pub mod reachability;
pub mod regular_file;
pub mod sizing;
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
pub use subject::{FrameLabel, JointTrack, PositionBuffer, Sequence, Subject, Units, UpAxis};
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
