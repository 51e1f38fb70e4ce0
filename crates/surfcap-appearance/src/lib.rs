//! Eigen appearance maps (thesis chapter 4, Boukhayma 2017): a subject's per-frame texture
//! maps aligned to a reference by optical flow and Poisson warping, then reduced to eigen
//! textures and eigen warps.
//!
//! Layout, one algorithm per file: [`texture_image`] (the texture map and its files),
//! [`texel_mask`] (the active texels of a UV atlas), [`flow_field`] (a dense warp and bilinear
//! sampling), [`histogram_equalisation`], [`bilateral_filter`] and [`texture_preprocessing`]
//! (4.4.1: the pre-processing before flow), [`image_pyramid`] and [`inactive_fill`] (the
//! flow's resampling and its extension of active texels), [`tv_l1_flow`] (4.4.1: TV-L1 flow
//! between texture maps).

pub mod atlas_raster;
pub mod bilateral_filter;
pub mod error;
pub mod flow_cache;
pub mod flow_field;
pub mod histogram_equalisation;
pub mod image_pyramid;
pub mod inactive_fill;
pub mod solid_texture;
pub mod texel_mask;
pub mod texture_image;
pub mod texture_preprocessing;
pub mod tv_l1_flow;

pub use bilateral_filter::BilateralParams;
pub use error::{Error, Result};
pub use flow_field::FlowField;
pub use texel_mask::TexelMask;
pub use texture_image::TextureImage;
pub use texture_preprocessing::{PreprocessOptions, preprocess};
pub use tv_l1_flow::{FlowOptions, texture_flow, tv_l1_flow};
