//! Eigen appearance maps (thesis chapter 4, Boukhayma 2017): a subject's per-frame texture
//! maps aligned to a reference by optical flow and Poisson warping, then reduced to eigen
//! textures and eigen warps.
//!
//! Layout, one algorithm per file: [`texture_image`] (the texture map and its files),
//! [`atlas_raster`] and [`texel_mask`] (the active texels of a UV atlas), [`flow_field`] (a
//! dense warp and bilinear sampling), [`histogram_equalisation`], [`bilateral_filter`] and
//! [`texture_preprocessing`] (4.4.1: the pre-processing before flow, with [`shading_removal`]), [`image_pyramid`] and
//! [`inactive_fill`] (the flow's resampling and its extension of active texels), [`tv_l1_flow`]
//! (4.4.1: TV-L1 flow between texture maps), [`flow_cache`] (flows kept on disk),
//! [`poisson_texture_warp`] (eq. 4.1-4.3), [`medoid_shift_alignment`] (Algorithm 4),
//! [`eigen_maps`] (PCA through the Gram matrix, eq. 4.4-4.11), [`appearance_model`] (eigen
//! textures and eigen warps: build, instantiate, interpolate, complete, save/load),
//! [`naive_texture_pca`] (the baseline of 4.5), [`solid_texture`] (a base texture painted from
//! 3D positions); benchmark data with ground truth (issue 20 item 7):
//! [`texture_generator`] (per-frame textures from a real mesh and texture: drift,
//! illumination, blur, noise, holes), [`texture_drift`] (the known drift and the true flow),
//! [`atlas_normals`] (normals and positions in texture space), [`generated_frames`] (the folder
//! and its reader); evaluation (4.5): [`mesh_rasteriser`] (textured renders from virtual
//! cameras), [`image_similarity`] (masked MSE and SSIM); shape and appearance together (Fig.
//! 7.1): [`blended_frame_textures`] (a texture for every frame of a synthesised animation, with
//! the weights Blend gives the geometry).

pub mod appearance_model;
pub mod atlas_normals;
pub mod atlas_raster;
pub mod bilateral_filter;
pub mod blended_frame_textures;
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
