//! surfcap's file formats: readers and writers between files and surfcap-mesh's `Subject` and
//! `FrameSet`, plus import (any source into a subject or a frame set) and export (a subject into
//! any format, with a sidecar JSON of frame labels). Every reader opens its input through
//! surfcap-mesh's regular-file check and names the file, the line or byte offset and the frame in
//! its errors; the fuzz targets in `fuzz/` cover the readers. Layouts: `docs/formats.md`.
//!
//! - **OBJ and PLY** (ascii and binary PLY): parsed by hand because `tobj` and `ply-rs-bw` report
//!   errors without line numbers or byte offsets; each reader states the subset it reads.
//! - **npy**: the shared-data layout (`template.obj` + `positions.npy` + `meta.json`,
//!   [`shared_layout`]) through `surfcap_mesh::npy`.
//! - **PC2** point caches: no maintained crate; the format is a 32-byte header and f32 frames.
//! - **glb**: a subject as morph targets (base mesh = first frame, one target per frame, one
//!   animation per sequence with sparse weight accessors, so the size is linear in the frames; at
//!   most 4 GiB, checked before writing, binary chunk streamed), and a frame set as a mesh and node
//!   per frame shown one at a time by node scale 0/1 with STEP keys, sharing the root, buffer-view,
//!   accessor and container code. Frames with UVs carry `TEXCOORD_0`, and with `FrameTextures` the
//!   material of their texture (a subject with textures is written as a frame set: morph targets
//!   cannot switch textures). Read back into a subject or a `FrameSet` with UVs and textures.
//!   Writing uses `gltf-json`'s typed structs, reading the `gltf` crate.
//! - **skinned glb** ([`glb_skin`]): a skinned rig (mesh, `JOINTS_0`/`WEIGHTS_0`, joints with
//!   inverse bind matrices, one joint animation per sequence) for engines to play as a character.
//! - **Alembic**: the Ogawa container written in two streamed passes (counting, then writing,
//!   since the root's offset precedes everything and the atomic writer cannot seek); the Abc/AbcGeom
//!   layers as the reference library lays them out, an `Xform` + `PolyMesh` per sequence,
//!   homogeneous topology for a subject, heterogeneous for a frame set. The reader bounds every
//!   offset and size by the file and checks groups for cycles and depth; a mesh whose topology
//!   changes becomes frames of a frame set. Written here because no Rust crate writes Alembic and
//!   `ogawa-rs` 0.4 panicked on the first `P` sample of a reference file; the tests read files back
//!   with the reference library (PyPI `alembic3d`).
//! - **USD text** (`.usda`): time-sampled points per sequence, units' name in `customLayerData`;
//!   a reader of a USDA subset without composition (nested Xform/Scope/Mesh prims, time-sampled or
//!   default points, fan-triangulated polygons, labels, UVs). Read back by Pixar's usd-core in
//!   the tests.
//! - **USD binary** (`.usdc`, crate version 0.8.0): the same stage as `.usda`, written streaming
//!   (`usd_crate_write`), and read back (`usd_crate_read`, files of usd-core's crate versions
//!   0.4.0-0.14.0 too); LZ4 and integer coding of the structural sections (`usd_crate_compress`).
//! - **Velocities**: Alembic's `.velocities` and USD's `velocities` (units per second, finite
//!   differences: `vertex_velocity`) written on every mesh of one topology and read back, so
//!   renderers draw motion blur.
//! - **Compact stream** (`.scstream`): positions quantised on a grid over the animation's box
//!   (`stream_quantise`), predicted from earlier frames (`stream_predict`) and deflated
//!   (`stream`, through `flate2`, which browsers inflate natively); decoded here and by the
//!   viewer's `stream_decode.js` to the same bits.
//! - **Manifests** (`surfcap.toml`, via `toml`): sequences from any of the above, PC2 or bare `.npy`
//!   caches with a template, fps, up axis, units, tags.
//! - **Import**: `open_any`/`import_any` return a subject or a frame set (a folder of frames whose
//!   connectivity differs imports as a frame set, with a note); `open_subject`/`import` refuse a
//!   frame set with a message saying what it is.
//!
//! Depends on `surfcap-mesh` and on no other surfcap crate. Only the crates that read or write
//! user files depend on it (the CLI, evaluation, the appearance crate's mesh reader); the
//! algorithms take and return the data model.

pub mod abc;
pub mod abc_read;
pub mod export;
pub mod frame_folder;
pub mod glb;
pub mod glb_frame_set;
pub mod glb_skin;
pub mod import;
pub mod manifest;
pub mod obj;
pub mod ogawa_read;
pub mod ogawa_write;
pub mod pc2;
pub mod ply;
pub mod shared_layout;
pub mod usda;
pub mod usda_read;
// ---- stream: velocities and the compact stream ----
pub mod stream;
pub mod stream_predict;
pub mod stream_quantise;
pub mod vertex_velocity;
// ---- usdc: USD's binary crate format ----
pub mod usd_crate;
pub mod usd_crate_compress;
pub mod usd_crate_read;
pub mod usd_crate_write;

/// `base`, or `base_1`, `base_2`, ... : the first not in `taken`, which it joins (names of
/// sibling objects in the USD and Alembic writers).
pub(crate) fn unique_name(base: String, taken: &mut Vec<String>) -> String {
    let mut unique = base.clone();
    let mut k = 1;
    while taken.contains(&unique) {
        unique = format!("{base}_{k}");
        k += 1;
    }
    taken.push(unique.clone());
    unique
}
