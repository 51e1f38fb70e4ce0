//! The UV atlas rasterised into texture space: for every texel, the triangle whose UV image
//! covers the texel's centre and the barycentric coordinates of that centre. The active texels
//! of the thesis (4.4.2: "only pixels that fall inside active regions", the texels mapped to the
//! 3D model) are the covered ones ([`crate::TexelMask::from_atlas`]); the texture generator
//! uses the barycentrics to carry per-vertex normals and positions into the atlas.
//!
//! Texel (x, y) has its centre at u = (x + 0.5) / width, v = 1 - (y + 0.5) / height: row 0 of
//! the image is v = 1 (the OBJ convention, as the data README states for the head scan).

use rayon::prelude::*;
use surfcap_mesh::UvAtlas;

use crate::error::{Error, Result};

/// Marks a texel no triangle covers.
pub const NO_TRIANGLE: u32 = u32::MAX;

#[derive(Debug, Clone)]
pub struct AtlasRaster {
    pub width: usize,
    pub height: usize,
    /// Covering triangle per texel, or [`NO_TRIANGLE`].
    pub triangle: Vec<u32>,
    /// Barycentric coordinates of the texel centre in its triangle (zero where uncovered).
    pub barycentric: Vec<[f32; 3]>,
}

impl AtlasRaster {
    /// Rasterises every UV triangle of `atlas` at `width x height` texels. Where charts overlap
    /// (mirrored or stacked UVs) the triangle of lowest index wins, so the result does not
    /// depend on the thread count.
    pub fn new(atlas: &UvAtlas, width: usize, height: usize) -> Result<AtlasRaster> {
        if width == 0 || height == 0 {
            return Err(Error::Invalid(format!("an atlas raster needs a positive size, got {width}x{height}")));
        }
        for (t, corners) in atlas.corners.iter().enumerate() {
            for &c in corners {
                let Some(uv) = atlas.coords.get(c as usize) else {
                    return Err(Error::Invalid(format!(
                        "triangle {t}: texture coordinate {c} does not exist (the atlas has {})",
                        atlas.coords.len()
                    )));
                };
                if !uv[0].is_finite() || !uv[1].is_finite() {
                    return Err(Error::Invalid(format!("triangle {t}: texture coordinate {c} is not finite")));
                }
            }
        }
        // Bin triangles by the rows they span, then fill rows in parallel.
        let mut rows: Vec<Vec<u32>> = vec![Vec::new(); height];
        let texel = |uv: [f32; 2]| -> [f64; 2] {
            [uv[0] as f64 * width as f64 - 0.5, (1.0 - uv[1] as f64) * height as f64 - 0.5]
        };
        for (t, corners) in atlas.corners.iter().enumerate() {
            let ps = corners.map(|c| texel(atlas.coords[c as usize]));
            let y0 = ps.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min).ceil().max(0.0);
            let y1 = ps.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max).floor().min(height as f64 - 1.0);
            let mut y = y0;
            while y <= y1 {
                rows[y as usize].push(t as u32);
                y += 1.0;
            }
        }
        let mut triangle = vec![NO_TRIANGLE; width * height];
        let mut barycentric = vec![[0.0f32; 3]; width * height];
        triangle.par_chunks_mut(width).zip(barycentric.par_chunks_mut(width)).enumerate().for_each(
            |(y, (tri_row, bary_row))| {
                for &t in &rows[y] {
                    let ps = atlas.corners[t as usize].map(|c| texel(atlas.coords[c as usize]));
                    let area =
                        (ps[1][0] - ps[0][0]) * (ps[2][1] - ps[0][1]) - (ps[2][0] - ps[0][0]) * (ps[1][1] - ps[0][1]);
                    if area.abs() < 1e-12 {
                        continue;
                    }
                    let x0 = ps.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min).ceil().max(0.0) as usize;
                    let x1 = ps.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max).floor();
                    if x1 < 0.0 {
                        continue;
                    }
                    let x1 = (x1 as usize).min(width - 1);
                    let py = y as f64;
                    for x in x0..=x1 {
                        if tri_row[x] != NO_TRIANGLE && tri_row[x] < t {
                            continue;
                        }
                        let px = x as f64;
                        let edge = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1]);
                        let l0 = edge(ps[1], ps[2]) / area;
                        let l1 = edge(ps[2], ps[0]) / area;
                        let l2 = 1.0 - l0 - l1;
                        const EPS: f64 = -1e-9;
                        if l0 >= EPS && l1 >= EPS && l2 >= EPS {
                            tri_row[x] = t;
                            bary_row[x] = [l0 as f32, l1 as f32, l2 as f32];
                        }
                    }
                }
            },
        );
        Ok(AtlasRaster { width, height, triangle, barycentric })
    }

    /// Whether texel `i` (row-major) is covered.
    pub fn covered(&self, i: usize) -> bool {
        self.triangle[i] != NO_TRIANGLE
    }

    /// Interpolates a per-corner attribute at every covered texel (`None` elsewhere):
    /// `corner_value(triangle, corner)` gives the value at a corner.
    pub fn interpolate<const K: usize>(
        &self,
        corner_value: impl Fn(usize, usize) -> [f32; K] + Sync,
    ) -> Vec<Option<[f32; K]>> {
        self.triangle
            .par_iter()
            .zip(self.barycentric.par_iter())
            .map(|(&t, b)| {
                if t == NO_TRIANGLE {
                    return None;
                }
                let mut out = [0.0f32; K];
                for (corner, &w) in b.iter().enumerate() {
                    let v = corner_value(t as usize, corner);
                    for k in 0..K {
                        out[k] += w * v[k];
                    }
                }
                Some(out)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_atlas() -> UvAtlas {
        // Two triangles covering the lower-left quarter of UV space [0, 0.5]^2.
        UvAtlas { coords: vec![[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]], corners: vec![[0, 1, 2], [0, 2, 3]] }
    }

    #[test]
    fn the_lower_left_quarter_of_uv_is_the_bottom_left_of_the_image() {
        let r = AtlasRaster::new(&square_atlas(), 8, 8).unwrap();
        for y in 0..8 {
            for x in 0..8 {
                let expected = x < 4 && y >= 4;
                assert_eq!(r.covered(y * 8 + x), expected, "texel ({x}, {y})");
            }
        }
    }

    #[test]
    fn barycentrics_reproduce_the_texel_centre() {
        let atlas = square_atlas();
        let r = AtlasRaster::new(&atlas, 16, 16).unwrap();
        let uv = r.interpolate(|t, c| atlas.coords[atlas.corners[t][c] as usize]);
        for y in 0..16 {
            for x in 0..16 {
                if let Some(p) = uv[y * 16 + x] {
                    assert!((p[0] - (x as f32 + 0.5) / 16.0).abs() < 1e-5);
                    assert!((p[1] - (1.0 - (y as f32 + 0.5) / 16.0)).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn a_missing_texture_coordinate_is_named() {
        let atlas = UvAtlas { coords: vec![[0.0, 0.0]], corners: vec![[0, 0, 3]] };
        let e = AtlasRaster::new(&atlas, 4, 4).unwrap_err().to_string();
        assert!(e.contains("triangle 0: texture coordinate 3 does not exist"), "{e}");
    }
}
