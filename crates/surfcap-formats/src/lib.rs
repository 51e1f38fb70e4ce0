//! surfcap's file formats: readers and writers of OBJ ([`obj`]), PLY ([`ply`]), PC2 ([`pc2`]),
//! glb/glTF ([`glb`] for a subject's morph targets, [`glb_frame_set`] for a mesh per frame),
//! Alembic ([`abc`], [`abc_read`] over the Ogawa container [`ogawa_write`], [`ogawa_read`]) and
//! USD ([`usda`], [`usda_read`]); the source layouts a capture comes in ([`frame_folder`]: a
//! folder of frames, [`shared_layout`]: a template with `positions.npy`, [`manifest`]: a
//! `surfcap.toml`); [`import`], which turns any mix of sources into a subject or a frame set;
//! and [`export`], which writes them for other tools.
//!
//! Depends on `surfcap-mesh` (the data model, and its `.npy` layer, which the caches there need
//! too: npy is read and written by `surfcap_mesh::npy`, never here) and on no other surfcap
//! crate. Only the crates that read or write user files depend on it (the CLI, evaluation, the
//! appearance crate's mesh reader); the algorithms take and return the data model. Every reader says which subset of its format it reads; every error names the file
//! and the line, frame or byte, and what was expected; nothing panics on input data.

pub mod abc;
pub mod abc_read;
pub mod export;
pub mod frame_folder;
pub mod glb;
pub mod glb_frame_set;
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
