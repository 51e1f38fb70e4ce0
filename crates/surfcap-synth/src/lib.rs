//! Built-in subjects with known answers, so surfcap runs out of the box.
//!
//! `bvh` reads motion capture (BVH) with forward kinematics. For now one procedural subject: a closed tube ("worm") that slithers and curls on the ground.
//! Its motion is analytic, deterministic and seeded, with real root travel; the skinned human
//! mannequin of the built-in-subjects issue will join it here.

pub mod bvh;
pub mod locomotion;
pub mod mannequin;
pub mod mannequin_subject;
pub mod retarget;
mod worm;

pub use worm::{WormParams, worm_subject};
