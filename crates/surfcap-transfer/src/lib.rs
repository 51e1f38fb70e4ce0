//! surfcap motion transfer between two subjects (thesis chapter 5; Boukhayma, Franco and Boyer,
//! "Surface motion capture transfer with Gaussian process regression", CVPR 2017).
//!
//! Two subjects, each with its own topology, and pairs of corresponding frames between them. A
//! subject's pose is its Procrustes-aligned mesh cut into overlapping body parts, each part
//! reduced by PCA, plus the rigid displacement from the previous frame (5.4). Sparse key-pose
//! pairs are densified by a constrained DTW over a Bayesian linear association cost (5.5.1); a GP
//! per part and one for the displacement map source to target (5.5.2); the predicted parts are
//! corrected against the nearest training meshes, stitched along optimal boundaries inside their
//! overlaps and moved by the accumulated displacement (5.6). Baran et al. 2009 (semantic
//! deformation transfer) is the baseline.
//!
//! One algorithm per module, each citing the equations it implements:
//! - body parts: [`body_parts`] (a tree of overlapping vertex sets with submeshes, canonical JSON),
//!   [`body_parts_from_labels`] (grown from per-vertex labels), [`body_parts_choice`] (a file, the
//!   whole body or a proposal, as the commands that learn per part take them), [`body_parts_file`] (the user's
//!   files: canonical, labels, cutting planes, vertex loops), [`body_parts_proposal`] (from joints,
//!   separate meshes or the rigidity of the motion);
//! - [`pose_representation`]: Procrustes alignment to the subject's reference, the rigid
//!   displacement from the previous frame as (dT, log dR) with the exact log, per-part PCA in the
//!   body frame;
//! - [`pairs_file`] (the key-pair CSV), [`correspondence_densification`] (eq. 5.4-5.10) applied per
//!   pair of sequences by [`training_pairs`];
//! - [`transfer_model`] (the GPs with NN/SE/linear kernels and fitted hyper-parameters),
//!   [`motion_transfer`] (training, per-frame transfer with the displacement accumulated from the
//!   target's reference), [`semantic_deformation_transfer`] (the Baran et al. baseline) and
//!   [`baran_transfer`] (it as a model applied to whole motions);
//! - reconstruction: [`part_correction`] (M nearest training meshes turned by their polar
//!   rotations, Poisson), [`part_stitching`] (the cheapest closed cut inside each overlap by
//!   Dijkstra, one Poisson merge, a seam measure), [`shape_reconstruction`] (ties them,
//!   factorisations once per model);
//! - [`transfer_model_file`] (the model folder: `model.json` + `target_training.npy`) and
//!   [`transfer_training`]: the trained model as a derived product, cached as a folder
//!   `transfer-model-<16 hex>` in the derived cache, keyed by both subjects' geometry, names and
//!   rates, the key pairs, both parts and every option.
//!
//! Parts and frames run in parallel, each part's fit with its own seed, so the result does not
//! depend on the thread count (tested). The workspace enables serde_json's `float_roundtrip`:
//! without it a float read back could land one bit off, and a reloaded model predicted
//! differently.

pub mod baran_transfer;
pub mod body_parts;
pub mod body_parts_choice;
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
