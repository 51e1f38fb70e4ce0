//! The pre-processing of texture maps before optical flow (thesis 4.4.1, Fig. 4.4): per-channel
//! histogram equalisation ([`crate::histogram_equalisation`]) then bilateral filtering
//! ([`crate::bilateral_filter`]), both over the active texels only. Brightness constancy does
//! not hold between textures seen under different viewpoints and illumination; equalisation
//! makes the flow's data term compare ranks rather than raw intensities, the bilateral filter
//! removes low-contrast detail while keeping edges. A third step, not in the thesis, removes
//! smooth shading ([`crate::shading_removal`]): without it the flow failed under the
//! illumination changes of the benchmark sequence (measured there).

use crate::bilateral_filter::{BilateralParams, bilateral_filter};
use crate::error::Result;
use crate::histogram_equalisation::equalise_histogram;
use crate::shading_removal::{remove_shading, shading_sigma};
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

/// Which pre-processing steps run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreprocessOptions {
    /// Per-channel histogram equalisation over the active texels.
    pub equalise: bool,
    /// Bilateral filtering after equalisation (`None`: skipped).
    pub bilateral: Option<BilateralParams>,
    /// Shading removal last, its blur's sigma as a fraction of the map's width (at least one
    /// texel; `None`: skipped).
    pub shading_sigma: Option<f32>,
}

impl Default for PreprocessOptions {
    /// The thesis's pipeline, equalisation then the bilateral filter with diameter 80, sigma
    /// colour 15, sigma space 80, followed by shading removal at sigma = width / 512.
    fn default() -> Self {
        PreprocessOptions {
            equalise: true,
            bilateral: Some(BilateralParams::default()),
            shading_sigma: Some(1.0 / 512.0),
        }
    }
}

impl PreprocessOptions {
    /// No pre-processing at all.
    pub fn none() -> Self {
        PreprocessOptions { equalise: false, bilateral: None, shading_sigma: None }
    }

    /// The thesis's steps only (4.4.1), without shading removal.
    pub fn thesis() -> Self {
        PreprocessOptions { shading_sigma: None, ..PreprocessOptions::default() }
    }
}

/// Pre-processes `image` over the active texels of `mask`; inactive texels keep their value.
pub fn preprocess(image: &TextureImage, mask: &TexelMask, opts: &PreprocessOptions) -> Result<TextureImage> {
    mask.check_size(image.width(), image.height(), "the texture map")?;
    let equalised = if opts.equalise { equalise_histogram(image, mask)? } else { image.clone() };
    let filtered = match &opts.bilateral {
        Some(p) => bilateral_filter(&equalised, mask, p)?,
        None => equalised,
    };
    match opts.shading_sigma {
        Some(s) => remove_shading(&filtered, mask, shading_sigma(image.width(), s)),
        None => Ok(filtered),
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
        let eq = PreprocessOptions { equalise: true, bilateral: None, shading_sigma: None };
        assert_eq!(preprocess(&img, &mask, &eq).unwrap(), equalise_histogram(&img, &mask).unwrap());
        let both = preprocess(&img, &mask, &PreprocessOptions::thesis()).unwrap();
        let expected = bilateral_filter(&equalise_histogram(&img, &mask).unwrap(), &mask, &BilateralParams::default());
        assert_eq!(both, expected.unwrap());
    }
}
