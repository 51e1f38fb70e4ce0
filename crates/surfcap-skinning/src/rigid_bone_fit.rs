//! One bone's rigid transform by weighted Procrustes (weighted absolute orientation), the bone
//! update of Smooth Skinning Decomposition with Rigid Bones (Le and Deng 2012, "bone
//! transformations update"): with the weights and every other bone fixed, bone j's rotation R
//! and translation T minimise
//!
//! `sum_i || q_i - w_ij (R p_i + T) ||^2`,
//!
//! where `p_i` is vertex i's rest position and `q_i` what the other bones leave of its target
//! (`v_i - sum_{k != j} w_ik (R_k p_i + T_k)`). Setting the derivative in T to zero gives
//! `T = q* - R p*` with `p* = sum w^2 p / sum w^2` and `q* = sum w q / sum w^2`; R is then the
//! rotation maximising `tr(R H)`, `H = sum_i w_ij (p_i - p*) q_i^T` (Kabsch: the rotation polar
//! factor of `H^T`, a reflection turned into the nearest rotation). With all weights 1 it is the
//! ordinary rigid fit of the bone's vertices.

use nalgebra::{Matrix3, Vector3};

/// A rigid (or, for the rest pose, any affine) bone transform `x -> R x + T`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoneTransform {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
}

impl BoneTransform {
    pub fn identity() -> Self {
        BoneTransform { rotation: Matrix3::identity(), translation: Vector3::zeros() }
    }

    #[inline]
    pub fn apply(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }
}

/// Running sums of one bone's weighted fit, accumulated point by point.
#[derive(Debug, Clone, Copy)]
pub struct RigidFitSums {
    /// sum w^2
    ww: f64,
    /// sum w
    w: f64,
    /// sum w^2 p
    wwp: Vector3<f64>,
    /// sum w q
    wq: Vector3<f64>,
    /// sum w p q^T
    wpq: Matrix3<f64>,
}

impl Default for RigidFitSums {
    fn default() -> Self {
        RigidFitSums { ww: 0.0, w: 0.0, wwp: Vector3::zeros(), wq: Vector3::zeros(), wpq: Matrix3::zeros() }
    }
}

impl RigidFitSums {
    /// Adds rest point `p` with weight `w` whose target is `q`.
    #[inline]
    pub fn add(&mut self, p: &Vector3<f64>, q: &Vector3<f64>, w: f64) {
        self.ww += w * w;
        self.w += w;
        self.wwp += (w * w) * p;
        self.wq += w * q;
        self.wpq += (w * p) * q.transpose();
    }

    /// The minimising rotation and translation, or `None` when the points do not fix one (no
    /// weight, or all at one point).
    pub fn solve(&self) -> Option<BoneTransform> {
        if self.ww.is_nan() || self.ww <= 1e-12 {
            return None;
        }
        let p_star = self.wwp / self.ww;
        let q_star = self.wq / self.ww;
        // H = sum w (p - p*) q^T = sum w p q^T - p* (sum w q)^T
        let h = self.wpq - p_star * self.wq.transpose();
        if !h.iter().all(|x| x.is_finite()) || h.norm() < 1e-300 {
            return None;
        }
        let (rotation, _) = surfcap_geometry::polar_decomposition::polar_decomposition(&h.transpose());
        let translation = q_star - rotation * p_star;
        Some(BoneTransform { rotation, translation })
    }

    /// Sum of the weights, for telling whether a bone has vertices at all.
    pub fn weight(&self) -> f64 {
        self.w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot(axis: Vector3<f64>, angle: f64) -> Matrix3<f64> {
        *nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle).matrix()
    }

    #[test]
    fn recovers_a_rigid_motion_exactly_with_unit_and_partial_weights() {
        let r = rot(Vector3::new(0.3, -1.0, 0.5), 1.1);
        let t = Vector3::new(0.5, -2.0, 3.0);
        let pts: Vec<Vector3<f64>> = (0..7)
            .map(|i| {
                let f = i as f64;
                Vector3::new(f.sin() * 2.0, (1.3 * f).cos(), 0.2 * f)
            })
            .collect();
        // Unit weights: plain rigid fit.
        let mut s = RigidFitSums::default();
        for p in &pts {
            s.add(p, &(r * p + t), 1.0);
        }
        let b = s.solve().unwrap();
        assert!((b.rotation - r).norm() < 1e-10 && (b.translation - t).norm() < 1e-10);
        // Partial weights: the target is w (R p + T), as when other bones carry the rest.
        let mut s = RigidFitSums::default();
        for (i, p) in pts.iter().enumerate() {
            let w = 0.2 + 0.1 * i as f64;
            s.add(p, &(w * (r * p + t)), w);
        }
        let b = s.solve().unwrap();
        assert!((b.rotation - r).norm() < 1e-10 && (b.translation - t).norm() < 1e-10);
        assert!((b.rotation.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_mirrored_target_gives_a_rotation_not_a_reflection() {
        let pts =
            [Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 0.0, 1.0), Vector3::zeros()];
        let mut s = RigidFitSums::default();
        for p in &pts {
            s.add(p, &Vector3::new(-p.x, p.y, p.z), 1.0);
        }
        let b = s.solve().unwrap();
        assert!((b.rotation.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn no_weight_gives_no_transform() {
        let mut s = RigidFitSums::default();
        s.add(&Vector3::new(1.0, 2.0, 3.0), &Vector3::zeros(), 0.0);
        assert!(s.solve().is_none());
    }
}
