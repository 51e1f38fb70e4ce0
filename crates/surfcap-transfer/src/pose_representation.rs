//! Shape pose representation (thesis 5.4, eq. 5.1-5.3; CVPR 2017 sec. 4.1-4.3): every pose
//! Procrustes-aligned to the subject's reference pose, the rigid displacement from the
//! previous frame as a 6-vector, and per-part PCA coefficients of the aligned pose.
//!
//! - **Alignment** (5.4.1): rotation + translation (no scale) minimising the squared vertex
//!   distances to the reference (Kabsch). The placement kept per frame maps the aligned pose
//!   back to the world: `world = R aligned + t`.
//! - **Rigid displacement** (eq. 5.3): `dR = R_{i-1}^T R_i`, `dT = R_{i-1}^T (t_i - t_{i-1})`,
//!   i.e. the motion from the previous frame expressed in that frame's body coordinates (so it
//!   does not depend on which way the subject faces), encoded as `(dT, log dR)`. The thesis
//!   takes `dR ~ I + H^` (eq. 5.2, small-angle); we use the exact log and exp maps
//!   (PAPER-NOTES), which matters for fast turns at low frame rates: at 30 degrees per frame
//!   the small-angle form is off by 4.5% in angle and is not a rotation. The first frame of a
//!   sequence has no previous frame: its displacement is zero.
//! - **Parts and PCA** (5.4.2-5.4.3): each part's vertices of the aligned pose, PCA with `m`
//!   components (20 in the thesis). The thesis says the part sub-meshes are "first rigidly
//!   aligned"; we keep them in the body frame given by the whole-body alignment instead of
//!   aligning each part on its own. Aligning every part separately would throw away where a
//!   limb points relative to the torso, and the reconstruction would then have to recover
//!   it from the overlap band alone (a few rings at the shoulder), which is fragile; in the
//!   body frame the PCA keeps it, and the stitching (5.6.2) still aligns each child to its
//!   parent over the overlap, as the thesis does.

use faer::Mat;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use surfcap_geometry::motion_plane_alignment::procrustes;
use surfcap_geometry::rotation_log_exp::{exp_rotation, log_rotation};
use surfcap_learn::pca::{Pca, PcaMethod};

use crate::body_parts::BodyParts;
use crate::error::{Error, Result};

/// Where an aligned pose is in the world: `world = rotation * aligned + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
}

impl Placement {
    pub fn identity() -> Placement {
        Placement { rotation: Matrix3::identity(), translation: Vector3::zeros() }
    }

    /// The aligned pose moved into the world.
    pub fn apply(&self, aligned: &[f32]) -> Vec<f32> {
        aligned
            .chunks_exact(3)
            .flat_map(|p| {
                let q = self.rotation * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) + self.translation;
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect()
    }

    /// The rigid displacement from `self` (previous frame) to `next`, eq. 5.3 with the exact log.
    pub fn displacement_to(&self, next: &Placement) -> [f64; 6] {
        let dr = self.rotation.transpose() * next.rotation;
        let dt = self.rotation.transpose() * (next.translation - self.translation);
        let h = log_rotation(&dr);
        [dt.x, dt.y, dt.z, h.x, h.y, h.z]
    }

    /// The placement after the displacement `d` (the inverse of [`Placement::displacement_to`]).
    pub fn moved_by(&self, d: &[f64; 6]) -> Placement {
        let dr = exp_rotation(&Vector3::new(d[3], d[4], d[5]));
        Placement {
            rotation: self.rotation * dr,
            translation: self.translation + self.rotation * Vector3::new(d[0], d[1], d[2]),
        }
    }
}

/// RMS per-vertex distance between `pred` and `truth` after aligning `truth` onto `pred`
/// (rotation + translation, [`align_to_reference`]): the error a transfer is judged by.
pub fn aligned_rms(pred: &[f32], truth: &[f32]) -> f64 {
    let (aligned, _) = align_to_reference(pred, truth);
    let s: f64 = pred.iter().zip(&aligned).map(|(a, b)| ((a - b) as f64).powi(2)).sum();
    (s / (pred.len() / 3).max(1) as f64).sqrt()
}

/// `pose` rigidly aligned onto `reference` (Kabsch, no scale), with the placement that maps
/// it back.
pub fn align_to_reference(reference: &[f32], pose: &[f32]) -> (Vec<f32>, Placement) {
    // procrustes gives reference ~ R pose + t.
    let (r, t, _) = procrustes(reference, pose, None, false);
    let forward = Placement { rotation: r, translation: t };
    let aligned = forward.apply(pose);
    let back = Placement { rotation: r.transpose(), translation: -(r.transpose() * t) };
    (aligned, back)
}

/// One sequence in the pose representation.
#[derive(Debug, Clone)]
pub struct AlignedMotion {
    /// Each frame aligned onto the reference.
    pub aligned: Vec<Vec<f32>>,
    /// Each frame's placement (`world = R aligned + t`).
    pub placements: Vec<Placement>,
    /// The rigid displacement from the previous frame (zero for the first), eq. 5.3.
    pub displacements: Vec<[f64; 6]>,
}

/// Aligns every frame of one sequence (frames in order) onto `reference`.
pub fn align_motion(reference: &[f32], frames: &[&[f32]]) -> AlignedMotion {
    let (aligned, placements): (Vec<Vec<f32>>, Vec<Placement>) =
        frames.par_iter().map(|f| align_to_reference(reference, f)).unzip();
    let displacements = (0..placements.len())
        .map(|i| if i == 0 { [0.0; 6] } else { placements[i - 1].displacement_to(&placements[i]) })
        .collect();
    AlignedMotion { aligned, placements, displacements }
}

/// Per-part PCA of a subject's aligned poses (5.4.3).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PartSpace {
    /// One PCA per part, in the parts' order.
    pub pcas: Vec<Pca>,
    /// The vertices of each part (copied from the parts so the space stands alone).
    pub part_vertices: Vec<Vec<u32>>,
}

impl PartSpace {
    /// Fits `m` components per part (capped at the number of poses minus one) to `poses`
    /// (aligned, whole template).
    pub fn fit(parts: &BodyParts, poses: &[&[f32]], m: usize) -> Result<PartSpace> {
        if poses.len() < 2 {
            return Err(Error::Invalid(format!("{} training poses: expected at least 2 for PCA", poses.len())));
        }
        let nv = parts.n_vertices;
        if let Some(bad) = poses.iter().position(|p| p.len() != 3 * nv) {
            return Err(Error::Invalid(format!(
                "training pose {bad} has {} vertices: expected {nv} (the parts' template)",
                poses[bad].len() / 3
            )));
        }
        let pcas = parts
            .parts
            .par_iter()
            .map(|part| {
                let d = 3 * part.vertices.len();
                let y = Mat::from_fn(poses.len(), d, |i, j| poses[i][3 * part.vertices[j / 3] as usize + j % 3] as f64);
                Pca::fit(y.as_ref(), m, PcaMethod::Auto)
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        Ok(PartSpace { pcas, part_vertices: parts.parts.iter().map(|p| p.vertices.clone()).collect() })
    }

    pub fn n_parts(&self) -> usize {
        self.pcas.len()
    }

    /// Components of part `k`.
    pub fn dimension(&self, k: usize) -> usize {
        self.pcas[k].n_components()
    }

    /// Part `k` of an aligned pose (`[vertices of the part][3]`, as f64).
    pub fn part_values(&self, k: usize, aligned: &[f32]) -> Vec<f64> {
        self.part_vertices[k].iter().flat_map(|&v| (0..3).map(move |c| aligned[3 * v as usize + c] as f64)).collect()
    }

    /// PCA coefficients of part `k` for each pose (rows).
    pub fn encode(&self, k: usize, poses: &[&[f32]]) -> Result<Mat<f64>> {
        let d = 3 * self.part_vertices[k].len();
        let rows: Vec<Vec<f64>> = poses.iter().map(|p| self.part_values(k, p)).collect();
        let y = Mat::from_fn(poses.len(), d, |i, j| rows[i][j]);
        Ok(self.pcas[k].project(y.as_ref())?)
    }

    /// Part `k`'s vertex positions (part order) from coefficients (one row).
    pub fn decode(&self, k: usize, coefficients: &[f64]) -> Result<Vec<f32>> {
        let c = Mat::from_fn(1, coefficients.len(), |_, j| coefficients[j]);
        let y = self.pcas[k].reconstruct(c.as_ref())?;
        Ok((0..y.ncols()).map(|j| y[(0, j)] as f32).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body_parts::Part;

    fn rot(axis: Vector3<f64>, angle: f64) -> Matrix3<f64> {
        exp_rotation(&(axis.normalize() * angle))
    }

    #[test]
    fn aligned_rms_ignores_a_rigid_motion_and_measures_a_change_of_shape() {
        let pose: Vec<f32> = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0];
        let r = rot(Vector3::new(0.3, 1.0, -0.2), 1.1);
        let moved: Vec<f32> = pose
            .chunks_exact(3)
            .flat_map(|p| {
                let q = r * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) + Vector3::new(5.0, -1.0, 2.0);
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect();
        assert!(aligned_rms(&pose, &moved) < 1e-5, "{}", aligned_rms(&pose, &moved));
        // One vertex pushed 0.4 off: a rigid fit cannot undo it.
        let mut bent = pose.clone();
        bent[9] += 0.4;
        let e = aligned_rms(&pose, &bent);
        assert!(e > 0.05 && e < 0.4, "{e}");
    }

    #[test]
    fn displacement_round_trips_and_is_heading_invariant() {
        let a = Placement { rotation: rot(Vector3::new(0.2, 1.0, 0.1), 0.8), translation: Vector3::new(1.0, 2.0, 3.0) };
        let b = Placement { rotation: rot(Vector3::new(0.0, 1.0, 0.3), 1.9), translation: Vector3::new(1.5, 2.1, 2.0) };
        let d = a.displacement_to(&b);
        let back = a.moved_by(&d);
        assert!((back.rotation - b.rotation).norm() < 1e-12 && (back.translation - b.translation).norm() < 1e-12);
        // The same relative motion after turning the whole world gives the same displacement.
        let turn = Placement { rotation: rot(Vector3::y(), 2.5), translation: Vector3::new(-4.0, 0.0, 7.0) };
        let compose = |p: &Placement| Placement {
            rotation: turn.rotation * p.rotation,
            translation: turn.rotation * p.translation + turn.translation,
        };
        let d2 = compose(&a).displacement_to(&compose(&b));
        for k in 0..6 {
            assert!((d[k] - d2[k]).abs() < 1e-12);
        }
        // A large per-frame turn is exact (the small-angle form would not be).
        let c = a.moved_by(&[0.0, 0.0, 0.0, 0.0, 2.0, 0.0]);
        assert!((a.displacement_to(&c)[4] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn alignment_removes_a_rigid_motion_exactly() {
        let reference: Vec<f32> = vec![0., 0., 0., 1., 0., 0., 0., 2., 0., 0., 0., 3., 1., 1., 1.];
        let p =
            Placement { rotation: rot(Vector3::new(1.0, 0.5, -0.3), 1.2), translation: Vector3::new(3.0, -1.0, 2.0) };
        let moved = p.apply(&reference);
        let (aligned, back) = align_to_reference(&reference, &moved);
        for (a, r) in aligned.iter().zip(&reference) {
            assert!((a - r).abs() < 1e-5);
        }
        for (a, m) in back.apply(&aligned).iter().zip(&moved) {
            assert!((a - m).abs() < 1e-5);
        }
        let motion = align_motion(&reference, &[&reference, &moved]);
        assert_eq!(motion.displacements[0], [0.0; 6]);
        let again = motion.placements[0].moved_by(&motion.displacements[1]);
        assert!((again.rotation - motion.placements[1].rotation).norm() < 1e-6);
    }

    #[test]
    fn part_pca_round_trips_poses_in_its_span() {
        let parts = BodyParts::new(
            4,
            vec![
                Part { name: "a".into(), parent: None, vertices: vec![0, 1, 2] },
                Part { name: "b".into(), parent: Some("a".into()), vertices: vec![2, 3] },
            ],
        )
        .unwrap();
        let poses: Vec<Vec<f32>> =
            (0..6).map(|i| (0..12).map(|j| ((i * 7 + j * 3) % 5) as f32 * 0.1 + j as f32).collect()).collect();
        let refs: Vec<&[f32]> = poses.iter().map(|p| p.as_slice()).collect();
        let space = PartSpace::fit(&parts, &refs, 20).unwrap();
        assert_eq!(space.dimension(0), 5);
        let c = space.encode(1, &refs).unwrap();
        let row: Vec<f64> = (0..c.ncols()).map(|j| c[(3, j)]).collect();
        let back = space.decode(1, &row).unwrap();
        let truth = space.part_values(1, &poses[3]);
        for (a, b) in back.iter().zip(&truth) {
            assert!((*a as f64 - b).abs() < 1e-4);
        }
        let e = PartSpace::fit(&parts, &refs[..1], 20).unwrap_err().to_string();
        assert!(e.contains("expected at least 2"), "{e}");
    }
}
