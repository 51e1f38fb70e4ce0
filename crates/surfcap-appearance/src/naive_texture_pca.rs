//! The baseline of thesis 4.5 (Fig. 4.9-4.12, "naive PCA"): PCA of the unaligned textures over
//! the same active texels, without alignment or warps, through the same F x F Gram route
//! ([`crate::eigen_maps`]). A texture is reconstructed from its first k coefficients;
//! inactive texels of a reconstruction are 0.

use crate::eigen_maps::EigenBasis;
use crate::error::{Error, Result};
use crate::medoid_shift_alignment::{active_vector, check_textures};
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

#[derive(Debug, Clone)]
pub struct NaiveTexturePca {
    mask: TexelMask,
    channels: usize,
    basis: EigenBasis,
}

impl NaiveTexturePca {
    /// PCA of `textures` (all on `mask`) keeping at most `n_components`.
    pub fn new(textures: &[TextureImage], mask: &TexelMask, n_components: usize) -> Result<NaiveTexturePca> {
        check_textures(textures, mask, None)?;
        let vectors: Vec<Vec<f32>> = textures.iter().map(|t| active_vector(t, mask)).collect();
        let refs: Vec<&[f32]> = vectors.iter().map(Vec::as_slice).collect();
        let basis = EigenBasis::new(&refs, n_components, "textures")?;
        Ok(NaiveTexturePca { mask: mask.clone(), channels: textures[0].channels(), basis })
    }

    pub fn basis(&self) -> &EigenBasis {
        &self.basis
    }
    pub fn n_components(&self) -> usize {
        self.basis.n_components()
    }

    /// Coefficients of a texture (all components).
    pub fn project(&self, texture: &TextureImage) -> Result<Vec<f64>> {
        self.mask.check_size(texture.width(), texture.height(), "the texture to project")?;
        if texture.channels() != self.channels {
            return Err(Error::Mismatch(format!(
                "the texture to project has {} channels: expected {}",
                texture.channels(),
                self.channels
            )));
        }
        self.basis.project(&active_vector(texture, &self.mask))
    }

    /// The texture of the first `coefficients.len()` components.
    pub fn instantiate(&self, coefficients: &[f64]) -> Result<TextureImage> {
        let v = self.basis.reconstruct(coefficients)?;
        let n = self.mask.len();
        let mut img = TextureImage::zeros(self.mask.width(), self.mask.height(), self.channels);
        for c in 0..self.channels {
            self.mask.scatter(&v[c * n..(c + 1) * n], img.plane_mut(c));
        }
        Ok(img)
    }

    /// Training frame `frame` from its first `k` coefficients.
    pub fn reconstruct(&self, frame: usize, k: usize) -> Result<TextureImage> {
        if frame >= self.basis.n_frames() {
            return Err(Error::Invalid(format!(
                "frame {frame}: the PCA has {} training frames",
                self.basis.n_frames()
            )));
        }
        let c = self.basis.frame_coefficients(frame);
        self.instantiate(&c[..k.min(c.len())])
    }

    /// Any texture projected and reconstructed with `k` components.
    pub fn reconstruct_texture(&self, texture: &TextureImage, k: usize) -> Result<TextureImage> {
        let c = self.project(texture)?;
        self.instantiate(&c[..k.min(c.len())])
    }
}
