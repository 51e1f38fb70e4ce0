//! Huang, Hilton and Starck 2009, "Human motion synthesis from 3D video" (CVPR): the surface
//! motion graph, surfcap's second synthesis engine, which needs no shared topology (every frame
//! may have its own vertices and triangles). One algorithm per file:
//! - [`motion_frames`]: the input (named sequences of per-frame meshes from a `Subject` or a
//!   `FrameSet`), area-weighted ground centroids, and the similarity matrix cached as
//!   `smg-similarity-<16 hex>.npy` in the derived cache;
//! - [`volume_voxelisation`]: the voxels inside a mesh (3.1 step 1): winding numbers along rays
//!   through voxel centres with a 2-of-3 axis vote, so holes and interpenetrating parts do not
//!   leak; one global lattice;
//! - [`shape_histogram`]: the volume-sampling spherical shape histogram (3.1 steps 2-4): bins
//!   10 x 20 x 360 at 1 degree, one `r_max` for the frame set;
//! - [`shape_similarity`]: eq. 2 for all pairs, the minimum over 360 rotations about the vertical
//!   through one real FFT cross-correlation per pair (one multiply-add per ring and frequency
//!   instead of 360 histogram distances), rows in parallel, thread-count independent;
//! - [`temporal_shape_similarity`]: triangular windows (eq. 3-4) and the optimal transition (eq.
//!   5); self-transitions jump back; the K best per connection as an opt-in extension;
//! - [`surface_motion_graph`]: the two-level graph (3.3), sequences split at transitions and key
//!   frames;
//! - [`self_transition_choice`]: self-transitions chosen among the loops a query may play,
//!   spanning the sequence's cross transitions and key frames (an extension of eq. 5);
//! - [`loop_exclusion`]: the loops that may pad time (no shorter than a minimum length, no
//!   less varied than a pose-variation floor), the others reported as excluded loops;
//! - [`path_optimisation`]: walks and elementary loops by depth-first search, planned once per key
//!   pair (`plan_paths`) and shared by every target, four ILPs per walk (eq. 6-20; `good_lp` with
//!   the pure-Rust `microlp`, which solves these models in under a millisecond), walks pruned by a
//!   cost lower bound and ILPs capped by the best cost known, Algorithm 2's feedback as cuts, an
//!   optional tolerance with the reason a target is unreachable, and the composition of the path
//!   (4.2.3) with centroids matched at each switch.

pub mod error;
pub mod loop_exclusion;
pub mod motion_frames;
pub mod path_optimisation;
pub mod self_transition_choice;
pub mod shape_histogram;
pub mod shape_similarity;
pub mod surface_motion_graph;
pub mod temporal_shape_similarity;
pub mod volume_voxelisation;

pub use error::{Error, Result};
