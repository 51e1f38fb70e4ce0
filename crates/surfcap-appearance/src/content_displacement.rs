//! Where the content of each texel of a re-projected texture truly came from: the ground-truth
//! texture-space displacement of a capture made through calibration and tracking error
//! ([`crate::capture_benchmark`]).
//!
//! A texel x is re-projected through the mesh as tracked and the cameras as calibrated: its
//! point p on the tracked mesh projects to pixel q_j of camera j ([`blend_samples`]: the same
//! cameras, pixels and cosine weights the blend uses). Camera j's pixel q_j, however, shows the
//! true mesh seen by the actual camera: the bilinear sample at q_j mixes four pixel centres,
//! each the ray hit of the actual camera on the true mesh, whose atlas coordinates s are known
//! from the hit triangle's UVs. The content camera j gives texel x is therefore the albedo at
//! `s_j = Σ bilinear weights × s(pixel centre)` (up to shading), displaced by `d_j = s_j - x`.
//!
//! The blend mixes the cameras, so texel x shows the cosine-weighted mixture of the albedo at
//! every `x + d_j`. Its mean `d̄ = Σ w_j d_j / Σ w_j` is the displacement a flow can follow; the
//! weighted RMS spread `sqrt(Σ w_j |d_j - d̄|² / Σ w_j)` is the ghosting no single flow can.
//! A texel's displacement is undefined when one of its samples mixes pixel centres of two UV
//! charts (a seam: the mean of their atlas coordinates means nothing), touches the background,
//! mixes pixel centres more than the blend's depth tolerance apart in depth (a depth step, or a
//! surface seen so obliquely that one pixel spans many texels: a smear, not a displacement), or
//! shows a surface more than [`OTHER_SURFACE`] tolerances from the texel's point (an occluder
//! the depth test let through: content from another surface). On the head scan seen by the
//! default ring of 12 cameras about half of the active texels keep a defined displacement.
//!
//! Between two frames a and b whose content comes from `x + d_a(x)` and `x + d_b(x)`, the true
//! flow `w` with `a(x) ≈ b(x + w(x))` solves `x + d_a(x) = x + w + d_b(x + w)`
//! ([`flow_between`]: the fixed point `w = d_a(x) - d_b(x + w)`, `d_b` sampled bilinearly).

use rayon::prelude::*;
use surfcap_mesh::{Topology, UvAtlas};

use crate::atlas_normals::AtlasGeometry;
use crate::atlas_raster::AtlasRaster;
use crate::capture_benchmark::{V3, blend_samples};
use crate::error::{Error, Result};
use crate::flow_field::{FlowField, sample_bilinear};
use crate::inactive_fill::push_pull_fill;
use crate::mesh_rasteriser::{Camera, Fragments, rasterise};
use crate::texel_mask::TexelMask;

/// The true displacement of every texel's content (texels, x right, y down): the texel shows
/// the albedo at `x + mean(x)`, mixed over cameras whose own displacements spread by `spread`.
#[derive(Debug, Clone, PartialEq)]
pub struct ContentDisplacement {
    pub mean: FlowField,
    /// Cosine-weighted RMS distance of the cameras' displacements from the mean (texels).
    pub spread: Vec<f32>,
    /// Active texels seen by a camera whose every sample lies inside one chart of the true mesh.
    pub defined: Vec<bool>,
}

impl ContentDisplacement {
    /// Mean over the defined texels of |mean| and of the spread (texels), and the number of
    /// defined texels.
    pub fn summary(&self) -> (f64, f64, usize) {
        self.summary_where(|_| true)
    }

    /// Medians over the defined texels of |mean| and of the spread (texels; 0 when none is).
    pub fn medians(&self) -> (f64, f64) {
        let mut size: Vec<f32> = Vec::new();
        let mut spread: Vec<f32> = Vec::new();
        for i in 0..self.defined.len() {
            if self.defined[i] {
                size.push(self.mean.u[i].hypot(self.mean.v[i]));
                spread.push(self.spread[i]);
            }
        }
        let median = |v: &mut Vec<f32>| {
            v.sort_by(f32::total_cmp);
            v.get(v.len() / 2).map_or(0.0, |&x| x as f64)
        };
        (median(&mut size), median(&mut spread))
    }

    /// [`Self::summary`] over the defined texels where `keep` is true.
    pub fn summary_where(&self, keep: impl Fn(usize) -> bool) -> (f64, f64, usize) {
        let (mut size, mut spread, mut n) = (0.0f64, 0.0f64, 0usize);
        for i in 0..self.defined.len() {
            if self.defined[i] && keep(i) {
                size += (self.mean.u[i] as f64).hypot(self.mean.v[i] as f64);
                spread += self.spread[i] as f64;
                n += 1;
            }
        }
        let d = n.max(1) as f64;
        (size / d, spread / d, n)
    }
}

/// The UV chart of every triangle: triangles sharing a texture-coordinate index are in one
/// chart (union-find, the smaller root kept, so the labels do not depend on the order of work).
pub fn uv_charts(atlas: &UvAtlas) -> Vec<u32> {
    let n = atlas.coords.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    for c in &atlas.corners {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, c[0] as usize), find(&mut parent, c[k] as usize));
            if a != b {
                let (lo, hi) = (a.min(b), a.max(b));
                parent[hi] = lo;
            }
        }
    }
    atlas.corners.iter().map(|c| find(&mut parent, c[0] as usize) as u32).collect()
}

/// The atlas coordinates (texel centres at integers, as [`sample_bilinear`]) and chart of the
/// true surface a pixel centre shows, or `None` on the background.
fn pixel_source(
    frags: &Fragments,
    atlas: &UvAtlas,
    charts: &[u32],
    size: [usize; 2],
    i: usize,
) -> Option<([f64; 2], u32)> {
    if !frags.covered(i) {
        return None;
    }
    let t = frags.triangle[i] as usize;
    let b = frags.barycentric[i];
    let mut uv = [0.0f64; 2];
    for (corner, &bc) in b.iter().enumerate() {
        let c = atlas.coords[atlas.corners[t][corner] as usize];
        uv[0] += bc * c[0] as f64;
        uv[1] += bc * c[1] as f64;
    }
    Some(([uv[0] * size[0] as f64 - 0.5, (1.0 - uv[1]) * size[1] as f64 - 0.5], charts[t]))
}

/// Camera `frags`' bilinear sample at pixel `q` (x right, y down, centres at +0.5), as the
/// blend takes it: the atlas coordinates it shows, or `None` across a seam, on the background,
/// across a depth step or at a grazing view (pixel centres more than `tolerance` apart in depth:
/// the sample mixes two surfaces, or smears one across many texels), or where the surface it shows lies more than [`OTHER_SURFACE`] tolerances nearer
/// or further than the texel's point (at depth `z`): an occluder the depth test let through,
/// whose content no displacement describes.
fn sample_source(
    frags: &Fragments,
    atlas: &UvAtlas,
    charts: &[u32],
    size: [usize; 2],
    q: [f64; 2],
    z: f64,
    tolerance: f64,
) -> Option<[f64; 2]> {
    let (w, h) = (frags.width, frags.height);
    let x = (q[0] - 0.5).clamp(0.0, (w - 1) as f64);
    let y = (q[1] - 0.5).clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let corners =
        [(x0, y0, (1.0 - fx) * (1.0 - fy)), (x1, y0, fx * (1.0 - fy)), (x0, y1, (1.0 - fx) * fy), (x1, y1, fx * fy)];
    let mut s = [0.0f64; 2];
    let mut chart = None;
    let (mut near, mut far, mut seen) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for (cx, cy, wt) in corners {
        if wt <= 0.0 {
            continue;
        }
        let (src, c) = pixel_source(frags, atlas, charts, size, cy * w + cx)?;
        let d = frags.depth[cy * w + cx];
        (near, far, seen) = (near.min(d), far.max(d), seen + wt * d);
        if chart.is_some_and(|k| k != c) {
            return None;
        }
        chart = Some(c);
        s[0] += wt * src[0];
        s[1] += wt * src[1];
    }
    if far - near > tolerance || (seen - z).abs() > OTHER_SURFACE * tolerance {
        return None;
    }
    chart.map(|_| s)
}

/// How many depth tolerances from the texel's point the surface a sample shows may lie before
/// it counts as another surface (the errors themselves move the seen point along the surface,
/// and on a slanted surface that changes its depth).
pub const OTHER_SURFACE: f64 = 3.0;

/// The mesh and cameras a capture is re-projected through and the ones that took it.
#[derive(Debug, Clone, Copy)]
pub struct CaptureGeometry<'a> {
    pub topology: &'a Topology,
    /// The mesh the texels are re-projected through (as tracked).
    pub tracked: &'a [f32],
    /// The cameras the re-projection uses (as calibrated).
    pub calibrated: &'a [Camera],
    /// The mesh the cameras saw.
    pub truth: &'a [f32],
    /// The cameras as they were (one per calibrated camera).
    pub actual: &'a [Camera],
}

/// The true displacement of the content of every active texel of `raster` (grown by
/// `dilation` rings) re-projected as [`crate::capture_benchmark::reproject`] does.
pub fn content_displacement(
    geometry: &CaptureGeometry<'_>,
    raster: &AtlasRaster,
    dilation: usize,
    depth_tolerance: f64,
) -> Result<ContentDisplacement> {
    let g = geometry;
    if g.calibrated.len() != g.actual.len() || g.calibrated.is_empty() {
        return Err(Error::Mismatch(format!(
            "{} calibrated cameras for {} actual ones: expected the same number, at least one",
            g.calibrated.len(),
            g.actual.len()
        )));
    }
    let atlas = g.topology.uv().ok_or_else(|| Error::Invalid("the mesh has no texture coordinates (vt)".into()))?;
    let charts = uv_charts(atlas);
    let (w, h) = (raster.width, raster.height);
    let mask = TexelMask::from_raster(raster, dilation)?;
    let tracked = AtlasGeometry::new(raster, g.topology, g.tracked, dilation)?;
    let depth: Vec<Fragments> =
        g.calibrated.iter().map(|c| rasterise(g.topology, g.tracked, c)).collect::<Result<_>>()?;
    let seen: Vec<Fragments> = g.actual.iter().map(|c| rasterise(g.topology, g.truth, c)).collect::<Result<_>>()?;
    let per_texel: Vec<Option<([f64; 2], f64)>> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            if !mask.is_active(i) || !tracked.defined[i] {
                return Ok(None);
            }
            let p: V3 = tracked.position[i].map(f64::from);
            let n: V3 = tracked.normal[i].map(f64::from);
            let x = [(i % w) as f64, (i / w) as f64];
            let mut ds: Vec<([f64; 2], f64)> = Vec::new();
            for s in blend_samples(p, n, g.calibrated, &depth, depth_tolerance)? {
                let z = s.depth;
                let Some(src) = sample_source(&seen[s.camera], atlas, &charts, [w, h], s.pixel, z, depth_tolerance)
                else {
                    return Ok(None);
                };
                ds.push(([src[0] - x[0], src[1] - x[1]], s.weight));
            }
            let total: f64 = ds.iter().map(|d| d.1).sum();
            if ds.is_empty() || total <= 0.0 {
                return Ok(None);
            }
            let mean = [
                ds.iter().map(|(d, wt)| wt * d[0]).sum::<f64>() / total,
                ds.iter().map(|(d, wt)| wt * d[1]).sum::<f64>() / total,
            ];
            let var = ds.iter().map(|(d, wt)| wt * ((d[0] - mean[0]).powi(2) + (d[1] - mean[1]).powi(2))).sum::<f64>()
                / total;
            Ok(Some((mean, var.sqrt())))
        })
        .collect::<Result<_>>()?;
    let mut out =
        ContentDisplacement { mean: FlowField::zeros(w, h), spread: vec![0.0; w * h], defined: vec![false; w * h] };
    for (i, t) in per_texel.iter().enumerate() {
        if let Some((m, s)) = t {
            out.mean.u[i] = m[0] as f32;
            out.mean.v[i] = m[1] as f32;
            out.spread[i] = *s as f32;
            out.defined[i] = true;
        }
    }
    Ok(out)
}

/// Fixed-point iterations of [`flow_between`].
const FLOW_ITERATIONS: usize = 10;

/// The true flow `w` from frame a to frame b (`a(x) ≈ b(x + w(x))`, the convention of the flow
/// estimators) from their content displacements: the fixed point of `w = d_a(x) - d_b(x + w)`.
/// `d_b` is sampled bilinearly after push-pull filling its undefined texels; the flow is
/// meaningful where `a.defined` (and zero elsewhere).
pub fn flow_between(a: &ContentDisplacement, b: &ContentDisplacement) -> Result<FlowField> {
    let (w, h) = (a.mean.width, a.mean.height);
    b.mean.check_size(w, h, "the second frame's displacement")?;
    let weight: Vec<f32> = b.defined.iter().map(|&d| if d { 1.0 } else { 0.0 }).collect();
    let bu = push_pull_fill(&b.mean.u, &weight, w, h);
    let bv = push_pull_fill(&b.mean.v, &weight, w, h);
    let mut flow = FlowField::zeros(w, h);
    for i in 0..w * h {
        if !a.defined[i] {
            continue;
        }
        let (x, y) = ((i % w) as f32, (i / w) as f32);
        let (mut u, mut v) = (0.0f32, 0.0f32);
        for _ in 0..FLOW_ITERATIONS {
            u = a.mean.u[i] - sample_bilinear(&bu, w, h, x + u, y + v);
            v = a.mean.v[i] - sample_bilinear(&bv, w, h, x + u, y + v);
        }
        flow.u[i] = u;
        flow.v[i] = v;
    }
    Ok(flow)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn displacement(size: usize, f: impl Fn(usize) -> [f32; 2]) -> ContentDisplacement {
        let mut mean = FlowField::zeros(size, size);
        for i in 0..size * size {
            [mean.u[i], mean.v[i]] = f(i);
        }
        ContentDisplacement { mean, spread: vec![0.0; size * size], defined: vec![true; size * size] }
    }

    #[test]
    fn the_flow_between_two_shifted_frames_is_their_difference() {
        // a shows x + (2, 0), b shows x + (0.5, -1): a(x) = b(x + (1.5, 1)).
        let a = displacement(16, |_| [2.0, 0.0]);
        let b = displacement(16, |_| [0.5, -1.0]);
        let w = flow_between(&a, &b).unwrap();
        assert!((w.u[100] - 1.5).abs() < 1e-5 && (w.v[100] - 1.0).abs() < 1e-5, "{} {}", w.u[100], w.v[100]);
    }

    #[test]
    fn the_flow_between_frames_follows_a_varying_displacement() {
        // b's displacement varies along x: the fixed point lands where x + w + d_b(x + w) is a's
        // source.
        let a = displacement(32, |_| [3.0, 0.0]);
        let b = displacement(32, |i| [0.1 * (i % 32) as f32, 0.0]);
        let w = flow_between(&a, &b).unwrap();
        let i = 10 * 32 + 10;
        let landed = 10.0 + w.u[i] + 0.1 * (10.0 + w.u[i]);
        assert!((landed - 13.0).abs() < 1e-3, "{landed}");
    }

    #[test]
    fn charts_are_the_triangles_sharing_texture_coordinates() {
        let atlas = UvAtlas { coords: vec![[0.0, 0.0]; 7], corners: vec![[0, 1, 2], [2, 1, 3], [4, 5, 6]] };
        assert_eq!(uv_charts(&atlas), vec![0, 0, 4]);
    }
}
