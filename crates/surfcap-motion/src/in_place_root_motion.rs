//! A subject whose in-place clips get their travel back from the feet's ground contacts
//! (`surfcap import --root-motion contacts`): each sequence that
//! [`clip_travel`](crate::clip_travel) finds in place is moved by the root motion
//! [`root_motion_from_contacts`] recovers, its vertices and its joint matrices alike, and is
//! tagged [`RECOVERED_TAG`] so the subject says which clips were changed. Clips that already
//! travel keep their captured motion (contacts would add their travel a second time).

use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_geometry::root_motion_from_contacts::{ContactParams, apply_root_motion, root_motion_from_contacts};
use surfcap_mesh::{Result, Sequence, Subject};

use crate::clip_travel::subject_travel;

/// The tag of sequences whose root motion was recovered from contacts.
pub const RECOVERED_TAG: &str = "root_motion_from_contacts";

/// What was done to one in-place sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct RecoveredClip {
    pub sequence: String,
    /// Net horizontal displacement of the centre before and after (subject units).
    pub before: f64,
    pub after: f64,
    /// Frame steps with ground contact, of `frames - 1`.
    pub contact_steps: usize,
    pub frames: usize,
}

/// `s` with every in-place sequence moved by its recovered root motion (see the module doc),
/// and what was recovered for each.
pub fn recover_in_place_root_motion(s: Subject, params: &ContactParams) -> Result<(Subject, Vec<RecoveredClip>)> {
    let travel = subject_travel(&s);
    let nv = s.topology().n_vertices();
    let (u, v, _) = plane_axes(s.up_axis);
    let mut recovered = Vec::new();
    let mut sequences = Vec::with_capacity(s.sequences().len());
    for (q, t) in s.sequences().iter().zip(&travel) {
        if !t.in_place {
            sequences.push(q.clone());
            continue;
        }
        let motion = root_motion_from_contacts(q.positions(), nv, s.fps, s.up_axis, params);
        let mut positions = q.positions().to_vec();
        apply_root_motion(&mut positions, nv, s.up_axis, &motion);
        let mut tags = q.tags.clone();
        tags.push(RECOVERED_TAG.into());
        let mut moved = Sequence::new(q.name.clone(), nv, positions)?.with_tags(tags).with_labels(q.labels.clone())?;
        if let Some(j) = &q.joints {
            let mut j = j.clone();
            let per_frame = 16 * j.n_joints();
            // Row-major 4x4: the translation is the last column (elements 3, 7, 11).
            for (frame, o) in j.matrices.chunks_exact_mut(per_frame.max(1)).zip(&motion.offsets) {
                for m in frame.chunks_exact_mut(16) {
                    m[4 * u + 3] += o[0] as f32;
                    m[4 * v + 3] += o[1] as f32;
                }
            }
            moved = moved.with_joints(j)?;
        }
        recovered.push(RecoveredClip {
            sequence: q.name.clone(),
            before: t.net_displacement,
            after: 0.0,
            contact_steps: motion.contact_steps,
            frames: q.n_frames(),
        });
        sequences.push(moved);
    }
    let out = Subject::new(s.name.clone(), s.topology().clone(), sequences, s.fps, s.up_axis, s.units.clone())?;
    let after = subject_travel(&out);
    for r in &mut recovered {
        if let Some(t) = after.iter().find(|t| t.sequence == r.sequence) {
            r.after = t.net_displacement;
        }
    }
    Ok((out, recovered))
}
