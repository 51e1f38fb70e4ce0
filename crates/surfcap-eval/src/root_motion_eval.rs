//! Root motion from ground contacts against ground truth: BVH clips with real root
//! travel drive the built-in mannequin; the clip's horizontal travel is stripped (every joint
//! moved back by the root's horizontal displacement since frame 0, the pelvis keeping its
//! height and the body its heading), as an in-place game clip is authored; the travel is then
//! recovered from the mesh's ground contacts
//! ([`surfcap_geometry::root_motion_from_contacts`]) and compared with the root's real track.

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::{Isometry3, Vector3};
use serde::Serialize;
use surfcap_builtin::bvh::{Bvh, read_bvh};
use surfcap_builtin::mannequin::{BodyShape, mannequin, skeleton};
use surfcap_builtin::mannequin_subject::Clip;
use surfcap_builtin::retarget::joint_map;
use surfcap_geometry::root_motion_from_contacts::{ContactParams, root_motion_from_contacts};
use surfcap_mesh::UpAxis;

use crate::error::{Error, Result};

/// Options of [`root_motion_eval`] (`surfcap eval root-motion`).
#[derive(Debug, Clone)]
pub struct RootMotionOptions {
    /// BVH clips with real root travel (joints with CMU names).
    pub bvh: Vec<PathBuf>,
    /// Target vertex count of the mannequin.
    pub vertices: usize,
    /// Thresholds of the contact detection.
    pub contacts: ContactParams,
}

/// One clip's recovered travel against its real one (lengths in metres).
#[derive(Debug, Clone, Serialize)]
pub struct ClipRootMotion {
    pub clip: String,
    /// The clip's motion tags (walk, run, turn_left, jump, ...) from its real root path.
    pub tags: Vec<String>,
    pub frames: usize,
    pub fps: f64,
    /// Length of the root's real horizontal track sampled every half second (the distance
    /// walked, without the pelvis's sway within a step).
    pub distance_walked: f64,
    /// Real and recovered net horizontal displacement, first to last frame.
    pub true_displacement: f64,
    pub recovered_displacement: f64,
    /// Mean and largest horizontal distance between the recovered and the real root offset
    /// (both relative to frame 0) over the frames.
    pub mean_error: f64,
    pub max_error: f64,
    /// Distance between the recovered and the real final position, and as a percentage of
    /// `distance_walked`.
    pub final_error: f64,
    pub final_error_percent: f64,
    /// Angle between the real and the recovered net displacement, in degrees (`None` when the
    /// clip ends less than 0.5 m from its start: no direction to compare).
    pub heading_error_degrees: Option<f64>,
    /// Frame steps with ground contact (the others continued the last velocity).
    pub contact_steps: usize,
}

/// Result of [`root_motion_eval`]; serialised, the report `root-motion.json`.
#[derive(Debug, Clone, Serialize)]
pub struct RootMotionEval {
    pub vertices: usize,
    pub contact_height: f64,
    pub contact_speed: f64,
    pub contact_vertical_speed: f64,
    pub clips: Vec<ClipRootMotion>,
    pub seconds: f64,
}

/// Strips, recovers and compares the travel of every clip of `opts` (see the module doc).
pub fn root_motion_eval(opts: &RootMotionOptions) -> Result<RootMotionEval> {
    if opts.bvh.is_empty() {
        return Err(Error::parameter("--bvh", None, "expected at least one BVH file"));
    }
    let t0 = Instant::now();
    let mut clips = Vec::new();
    let mut nv = 0;
    for path in &opts.bvh {
        let bvh = read_bvh(path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        let m = mannequin(&leg_matched_shape(&bvh, mpu)?, opts.vertices)?;
        nv = m.topology.n_vertices();
        let clip = Clip::from_bvh(path, &bvh, &m, mpu)?;
        let root = |w: &[Isometry3<f64>]| w[0].translation.vector;
        let start = root(&clip.poses[0]);
        let truth: Vec<[f64; 2]> = clip.poses.iter().map(|w| [root(w).x - start.x, root(w).z - start.z]).collect();
        let positions: Vec<f32> = clip
            .poses
            .iter()
            .zip(&truth)
            .flat_map(|(w, t)| {
                let back = Vector3::new(-t[0], 0.0, -t[1]);
                let stripped: Vec<Isometry3<f64>> =
                    w.iter().map(|j| Isometry3::from_parts((j.translation.vector + back).into(), j.rotation)).collect();
                m.pose(&stripped)
            })
            .collect();
        let rm = root_motion_from_contacts(&positions, nv, clip.fps, UpAxis::PosY, &opts.contacts);
        clips.push(compare(&clip, &truth, &rm.offsets, rm.contact_steps));
    }
    Ok(RootMotionEval {
        vertices: nv,
        contact_height: opts.contacts.height,
        contact_speed: opts.contacts.speed,
        contact_vertical_speed: opts.contacts.vertical_speed,
        clips,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The average body scaled so that its legs (hip to ankle) are as long as the BVH skeleton's:
/// the BVH root's real travel is then the travel the mannequin's planted feet produce (legs
/// 6% shorter, as the average body's are against CMU subject 16's, would skate and walk 6%
/// less far than the root is carried).
fn leg_matched_shape(bvh: &Bvh, metres_per_unit: f64) -> Result<BodyShape> {
    let average = BodyShape::average();
    let sk = skeleton(&average);
    let joint = |n: &str| sk.names.iter().position(|&x| x == n).expect("mannequin joint");
    let (hip, knee, ankle) = (joint("lfemur"), joint("ltibia"), joint("lfoot"));
    let ours = (sk.rest[hip] - sk.rest[knee]).norm() + (sk.rest[knee] - sk.rest[ankle]).norm();
    let m = joint_map(bvh, &sk)?;
    let w = bvh.world(0);
    let at = |j: usize| w[m[j]].translation.vector;
    let theirs = ((at(hip) - at(knee)).norm() + (at(knee) - at(ankle)).norm()) * metres_per_unit;
    Ok(BodyShape { height: average.height * theirs / ours, ..average })
}

fn compare(clip: &Clip, truth: &[[f64; 2]], recovered: &[[f64; 2]], contact_steps: usize) -> ClipRootMotion {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let errors: Vec<f64> = truth.iter().zip(recovered).map(|(t, r)| dist(*t, *r)).collect();
    let n = truth.len();
    let stride = ((clip.fps / 2.0).round() as usize).max(1);
    let mut samples: Vec<[f64; 2]> = truth.iter().step_by(stride).copied().collect();
    if !(n - 1).is_multiple_of(stride) {
        samples.push(truth[n - 1]);
    }
    let distance_walked: f64 = samples.windows(2).map(|p| dist(p[0], p[1])).sum();
    let (t, r) = (truth[n - 1], recovered[n - 1]);
    let final_error = dist(t, r);
    let true_displacement = t[0].hypot(t[1]);
    let heading_error_degrees = (true_displacement >= 0.5).then(|| {
        let a = r[1].atan2(r[0]) - t[1].atan2(t[0]);
        (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    });
    ClipRootMotion {
        clip: clip.name.clone(),
        tags: clip.tags.clone(),
        frames: n,
        fps: clip.fps,
        distance_walked,
        true_displacement,
        recovered_displacement: r[0].hypot(r[1]),
        mean_error: errors.iter().sum::<f64>() / n as f64,
        max_error: errors.iter().copied().fold(0.0, f64::max),
        final_error,
        final_error_percent: 100.0 * final_error / distance_walked.max(f64::MIN_POSITIVE),
        heading_error_degrees: heading_error_degrees.map(|a| a.abs().to_degrees()),
        contact_steps,
    }
}
