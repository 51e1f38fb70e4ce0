//! Readers and writers, one format per file.

pub mod abc;
pub mod abc_read;
pub mod frame_folder;
pub mod glb;
pub mod glb_frame_set;
pub mod npy;
pub mod obj;
pub mod ogawa_read;
pub mod ogawa_write;
pub mod pc2;
pub mod ply;
pub mod regular_file;
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
