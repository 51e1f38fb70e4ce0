//! Eigen appearance maps (thesis chapter 4, Boukhayma 2017): a subject's per-frame texture
//! maps aligned to a reference by optical flow and Poisson warping, then reduced to eigen
//! textures and eigen warps.
//!
//! Layout, one algorithm per file: [`texture_image`] (the texture map and its files),
//! [`texel_mask`] (the active texels of a UV atlas), [`flow_field`] (a dense warp and bilinear
//! sampling).

pub mod atlas_raster;
pub mod error;
pub mod flow_cache;
pub mod flow_field;
pub mod solid_texture;
pub mod texel_mask;
pub mod texture_image;

pub use error::{Error, Result};
pub use flow_field::FlowField;
pub use texel_mask::TexelMask;
pub use texture_image::TextureImage;
