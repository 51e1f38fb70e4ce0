//! A subject (the foundation's data model) made of the mannequin moved by clips: BVH files
//! retargeted onto it, or procedural locomotion. One sequence per clip, all resampled to one
//! frame rate, with motion-type tags and the ground-truth joint transforms stored beside the
//! positions (`Sequence::joints`: per frame, each joint's world matrix).

use std::path::Path;

use nalgebra::Isometry3;
use surfcap_mesh::sizing::{Estimate, bytes};
use surfcap_mesh::{Error, ErrorKind, JointTrack, Result, Sequence, Subject, Units, UpAxis};

use crate::bvh::Bvh;
use crate::locomotion::{Gait, locomotion};
use crate::mannequin::Mannequin;
use crate::retarget::retarget;

/// One motion of the mannequin: joint world transforms per frame, at `fps`.
#[derive(Debug, Clone)]
pub struct Clip {
    pub name: String,
    pub tags: Vec<String>,
    pub fps: f64,
    pub poses: Vec<Vec<Isometry3<f64>>>,
}

impl Clip {
    /// A BVH clip retargeted onto the mannequin, named after the file, tagged by
    /// [`motion_tags`].
    pub fn from_bvh(path: &Path, bvh: &Bvh, m: &Mannequin, metres_per_unit: f64) -> Result<Clip> {
        let poses = retarget(bvh, m, metres_per_unit).map_err(|e| e.in_file(path))?;
        if poses.len() < 2 {
            return Err(Error::new(
                ErrorKind::Empty,
                format!("{} frame{}: expected at least 2", poses.len(), if poses.len() == 1 { "" } else { "s" }),
            )
            .in_file(path));
        }
        let name = path.file_stem().map_or_else(|| "bvh".into(), |s| s.to_string_lossy().into_owned());
        let tags = motion_tags(&poses, bvh.fps());
        Ok(Clip { name, tags, fps: bvh.fps(), poses })
    }

    /// A procedural motion, named and tagged after its gait.
    pub fn procedural(m: &Mannequin, gait: Gait, fps: f64, duration: f64, seed: u64) -> Result<Clip> {
        let poses = locomotion(&m.skeleton, gait, fps, duration, seed)?;
        Ok(Clip { name: gait.name().to_string(), tags: gait.tags(), fps, poses })
    }
}

/// Motion-type tags of a clip from its root path (heuristic, for clips that come without any):
/// `jump` when the root rises more than 12 cm above its median height; by mean horizontal
/// speed, `idle` (< 0.3 m/s, limbs still) or `in_place` (< 0.3 m/s, limbs moving: dancing,
/// gesturing), else, for clips that do not jump, `walk` (< 2 m/s) or `run`, plus `turn_left` /
/// `turn_right` when the heading changes by more than 45 degrees (first-20% chord of the root
/// path to the last-20% chord).
pub fn motion_tags(poses: &[Vec<Isometry3<f64>>], fps: f64) -> Vec<String> {
    let root: Vec<[f64; 3]> = poses.iter().map(|w| w[0].translation.vector.into()).collect();
    let n = root.len();
    let duration = (n - 1) as f64 / fps;
    let mut heights: Vec<f64> = root.iter().map(|r| r[1]).collect();
    heights.sort_by(f64::total_cmp);
    let rise = heights[n - 1] - heights[n / 2];
    let (a, z) = (root[0], root[n - 1]);
    let speed = ((z[0] - a[0]).powi(2) + (z[2] - a[2]).powi(2)).sqrt() / duration;
    let mut tags = Vec::new();
    if rise > 0.12 {
        tags.push("jump");
    }
    if speed < 0.3 {
        // Limb activity: mean speed of the joints relative to the root.
        let mut moved = 0.0;
        for f in 1..n {
            for j in 1..poses[f].len() {
                let rel = |g: usize| poses[g][j].translation.vector - poses[g][0].translation.vector;
                moved += (rel(f) - rel(f - 1)).norm();
            }
        }
        let limb_speed = moved / ((poses[0].len() - 1) as f64 * duration);
        tags.push(if limb_speed < 0.15 { "idle" } else { "in_place" });
    } else if tags.is_empty() {
        tags.push(if speed < 2.0 { "walk" } else { "run" });
        let k = (n / 5).max(1);
        let chord = |p: [f64; 3], q: [f64; 3]| (q[0] - p[0]).atan2(q[2] - p[2]);
        let mut turn = chord(root[n - 1 - k], root[n - 1]) - chord(root[0], root[k]);
        turn = (turn + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        if turn > 45f64.to_radians() {
            tags.push("turn_left");
        } else if turn < -45f64.to_radians() {
            tags.push("turn_right");
        }
    }
    tags.into_iter().map(String::from).collect()
}

/// A clip's poses at another frame rate: each output time between two input frames gets their
/// translations interpolated linearly and rotations spherically.
pub fn resample(poses: &[Vec<Isometry3<f64>>], from_fps: f64, to_fps: f64) -> Vec<Vec<Isometry3<f64>>> {
    if (from_fps - to_fps).abs() < 1e-9 * from_fps {
        return poses.to_vec();
    }
    let duration = (poses.len() - 1) as f64 / from_fps;
    let frames = (duration * to_fps + 1e-9).floor() as usize + 1;
    (0..frames)
        .map(|f| {
            let x = f as f64 / to_fps * from_fps;
            let i = (x.floor() as usize).min(poses.len() - 1);
            let (j, t) = if i + 1 < poses.len() { (i + 1, x - i as f64) } else { (i, 0.0) };
            poses[i].iter().zip(&poses[j]).map(|(a, b)| a.lerp_slerp(b, t)).collect()
        })
        .collect()
}

/// Row-major 4x4 world matrices, `[frames][joints][4][4]`, as `JointTrack` stores them.
fn joint_track(m: &Mannequin, poses: &[Vec<Isometry3<f64>>]) -> JointTrack {
    let matrices = poses
        .iter()
        .flat_map(|w| w.iter())
        .flat_map(|iso| iso.to_homogeneous().transpose().as_slice().to_vec())
        .map(|x| x as f32);
    JointTrack {
        names: m.skeleton.names.iter().map(|s| s.to_string()).collect(),
        parents: m.skeleton.parents.clone(),
        matrices: matrices.collect(),
    }
}

/// Frames of a clip lasting `duration` seconds at `fps`, first to last frame, as
/// [`locomotion`] and [`resample`] count them (in `f64`, so a huge request is a huge number,
/// not a wrapped one).
pub fn clip_frames(duration: f64, fps: f64) -> f64 {
    (duration * fps).round().max(1.0) + 1.0
}

/// What [`mannequin_subject`] takes for clips of `frames` frames each (at the subject's rate),
/// estimated before any clip is made: per frame and vertex three f32 positions, per frame and
/// joint the clip's and the resampled pose (two f64 isometries) and the ground-truth matrix in
/// memory; the subject cache writes the positions and one f32 4x4 matrix per joint.
/// `what` names the arguments responsible, `lower` what to lower instead of raising a limit.
pub fn mannequin_subject_size(m: &Mannequin, frames: &[f64], what: String, lower: String) -> Estimate {
    let total: f64 = frames.iter().sum();
    let (nv, nj) = (m.topology.n_vertices() as f64, m.skeleton.names.len() as f64);
    let per_frame_disk = 12.0 * nv + 64.0 * nj;
    let per_frame_memory = per_frame_disk + 2.0 * 56.0 * nj;
    Estimate { what, memory: bytes(&[total, per_frame_memory], 1), disk: bytes(&[total, per_frame_disk], 1), lower }
}

/// The subject: one sequence per clip (resampled to `fps`), +y up, metres, each with its tags
/// and ground-truth joints. Clip names must be unique.
pub fn mannequin_subject(name: &str, m: &Mannequin, clips: &[Clip], fps: f64) -> Result<Subject> {
    let nv = m.topology.n_vertices();
    let mut sequences = Vec::with_capacity(clips.len());
    for clip in clips {
        let poses = resample(&clip.poses, clip.fps, fps);
        let positions: Vec<f32> = poses.iter().flat_map(|w| m.pose(w)).collect();
        let seq = Sequence::new(clip.name.clone(), nv, positions)?
            .with_tags(clip.tags.clone())
            .with_joints(joint_track(m, &poses))?;
        sequences.push(seq);
    }
    Subject::new(name, m.topology.clone(), sequences, fps, UpAxis::PosY, Units::metres())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mannequin::{BodyShape, mannequin};

    #[test]
    fn the_size_estimate_counts_frames_vertices_and_joints_before_any_clip_is_made() {
        let m = mannequin(&BodyShape::average(), 1000).unwrap();
        assert_eq!(clip_frames(3.0, 30.0), 91.0);
        assert_eq!(clip_frames(1e9, 30.0), 3e10 + 1.0);
        let (nv, nj) = (m.topology.n_vertices() as u64, m.skeleton.names.len() as u64);
        let e = mannequin_subject_size(&m, &[91.0, 61.0], "--duration 3".into(), "--duration".into());
        assert_eq!(e.disk, 152 * (12 * nv + 64 * nj));
        assert_eq!(e.memory, 152 * (12 * nv + 64 * nj + 112 * nj));
        // A billion seconds is refused by any budget, not wrapped to a small number.
        let huge = mannequin_subject_size(&m, &[clip_frames(1e9, 30.0)], String::new(), String::new());
        assert!(huge.memory > 1 << 45, "{}", huge.memory);
    }

    #[test]
    fn procedural_subject_with_tags_joints_and_one_frame_rate() {
        let m = mannequin(&BodyShape::average(), 1000).unwrap();
        let clips: Vec<Clip> = [(Gait::Walk, 30.0), (Gait::TurnLeft, 24.0), (Gait::Jump, 60.0)]
            .into_iter()
            .map(|(g, fps)| Clip::procedural(&m, g, fps, 1.0, 5).unwrap())
            .collect();
        let s = mannequin_subject("m", &m, &clips, 30.0).unwrap();
        assert_eq!(s.sequences().len(), 3);
        for seq in s.sequences() {
            assert_eq!(seq.n_frames(), 31, "{}: one second at 30 fps", seq.name);
            let j = seq.joints.as_ref().unwrap();
            assert_eq!(j.n_joints(), 15);
            // The pelvis matrix's translation column is the root position.
            assert!(j.matrices[3].is_finite() && (j.matrices[15] - 1.0).abs() < 1e-6);
        }
        assert_eq!(s.sequences()[1].tags, vec!["turn_left", "walk", "turn"]);
        // The heuristic tags agree with the procedural ones on walk and jump.
        assert_eq!(motion_tags(&clips[0].poses, 30.0), vec!["walk"]);
        assert_eq!(motion_tags(&clips[2].poses, 60.0), vec!["jump"]);
        // Resampling keeps the first and last poses.
        let r = resample(&clips[2].poses, 60.0, 30.0);
        assert_eq!(r.len(), 31);
        assert!((r[30][0].translation.vector - clips[2].poses[60][0].translation.vector).norm() < 1e-12);
        let dup = [clips[0].clone(), clips[0].clone()];
        assert!(mannequin_subject("m", &m, &dup, 30.0).is_err(), "two sequences of one name");
    }
}
