//! Benchmark texture sequences with ground truth: there is no public
//! multi-view texture capture here, so per-frame texture maps are made from a real UV-mapped
//! mesh and its real texture, with every degradation the thesis's method must cope with known
//! exactly. Frame k, on the content texels `C` (the atlas's covered texels grown by
//! `margin` rings, black elsewhere):
//!
//! 1. **drift** (a): `A_k(x) = T(x + d_k(x))`, the smooth tangential warp of
//!    [`crate::texture_drift`] (at most `max_drift` texels; the ground-truth flow between any
//!    two frames is [`DriftModel::true_flow`]);
//! 2. **illumination** (b): `S_k(x) = g_k (ambient + diffuse max(0, n(x) . l_k))`, with `n(x)`
//!    the surface normal carried into the atlas ([`crate::atlas_normals`]), `l_k` a light
//!    swinging smoothly around the subject's front and `g_k` a per-channel colour gain
//!    `1 + tint sin(...)` drifting slowly: low frequency over the surface, as the thesis's
//!    "illumination changes" (4.4.1);
//! 3. **blur** (c): a Gaussian of `blur_sigma` texels over `C` only (weights renormalised over
//!    the content texels, so the black outside does not bleed in); the result, clamped to
//!    0-255, is the **clean frame**, stored as ground truth;
//! 4. **noise** (c): Gaussian, `noise_sigma` on the 0-255 scale, per texel and channel;
//! 5. **holes** (d): in `round(hole_fraction F)` seeded frames, the texels whose surface point
//!    lies in a seeded ellipsoid around a mesh vertex (a region of the surface, cut across
//!    charts as an occluder would) are set to black; the masks are saved.
//!
//! The source texture is first resampled to the asked size by area averaging. Every random
//! choice comes from ChaCha8 streams of the seed (stream 0: drift, lights, gains, holes; stream
//! k + 1: frame k's noise), so a seed gives the same frames whatever the thread count.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use surfcap_mesh::{Progress, Topology};

use crate::atlas_normals::AtlasGeometry;
use crate::atlas_raster::AtlasRaster;
use crate::error::{Error, Result};
use crate::flow_field::warp_direct;
use crate::texture_drift::DriftModel;
use crate::texture_image::TextureImage;

/// The generator's parameters (defaults: a drift, light change, blur, noise and holes of the size real captures show).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GeneratorOptions {
    /// Frames to generate.
    pub frames: usize,
    pub seed: u64,
    /// Width of the generated textures in texels (the height keeps the source's aspect);
    /// `None`: the source texture's size.
    pub size: Option<usize>,
    /// Largest drift displacement, texels of the generated size.
    pub max_drift: f64,
    /// Sinusoids per displacement component.
    pub drift_waves: usize,
    /// Shading: `ambient + diffuse max(0, n . l)`.
    pub ambient: f64,
    pub diffuse: f64,
    /// Amplitude of the per-channel colour gain `1 + tint sin(...)`.
    pub tint: f64,
    /// Largest swing of the light's azimuth around the front (+z), degrees.
    pub light_swing_deg: f64,
    /// Light sweeps (back and forth) over the sequence.
    pub light_cycles: f64,
    /// Gaussian blur, texels (0: none).
    pub blur_sigma: f64,
    /// Gaussian noise on the 0-255 scale (0: none).
    pub noise_sigma: f64,
    /// Share of frames with an occlusion hole.
    pub hole_fraction: f64,
    /// Mean semi-axis of a hole's ellipsoid, as a share of the mesh's bounding-box diagonal.
    pub hole_size: f64,
    /// Rings of texels around the atlas's charts that carry content (the rest is black): at
    /// least the drift, so that a flow read anywhere in a one-ring active mask finds texture.
    pub margin: usize,
}

impl Default for GeneratorOptions {
    fn default() -> Self {
        GeneratorOptions {
            frames: 100,
            seed: 0,
            size: None,
            max_drift: 3.0,
            drift_waves: 3,
            ambient: 0.55,
            diffuse: 0.6,
            tint: 0.06,
            light_swing_deg: 60.0,
            light_cycles: 1.0,
            blur_sigma: 0.6,
            noise_sigma: 2.0,
            hole_fraction: 0.15,
            hole_size: 0.1,
            margin: 4,
        }
    }
}

/// Largest blur the generator accepts, texels: real captures blur by a texel or two (the
/// default is 0.6); at 32 a texture is a smear, and the kernel (6 sigma + 1 texels per pass)
/// stays small.
pub const MAX_BLUR_SIGMA: f64 = 32.0;

/// Largest noise the generator accepts, on the 0-255 scale: beyond one full range the frames
/// are noise whatever the texture.
pub const MAX_NOISE_SIGMA: f64 = 255.0;

/// Largest drift the generator accepts, texels: real texture drift is a few texels (the
/// default is 3); the flow estimators are built for displacements well under 64.
pub const MAX_DRIFT: f64 = 64.0;

/// The generated textures' width and height for a source texture of `texture_size`.
pub fn generated_size(options: &GeneratorOptions, texture_size: [usize; 2]) -> [usize; 2] {
    let [tw, th] = texture_size;
    let width = options.size.unwrap_or(tw);
    let height = ((width as f64 * th as f64 / tw.max(1) as f64).round() as usize).max(1);
    [width, height]
}

/// What [`write_generated_frames`] takes, estimated before any work from the options, the
/// source texture's size and the threads that make frames at once. Memory: the source and the
/// resampled texture, the atlas's geometry (about 96 bytes a texel), each thread's frame in
/// the making (about 96 bytes a texel), the hole masks (a byte a texel per holed frame) and a
/// little per frame; disk: two PNGs a frame (3 bytes a texel at worst), the hole masks, and
/// with `displacement` the f32 [F, 2, H, W] array.
pub fn generated_frames_size(
    options: &GeneratorOptions,
    texture_size: [usize; 2],
    displacement: bool,
    threads: usize,
) -> surfcap_mesh::sizing::Estimate {
    use surfcap_mesh::sizing::bytes;
    let [w, h] = generated_size(options, texture_size);
    let texels = w as f64 * h as f64;
    let frames = options.frames as f64;
    let holed = (options.hole_fraction * frames).round();
    let memory = bytes(&[texture_size[0] as f64, texture_size[1] as f64], 12)
        .saturating_add(bytes(&[texels], 96 + 96 * threads.max(1) as u64))
        .saturating_add(bytes(&[holed, texels], 1))
        .saturating_add(bytes(&[frames], 128));
    let disk = bytes(&[frames, texels], 6).saturating_add(bytes(&[holed, texels], 1)).saturating_add(if displacement {
        bytes(&[frames, texels], 8)
    } else {
        0
    });
    surfcap_mesh::sizing::Estimate {
        what: format!(
            "--frames {} at {w}x{h}{}",
            options.frames,
            if displacement { " with --displacement-npy" } else { "" }
        ),
        memory,
        disk,
        lower: if displacement {
            "--frames or --size, or leave out --displacement-npy".into()
        } else {
            "--frames or --size".into()
        },
    }
}

impl GeneratorOptions {
    fn check(&self) -> Result<()> {
        let bad = |what: &str, v: String| Err(Error::Invalid(format!("{what}: {v}")));
        if self.frames == 0 {
            return bad("frames", "expected at least 1".into());
        }
        if self.size == Some(0) {
            return bad("size", "expected a positive texture width".into());
        }
        for (name, v) in [
            ("max_drift", self.max_drift),
            ("ambient", self.ambient),
            ("diffuse", self.diffuse),
            ("tint", self.tint),
            ("light_swing_deg", self.light_swing_deg),
            ("light_cycles", self.light_cycles),
            ("blur_sigma", self.blur_sigma),
            ("noise_sigma", self.noise_sigma),
            ("hole_size", self.hole_size),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, format!("{v}: expected a finite value >= 0"));
            }
        }
        for (name, v, max) in [
            ("max_drift", self.max_drift, MAX_DRIFT),
            ("blur_sigma", self.blur_sigma, MAX_BLUR_SIGMA),
            ("noise_sigma", self.noise_sigma, MAX_NOISE_SIGMA),
        ] {
            if v > max {
                return bad(name, format!("{v:?}: expected at most {max}"));
            }
        }
        if !(0.0..=1.0).contains(&self.hole_fraction) {
            return bad("hole_fraction", format!("{}: expected a share in [0, 1]", self.hole_fraction));
        }
        if self.tint >= 1.0 {
            return bad("tint", format!("{}: expected below 1", self.tint));
        }
        if self.drift_waves == 0 {
            return bad("drift_waves", "expected at least 1".into());
        }
        Ok(())
    }
}

/// One occlusion: texels whose surface point `p` has `sum_i ((p_i - center_i) / semi_axes_i)^2
/// <= 1` are black in `frame`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hole {
    pub frame: usize,
    pub center: [f64; 3],
    pub semi_axes: [f64; 3],
}

/// A generated frame: the degraded texture, its clean ground truth (before noise and holes),
/// and the hole mask where the frame has one.
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratedFrame {
    pub frame: TextureImage,
    pub clean: TextureImage,
    pub hole: Option<Vec<bool>>,
}

/// Everything a sequence is generated from (the seeded draws made once).
#[derive(Debug, Clone)]
pub struct TextureGenerator {
    options: GeneratorOptions,
    texture: TextureImage,
    content: Vec<bool>,
    geometry: AtlasGeometry,
    drift: DriftModel,
    lights: Vec<[f64; 3]>,
    gains: Vec<[f64; 3]>,
    holes: Vec<Hole>,
}

/// Area-averaging resample to `width x height` (each output texel the mean of the source area
/// it covers; separable).
pub fn resample_area(image: &TextureImage, width: usize, height: usize) -> Result<TextureImage> {
    if width == 0 || height == 0 {
        return Err(Error::Invalid(format!("cannot resample to {width}x{height}")));
    }
    if width == image.width() && height == image.height() {
        return Ok(image.clone());
    }
    // Weights of each output index over the source indices.
    let weights = |n_in: usize, n_out: usize| -> Vec<Vec<(usize, f32)>> {
        let s = n_in as f64 / n_out as f64;
        (0..n_out)
            .map(|o| {
                let (a, b) = (o as f64 * s, (o + 1) as f64 * s);
                let mut w = Vec::new();
                let mut i = a.floor() as usize;
                while (i as f64) < b && i < n_in {
                    let overlap = (b.min(i as f64 + 1.0) - a.max(i as f64)).max(0.0);
                    if overlap > 0.0 {
                        w.push((i, (overlap / s) as f32));
                    }
                    i += 1;
                }
                w
            })
            .collect()
    };
    let (wx, wy) = (weights(image.width(), width), weights(image.height(), height));
    let (iw, ih) = (image.width(), image.height());
    let mut out = TextureImage::zeros(width, height, image.channels());
    for c in 0..image.channels() {
        let src = image.plane(c);
        let mut rows = vec![0.0f32; width * ih];
        rows.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                *o = wx[x].iter().map(|&(i, w)| w * src[y * iw + i]).sum();
            }
        });
        out.plane_mut(c).par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                *o = wy[y].iter().map(|&(j, w)| w * rows[j * width + x]).sum();
            }
        });
    }
    Ok(out)
}

/// Gaussian blur of one plane restricted to `mask` (weights renormalised over masked texels;
/// texels off the mask set to 0).
fn blur_masked(plane: &[f32], mask: &[bool], width: usize, height: usize, sigma: f64) -> Vec<f32> {
    if sigma <= 0.0 {
        return plane.iter().zip(mask).map(|(&v, &m)| if m { v } else { 0.0 }).collect();
    }
    let r = (3.0 * sigma).ceil() as usize;
    let k: Vec<f32> =
        (0..=2 * r).map(|i| (-((i as f64 - r as f64).powi(2)) / (2.0 * sigma * sigma)).exp() as f32).collect();
    let pass = |values: &[f32], weights: &[f32], horizontal: bool| -> (Vec<f32>, Vec<f32>) {
        let mut v_out = vec![0.0f32; width * height];
        let mut w_out = vec![0.0f32; width * height];
        v_out.par_chunks_mut(width).zip(w_out.par_chunks_mut(width)).enumerate().for_each(|(y, (rv, rw))| {
            for x in 0..width {
                let (mut sv, mut sw) = (0.0f32, 0.0f32);
                for (t, &g) in k.iter().enumerate() {
                    let (xx, yy) = if horizontal { ((x + t).wrapping_sub(r), y) } else { (x, (y + t).wrapping_sub(r)) };
                    if xx >= width || yy >= height {
                        continue;
                    }
                    let j = yy * width + xx;
                    sv += g * values[j];
                    sw += g * weights[j];
                }
                rv[x] = sv;
                rw[x] = sw;
            }
        });
        (v_out, w_out)
    };
    let m: Vec<f32> = mask.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect();
    let masked: Vec<f32> = plane.iter().zip(&m).map(|(v, w)| v * w).collect();
    let (v1, w1) = pass(&masked, &m, true);
    let (v2, w2) = pass(&v1, &w1, false);
    (0..width * height).map(|i| if mask[i] && w2[i] > 0.0 { v2[i] / w2[i] } else { 0.0 }).collect()
}

/// Two independent standard normals (Box-Muller).
fn normal_pair(rng: &mut ChaCha8Rng) -> [f32; 2] {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    let r = (-2.0 * u1.ln()).sqrt();
    let t = std::f64::consts::TAU * u2;
    [(r * t.cos()) as f32, (r * t.sin()) as f32]
}

impl TextureGenerator {
    /// Prepares a sequence from a mesh with a UV atlas and its texture.
    pub fn new(
        topology: &Topology,
        positions: &[f32],
        texture: &TextureImage,
        options: &GeneratorOptions,
    ) -> Result<TextureGenerator> {
        options.check()?;
        let atlas = topology.uv().ok_or_else(|| {
            Error::Invalid("the mesh has no texture coordinates (vt): expected a UV-mapped mesh".into())
        })?;
        let [width, height] = generated_size(options, [texture.width(), texture.height()]);
        let texture = resample_area(texture, width, height)?;
        let raster = AtlasRaster::new(atlas, width, height)?;
        let geometry = AtlasGeometry::new(&raster, topology, positions, options.margin)?;
        let content = geometry.defined.clone();
        if !content.iter().any(|&c| c) {
            return Err(Error::Invalid(format!("the UV atlas covers no texel centre at {width}x{height}")));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
        let drift = DriftModel::random(width, height, options.max_drift, options.drift_waves, &mut rng)?;
        // Lights: azimuth swinging about the front (+z, y up), elevation wavering 15-35 deg.
        let f = options.frames as f64;
        let (az_phase, el_phase) =
            (rng.random_range(0.0..std::f64::consts::TAU), rng.random_range(0.0..std::f64::consts::TAU));
        let lights = (0..options.frames)
            .map(|k| {
                let t = std::f64::consts::TAU * options.light_cycles * k as f64 / f;
                let az = options.light_swing_deg.to_radians() * (t + az_phase).sin();
                let el = (25.0 + 10.0 * (0.7 * t + el_phase).sin()).to_radians();
                [el.cos() * az.sin(), el.sin(), el.cos() * az.cos()]
            })
            .collect();
        let gain_phase: [f64; 3] = std::array::from_fn(|_| rng.random_range(0.0..std::f64::consts::TAU));
        let gains = (0..options.frames)
            .map(|k| {
                let t = std::f64::consts::TAU * 0.5 * options.light_cycles * k as f64 / f;
                std::array::from_fn(|c| 1.0 + options.tint * (t + gain_phase[c]).sin())
            })
            .collect();
        // Holes: which frames, then one ellipsoid each.
        let n_holes = (options.hole_fraction * f).round() as usize;
        let mut order: Vec<usize> = (0..options.frames).collect();
        for i in 0..n_holes.min(options.frames) {
            let j = rng.random_range(i..options.frames);
            order.swap(i, j);
        }
        let mut hole_frames: Vec<usize> = order[..n_holes.min(options.frames)].to_vec();
        hole_frames.sort_unstable();
        let (lo, hi) = bounding_box(positions);
        let diagonal = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
        let holes = hole_frames
            .into_iter()
            .map(|frame| {
                let v = rng.random_range(0..topology.n_vertices());
                let center = [positions[3 * v] as f64, positions[3 * v + 1] as f64, positions[3 * v + 2] as f64];
                let semi_axes = std::array::from_fn(|_| options.hole_size * diagonal * rng.random_range(0.6..1.4));
                Hole { frame, center, semi_axes }
            })
            .collect();
        Ok(TextureGenerator { options: options.clone(), texture, content, geometry, drift, lights, gains, holes })
    }

    pub fn options(&self) -> &GeneratorOptions {
        &self.options
    }
    /// The source texture at the generated size.
    pub fn texture(&self) -> &TextureImage {
        &self.texture
    }
    pub fn width(&self) -> usize {
        self.texture.width()
    }
    pub fn height(&self) -> usize {
        self.texture.height()
    }
    /// The content texels (covered, grown by `margin`).
    pub fn content(&self) -> &[bool] {
        &self.content
    }
    pub fn drift(&self) -> &DriftModel {
        &self.drift
    }
    /// Light direction per frame (unit, world coordinates, +y up, +z the front).
    pub fn lights(&self) -> &[[f64; 3]] {
        &self.lights
    }
    /// Per-channel colour gain per frame.
    pub fn gains(&self) -> &[[f64; 3]] {
        &self.gains
    }
    pub fn holes(&self) -> &[Hole] {
        &self.holes
    }

    /// The hole mask of frame `k`, if it has a hole.
    pub fn hole_mask(&self, k: usize) -> Option<Vec<bool>> {
        let hole = self.holes.iter().find(|h| h.frame == k)?;
        Some(
            self.geometry
                .position
                .par_iter()
                .zip(self.content.par_iter())
                .map(|(p, &c)| {
                    c && (0..3).map(|i| ((p[i] as f64 - hole.center[i]) / hole.semi_axes[i]).powi(2)).sum::<f64>()
                        <= 1.0
                })
                .collect(),
        )
    }

    /// The shading factor of frame `k` at every texel, channel `c`.
    fn shading(&self, k: usize, c: usize) -> Vec<f32> {
        let l = self.lights[k];
        let g = self.gains[k][c];
        let (a, d) = (self.options.ambient, self.options.diffuse);
        self.geometry
            .normal
            .par_iter()
            .map(|n| {
                let nl = n[0] as f64 * l[0] + n[1] as f64 * l[1] + n[2] as f64 * l[2];
                (g * (a + d * nl.max(0.0))) as f32
            })
            .collect()
    }

    /// Frame `k` (0-based), its clean version and its hole mask.
    pub fn frame(&self, k: usize) -> Result<GeneratedFrame> {
        if k >= self.options.frames {
            return Err(Error::Invalid(format!("frame {k}: the sequence has {} frames", self.options.frames)));
        }
        let (w, h) = (self.width(), self.height());
        let warped = warp_direct(&self.texture, &self.drift.displacement(k))?;
        let mut clean = TextureImage::zeros(w, h, self.texture.channels());
        for c in 0..self.texture.channels() {
            let s = self.shading(k, c % 3);
            let lit: Vec<f32> = warped.plane(c).iter().zip(&s).map(|(v, s)| v * s).collect();
            let blurred = blur_masked(&lit, &self.content, w, h, self.options.blur_sigma);
            for (o, v) in clean.plane_mut(c).iter_mut().zip(blurred) {
                *o = v.clamp(0.0, 255.0);
            }
        }
        let mut frame = clean.clone();
        if self.options.noise_sigma > 0.0 {
            let mut rng = ChaCha8Rng::seed_from_u64(self.options.seed);
            rng.set_stream(k as u64 + 1);
            let sigma = self.options.noise_sigma as f32;
            let n = w * h;
            let data = frame.data_mut();
            for c in 0..data.len() / n {
                for i in (0..n).step_by(2) {
                    let z = normal_pair(&mut rng);
                    for (j, zz) in z.iter().enumerate() {
                        let t = i + j;
                        if t < n && self.content[t] {
                            data[c * n + t] = (data[c * n + t] + sigma * zz).clamp(0.0, 255.0);
                        }
                    }
                }
            }
        }
        let hole = self.hole_mask(k);
        if let Some(mask) = &hole {
            let n = w * h;
            let data = frame.data_mut();
            for c in 0..data.len() / n {
                for (i, &m) in mask.iter().enumerate() {
                    if m {
                        data[c * n + i] = 0.0;
                    }
                }
            }
        }
        Ok(GeneratedFrame { frame, clean, hole })
    }
}

fn bounding_box(positions: &[f32]) -> ([f64; 3], [f64; 3]) {
    let (lo, hi) = surfcap_mesh::bounding_box(positions);
    (lo.map(f64::from), hi.map(f64::from))
}

/// Reads a UV-mapped OBJ mesh: its topology (with the atlas) and positions; errors name the
/// file, and a mesh without texture coordinates is refused as such.
pub fn read_uv_mesh(path: &Path) -> Result<(Topology, Vec<f32>)> {
    let obj = surfcap_formats::obj::read_obj(path)?;
    let topology = obj.topology().map_err(|e| e.in_file(path))?;
    if topology.uv().is_none() {
        return Err(Error::Invalid(format!(
            "{}: the mesh has no texture coordinates (no 'vt' on every face corner): expected a UV-mapped mesh",
            path.display()
        )));
    }
    Ok((topology, obj.positions))
}

/// Generates the sequence of `options` from the mesh and texture files and writes it as a
/// folder `out` (see [`crate::generated_frames`] for the layout), replacing an earlier one of
/// the same kind (any folder with `force`), with `displacement.npy` when `displacement` is
/// true; `progress` counts frames. Returns the folder's description.
pub fn write_generated_frames(
    mesh: &Path,
    texture: &Path,
    options: &GeneratorOptions,
    out: &Path,
    force: bool,
    displacement: bool,
    progress: &dyn Progress,
) -> Result<crate::generated_frames::FramesHeader> {
    let (topology, positions) = read_uv_mesh(mesh)?;
    let source = TextureImage::read(texture)?;
    let mesh_bytes = surfcap_mesh::read_regular_file(mesh)?;
    let source = GeneratorSource {
        topology: &topology,
        positions: &positions,
        texture: &source,
        mesh_name: mesh,
        texture_name: texture,
        mesh_obj: &mesh_bytes,
    };
    write_generated_frames_of(&source, options, out, force, displacement, progress)
}

/// The mesh and texture a sequence is generated from, in memory, with the names `frames.json`
/// gives them and the OBJ text copied as `template.obj`.
pub struct GeneratorSource<'a> {
    pub topology: &'a Topology,
    pub positions: &'a [f32],
    pub texture: &'a TextureImage,
    pub mesh_name: &'a Path,
    pub texture_name: &'a Path,
    pub mesh_obj: &'a [u8],
}

/// As [`write_generated_frames`], from a mesh and texture in memory (a subject's frame: the
/// head moved by `surfcap make head`, the mannequin with its atlas).
pub fn write_generated_frames_of(
    source: &GeneratorSource,
    options: &GeneratorOptions,
    out: &Path,
    force: bool,
    displacement: bool,
    progress: &dyn Progress,
) -> Result<crate::generated_frames::FramesHeader> {
    let (mesh, texture) = (source.mesh_name, source.texture_name);
    let generator =
        TextureGenerator::new(source.topology, source.positions, source.texture, options).map_err(|e| match e {
            Error::Invalid(m) if m.starts_with("the mesh") || m.starts_with("the UV atlas") => {
                Error::Invalid(format!("{}: {m}", mesh.display()))
            }
            other => other,
        })?;
    crate::generated_frames::write(
        &generator,
        mesh,
        texture,
        [source.texture.width(), source.texture.height()],
        source.mesh_obj,
        out,
        force,
        displacement,
        progress,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::UvAtlas;

    /// A square of two triangles mapped onto most of UV space, with a smooth texture.
    fn plane(size: usize) -> (Topology, Vec<f32>, TextureImage) {
        let positions = vec![-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0];
        let atlas = UvAtlas {
            coords: vec![[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]],
            corners: vec![[0, 1, 2], [0, 2, 3]],
        };
        let topo = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], Some(atlas)).unwrap();
        let n = size * size;
        let data: Vec<f32> = (0..3 * n)
            .map(|i| {
                let (c, t) = (i / n, i % n);
                let (x, y) = ((t % size) as f32 / size as f32, (t / size) as f32 / size as f32);
                120.0 + 60.0 * (6.0 * x + 2.0 * c as f32).sin() * (5.0 * y).cos()
            })
            .collect();
        (topo, positions, TextureImage::from_planes(size, size, 3, data).unwrap())
    }

    fn quiet(frames: usize) -> GeneratorOptions {
        GeneratorOptions {
            frames,
            seed: 3,
            ambient: 1.0,
            diffuse: 0.0,
            tint: 0.0,
            blur_sigma: 0.0,
            noise_sigma: 0.0,
            hole_fraction: 0.0,
            ..GeneratorOptions::default()
        }
    }

    #[test]
    fn warping_by_the_true_flow_aligns_noise_free_frames() {
        let (topo, pos, tex) = plane(96);
        let g = TextureGenerator::new(&topo, &pos, &tex, &quiet(20)).unwrap();
        let (a, b) = (g.frame(2).unwrap().clean, g.frame(17).unwrap().clean);
        let w = g.drift().true_flow(2, 17);
        let aligned = warp_direct(&b, &w).unwrap();
        // Compare inside the charts, away from the content border.
        let raster = AtlasRaster::new(topo.uv().unwrap(), 96, 96).unwrap();
        let inner = crate::TexelMask::from_raster(&raster, 0).unwrap();
        let keep: Vec<bool> = (0..96 * 96)
            .map(|i| {
                let (x, y) = (i % 96, i / 96);
                inner.is_active(i) && (14..82).contains(&x) && (14..82).contains(&y)
            })
            .collect();
        let err = crate::image_similarity::mse(&a, &aligned, &keep).unwrap();
        let before = crate::image_similarity::mse(&a, &b, &keep).unwrap();
        assert!(err < 0.05, "mse after the true flow {err} (before {before})");
        assert!(before > 20.0 * err.max(1e-3), "the frames did differ: {before}");
    }

    #[test]
    fn the_real_head_aligns_by_the_true_flow_up_to_blur_and_noise() {
        let Some(data) = surfcap_testkit::shared_data() else { return };
        let head = data.join("leeperrysmith_head");
        let (topo, pos) = read_uv_mesh(&head.join("template.obj")).unwrap();
        let tex = TextureImage::read(&head.join("Map-COL.jpg")).unwrap();
        let opts =
            GeneratorOptions { frames: 30, seed: 11, size: Some(256), max_drift: 2.0, ..GeneratorOptions::default() };
        let g = TextureGenerator::new(&topo, &pos, &tex, &opts).unwrap();
        let (a, b) = (g.frame(4).unwrap(), g.frame(25).unwrap());
        let mask = crate::TexelMask::from_atlas(topo.uv().unwrap(), 256, 256, 0).unwrap();
        let mut keep: Vec<bool> = (0..256 * 256).map(|i| mask.is_active(i)).collect();
        for m in [&a.hole, &b.hole].into_iter().flatten() {
            keep.iter_mut().zip(m).for_each(|(k, h)| *k &= !h);
        }
        let aligned = warp_direct(&b.frame, &g.drift().true_flow(4, 25)).unwrap();
        let before = crate::image_similarity::ssim(&a.frame, &b.frame, &keep).unwrap();
        let after = crate::image_similarity::ssim(&a.frame, &aligned, &keep).unwrap();
        assert!(after > before, "ssim before {before}, after the true flow {after}");
        // Without illumination changes the clean frames (blurred, noise-free) align closely.
        let flat = GeneratorOptions { ambient: 1.0, diffuse: 0.0, tint: 0.0, ..opts };
        let g = TextureGenerator::new(&topo, &pos, &tex, &flat).unwrap();
        let (a, b) = (g.frame(4).unwrap().clean, g.frame(25).unwrap().clean);
        let mse_before = crate::image_similarity::mse(&a, &b, &keep).unwrap();
        let mse_after =
            crate::image_similarity::mse(&a, &warp_direct(&b, &g.drift().true_flow(4, 25)).unwrap(), &keep).unwrap();
        assert!(mse_after < 0.3 * mse_before, "{mse_after} vs {mse_before}");
    }

    #[test]
    fn frames_degrade_as_asked() {
        let (topo, pos, tex) = plane(64);
        let opts =
            GeneratorOptions { frames: 20, seed: 9, hole_fraction: 0.2, hole_size: 0.3, ..GeneratorOptions::default() };
        let g = TextureGenerator::new(&topo, &pos, &tex, &opts).unwrap();
        assert_eq!(g.holes().len(), 4);
        let k = g.holes()[0].frame;
        let f = g.frame(k).unwrap();
        let hole = f.hole.as_ref().unwrap();
        let n_hole = hole.iter().filter(|&&h| h).count();
        assert!(n_hole > 20, "{n_hole}");
        for (i, &in_hole) in hole.iter().enumerate() {
            if in_hole {
                assert!((0..3).all(|c| f.frame.plane(c)[i] == 0.0));
            }
            if !g.content()[i] {
                assert!((0..3).all(|c| f.frame.plane(c)[i] == 0.0 && f.clean.plane(c)[i] == 0.0));
            }
        }
        // Noise of sigma 2 off the hole.
        let keep: Vec<bool> = (0..64 * 64).map(|i| g.content()[i] && !hole[i]).collect();
        let noise = crate::image_similarity::mse(&f.frame, &f.clean, &keep).unwrap().sqrt();
        assert!((1.6..2.4).contains(&noise), "noise {noise}");
        // A frame without hole has none.
        let other = (0..20).find(|k| g.holes().iter().all(|h| h.frame != *k)).unwrap();
        assert!(g.frame(other).unwrap().hole.is_none());
        // Illumination changes over the frames.
        let (c0, c1) = (g.frame(0).unwrap().clean, g.frame(10).unwrap().clean);
        let m0: f32 = c0.plane(0).iter().sum();
        let m1: f32 = c1.plane(0).iter().sum();
        assert!((m0 - m1).abs() / m0 > 0.01, "{m0} vs {m1}");
    }

    #[test]
    fn the_same_seed_gives_the_same_frames_whatever_the_thread_count() {
        let (topo, pos, tex) = plane(48);
        let opts = GeneratorOptions { frames: 10, seed: 21, hole_fraction: 0.3, ..GeneratorOptions::default() };
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
                let g = TextureGenerator::new(&topo, &pos, &tex, &opts).unwrap();
                (0..10).map(|k| g.frame(k).unwrap()).collect::<Vec<_>>()
            })
        };
        let one = run(1);
        assert_eq!(one, run(3));
        let other = TextureGenerator::new(&topo, &pos, &tex, &GeneratorOptions { seed: 22, ..opts.clone() }).unwrap();
        assert_ne!(one[0].frame, other.frame(0).unwrap().frame, "another seed, other frames");
    }

    #[test]
    fn area_resampling_keeps_the_mean_and_a_flat_image() {
        let (_, _, tex) = plane(64);
        let small = resample_area(&tex, 16, 16).unwrap();
        let mean = |t: &TextureImage| t.plane(1).iter().map(|&v| v as f64).sum::<f64>() / t.texels() as f64;
        assert!((mean(&tex) - mean(&small)).abs() < 1e-3);
        let flat = TextureImage::from_planes(10, 10, 1, vec![7.0; 100]).unwrap();
        assert!(resample_area(&flat, 3, 4).unwrap().data().iter().all(|&v| (v - 7.0).abs() < 1e-5));
    }

    #[test]
    fn the_size_estimate_grows_with_frames_and_texels_and_counts_the_displacement() {
        let o =
            GeneratorOptions { frames: 1_000_000, size: Some(1024), hole_fraction: 0.0, ..GeneratorOptions::default() };
        assert_eq!(generated_size(&o, [2048, 1024]), [1024, 512]);
        let plain = generated_frames_size(&o, [1024, 1024], false, 2);
        let with = generated_frames_size(&o, [1024, 1024], true, 2);
        assert_eq!(plain.disk, 1_000_000 * 1024 * 1024 * 6);
        // The displacement: 8 bytes a texel a frame, 8 TB for a million 1024 x 1024 frames.
        assert_eq!(with.disk - plain.disk, 1_000_000 * 1024 * 1024 * 8);
        assert!(with.what.contains("--frames 1000000 at 1024x1024 with --displacement-npy"), "{}", with.what);
        assert!(plain.memory < 1 << 30, "no frame is kept: {}", plain.memory);
    }

    #[test]
    fn blur_noise_and_drift_beyond_their_ranges_are_refused_before_any_work() {
        let (topo, pos, tex) = plane(32);
        for (o, name) in [
            (GeneratorOptions { blur_sigma: 1e308, ..quiet(2) }, "blur_sigma: 1e308: expected at most 32"),
            (GeneratorOptions { noise_sigma: 256.0, ..quiet(2) }, "noise_sigma: 256.0: expected at most 255"),
            (GeneratorOptions { max_drift: 1e308, ..quiet(2) }, "max_drift: 1e308: expected at most 64"),
        ] {
            let Err(e) = TextureGenerator::new(&topo, &pos, &tex, &o) else { panic!("{name}: accepted") };
            let e = e.to_string();
            assert!(e.contains(name), "{e}");
        }
    }

    #[test]
    fn a_mesh_without_texture_coordinates_is_refused() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let e = TextureGenerator::new(&topo, &[0.0; 9], &TextureImage::zeros(4, 4, 3), &GeneratorOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no texture coordinates"), "{e}");
    }
}
