//! surfcap motion variation synthesis (thesis chapter 6).
//!
//! A few sequences of one motion type (walk, jog, turns; or jumps) of one subject become an
//! endless supply of slightly different versions of each of them, and of any blend of two:
//! - **preparation** (6.4 and 6.5.2, [`motion_preparation`]): every frame Procrustes-aligned onto
//!   the reference pose with its rigid displacement from the previous frame (dT, exact log dR),
//!   every sequence re-timed onto the reference sequence's frames by surfcap-motion's
//!   contact-guided DTW (the feet are the parts named `leg*`) with its time map kept, pairs blended
//!   non-linearly (eq. 2.45-2.49) at a few weights (6.7) joining the training set; per-part
//!   vectors, the torso's carrying the 6 scaled displacement numbers;
//! - **learning** (6.5, [`variation_model`]): one GPDM per body part over all sequences, sharing
//!   one latent space, parts fitted in parallel, each deterministic; the stitching factorised once
//!   on the reference pose;
//! - **sampling** (6.6, [`variation_sampling`]): a seeded HMC chain over whole latent trajectories
//!   per part, started at the learnt trajectory (or the mean prediction of 6.6.1); each sampled
//!   trajectory smoothed (triangular, radius 2), poses from the reconstruction GP's mean, parts
//!   stitched (chapter 5's cheapest cuts and Poisson merge), their deviation from the learnt
//!   motion averaged over time ([`pose_deviation_smoothing`], radius 4), each triangle given the learnt
//!   motion's stretch at the same frame under its own rotation ([`learnt_stretch`]), placed by
//!   a `VariantPath` (the source's path by default; the integrated sampled displacements of
//!   6.6.2; or travel from the variant's own foot contacts) and re-timed to the sequence's own
//!   frames. A chain's seed is derived from the seed, the sequence's name and the part, so
//!   variants do not depend on the thread count; `variant_on_source_path` serves synthesis;
//! - **foot-skate clean-up** ([`foot_skate_cleanup`], on by default in sampling): every step the
//!   shared contact detector plants (the steps the foot-sliding measure counts) pinned
//!   mid-contact, the whole body moved along the ground with the planted feet and the feet
//!   moved to meet their pins, the legs deformed in the gradient domain for what is left (rest
//!   Laplacian factorised once, one solve per frame), blended in and out around each contact
//!   (Kovar et al. 2002), the legs then bent as rigidly as possible; detected and pinned three times;
//! - **parametrisation** (6.7, [`motion_parametrisation`]): variants of the two learnt
//!   trajectories around a weight, interpolated in the latent space, with their timing;
//! - the model folder on disk ([`variation_model_file`]: `model.json`, `faces.npy`,
//!   `reference_pose.npy`, per part its latent positions and training vectors as `.npy`, every
//!   shape checked on load and the file at fault named; factorisations recomputed on load).
//! - measures of variants against what they vary: the learnt motion without sampling
//!   ([`learnt_motion`]), [`pose_centroid`], [`mean_vertex_distance`] (body-frame poses),
//!   [`centroid_path_length`].

pub mod centroid_path_length;
pub mod error;
pub mod foot_skate_cleanup;
pub mod learnt_motion;
pub mod learnt_stretch;
pub mod mean_vertex_distance;
pub mod motion_parametrisation;
pub mod motion_preparation;
pub mod pose_centroid;
pub mod pose_deviation_smoothing;
pub mod variation_model;
pub mod variation_model_file;
pub mod variation_sampling;

pub use error::{Error, Result};
pub use variation_model::VariationModel;
