//! The pre-processing of texture maps before optical flow (thesis 4.4.1, Fig. 4.4): per-channel
//! histogram equalisation ([`crate::histogram_equalisation`]) then bilateral filtering
//! ([`crate::bilateral_filter`]), both over the active texels only. Brightness constancy does
//! not hold between textures seen under different viewpoints and illumination; equalisation
//! makes the flow's data term compare ranks rather than raw intensities, the bilateral filter
//! removes low-contrast detail while keeping edges.

use crate::bilateral_filter::{BilateralParams, bilateral_filter};
use crate::error::Result;
use crate::histogram_equalisation::equalise_histogram;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

/// Which pre-processing steps run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreprocessOptions {
    /// Per-channel histogram equalisation over the active texels.
    pub equalise: bool,
    /// Bilateral filtering after equalisation (`None`: skipped).
    pub bilateral: Option<BilateralParams>,
}

impl Default for PreprocessOptions {
    /// The thesis's pipeline: equalisation, then the bilateral filter with diameter 80, sigma
    /// colour 15, sigma space 80.
    fn default() -> Self {
        PreprocessOptions { equalise: true, bilateral: Some(BilateralParams::default()) }
    }
}

impl PreprocessOptions {
    /// No pre-processing at all.
    pub fn none() -> Self {
        PreprocessOptions { equalise: false, bilateral: None }
    }
}

/// Pre-processes `image` over the active texels of `mask`; inactive texels keep their value.
pub fn preprocess(image: &TextureImage, mask: &TexelMask, opts: &PreprocessOptions) -> Result<TextureImage> {
    mask.check_size(image.width(), image.height(), "the texture map")?;
    let equalised = if opts.equalise { equalise_histogram(image, mask)? } else { image.clone() };
    match &opts.bilateral {
        Some(p) => bilateral_filter(&equalised, mask, p),
        None => Ok(equalised),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_steps_compose_and_none_is_the_identity() {
        let data: Vec<f32> = (0..2 * 64).map(|i| ((i * 29) % 97) as f32 + 40.0).collect();
        let img = TextureImage::from_planes(8, 8, 2, data).unwrap();
        let mask = TexelMask::full(8, 8);
        assert_eq!(preprocess(&img, &mask, &PreprocessOptions::none()).unwrap(), img);
        let eq = PreprocessOptions { equalise: true, bilateral: None };
        assert_eq!(preprocess(&img, &mask, &eq).unwrap(), equalise_histogram(&img, &mask).unwrap());
        let both = preprocess(&img, &mask, &PreprocessOptions::default()).unwrap();
        let expected = bilateral_filter(&equalise_histogram(&img, &mask).unwrap(), &mask, &BilateralParams::default());
        assert_eq!(both, expected.unwrap());
    }
}
