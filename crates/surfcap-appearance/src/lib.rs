//! Eigen appearance maps (thesis chapter 4, Boukhayma 2017): a subject's per-frame texture
//! maps aligned to a reference by optical flow and Poisson warping, then reduced to eigen
//! textures and eigen warps.
//!
//! Layout, one algorithm per file: [`texture_image`] (the texture map and its files),
//! [`texel_mask`] (the active texels of a UV atlas), [`flow_field`] (a dense warp and bilinear
//! sampling), [`poisson_texture_warp`] (eq. 4.1-4.3), [`medoid_shift_alignment`] (Algorithm 4),
//! [`eigen_maps`] (PCA through the Gram matrix, eq. 4.4-4.11), [`appearance_model`] (eigen
//! textures and eigen warps: build, instantiate, interpolate, complete, save/load),
//! [`naive_texture_pca`] (the baseline of 4.5).

pub mod appearance_model;
pub mod atlas_raster;
pub mod eigen_maps;
pub mod error;
pub mod flow_field;
pub mod medoid_shift_alignment;
pub mod naive_texture_pca;
pub mod poisson_texture_warp;
pub mod texel_mask;
pub mod texture_image;

#[cfg(test)]
mod test_support;

pub use appearance_model::{AppearanceModel, AppearanceOptions, BuildReport, build_appearance_model};
pub use eigen_maps::EigenBasis;
pub use error::{Error, Result};
pub use flow_field::FlowField;
pub use medoid_shift_alignment::{Alignment, FlowEstimator, align_by_medoid_shift};
pub use naive_texture_pca::NaiveTexturePca;
pub use poisson_texture_warp::{PoissonTextureWarp, TextureWarper, Warping};
pub use texel_mask::TexelMask;
pub use texture_image::TextureImage;
