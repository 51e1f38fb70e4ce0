//! surfcap motion transfer between two subjects (thesis chapter 5; Boukhayma, Franco and
//! Boyer, "Surface motion capture transfer with Gaussian process regression", CVPR 2017).
//!
//! Two subjects, each with its own topology, and pairs of corresponding frames between them.
//! A subject's pose is its Procrustes-aligned mesh cut into overlapping body parts, each part
//! reduced by PCA, plus the rigid displacement from the previous frame (5.4). Sparse key-pose
//! pairs are densified by a constrained DTW over a Bayesian linear association cost (5.5.1);
//! a GP per part and one for the displacement map source to target (5.5.2); the predicted
//! parts are corrected against the nearest training meshes, stitched along optimal
//! boundaries inside their overlaps and moved by the accumulated displacement (5.6). Baran et
//! al. 2009 (semantic deformation transfer) is the baseline.
//!
//! One algorithm per module, named after what it computes; each cites the equations it
//! implements.

pub mod body_parts;
pub mod body_parts_file;
pub mod body_parts_from_labels;
pub mod body_parts_proposal;
pub mod correspondence_densification;
pub mod error;
pub mod motion_transfer;
pub mod pairs_file;
pub mod part_correction;
pub mod part_stitching;
pub mod pose_representation;
pub mod semantic_deformation_transfer;
pub mod shape_reconstruction;
pub mod training_pairs;
pub mod transfer_model;
pub mod transfer_model_file;
pub mod transfer_training;

pub use body_parts::BodyParts;
pub use error::{Error, Result};
