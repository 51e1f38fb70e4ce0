//! Readers and writers, one format per file.

pub mod abc;
pub mod abc_read;
pub mod frame_folder;
pub mod glb;
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
