//! Foot sliding ("foot-skate", thesis 2.5.5 and 5.5's post-processing note): how fast the
//! vertices in ground contact move horizontally while they are in contact. A planted foot of a
//! travelling motion stays still, so the measure is near 0 for captured motion and grows when
//! synthesis (blending, sampling variants) lets planted feet drift.
//!
//! From the clip's own [`crate::ground_contacts`] (ground and subject height from the motion
//! itself, so two motions of one subject are measured alike), restricted to the planted group
//! of each step ([`crate::root_motion_from_contacts::planted_contacts`]: the contacts moving
//! together whose track is smoothest over the clip; a swinging foot grazing the ground is not
//! planted: counted, it made the mannequin's captured CMU walk 16_15 slide at 0.81 m/s against
//! 1.15 m/s for the same walk in place, planted contacts only 0.16 against 1.10): over every frame step f -> f+1 and its planted
//! vertices P_f, the contact-weighted mean of the horizontal displacement's length (along the
//! two ground axes), times the frame rate:
//!
//! `sliding = fps * sum_{f, v in P_f} w_fv |d_fv| / sum_{f, v in P_f} w_fv`
//!
//! in subject units per second. The weight (1 on the ground, 0 at the contact height) makes
//! the vertices at the top of the contact band (a heel rising, toes lifting) count little
//! beside the sole. Per foot, the same over the foot's own planted vertices. An in-place clip
//! (root pinned) slides at its walking speed by this measure: recover its root motion first
//! ([`crate::root_motion_from_contacts`]).

use rayon::prelude::*;
use surfcap_mesh::UpAxis;

use crate::error::{Error, Result};
use crate::foot_contacts::foot_masks;
use crate::ground_contacts::ContactParams;
use crate::ground_contacts::GroundContacts;
use crate::motion_plane_alignment::plane_axes;
use crate::root_motion_from_contacts::planted_contacts;

/// The foot sliding of one clip.
#[derive(Debug, Clone, PartialEq)]
pub struct FootSliding {
    /// Contact-weighted mean horizontal speed of the planted vertices over their steps
    /// (subject units per second); 0 when the clip has no contact.
    pub mean_speed: f64,
    /// The same over each foot's planted vertices (`None` for a foot never planted).
    pub per_foot: Vec<Option<f64>>,
    /// The subject height the contacts were detected with (to express speeds in heights per
    /// second).
    pub subject_height: f64,
    /// Frame steps with planted vertices.
    pub contact_steps: usize,
}

/// Measures the foot sliding of a clip (see the module doc), `positions` being
/// `[frames][n_vertices][3]` and `contacts` its ground contacts detected with `params`; `feet`
/// are vertex sets (possibly none) whose sliding is also reported apart. Steps are measured in
/// parallel and summed in order, so the result does not depend on the thread count.
pub fn foot_sliding(
    positions: &[f32],
    n_vertices: usize,
    fps: f64,
    up: UpAxis,
    contacts: &GroundContacts,
    params: &ContactParams,
    feet: &[Vec<u32>],
) -> Result<FootSliding> {
    let masks = foot_masks(feet, n_vertices)?;
    let per_frame = 3 * n_vertices;
    let frames = positions.len().checked_div(per_frame).unwrap_or(0);
    if frames != contacts.frames || (per_frame > 0 && !positions.len().is_multiple_of(per_frame)) {
        return Err(Error::ContactFrames { contacts: contacts.frames, frames });
    }
    let (u, v, _) = plane_axes(up);
    let planted = planted_contacts(positions, n_vertices, fps, up, contacts, params);
    // Per step: (weighted sum of speeds, weight) for all contacts, then per foot.
    let sums: Vec<Vec<(f64, f64)>> = planted
        .par_iter()
        .enumerate()
        .map(|(f, step)| {
            let (a, b) =
                (&positions[f * per_frame..(f + 1) * per_frame], &positions[(f + 1) * per_frame..(f + 2) * per_frame]);
            let mut out = vec![(0.0, 0.0); 1 + masks.len()];
            for c in step {
                let k = c.vertex as usize;
                let d = ((b[3 * k + u] - a[3 * k + u]) as f64).hypot((b[3 * k + v] - a[3 * k + v]) as f64);
                let w = c.weight;
                out[0].0 += w * d;
                out[0].1 += w;
                for (o, m) in out[1..].iter_mut().zip(&masks) {
                    if m[k] {
                        o.0 += w * d;
                        o.1 += w;
                    }
                }
            }
            out
        })
        .collect();
    let speed = |k: usize| {
        let (s, w) = sums.iter().fold((0.0, 0.0), |acc, x| (acc.0 + x[k].0, acc.1 + x[k].1));
        (w > 0.0).then(|| fps * s / w)
    };
    Ok(FootSliding {
        mean_speed: speed(0).unwrap_or(0.0),
        per_foot: (1..=masks.len()).map(speed).collect(),
        subject_height: contacts.subject_height,
        contact_steps: planted.iter().filter(|s| !s.is_empty()).count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ground_contacts::{ContactParams, ground_contacts};

    /// Two feet of 4 vertices and a head 2 high, +y up, 10 fps, 5 frames: the left foot on the
    /// ground sliding along x at `left` units per second, the right one at `right_height`
    /// moving along z at `right` units per second.
    fn feet(left: f32, right: f32, right_height: f32) -> Vec<f32> {
        let mut out = Vec::new();
        for f in 0..5 {
            let t = f as f32 / 10.0;
            for k in 0..4 {
                out.extend([k as f32 * 0.1 + left * t, 0.0, 0.0]);
            }
            for k in 0..4 {
                out.extend([k as f32 * 0.1, right_height, 0.3 + right * t]);
            }
            out.extend([0.0, 2.0, 0.0]);
        }
        out
    }

    fn measure(p: &[f32], up: UpAxis, feet: &[Vec<u32>]) -> FootSliding {
        let c = ground_contacts(p, 9, 10.0, up, &ContactParams::default());
        foot_sliding(p, 9, 10.0, up, &c, &ContactParams::default(), feet).unwrap()
    }

    #[test]
    fn a_sliding_planted_foot_is_measured_at_its_speed_and_a_grazing_swing_is_not_planted() {
        let both = [(0..4).collect(), (4..8).collect()];
        // The right foot up: the left one slides at 0.5.
        let s = measure(&feet(0.5, 0.0, 0.5), UpAxis::PosY, &both);
        assert!((s.per_foot[0].unwrap() - 0.5).abs() < 1e-5, "{:?}", s.per_foot);
        assert_eq!(s.per_foot[1], None);
        assert!((s.mean_speed - 0.5).abs() < 1e-5, "{}", s.mean_speed);
        assert_eq!((s.subject_height, s.contact_steps), (2.0, 4));
        // Both down and still: no sliding.
        let s = measure(&feet(0.0, 0.0, 0.0), UpAxis::PosY, &both);
        assert_eq!((s.mean_speed, s.per_foot.clone()), (0.0, vec![Some(0.0), Some(0.0)]));
        // The right foot swings through the contact band (0.02 above the ground) at 3 units per
        // second while the left is planted: the planted one is measured, the swing left out.
        let s = measure(&feet(0.0, 3.0, 0.02), UpAxis::PosY, &both);
        assert_eq!((s.mean_speed, s.per_foot.clone()), (0.0, vec![Some(0.0), None]));
        // Along the other ground axis with +z up (y -> z, z -> -y): the same.
        let p = feet(0.0, 0.2, 0.0);
        let turned: Vec<f32> = p.chunks_exact(3).flat_map(|q| [q[0], -q[2], q[1]]).collect();
        let s = measure(&turned, UpAxis::PosZ, &[vec![8]]);
        // Both feet within the grouping tolerance (0.05 a step): one planted group, half of it
        // sliding at 0.2.
        assert!((s.mean_speed - 0.1).abs() < 1e-5, "{}", s.mean_speed);
        assert_eq!(s.per_foot, vec![None]);
        // Contacts of another clip are refused.
        let c = ground_contacts(&turned, 9, 10.0, UpAxis::PosZ, &ContactParams::default());
        let e = foot_sliding(&turned[..27 * 4], 9, 10.0, UpAxis::PosZ, &c, &ContactParams::default(), &[]).unwrap_err();
        assert_eq!(e.to_string(), "ground contacts of 5 frames given for a clip of 4 frames");
    }
}
