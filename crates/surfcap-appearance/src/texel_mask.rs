//! The active texels of a texture atlas (thesis 4.4.2: the vectors of textures and warps hold
//! "only pixels that fall inside active regions within texture maps"; 4.5: errors are measured
//! on "the set of texels actually mapped to the 3D model").
//!
//! A texel is active when a UV triangle covers its centre ([`crate::atlas_raster`]), grown by a
//! ring of `dilation` texels: a renderer's bilinear lookup at a chart's edge reads the texels
//! just outside it, so those must carry appearance too (one texel by default; the thesis does
//! not say). Active texels are numbered in row-major order ([`TexelMask::index`]), the order of
//! every per-texel vector of the model.

use surfcap_mesh::UvAtlas;

use crate::atlas_raster::AtlasRaster;
use crate::error::{Error, Result};

/// Marks an inactive texel in [`TexelMask::slot`].
pub const INACTIVE: u32 = u32::MAX;

#[derive(Debug, Clone, PartialEq)]
pub struct TexelMask {
    width: usize,
    height: usize,
    /// Row-major texel of each active texel, increasing.
    index: Vec<u32>,
    /// Active number of each texel, or [`INACTIVE`].
    slot: Vec<u32>,
}

impl TexelMask {
    /// A mask from a per-texel flag (row-major).
    pub fn from_flags(width: usize, height: usize, active: &[bool]) -> Result<TexelMask> {
        if active.len() != width * height {
            return Err(Error::Mismatch(format!("{} flags for a {width}x{height} mask", active.len())));
        }
        let mut index = Vec::new();
        let mut slot = vec![INACTIVE; width * height];
        for (i, &a) in active.iter().enumerate() {
            if a {
                slot[i] = index.len() as u32;
                index.push(i as u32);
            }
        }
        if index.is_empty() {
            return Err(Error::Invalid(format!("no active texel in the {width}x{height} mask")));
        }
        Ok(TexelMask { width, height, index, slot })
    }

    /// Every texel active.
    pub fn full(width: usize, height: usize) -> TexelMask {
        TexelMask::from_flags(width, height, &vec![true; width * height]).expect("a non-empty full mask")
    }

    /// The texels the atlas covers at `width x height`, grown by `dilation` texels.
    pub fn from_atlas(atlas: &UvAtlas, width: usize, height: usize, dilation: usize) -> Result<TexelMask> {
        let raster = AtlasRaster::new(atlas, width, height)?;
        Self::from_raster(&raster, dilation)
    }

    /// The texels of a raster, grown by `dilation` texels (8-connected rings).
    pub fn from_raster(raster: &AtlasRaster, dilation: usize) -> Result<TexelMask> {
        let (w, h) = (raster.width, raster.height);
        let mut active: Vec<bool> = (0..w * h).map(|i| raster.covered(i)).collect();
        for _ in 0..dilation {
            let prev = active.clone();
            for y in 0..h {
                for x in 0..w {
                    if prev[y * w + x] {
                        continue;
                    }
                    let near = (y.saturating_sub(1)..(y + 2).min(h))
                        .any(|yy| (x.saturating_sub(1)..(x + 2).min(w)).any(|xx| prev[yy * w + xx]));
                    active[y * w + x] = near;
                }
            }
        }
        TexelMask::from_flags(w, h, &active)
            .map_err(|_| Error::Invalid(format!("the UV atlas covers no texel centre at {w}x{h}")))
    }

    pub fn width(&self) -> usize {
        self.width
    }
    pub fn height(&self) -> usize {
        self.height
    }
    /// Number of active texels.
    pub fn len(&self) -> usize {
        self.index.len()
    }
    /// Never true: a mask has at least one active texel.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }
    /// Row-major texel of each active texel.
    pub fn index(&self) -> &[u32] {
        &self.index
    }
    /// Active number of each texel, or [`INACTIVE`].
    pub fn slot(&self) -> &[u32] {
        &self.slot
    }
    pub fn is_active(&self, texel: usize) -> bool {
        self.slot[texel] != INACTIVE
    }
    /// Checks that the mask is `width x height`; `what` names the other side in the error.
    pub fn check_size(&self, width: usize, height: usize, what: &str) -> Result<()> {
        if self.width == width && self.height == height {
            return Ok(());
        }
        Err(Error::Mismatch(format!(
            "{what} is {width}x{height}: expected {}x{} like the active-texel mask",
            self.width, self.height
        )))
    }
    /// The active values of one plane, in active order.
    pub fn gather(&self, plane: &[f32]) -> Vec<f32> {
        self.index.iter().map(|&i| plane[i as usize]).collect()
    }
    /// Writes active values back into a plane (inactive texels untouched).
    pub fn scatter(&self, values: &[f32], plane: &mut [f32]) {
        for (&i, &v) in self.index.iter().zip(values) {
            plane[i as usize] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_grows_the_covered_region_by_one_ring() {
        let atlas = UvAtlas {
            coords: vec![[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
            corners: vec![[0, 1, 2], [0, 2, 3]],
        };
        let tight = TexelMask::from_atlas(&atlas, 8, 8, 0).unwrap();
        let grown = TexelMask::from_atlas(&atlas, 8, 8, 1).unwrap();
        assert_eq!(tight.len(), 16);
        assert_eq!(grown.len(), 25); // 4x4 quarter -> 5x5 (clipped at the image border)
        assert!(grown.is_active(3 * 8 + 4));
    }

    #[test]
    fn gather_and_scatter_are_inverse_on_active_texels() {
        let mask = TexelMask::from_flags(3, 1, &[true, false, true]).unwrap();
        assert_eq!(mask.gather(&[1.0, 2.0, 3.0]), vec![1.0, 3.0]);
        let mut plane = vec![0.0; 3];
        mask.scatter(&[5.0, 6.0], &mut plane);
        assert_eq!(plane, vec![5.0, 0.0, 6.0]);
    }

    #[test]
    fn an_atlas_outside_the_texture_is_refused() {
        let atlas = UvAtlas { coords: vec![[2.0, 2.0], [2.5, 2.0], [2.0, 2.5]], corners: vec![[0, 1, 2]] };
        let e = TexelMask::from_atlas(&atlas, 8, 8, 1).unwrap_err().to_string();
        assert!(e.contains("covers no texel"), "{e}");
    }
}
