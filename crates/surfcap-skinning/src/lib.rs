//! Skinned rigs from mesh sequences: Smooth Skinning Decomposition with Rigid Bones (Le and Deng
//! 2012) turns any subject's frames into linear blend skinning, bones with one rigid transform
//! per frame and sparse weights (at most K bones per vertex), which engines (Unity, Unreal,
//! Godot, three.js) play and re-pose as an ordinary skinned character.
//!
//! One algorithm per file:
//! - [`bone_initialisation`]: the initial bones, a rigid clustering of the vertices;
//! - [`rigid_bone_fit`]: one bone's rigid transform by weighted Procrustes;
//! - [`skinning_weights`]: one vertex's non-negative, affine, K-sparse weights (active-set NNLS);
//! - [`ssdr`]: the alternation of the two updates, and the rig ([`SkinnedRig`]);
//! - [`reconstruction_error`]: per-frame RMS and max error against the source;
//! - [`joint_animation`]: the bones as a skeleton file's joints (bind centres, joint poses).
//!
//! Deterministic for a seed on any thread count. The glTF skin writer is in surfcap-formats
//! (`glb_skin`), the command in the CLI (`surfcap rig`).

pub mod bone_initialisation;
pub mod error;
pub mod joint_animation;
pub mod reconstruction_error;
pub mod rigid_bone_fit;
pub mod skinning_weights;
pub mod ssdr;

pub use error::{Error, Result};
pub use reconstruction_error::{FrameError, overall_rms, reconstruction_errors};
pub use rigid_bone_fit::BoneTransform;
pub use ssdr::{SkinnedRig, SsdrOptions, decompose};
