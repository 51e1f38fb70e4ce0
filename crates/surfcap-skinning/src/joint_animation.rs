//! A rig's bones as joints of a skeleton file (glTF): each bone's bind pose is a translation to
//! its rest centre `c_j` (the weighted mean of the rest positions it moves), so that its
//! skinning matrix `M_j^t = [R_j^t | T_j^t]` is the joint's pose times the inverse bind
//! translation: the joint's local rotation is `R_j^t` and its translation `T_j^t + R_j^t c_j`.
//! Rotations are unit quaternions (x, y, z, w) with the sign kept continuous from frame to
//! frame, so that interpolating neighbouring keys takes the short way.

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::ssdr::SkinnedRig;

/// Each bone's rest centre (weighted mean of its vertices' rest positions; the origin for a
/// bone without vertices).
pub fn bone_centres(rig: &SkinnedRig) -> Vec<[f64; 3]> {
    let mut sum = vec![(Vector3::zeros(), 0.0f64); rig.n_bones];
    for (p, w) in rig.rest.iter().zip(&rig.weights) {
        for &(j, x) in w {
            sum[j].0 += x * p;
            sum[j].1 += x;
        }
    }
    sum.iter()
        .map(|(s, w)| {
            if *w > 0.0 {
                let c = s / *w;
                [c.x, c.y, c.z]
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

/// Joint poses of frames `range` (of the rig's frames): `[frame][bone]` quaternions (x, y, z, w)
/// and translations.
pub fn joint_poses(
    rig: &SkinnedRig,
    centres: &[[f64; 3]],
    range: std::ops::Range<usize>,
) -> (Vec<[f32; 4]>, Vec<[f32; 3]>) {
    let nb = rig.n_bones;
    let mut rot = Vec::with_capacity(range.len() * nb);
    let mut tr = Vec::with_capacity(range.len() * nb);
    let mut prev: Vec<Option<UnitQuaternion<f64>>> = vec![None; nb];
    for t in range {
        for j in 0..nb {
            let m = &rig.transforms[t * nb + j];
            let mut q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m.rotation));
            if let Some(p) = prev[j]
                && p.coords.dot(&q.coords) < 0.0
            {
                q = UnitQuaternion::new_unchecked(-q.into_inner());
            }
            prev[j] = Some(q);
            let c = Vector3::from(centres[j]);
            let t = m.translation + m.rotation * c;
            let v = q.coords;
            rot.push([v.x as f32, v.y as f32, v.z as f32, v.w as f32]);
            tr.push([t.x as f32, t.y as f32, t.z as f32]);
        }
    }
    (rot, tr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rigid_bone_fit::BoneTransform;

    #[test]
    fn joint_pose_times_inverse_bind_is_the_bone_transform() {
        let r = *Rotation3::from_euler_angles(0.3, -1.2, 2.5).matrix();
        let b = BoneTransform { rotation: r, translation: Vector3::new(1.0, 2.0, -0.5) };
        let rig = SkinnedRig {
            n_vertices: 2,
            n_bones: 1,
            rest: vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(3.0, 2.0, 0.0)],
            weights: vec![vec![(0, 1.0)], vec![(0, 1.0)]],
            transforms: vec![b, b],
            rms_history: vec![],
        };
        let c = bone_centres(&rig);
        assert_eq!(c[0], [2.0, 1.0, 0.0]);
        let (q, t) = joint_poses(&rig, &c, 0..2);
        assert_eq!(q.len(), 2);
        let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[0][3] as f64,
            q[0][0] as f64,
            q[0][1] as f64,
            q[0][2] as f64,
        ));
        // joint(p - c) == b(p) for a rest point p
        let p = Vector3::new(0.4, -0.7, 1.1);
        let via_joint = q * (p - Vector3::from(c[0])) + Vector3::new(t[0][0] as f64, t[0][1] as f64, t[0][2] as f64);
        assert!((via_joint - b.apply(&p)).norm() < 1e-5);
    }
}
