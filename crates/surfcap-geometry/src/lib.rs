//! surfcap pose geometry (thesis sections 2.3 and 2.4): rigid alignment, deformation gradients,
//! polar decomposition, rotation log/exp, pose distances and their all-pairs matrix,
//! differential operators, Poisson reconstruction and pose interpolation; ground contacts, the
//! feet's contact signals and foot sliding (thesis 6.4's contact-guided alignment), and root
//! motion from the contacts.
//!
//! One algorithm per module, named after what it computes; each cites the thesis equations it
//! implements. Expensive precomputation (per-frame triangle frames, Cholesky factorisations) is
//! separate from per-query work.

pub mod deformation_gradient;
pub mod distance_matrix;
pub mod distance_tiles;
pub mod error;
pub mod foot_contacts;
pub mod foot_sliding;
pub mod gradient_operator;
pub mod ground_contacts;
pub mod motion_plane_alignment;
pub mod poisson_reconstruction;
pub mod polar_decomposition;
pub mod pose_distance;
pub mod pose_interpolation;
pub mod root_motion_from_contacts;
pub mod rotation_log_exp;
pub mod shape_distortion;

pub use error::{Error, Result};
