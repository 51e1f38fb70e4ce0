//! A subject (captured or synthesised) as a skinned rig: every frame of every sequence
//! decomposed together by Smooth Skinning Decomposition with Rigid Bones
//! (`surfcap_skinning::ssdr`: one set of bones and weights for the whole subject, a bone pose
//! per frame), written as a glTF skin (`surfcap_formats::glb_skin`, one animation per
//! sequence), with a report: reconstruction error per frame against the source (RMS and max, in
//! the subject's units and in % of its height), the file's size beside the morph-target glb's,
//! and the time taken.

use std::time::Instant;

use serde::Serialize;
use surfcap_formats::glb_skin::{JointSequence, SkinnedGlb, skinned_glb_bytes};
use surfcap_mesh::{Progress, Subject, UpAxis};
use surfcap_skinning::{SkinnedRig, SsdrOptions, overall_rms, reconstruction_errors};

use crate::error::{Error, Result};

/// One frame's reconstruction error.
#[derive(Debug, Clone, Serialize)]
pub struct RigFrameError {
    /// `sequence:frame`
    pub frame: String,
    /// RMS over vertices, in the subject's units.
    pub rms: f64,
    /// Largest vertex error, in the subject's units.
    pub max: f64,
    pub rms_percent_of_height: f64,
    pub max_percent_of_height: f64,
}

/// What `surfcap rig` reports.
#[derive(Debug, Clone, Serialize)]
pub struct RigReport {
    pub subject: String,
    pub vertices: usize,
    pub frames: usize,
    pub sequences: usize,
    /// Bones asked for and bones the rig has (fewer when the frames have fewer distinct
    /// trajectories).
    pub bones_requested: usize,
    pub bones: usize,
    pub max_influences: usize,
    /// The most bones one vertex uses.
    pub influences_used: usize,
    pub iterations: usize,
    pub seed: u64,
    /// The unit lengths are given in (its symbol).
    pub units: String,
    /// The subject's height (extent along its up axis in the first frame), in its units.
    pub height: f64,
    /// RMS over every frame and vertex.
    pub rms: f64,
    pub rms_percent_of_height: f64,
    /// Largest vertex error over every frame.
    pub max: f64,
    pub max_percent_of_height: f64,
    /// Size of the skinned glb, bytes.
    pub bytes: u64,
    /// Size the same frames take as a morph-target glb (`surfcap export --format glb`), bytes.
    pub morph_glb_bytes: u64,
    /// Seconds of the decomposition (initialisation and alternation).
    pub decomposition_seconds: f64,
    /// Seconds of the whole run: decomposition, errors and the glb.
    pub seconds: f64,
    /// RMS after the initial clustering and after each iteration.
    pub rms_history: Vec<f64>,
    pub per_frame: Vec<RigFrameError>,
}

/// A rigged subject: the rig, its glb and its report.
pub struct RiggedSubject {
    pub rig: SkinnedRig,
    pub glb: Vec<u8>,
    pub report: RigReport,
}

/// Extent of a pose along the up axis.
fn height(pose: &[f32], up: UpAxis) -> f64 {
    let (axis, sign) = up.axis_and_sign();
    let (lo, hi) = pose
        .chunks_exact(3)
        .map(|p| sign * f64::from(p[axis]))
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    (hi - lo).max(0.0)
}

/// Decomposes every frame of `subject` into one skinned rig and lays out its glb.
pub fn rig_subject(subject: &Subject, opts: &SsdrOptions, progress: &dyn Progress) -> Result<RiggedSubject> {
    let start = Instant::now();
    let nv = subject.topology().n_vertices();
    let frames: Vec<&[f32]> =
        subject.sequences().iter().flat_map(|s| (0..s.n_frames()).map(move |f| s.frame(f))).collect();
    progress.start("skinning decomposition", 1);
    let rig = surfcap_skinning::decompose(&frames, nv, opts)
        .map_err(|e| Error::Request(format!("rigging {:?}: {e}", subject.name)))?;
    progress.advance(1);
    progress.finish();
    let decomposition_seconds = start.elapsed().as_secs_f64();
    let errors = reconstruction_errors(&rig, &frames);
    let h = height(frames[0], subject.up_axis);
    let pct = |x: f64| if h > 0.0 { 100.0 * x / h } else { f64::NAN };
    let mut per_frame = Vec::with_capacity(frames.len());
    let mut k = 0;
    for s in subject.sequences() {
        for f in 0..s.n_frames() {
            let e = errors[k];
            per_frame.push(RigFrameError {
                frame: format!("{}:{f}", s.name),
                rms: e.rms,
                max: e.max,
                rms_percent_of_height: pct(e.rms),
                max_percent_of_height: pct(e.max),
            });
            k += 1;
        }
    }
    let rms = overall_rms(&errors);
    let max = errors.iter().map(|e| e.max).fold(0.0, f64::max);

    // The glb: weights in 4 or 8 slots, the bones as joints.
    let slots = if opts.max_influences <= 4 { 4 } else { 8 };
    let mut joints = vec![0u16; nv * slots];
    let mut weights = vec![0f32; nv * slots];
    for (i, w) in rig.weights.iter().enumerate() {
        let total: f32 = w.iter().map(|x| x.1 as f32).sum();
        for (s, &(j, x)) in w.iter().enumerate() {
            joints[i * slots + s] = j as u16;
            weights[i * slots + s] = x as f32 / total;
        }
    }
    let centres = surfcap_skinning::joint_animation::bone_centres(&rig);
    let mut sequences = Vec::new();
    let mut first = 0;
    for s in subject.sequences() {
        let n = s.n_frames();
        let (rotations, translations) =
            surfcap_skinning::joint_animation::joint_poses(&rig, &centres, first..first + n);
        sequences.push(JointSequence {
            name: s.name.clone(),
            tags: s.tags.clone(),
            n_frames: n,
            rotations,
            translations,
        });
        first += n;
    }
    let options = serde_json::json!({
        "bones": rig.n_bones,
        "max_influences": opts.max_influences,
        "iterations": opts.iterations,
        "seed": opts.seed,
        "rms": rms,
        "max": max,
    });
    let glb = skinned_glb_bytes(&SkinnedGlb {
        name: subject.name.clone(),
        topology: subject.topology(),
        rest: frames[0].to_vec(),
        slots,
        joints,
        weights,
        bind_centres: centres.iter().map(|c| [c[0] as f32, c[1] as f32, c[2] as f32]).collect(),
        sequences,
        fps: subject.fps,
        up_axis: subject.up_axis,
        units: subject.units.clone(),
        extras: options,
    })?;
    let seq_frames: Vec<usize> = subject.sequences().iter().map(|s| s.n_frames()).collect();
    let report = RigReport {
        subject: subject.name.clone(),
        vertices: nv,
        frames: frames.len(),
        sequences: seq_frames.len(),
        bones_requested: opts.bones,
        bones: rig.n_bones,
        max_influences: opts.max_influences,
        influences_used: rig.influences_used(),
        iterations: opts.iterations,
        seed: opts.seed,
        units: subject.units.symbol().to_string(),
        height: h,
        rms,
        rms_percent_of_height: pct(rms),
        max,
        max_percent_of_height: pct(max),
        bytes: glb.len() as u64,
        morph_glb_bytes: surfcap_formats::glb::estimated_glb_bytes(nv, subject.topology().n_triangles(), &seq_frames),
        decomposition_seconds,
        seconds: start.elapsed().as_secs_f64(),
        rms_history: rig.rms_history.clone(),
        per_frame,
    };
    Ok(RiggedSubject { rig, glb, report })
}
