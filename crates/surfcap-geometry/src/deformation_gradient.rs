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

/// Orthonormal basis (t, b, n) of a triangle (t along v1 - v3) and its edges v1 - v3, v2 - v3 in
/// that basis as the upper-triangular [[a11, a12], [0, a22]]; `None` for a zero-area triangle.
fn triangle_basis(p: &[f32], t: &[u32; 3]) -> Option<(Matrix3<f64>, [f64; 3])> {
    let (v1, v2, v3) = (vertex(p, t[0]), vertex(p, t[1]), vertex(p, t[2]));
    let (e1, e2) = (v1 - v3, v2 - v3);
    let c = e1.cross(&e2);
    let (len1, area2) = (e1.norm(), c.norm());
    if area2 <= 1e-12 * e1.norm_squared().max(e2.norm_squared()) || len1 == 0.0 {
        return None;
    }
    let tt = e1 / len1;
    let n = c / area2;
    let b = n.cross(&tt);
    Some((Matrix3::from_columns(&[tt, b, n]), [len1, e2.dot(&tt), e2.dot(&b)]))
}

/// Polar factors (R, S) of every triangle's deformation gradient J = B A^-1, in closed form:
/// with each frame written as an orthonormal basis Q times an upper-triangular 2x2 edge matrix
/// (plus 1 for the normal), J = Q_j (m (+) 1) Q_i^T with m = a_j a_i^-1, so R = Q_j (r (+) 1) Q_i^T
/// and S = Q_i (s (+) 1) Q_i^T where m = r s is the 2x2 polar decomposition (rotation angle
/// atan2(m21 - m12, m11 + m22)). The same factors as [`polar_decomposition`] of J (tested), without
/// a 3x3 SVD per triangle. `None` for zero-area triangles.
///
/// [`polar_decomposition`]: crate::polar_decomposition::polar_decomposition
pub fn deformation_polar_factors(
    topology: &Topology,
    pi: &[f32],
    pj: &[f32],
) -> Vec<Option<(Matrix3<f64>, Matrix3<f64>)>> {
    topology.triangles().iter().map(|t| triangle_polar_factors(pi, pj, t)).collect()
}

/// [`deformation_polar_factors`] of one triangle `t`: (R, S) of its deformation gradient from
/// pose `pi` to pose `pj`; `None` when it has zero area in either.
pub fn triangle_polar_factors(pi: &[f32], pj: &[f32], t: &[u32; 3]) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let (qi, a) = triangle_basis(pi, t)?;
    let (qj, b) = triangle_basis(pj, t)?;
    // m = b a^-1 for upper-triangular a = [[a0, a1], [0, a2]], b likewise.
    let (p, q, u) = (b[0] / a[0], (b[1] - b[0] * a[1] / a[0]) / a[2], b[2] / a[2]);
    let h = ((p + u) * (p + u) + q * q).sqrt();
    let (c, s) = ((p + u) / h, -q / h);
    let r2 = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    // s2 = r2^T m (symmetric positive 2x2), in the i basis.
    let m = Matrix3::new(p, q, 0.0, 0.0, u, 0.0, 0.0, 0.0, 1.0);
    let mut s2 = r2.transpose() * m;
    let off = 0.5 * (s2[(0, 1)] + s2[(1, 0)]);
    s2[(0, 1)] = off;
    s2[(1, 0)] = off;
    Some((qj * r2 * qi.transpose(), qi * s2 * qi.transpose()))
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
        // The closed-form polar factors equal the SVD route's.
        let (r, s) = deformation_polar_factors(&topo, &pi, &pj)[0].unwrap();
        let (r0, s0) = crate::polar_decomposition::polar_decomposition(&j);
        assert!((r - r0).norm() < 1e-12 && (s - s0).norm() < 1e-12, "{r} {r0} {s} {s0}");
        assert!((r * s - j).norm() < 1e-12);
    }
}
