//! Built-in subjects with known answers, so surfcap runs out of the box: the skinned human
//! mannequin (`mannequin`), moved by BVH motion capture (`bvh`, `retarget`) or by procedural
//! locomotion (`locomotion`), assembled into subjects with tags and ground-truth joints
//! (`mannequin_subject`); and a procedural tube (`worm`) whose size benchmarks can choose.

pub mod bvh;
pub mod frame_remeshing;
pub mod head_motion;
pub mod locomotion;
pub mod mannequin;
pub mod mannequin_atlas;
pub mod mannequin_subject;
pub mod retarget;
mod worm;

pub use worm::{WormParams, worm_subject};
