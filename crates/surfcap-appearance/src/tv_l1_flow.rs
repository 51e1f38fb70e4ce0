//! Dense optical flow between texture maps by TV-L1 (thesis 4.4.1, "Correspondence with optical
//! flow": the warps are estimated with Sanchez Perez, Meinhardt-Llopis and Facciolo 2013,
//! "TV-L1 Optical Flow Estimation", IPOL 3, pp. 137-150), restricted to the active texels.
//!
//! The flow w minimises `sum_x |grad w1| + |grad w2| + lambda |I1(x + w) - I0(x)|` (IPOL eq. 2),
//! relaxed with an auxiliary field v (eq. 8, weight theta) and solved per warp by alternating
//! (IPOL Algorithm 1, the reference `tvl1flow_lib.c`):
//! - the thresholding step (eq. 11-12): with `rho(u) = I1(x + u0) + grad I1 . (u - u0) - I0`,
//!   `v = u + lambda theta grad I1` if `rho < -lambda theta |grad I1|^2`,
//!   `- lambda theta grad I1` if `rho > lambda theta |grad I1|^2`, `- rho grad I1 / |grad I1|^2`
//!   otherwise;
//! - `u = v + theta div p` (eq. 13);
//! - Chambolle's dual projection (eq. 14): `p = (p + tau / theta grad u) / (1 + tau / theta |grad u|)`,
//!   forward differences, divergence its adjoint;
//!
//! until the mean squared change of u falls below `epsilon^2` or after `max_iterations`; the
//! target and its centred gradient are re-warped (bicubic) `warps` times per scale. Scales
//! go coarse to fine (zoom 0.5, Gaussian anti-aliasing before each downsampling,
//! [`crate::image_pyramid`]); the images are first normalised jointly to 0-255 and smoothed
//! with sigma 0.8, as in the reference. Defaults are IPOL's: tau 0.25, lambda 0.15,
//! theta 0.3, epsilon 0.01, 5 warps, at most 300 iterations, as many scales as keep the
//! coarsest image's diagonal above 16 texels. No median filtering (IPOL has none).
//!
//! Active texels (extension for texture atlases): the data term is on only where the reference
//! texel is active (`lambda` times the texel's active fraction at coarser scales), so the TV
//! term fills inactive texels smoothly from their active neighbours; before smoothing, the
//! inactive texels of both images are replaced by a push-pull extension of the active values
//! ([`crate::inactive_fill`]), so whatever the atlas's background holds never reaches the
//! flow. As in the reference, where `x + w` leaves the image the data term is off.
//!
//! Convention (that of [`crate::flow_field`]): `reference(x) ~ target(x + w(x))`, i.e.
//! `warp_direct(target, w) ~ reference`.
//!
//! Every step updates each texel from the previous step's values only and every sum is taken
//! per row then over rows in order, so the result does not depend on the thread count.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::flow_field::FlowField;
use crate::image_pyramid::{cubic_taps, gaussian_blur, rows_per_task, zoom_in, zoom_out};
use crate::inactive_fill::push_pull_fill;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;
use crate::texture_preprocessing::{PreprocessOptions, preprocess};

/// Smoothing of the finest images before the pyramid (IPOL `PRESMOOTHING_SIGMA`).
const PRESMOOTHING_SIGMA: f32 = 0.8;
/// The coarsest scale's diagonal, in texels (IPOL caps the scales at `1 + log(diag / 16) / log(1 / z)`).
const COARSEST_DIAGONAL: f32 = 16.0;

/// TV-L1 parameters (IPOL's names and defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowOptions {
    /// Weight of the data term (0.15).
    pub lambda: f32,
    /// Coupling between u and v (0.3).
    pub theta: f32,
    /// Time step of the dual projection (0.25; at most 0.25 for convergence).
    pub tau: f32,
    /// Stopping threshold on the root mean squared change of the flow per iteration (0.01).
    pub epsilon: f32,
    /// Zoom factor between scales, in (0, 1) (0.5).
    pub zoom: f32,
    /// At most this many scales (100: the cap above decides).
    pub scales: usize,
    /// Warps of the target per scale (5).
    pub warps: usize,
    /// Iterations per warp at most (300).
    pub max_iterations: usize,
    /// 0: solve down to full resolution; k > 0: stop at scale k (size zoom^k) and upsample the
    /// flow bicubically (a speed option; capped at the coarsest scale).
    pub finest_scale: usize,
}

impl Default for FlowOptions {
    fn default() -> Self {
        FlowOptions {
            lambda: 0.15,
            theta: 0.3,
            tau: 0.25,
            epsilon: 0.01,
            zoom: 0.5,
            scales: 100,
            warps: 5,
            max_iterations: 300,
            finest_scale: 0,
        }
    }
}

impl FlowOptions {
    fn check(&self) -> Result<()> {
        let positive = [("lambda", self.lambda), ("theta", self.theta), ("tau", self.tau)];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::Invalid(format!("flow {name} {v}: expected a positive number")));
            }
        }
        if self.tau > 0.25 {
            return Err(Error::Invalid(format!("flow tau {}: expected at most 0.25 (Chambolle's bound)", self.tau)));
        }
        if !(self.epsilon.is_finite() && self.epsilon >= 0.0) {
            return Err(Error::Invalid(format!("flow epsilon {}: expected a number >= 0", self.epsilon)));
        }
        if !(self.zoom > 0.0 && self.zoom < 1.0) {
            return Err(Error::Invalid(format!("flow zoom {}: expected a factor in (0, 1)", self.zoom)));
        }
        for (name, v) in [("scales", self.scales), ("warps", self.warps), ("max_iterations", self.max_iterations)] {
            if v == 0 {
                return Err(Error::Invalid(format!("flow {name} 0: expected at least 1")));
            }
        }
        Ok(())
    }
}

/// TV-L1 flow `w` with `reference(x) ~ target(x + w(x))` between two row-major grey planes of
/// `width x height`. With a mask, only active texels carry the data term (see the module doc);
/// the flow is defined everywhere.
pub fn tv_l1_flow(
    reference: &[f32],
    target: &[f32],
    width: usize,
    height: usize,
    mask: Option<&TexelMask>,
    opts: &FlowOptions,
) -> Result<FlowField> {
    opts.check()?;
    if width == 0 || height == 0 {
        return Err(Error::Invalid(format!("optical flow needs a positive image size, got {width}x{height}")));
    }
    for (name, plane) in [("reference", reference), ("target", target)] {
        if plane.len() != width * height {
            return Err(Error::Mismatch(format!(
                "the {name} image has {} values: expected {width}x{height} = {}",
                plane.len(),
                width * height
            )));
        }
        if let Some(i) = plane.iter().position(|v| !v.is_finite()) {
            return Err(Error::Invalid(format!(
                "the {name} image is not finite at texel ({}, {})",
                i % width,
                i / width
            )));
        }
    }
    let weight: Vec<f32> = match mask {
        Some(m) => {
            m.check_size(width, height, "the flow's images")?;
            (0..width * height).map(|i| if m.is_active(i) { 1.0 } else { 0.0 }).collect()
        }
        None => vec![1.0; width * height],
    };
    let (mut i0, mut i1) = match mask {
        Some(_) => (push_pull_fill(reference, &weight, width, height), push_pull_fill(target, &weight, width, height)),
        None => (reference.to_vec(), target.to_vec()),
    };
    normalise_jointly(&mut i0, &mut i1);
    let i0 = gaussian_blur(&i0, width, height, PRESMOOTHING_SIGMA);
    let i1 = gaussian_blur(&i1, width, height, PRESMOOTHING_SIGMA);

    // The pyramid (IPOL caps the number of scales so the coarsest diagonal stays >= 16).
    let diagonal = ((width * width + height * height) as f32).sqrt();
    let cap = 1.0 + (diagonal / COARSEST_DIAGONAL).ln() / (1.0 / opts.zoom).ln();
    let scales = opts.scales.min(cap.max(1.0) as usize).max(1);
    let finest = opts.finest_scale.min(scales - 1);
    let mut levels = vec![Level { w: width, h: height, i0, i1, weight }];
    for _ in 1..scales {
        let l = levels.last().expect("the finest level");
        let (i0, w, h) = zoom_out(&l.i0, l.w, l.h, opts.zoom);
        let (i1, _, _) = zoom_out(&l.i1, l.w, l.h, opts.zoom);
        let (weight, _, _) = zoom_out(&l.weight, l.w, l.h, opts.zoom);
        levels.push(Level { w, h, i0, i1, weight });
    }

    let coarsest = &levels[scales - 1];
    let mut u = vec![[0.0f32; 2]; coarsest.w * coarsest.h];
    for s in (finest..scales).rev() {
        let l = &levels[s];
        solve_scale(l, &mut u, opts);
        if s > finest {
            let next = &levels[s - 1];
            u = zoom_flow(&u, l.w, l.h, next.w, next.h, 1.0 / opts.zoom);
        }
    }
    if finest > 0 {
        let l = &levels[finest];
        u = zoom_flow(&u, l.w, l.h, width, height, (1.0 / opts.zoom).powi(finest as i32));
    }
    Ok(FlowField { width, height, u: u.iter().map(|f| f[0]).collect(), v: u.iter().map(|f| f[1]).collect() })
}

/// TV-L1 flow between two texture maps over the active texels of `mask`: both are
/// pre-processed ([`preprocess`], thesis 4.4.1), then the flow runs on their grey (channel
/// mean) images. `reference(x) ~ target(x + w(x))`.
pub fn texture_flow(
    reference: &TextureImage,
    target: &TextureImage,
    mask: &TexelMask,
    pre: &PreprocessOptions,
    opts: &FlowOptions,
) -> Result<FlowField> {
    reference.check_same_shape(target, "the target texture")?;
    mask.check_size(reference.width(), reference.height(), "the reference texture")?;
    let a = preprocess(reference, mask, pre)?;
    let b = preprocess(target, mask, pre)?;
    tv_l1_flow(&a.grey(), &b.grey(), reference.width(), reference.height(), Some(mask), opts)
}

/// One scale of the pyramid.
struct Level {
    w: usize,
    h: usize,
    i0: Vec<f32>,
    i1: Vec<f32>,
    /// Active fraction (data-term weight) per texel.
    weight: Vec<f32>,
}

/// Scales both images jointly to 0-255 (IPOL `image_normalization`).
fn normalise_jointly(a: &mut [f32], b: &mut [f32]) {
    let lo = a.iter().chain(b.iter()).copied().fold(f32::INFINITY, f32::min);
    let hi = a.iter().chain(b.iter()).copied().fold(f32::NEG_INFINITY, f32::max);
    if hi > lo {
        let k = 255.0 / (hi - lo);
        a.iter_mut().chain(b.iter_mut()).for_each(|v| *v = (*v - lo) * k);
    }
}

/// Bicubic zoom of a flow to `out_w x out_h`, its vectors multiplied by `scale`.
fn zoom_flow(u: &[[f32; 2]], w: usize, h: usize, out_w: usize, out_h: usize, scale: f32) -> Vec<[f32; 2]> {
    let u1: Vec<f32> = u.iter().map(|f| f[0]).collect();
    let u2: Vec<f32> = u.iter().map(|f| f[1]).collect();
    let z1 = zoom_in(&u1, w, h, out_w, out_h);
    let z2 = zoom_in(&u2, w, h, out_w, out_h);
    z1.into_iter().zip(z2).map(|(a, b)| [a * scale, b * scale]).collect()
}

/// Centred differences (IPOL `centered_gradient`: half one-sided differences at the border).
fn centred_gradient(plane: &[f32], w: usize, h: usize) -> (Vec<f32>, Vec<f32>) {
    let mut gx = vec![0.0f32; w * h];
    let mut gy = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (l, r) = (if x > 0 { i - 1 } else { i }, if x + 1 < w { i + 1 } else { i });
            let (u, d) = (if y > 0 { i - w } else { i }, if y + 1 < h { i + w } else { i });
            gx[i] = 0.5 * (plane[r] - plane[l]);
            gy[i] = 0.5 * (plane[d] - plane[u]);
        }
    }
    (gx, gy)
}

/// Per-texel constants of one warp: the warped target's gradient, `1 / |grad|^2`, the constant
/// part of rho and the thresholding bound `lambda theta weight`.
#[derive(Clone, Copy, Default)]
struct WarpData {
    ix: f32,
    iy: f32,
    inv_grad: f32,
    rho_c: f32,
    lt: f32,
}

/// Dual TV-L1 at one scale (IPOL `Dual_TVL1_optic_flow`), refining `u` in place.
fn solve_scale(l: &Level, u: &mut [[f32; 2]], opts: &FlowOptions) {
    let (w, h) = (l.w, l.h);
    let n = w * h;
    let rows = rows_per_task(w);
    let (gx, gy) = centred_gradient(&l.i1, w, h);
    let l_t = opts.lambda * opts.theta;
    let theta = opts.theta;
    let taut = opts.tau / opts.theta;
    let mut p = vec![[0.0f32; 4]; n];
    let mut data = vec![WarpData::default(); n];
    let mut row_error = vec![0.0f32; h];
    let stop = (opts.epsilon as f64) * (opts.epsilon as f64);
    for _ in 0..opts.warps {
        // Warp the target and its gradient by the current flow (bicubic).
        data.par_chunks_mut(rows * w).enumerate().for_each(|(c, chunk)| {
            for (r, drow) in chunk.chunks_mut(w).enumerate() {
                let y = c * rows + r;
                for (x, d) in drow.iter_mut().enumerate() {
                    let i = y * w + x;
                    let [u1, u2] = u[i];
                    let (xs, ys) = (x as f32 + u1, y as f32 + u2);
                    if xs < -0.5 || ys < -0.5 || xs > w as f32 - 0.5 || ys > h as f32 - 0.5 {
                        *d = WarpData::default();
                        continue;
                    }
                    let (xi, xw) = cubic_taps(xs, w);
                    let (yi, yw) = cubic_taps(ys, h);
                    let (mut iw, mut ix, mut iy) = (0.0f32, 0.0f32, 0.0f32);
                    for k in 0..4 {
                        let o = yi[k] * w;
                        for j in 0..4 {
                            let wt = yw[k] * xw[j];
                            let t = o + xi[j];
                            iw += wt * l.i1[t];
                            ix += wt * gx[t];
                            iy += wt * gy[t];
                        }
                    }
                    let grad = ix * ix + iy * iy;
                    *d = WarpData {
                        ix,
                        iy,
                        inv_grad: 1.0 / grad.max(1e-10),
                        rho_c: iw - ix * u1 - iy * u2 - l.i0[i],
                        lt: l_t * l.weight[i],
                    };
                }
            }
        });
        let mut error = f64::INFINITY;
        let mut iterations = 0;
        while error > stop && iterations < opts.max_iterations {
            iterations += 1;
            // Thresholding (v) and u = v + theta div p, pointwise; p is read only.
            let p_ro = &p;
            let data_ro = &data;
            u.par_chunks_mut(rows * w).zip(row_error.par_chunks_mut(rows)).enumerate().for_each(
                |(c, (chunk, errs))| {
                    for (r, (urow, e)) in chunk.chunks_mut(w).zip(errs.iter_mut()).enumerate() {
                        let y = c * rows + r;
                        *e = update_u_row(
                            urow,
                            &data_ro[y * w..(y + 1) * w],
                            &p_ro[y * w..(y + 1) * w],
                            if y > 0 { Some(&p_ro[(y - 1) * w..y * w]) } else { None },
                            theta,
                        );
                    }
                },
            );
            error = row_error.iter().map(|&e| e as f64).sum::<f64>() / n as f64;
            // Dual projection, pointwise; u is read only.
            let u_ro: &[[f32; 2]] = u;
            p.par_chunks_mut(rows * w).enumerate().for_each(|(c, chunk)| {
                for (r, prow) in chunk.chunks_mut(w).enumerate() {
                    let y = c * rows + r;
                    let below = if y + 1 < h { Some(&u_ro[(y + 1) * w..(y + 2) * w]) } else { None };
                    update_p_row(prow, &u_ro[y * w..(y + 1) * w], below, taut);
                }
            });
        }
    }
}

/// One row of the thresholding step and of `u = v + theta div p`; returns the row's sum of
/// squared changes. `above` is the previous row of p (None on the first row, where the
/// divergence's vertical term reads zero).
#[inline]
fn update_u_row(
    urow: &mut [[f32; 2]],
    drow: &[WarpData],
    prow: &[[f32; 4]],
    above: Option<&[[f32; 4]]>,
    theta: f32,
) -> f32 {
    // Branch-free inner loop: on the first row `above` is this row, multiplied by zero.
    let (above, has_above) = match above {
        Some(a) => (a, 1.0f32),
        None => (prow, 0.0f32),
    };
    let texel = |u: [f32; 2], d: WarpData, pc: [f32; 4], pl: [f32; 4], pu: [f32; 4]| -> ([f32; 2], f32) {
        let rho = d.rho_c + d.ix * u[0] + d.iy * u[1];
        let fi = (-rho * d.inv_grad).max(-d.lt).min(d.lt);
        let div1 = pc[0] - pl[0] + pc[1] - has_above * pu[1];
        let div2 = pc[2] - pl[2] + pc[3] - has_above * pu[3];
        let n1 = u[0] + fi * d.ix + theta * div1;
        let n2 = u[1] + fi * d.iy + theta * div2;
        ([n1, n2], (n1 - u[0]) * (n1 - u[0]) + (n2 - u[1]) * (n2 - u[1]))
    };
    let w = urow.len();
    let (first, e0) = texel(urow[0], drow[0], prow[0], [0.0; 4], above[0]);
    urow[0] = first;
    let mut error = e0;
    for x in 1..w {
        let (n, e) = texel(urow[x], drow[x], prow[x], prow[x - 1], above[x]);
        urow[x] = n;
        error += e;
    }
    error
}

/// One row of Chambolle's projection with forward differences (zero past the last column/row).
#[inline]
fn update_p_row(prow: &mut [[f32; 4]], urow: &[[f32; 2]], below: Option<&[[f32; 2]]>, taut: f32) {
    // On the last row `below` is this row: the vertical differences are then zero.
    let below = below.unwrap_or(urow);
    let texel = |q: [f32; 4], ux1: f32, ux2: f32, uy1: f32, uy2: f32| -> [f32; 4] {
        let ng1 = 1.0 + taut * (ux1 * ux1 + uy1 * uy1).sqrt();
        let ng2 = 1.0 + taut * (ux2 * ux2 + uy2 * uy2).sqrt();
        [(q[0] + taut * ux1) / ng1, (q[1] + taut * uy1) / ng1, (q[2] + taut * ux2) / ng2, (q[3] + taut * uy2) / ng2]
    };
    let w = prow.len();
    for x in 0..w - 1 {
        let (uc, ur, ub) = (urow[x], urow[x + 1], below[x]);
        prow[x] = texel(prow[x], ur[0] - uc[0], ur[1] - uc[1], ub[0] - uc[0], ub[1] - uc[1]);
    }
    let (uc, ub) = (urow[w - 1], below[w - 1]);
    prow[w - 1] = texel(prow[w - 1], 0.0, 0.0, ub[0] - uc[0], ub[1] - uc[1]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth textured function (sum of sines and a Gaussian blob), 0-255.
    fn pattern(x: f32, y: f32) -> f32 {
        let s =
            (0.31 * x).sin() * (0.23 * y).cos() + 0.5 * (0.17 * x + 0.29 * y).sin() + 0.4 * (0.41 * y - 0.07 * x).cos();
        let blob = (-((x - 20.0).powi(2) + (y - 30.0).powi(2)) / 60.0).exp();
        128.0 + 50.0 * s + 60.0 * blob
    }

    fn sampled(w: usize, h: usize, dx: f32, dy: f32) -> Vec<f32> {
        (0..w * h).map(|i| pattern((i % w) as f32 - dx, (i / w) as f32 - dy)).collect()
    }

    fn interior_epe(flow: &FlowField, du: f32, dv: f32, margin: usize) -> f64 {
        let truth =
            FlowField { width: flow.width, height: flow.height, u: vec![du; flow.u.len()], v: vec![dv; flow.v.len()] };
        let (w, h) = (flow.width, flow.height);
        flow.end_point_error(&truth, |i| {
            let (x, y) = (i % w, i / w);
            x >= margin && y >= margin && x + margin < w && y + margin < h
        })
    }

    #[test]
    fn a_constant_shift_is_recovered() {
        let (w, h) = (64, 64);
        // target = pattern shifted by d, so reference(x) = target(x + d).
        let (du, dv) = (1.5, -0.75);
        let reference = sampled(w, h, 0.0, 0.0);
        let target = sampled(w, h, du, dv);
        let flow = tv_l1_flow(&reference, &target, w, h, None, &FlowOptions::default()).unwrap();
        let epe = interior_epe(&flow, du, dv, 6);
        assert!(epe < 0.05, "end-point error {epe}");
    }

    #[test]
    fn inactive_texels_do_not_pull_the_data_term() {
        let (w, h) = (64, 64);
        // Active: the left half, where target = reference (no motion). In the inactive right
        // half the target is shifted by 3 texels: without the mask the flow follows it.
        let reference = sampled(w, h, 0.0, 0.0);
        let shifted = sampled(w, h, 3.0, 0.0);
        let target: Vec<f32> = (0..w * h).map(|i| if i % w < 32 { reference[i] } else { shifted[i] }).collect();
        let flags: Vec<bool> = (0..w * h).map(|i| i % w < 32).collect();
        let mask = TexelMask::from_flags(w, h, &flags).unwrap();
        let opts = FlowOptions::default();
        let masked = tv_l1_flow(&reference, &target, w, h, Some(&mask), &opts).unwrap();
        let free = tv_l1_flow(&reference, &target, w, h, None, &opts).unwrap();
        let on_active = |f: &FlowField| interior_epe_where(f, |x, _| x < 32);
        let on_right = |f: &FlowField| interior_epe_where(f, |x, _| x >= 40);
        assert!(on_active(&masked) < 0.05, "masked flow on active texels {}", on_active(&masked));
        assert!(on_right(&free) > 2.0, "unmasked flow follows the right half: {}", on_right(&free));
        // Whatever the inactive texels hold, the flow is the same.
        let mut noisy_ref = reference.clone();
        let mut noisy_target = target.clone();
        for i in 0..w * h {
            if !flags[i] {
                noisy_ref[i] = ((i * 7919) % 255) as f32;
                noisy_target[i] = 0.0;
            }
        }
        let again = tv_l1_flow(&noisy_ref, &noisy_target, w, h, Some(&mask), &opts).unwrap();
        assert_eq!(again, masked);
    }

    fn interior_epe_where(flow: &FlowField, keep: impl Fn(usize, usize) -> bool) -> f64 {
        let w = flow.width;
        flow.end_point_error(&FlowField::zeros(w, flow.height), |i| keep(i % w, i / w))
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        let (w, h) = (80, 48);
        let reference = sampled(w, h, 0.0, 0.0);
        let target = sampled(w, h, -1.0, 2.0);
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| tv_l1_flow(&reference, &target, w, h, None, &FlowOptions::default()).unwrap())
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn the_half_resolution_option_still_recovers_a_shift() {
        let (w, h) = (64, 64);
        let reference = sampled(w, h, 0.0, 0.0);
        let target = sampled(w, h, 2.0, 1.0);
        let opts = FlowOptions { finest_scale: 1, ..FlowOptions::default() };
        let flow = tv_l1_flow(&reference, &target, w, h, None, &opts).unwrap();
        let epe = interior_epe(&flow, 2.0, 1.0, 6);
        assert!(epe < 0.2, "end-point error {epe}");
    }

    #[test]
    fn sizes_and_options_are_checked_by_name() {
        let a = vec![0.0; 12];
        let e = tv_l1_flow(&a, &a[..10], 4, 3, None, &FlowOptions::default()).unwrap_err().to_string();
        assert!(e.contains("the target image has 10 values: expected 4x3 = 12"), "{e}");
        let mask = TexelMask::full(3, 4);
        let e = tv_l1_flow(&a, &a, 4, 3, Some(&mask), &FlowOptions::default()).unwrap_err().to_string();
        assert!(e.contains("the flow's images is 4x3: expected 3x4"), "{e}");
        let bad = FlowOptions { tau: 0.5, ..FlowOptions::default() };
        let e = tv_l1_flow(&a, &a, 4, 3, None, &bad).unwrap_err().to_string();
        assert!(e.contains("tau 0.5"), "{e}");
        let t1 = TextureImage::zeros(4, 3, 3);
        let t2 = TextureImage::zeros(4, 4, 3);
        let e = texture_flow(&t1, &t2, &TexelMask::full(4, 3), &PreprocessOptions::none(), &FlowOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("the target texture is 4x4x3: expected 4x3x3"), "{e}");
    }
}
