//! Eigen appearance maps (thesis chapter 4, Boukhayma 2017): a subject's per-frame texture maps
//! aligned to a reference by optical flow and Poisson warping, then reduced to eigen textures and
//! eigen warps. One algorithm per file:
//!
//! - Texture space: [`texture_image`] (planar f32 channels on the 8-bit scale, PNG/JPEG read with
//!   the file named, PNG written atomically), [`atlas_raster`] (covering triangle and barycentrics
//!   per texel, the lowest triangle where charts overlap), [`texel_mask`] (covered texels grown by
//!   one ring, numbered row-major: the order of every per-texel vector), [`flow_field`] (dense
//!   warps and bilinear resampling: direct warping, the baseline of Fig. 4.5).
//! - Pre-processing before flow (4.4.1): [`histogram_equalisation`] (OpenCV's equalizeHist over the
//!   active texels), [`bilateral_filter`] (diameter 80, sigma colour 15, sigma space 80; exact
//!   range levels every sigma/3 on a grid of cells, within 0.63 grey levels of brute force),
//!   [`texture_preprocessing`] (both, then [`shading_removal`]: not in the thesis, a high-pass of
//!   the log image without which TV-L1 drifted 20-28 texels under a moving light).
//! - Flow: [`tv_l1_flow`](mod@tv_l1_flow) (Sanchez Perez et al., IPOL 2013, coarse to fine with IPOL's defaults,
//!   data term on active texels only, optionally stopping at half resolution), [`image_pyramid`]
//!   (Gaussian, bicubic zoom as IPOL), [`inactive_fill`] (push-pull over inactive texels),
//!   [`flow_cache`] (flows on disk as `texture-flow-<16 hex>.npy`, f32 [2, H, W], keyed by both
//!   textures, the active texels and every option; `TextureFlow` is the estimator every command
//!   passes to the model, which does not depend on it: flows are passed in as functions).
//! - The model: [`poisson_texture_warp`] (eq. 4.1-4.3, Neumann at the charts' borders; `LᵀL + λ²I`
//!   factorised once per mask by faer's sequential sparse Cholesky and shared by every frame and
//!   channel: 13.5 s and 1.8 GB for the 968k active texels of a 1024² head atlas, then 0.4 s per
//!   channel solve), [`medoid_shift_alignment`] (Algorithm 4), [`eigen_maps`] (PCA through the
//!   F x F Gram matrix, eq. 4.4-4.11, f32 data, f64 fixed-order sums), [`appearance_model`] (build
//!   with per-stage timings, instantiate 4.4.3, interpolate 4.6.1, complete 4.6.2; the
//!   `appearance-model` folder numpy opens), [`naive_texture_pca`] (the baseline of 4.5),
//!   [`texture_folder`] (a folder of per-frame maps), [`solid_texture`] (a base texture painted
//!   from 3D rest positions).
//! - Benchmark data with ground truth: [`texture_generator`] (per-frame textures of a real mesh:
//!   known drift, shading under a moving light, blur, seeded noise, occlusion holes; clean frames
//!   kept), [`texture_drift`] (seeded sinusoids and the true flow between two frames),
//!   [`atlas_normals`] (normals and positions carried into the atlas), [`generated_frames`] (the
//!   `appearance-frames` folder and its reader); [`capture_benchmark`] (the textures multi-view
//!   capture makes: a moving subject rendered from a camera ring with specular shading, sensor
//!   noise, per-camera calibration error and per-frame tracking error, re-projected into the
//!   atlas by view-weighted blending with a depth test; the clean truth kept) and
//!   [`content_displacement`] (its ground truth: where each texel's blended content truly came
//!   from, per camera and as the cosine-weighted mean and spread, and the true flow between two
//!   frames).
//! - Evaluation (4.5): [`mesh_rasteriser`] (z-buffer, perspective-correct barycentrics and UVs,
//!   cameras on a ring),
//!   [`image_similarity`] (masked MSE and SSIM).
//! - Shape and appearance together (Fig. 7.1): [`blended_frame_textures`]: a texture for every
//!   frame of a synthesised animation, a captured frame's reconstruction or two frames interpolated
//!   with the weight Blend gives the geometry; each distinct texture made once, in parallel, and
//!   encoded to PNG as soon as made, so one float texture per thread is alive.
//!
//! `image` 0.24 with only PNG and JPEG: the version plotters already builds.

pub mod appearance_model;
pub mod appearance_requests;
pub mod atlas_normals;
pub mod atlas_raster;
pub mod bilateral_filter;
pub mod blended_frame_textures;
pub mod capture_benchmark;
pub mod content_displacement;
pub mod eigen_maps;
pub mod error;
pub mod flow_cache;
pub mod flow_field;
pub mod generated_frames;
pub mod histogram_equalisation;
pub mod image_pyramid;
pub mod image_similarity;
pub mod inactive_fill;
pub mod medoid_shift_alignment;
pub mod mesh_rasteriser;
pub mod naive_texture_pca;
pub mod poisson_texture_warp;
pub mod shading_removal;
pub mod solid_texture;
pub mod texel_mask;
pub mod texture_drift;
pub mod texture_folder;
pub mod texture_generator;
pub mod texture_image;
pub mod texture_preprocessing;
pub mod tv_l1_flow;

#[cfg(test)]
mod test_support;

pub use appearance_model::{AppearanceModel, AppearanceOptions, BuildReport, build_appearance_model};
pub use bilateral_filter::BilateralParams;
pub use eigen_maps::EigenBasis;
pub use error::{Error, Result};
pub use flow_field::FlowField;
pub use medoid_shift_alignment::{Alignment, FlowEstimator, align_by_medoid_shift};
pub use naive_texture_pca::NaiveTexturePca;
pub use poisson_texture_warp::{PoissonTextureWarp, TextureWarper, Warping};
pub use texel_mask::TexelMask;
pub use texture_image::TextureImage;
pub use texture_preprocessing::{PreprocessOptions, preprocess};
pub use tv_l1_flow::{FlowOptions, texture_flow, tv_l1_flow};
