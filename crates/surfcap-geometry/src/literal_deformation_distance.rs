//! The deformation distance of eq. 2.13 (and eq. 2.14's log-S form) with eq. 2.6 read
//! literally, offered to show what that reading changes (`surfcap eval pose-metric
//! --deformation-gradient literal`, the metric `deformation-literal`).
//!
//! Eq. 2.6 is printed T = (v1 - v3, v2 - v3, n)_i^-1 (v1 - v3, v2 - v3, n)_j. With the vectors
//! as matrix columns A (pose i) and B (pose j), that is T = A^-1 B, not the spatial deformation
//! gradient J = B A^-1 that surfcap uses (PAPER-NOTES on eq. 2.6; `deformation_gradient`).
//! Here, per triangle, T = A^-1 (G B), G the rotation about the up axis that aligns pose j onto
//! pose i (as for surfcap's reading), then T = R S by the polar decomposition and the cost
//! angle(R) + w ||S - I||_F (eq. 2.13; with `log_s`, w ||log S||_F, eq. 2.14).
//!
//! A and B are rebuilt from a frame's stored fields ([`crate::pose_distance::triangle_frames`]):
//! A = Q (a (+) 1) with Q = (t, b, n) and a the upper-triangular 2x2 of the edges in that basis,
//! so T = (a_i (+) 1)^-1 Q_i^T G Q_j (a_j (+) 1). Unlike J, T has no closed-form polar factors,
//! so each triangle pair costs a 3x3 SVD; zero-area triangles (in either pose) are skipped, as
//! for surfcap's reading.

use nalgebra::Matrix3;

use crate::polar_decomposition::polar_decomposition;
use crate::pose_distance::{BLOCK, BLOCK_FLOATS};
use crate::rotation_log_exp::rotation_angle;

/// Sum over triangles of the eq. 2.13 cost (eq. 2.14's with `log_s`) of T = A_i^-1 (G B_j).
/// `fi`, `fj` are whole storage blocks of `triangle_frames` (the same blocks of both frames);
/// `g` rotates pose j onto pose i about the up axis.
pub fn literal_deformation_distance(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
    let mut total = 0.0;
    for (a, b) in fi.chunks_exact(BLOCK_FLOATS).zip(fj.chunks_exact(BLOCK_FLOATS)) {
        let field = |s: &[f64], f: usize, k: usize| s[f * BLOCK + k];
        for k in 0..BLOCK {
            if field(a, 11, k) == 0.0 || field(b, 11, k) == 0.0 {
                continue;
            }
            let q = |s: &[f64]| {
                Matrix3::new(
                    field(s, 0, k),
                    field(s, 3, k),
                    field(s, 6, k),
                    field(s, 1, k),
                    field(s, 4, k),
                    field(s, 7, k),
                    field(s, 2, k),
                    field(s, 5, k),
                    field(s, 8, k),
                )
            };
            let (qi, qj) = (q(a), q(b));
            let edges_j = Matrix3::new(field(b, 9, k), field(b, 10, k), 0.0, 0.0, field(b, 11, k), 0.0, 0.0, 0.0, 1.0);
            // (a_i (+) 1)^-1 from the stored inverse: [[1/a11, -a12/(a11 a22)], [0, 1/a22]].
            let edges_i_inv =
                Matrix3::new(field(a, 12, k), field(a, 13, k), 0.0, 0.0, field(a, 14, k), 0.0, 0.0, 0.0, 1.0);
            let t = edges_i_inv * qi.transpose() * g * qj * edges_j;
            let (r, s) = polar_decomposition(&t);
            let stretch = if log_s {
                s.symmetric_eigen().eigenvalues.map(|x| x.abs().max(f64::MIN_POSITIVE).ln().powi(2)).sum().sqrt()
            } else {
                (s - Matrix3::identity()).norm()
            };
            total += rotation_angle(&r) + w * stretch;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deformation_gradient::triangle_frame;
    use crate::motion_plane_alignment::rotation_about_up;
    use crate::pose_distance::triangle_frames;
    use surfcap_mesh::UpAxis;

    fn lcg(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 33) as f32 / (1u64 << 31) as f32) - 0.5
    }

    /// The stored fields give the same T as the printed formula on the triangles' own frames,
    /// and the reading differs from surfcap's J = B A^-1 where the triangles stretch.
    #[test]
    fn matches_the_printed_formula_and_differs_from_the_spatial_gradient() {
        let mut seed = 7u64;
        let tris: Vec<[u32; 3]> = (0..70).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let pi: Vec<f32> = (0..70 * 9).map(|_| lcg(&mut seed)).collect();
        let pj: Vec<f32> = pi.iter().map(|x| x * 1.3 + 0.1 * lcg(&mut seed)).collect();
        let g = rotation_about_up(UpAxis::PosY, 0.4);
        let (mut fi, mut fj) = (Vec::new(), Vec::new());
        triangle_frames(&tris, &pi, &mut fi);
        triangle_frames(&tris, &pj, &mut fj);
        let w = 0.01;
        let mut printed = 0.0;
        let mut spatial = 0.0;
        for t in &tris {
            let (Some(a), Some(b)) = (triangle_frame(&pi, t), triangle_frame(&pj, t)) else { continue };
            let lit = a.try_inverse().unwrap() * g * b;
            let (r, s) = polar_decomposition(&lit);
            printed += rotation_angle(&r) + w * (s - Matrix3::identity()).norm();
            let (r, s) = polar_decomposition(&(g * b * a.try_inverse().unwrap()));
            spatial += rotation_angle(&r) + w * (s - Matrix3::identity()).norm();
        }
        let ours = literal_deformation_distance(&fi, &fj, &g, w, false);
        assert!((ours - printed).abs() <= 1e-9 * printed.abs().max(1.0), "{ours} vs {printed}");
        assert!((ours - spatial).abs() > 1e-3 * spatial, "the readings agree: {ours} vs {spatial}");
        // The same pose at the same orientation costs nothing; the log form is finite.
        assert!(literal_deformation_distance(&fi, &fi, &Matrix3::identity(), w, false).abs() < 1e-9);
        assert!(literal_deformation_distance(&fi, &fj, &g, w, true).is_finite());
    }
}
