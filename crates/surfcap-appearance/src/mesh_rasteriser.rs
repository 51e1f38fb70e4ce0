//! A software rasteriser for the image-domain evaluation of the thesis (4.5: the textured model
//! "rendered from 8 virtual cameras" and compared with renders of the ground-truth textures):
//! a triangle mesh with a UV atlas, textured by a [`TextureImage`], seen by a pinhole camera.
//!
//! Per pixel: the nearest triangle by z-buffer (depth = distance along the view axis), its
//! texture coordinates interpolated perspective-correctly (u/z, v/z and 1/z are affine in
//! screen space), and a bilinear lookup in the texture ([`crate::flow_field::sample_bilinear`],
//! texel centres at ((x + 0.5) / W, 1 - (y + 0.5) / H), the atlas convention of
//! [`crate::atlas_raster`]). Pixel (px, py) is sampled at its centre; row 0 is the top of the
//! image. Pixels no triangle covers are background: black in the image and false in the
//! silhouette mask. Triangles with a corner behind the near plane are skipped (the cameras
//! stand outside the subject); both faces of a triangle are drawn.
//!
//! Rows are rendered in parallel bands, each band reading every triangle that spans it in index
//! order; a depth tie keeps the lower triangle index, so the image does not depend on the
//! thread count.

use rayon::prelude::*;
use surfcap_mesh::Topology;

use crate::error::{Error, Result};
use crate::flow_field::sample_bilinear;
use crate::texture_image::TextureImage;

/// The image side of a pinhole camera: vertical field of view and size in pixels.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Lens {
    pub fov_y_deg: f64,
    pub width: usize,
    pub height: usize,
}

/// A pinhole camera looking from `eye` at `target`, `up` giving the image's vertical.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub lens: Lens,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn normalise(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 1e-12 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

/// Near-plane distance below which a corner counts as behind the camera (scene units).
const NEAR: f64 = 1e-6;

impl Camera {
    /// The camera's right, true-up and forward axes (orthonormal, right-handed).
    fn basis(&self) -> Result<[[f64; 3]; 3]> {
        let f = normalise(sub(self.target, self.eye))
            .ok_or_else(|| Error::Invalid("a camera's eye and target coincide".into()))?;
        let r = normalise(cross(f, self.up))
            .ok_or_else(|| Error::Invalid("a camera's up direction is parallel to its view direction".into()))?;
        let u = cross(r, f);
        Ok([r, u, f])
    }

    /// Pixel coordinates (x right, y down, pixel centres at +0.5) and depth along the view axis
    /// of a point, or `None` behind the near plane.
    pub fn project(&self, p: [f64; 3]) -> Result<Option<[f64; 3]>> {
        let basis = self.basis()?;
        Ok(project_with(&basis, self, p))
    }
}

fn project_with(basis: &[[f64; 3]; 3], cam: &Camera, p: [f64; 3]) -> Option<[f64; 3]> {
    let d = sub(p, cam.eye);
    let z = dot(d, basis[2]);
    if z <= NEAR {
        return None;
    }
    let focal = cam.lens.height as f64 / 2.0 / (cam.lens.fov_y_deg.to_radians() / 2.0).tan();
    let x = cam.lens.width as f64 / 2.0 + focal * dot(d, basis[0]) / z;
    let y = cam.lens.height as f64 / 2.0 - focal * dot(d, basis[1]) / z;
    Some([x, y, z])
}

/// `n` cameras on a horizontal ring (about `up`) of radius `radius` around `center`, raised by
/// `elevation_deg` above the ring's plane, equally spaced in azimuth (turning from the start
/// towards up x start) from the world axis least aligned with `up` (ties to z then x: +z for a y-up
/// subject), all looking at `center`.
pub fn cameras_around(
    center: [f64; 3],
    up: [f64; 3],
    radius: f64,
    n: usize,
    elevation_deg: f64,
    lens: Lens,
) -> Vec<Camera> {
    let up_n = normalise(up).unwrap_or([0.0, 1.0, 0.0]);
    // A horizontal start direction: the world axis least aligned with up (ties to z, then x),
    // made perpendicular: +z for a y-up subject (glTF's front), +x for a z-up one.
    let mut axis = 2;
    for a in [0, 1] {
        if up_n[a].abs() < up_n[axis].abs() {
            axis = a;
        }
    }
    let mut e = [0.0; 3];
    e[axis] = 1.0;
    let a = normalise(sub(e, up_n.map(|v| v * dot(e, up_n)))).unwrap_or([1.0, 0.0, 0.0]);
    let b = cross(up_n, a);
    let el = elevation_deg.to_radians();
    (0..n)
        .map(|k| {
            let az = 2.0 * std::f64::consts::PI * k as f64 / n.max(1) as f64;
            let dir: [f64; 3] =
                std::array::from_fn(|i| el.cos() * (az.cos() * a[i] + az.sin() * b[i]) + el.sin() * up_n[i]);
            Camera { eye: std::array::from_fn(|i| center[i] + radius * dir[i]), target: center, up: up_n, lens }
        })
        .collect()
}

/// [`cameras_around`] a mesh: centred on its bounding box, at the distance where the bounding
/// sphere fills the field of view with a 5% margin.
pub fn cameras_around_mesh(positions: &[f32], up: [f64; 3], n: usize, elevation_deg: f64, lens: Lens) -> Vec<Camera> {
    let (lo, hi) = surfcap_mesh::bounding_box(positions);
    let (lo, hi) = (lo.map(f64::from), hi.map(f64::from));
    let center: [f64; 3] = std::array::from_fn(|i| (lo[i] + hi[i]) / 2.0);
    let r = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt() / 2.0;
    let half_y = lens.fov_y_deg.to_radians() / 2.0;
    let half_x = (half_y.tan() * lens.width as f64 / lens.height.max(1) as f64).atan();
    let half = half_y.min(half_x);
    cameras_around(center, up, 1.05 * r / half.sin(), n, elevation_deg, lens)
}

/// A rendered view: the image (black background) and its silhouette (pixels a triangle covers).
#[derive(Debug, Clone, PartialEq)]
pub struct Render {
    pub image: TextureImage,
    pub mask: Vec<bool>,
}

/// Rows per parallel band.
const BAND: usize = 16;

/// What a camera sees per pixel (row-major): the nearest triangle (or `u32::MAX`), its depth
/// along the view axis (infinite on the background) and the perspective-correct barycentrics
/// of the pixel centre's ray hit in that triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Fragments {
    pub width: usize,
    pub height: usize,
    pub triangle: Vec<u32>,
    pub depth: Vec<f64>,
    pub barycentric: Vec<[f64; 3]>,
}

impl Fragments {
    /// Whether pixel `i` shows a triangle.
    pub fn covered(&self, i: usize) -> bool {
        self.triangle[i] != u32::MAX
    }
}

/// Rasterises `positions` ([vertices][3]) with `topology`'s triangles from `camera`: the
/// z-buffer, the owner triangle and the perspective-correct barycentrics of every pixel.
pub fn rasterise(topology: &Topology, positions: &[f32], camera: &Camera) -> Result<Fragments> {
    if positions.len() != topology.n_vertices() * 3 {
        return Err(Error::Mismatch(format!(
            "{} position values for a mesh of {} vertices: expected {}",
            positions.len(),
            topology.n_vertices(),
            topology.n_vertices() * 3
        )));
    }
    let (w, h) = (camera.lens.width, camera.lens.height);
    if w == 0 || h == 0 || !(camera.lens.fov_y_deg > 0.0 && camera.lens.fov_y_deg < 180.0) {
        return Err(Error::Invalid(format!(
            "a camera needs a positive image size and a field of view in (0, 180) degrees, got {w}x{h} and {}",
            camera.lens.fov_y_deg
        )));
    }
    let basis = camera.basis()?;
    let projected: Vec<Option<[f64; 3]>> = positions
        .chunks_exact(3)
        .map(|p| project_with(&basis, camera, [p[0] as f64, p[1] as f64, p[2] as f64]))
        .collect();
    // Screen triangles that survive the near plane, binned by band.
    let n_bands = h.div_ceil(BAND);
    let mut bands: Vec<Vec<u32>> = vec![Vec::new(); n_bands];
    for (t, tri) in topology.triangles().iter().enumerate() {
        let Some(ps) = tri.iter().map(|&v| projected[v as usize]).collect::<Option<Vec<_>>>() else {
            continue;
        };
        let y0 = ps.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        let y1 = ps.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
        if y1 < 0.0 || y0 > h as f64 || !y0.is_finite() || !y1.is_finite() {
            continue;
        }
        let b0 = ((y0 - 0.5).max(0.0) as usize / BAND).min(n_bands - 1);
        let b1 = ((y1 - 0.5).max(0.0) as usize / BAND).min(n_bands - 1);
        for band in &mut bands[b0..=b1] {
            band.push(t as u32);
        }
    }
    type Band = (Vec<f64>, Vec<u32>, Vec<[f64; 3]>);
    let results: Vec<Band> = (0..n_bands)
        .into_par_iter()
        .map(|bi| {
            let r0 = bi * BAND;
            let r1 = (r0 + BAND).min(h);
            let rows = r1 - r0;
            let mut depth = vec![f64::INFINITY; rows * w];
            let mut owner = vec![u32::MAX; rows * w];
            let mut bary = vec![[0.0f64; 3]; rows * w];
            for &t in &bands[bi] {
                let tri = topology.triangles()[t as usize];
                let ps = tri.map(|v| projected[v as usize].expect("binned triangles are in front"));
                let area =
                    (ps[1][0] - ps[0][0]) * (ps[2][1] - ps[0][1]) - (ps[2][0] - ps[0][0]) * (ps[1][1] - ps[0][1]);
                if area.abs() < 1e-12 {
                    continue;
                }
                let xs = ps.map(|p| p[0]);
                let ys = ps.map(|p| p[1]);
                let x0 = (xs.iter().cloned().fold(f64::INFINITY, f64::min) - 0.5).ceil().max(0.0);
                let x1 = (xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - 0.5).floor().min(w as f64 - 1.0);
                let y0 = (ys.iter().cloned().fold(f64::INFINITY, f64::min) - 0.5).ceil().max(r0 as f64);
                let y1 = (ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - 0.5).floor().min(r1 as f64 - 1.0);
                if x1 < x0 || y1 < y0 {
                    continue;
                }
                let inv_z = ps.map(|p| 1.0 / p[2]);
                for py in y0 as usize..=y1 as usize {
                    let cy = py as f64 + 0.5;
                    for px in x0 as usize..=x1 as usize {
                        let cx = px as f64 + 0.5;
                        let edge = |a: [f64; 3], b: [f64; 3]| (b[0] - a[0]) * (cy - a[1]) - (cx - a[0]) * (b[1] - a[1]);
                        let l0 = edge(ps[1], ps[2]) / area;
                        let l1 = edge(ps[2], ps[0]) / area;
                        let l2 = 1.0 - l0 - l1;
                        const EPS: f64 = -1e-9;
                        if l0 < EPS || l1 < EPS || l2 < EPS {
                            continue;
                        }
                        // Perspective-correct: 1/z, u/z, v/z are affine in screen space.
                        let iz = l0 * inv_z[0] + l1 * inv_z[1] + l2 * inv_z[2];
                        let z = 1.0 / iz;
                        let i = (py - r0) * w + px;
                        if z < depth[i] || (z == depth[i] && t < owner[i]) {
                            depth[i] = z;
                            owner[i] = t;
                            bary[i] = [l0 * inv_z[0] * z, l1 * inv_z[1] * z, l2 * inv_z[2] * z];
                        }
                    }
                }
            }
            (depth, owner, bary)
        })
        .collect();
    let mut depth = Vec::with_capacity(w * h);
    let mut triangle = Vec::with_capacity(w * h);
    let mut barycentric = Vec::with_capacity(w * h);
    for (d, o, b) in results {
        depth.extend(d);
        triangle.extend(o);
        barycentric.extend(b);
    }
    Ok(Fragments { width: w, height: h, triangle, depth, barycentric })
}

/// Renders `positions` ([vertices][3]) with `topology`'s triangles and UV atlas, textured by
/// `texture`, from `camera`.
pub fn render(topology: &Topology, positions: &[f32], texture: &TextureImage, camera: &Camera) -> Result<Render> {
    let atlas = topology.uv().ok_or_else(|| {
        Error::Invalid("the mesh has no texture coordinates: expected a UV atlas to render a texture".into())
    })?;
    let frags = rasterise(topology, positions, camera)?;
    let (w, h) = (frags.width, frags.height);
    let channels = texture.channels();
    let (tw, th) = (texture.width(), texture.height());
    let values: Vec<Option<Vec<f32>>> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            if !frags.covered(i) {
                return None;
            }
            let t = frags.triangle[i] as usize;
            let uvs = atlas.corners[t].map(|c| atlas.coords[c as usize]);
            let b = frags.barycentric[i];
            let uv = [
                b[0] * uvs[0][0] as f64 + b[1] * uvs[1][0] as f64 + b[2] * uvs[2][0] as f64,
                b[0] * uvs[0][1] as f64 + b[1] * uvs[1][1] as f64 + b[2] * uvs[2][1] as f64,
            ];
            let tx = (uv[0] * tw as f64 - 0.5) as f32;
            let ty = ((1.0 - uv[1]) * th as f64 - 0.5) as f32;
            Some((0..channels).map(|c| sample_bilinear(texture.plane(c), tw, th, tx, ty)).collect())
        })
        .collect();
    let mut colour = vec![0.0f32; channels * w * h];
    let mut mask = vec![false; w * h];
    for (i, v) in values.into_iter().enumerate() {
        if let Some(v) = v {
            mask[i] = true;
            for (c, x) in v.into_iter().enumerate() {
                colour[c * w * h + i] = x;
            }
        }
    }
    Ok(Render { image: TextureImage::from_planes(w, h, channels, colour)?, mask })
}

/// Renders from every camera (views in parallel through the bands), in camera order.
pub fn render_views(
    topology: &Topology,
    positions: &[f32],
    texture: &TextureImage,
    cameras: &[Camera],
) -> Result<Vec<Render>> {
    cameras.iter().map(|c| render(topology, positions, texture, c)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::UvAtlas;

    fn lens(n: usize) -> Lens {
        Lens { fov_y_deg: 60.0, width: n, height: n }
    }

    /// A unit square in the plane z = `z`, UV [0,1]^2, x right and y up.
    fn quad(z: f32) -> (Topology, Vec<f32>) {
        let positions = vec![-1.0, -1.0, z, 1.0, -1.0, z, 1.0, 1.0, z, -1.0, 1.0, z];
        let atlas = UvAtlas {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            corners: vec![[0, 1, 2], [0, 2, 3]],
        };
        (Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], Some(atlas)).unwrap(), positions)
    }

    fn front_camera(dist: f64, n: usize) -> Camera {
        Camera { eye: [0.0, 0.0, dist], target: [0.0; 3], up: [0.0, 1.0, 0.0], lens: lens(n) }
    }

    #[test]
    fn a_quad_facing_the_camera_shows_the_texture() {
        // The camera sees exactly [-1, 1]^2 at distance 1 / tan(30 deg): the render is the
        // texture resampled at pixel centres.
        let n = 32;
        let (topo, pos) = quad(0.0);
        let data: Vec<f32> = (0..3 * n * n)
            .map(|i| ((i % (n * n)) % n * 7 + (i % (n * n)) / n * 3 + i / (n * n) * 50) as f32 % 256.0)
            .collect();
        let tex = TextureImage::from_planes(n, n, 3, data).unwrap();
        let cam = front_camera(1.0 / 30f64.to_radians().tan(), n);
        let r = render(&topo, &pos, &tex, &cam).unwrap();
        let mut worst = 0.0f32;
        for c in 0..3 {
            for y in 0..n {
                for x in 0..n {
                    assert!(r.mask[y * n + x]);
                    worst = worst.max((r.image.get(c, x, y) - tex.get(c, x, y)).abs());
                }
            }
        }
        assert!(worst < 1e-2, "largest difference {worst}");
    }

    #[test]
    fn perspective_correct_uv_on_a_slanted_quad() {
        // A quad receding in depth: the texture coordinate at a pixel is that of the 3-D point
        // the pixel's ray hits, not the screen-space interpolation.
        let positions = vec![-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, -4.0, -1.0, 1.0, -4.0];
        let atlas = UvAtlas {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            corners: vec![[0, 1, 2], [0, 2, 3]],
        };
        let topo = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], Some(atlas)).unwrap();
        // A texture whose value is 255 v (row 0 is v = 1).
        let tn = 256;
        let data: Vec<f32> = (0..tn * tn).map(|i| 255.0 * (1.0 - ((i / tn) as f32 + 0.5) / tn as f32)).collect();
        let tex = TextureImage::from_planes(tn, tn, 1, data).unwrap();
        let cam = Camera { eye: [0.0, 0.0, 3.0], target: [0.0, 0.0, -1.0], up: [0.0, 1.0, 0.0], lens: lens(64) };
        let r = render(&topo, &positions, &tex, &cam).unwrap();
        let basis = cam.basis().unwrap();
        let f = 32.0 / 30f64.to_radians().tan();
        let mut checked = 0;
        for py in 0..64 {
            let x = 32usize;
            if !r.mask[py * 64 + x] {
                continue;
            }
            // Ray through the pixel centre, intersected with the plane of the quad.
            let dy = -((py as f64 + 0.5) - 32.0) / f;
            let dir: [f64; 3] =
                std::array::from_fn(|i| basis[2][i] + dy * basis[1][i] + ((x as f64 + 0.5 - 32.0) / f) * basis[0][i]);
            // Plane through (0,-1,0) and (0,1,-4): y = -1 + 2 s, z = -4 s => z = -2 (y + 1).
            let t = (-2.0 * (cam.eye[1] + 1.0) - cam.eye[2]) / (dir[2] + 2.0 * dir[1]);
            let y_hit = cam.eye[1] + t * dir[1];
            let v = (y_hit + 1.0) / 2.0;
            let got = r.image.get(0, x, py) as f64 / 255.0;
            assert!((got - v).abs() < 5e-3, "row {py}: v {got} vs {v}");
            checked += 1;
        }
        assert!(checked > 20, "{checked}");
    }

    #[test]
    fn the_silhouette_of_a_known_triangle() {
        // A triangle at the image centre plane: its silhouette holds exactly the pixel centres
        // inside its projection.
        let n = 40;
        let positions = vec![-0.5f32, -0.5, 0.0, 0.7, -0.2, 0.0, 0.0, 0.8, 0.0];
        let atlas = UvAtlas { coords: vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]], corners: vec![[0, 1, 2]] };
        let topo = Topology::new(3, vec![[0, 1, 2]], Some(atlas)).unwrap();
        let tex = TextureImage::from_planes(2, 2, 3, vec![200.0; 12]).unwrap();
        let cam = front_camera(1.0 / 30f64.to_radians().tan(), n);
        let r = render(&topo, &positions, &tex, &cam).unwrap();
        // At distance 1/tan(30), world (x, y) maps to pixel (20 + 20 x, 20 - 20 y).
        let px = |p: [f64; 2]| [20.0 + 20.0 * p[0], 20.0 - 20.0 * p[1]];
        let a = px([-0.5, -0.5]);
        let b = px([0.7, -0.2]);
        let c = px([0.0, 0.8]);
        let side = |p: [f64; 2], q: [f64; 2], x: f64, y: f64| (q[0] - p[0]) * (y - p[1]) - (x - p[0]) * (q[1] - p[1]);
        let mut inside = 0;
        for y in 0..n {
            for x in 0..n {
                let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                let s = [side(a, b, cx, cy), side(b, c, cx, cy), side(c, a, cx, cy)];
                let margin = s.iter().map(|v| v.abs()).fold(f64::INFINITY, f64::min);
                if margin < 1e-3 {
                    continue; // on an edge: either answer is right
                }
                let expected = s.iter().all(|&v| v > 0.0) || s.iter().all(|&v| v < 0.0);
                assert_eq!(r.mask[y * n + x], expected, "pixel ({x}, {y})");
                if expected {
                    inside += 1;
                    assert!((r.image.get(0, x, y) - 200.0).abs() < 1e-3);
                } else {
                    assert_eq!(r.image.get(0, x, y), 0.0);
                }
            }
        }
        assert!(inside > 200, "{inside}");
    }

    /// A quad spanning x in [x0, x1], y in [-1, 1] at depth z, textured by texture column u.
    fn strip(x0: f32, x1: f32, z: f32, u: f32, first: u32) -> (Vec<f32>, Vec<[f32; 2]>, Vec<[u32; 3]>) {
        let positions = vec![x0, -1.0, z, x1, -1.0, z, x1, 1.0, z, x0, 1.0, z];
        let uv = vec![[u, 0.5]; 4];
        let tris = vec![[first, first + 1, first + 2], [first, first + 2, first + 3]];
        (positions, uv, tris)
    }

    fn two_strips(near_first: bool) -> Render {
        // Far: a wide white quad at z = -1; near: a grey quad over its left half at z = 0.5.
        let far = strip(-1.0, 1.0, -1.0, 0.25, 0);
        let near = strip(-1.0, 0.0, 0.5, 0.75, 4);
        let (a, b) =
            if near_first { (strip(-1.0, 0.0, 0.5, 0.75, 0), strip(-1.0, 1.0, -1.0, 0.25, 4)) } else { (far, near) };
        let mut positions = a.0;
        positions.extend(b.0);
        let mut coords = a.1;
        coords.extend(b.1);
        let mut tris = a.2;
        tris.extend(b.2);
        let atlas = UvAtlas { coords, corners: tris.clone() };
        let topo = Topology::new(8, tris, Some(atlas)).unwrap();
        // Texture: left half 255, right half 100.
        let tex = TextureImage::from_planes(2, 1, 1, vec![255.0, 100.0]).unwrap();
        render(&topo, &positions, &tex, &front_camera(4.0, 32)).unwrap()
    }

    #[test]
    fn the_nearer_of_two_overlapping_triangles_wins() {
        for near_first in [false, true] {
            let r = two_strips(near_first);
            // Left of centre both quads cover the pixel: the near one (grey) shows.
            assert_eq!(r.image.get(0, 12, 16), 100.0, "near first: {near_first}");
            // Right of centre only the far one does.
            assert_eq!(r.image.get(0, 19, 16), 255.0, "near first: {near_first}");
        }
        assert_eq!(two_strips(false), two_strips(true));
    }

    #[test]
    fn cameras_on_a_ring_look_at_the_centre() {
        let cams = cameras_around([1.0, 2.0, 3.0], [0.0, 1.0, 0.0], 5.0, 8, 20.0, lens(16));
        assert_eq!(cams.len(), 8);
        for c in &cams {
            let d = sub(c.eye, [1.0, 2.0, 3.0]);
            assert!((dot(d, d).sqrt() - 5.0).abs() < 1e-9);
            assert!((d[1] / 5.0 - 20f64.to_radians().sin()).abs() < 1e-9);
            let p = c.project([1.0, 2.0, 3.0]).unwrap().unwrap();
            assert!((p[0] - 8.0).abs() < 1e-9 && (p[1] - 8.0).abs() < 1e-9);
        }
        // Distinct azimuths.
        assert!(sub(cams[0].eye, cams[4].eye).iter().map(|v| v * v).sum::<f64>() > 50.0);
    }

    #[test]
    fn renders_do_not_depend_on_the_thread_count() {
        let (topo, pos) = quad(0.0);
        let tex = TextureImage::from_planes(3, 3, 1, (0..9).map(|i| i as f32 * 20.0).collect()).unwrap();
        let cam = Camera { eye: [0.3, -0.4, 2.0], target: [0.0; 3], up: [0.0, 1.0, 0.0], lens: lens(50) };
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| render(&topo, &pos, &tex, &cam).unwrap());
        let many = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| render(&topo, &pos, &tex, &cam).unwrap());
        assert_eq!(one, many);
    }

    #[test]
    fn the_real_head_seen_by_eight_cameras() {
        let Some(data) = surfcap_testkit::shared_data() else { return };
        let head = data.join("leeperrysmith_head");
        let (topo, pos) = crate::texture_generator::read_uv_mesh(&head.join("template.obj")).unwrap();
        let tex = TextureImage::read(&head.join("Map-COL.jpg")).unwrap();
        let cams = cameras_around_mesh(&pos, [0.0, 1.0, 0.0], 8, 15.0, lens(96));
        let renders = render_views(&topo, &pos, &tex, &cams).unwrap();
        assert_eq!(renders.len(), 8);
        for (k, r) in renders.iter().enumerate() {
            let covered = r.mask.iter().filter(|&&m| m).count() as f64 / (96.0 * 96.0);
            // The whole head is in view (the border rows and columns stay background) and fills
            // a good part of it.
            assert!((0.08..0.8).contains(&covered), "camera {k}: {covered}");
            assert!((0..96).all(|i| !r.mask[i] && !r.mask[95 * 96 + i] && !r.mask[i * 96] && !r.mask[i * 96 + 95]));
            let mean = r.image.plane(0).iter().zip(&r.mask).filter(|(_, m)| **m).map(|(v, _)| *v as f64).sum::<f64>()
                / (covered * 96.0 * 96.0);
            assert!(mean > 60.0, "camera {k}: the skin texture shows, mean red {mean}");
        }
        // The front camera (k = 0 looks from +z, the face) and the back one see different things.
        let s = crate::image_similarity::ssim(&renders[0].image, &renders[4].image, &vec![true; 96 * 96]).unwrap();
        assert!(s < 0.9, "{s}");
    }

    #[test]
    fn a_mesh_without_uvs_is_refused() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let e = render(&topo, &[0.0; 9], &TextureImage::zeros(2, 2, 3), &front_camera(2.0, 8)).unwrap_err().to_string();
        assert!(e.contains("no texture coordinates"), "{e}");
    }
}
