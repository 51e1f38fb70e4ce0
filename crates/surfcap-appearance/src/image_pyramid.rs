//! Image resampling for coarse-to-fine optical flow, as in the IPOL TV-L1 reference
//! (Sanchez Perez, Meinhardt-Llopis and Facciolo 2013, `zoom.c`, `bicubic_interpolation.c`,
//! `mask.c`): separable Gaussian smoothing with symmetric (Neumann) borders, Catmull-Rom
//! bicubic interpolation with clamped borders, zoom out (Gaussian of sigma
//! `0.6 sqrt(1 / z^2 - 1)` then bicubic sampling at `x / z`) and zoom in (bicubic at
//! `x n_coarse / n_fine`).

use rayon::prelude::*;

/// Sigma of the anti-aliasing Gaussian per unit of `sqrt(1 / z^2 - 1)` (IPOL `ZOOM_SIGMA_ZERO`).
const ZOOM_SIGMA_ZERO: f32 = 0.6;

/// Rows per rayon task: enough work per task that small images do not drown in overhead.
pub(crate) fn rows_per_task(width: usize) -> usize {
    (16_384 / width.max(1)).max(1)
}

/// The size of an image zoomed by `z` (IPOL `zoom_size`: `(int)(n z + 0.5)`, at least 1).
pub fn zoom_size(width: usize, height: usize, z: f32) -> (usize, usize) {
    let f = |n: usize| (((n as f32) * z + 0.5) as usize).max(1);
    (f(width), f(height))
}

/// Separable Gaussian smoothing of a row-major plane (symmetric borders: texel -1 is texel 0).
pub fn gaussian_blur(plane: &[f32], width: usize, height: usize, sigma: f32) -> Vec<f32> {
    if sigma <= 0.0 {
        return plane.to_vec();
    }
    let radius = (4.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = {
        let k: Vec<f32> = (-radius..=radius).map(|d| (-(d * d) as f32 / (2.0 * sigma * sigma)).exp()).collect();
        let sum: f32 = k.iter().sum();
        k.into_iter().map(|v| v / sum).collect()
    };
    let mirror = |i: isize, n: usize| -> usize {
        let n = n as isize;
        let mut i = i;
        // Symmetric extension, repeated for kernels wider than the image.
        loop {
            if i < 0 {
                i = -i - 1;
            } else if i >= n {
                i = 2 * n - i - 1;
            } else {
                return i as usize;
            }
        }
    };
    let chunk = rows_per_task(width) * width;
    let mut tmp = vec![0.0f32; plane.len()];
    tmp.par_chunks_mut(chunk).enumerate().for_each(|(c, out)| {
        for (r, row_out) in out.chunks_mut(width).enumerate() {
            let y = c * rows_per_task(width) + r;
            let row = &plane[y * width..(y + 1) * width];
            for (x, o) in row_out.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (k, &kw) in kernel.iter().enumerate() {
                    acc += kw * row[mirror(x as isize + k as isize - radius, width)];
                }
                *o = acc;
            }
        }
    });
    let mut out = vec![0.0f32; plane.len()];
    out.par_chunks_mut(chunk).enumerate().for_each(|(c, out)| {
        for (r, row_out) in out.chunks_mut(width).enumerate() {
            let y = c * rows_per_task(width) + r;
            for (k, &kw) in kernel.iter().enumerate() {
                let sy = mirror(y as isize + k as isize - radius, height);
                let src = &tmp[sy * width..(sy + 1) * width];
                for (o, s) in row_out.iter_mut().zip(src) {
                    *o += kw * s;
                }
            }
        }
    });
    out
}

/// Catmull-Rom weights of the four taps around a point at fraction `t` past the second tap.
#[inline]
pub(crate) fn cubic_weights(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [0.5 * (-t + 2.0 * t2 - t3), 0.5 * (2.0 - 5.0 * t2 + 3.0 * t3), 0.5 * (t + 4.0 * t2 - 3.0 * t3), 0.5 * (t3 - t2)]
}

/// The four clamped tap indices and weights along one axis for coordinate `x`.
#[inline]
pub(crate) fn cubic_taps(x: f32, n: usize) -> ([usize; 4], [f32; 4]) {
    let f = x.floor();
    let i = f as isize;
    let last = n as isize - 1;
    let idx = [(i - 1).clamp(0, last), i.clamp(0, last), (i + 1).clamp(0, last), (i + 2).clamp(0, last)];
    (idx.map(|v| v as usize), cubic_weights(x - f))
}

/// Bicubic sample of a plane at (x, y), clamped borders.
pub fn sample_bicubic(plane: &[f32], width: usize, height: usize, x: f32, y: f32) -> f32 {
    let (xi, xw) = cubic_taps(x, width);
    let (yi, yw) = cubic_taps(y, height);
    let mut acc = 0.0;
    for r in 0..4 {
        let row = &plane[yi[r] * width..];
        acc += yw[r] * (xw[0] * row[xi[0]] + xw[1] * row[xi[1]] + xw[2] * row[xi[2]] + xw[3] * row[xi[3]]);
    }
    acc
}

/// Resamples a plane to `out_w x out_h` by bicubic sampling at `(x sx, y sy)`.
fn resample(plane: &[f32], width: usize, height: usize, out_w: usize, out_h: usize, sx: f32, sy: f32) -> Vec<f32> {
    let mut out = vec![0.0f32; out_w * out_h];
    let rows = rows_per_task(out_w);
    out.par_chunks_mut(rows * out_w).enumerate().for_each(|(c, chunk)| {
        for (r, row) in chunk.chunks_mut(out_w).enumerate() {
            let y = (c * rows + r) as f32 * sy;
            for (x, o) in row.iter_mut().enumerate() {
                *o = sample_bicubic(plane, width, height, x as f32 * sx, y);
            }
        }
    });
    out
}

/// Zooms a plane out by `z` < 1 (IPOL `zoom_out`): anti-aliasing Gaussian, then bicubic
/// sampling. Returns the plane and its size.
pub fn zoom_out(plane: &[f32], width: usize, height: usize, z: f32) -> (Vec<f32>, usize, usize) {
    let (w, h) = zoom_size(width, height, z);
    let sigma = ZOOM_SIGMA_ZERO * (1.0 / (z * z) - 1.0).max(0.0).sqrt();
    let smooth = gaussian_blur(plane, width, height, sigma);
    (resample(&smooth, width, height, w, h, 1.0 / z, 1.0 / z), w, h)
}

/// Zooms a plane in to `out_w x out_h` (IPOL `zoom_in`: bicubic at `x width / out_w`).
pub fn zoom_in(plane: &[f32], width: usize, height: usize, out_w: usize, out_h: usize) -> Vec<f32> {
    resample(plane, width, height, out_w, out_h, width as f32 / out_w as f32, height as f32 / out_h as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bicubic_reproduces_samples_and_linear_ramps() {
        let (w, h) = (7, 5);
        let plane: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 2.0 + (i / w) as f32 * 3.0).collect();
        assert_eq!(sample_bicubic(&plane, w, h, 3.0, 2.0), plane[2 * w + 3]);
        let v = sample_bicubic(&plane, w, h, 2.25, 1.5);
        assert!((v - (2.25 * 2.0 + 1.5 * 3.0)).abs() < 1e-5, "{v}");
    }

    #[test]
    fn blur_keeps_constants_and_the_mean_of_a_symmetric_image() {
        let plane = vec![3.0f32; 20 * 10];
        let out = gaussian_blur(&plane, 20, 10, 1.5);
        assert!(out.iter().all(|v| (v - 3.0).abs() < 1e-5));
    }

    #[test]
    fn zoom_sizes_follow_ipol() {
        assert_eq!(zoom_size(1024, 1024, 0.5), (512, 512));
        assert_eq!(zoom_size(33, 9, 0.5), (17, 5));
        let (p, w, h) = zoom_out(&vec![1.0; 33 * 9], 33, 9, 0.5);
        assert_eq!((w, h, p.len()), (17, 5, 85));
        assert_eq!(zoom_in(&p, w, h, 33, 9).len(), 33 * 9);
    }
}
