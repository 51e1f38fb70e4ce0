//! Pose distances between two frames of one topology (thesis 2.3.2):
//! - Euclidean after motion-plane alignment (eq. 2.2);
//! - deformation-gradient distance (eq. 2.13): sum over triangles of the rotation angle of the
//!   polar factor R of J plus w ||S - I||_F, w = 0.01;
//! - its log-S variant (eq. 2.14): angle + w ||log S||_F. We read the 1/sqrt 2 of eq. 2.14 as
//!   applying to the rotation term only, as in eq. 2.13 (1/sqrt 2 ||log R||_F is the angle);
//!   scaling the S term as well would only rescale w.
//!
//! Before the deformation distances, pose j is rotated about the up axis onto pose i with
//! eq. 2.3 (end of 2.3.2: the metric is not rotation invariant); that rotation multiplies J on
//! the left and leaves S unchanged.
//!
//! Speed: J = B A^-1 maps triangle i's frame (e1, e2, n) onto triangle j's. Writing each frame
//! as an orthonormal basis Q = (t, b, n) times the upper-triangular 2x2 matrix of its edges in
//! that basis (plus 1 for the normal), J = G Q_j (m (+) 1) Q_i^T with m = a_j a_i^-1 upper
//! triangular 2x2. Its polar factors are R = G Q_j (r (+) 1) Q_i^T and S = Q_i (s (+) 1) Q_i^T
//! where m = r s is the 2x2 polar decomposition, which has a closed form. So each triangle pair
//! costs a few dot products and one acos instead of a 3x3 SVD, with the same result (checked
//! against the SVD route in the tests). Zero-area triangles (in either pose) have no
//! deformation gradient: they are skipped and counted.

use nalgebra::Matrix3;
use surfcap_mesh::Topology;

use crate::deformation_gradient::vertex;

/// Which pose distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseMetric {
    /// eq. 2.2: residual of the motion-plane alignment.
    Euclidean,
    /// eq. 2.13.
    Deformation,
    /// eq. 2.14.
    DeformationLog,
}

impl PoseMetric {
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "euclidean" => PoseMetric::Euclidean,
            "deformation" => PoseMetric::Deformation,
            "deformation-log" => PoseMetric::DeformationLog,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            PoseMetric::Euclidean => "euclidean",
            PoseMetric::Deformation => "deformation",
            PoseMetric::DeformationLog => "deformation-log",
        }
    }
}

/// Floats stored per triangle and frame: t, b, n (9), edge coordinates a11, a12, a22 (3) and
/// the inverse's 1/a11, -a12/(a11 a22), 1/a22 (3). Zero-area triangles store zeros.
pub const FRAME_FLOATS: usize = 15;

/// Per-frame precomputation for the deformation distances (the expensive part is per pair).
/// Stored in f64: the rotation angle comes from acos of a trace near 3 for similar poses, and
/// f32 frames would put a noise floor of ~5e-4 rad on every triangle.
pub fn triangle_frames(topology: &Topology, p: &[f32], out: &mut Vec<f64>) {
    out.clear();
    out.reserve(topology.n_triangles() * FRAME_FLOATS);
    for t in topology.triangles() {
        let (v1, v2, v3) = (vertex(p, t[0]), vertex(p, t[1]), vertex(p, t[2]));
        let (e1, e2) = (v1 - v3, v2 - v3);
        let c = e1.cross(&e2);
        let (len1, area2) = (e1.norm(), c.norm());
        let scale = e1.norm_squared().max(e2.norm_squared());
        if area2 <= 1e-12 * scale || len1 == 0.0 {
            out.extend_from_slice(&[0.0; FRAME_FLOATS]);
            continue;
        }
        let tt = e1 / len1;
        let n = c / area2;
        let b = n.cross(&tt);
        let (a11, a12, a22) = (len1, e2.dot(&tt), e2.dot(&b));
        let inv = [1.0 / a11, -a12 / (a11 * a22), 1.0 / a22];
        for v in [tt.x, tt.y, tt.z, b.x, b.y, b.z, n.x, n.y, n.z, a11, a12, a22, inv[0], inv[1], inv[2]] {
            out.push(v);
        }
    }
}

/// Clears the upper halves of the vector registers (`vzeroupper`) when the CPU has AVX.
///
/// The loop below is SSE code that calls libm's `acos` (VEX-encoded on FMA machines). Measured
/// on this project's 2-core Xeon: after wide AVX-512 kernels (faer's GEMM) had run on a thread,
/// the loop ran 5-6 times slower on that thread (the penalty showed at the `acos` call and
/// return), and clearing the state first restored the speed.
#[inline]
fn clear_upper_vector_state() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: `vzeroupper` only requires AVX, checked at run time just above.
            unsafe { zeroupper() }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn zeroupper() {
    std::arch::x86_64::_mm256_zeroupper();
}

/// Sum over triangles of the per-triangle deformation cost from frame i to frame j, where `g`
/// is the rotation about the up axis that aligns pose j onto pose i. Returns the distance and
/// the number of triangles skipped because they have zero area in either frame.
pub fn deformation_distance(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> (f64, usize) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the features the function is compiled for were detected just above.
            return unsafe { deformation_distance_avx2(fi, fj, g, w, log_s) };
        }
    }
    clear_upper_vector_state();
    deformation_distance_body(fi, fj, g, w, log_s)
}

/// The same loop compiled for AVX2 + FMA (VEX encodings throughout: no SSE/AVX transitions
/// around libm's FMA `acos`, and fused multiply-adds in the dot products).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn deformation_distance_avx2(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> (f64, usize) {
    deformation_distance_body(fi, fj, g, w, log_s)
}

#[inline(always)]
fn deformation_distance_body(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> (f64, usize) {
    let gm = [g[(0, 0)], g[(0, 1)], g[(0, 2)], g[(1, 0)], g[(1, 1)], g[(1, 2)], g[(2, 0)], g[(2, 1)], g[(2, 2)]];
    let rot = |x: f64, y: f64, z: f64| {
        [gm[0] * x + gm[1] * y + gm[2] * z, gm[3] * x + gm[4] * y + gm[5] * z, gm[6] * x + gm[7] * y + gm[8] * z]
    };
    let mut total = 0.0f64;
    let mut skipped = 0usize;
    for (a, b) in fi.chunks_exact(FRAME_FLOATS).zip(fj.chunks_exact(FRAME_FLOATS)) {
        let a = |k: usize| a[k];
        let b = |k: usize| b[k];
        if a(11) == 0.0 || b(11) == 0.0 {
            skipped += 1;
            continue;
        }
        // m = a_j a_i^-1, upper triangular [[p, q], [0, t]].
        let p = b(9) * a(12);
        let q = b(9) * a(13) + b(10) * a(14);
        let t = b(11) * a(14);
        let h = ((p + t) * (p + t) + q * q).sqrt();
        let (cphi, sphi) = ((p + t) / h, -q / h);
        let gt = rot(b(0), b(1), b(2));
        let gb = rot(b(3), b(4), b(5));
        let gn = rot(b(6), b(7), b(8));
        let dot = |u: usize, v: &[f64; 3]| a(u) * v[0] + a(u + 1) * v[1] + a(u + 2) * v[2];
        let p00_p11 = dot(0, &gt) + dot(3, &gb);
        let p01_p10 = dot(0, &gb) - dot(3, &gt);
        let p22 = dot(6, &gn);
        let trace = cphi * p00_p11 + sphi * p01_p10 + p22;
        let angle = (0.5 * (trace - 1.0)).clamp(-1.0, 1.0).acos();
        let stretch = if log_s {
            // Singular values of m: roots of x^2 - h x + p t.
            let disc = (h * h - 4.0 * p * t).max(0.0).sqrt();
            let (s1, s2) = (0.5 * (h + disc), (0.5 * (h - disc)).max(f64::MIN_POSITIVE));
            (s1.ln().powi(2) + s2.ln().powi(2)).sqrt()
        } else {
            (p * p + q * q + t * t - 2.0 * h + 2.0).max(0.0).sqrt()
        };
        total += angle + w * stretch;
    }
    (total, skipped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deformation_gradient::deformation_gradients;
    use crate::polar_decomposition::polar_decomposition;
    use crate::rotation_log_exp::{exp_rotation, log_rotation, rotation_angle};
    use nalgebra::Vector3;

    /// The SVD route, written as the thesis does, for reference.
    fn reference(topo: &Topology, pi: &[f32], pj: &[f32], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
        deformation_gradients(topo, pi, pj)
            .into_iter()
            .flatten()
            .map(|j| {
                let (r, s) = polar_decomposition(&(g * j));
                let stretch = if log_s {
                    let e = s.symmetric_eigen();
                    e.eigenvalues.map(|x| x.ln().powi(2)).sum().sqrt()
                } else {
                    (s - Matrix3::identity()).norm()
                };
                rotation_angle(&r) + w * stretch
            })
            .sum()
    }

    fn lcg(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 33) as f32 / (1u64 << 31) as f32) - 0.5
    }

    #[test]
    fn closed_form_matches_the_svd_route() {
        let mut seed = 7u64;
        let n = 30usize;
        let tris: Vec<[u32; 3]> = (0..n as u32 / 3).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let topo = Topology::new(n, tris, None).unwrap();
        let pi: Vec<f32> = (0..3 * n).map(|_| lcg(&mut seed)).collect();
        let r = exp_rotation(&Vector3::new(0.3, 2.9, -0.4));
        let pj: Vec<f32> = pi
            .chunks(3)
            .flat_map(|v| {
                let x = r * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                [x.x as f32 + 0.3 * lcg(&mut seed), x.y as f32 + 0.3 * lcg(&mut seed), x.z as f32]
            })
            .collect();
        let g = exp_rotation(&Vector3::new(0.0, 0.7, 0.0));
        let (mut fi, mut fj) = (Vec::new(), Vec::new());
        triangle_frames(&topo, &pi, &mut fi);
        triangle_frames(&topo, &pj, &mut fj);
        for log_s in [false, true] {
            let (fast, skipped) = deformation_distance(&fi, &fj, &g, 0.01, log_s);
            // The portable loop and the AVX2 one (when this machine has it) agree.
            let (portable, _) = deformation_distance_body(&fi, &fj, &g, 0.01, log_s);
            assert!((fast - portable).abs() < 1e-12 * fast.max(1.0), "{fast} vs {portable}");
            let slow = reference(&topo, &pi, &pj, &g, 0.01, log_s);
            assert_eq!(skipped, 0);
            assert!((fast - slow).abs() < 1e-4 * slow.max(1.0), "log_s={log_s}: {fast} vs {slow}");
        }
        let (zero, _) = deformation_distance(&fi, &fi, &Matrix3::identity(), 0.01, false);
        assert!(zero < 1e-6, "{zero}");
        let _ = log_rotation(&r);
    }
}
