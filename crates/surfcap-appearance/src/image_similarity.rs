//! Image similarity on a masked domain: the mean squared error and SSIM (Wang, Bovik, Sheikh and
//! Simoncelli 2004, "Image quality assessment: from error visibility to structural
//! similarity"), the two measures of the thesis's evaluation (4.5, Fig. 4.9-4.12): in the
//! texture domain over the active texels, in the image domain over the union of the
//! silhouettes of the renders compared.
//!
//! SSIM follows Wang et al.'s eq. 13 with their parameters: an 11 x 11 circular-symmetric
//! Gaussian window of standard deviation 1.5 (eq. 14-16 weights), `C1 = (0.01 L)^2`,
//! `C2 = (0.03 L)^2` with `L = 255` (images on the 8-bit scale, as [`TextureImage`]). Means,
//! variances and the covariance of a window are the weighted moments of eq. 14-16
//! (population form, divided by the weights' sum, not `N - 1`).
//!
//! The mask: a window takes only the masked pixels it covers, its Gaussian weights renormalised
//! over them (`mu = sum_q m_q g_q a_q / sum_q m_q g_q`, the same for the second moments);
//! pixels beyond the image border count as unmasked, so there is no padding rule. The SSIM map
//! is computed at every masked pixel and the score is its mean over the masked pixels, per
//! channel, then averaged over the channels (Wang et al. use grey images; per-channel averaging
//! is scikit-image's `channel_axis` convention). With a full mask, away from the border, this
//! is exactly Wang et al.'s windowed SSIM. Window sums are separable convolutions of
//! `m`, `m a`, `m b`, `m a^2`, `m b^2` and `m a b`, rows in parallel (deterministic: each
//! output value is a fixed-order sum).

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::texture_image::TextureImage;

/// Wang et al.'s window: standard deviation of the Gaussian, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;
/// Wang et al.'s window: radius (11 x 11).
pub const SSIM_RADIUS: usize = 5;
/// `C1 = (K1 L)^2` with `K1 = 0.01`, `L = 255`.
pub const SSIM_C1: f64 = (0.01 * 255.0) * (0.01 * 255.0);
/// `C2 = (K2 L)^2` with `K2 = 0.03`, `L = 255`.
pub const SSIM_C2: f64 = (0.03 * 255.0) * (0.03 * 255.0);

fn check(a: &TextureImage, b: &TextureImage, mask: &[bool]) -> Result<usize> {
    a.check_same_shape(b, "the second image")?;
    if mask.len() != a.texels() {
        return Err(Error::Mismatch(format!(
            "the mask has {} pixels for {}x{} images",
            mask.len(),
            a.width(),
            a.height()
        )));
    }
    let n = mask.iter().filter(|&&m| m).count();
    if n == 0 {
        return Err(Error::Invalid("the mask selects no pixel: nothing to compare".into()));
    }
    Ok(n)
}

/// Mean squared error over the masked pixels and every channel (8-bit scale units squared).
pub fn mse(a: &TextureImage, b: &TextureImage, mask: &[bool]) -> Result<f64> {
    let n = check(a, b, mask)?;
    let mut sum = 0.0f64;
    for c in 0..a.channels() {
        let (pa, pb) = (a.plane(c), b.plane(c));
        let s: f64 = pa
            .par_chunks(a.width())
            .zip(pb.par_chunks(a.width()))
            .zip(mask.par_chunks(a.width()))
            .map(|((ra, rb), rm)| {
                let mut s = 0.0f64;
                for i in 0..ra.len() {
                    if rm[i] {
                        let d = ra[i] as f64 - rb[i] as f64;
                        s += d * d;
                    }
                }
                s
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        sum += s;
    }
    Ok(sum / (n * a.channels()) as f64)
}

/// The normalised 1-D Gaussian of Wang et al.'s window (11 taps, sigma 1.5); the 2-D window is
/// its outer product.
pub fn ssim_kernel() -> [f64; 2 * SSIM_RADIUS + 1] {
    let mut k = [0.0f64; 2 * SSIM_RADIUS + 1];
    for (i, v) in k.iter_mut().enumerate() {
        let d = i as f64 - SSIM_RADIUS as f64;
        *v = (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    let s: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    k
}

/// Separable convolution with zero outside the image (the weights are renormalised by the
/// caller through the convolved mask).
fn convolve(plane: &[f64], width: usize, height: usize, k: &[f64]) -> Vec<f64> {
    let r = k.len() / 2;
    let mut tmp = vec![0.0f64; width * height];
    tmp.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let src = &plane[y * width..(y + 1) * width];
        for (x, o) in row.iter_mut().enumerate() {
            let mut s = 0.0;
            let lo = x.saturating_sub(r);
            let hi = (x + r).min(width - 1);
            for xx in lo..=hi {
                s += k[xx + r - x] * src[xx];
            }
            *o = s;
        }
    });
    let mut out = vec![0.0f64; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let lo = y.saturating_sub(r);
        let hi = (y + r).min(height - 1);
        for (x, o) in row.iter_mut().enumerate() {
            let mut s = 0.0;
            for yy in lo..=hi {
                s += k[yy + r - y] * tmp[yy * width + x];
            }
            *o = s;
        }
    });
    out
}

/// The SSIM map of one channel pair at every pixel (`NaN` off the mask), Wang et al.'s eq. 13
/// with masked, renormalised windows (see the module documentation).
pub fn ssim_map_plane(a: &[f32], b: &[f32], mask: &[bool], width: usize, height: usize) -> Vec<f64> {
    let k = ssim_kernel();
    let m: Vec<f64> = mask.iter().map(|&v| if v { 1.0 } else { 0.0 }).collect();
    let prod = |f: &(dyn Fn(f64, f64) -> f64 + Sync)| -> Vec<f64> {
        (0..width * height).map(|i| if mask[i] { f(a[i] as f64, b[i] as f64) } else { 0.0 }).collect()
    };
    let wm = convolve(&m, width, height, &k);
    let wa = convolve(&prod(&|x, _| x), width, height, &k);
    let wb = convolve(&prod(&|_, y| y), width, height, &k);
    let waa = convolve(&prod(&|x, _| x * x), width, height, &k);
    let wbb = convolve(&prod(&|_, y| y * y), width, height, &k);
    let wab = convolve(&prod(&|x, y| x * y), width, height, &k);
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            if !mask[i] {
                return f64::NAN;
            }
            let w = wm[i];
            let (ma, mb) = (wa[i] / w, wb[i] / w);
            // Weighted moments; clamped at 0 against cancellation in E[x^2] - E[x]^2.
            let va = (waa[i] / w - ma * ma).max(0.0);
            let vb = (wbb[i] / w - mb * mb).max(0.0);
            let cab = wab[i] / w - ma * mb;
            ((2.0 * ma * mb + SSIM_C1) * (2.0 * cab + SSIM_C2)) / ((ma * ma + mb * mb + SSIM_C1) * (va + vb + SSIM_C2))
        })
        .collect()
}

/// Mean SSIM over the masked pixels, averaged over the channels (1 for identical images).
pub fn ssim(a: &TextureImage, b: &TextureImage, mask: &[bool]) -> Result<f64> {
    let n = check(a, b, mask)?;
    let mut total = 0.0f64;
    for c in 0..a.channels() {
        let map = ssim_map_plane(a.plane(c), b.plane(c), mask, a.width(), a.height());
        let s: f64 = map.iter().zip(mask).filter(|(_, m)| **m).map(|(v, _)| *v).sum();
        total += s / n as f64;
    }
    Ok(total / a.channels() as f64)
}

/// MSE and SSIM of one comparison.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Similarity {
    pub mse: f64,
    pub ssim: f64,
}

/// Both measures over the same mask.
pub fn similarity(a: &TextureImage, b: &TextureImage, mask: &[bool]) -> Result<Similarity> {
    Ok(Similarity { mse: mse(a, b, mask)?, ssim: ssim(a, b, mask)? })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random_image(w: usize, h: usize, c: usize, seed: u64) -> TextureImage {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let data: Vec<f32> = (0..w * h * c).map(|_| rng.random_range(0.0..255.0f32)).collect();
        TextureImage::from_planes(w, h, c, data).unwrap()
    }

    #[test]
    fn identical_images_have_ssim_one_and_mse_zero() {
        let a = random_image(20, 17, 3, 1);
        let mask: Vec<bool> = (0..20 * 17).map(|i| i % 7 != 0).collect();
        let s = similarity(&a, &a, &mask).unwrap();
        assert_eq!(s.mse, 0.0);
        assert!((s.ssim - 1.0).abs() < 1e-12, "{}", s.ssim);
    }

    #[test]
    fn a_constant_offset_of_a_flat_image_matches_the_closed_form() {
        // a = alpha, b = alpha + c everywhere: variances and covariance vanish, so SSIM is the
        // luminance term (2 alpha (alpha + c) + C1) / (alpha^2 + (alpha + c)^2 + C1).
        let (alpha, c) = (100.0f64, 30.0f64);
        let a = TextureImage::from_planes(16, 12, 1, vec![alpha as f32; 192]).unwrap();
        let b = TextureImage::from_planes(16, 12, 1, vec![(alpha + c) as f32; 192]).unwrap();
        let mask: Vec<bool> = (0..192).map(|i| (i / 16) % 3 != 1).collect();
        let expected = (2.0 * alpha * (alpha + c) + SSIM_C1) / (alpha * alpha + (alpha + c).powi(2) + SSIM_C1);
        let s = similarity(&a, &b, &mask).unwrap();
        assert!((s.ssim - expected).abs() < 1e-12, "{} vs {expected}", s.ssim);
        assert!((s.mse - c * c).abs() < 1e-9);
    }

    #[test]
    fn the_separable_form_matches_a_direct_window_sum() {
        // An independent reference: each window summed directly over the 11 x 11 neighbourhood
        // with the 2-D Gaussian, masked and renormalised.
        let (w, h) = (23, 19);
        let a = random_image(w, h, 1, 2);
        let mut b = a.clone();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        b.data_mut().iter_mut().for_each(|v| *v = (*v * 0.8 + rng.random_range(-20.0..20.0f32)).clamp(0.0, 255.0));
        let mask: Vec<bool> = (0..w * h).map(|i| (i * 37 % 11) != 0).collect();
        let (pa, pb) = (a.plane(0), b.plane(0));
        let mut sum = 0.0;
        let mut n = 0;
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                if !mask[(y * w as i64 + x) as usize] {
                    continue;
                }
                let (mut sw, mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0);
                for dy in -5..=5i64 {
                    for dx in -5..=5i64 {
                        let (xx, yy) = (x + dx, y + dy);
                        if xx < 0 || yy < 0 || xx >= w as i64 || yy >= h as i64 {
                            continue;
                        }
                        let q = (yy * w as i64 + xx) as usize;
                        if !mask[q] {
                            continue;
                        }
                        let g = (-((dx * dx + dy * dy) as f64) / (2.0 * 1.5 * 1.5)).exp();
                        let (va, vb) = (pa[q] as f64, pb[q] as f64);
                        sw += g;
                        sa += g * va;
                        sb += g * vb;
                        saa += g * va * va;
                        sbb += g * vb * vb;
                        sab += g * va * vb;
                    }
                }
                let (ma, mb) = (sa / sw, sb / sw);
                let (va, vb, cab) = (saa / sw - ma * ma, sbb / sw - mb * mb, sab / sw - ma * mb);
                sum += ((2.0 * ma * mb + SSIM_C1) * (2.0 * cab + SSIM_C2))
                    / ((ma * ma + mb * mb + SSIM_C1) * (va + vb + SSIM_C2));
                n += 1;
            }
        }
        let direct = sum / n as f64;
        let fast = ssim(&a, &b, &mask).unwrap();
        assert!((fast - direct).abs() < 1e-9, "{fast} vs {direct}");
        assert!(fast < 0.95, "a degraded image scores below 1: {fast}");
    }

    #[test]
    fn unmasked_pixels_do_not_matter() {
        let a = random_image(16, 16, 3, 4);
        let mut b = a.clone();
        let mask: Vec<bool> = (0..256).map(|i| i % 16 < 8).collect();
        for c in 0..3 {
            for y in 0..16 {
                for x in 8..16 {
                    b.plane_mut(c)[y * 16 + x] = 0.0;
                }
            }
        }
        let s = similarity(&a, &b, &mask).unwrap();
        assert_eq!(s.mse, 0.0);
        assert!((s.ssim - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_inputs_are_refused() {
        let a = TextureImage::zeros(4, 4, 3);
        let b = TextureImage::zeros(4, 5, 3);
        assert!(mse(&a, &b, &[true; 16]).unwrap_err().to_string().contains("expected 4x4x3"));
        assert!(ssim(&a, &a, &[true; 15]).unwrap_err().to_string().contains("15 pixels"));
        assert!(ssim(&a, &a, &[false; 16]).unwrap_err().to_string().contains("no pixel"));
    }
}
