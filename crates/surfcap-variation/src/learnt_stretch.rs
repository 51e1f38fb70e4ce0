//! A sampled pose given the learnt motion's surface stretch, in the gradient domain (thesis
//! eq. 2.45-2.48: a deformation gradient split by its polar decomposition into a rotation and
//! a stretch, then Poisson reconstruction).
//!
//! A variant's pose is the reconstruction GPs' mean at sampled latent points (eq. 6.12), a
//! weighted sum of training poses in vertex space: away from the learnt latents it blends
//! poses linearly, and linear blends shrink and stretch the surface (thesis 2.4, Fig. 2.8).
//! Measured with `surfcap eval vary`, the variants' edge distortion was up to 11% above the
//! captures' in the body frame (KayKit Walking_C: 0.0263 against 0.0237), while the learnt
//! motion's equals the capture's (docs/results/variation.md).
//!
//! So every triangle of the variant's frame `i` keeps its own rotation `R_v` (what makes it a
//! variant: how its parts turn) and takes the stretch `S_l` of the learnt motion's frame `i`
//! (the same reference frame of the same sequence: the surface state the capture has at that
//! moment of the motion), both relative to the model's reference pose: `J = R_v S_l`. The
//! vertices are the least-squares fit to those gradients (eq. 2.48, the reference pose's
//! operator, factorised once per model), each connected component translated back onto the
//! variant's own centroid. Edge lengths depend on the stretch alone, so where the rotations
//! fit together the variant's surface is stretched as the learnt motion's is.
//!
//! A triangle of zero area in the reference pose, the variant's or the learnt frame keeps the
//! variant's own gradient.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use surfcap_geometry::deformation_gradient::deformation_polar_factors;
use surfcap_geometry::poisson_reconstruction::PoissonSolver;
use surfcap_mesh::Topology;

use crate::error::{Error, Result};

/// The factorised reconstruction of one mesh in its reference pose.
pub struct LearntStretch {
    topology: Topology,
    reference: Vec<f32>,
    solver: PoissonSolver,
    /// The reference pose's own gradients (the identity deformation), per triangle.
    reference_gradients: Vec<Matrix3<f64>>,
}

impl std::fmt::Debug for LearntStretch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LearntStretch").field("vertices", &self.topology.n_vertices()).finish()
    }
}

impl LearntStretch {
    /// Factorises the Poisson system of `topology` in its reference pose `reference` (`[n][3]`).
    pub fn new(topology: &Topology, reference: &[f32]) -> Result<Self> {
        if reference.len() != 3 * topology.n_vertices() {
            return Err(Error::Invalid(format!(
                "a reference pose of {} coordinates: expected 3 x {} vertices",
                reference.len(),
                topology.n_vertices()
            )));
        }
        let solver = PoissonSolver::new(topology, reference)
            .map_err(|e| Error::Invalid(format!("the reference pose's Poisson system: {e}")))?;
        let reference_gradients = solver.operator().gradients(reference);
        Ok(LearntStretch { topology: topology.clone(), reference: reference.to_vec(), solver, reference_gradients })
    }

    /// `pose` with the stretch of `learnt` (see the module doc); both `[n][3]`, in one frame.
    pub fn apply(&self, pose: &[f32], learnt: &[f32]) -> Result<Vec<f32>> {
        let n = 3 * self.topology.n_vertices();
        if pose.len() != n || learnt.len() != n {
            return Err(Error::Invalid(format!(
                "poses of {} and {} coordinates: expected {n}",
                pose.len(),
                learnt.len()
            )));
        }
        let own = deformation_polar_factors(&self.topology, &self.reference, pose);
        let stretch = deformation_polar_factors(&self.topology, &self.reference, learnt);
        let own_gradients = self.solver.operator().gradients(pose);
        let targets: Vec<Matrix3<f64>> = own
            .iter()
            .zip(&stretch)
            .enumerate()
            .map(|(m, (o, s))| match (o, s) {
                (Some((r, _)), Some((_, s))) => self.reference_gradients[m] * (r * s).transpose(),
                _ => own_gradients[m],
            })
            .collect();
        let centroids: Vec<Vector3<f64>> = self.solver.component_centroids(pose);
        Ok(self.solver.solve(&targets, &centroids))
    }

    /// Every frame of `poses` with the stretch of the same frame of `learnt` (frames in
    /// parallel; each is independent, so the result does not depend on the thread count).
    pub fn apply_all(&self, poses: &[Vec<f32>], learnt: &[Vec<f32>]) -> Result<Vec<Vec<f32>>> {
        if poses.len() != learnt.len() {
            return Err(Error::Invalid(format!(
                "{} frames against a learnt motion of {}: expected one timing",
                poses.len(),
                learnt.len()
            )));
        }
        poses.par_iter().zip(learnt).map(|(p, l)| self.apply(p, l)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_geometry::shape_distortion::edge_length_distortion;

    /// A strip of `k` quads along x, two triangles each.
    fn strip(k: usize) -> (Topology, Vec<f32>) {
        let mut p = Vec::new();
        for i in 0..=k {
            p.extend([i as f32, 0.0, 0.0, i as f32, 1.0, 0.0]);
        }
        let mut t = Vec::new();
        for i in 0..k as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            t.push([a, c, b]);
            t.push([b, c, d]);
        }
        (Topology::new(p.len() / 3, t, None).unwrap(), p)
    }

    /// Bent about the z axis with curvature `k` (isometric along the strip's edge y = 0), and
    /// squashed across by `squash`.
    fn bent(p: &[f32], k: f32, squash: f32) -> Vec<f32> {
        p.chunks_exact(3)
            .flat_map(|q| {
                let (a, r) = (k * q[0], 1.0 / k - q[1] * squash);
                [r * a.sin(), 1.0 / k - r * a.cos(), q[2]]
            })
            .collect()
    }

    #[test]
    fn the_variants_turns_are_kept_and_its_stretch_becomes_the_learnt_ones() {
        let (t, rest) = strip(8);
        // The learnt frame: bent, unstretched; the variant: bent further and squashed across.
        let learnt = bent(&rest, 0.05, 1.0);
        let variant = bent(&rest, 0.15, 0.8);
        let fix = LearntStretch::new(&t, &rest).unwrap();
        let out = fix.apply(&variant, &learnt).unwrap();
        let d = |p: &[f32]| edge_length_distortion(&t, &rest, &rest, p, 0.0);
        assert!(d(&variant) > 0.05, "the squashed variant is distorted: {}", d(&variant));
        assert!(
            d(&out) - d(&learnt) < 0.3 * (d(&variant) - d(&learnt)),
            "stretch restored: {} from {} (learnt {})",
            d(&out),
            d(&variant),
            d(&learnt)
        );
        // The variant's bend is kept: the far end turned as the variant's, not as the learnt's.
        let end = |p: &[f32]| {
            let n = p.len() / 3;
            let (a, b) = (&p[3 * (n - 2)..3 * (n - 1)], &p[3 * (n - 1)..]);
            ((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0)
        };
        let heading = |p: &[f32]| {
            let (e, s) = (end(p), (p[0] / 2.0 + p[3] / 2.0, p[1] / 2.0 + p[4] / 2.0));
            (e.1 - s.1).atan2(e.0 - s.0)
        };
        assert!(
            (heading(&out) - heading(&variant)).abs() < 0.25 * (heading(&variant) - heading(&learnt)).abs(),
            "headings: out {} variant {} learnt {}",
            heading(&out),
            heading(&variant),
            heading(&learnt)
        );
        // An unstretched pose is its own fixed point.
        let same = fix.apply(&learnt, &learnt).unwrap();
        let err = same.iter().zip(&learnt).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(err < 1e-4, "a learnt frame comes back as it is: {err}");
        assert!(fix.apply(&variant[3..], &learnt).is_err());
        assert!(fix.apply_all(std::slice::from_ref(&variant), &[]).is_err());
    }
}
