//! Test helpers: a small parametric flow estimator (quadratic flow fields fitted by
//! Levenberg-Marquardt on blurred grey images) so the model's tests do not depend on the TV-L1
//! flow, synthetic textures with known smooth warps, and the real head texture's crops.

#![allow(clippy::needless_range_loop)]

use crate::error::Result;
use crate::flow_field::{FlowField, sample_bilinear};
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

fn blurred_grey(img: &TextureImage) -> Vec<f32> {
    let (w, h) = (img.width(), img.height());
    let mut g = img.grey();
    for _ in 0..2 {
        let src = g.clone();
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                let mut n = 0.0;
                for yy in y.saturating_sub(1)..(y + 2).min(h) {
                    for xx in x.saturating_sub(1)..(x + 2).min(w) {
                        s += src[yy * w + xx];
                        n += 1.0;
                    }
                }
                g[y * w + x] = s / n;
            }
        }
    }
    g
}

fn basis(x: f64, y: f64, w: usize, h: usize) -> [f64; 6] {
    let xs = (x - 0.5 * w as f64) / (0.5 * w as f64);
    let ys = (y - 0.5 * h as f64) / (0.5 * h as f64);
    [1.0, xs, ys, xs * xs, xs * ys, ys * ys]
}

/// The flow w with reference(x) ≈ target(x + w(x)) among quadratic fields, over `domain`
/// (every texel when `None`) minus a 2-texel border.
pub(crate) fn quadratic_flow(
    reference: &TextureImage,
    target: &TextureImage,
    domain: Option<&TexelMask>,
) -> Result<FlowField> {
    let (w, h) = (reference.width(), reference.height());
    let r = blurred_grey(reference);
    let t = blurred_grey(target);
    let pts: Vec<usize> = (0..w * h)
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            x >= 2 && y >= 2 && x + 2 < w && y + 2 < h && domain.is_none_or(|m| m.is_active(i))
        })
        .collect();
    let phi: Vec<[f64; 6]> = pts.iter().map(|&i| basis((i % w) as f64, (i / w) as f64, w, h)).collect();
    let flow_at = |p: &[f64; 12], k: usize| -> (f64, f64) {
        let (mut u, mut v) = (0.0, 0.0);
        for j in 0..6 {
            u += p[j] * phi[k][j];
            v += p[6 + j] * phi[k][j];
        }
        (u, v)
    };
    let sample = |x: f64, y: f64| sample_bilinear(&t, w, h, x as f32, y as f32) as f64;
    let cost = |p: &[f64; 12]| -> f64 {
        pts.iter()
            .enumerate()
            .map(|(k, &i)| {
                let (u, v) = flow_at(p, k);
                (sample((i % w) as f64 + u, (i / w) as f64 + v) - r[i] as f64).powi(2)
            })
            .sum()
    };
    let mut p = [0.0f64; 12];
    let mut c = cost(&p);
    let mut mu = 1e-3;
    for _ in 0..60 {
        let mut a = [[0.0f64; 12]; 12];
        let mut b = [0.0f64; 12];
        for (k, &i) in pts.iter().enumerate() {
            let (u, v) = flow_at(&p, k);
            let (x, y) = ((i % w) as f64 + u, (i / w) as f64 + v);
            let res = sample(x, y) - r[i] as f64;
            let gx = 0.5 * (sample(x + 1.0, y) - sample(x - 1.0, y));
            let gy = 0.5 * (sample(x, y + 1.0) - sample(x, y - 1.0));
            let mut jrow = [0.0f64; 12];
            for j in 0..6 {
                jrow[j] = gx * phi[k][j];
                jrow[6 + j] = gy * phi[k][j];
            }
            for m in 0..12 {
                b[m] -= jrow[m] * res;
                for n in 0..12 {
                    a[m][n] += jrow[m] * jrow[n];
                }
            }
        }
        let mut improved = false;
        for _ in 0..8 {
            let mut m = a;
            for d in 0..12 {
                m[d][d] *= 1.0 + mu;
                m[d][d] += 1e-9;
            }
            let step = solve12(m, b);
            let mut q = p;
            for d in 0..12 {
                q[d] += step[d];
            }
            let cq = cost(&q);
            if cq < c {
                p = q;
                let done = (c - cq) < 1e-9 * c.max(1e-12);
                c = cq;
                mu = (mu * 0.3).max(1e-6);
                improved = !done;
                break;
            }
            mu *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let mut flow = FlowField::zeros(w, h);
    for i in 0..w * h {
        let f = basis((i % w) as f64, (i / w) as f64, w, h);
        let (mut u, mut v) = (0.0, 0.0);
        for j in 0..6 {
            u += p[j] * f[j];
            v += p[6 + j] * f[j];
        }
        flow.u[i] = u as f32;
        flow.v[i] = v as f32;
    }
    Ok(flow)
}

fn solve12(mut a: [[f64; 12]; 12], mut b: [f64; 12]) -> [f64; 12] {
    for c in 0..12 {
        let piv = (c..12).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs())).unwrap();
        a.swap(c, piv);
        b.swap(c, piv);
        let d = a[c][c];
        if d.abs() < 1e-300 {
            continue;
        }
        for r in c + 1..12 {
            let f = a[r][c] / d;
            for k in c..12 {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 12];
    for c in (0..12).rev() {
        let mut s = b[c];
        for k in c + 1..12 {
            s -= a[c][k] * x[k];
        }
        x[c] = if a[c][c].abs() < 1e-300 { 0.0 } else { s / a[c][c] };
    }
    x
}

/// A disc of active texels (radius 0.45 of the size) in a `size x size` mask.
pub(crate) fn disc_mask(size: usize) -> TexelMask {
    let c = 0.5 * size as f64 - 0.5;
    let r = 0.45 * size as f64;
    let flags: Vec<bool> =
        (0..size * size).map(|i| ((i % size) as f64 - c).hypot((i / size) as f64 - c) <= r).collect();
    TexelMask::from_flags(size, size, &flags).unwrap()
}

/// A smooth quadratic warp of amplitude about `amp` texels, varying with `seed`.
pub(crate) fn known_warp(size: usize, amp: f64, seed: u64) -> FlowField {
    let s = seed as f64;
    let mut f = FlowField::zeros(size, size);
    for i in 0..size * size {
        let b = basis((i % size) as f64, (i / size) as f64, size, size);
        let u = amp * ((0.7 * s).sin() * b[0] + 0.4 * (1.3 * s).cos() * b[1] + 0.3 * (0.5 * s).sin() * b[4]);
        let v = amp * ((1.1 * s).cos() * b[0] + 0.4 * (0.9 * s).sin() * b[2] + 0.3 * (1.7 * s).cos() * b[3]);
        f.u[i] = u as f32;
        f.v[i] = v as f32;
    }
    f
}

/// Synthetic frame `k`: a smooth three-channel pattern read through `known_warp(k)` (evaluated
/// analytically, so the warp is exact), with a gentle per-frame illumination gradient; zero
/// outside `mask`.
pub(crate) fn synthetic_frame(mask: &TexelMask, k: u64, amp: f64) -> TextureImage {
    let size = mask.width();
    let warp = known_warp(size, amp, k + 1);
    let n = size * size;
    let mut data = vec![0.0f32; 3 * n];
    let tau = std::f64::consts::TAU;
    for i in 0..n {
        if !mask.is_active(i) {
            continue;
        }
        let x = (i % size) as f64 + warp.u[i] as f64;
        let y = (i / size) as f64 + warp.v[i] as f64;
        let gain = 1.0 + 0.06 * (k as f64 * 0.9).sin() * (x / size as f64 - 0.5) + 0.03 * (k as f64 * 0.4).cos();
        for c in 0..3 {
            let ph = c as f64 * 0.8;
            let v = 128.0
                + 55.0 * (tau * x / 12.0 + ph).sin() * (tau * y / 10.0 - 0.5 * ph).cos()
                + 30.0 * (tau * (x + 2.0 * y) / 23.0 + ph).sin();
            data[c * n + i] = (gain * v) as f32;
        }
    }
    TextureImage::from_planes(size, size, 3, data).unwrap()
}

/// A `size x size` crop of the real head texture (Map-COL.jpg) starting at (`x0`, `y0`),
/// averaged over `factor x factor` blocks; `None` when the data is absent and skipping was asked.
pub(crate) fn head_crop(x0: usize, y0: usize, size: usize, factor: usize) -> Option<TextureImage> {
    let data = surfcap_testkit::shared_data()?;
    let img = TextureImage::read(&data.join("leeperrysmith_head/Map-COL.jpg")).unwrap();
    let n = size * size;
    let mut out = vec![0.0f32; 3 * n];
    for c in 0..3 {
        for y in 0..size {
            for x in 0..size {
                let mut s = 0.0;
                for dy in 0..factor {
                    for dx in 0..factor {
                        s += img.get(c, x0 + x * factor + dx, y0 + y * factor + dy);
                    }
                }
                out[c * n + y * size + x] = s / (factor * factor) as f32;
            }
        }
    }
    Some(TextureImage::from_planes(size, size, 3, out).unwrap())
}

/// Mean squared difference over the texels where `keep` is true, all channels
/// ([`crate::image_similarity::mse`] over that mask).
pub(crate) fn mse(a: &TextureImage, b: &TextureImage, keep: impl Fn(usize) -> bool) -> f64 {
    let mask: Vec<bool> = (0..a.texels()).map(keep).collect();
    crate::image_similarity::mse(a, b, &mask).expect("test maps of one shape and a non-empty mask")
}
