//! Huang, Hilton and Starck 2009, "Human motion synthesis from 3D video" (CVPR): the surface
//! motion graph, surfcap's second synthesis engine, which needs no shared topology (every frame
//! may have its own vertices and triangles). One algorithm per file:
//! - [`motion_frames`]: the input (named sequences of frames, each with its own triangles), the
//!   ground centroids and the cached similarity matrix;
//! - [`volume_voxelisation`]: the voxels inside a mesh (3.1 step 1);
//! - [`shape_histogram`]: the volume-sampling spherical shape histogram (3.1 steps 2-4);
//! - [`shape_similarity`]: frame-to-frame shape similarity, the minimum over 360 rotations about
//!   the vertical axis (eq. 2), for all pairs of a frame set;
//! - [`temporal_shape_similarity`]: the similarity over a triangular temporal window (eq. 3-4) and
//!   the optimal transition between two sequences (eq. 5);
//! - [`surface_motion_graph`]: the two-level graph, the lower level built from the user's higher
//!   level and key frames (3.3);
//! - [`path_optimisation`]: walks and loops by depth-first search (Algorithm 1), the repetitions
//!   by four integer linear programs per walk (eq. 6-20) with the feedback cuts of Algorithm 2,
//!   and the composition of the path (4.2.3).

pub mod error;
pub mod motion_frames;
pub mod path_optimisation;
pub mod shape_histogram;
pub mod shape_similarity;
pub mod surface_motion_graph;
pub mod temporal_shape_similarity;
pub mod volume_voxelisation;

pub use error::{Error, Result};
