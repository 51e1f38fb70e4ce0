//! surfcap motion variation synthesis (thesis chapter 6).
//!
//! A few sequences of one motion type (walk, jog, turns; or jumps) of one subject become an
//! endless supply of slightly different versions of each of them, and of any blend of two:
//! - **preparation** (6.4, [`motion_preparation`]): every frame rigidly aligned to the
//!   reference pose with its rigid displacement from the previous frame, every sequence
//!   re-timed onto the reference sequence's frames, cut into overlapping body parts (P = 5);
//!   pairs blended non-linearly at a few weights (6.7) join the training set;
//! - **learning** (6.5, [`variation_model`]): one GPDM per part over all sequences, sharing one
//!   latent space, the torso's vector carrying the 6-D displacement;
//! - **sampling** (6.6, [`variation_sampling`]): whole latent trajectories drawn by HMC from
//!   the mean prediction of a learned sequence, poses from the reconstruction GP, the parts
//!   stitched and moved by the sampled displacements, then brought back to the sequence's own
//!   timing;
//! - **parametrisation** (6.7, [`motion_parametrisation`]): a variant of the blend at any
//!   weight by interpolating variants of the two nearest learned trajectories;
//! - the model folder on disk ([`variation_model_file`]);
//! - measures of variants against what they vary: the learnt motion without sampling
//!   ([`learnt_motion`]), [`pose_centroid`], [`mean_vertex_distance`] (body-frame poses),
//!   [`centroid_path_length`].

pub mod centroid_path_length;
pub mod error;
pub mod learnt_motion;
pub mod mean_vertex_distance;
pub mod motion_parametrisation;
pub mod motion_preparation;
pub mod pose_centroid;
pub mod variation_model;
pub mod variation_model_file;
pub mod variation_sampling;

pub use error::{Error, Result};
pub use variation_model::VariationModel;
