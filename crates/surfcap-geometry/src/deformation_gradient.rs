//! Deformation gradients (thesis eq. 2.6): for each triangle, the 3x3 matrix J that maps pose
//! i's edge vectors and unit normal onto pose j's.
//!
//! Reading of eq. 2.6 (PAPER-NOTES): with the frames as matrix columns, A = (v1-v3, v2-v3, n)_i
//! and B = (v1-v3, v2-v3, n)_j, the printed A^-1 B is not the spatial deformation gradient; the
//! spatial one is J = B A^-1 (J A = B). We use J = B A^-1. Its polar factors have the same
//! rotation angle and the same ||S - I|| as those of J^T (the row reading), so eq. 2.13 is the
//! same for both readings of the spatial gradient.

use nalgebra::{Matrix3, Vector3};
use surfcap_mesh::Topology;

/// Position of vertex `k` as f64.
#[inline]
pub fn vertex(p: &[f32], k: u32) -> Vector3<f64> {
    let i = 3 * k as usize;
    Vector3::new(p[i] as f64, p[i + 1] as f64, p[i + 2] as f64)
}

/// The frame (v1 - v3, v2 - v3, n) of a triangle as matrix columns, with n the unit normal of
/// eq. 2.29; `None` for a zero-area triangle (the frame is singular there).
pub fn triangle_frame(p: &[f32], t: &[u32; 3]) -> Option<Matrix3<f64>> {
    let (v1, v2, v3) = (vertex(p, t[0]), vertex(p, t[1]), vertex(p, t[2]));
    let (e1, e2) = (v1 - v3, v2 - v3);
    let c = e1.cross(&e2);
    let len = c.norm();
    let scale = e1.norm_squared().max(e2.norm_squared());
    if len <= 1e-12 * scale || scale == 0.0 {
        return None;
    }
    Some(Matrix3::from_columns(&[e1, e2, c / len]))
}

/// J = B A^-1 for every triangle; zero-area triangles (in either pose) get `None`.
pub fn deformation_gradients(topology: &Topology, pi: &[f32], pj: &[f32]) -> Vec<Option<Matrix3<f64>>> {
    topology
        .triangles()
        .iter()
        .map(|t| {
            let a = triangle_frame(pi, t)?;
            let b = triangle_frame(pj, t)?;
            Some(b * a.try_inverse()?)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_edges_and_normal_and_is_identity_for_equal_poses() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let pi = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let pj = [0.0f32, 0.0, 1.0, 0.0, 2.0, 1.0, -1.0, 0.0, 1.0];
        let j = deformation_gradients(&topo, &pi, &pj)[0].unwrap();
        let (a, b) = (triangle_frame(&pi, &[0, 1, 2]).unwrap(), triangle_frame(&pj, &[0, 1, 2]).unwrap());
        assert!((j * a - b).norm() < 1e-12);
        let same = deformation_gradients(&topo, &pi, &pi)[0].unwrap();
        assert!((same - Matrix3::identity()).norm() < 1e-12);
        let flat = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0];
        assert!(deformation_gradients(&topo, &pi, &flat)[0].is_none());
    }
}
