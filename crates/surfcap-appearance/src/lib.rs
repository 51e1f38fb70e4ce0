//! Eigen appearance maps (thesis chapter 4, Boukhayma 2017): a subject's per-frame texture
//! maps aligned to a reference by optical flow and Poisson warping, then reduced to eigen
//! textures and eigen warps.
//!
//! Layout, one algorithm per file: [`texture_image`] (the texture map and its files),
//! [`texel_mask`] (the active texels of a UV atlas), [`flow_field`] (a dense warp and bilinear
//! sampling); benchmark data with ground truth (issue 20 item 7): [`texture_generator`] (per-frame
//! textures from a real mesh and texture: drift, illumination, blur, noise, holes),
//! [`texture_drift`] (the known drift and the true flow), [`atlas_normals`] (normals and
//! positions in texture space), [`generated_frames`] (the folder and its reader); evaluation
//! (4.5): [`mesh_rasteriser`] (textured renders from virtual cameras), [`image_similarity`]
//! (masked MSE and SSIM).

pub mod atlas_normals;
pub mod atlas_raster;
pub mod error;
pub mod flow_field;
pub mod generated_frames;
pub mod image_similarity;
pub mod mesh_rasteriser;
pub mod texel_mask;
pub mod texture_drift;
pub mod texture_generator;
pub mod texture_image;

pub use error::{Error, Result};
pub use flow_field::FlowField;
pub use texel_mask::TexelMask;
pub use texture_image::TextureImage;
