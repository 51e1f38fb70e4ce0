//! Driving the mannequin with a BVH clip: joints matched by name (CMU ASF names, and the
//! names of CMU's cgspeed BVH conversions), bone directions copied, root travel kept.
//!
//! Method: forward kinematics of the BVH gives its joints' world positions each frame. The
//! pelvis and thorax take the orientation of the BVH's hip and shoulder axes (with the spine as
//! up); every limb joint takes the smallest rotation that turns its mannequin rest bone (towards
//! its child) onto the BVH bone; hands and head follow their parent. Positions are rebuilt from
//! the mannequin's own bone lengths, so the mannequin keeps its proportions while its pelvis
//! follows the BVH root's real horizontal travel (in metres) and the root's height changes.
//! Twist about a limb's own axis is not transferred (a direction has none).

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use surfcap_mesh::{Error, ErrorKind, Result};

use crate::bvh::Bvh;
use crate::mannequin::{Mannequin, Skeleton};

/// BVH names that may stand for each mannequin joint.
fn candidates(mannequin_joint: &str) -> &'static [&'static str] {
    match mannequin_joint {
        "pelvis" => &["pelvis", "Hips", "hip", "Hip"],
        "lfemur" => &["lfemur", "LeftUpLeg", "LeftHip"],
        "ltibia" => &["ltibia", "LeftLeg", "LeftKnee"],
        "lfoot" => &["lfoot", "LeftFoot", "LeftAnkle"],
        "rfemur" => &["rfemur", "RightUpLeg", "RightHip"],
        "rtibia" => &["rtibia", "RightLeg", "RightKnee"],
        "rfoot" => &["rfoot", "RightFoot", "RightAnkle"],
        "thorax" => &["thorax", "Spine1", "Chest", "Spine"],
        "head" => &["head", "Head"],
        "lhumerus" => &["lhumerus", "LeftArm", "LeftShoulder"],
        "lradius" => &["lradius", "LeftForeArm", "LeftElbow"],
        "lhand" => &["lhand", "LeftHand", "LeftWrist"],
        "rhumerus" => &["rhumerus", "RightArm", "RightShoulder"],
        "rradius" => &["rradius", "RightForeArm", "RightElbow"],
        "rhand" => &["rhand", "RightHand", "RightWrist"],
        _ => &[],
    }
}

/// Index of the BVH joint for every joint of the mannequin's skeleton.
pub fn joint_map(bvh: &Bvh, skeleton: &Skeleton) -> Result<Vec<usize>> {
    skeleton
        .names
        .iter()
        .map(|&name| {
            candidates(name).iter().find_map(|c| bvh.joints.iter().position(|j| j.name == *c)).ok_or_else(|| {
                Error::new(
                    ErrorKind::Metadata,
                    format!("no BVH joint for the mannequin's {name:?}: expected one of {:?}", candidates(name)),
                )
            })
        })
        .collect()
}

/// Rotation taking the frame (x, up) of the rest pose to the frame (x, up) given.
fn frame_rotation(x: Vector3<f64>, up: Vector3<f64>) -> UnitQuaternion<f64> {
    let x = x.normalize();
    let up = (up - x * x.dot(&up)).normalize();
    let z = x.cross(&up);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, up, z])))
}

fn swing(from: Vector3<f64>, to: Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&from, &to).unwrap_or_else(|| {
        // Opposite directions: half a turn about any axis perpendicular to `from`.
        let axis = if from.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(from.cross(&axis)), std::f64::consts::PI)
    })
}

/// World transforms of the mannequin's joints for every BVH frame (for `Mannequin::pose`).
pub fn retarget(bvh: &Bvh, m: &Mannequin, metres_per_unit: f64) -> Result<Vec<Vec<Isometry3<f64>>>> {
    let map = joint_map(bvh, &m.skeleton)?;
    if bvh.n_frames() == 0 {
        return Err(Error::new(ErrorKind::Empty, "the BVH clip has no frames: expected at least one"));
    }
    let sk = &m.skeleton;
    let idx = |n: &str| sk.names.iter().position(|&x| x == n).expect("mannequin joint");
    let (pelvis, lf, rf, thorax, head, lh, rh) =
        (idx("pelvis"), idx("lfemur"), idx("rfemur"), idx("thorax"), idx("head"), idx("lhumerus"), idx("rhumerus"));
    // The first child of each joint in the mannequin.
    let child: Vec<Option<usize>> =
        (0..sk.names.len()).map(|j| sk.parents.iter().position(|&p| p == Some(j))).collect();
    let rest_root = bvh.world(0)[map[pelvis]].translation.vector * metres_per_unit;
    let mut out = Vec::with_capacity(bvh.n_frames());
    for f in 0..bvh.n_frames() {
        let w = bvh.world(f);
        let at = |j: usize| w[map[j]].translation.vector * metres_per_unit;
        let mut q = vec![UnitQuaternion::identity(); sk.names.len()];
        q[pelvis] = frame_rotation(at(lf) - at(rf), at(thorax) - at(pelvis));
        q[thorax] = frame_rotation(at(lh) - at(rh), at(head) - at(thorax));
        for j in 0..sk.names.len() {
            if j == pelvis || j == thorax {
                continue;
            }
            // The parent's rotation, then the smallest swing that turns the bone (as the parent
            // carries it) onto the BVH bone: the joint's rotation relative to its parent is a
            // pure swing, with no twist about the bone that would wring the skin around it.
            let parent = q[sk.parents[j].expect("only the pelvis is a root")];
            q[j] = match child[j] {
                Some(c) => swing(parent * (sk.rest[c] - sk.rest[j]), at(c) - at(j)) * parent,
                None => parent,
            };
        }
        let mut pos = vec![Point3::origin(); sk.names.len()];
        let root = at(pelvis);
        pos[pelvis] = Point3::new(root.x, sk.rest[pelvis].y + (root.y - rest_root.y), root.z);
        for j in 0..sk.names.len() {
            if let Some(p) = sk.parents[j] {
                pos[j] = pos[p] + q[p] * (sk.rest[j] - sk.rest[p]);
            }
        }
        out.push((0..sk.names.len()).map(|j| Isometry3::from_parts(Translation3::from(pos[j].coords), q[j])).collect());
    }
    Ok(out)
}
