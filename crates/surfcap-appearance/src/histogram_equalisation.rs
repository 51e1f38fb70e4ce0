//! Per-channel histogram equalisation over the active texels (thesis 4.4.1: "we use histogram
//! equalization as a preprocessing step, which presents the benefit of enhancing contrast and
//! edges", applied before the optical flow so that brightness constancy holds better between
//! textures seen under different illumination).
//!
//! The mapping is OpenCV's `equalizeHist` (the tool the thesis used): values are binned to the
//! 256 integer levels (rounded, clamped to 0-255), `c` is the cumulative histogram and `c_min`
//! the count of the lowest occupied level, and level `i` maps to
//! `round(255 (c(i) - c_min) / (n - c_min))`. Only active texels enter the histogram (the
//! inactive background of an atlas, often one flat colour over half the map, would otherwise
//! take a large share of the output range) and only active texels are rewritten; inactive
//! texels keep their input value.

use crate::error::Result;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

/// Equalises every channel of `image` over the active texels of `mask` (inactive texels are
/// copied unchanged).
pub fn equalise_histogram(image: &TextureImage, mask: &TexelMask) -> Result<TextureImage> {
    mask.check_size(image.width(), image.height(), "the texture map")?;
    let mut out = image.clone();
    for c in 0..image.channels() {
        equalise_plane(out.plane_mut(c), mask);
    }
    Ok(out)
}

/// Equalises one row-major plane in place over the active texels of `mask`.
pub fn equalise_plane(plane: &mut [f32], mask: &TexelMask) {
    let level = |v: f32| v.round().clamp(0.0, 255.0) as usize;
    let mut histogram = [0u64; 256];
    for &i in mask.index() {
        histogram[level(plane[i as usize])] += 1;
    }
    let total: u64 = histogram.iter().sum();
    let first = histogram.iter().position(|&h| h > 0).expect("a mask has at least one active texel");
    let mut lut = [0.0f32; 256];
    if histogram[first] == total {
        // One level only: OpenCV leaves it as it is.
        lut[first] = first as f32;
    } else {
        let scale = 255.0 / (total - histogram[first]) as f64;
        let mut cumulative = 0u64;
        for i in first + 1..256 {
            cumulative += histogram[i];
            lut[i] = (cumulative as f64 * scale).round() as f32;
        }
    }
    for &i in mask.index() {
        let v = &mut plane[i as usize];
        *v = lut[level(*v)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn active_levels_spread_over_the_full_range() {
        // Active values 100, 101, 102, 103 (one each); inactive 0 and 255 must not count.
        let plane = vec![100.0, 101.0, 0.0, 102.0, 103.0, 255.0];
        let mask = TexelMask::from_flags(6, 1, &[true, true, false, true, true, false]).unwrap();
        let img = TextureImage::from_planes(6, 1, 1, plane).unwrap();
        let out = equalise_histogram(&img, &mask).unwrap();
        assert_eq!(out.plane(0), &[0.0, 85.0, 0.0, 170.0, 255.0, 255.0]);
    }

    #[test]
    fn a_monotone_change_of_brightness_is_undone() {
        // Equalisation depends only on the order of the values: a gamma and gain change of the
        // active texels gives the same output.
        let values: Vec<f32> = (0..64).map(|i| ((i * 37) % 64) as f32 * 2.0 + 20.0).collect();
        let changed: Vec<f32> = values.iter().map(|v| 255.0 * (v / 255.0).powf(0.7) * 0.9).collect();
        let mask = TexelMask::full(8, 8);
        let a = equalise_histogram(&TextureImage::from_planes(8, 8, 1, values).unwrap(), &mask).unwrap();
        let b = equalise_histogram(&TextureImage::from_planes(8, 8, 1, changed).unwrap(), &mask).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn a_mask_of_another_size_is_refused() {
        let img = TextureImage::zeros(4, 4, 3);
        let e = equalise_histogram(&img, &TexelMask::full(4, 5)).unwrap_err().to_string();
        assert!(e.contains("the texture map is 4x4: expected 4x5"), "{e}");
    }
}
