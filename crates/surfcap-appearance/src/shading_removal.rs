//! Removal of smooth shading before optical flow: each channel's logarithm minus its masked
//! Gaussian blur, a high-pass of the log image. Not in the thesis: its pre-processing (4.4.1:
//! histogram equalisation, bilateral filter) did not make TV-L1 robust to the illumination
//! changes the thesis names as its reason. On the benchmark sequence of `surfcap appearance
//! generate` at 256 x 256 (light moving over the head scan, shading 0.55 + 0.6 max(0, n.l)),
//! the flow between two frames with the thesis's pre-processing drifted by 20-28 texels on
//! average against true displacements of 0.2-0.5 texel (end-point error 20-28); with this step
//! added the error fell to 0.17-0.32 (0.10-0.11 at 1024 x 1024), and without lighting changes
//! the flow was already at 0.1. Shading multiplies the albedo, so in the log it adds; being
//! smooth over the surface, it is mostly removed by the high-pass, while the texture's detail,
//! which the flow matches, is kept. The blur is a normalised convolution over the active
//! texels (inactive ones neither contribute nor bias the chart borders); the smallest width
//! measured best (1 texel at 256, 2 at 1024), so sigma scales with the map: width / 512,
//! at least one texel. Inactive texels are set to 0.

use crate::error::Result;
use crate::image_pyramid::gaussian_blur;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

/// Offset before the logarithm, on the 0-255 scale (keeps black texels finite).
const LOG_OFFSET: f32 = 4.0;

/// The blur's sigma, texels, for a map `width` texels wide when the options give
/// `sigma_per_width` (a fraction of the width).
pub fn shading_sigma(width: usize, sigma_per_width: f32) -> f32 {
    (width as f32 * sigma_per_width).max(1.0)
}

/// `log(I + 4) - blur_sigma(log(I + 4))` per channel over the active texels of `mask`, scaled
/// by 40 (the flow normalises its inputs; the scale only keeps values readable).
pub fn remove_shading(image: &TextureImage, mask: &TexelMask, sigma: f32) -> Result<TextureImage> {
    mask.check_size(image.width(), image.height(), "the texture map")?;
    let (w, h) = (image.width(), image.height());
    let weight: Vec<f32> = (0..w * h).map(|i| if mask.is_active(i) { 1.0 } else { 0.0 }).collect();
    let blurred_weight = gaussian_blur(&weight, w, h, sigma);
    let mut out = image.clone();
    for c in 0..image.channels() {
        let log: Vec<f32> =
            image.plane(c).iter().zip(&weight).map(|(&v, &m)| m * 40.0 * (v.max(0.0) + LOG_OFFSET).ln()).collect();
        let blurred = gaussian_blur(&log, w, h, sigma);
        for (i, o) in out.plane_mut(c).iter_mut().enumerate() {
            *o =
                if weight[i] > 0.0 && blurred_weight[i] > 1e-6 { log[i] - blurred[i] / blurred_weight[i] } else { 0.0 };
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_smooth_gain_is_removed_and_detail_kept() {
        let (w, h) = (48, 40);
        let detail = |x: usize, y: usize| 100.0 + 50.0 * ((x as f32 * 1.7).sin() * (y as f32 * 1.3).cos());
        let gain = |x: usize, _y: usize| 0.5 + 0.5 * x as f32 / w as f32;
        let plane = |shaded: bool| -> Vec<f32> {
            (0..w * h).map(|i| detail(i % w, i / w) * if shaded { gain(i % w, i / w) } else { 1.0 }).collect()
        };
        let a = TextureImage::from_planes(w, h, 1, plane(false)).unwrap();
        let b = TextureImage::from_planes(w, h, 1, plane(true)).unwrap();
        let active: Vec<bool> = (0..w * h).map(|i| (i % w) > 2 && (i % w) < w - 3).collect();
        let mask = TexelMask::from_flags(w, h, &active).unwrap();
        let (ra, rb) = (remove_shading(&a, &mask, 2.0).unwrap(), remove_shading(&b, &mask, 2.0).unwrap());
        let diff = |x: &TextureImage, y: &TextureImage| -> f32 {
            let n = mask.len() as f32;
            mask.index().iter().map(|&i| (x.plane(0)[i as usize] - y.plane(0)[i as usize]).abs()).sum::<f32>() / n
        };
        let spread = mask.index().iter().map(|&i| ra.plane(0)[i as usize].abs()).sum::<f32>() / mask.len() as f32;
        // The shaded and unshaded maps become nearly the same; the detail stays.
        assert!(diff(&ra, &rb) < 0.05 * spread, "difference {} against detail {spread}", diff(&ra, &rb));
        assert!(spread > 5.0);
        // Inactive texels are zero.
        assert_eq!(ra.plane(0)[0], 0.0);
    }
}
