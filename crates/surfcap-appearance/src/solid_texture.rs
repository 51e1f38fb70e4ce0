//! A texture painted from 3D positions: the base appearance of a subject that has an atlas but
//! no texture (the built-in mannequin). Every texel takes the colour of the
//! rest-pose surface point it shows (through [`AtlasRaster`]'s barycentrics), so the pattern is
//! continuous across the atlas's seams, as a painted body would be: horizontal bands of three
//! garment colours along the up axis, a coarse 3D checker, and two octaves of 3D value noise
//! (a hashed lattice, trilinearly interpolated) for the fine detail optical flow needs to lock
//! on. Deterministic: no random state, the same texture on every machine.

use rayon::prelude::*;

use crate::atlas_raster::AtlasRaster;
use crate::error::{Error, Result};
use crate::texture_image::TextureImage;

/// A hash of a lattice point to [0, 1).
fn lattice(x: i64, y: i64, z: i64) -> f32 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (z as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Value noise in [0, 1) at `p` (lattice spacing 1).
fn value_noise(p: [f32; 3]) -> f32 {
    let base = p.map(|c| c.floor());
    let f = [p[0] - base[0], p[1] - base[1], p[2] - base[2]].map(|t| t * t * (3.0 - 2.0 * t));
    let b = base.map(|c| c as i64);
    let mut acc = 0.0;
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let w: f32 = (0..3).map(|a| if o[a] == 1 { f[a] } else { 1.0 - f[a] }).product();
        acc += w * lattice(b[0] + o[0] as i64, b[1] + o[1] as i64, b[2] + o[2] as i64);
    }
    acc
}

/// What painting a `size` x `size` texture takes, estimated before any work: the atlas raster
/// and the surface point of every texel (about 40 bytes a texel), the texture (12) and its
/// PNG encoding (6); on disk the PNG, 3 bytes a texel at worst.
pub fn solid_texture_size(size: usize) -> surfcap_mesh::sizing::Estimate {
    use surfcap_mesh::sizing::bytes;
    surfcap_mesh::sizing::Estimate {
        what: format!("--size {size} ({size}x{size} texels)"),
        memory: bytes(&[size as f64, size as f64], 58),
        disk: bytes(&[size as f64, size as f64], 3),
        lower: "--size".into(),
    }
}

/// The texture of `raster`'s atlas painted from the rest positions `positions` ([vertices][3])
/// of the mesh whose `triangles` the atlas maps; `up` is the index of the up axis (0, 1 or 2).
/// Texels no triangle covers are mid grey.
pub fn solid_texture(
    raster: &AtlasRaster,
    triangles: &[[u32; 3]],
    positions: &[f32],
    up: usize,
) -> Result<TextureImage> {
    if up > 2 {
        return Err(Error::Invalid(format!("up axis index {up}: expected 0, 1 or 2")));
    }
    let nv = positions.len() / 3;
    if let Some((t, _)) = triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= nv)) {
        return Err(Error::Mismatch(format!("triangle {t} names a vertex beyond the {nv} positions")));
    }
    if raster.triangle.iter().any(|&t| t != crate::atlas_raster::NO_TRIANGLE && t as usize >= triangles.len()) {
        return Err(Error::Mismatch(format!("the atlas raster names triangles beyond the mesh's {}", triangles.len())));
    }
    let (lo, hi) = surfcap_mesh::bounding_box(positions);
    let size = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max).max(1e-6);
    let points = raster.interpolate(|t, c| {
        let v = triangles[t][c] as usize;
        [positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]]
    });
    let palette = [[178.0f32, 60.0, 52.0], [52.0, 92.0, 160.0], [222.0, 190.0, 150.0]];
    let colours: Vec<[f32; 3]> = points
        .par_iter()
        .map(|p| {
            let Some(p) = p else { return [128.0; 3] };
            let q = [(p[0] - lo[0]) / size, (p[1] - lo[1]) / size, (p[2] - lo[2]) / size];
            let band = ((q[up] * 6.0).floor() as usize) % 3;
            let checker = ((q[0] * 10.0).floor() + (q[1] * 10.0).floor() + (q[2] * 10.0).floor()) as i64 % 2 == 0;
            let detail = 0.6 * value_noise(q.map(|c| c * 40.0)) + 0.4 * value_noise(q.map(|c| c * 120.0));
            let shade = (if checker { 0.85 } else { 1.0 }) * (0.7 + 0.6 * detail);
            palette[band].map(|c| (c * shade).clamp(0.0, 255.0))
        })
        .collect();
    let n = raster.width * raster.height;
    let mut data = vec![0.0f32; 3 * n];
    for (i, c) in colours.iter().enumerate() {
        for k in 0..3 {
            data[k * n + i] = c[k];
        }
    }
    TextureImage::from_planes(raster.width, raster.height, 3, data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::UvAtlas;

    #[test]
    fn texels_of_one_surface_point_get_one_colour_across_charts() {
        // The same triangle mapped twice, into two charts: both charts show the same colours.
        let positions = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.3];
        let triangles = vec![[0, 1, 2], [0, 1, 2]];
        let atlas = UvAtlas {
            coords: vec![[0.0, 0.0], [0.5, 0.0], [0.0, 0.5], [0.5, 0.5], [1.0, 0.5], [0.5, 1.0]],
            corners: vec![[0, 1, 2], [3, 4, 5]],
        };
        let r = AtlasRaster::new(&atlas, 32, 32).unwrap();
        let t = solid_texture(&r, &triangles, &positions, 1).unwrap();
        // Texel (2, 29) of the first chart and texel (18, 13) of the second show one point.
        for c in 0..3 {
            assert!((t.get(c, 2, 29) - t.get(c, 18, 13)).abs() < 1e-3);
        }
        // Uncovered texels are grey, covered ones are not all equal (there is detail).
        assert_eq!(t.get(0, 31, 31), 128.0);
        let covered: Vec<f32> = (0..32 * 32).filter(|&i| r.covered(i)).map(|i| t.plane(0)[i]).collect();
        let (lo, hi) = covered.iter().fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        assert!(hi - lo > 10.0, "{lo}..{hi}");
    }
}
