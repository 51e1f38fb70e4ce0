//! A texture benchmark made the way multi-view capture makes per-frame texture maps, with the
//! clean truth kept:
//!
//! 1. **The moving subject.** A UV-mapped mesh (the head scan) turns and nods rigidly about its
//!    bounding-box centre (yaw and pitch sinusoids with seeded phases) in front of a fixed
//!    light.
//! 2. **Renders.** A ring of `cameras` pinhole cameras (alternately 20 degrees above and 5
//!    below the centre, equally spaced in azimuth) sees the true posed mesh
//!    ([`crate::mesh_rasteriser::rasterise`]: z-buffer, perspective-correct barycentrics); each
//!    pixel is `albedo (ambient + diffuse max(0, n.l)) + 255 specular max(0, n.h)^shininess`
//!    (Blinn-Phong, `h` halfway between the light and the pixel's view direction: the
//!    view-dependent term), plus seeded Gaussian sensor noise, clamped to 0-255.
//! 3. **Capture errors.** Each true camera differs from its calibration (the nominal ring the
//!    re-projection uses) by a fixed seeded error: eye moved by `calibration_shift` of the
//!    subject's radius, view and roll turned by `calibration_deg`, focal length scaled by
//!    `1 + calibration_focal` (Gaussian draws). Each frame's tracked mesh differs from the true
//!    one by a smooth per-frame vertex perturbation: `tracking_waves` sinusoids of the rest
//!    position (random directions, 0.5-1.5 cycles per radius, random phases) whose sum has an
//!    RMS of `tracking` radii, drawn anew per frame.
//! 4. **Re-projection** ([`reproject`]), as capture pipelines texture a tracked mesh: every
//!    active texel's point and normal on the tracked mesh ([`AtlasGeometry`]) is projected into
//!    every calibrated camera; it is visible when it faces the camera and its depth is within
//!    `depth_tolerance` radii of the tracked mesh's own depth map from that camera; the texel is
//!    the blend of the visible cameras' bilinear samples weighted by the cosine of the view
//!    angle. Texels no camera sees are filled by push-pull from the seen ones
//!    ([`crate::inactive_fill::push_pull_fill`]).
//! 5. **Truth.** The clean frame is the albedo atlas shaded by the true pose's diffuse term, no
//!    specular, no capture error: what a perfect capture under this light would give.
//!    Occlusion holes (a seeded ellipsoid about a surface point in a seeded share of frames)
//!    are black in the degraded frame, as in [`crate::texture_generator`].
//!
//! Every random draw comes from ChaCha8 seeded by `seed` (one stream per frame and camera), and
//! frames are computed independently, so the result does not depend on the thread count.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use surfcap_mesh::Topology;

use crate::atlas_normals::{AtlasGeometry, vertex_normals};
use crate::atlas_raster::AtlasRaster;
use crate::content_displacement::{CaptureGeometry, ContentDisplacement, content_displacement};
use crate::error::{Error, Result};
use crate::flow_field::sample_bilinear;
use crate::inactive_fill::push_pull_fill;
use crate::mesh_rasteriser::{Camera, Fragments, Lens, cameras_around, rasterise};
use crate::texel_mask::TexelMask;
use crate::texture_generator::{Hole, resample_area};
use crate::texture_image::TextureImage;

/// The benchmark's parameters (defaults: errors of the size multi-view studios report, a few
/// millimetres of tracking and a fraction of a degree of calibration on a 25 cm head).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaptureOptions {
    pub frames: usize,
    pub seed: u64,
    /// Atlas width and height, texels.
    pub size: usize,
    /// Cameras on the ring.
    pub cameras: usize,
    /// Render width and height, pixels.
    pub image_size: usize,
    pub fov_y_deg: f64,
    /// Shading: `ambient + diffuse max(0, n.l)` times the albedo, plus `255 specular
    /// max(0, n.h)^shininess`.
    pub ambient: f64,
    pub diffuse: f64,
    pub specular: f64,
    pub shininess: f64,
    /// Direction towards the light (world, y up, +z the subject's front).
    pub light: [f64; 3],
    /// Amplitudes of the subject's turn (about y) and nod (about x), degrees.
    pub yaw_deg: f64,
    pub pitch_deg: f64,
    /// Per-camera calibration error: view and roll angle (degrees), eye shift (radii), focal
    /// scale, each the standard deviation of a Gaussian draw.
    pub calibration_deg: f64,
    pub calibration_shift: f64,
    pub calibration_focal: f64,
    /// RMS of the per-frame tracking error, radii of the subject's bounding sphere.
    pub tracking: f64,
    pub tracking_waves: usize,
    /// Sensor noise, 0-255 scale.
    pub noise_sigma: f64,
    /// Share of frames with an occlusion hole, and its semi-axes (radii).
    pub hole_fraction: f64,
    pub hole_size: f64,
    /// Depth test tolerance, radii.
    pub depth_tolerance: f64,
    /// Rings of texels around the atlas's charts that are re-projected (the eval's active
    /// texels: one ring).
    pub dilation: usize,
}

impl Default for CaptureOptions {
    fn default() -> Self {
        CaptureOptions {
            frames: 60,
            seed: 7,
            size: 256,
            cameras: 12,
            image_size: 256,
            fov_y_deg: 30.0,
            ambient: 0.5,
            diffuse: 0.6,
            specular: 0.25,
            shininess: 20.0,
            light: [0.35, 0.6, 0.72],
            yaw_deg: 35.0,
            pitch_deg: 10.0,
            calibration_deg: 0.3,
            calibration_shift: 0.01,
            calibration_focal: 0.01,
            tracking: 0.02,
            tracking_waves: 4,
            noise_sigma: 2.0,
            hole_fraction: 0.15,
            hole_size: 0.25,
            depth_tolerance: 0.03,
            dilation: 1,
        }
    }
}

impl CaptureOptions {
    fn check(&self) -> Result<()> {
        let bad = |field: &str, what: String| Err(Error::Invalid(format!("capture benchmark option {field}: {what}")));
        if self.frames == 0 {
            return bad("frames", "expected at least 1".into());
        }
        if self.cameras == 0 {
            return bad("cameras", "expected at least 1".into());
        }
        if !(8..=4096).contains(&self.size) || !(8..=4096).contains(&self.image_size) {
            return bad(
                "size",
                format!("expected 8-4096 texels and pixels, got {} and {}", self.size, self.image_size),
            );
        }
        let finite = [
            self.ambient,
            self.diffuse,
            self.specular,
            self.shininess,
            self.yaw_deg,
            self.pitch_deg,
            self.calibration_deg,
            self.calibration_shift,
            self.calibration_focal,
            self.tracking,
            self.noise_sigma,
            self.hole_size,
            self.depth_tolerance,
        ];
        if finite.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return bad("shading, motion and error sizes", "expected finite values of at least 0".into());
        }
        if !(0.0..=1.0).contains(&self.hole_fraction) {
            return bad("hole_fraction", format!("expected a share in [0, 1], got {}", self.hole_fraction));
        }
        if !(self.fov_y_deg > 1.0 && self.fov_y_deg < 170.0) {
            return bad("fov_y_deg", format!("expected 1-170 degrees, got {}", self.fov_y_deg));
        }
        Ok(())
    }
}

/// Which capture errors a [`CaptureBenchmark::content_displacement`] includes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ErrorCauses {
    pub calibration: bool,
    pub tracking: bool,
}

impl ErrorCauses {
    pub const BOTH: ErrorCauses = ErrorCauses { calibration: true, tracking: true };
    pub const CALIBRATION: ErrorCauses = ErrorCauses { calibration: true, tracking: false };
    pub const TRACKING: ErrorCauses = ErrorCauses { calibration: false, tracking: true };
    pub const NONE: ErrorCauses = ErrorCauses { calibration: false, tracking: false };
}

/// One frame: the re-projected texture (holes black), the clean truth, the hole mask where the
/// frame has one, and the texels at least one camera saw.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureFrame {
    pub frame: TextureImage,
    pub clean: TextureImage,
    pub hole: Option<Vec<bool>>,
    pub seen: Vec<bool>,
}

/// A re-projected texture and the texels a camera saw.
#[derive(Debug, Clone, PartialEq)]
pub struct Reprojection {
    pub texture: TextureImage,
    pub seen: Vec<bool>,
}

/// Minimum cosine between a texel's normal and its view direction for a camera to count.
pub const MIN_COS: f64 = 0.05;

pub type V3 = [f64; 3];
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn unit(a: V3) -> V3 {
    let n = dot(a, a).sqrt();
    if n > 0.0 { [a[0] / n, a[1] / n, a[2] / n] } else { [0.0; 3] }
}
fn f64s(a: [f32; 3]) -> V3 {
    a.map(f64::from)
}

fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

fn gaussian3(rng: &mut ChaCha8Rng) -> V3 {
    [gaussian(rng), gaussian(rng), gaussian(rng)]
}

/// One camera's share of a texel's blend: the camera, the pixel the texel's point projects to
/// (x right, y down, pixel centres at +0.5) and the blend weight (the cosine of the view angle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendSample {
    pub camera: usize,
    pub pixel: [f64; 2],
    /// The point's depth along the camera's view axis.
    pub depth: f64,
    pub weight: f64,
}

/// The cameras that see the surface point `p` with normal `n` (facing it by at least
/// [`MIN_COS`], inside the image, within `depth_tolerance` of the depth map `depth[j]` of the
/// mesh the texels are re-projected through), in camera order: the samples [`reproject`]
/// blends.
pub fn blend_samples(
    p: V3,
    n: V3,
    cameras: &[Camera],
    depth: &[Fragments],
    depth_tolerance: f64,
) -> Result<Vec<BlendSample>> {
    let mut out = Vec::new();
    for (j, (cam, d)) in cameras.iter().zip(depth).enumerate() {
        let cos = dot(n, unit(sub(cam.eye, p)));
        if cos < MIN_COS {
            continue;
        }
        let Some([x, y, z]) = cam.project(p)? else { continue };
        let (cw, ch) = (cam.lens.width, cam.lens.height);
        if !(x >= 0.0 && y >= 0.0 && x < cw as f64 && y < ch as f64) {
            continue;
        }
        let (px, py) = (x as usize, y as usize);
        if z > d.depth[py * cw + px] + depth_tolerance {
            continue;
        }
        out.push(BlendSample { camera: j, pixel: [x, y], depth: z, weight: cos });
    }
    Ok(out)
}

/// Re-projects the images seen by `cameras` onto the texels of `raster` (the covered ones and
/// `dilation` rings: the active texels of [`TexelMask::from_raster`]) through the mesh at `positions`: the cosine-weighted blend
/// of the cameras that see each texel's point (facing it, within `depth_tolerance` scene units
/// of the mesh's own depth map from that camera). Texels no camera sees are filled by push-pull;
/// `seen` marks the others.
pub fn reproject(
    topology: &Topology,
    positions: &[f32],
    raster: &AtlasRaster,
    dilation: usize,
    images: &[TextureImage],
    cameras: &[Camera],
    depth_tolerance: f64,
) -> Result<Reprojection> {
    if images.len() != cameras.len() || images.is_empty() {
        return Err(Error::Mismatch(format!(
            "{} images for {} cameras: expected one image per camera, at least one",
            images.len(),
            cameras.len()
        )));
    }
    let (w, h) = (raster.width, raster.height);
    let mask = TexelMask::from_raster(raster, dilation)?;
    let channels = images[0].channels();
    for (j, (im, cam)) in images.iter().zip(cameras).enumerate() {
        if im.width() != cam.lens.width || im.height() != cam.lens.height || im.channels() != channels {
            return Err(Error::Mismatch(format!(
                "camera {j}: image of {}x{}x{} for a lens of {}x{} ({channels} channels expected)",
                im.width(),
                im.height(),
                im.channels(),
                cam.lens.width,
                cam.lens.height
            )));
        }
    }
    let geometry = AtlasGeometry::new(raster, topology, positions, dilation)?;
    let depth: Vec<_> = cameras.iter().map(|c| rasterise(topology, positions, c)).collect::<Result<_>>()?;
    let blended: Vec<Option<Vec<f32>>> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            if !mask.is_active(i) || !geometry.defined[i] {
                return Ok(None);
            }
            let p = f64s(geometry.position[i]);
            let n = f64s(geometry.normal[i]);
            let mut acc = vec![0.0f64; channels];
            let mut total = 0.0f64;
            for s in blend_samples(p, n, cameras, &depth, depth_tolerance)? {
                let (im, cw, ch) = (&images[s.camera], cameras[s.camera].lens.width, cameras[s.camera].lens.height);
                for (c, a) in acc.iter_mut().enumerate() {
                    *a += s.weight
                        * sample_bilinear(im.plane(c), cw, ch, (s.pixel[0] - 0.5) as f32, (s.pixel[1] - 0.5) as f32)
                            as f64;
                }
                total += s.weight;
            }
            Ok((total > 0.0).then(|| acc.iter().map(|a| (a / total) as f32).collect()))
        })
        .collect::<Result<_>>()?;
    let seen: Vec<bool> = blended.iter().map(|b| b.is_some()).collect();
    let weight: Vec<f32> = seen.iter().map(|&s| if s { 1.0 } else { 0.0 }).collect();
    let mut data = vec![0.0f32; channels * w * h];
    for c in 0..channels {
        let plane: Vec<f32> = blended.iter().map(|b| b.as_ref().map_or(0.0, |v| v[c])).collect();
        let filled = push_pull_fill(&plane, &weight, w, h);
        for i in 0..w * h {
            if mask.is_active(i) {
                data[c * w * h + i] = filled[i];
            }
        }
    }
    Ok(Reprojection { texture: TextureImage::from_planes(w, h, channels, data)?, seen })
}

/// Everything a capture benchmark is generated from (the seeded draws made once).
#[derive(Debug, Clone)]
pub struct CaptureBenchmark {
    options: CaptureOptions,
    topology: Topology,
    rest: Vec<f32>,
    albedo: TextureImage,
    raster: AtlasRaster,
    mask: TexelMask,
    rest_geometry: AtlasGeometry,
    center: V3,
    radius: f64,
    /// What the re-projection believes (the nominal ring) and where the cameras are.
    calibrated: Vec<Camera>,
    actual: Vec<Camera>,
    /// Yaw and pitch per frame, radians.
    poses: Vec<[f64; 2]>,
    holes: Vec<Hole>,
}

impl CaptureBenchmark {
    /// Prepares a benchmark from a UV-mapped mesh and its albedo texture (resampled to the
    /// atlas size).
    pub fn new(
        topology: &Topology,
        positions: &[f32],
        texture: &TextureImage,
        options: &CaptureOptions,
    ) -> Result<CaptureBenchmark> {
        options.check()?;
        let atlas = topology.uv().ok_or_else(|| {
            Error::Invalid("the mesh has no texture coordinates (vt): expected a UV-mapped mesh".into())
        })?;
        if positions.len() != 3 * topology.n_vertices() {
            return Err(Error::Mismatch(format!(
                "{} position values for a mesh of {} vertices",
                positions.len(),
                topology.n_vertices()
            )));
        }
        let n = options.size;
        let albedo = resample_area(texture, n, n)?;
        let raster = AtlasRaster::new(atlas, n, n)?;
        let mask = TexelMask::from_raster(&raster, options.dilation)?;
        if mask.is_empty() {
            return Err(Error::Invalid(format!("the UV atlas covers no texel centre at {n}x{n}")));
        }
        let rest_geometry = AtlasGeometry::new(&raster, topology, positions, options.dilation)?;
        let (lo, hi) = surfcap_mesh::bounding_box(positions);
        let center: V3 = std::array::from_fn(|i| (lo[i] as f64 + hi[i] as f64) / 2.0);
        let radius = (0..3).map(|i| (hi[i] as f64 - lo[i] as f64).powi(2)).sum::<f64>().sqrt() / 2.0;
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(Error::Invalid("the mesh has no extent: expected a subject to photograph".into()));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
        let lens = Lens { fov_y_deg: options.fov_y_deg, width: options.image_size, height: options.image_size };
        let half = options.fov_y_deg.to_radians() / 2.0;
        let distance = 1.1 * radius / half.sin();
        let calibrated: Vec<Camera> = (0..options.cameras)
            .map(|j| {
                let elevation = if j % 2 == 0 { 20.0 } else { -5.0 };
                cameras_around(center, [0.0, 1.0, 0.0], distance, options.cameras, elevation, lens)[j]
            })
            .collect();
        let actual: Vec<Camera> = calibrated
            .iter()
            .map(|c| {
                let shift = gaussian3(&mut rng);
                let turn = gaussian3(&mut rng);
                let roll = gaussian3(&mut rng);
                let focal = 1.0 + options.calibration_focal * gaussian(&mut rng);
                let angle = options.calibration_deg.to_radians();
                let d = distance;
                let eye = std::array::from_fn(|i| c.eye[i] + options.calibration_shift * radius * shift[i]);
                let target = std::array::from_fn(|i| c.target[i] + angle * d * turn[i]);
                let up = unit(std::array::from_fn(|i| c.up[i] + angle * roll[i]));
                // A focal length scaled by `focal` is a field of view of 2 atan(tan(fov/2) / focal).
                let fov = 2.0 * ((c.lens.fov_y_deg.to_radians() / 2.0).tan() / focal).atan();
                Camera { eye, target, up, lens: Lens { fov_y_deg: fov.to_degrees(), ..c.lens } }
            })
            .collect();
        let phases: [f64; 2] = std::array::from_fn(|_| rng.random_range(0.0..std::f64::consts::TAU));
        let f = options.frames as f64;
        let poses = (0..options.frames)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / f;
                [
                    options.yaw_deg.to_radians() * (1.3 * t + phases[0]).sin(),
                    options.pitch_deg.to_radians() * (2.1 * t + phases[1]).sin(),
                ]
            })
            .collect();
        let n_holes = ((options.hole_fraction * f).round() as usize).min(options.frames);
        let mut order: Vec<usize> = (0..options.frames).collect();
        for i in 0..n_holes {
            let j = rng.random_range(i..options.frames);
            order.swap(i, j);
        }
        let mut hole_frames: Vec<usize> = order[..n_holes].to_vec();
        hole_frames.sort_unstable();
        let holes = hole_frames
            .into_iter()
            .map(|frame| {
                let v = rng.random_range(0..topology.n_vertices());
                let c = [positions[3 * v] as f64, positions[3 * v + 1] as f64, positions[3 * v + 2] as f64];
                let semi_axes = std::array::from_fn(|_| options.hole_size * radius * rng.random_range(0.6..1.4));
                Hole { frame, center: c, semi_axes }
            })
            .collect();
        Ok(CaptureBenchmark {
            options: options.clone(),
            topology: topology.clone(),
            rest: positions.to_vec(),
            albedo,
            raster,
            mask,
            rest_geometry,
            center,
            radius,
            calibrated,
            actual,
            poses,
            holes,
        })
    }

    pub fn options(&self) -> &CaptureOptions {
        &self.options
    }
    /// The atlas's active texels (covered, grown by `dilation` rings).
    pub fn mask(&self) -> &TexelMask {
        &self.mask
    }
    pub fn holes(&self) -> &[Hole] {
        &self.holes
    }
    /// The cameras as calibrated (the nominal ring the re-projection uses).
    pub fn calibrated_cameras(&self) -> &[Camera] {
        &self.calibrated
    }
    /// The cameras as they are (calibration error included).
    pub fn actual_cameras(&self) -> &[Camera] {
        &self.actual
    }
    /// The subject's bounding-sphere radius, scene units.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// `rest + offset` turned and nodded by frame `k`'s pose about the centre.
    fn posed(&self, k: usize, offset: Option<&[V3]>) -> Vec<f32> {
        let [yaw, pitch] = self.poses[k];
        let (sy, cy) = yaw.sin_cos();
        let (sp, cp) = pitch.sin_cos();
        let c = self.center;
        let mut out = Vec::with_capacity(self.rest.len());
        for (v, p) in self.rest.chunks_exact(3).enumerate() {
            let mut q = [p[0] as f64 - c[0], p[1] as f64 - c[1], p[2] as f64 - c[2]];
            if let Some(o) = offset {
                q = [q[0] + o[v][0], q[1] + o[v][1], q[2] + o[v][2]];
            }
            // Nod about x, then turn about y.
            let (y1, z1) = (cp * q[1] - sp * q[2], sp * q[1] + cp * q[2]);
            let (x2, z2) = (cy * q[0] + sy * z1, -sy * q[0] + cy * z1);
            out.extend([(x2 + c[0]) as f32, (y1 + c[1]) as f32, (z2 + c[2]) as f32]);
        }
        out
    }

    /// The true mesh of frame `k`.
    pub fn true_positions(&self, k: usize) -> Vec<f32> {
        self.posed(k, None)
    }

    /// The tracked mesh of frame `k`: the tracking error added to the rest shape, then posed.
    pub fn tracked_positions(&self, k: usize) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.options.seed);
        rng.set_stream(2 * k as u64 + 1);
        let waves = self.options.tracking_waves.max(1);
        // Each wave a_w sin(2 pi f_w (d_w . q) / r + phi_w): RMS |a_w| / sqrt(2) per wave.
        let scale = self.options.tracking * self.radius * (2.0 / waves as f64).sqrt();
        let draws: Vec<(V3, V3, f64, f64)> = (0..waves)
            .map(|_| {
                let dir = unit(gaussian3(&mut rng));
                let amp = unit(gaussian3(&mut rng)).map(|v| v * scale);
                (dir, amp, rng.random_range(0.5..1.5), rng.random_range(0.0..std::f64::consts::TAU))
            })
            .collect();
        let c = self.center;
        let offsets: Vec<V3> = self
            .rest
            .chunks_exact(3)
            .map(|p| {
                let q = [p[0] as f64 - c[0], p[1] as f64 - c[1], p[2] as f64 - c[2]];
                let mut o = [0.0; 3];
                for (dir, amp, freq, phase) in &draws {
                    let s = (std::f64::consts::TAU * freq * dot(*dir, q) / self.radius + phase).sin();
                    for i in 0..3 {
                        o[i] += amp[i] * s;
                    }
                }
                o
            })
            .collect();
        self.posed(k, Some(&offsets))
    }

    /// Camera `j`'s image of frame `k`: the true mesh seen by the actual camera, shaded, with
    /// sensor noise.
    pub fn render(&self, k: usize, j: usize) -> Result<TextureImage> {
        self.render_positions(k, j, &self.true_positions(k))
    }

    fn render_positions(&self, k: usize, j: usize, positions: &[f32]) -> Result<TextureImage> {
        let cam =
            self.actual.get(j).ok_or_else(|| Error::Invalid(format!("camera {j}: there are {}", self.actual.len())))?;
        let frags = rasterise(&self.topology, positions, cam)?;
        let atlas = self.topology.uv().expect("checked at construction");
        let normals = vertex_normals(&self.topology, positions);
        let tris = self.topology.triangles();
        let light = unit(self.options.light);
        let o = &self.options;
        let (w, h) = (cam.lens.width, cam.lens.height);
        let (tw, th) = (self.albedo.width(), self.albedo.height());
        let channels = self.albedo.channels();
        let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
        rng.set_stream(2 * (k * self.actual.len() + j) as u64 + 2);
        let mut data = vec![0.0f32; channels * w * h];
        for i in 0..w * h {
            if !frags.covered(i) {
                continue;
            }
            let t = frags.triangle[i] as usize;
            let b = frags.barycentric[i];
            let mut uv = [0.0f64; 2];
            let mut p = [0.0f64; 3];
            let mut n = [0.0f64; 3];
            for (corner, &bc) in b.iter().enumerate() {
                let c = atlas.coords[atlas.corners[t][corner] as usize];
                uv[0] += bc * c[0] as f64;
                uv[1] += bc * c[1] as f64;
                let v = tris[t][corner] as usize;
                for a in 0..3 {
                    p[a] += bc * positions[3 * v + a] as f64;
                    n[a] += bc * normals[v][a] as f64;
                }
            }
            let mut n = unit(n);
            let view = unit(sub(cam.eye, p));
            if dot(n, view) < 0.0 {
                n = n.map(|v| -v);
            }
            let nl = dot(n, light);
            let halfway = unit([light[0] + view[0], light[1] + view[1], light[2] + view[2]]);
            let spec = if nl > 0.0 { 255.0 * o.specular * dot(n, halfway).max(0.0).powf(o.shininess) } else { 0.0 };
            let shade = o.ambient + o.diffuse * nl.max(0.0);
            let tx = (uv[0] * tw as f64 - 0.5) as f32;
            let ty = ((1.0 - uv[1]) * th as f64 - 0.5) as f32;
            for c in 0..channels {
                let a = sample_bilinear(self.albedo.plane(c), tw, th, tx, ty) as f64;
                data[c * w * h + i] = (a * shade + spec) as f32;
            }
        }
        if o.noise_sigma > 0.0 {
            for i in 0..w * h {
                if frags.covered(i) {
                    for c in 0..channels {
                        data[c * w * h + i] += (o.noise_sigma * gaussian(&mut rng)) as f32;
                    }
                }
            }
        }
        data.iter_mut().for_each(|v| *v = v.clamp(0.0, 255.0));
        TextureImage::from_planes(w, h, channels, data)
    }

    /// The clean truth of frame `k`: the albedo shaded by the true pose's diffuse term.
    pub fn clean(&self, k: usize) -> Result<TextureImage> {
        let geometry =
            AtlasGeometry::new(&self.raster, &self.topology, &self.true_positions(k), self.options.dilation)?;
        let light = unit(self.options.light);
        let (w, h) = (self.raster.width, self.raster.height);
        let mut out = TextureImage::zeros(w, h, self.albedo.channels());
        for c in 0..self.albedo.channels() {
            let a = self.albedo.plane(c);
            let plane = out.plane_mut(c);
            for i in 0..w * h {
                if self.mask.is_active(i) && geometry.defined[i] {
                    let nl = dot(f64s(geometry.normal[i]), light).max(0.0);
                    plane[i] =
                        (a[i] as f64 * (self.options.ambient + self.options.diffuse * nl)).clamp(0.0, 255.0) as f32;
                }
            }
        }
        Ok(out)
    }

    /// The hole mask of frame `k`, if it has a hole (texels whose rest point lies in the
    /// ellipsoid).
    pub fn hole_mask(&self, k: usize) -> Option<Vec<bool>> {
        let hole = self.holes.iter().find(|h| h.frame == k)?;
        Some(
            (0..self.raster.width * self.raster.height)
                .map(|i| {
                    self.mask.is_active(i)
                        && self.rest_geometry.defined[i]
                        && (0..3)
                            .map(|a| {
                                ((self.rest_geometry.position[i][a] as f64 - hole.center[a]) / hole.semi_axes[a])
                                    .powi(2)
                            })
                            .sum::<f64>()
                            <= 1.0
                })
                .collect(),
        )
    }

    /// The true displacement of frame `k`'s re-projected content
    /// ([`crate::content_displacement`]) with the capture errors `causes` names (the others
    /// left out: the true mesh as tracked, the actual cameras as calibrated).
    pub fn content_displacement(&self, k: usize, causes: ErrorCauses) -> Result<ContentDisplacement> {
        if k >= self.options.frames {
            return Err(Error::Invalid(format!("frame {k}: the benchmark has {} frames", self.options.frames)));
        }
        let truth = self.true_positions(k);
        let tracked = if causes.tracking { self.tracked_positions(k) } else { truth.clone() };
        let actual = if causes.calibration { &self.actual } else { &self.calibrated };
        let geometry = CaptureGeometry {
            topology: &self.topology,
            tracked: &tracked,
            calibrated: &self.calibrated,
            truth: &truth,
            actual,
        };
        content_displacement(&geometry, &self.raster, self.options.dilation, self.options.depth_tolerance * self.radius)
    }

    /// Frame `k`: every camera's render re-projected through the tracked mesh and the
    /// calibrated cameras, its clean truth and its hole.
    pub fn frame(&self, k: usize) -> Result<CaptureFrame> {
        if k >= self.options.frames {
            return Err(Error::Invalid(format!("frame {k}: the benchmark has {} frames", self.options.frames)));
        }
        let truth = self.true_positions(k);
        let images: Vec<TextureImage> =
            (0..self.actual.len()).map(|j| self.render_positions(k, j, &truth)).collect::<Result<_>>()?;
        let tracked = self.tracked_positions(k);
        let r = reproject(
            &self.topology,
            &tracked,
            &self.raster,
            self.options.dilation,
            &images,
            &self.calibrated,
            self.options.depth_tolerance * self.radius,
        )?;
        let mut frame = r.texture;
        let hole = self.hole_mask(k);
        if let Some(m) = &hole {
            let n = m.len();
            let data = frame.data_mut();
            for c in 0..data.len() / n {
                for (i, &x) in m.iter().enumerate() {
                    if x {
                        data[c * n + i] = 0.0;
                    }
                }
            }
        }
        Ok(CaptureFrame { frame, clean: self.clean(k)?, hole, seen: r.seen })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::UvAtlas;

    /// A unit cube, each face its own chart in a 3 x 2 grid of the atlas (with a gap).
    fn cube() -> (Topology, Vec<f32>) {
        let faces: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
            ([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            ([1.0, -1.0, -1.0], [-2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            ([1.0, -1.0, 1.0], [0.0, 0.0, -2.0], [0.0, 2.0, 0.0]),
            ([-1.0, -1.0, -1.0], [0.0, 0.0, 2.0], [0.0, 2.0, 0.0]),
            ([-1.0, 1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 0.0, -2.0]),
            ([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
        ];
        let mut positions = Vec::new();
        let mut coords = Vec::new();
        let mut tris = Vec::new();
        for (f, (o, a, b)) in faces.iter().enumerate() {
            let (cu, cv) = ((f % 3) as f32 / 3.0, (f / 3) as f32 / 2.0);
            let base = (positions.len() / 3) as u32;
            for (s, t) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                positions.extend((0..3).map(|i| o[i] + s * a[i] + t * b[i]));
                coords.push([cu + 0.02 + 0.29 * s, cv + 0.03 + 0.44 * t]);
            }
            tris.push([base, base + 1, base + 2]);
            tris.push([base, base + 2, base + 3]);
        }
        let atlas = UvAtlas { coords, corners: tris.clone() };
        (Topology::new(24, tris, Some(atlas)).unwrap(), positions)
    }

    fn smooth_texture(n: usize) -> TextureImage {
        let data = (0..3 * n * n)
            .map(|i| {
                let (c, t) = (i / (n * n), i % (n * n));
                let (x, y) = ((t % n) as f32 / n as f32, (t / n) as f32 / n as f32);
                128.0 + 60.0 * (6.0 * x + 2.0 * c as f32).sin() + 50.0 * (5.0 * y - c as f32).cos()
            })
            .collect();
        TextureImage::from_planes(n, n, 3, data).unwrap()
    }

    #[test]
    fn reprojecting_clean_renders_gives_back_the_atlas_on_seen_texels() {
        // No shading, no error: every camera's plain render re-projected through the same mesh
        // and cameras is the atlas again, up to two bilinear resamplings.
        let (topo, pos) = cube();
        let n = 64;
        let tex = smooth_texture(n);
        let raster = AtlasRaster::new(topo.uv().unwrap(), n, n).unwrap();
        let mask = TexelMask::from_raster(&raster, 0).unwrap();
        let lens = Lens { fov_y_deg: 40.0, width: 128, height: 128 };
        let cams: Vec<Camera> =
            [30.0, -25.0].iter().flat_map(|&el| cameras_around([0.0; 3], [0.0, 1.0, 0.0], 6.0, 6, el, lens)).collect();
        let images: Vec<TextureImage> =
            cams.iter().map(|c| crate::mesh_rasteriser::render(&topo, &pos, &tex, c).unwrap().image).collect();
        let r = reproject(&topo, &pos, &raster, 0, &images, &cams, 0.02).unwrap();
        let mut err = 0.0f64;
        let mut count = 0usize;
        for i in 0..n * n {
            if mask.is_active(i) && r.seen[i] {
                for c in 0..3 {
                    err += (r.texture.plane(c)[i] - tex.plane(c)[i]).abs() as f64;
                }
                count += 1;
            }
        }
        assert!(count as f64 > 0.9 * mask.len() as f64, "{count} of {} texels seen", mask.len());
        let mean = err / (3 * count) as f64;
        assert!(mean < 2.5, "mean absolute difference {mean} grey levels");
    }

    #[test]
    fn a_shifted_camera_moves_what_the_atlas_shows() {
        // The same re-projection with the renders taken by cameras moved sideways: the atlas
        // no longer matches (the calibration error the benchmark adds does something).
        let (topo, pos) = cube();
        let n = 64;
        let tex = smooth_texture(n);
        let raster = AtlasRaster::new(topo.uv().unwrap(), n, n).unwrap();
        let lens = Lens { fov_y_deg: 40.0, width: 128, height: 128 };
        let cams = cameras_around([0.0; 3], [0.0, 1.0, 0.0], 6.0, 6, 30.0, lens);
        let moved: Vec<Camera> = cams.iter().map(|c| Camera { target: [0.15, 0.1, 0.0], ..*c }).collect();
        let images: Vec<TextureImage> =
            moved.iter().map(|c| crate::mesh_rasteriser::render(&topo, &pos, &tex, c).unwrap().image).collect();
        let r = reproject(&topo, &pos, &raster, 0, &images, &cams, 0.02).unwrap();
        let err: f64 = (0..n * n)
            .filter(|&i| r.seen[i])
            .map(|i| (r.texture.plane(0)[i] - tex.plane(0)[i]).abs() as f64)
            .sum::<f64>()
            / r.seen.iter().filter(|&&s| s).count() as f64;
        assert!(err > 5.0, "{err}");
    }

    fn tiny_benchmark(seed: u64) -> CaptureBenchmark {
        let (topo, pos) = cube();
        let options = CaptureOptions {
            frames: 3,
            seed,
            size: 32,
            cameras: 4,
            image_size: 48,
            hole_fraction: 0.34,
            ..CaptureOptions::default()
        };
        CaptureBenchmark::new(&topo, &pos, &smooth_texture(32), &options).unwrap()
    }

    #[test]
    fn the_same_seed_gives_the_same_frames_on_any_thread_count() {
        let b = tiny_benchmark(3);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| b.frame(1).unwrap());
        let many = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| b.frame(1).unwrap());
        assert_eq!(one, many);
        assert_eq!(tiny_benchmark(3).frame(2).unwrap(), b.frame(2).unwrap());
        assert_ne!(tiny_benchmark(4).frame(1).unwrap().frame, one.frame);
        assert_eq!(b.holes().len(), 1);
    }

    #[test]
    fn the_head_scan_captured_without_error_is_its_truth_and_with_error_is_not() {
        let Some(data) = surfcap_testkit::shared_data() else { return };
        let head = data.join("leeperrysmith_head");
        let (topo, pos) = crate::texture_generator::read_uv_mesh(&head.join("template.obj")).unwrap();
        let tex = TextureImage::read(&head.join("Map-COL.jpg")).unwrap();
        let base = CaptureOptions { frames: 2, size: 64, cameras: 8, image_size: 128, ..CaptureOptions::default() };
        let perfect = CaptureOptions {
            specular: 0.0,
            calibration_deg: 0.0,
            calibration_shift: 0.0,
            calibration_focal: 0.0,
            tracking: 0.0,
            noise_sigma: 0.0,
            hole_fraction: 0.0,
            ..base.clone()
        };
        let measure = |o: &CaptureOptions| {
            let b = CaptureBenchmark::new(&topo, &pos, &tex, o).unwrap();
            let f = b.frame(1).unwrap();
            let m = b.mask();
            let (mut err, mut seen) = (0.0f64, 0usize);
            for i in 0..64 * 64 {
                if m.is_active(i) && f.seen[i] && f.hole.as_ref().is_none_or(|h| !h[i]) {
                    err += (0..3).map(|c| (f.frame.plane(c)[i] - f.clean.plane(c)[i]).abs() as f64).sum::<f64>() / 3.0;
                    seen += 1;
                }
            }
            (err / seen as f64, seen as f64 / m.len() as f64)
        };
        let (clean_err, clean_seen) = measure(&perfect);
        let (err, seen) = measure(&base);
        // Most of the head is seen by a ring of 8 (the crown and under the chin are not).
        assert!(clean_seen > 0.75 && seen > 0.75, "{clean_seen} {seen}");
        // Without error the capture is the truth up to resampling (a texel of the 64 x 64 atlas
        // spans several pixels of skin detail); calibration, tracking, specular and noise take
        // it further.
        assert!(clean_err < 5.0, "{clean_err}");
        assert!(err > 1.5 * clean_err, "{err} vs {clean_err}");
    }

    #[test]
    fn content_comes_from_its_own_texel_without_error_and_from_elsewhere_with_it() {
        // Renders fine enough that the four pixel centres of a sample lie within the depth
        // tolerance of each other on the cube's slanted faces.
        let (topo, pos) = cube();
        let options =
            CaptureOptions { frames: 3, seed: 5, size: 32, cameras: 4, image_size: 192, ..CaptureOptions::default() };
        let b = CaptureBenchmark::new(&topo, &pos, &smooth_texture(32), &options).unwrap();
        // The texels the charts cover (the dilated ring's points are its inner neighbours').
        let covered = |i: usize| b.raster.covered(i);
        let summary = |c: ErrorCauses| b.content_displacement(1, c).unwrap().summary_where(covered);
        let (none, none_spread, defined) = summary(ErrorCauses::NONE);
        let n_covered = (0..32 * 32).filter(|&i| covered(i)).count();
        // Texels a camera sees at a grazing angle (a pixel there spans several texels of depth
        // beyond the tolerance) are left undefined; the ones all cameras see squarely remain.
        assert!(defined >= 40 && defined < n_covered, "{defined} of {n_covered}");
        // Without error every camera's sample shows the texel's own point, up to the bilinear
        // mix of four pixel centres.
        assert!(none < 0.05 && none_spread < 0.05, "{none} {none_spread}");
        let (ring, _, _) = b.content_displacement(1, ErrorCauses::NONE).unwrap().summary_where(|i| !covered(i));
        assert!(ring > 0.3, "the ring shows its inner neighbours' points: {ring}");
        let mut big = b.clone();
        big.options.calibration_deg = 0.0;
        for (a, c) in big.actual.iter_mut().zip(&big.calibrated) {
            // Every actual camera looks 0.15 units (about 2 texels of a 32-texel cube face) off.
            a.target = [c.target[0] + 0.15, c.target[1], c.target[2]];
        }
        let (moved, moved_spread, _) =
            big.content_displacement(1, ErrorCauses::CALIBRATION).unwrap().summary_where(covered);
        assert!(moved > 0.5, "{moved}");
        // The cameras look off in different directions in the atlas: the blend ghosts.
        assert!(moved_spread > 0.1, "{moved_spread}");
        let (tracked, _, _) = b.content_displacement(1, ErrorCauses::TRACKING).unwrap().summary_where(covered);
        assert!(tracked > 0.05, "{tracked}");
    }

    #[test]
    fn bad_options_are_named() {
        let (topo, pos) = cube();
        let o = CaptureOptions { hole_fraction: 2.0, ..CaptureOptions::default() };
        let e = CaptureBenchmark::new(&topo, &pos, &smooth_texture(8), &o).unwrap_err().to_string();
        assert!(e.contains("hole_fraction"), "{e}");
    }
}
