//! Ground-truth pose distance from a skeleton (thesis eq. 2.15-2.16): per joint, the Euler
//! angles of its rotation relative to its parent; per pair of frames, the square root of the
//! sum over joints and angles of the wrapped angle differences squared.
//!
//! Readings: eq. 2.15 as printed has no sum over joints; the sum is implied ("represented each
//! by Euler angles of their joints"). The local rotation is R_parent^-1 R_joint, each world
//! rotation first stripped of scale (its polar rotation: KayKit matrices carry a uniform armature
//! scale). Euler angles follow nalgebra's convention (R = Rz(yaw) Ry(pitch) Rx(roll)). Root joints
//! are left out (their rotation is the global heading, which the mesh distances align away), as
//! are joints whose name marks them as rig helpers (IK targets, controls), which carry no skin.

use nalgebra::{Matrix3, Rotation3};
use surfcap_mesh::JointTrack;

/// Which joints the distance uses.
pub fn joint_selection(track: &JointTrack) -> Vec<usize> {
    (0..track.n_joints())
        .filter(|&j| track.parents[j].is_some())
        .filter(|&j| {
            let n = track.names[j].to_ascii_lowercase();
            !(n.contains("ik") || n.contains("control"))
        })
        .collect()
}

fn world_rotation(m: &[f32]) -> Matrix3<f64> {
    // Row-major 4x4, column-vector convention: the rotation block is rows 0..3, cols 0..3.
    let r = Matrix3::from_fn(|i, j| m[4 * i + j] as f64);
    let svd = r.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => {
            let q = u * v_t;
            if q.determinant() < 0.0 { -q } else { q }
        }
        _ => Matrix3::identity(),
    }
}

/// Euler angles (roll, pitch, yaw) of every selected joint's local rotation in one frame.
pub fn local_euler_angles(track: &JointTrack, frame: usize, joints: &[usize]) -> Vec<[f64; 3]> {
    let nj = track.n_joints();
    let at = |j: usize| &track.matrices[(frame * nj + j) * 16..(frame * nj + j + 1) * 16];
    joints
        .iter()
        .map(|&j| {
            let world = world_rotation(at(j));
            let local = match track.parents[j] {
                Some(p) => world_rotation(at(p)).transpose() * world,
                None => world,
            };
            let (a, b, c) = Rotation3::from_matrix_unchecked(local).euler_angles();
            [a, b, c]
        })
        .collect()
}

/// eq. 2.16: the difference of two angles wrapped into [0, pi].
pub fn angle_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).abs().rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// eq. 2.15 between two frames' angle sets.
pub fn euler_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (0..3).map(|k| angle_difference(x[k], y[k]).powi(2)).sum::<f64>()).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_angles_and_reads_local_rotations() {
        assert!((angle_difference(3.1, -3.1) - (std::f64::consts::TAU - 6.2)).abs() < 1e-12);
        assert!((angle_difference(0.5, 0.2) - 0.3).abs() < 1e-12);
        // Two joints: a root turned by 1 rad about z and a child turned by a further 0.25 rad,
        // both scaled by 2: the child's local roll/pitch/yaw is (0, 0, 0.25).
        let rz = |t: f64| Rotation3::from_euler_angles(0.0, 0.0, t).into_inner() * 2.0;
        let mat = |r: Matrix3<f64>| {
            let mut m = [0f32; 16];
            for i in 0..3 {
                for j in 0..3 {
                    m[4 * i + j] = r[(i, j)] as f32;
                }
            }
            m[15] = 1.0;
            m
        };
        let mut matrices = mat(rz(1.0)).to_vec();
        matrices.extend(mat(rz(1.25)));
        let track = JointTrack { names: vec!["root".into(), "spine".into()], parents: vec![None, Some(0)], matrices };
        let sel = joint_selection(&track);
        assert_eq!(sel, vec![1]);
        let e = local_euler_angles(&track, 0, &sel);
        assert!((e[0][2] - 0.25).abs() < 1e-6 && e[0][0].abs() < 1e-6, "{e:?}");
    }
}
