//! Built-in subjects with known answers, so surfcap runs out of the box and tests have ground truth:
//!
//! - the mannequin (`mannequin`): capsules around a 15-joint A-pose skeleton, torso and each limb
//!   smoothly united, marching tetrahedra then remeshing by short-edge collapse, edge flips and
//!   tangential smoothing: a closed 2-manifold of 1,000-20,000 vertices, in several body shapes;
//!   skinning weights diffused over the surface from the nearest skeleton segment; dual-quaternion
//!   skinning;
//! - motion for it: BVH clips (`bvh`: the motion-capture reader, forward kinematics, a unit
//!   guess, errors with their lines) retargeted by joint names with their real root travel (`retarget`) and seeded procedural walk, jog, turns, jump and idle
//!   (`locomotion`); clips become a subject with tags and joint matrices (`mannequin_subject`);
//! - for appearance: the mannequin's UV atlas (`mannequin_atlas`: a cylindrical chart per bone,
//!   `surfcap make mannequin --uv-atlas`) and a moving head from one UV-mapped scan (`head_motion`: nod,
//!   turn, tilt as a smooth non-rigid bend about a pivot below the scan, topology and atlas kept,
//!   `surfcap make head`);
//! - a procedural tube (`worm`) whose size benchmarks choose;
//! - frame sets with known answers (`frame_remeshing`, `surfcap remesh-frames`): every frame of a
//!   subject re-meshed on its own (Botsch-Kobbelt split/collapse/flip/tangential smoothing projected
//!   onto the source triangles through a BVH, boundaries kept; seeded +-10% edge length, processing
//!   and vertex order), each new vertex's source triangle and barycentrics kept. Frames run in
//!   parallel, each from its own seeded stream, so the result does not depend on the thread count.
//!
//! `nalgebra` for joint rotations, dual quaternions and rigid transforms; `rand` + `rand_chacha`
//! for seeded, platform-independent motion variation.

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
