//! The surface carried into texture space: per-texel unit normal and 3-D position, from the
//! mesh's area-weighted vertex normals and its positions interpolated with the barycentrics of
//! the [`AtlasRaster`]. The texture generator shades texels by these normals (low-frequency
//! illumination) and cuts occlusion holes by these positions.
//!
//! Texels just outside the charts (the rings a [`crate::TexelMask`] dilation adds, which a
//! renderer's bilinear lookup reads) get the mean of their already-defined 8-neighbours, one
//! ring at a time, each ring reading only the previous one (so the result does not depend on
//! the thread count).

use rayon::prelude::*;
use surfcap_mesh::Topology;

use crate::atlas_raster::{AtlasRaster, NO_TRIANGLE};
use crate::error::{Error, Result};

/// Per-texel normal and position (row-major), defined on the covered texels and `dilation`
/// rings around them.
#[derive(Debug, Clone, PartialEq)]
pub struct AtlasGeometry {
    pub width: usize,
    pub height: usize,
    /// Unit normal per texel (zero where undefined).
    pub normal: Vec<[f32; 3]>,
    /// Surface point per texel (zero where undefined).
    pub position: Vec<[f32; 3]>,
    /// Whether the texel has a normal and a position.
    pub defined: Vec<bool>,
}

/// Area-weighted vertex normals (the sum of the incident triangles' cross products,
/// normalised); a vertex of only degenerate triangles gets the zero vector, which shading
/// treats as facing no light.
pub fn vertex_normals(topology: &Topology, positions: &[f32]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; topology.n_vertices()];
    let p = |v: u32| {
        let i = v as usize * 3;
        [positions[i] as f64, positions[i + 1] as f64, positions[i + 2] as f64]
    };
    for t in topology.triangles() {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        for &v in t {
            for k in 0..3 {
                acc[v as usize][k] += n[k];
            }
        }
    }
    acc.iter().map(|n| normalised(*n)).collect()
}

fn normalised(n: [f64; 3]) -> [f32; 3] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 && l.is_finite() { [(n[0] / l) as f32, (n[1] / l) as f32, (n[2] / l) as f32] } else { [0.0; 3] }
}

impl AtlasGeometry {
    /// Normals and positions of `topology` at `positions` ([vertices][3]) on the texels of
    /// `raster`, grown by `dilation` rings.
    pub fn new(raster: &AtlasRaster, topology: &Topology, positions: &[f32], dilation: usize) -> Result<AtlasGeometry> {
        if positions.len() != 3 * topology.n_vertices() {
            return Err(Error::Mismatch(format!(
                "{} position values for a mesh of {} vertices",
                positions.len(),
                topology.n_vertices()
            )));
        }
        if raster.triangle.iter().any(|&t| t != NO_TRIANGLE && t as usize >= topology.n_triangles()) {
            return Err(Error::Mismatch("the atlas raster names a triangle the mesh does not have".into()));
        }
        let vn = vertex_normals(topology, positions);
        let tris = topology.triangles();
        let normal_opt = raster.interpolate(|t, c| vn[tris[t][c] as usize]);
        let position_opt = raster.interpolate(|t, c| {
            let i = tris[t][c] as usize * 3;
            [positions[i], positions[i + 1], positions[i + 2]]
        });
        let (w, h) = (raster.width, raster.height);
        let mut defined: Vec<bool> = normal_opt.iter().map(|n| n.is_some()).collect();
        let mut normal: Vec<[f32; 3]> =
            normal_opt.iter().map(|n| n.map(|n| normalised(n.map(|v| v as f64))).unwrap_or([0.0; 3])).collect();
        let mut position: Vec<[f32; 3]> = position_opt.iter().map(|p| p.unwrap_or([0.0; 3])).collect();
        for _ in 0..dilation {
            let (pd, pn, pp) = (defined.clone(), normal.clone(), position.clone());
            let grown: Vec<Option<([f32; 3], [f32; 3])>> = (0..w * h)
                .into_par_iter()
                .map(|i| {
                    if pd[i] {
                        return None;
                    }
                    let (x, y) = (i % w, i / w);
                    let (mut n, mut p, mut count) = ([0.0f64; 3], [0.0f64; 3], 0usize);
                    for yy in y.saturating_sub(1)..(y + 2).min(h) {
                        for xx in x.saturating_sub(1)..(x + 2).min(w) {
                            let j = yy * w + xx;
                            if pd[j] {
                                for k in 0..3 {
                                    n[k] += pn[j][k] as f64;
                                    p[k] += pp[j][k] as f64;
                                }
                                count += 1;
                            }
                        }
                    }
                    (count > 0).then(|| (normalised(n), p.map(|v| (v / count as f64) as f32)))
                })
                .collect();
            for (i, g) in grown.into_iter().enumerate() {
                if let Some((n, p)) = g {
                    defined[i] = true;
                    normal[i] = n;
                    position[i] = p;
                }
            }
        }
        Ok(AtlasGeometry { width: w, height: h, normal, position, defined })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::UvAtlas;

    #[test]
    fn a_flat_square_has_its_plane_normal_and_positions_everywhere_it_is_mapped() {
        // The square z = 0, [0, 2]^2, mapped onto the lower-left quarter of UV space.
        let positions = vec![0.0f32, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 2.0, 0.0, 0.0, 2.0, 0.0];
        let atlas = UvAtlas {
            coords: vec![[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
            corners: vec![[0, 1, 2], [0, 2, 3]],
        };
        let topo = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], Some(atlas)).unwrap();
        let raster = AtlasRaster::new(topo.uv().unwrap(), 16, 16).unwrap();
        let g = AtlasGeometry::new(&raster, &topo, &positions, 1).unwrap();
        let mut n_defined = 0;
        for y in 0..16 {
            for x in 0..16 {
                let i = y * 16 + x;
                if raster.covered(i) {
                    assert_eq!(g.normal[i], [0.0, 0.0, 1.0]);
                    // Texel centre u = (x + 0.5) / 16 in [0, 0.5] -> X = 4 u; v likewise.
                    let ex = 4.0 * (x as f32 + 0.5) / 16.0;
                    let ey = 4.0 * (1.0 - (y as f32 + 0.5) / 16.0);
                    assert!((g.position[i][0] - ex).abs() < 1e-5 && (g.position[i][1] - ey).abs() < 1e-5);
                }
                if g.defined[i] {
                    n_defined += 1;
                    assert_eq!(g.normal[i], [0.0, 0.0, 1.0], "texel ({x}, {y})");
                }
            }
        }
        assert_eq!(n_defined, 81, "the 8x8 covered quarter grown by one ring");
    }
}
