//! Texture alignment with iterative reference selection by medoid shift (thesis 4.4.1,
//! Algorithm 4, Boukhayma 2017).
//!
//! Initial reference: the frame whose texture is closest (sum of squared differences over the
//! active texels) to the mean texture, the cheapest stand-in for the medoid before any
//! alignment (the thesis only says "initializations"). Each iteration then aligns every frame
//! to the reference `I_ref` (forward flow `w_k = flow(I_ref, I_k)`, so `I_ref ≈ I_k(x + w_k)`,
//! and `A_k = I_k(x + w_k)` by the chosen warping; the reference itself is kept as it is, its
//! flow zero), measures `e_i = Σ_k ||A_k - A_ref||²` and picks the new reference as the medoid
//! `argmin_k Σ_l ||A_k - A_l||²` of the aligned textures, computed from the F x F Gram matrix of
//! `A_k - A_ref` (f64, one fixed-order sum per block of texels, blocks added in order: the same
//! bits whatever the thread count). It stops when the error no longer decreases (the previous,
//! best, alignment is kept), when the medoid is the current reference (the next iteration
//! would repeat this one), or after `max_iterations` alignments.

use rayon::prelude::*;
use surfcap_mesh::Progress;

use crate::error::{Error, Result};
use crate::flow_field::FlowField;
use crate::poisson_texture_warp::TextureWarper;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

/// A flow estimator: `flow(reference, target) = w` with `reference(x) ≈ target(x + w(x))`.
pub type FlowEstimator<'a> = dyn Fn(&TextureImage, &TextureImage) -> Result<FlowField> + Sync + 'a;

/// The textures aligned to the chosen reference.
#[derive(Debug, Clone)]
pub struct Alignment {
    /// The reference frame `k0` (`A_ref = I_k0`).
    pub reference: usize,
    /// `A_k = I_k(x + w_k)`, one per frame.
    pub aligned: Vec<TextureImage>,
    /// Forward flows `w_k` (`I_ref ≈ I_k(x + w_k)`), zero for the reference.
    pub forward: Vec<FlowField>,
    /// Total alignment error `e_i` of every iteration run (the last one may be the one that
    /// did not decrease and was discarded).
    pub errors: Vec<f64>,
    /// The reference each iteration aligned to.
    pub references: Vec<usize>,
}

/// Texels per block of the Gram accumulation (a fixed size, so the sums do not depend on the
/// thread count).
pub(crate) const BLOCK: usize = 8192;

/// Gram matrix `G_kl = Σ_i (x_k,i - o_i)(x_l,i - o_i)` of vectors of equal length, in f64,
/// where `o` is an optional offset (`None`: zero); row-major F x F.
pub(crate) fn gram_matrix(vectors: &[&[f32]], offset: Option<&[f32]>) -> Vec<f64> {
    let f = vectors.len();
    let n = vectors.first().map_or(0, |v| v.len());
    let partials: Vec<Vec<f64>> = (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
            let mut m = faer::Mat::<f64>::zeros(hi - lo, f);
            for (k, v) in vectors.iter().enumerate() {
                for i in lo..hi {
                    m[(i - lo, k)] = v[i] as f64 - offset.map_or(0.0, |o| o[i] as f64);
                }
            }
            let mut g = faer::Mat::<f64>::zeros(f, f);
            faer::linalg::matmul::matmul(
                g.as_mut(),
                faer::Accum::Replace,
                m.transpose(),
                m.as_ref(),
                1.0,
                faer::Par::Seq,
            );
            (0..f * f).map(|i| g[(i / f, i % f)]).collect()
        })
        .collect();
    let mut g = vec![0.0f64; f * f];
    for p in &partials {
        for (a, b) in g.iter_mut().zip(p) {
            *a += b;
        }
    }
    // Exactly symmetric.
    for k in 0..f {
        for l in 0..k {
            let s = 0.5 * (g[k * f + l] + g[l * f + k]);
            g[k * f + l] = s;
            g[l * f + k] = s;
        }
    }
    g
}

/// The active texels of every channel, channel after channel.
pub(crate) fn active_vector(image: &TextureImage, mask: &TexelMask) -> Vec<f32> {
    (0..image.channels()).flat_map(|c| mask.gather(image.plane(c))).collect()
}

/// The frame closest to the mean of the textures over the active texels (lowest index on ties).
fn closest_to_mean(vectors: &[Vec<f32>]) -> usize {
    let f = vectors.len();
    let n = vectors[0].len();
    let mut mean = vec![0.0f64; n];
    for v in vectors {
        for (m, &x) in mean.iter_mut().zip(v) {
            *m += x as f64;
        }
    }
    mean.iter_mut().for_each(|m| *m /= f as f64);
    let dist: Vec<f64> =
        vectors.par_iter().map(|v| v.iter().zip(&mean).map(|(&x, &m)| (x as f64 - m).powi(2)).sum()).collect();
    argmin(&dist)
}

fn argmin(values: &[f64]) -> usize {
    let mut best = 0;
    for (k, &v) in values.iter().enumerate() {
        if v < values[best] {
            best = k;
        }
    }
    best
}

/// The map whose active texels are `v` (channel after channel), zero elsewhere.
pub(crate) fn image_of(v: &[f32], mask: &TexelMask, channels: usize) -> TextureImage {
    let n = mask.len();
    let mut out = TextureImage::zeros(mask.width(), mask.height(), channels);
    for c in 0..channels {
        mask.scatter(&v[c * n..(c + 1) * n], out.plane_mut(c));
    }
    out
}

/// Checks that every texture has the first one's shape and the mask's size, naming the frame.
pub(crate) fn check_textures(textures: &[TextureImage], mask: &TexelMask, names: Option<&[String]>) -> Result<()> {
    let Some(first) = textures.first() else {
        return Err(Error::Invalid("no texture to align: expected at least one frame".into()));
    };
    let name = |k: usize| names.and_then(|n| n.get(k)).map_or(format!("frame {k}"), |n| format!("frame {n}"));
    mask.check_size(first.width(), first.height(), &name(0))?;
    for (k, t) in textures.iter().enumerate().skip(1) {
        first.check_same_shape(t, &name(k))?;
    }
    Ok(())
}

/// Aligns `textures` (all on `mask`) by Algorithm 4: see the module documentation. The
/// aligned textures' inactive texels are zero (only active texels are aligned).
pub fn align_by_medoid_shift(
    textures: &[TextureImage],
    mask: &TexelMask,
    warper: &TextureWarper,
    flow: &FlowEstimator<'_>,
    max_iterations: usize,
    progress: &dyn Progress,
) -> Result<Alignment> {
    medoid_shift(textures, mask, warper, flow, max_iterations, progress, true)
}

/// [`align_by_medoid_shift`], with the aligned textures kept only when `keep_aligned` (else
/// `Alignment::aligned` is empty: a caller that re-warps with another warping needs only the
/// flows). An iteration holds its frames' active texels and flows, never whole aligned maps,
/// and the best iteration so far only what is kept: at 100 maps of 1024 x 1024 that is about
/// 2 GB against 5 GB with the images of both.
pub(crate) fn medoid_shift(
    textures: &[TextureImage],
    mask: &TexelMask,
    warper: &TextureWarper,
    flow: &FlowEstimator<'_>,
    max_iterations: usize,
    progress: &dyn Progress,
    keep_aligned: bool,
) -> Result<Alignment> {
    check_textures(textures, mask, None)?;
    if max_iterations == 0 {
        return Err(Error::Invalid("the medoid shift needs at least one iteration: got 0".into()));
    }
    let (w, h) = (mask.width(), mask.height());
    let f = textures.len();
    let originals: Vec<Vec<f32>> = textures.par_iter().map(|t| active_vector(t, mask)).collect();
    let mut reference = closest_to_mean(&originals);
    drop(originals);
    let mut best: Option<Alignment> = None;
    let mut errors = Vec::new();
    let mut references = Vec::new();
    for iteration in 0..max_iterations {
        progress.start(&format!("aligning to frame {reference} (medoid shift iteration {})", iteration + 1), f as u64);
        let aligned: Vec<(Vec<f32>, FlowField)> = textures
            .par_iter()
            .enumerate()
            .map(|(k, t)| {
                let out = if k == reference {
                    (active_vector(t, mask), FlowField::zeros(w, h))
                } else {
                    let fw = flow(&textures[reference], t)
                        .and_then(|fw| fw.check_size(w, h, "the flow").map(|()| fw))
                        .map_err(|e| Error::Invalid(format!("aligning frame {k} to frame {reference}: {e}")))?;
                    (active_vector(&warper.warp(t, &fw)?, mask), fw)
                };
                progress.advance(1);
                Ok(out)
            })
            .collect::<Result<_>>()?;
        progress.finish();
        let refs: Vec<&[f32]> = aligned.iter().map(|(v, _)| v.as_slice()).collect();
        let g = gram_matrix(&refs, Some(&aligned[reference].0));
        drop(refs);
        let error: f64 = (0..f).map(|k| g[k * f + k]).sum();
        errors.push(error);
        references.push(reference);
        if best.as_ref().is_some_and(|b| error >= b.errors[b.errors.len() - 1]) {
            break;
        }
        // Σ_l ||A_k - A_l||² = F G_kk + Σ_l G_ll - 2 Σ_l G_kl.
        let trace: f64 = (0..f).map(|l| g[l * f + l]).sum();
        let spread: Vec<f64> =
            (0..f).map(|k| f as f64 * g[k * f + k] + trace - 2.0 * g[k * f..(k + 1) * f].iter().sum::<f64>()).collect();
        let medoid = argmin(&spread);
        let (vectors, forward): (Vec<_>, Vec<_>) = aligned.into_iter().unzip();
        let channels = textures[0].channels();
        let aligned =
            if keep_aligned { vectors.iter().map(|v| image_of(v, mask, channels)).collect() } else { Vec::new() };
        drop(vectors);
        best = Some(Alignment { reference, aligned, forward, errors: errors.clone(), references: references.clone() });
        if medoid == reference {
            break;
        }
        reference = medoid;
    }
    let mut best = best.expect("at least one iteration ran");
    best.errors = errors;
    best.references = references;
    Ok(best)
}
