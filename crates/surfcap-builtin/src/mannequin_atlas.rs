//! A UV atlas for the built-in mannequin, so it can carry a texture per frame (the built-in
//! mannequin with a generated texture per frame). The mannequin is a union of
//! capsules, so each bone gets a cylindrical chart: a triangle belongs to the bone nearest its
//! centroid (distance to the bone's segment minus its radius), and its corners are mapped to
//! (angle around the bone's axis, position along it). A triangle straddling the chart's angular
//! seam gets its small angles moved up by one turn, so no triangle spans the chart. Charts are
//! laid out in a square grid of equal cells with a margin, each scaled to fill its cell.
//! Caps are squeezed (a cylinder cannot flatten a hemisphere), which a texture made in the atlas
//! simply follows. Every corner has its own texture coordinate (seams everywhere between
//! charts), as scanned atlases have.

use nalgebra::{Point3, Vector3};
use surfcap_mesh::UvAtlas;

use crate::mannequin::Mannequin;

/// Distance from `p` to the segment [a, b].
fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-12)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// The atlas of `m` (one corner triple per triangle, in the topology's triangle order).
pub fn mannequin_uv_atlas(m: &Mannequin) -> UvAtlas {
    let bones = &m.skeleton.bones;
    let vertex = |i: u32| {
        let k = 3 * i as usize;
        Point3::new(m.positions[k] as f64, m.positions[k + 1] as f64, m.positions[k + 2] as f64)
    };
    let triangles = m.topology.triangles();
    // Chart (bone) of each triangle.
    let chart: Vec<usize> = triangles
        .iter()
        .map(|t| {
            let c = Point3::from((vertex(t[0]).coords + vertex(t[1]).coords + vertex(t[2]).coords) / 3.0);
            (0..bones.len())
                .min_by(|&x, &y| {
                    let dx = segment_distance(&c, &bones[x].a, &bones[x].b) - bones[x].radius;
                    let dy = segment_distance(&c, &bones[y].a, &bones[y].b) - bones[y].radius;
                    dx.total_cmp(&dy)
                })
                .expect("the mannequin has bones")
        })
        .collect();
    // Each bone's frame: axis d, perpendiculars e1, e2.
    let frames: Vec<(Vector3<f64>, Vector3<f64>, Vector3<f64>)> = bones
        .iter()
        .map(|b| {
            let d = (b.b - b.a).try_normalize(1e-12).unwrap_or(Vector3::y());
            let helper = if d.z.abs() < 0.9 { Vector3::z() } else { Vector3::x() };
            let e1 = helper.cross(&d).normalize();
            (d, e1, d.cross(&e1))
        })
        .collect();
    // Cylindrical coordinates per corner: (turns around the axis, length along it).
    let mut raw: Vec<[[f64; 2]; 3]> = triangles
        .iter()
        .zip(&chart)
        .map(|(t, &c)| {
            let (d, e1, e2) = frames[c];
            let a = bones[c].a;
            let mut uv = t.map(|v| {
                let p = vertex(v) - a;
                let turns = p.dot(&e2).atan2(p.dot(&e1)) / std::f64::consts::TAU + 0.5;
                [turns, p.dot(&d)]
            });
            let (lo, hi) = uv.iter().fold((f64::MAX, f64::MIN), |(l, h), q| (l.min(q[0]), h.max(q[0])));
            if hi - lo > 0.5 {
                for q in &mut uv {
                    if q[0] < 0.5 {
                        q[0] += 1.0;
                    }
                }
            }
            uv
        })
        .collect();
    // Each chart's extent, then its cell.
    let mut extent = vec![[f64::MAX, f64::MIN, f64::MAX, f64::MIN]; bones.len()];
    for (uv, &c) in raw.iter().zip(&chart) {
        for q in uv {
            let e = &mut extent[c];
            e[0] = e[0].min(q[0]);
            e[1] = e[1].max(q[0]);
            e[2] = e[2].min(q[1]);
            e[3] = e[3].max(q[1]);
        }
    }
    let grid = (bones.len() as f64).sqrt().ceil() as usize;
    let cell = 1.0 / grid as f64;
    let margin = 0.04 * cell;
    for (uv, &c) in raw.iter_mut().zip(&chart) {
        let e = extent[c];
        let (gx, gy) = ((c % grid) as f64, (c / grid) as f64);
        for q in uv.iter_mut() {
            let su = (q[0] - e[0]) / (e[1] - e[0]).max(1e-12);
            let sv = (q[1] - e[2]) / (e[3] - e[2]).max(1e-12);
            *q = [gx * cell + margin + su * (cell - 2.0 * margin), gy * cell + margin + sv * (cell - 2.0 * margin)];
        }
    }
    let coords: Vec<[f32; 2]> = raw.iter().flat_map(|uv| uv.map(|q| [q[0] as f32, q[1] as f32])).collect();
    let corners = (0..triangles.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    UvAtlas { coords, corners }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mannequin::{BodyShape, mannequin};

    #[test]
    fn every_triangle_lies_in_one_cell_with_positive_area() {
        let m = mannequin(&BodyShape::average(), 1500).unwrap();
        let atlas = mannequin_uv_atlas(&m);
        assert_eq!(atlas.corners.len(), m.topology.n_triangles());
        let grid = (m.skeleton.bones.len() as f32).sqrt().ceil();
        let mut degenerate = 0;
        for c in &atlas.corners {
            let q = c.map(|i| atlas.coords[i as usize]);
            for p in &q {
                assert!((0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]), "{p:?}");
            }
            let cells: Vec<(i32, i32)> = q.iter().map(|p| ((p[0] * grid) as i32, (p[1] * grid) as i32)).collect();
            assert!(cells.iter().all(|&x| x == cells[0]), "a triangle spans charts: {q:?}");
            let area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]);
            if area.abs() < 1e-9 {
                degenerate += 1;
            }
        }
        assert!(degenerate * 100 < atlas.corners.len(), "{degenerate} flat triangles");
    }
}
