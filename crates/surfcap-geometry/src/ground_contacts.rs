//! Ground contacts of a clip's vertices, from their height and vertical speed alone: the
//! detection shared by root motion ([`crate::root_motion_from_contacts`]), the per-foot contact
//! signals ([`crate::foot_contacts`]) and the foot-sliding measure ([`crate::foot_sliding`]).
//!
//! The thesis aligns motions in time "with dynamic time warping guided with feet contact
//! annotation" (6.4, 6.8) and notes that mesh data comes without such annotation (2.5.5, 3.2);
//! like the annotations of motion capture, we take contacts from the feet's height and speed,
//! here from the vertices themselves:
//!
//! 1. **Ground height**: the 20th percentile of the clip's per-frame lowest vertex height (along
//!    the up axis). A percentile rather than the minimum, so one frame dipping below the floor
//!    does not lift the ground; low enough that the flight phases of a run (a third of its
//!    frames at most) do not raise it.
//! 2. **Subject height**: the largest vertical extent of a frame (the clip's own, so two motions
//!    of one subject get comparable thresholds without outside information).
//! 3. **Contact vertices of a step f -> f+1**: low at both frames (within
//!    [`ContactParams::height`] x the subject's height above the ground) and nearly still
//!    vertically (moving less than [`ContactParams::vertical_speed`] x the subject's height
//!    per second). Horizontal stillness is not asked: in an in-place clip the planted foot
//!    slides backwards at the walking speed, which is what root motion measures. Each contact
//!    has a weight in (0, 1] for how low it is, `(low - max(h_f, h_f+1)) / (low - ground)`
//!    (above 1 for a vertex below the ground), the sole more than the ankle.

use rayon::prelude::*;
use surfcap_mesh::UpAxis;

use crate::motion_plane_alignment::plane_axes;

/// Thresholds of the contact detection, as fractions of the subject's height so that one set
/// works in any unit and for any body size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// A contact vertex is at most this fraction of the subject's height above the ground
    /// (0.04: 7 cm for a 1.75 m person, the height of a flat foot's sole and toes, not the
    /// ankle; a heel rising by more leaves contact).
    pub height: f64,
    /// A planted foot's vertices agree with each other horizontally within this fraction of
    /// the subject's height per second, and the planted group's step changes by about that
    /// much from one frame to the next (0.25: 0.44 m/s for a 1.75 m person; a swinging foot
    /// moves several metres per second). Used by root motion's grouping, not by the
    /// detection itself.
    pub speed: f64,
    /// A contact vertex moves less than this fraction of the subject's height per second
    /// vertically (0.5: 0.9 m/s for a 1.75 m person; a running foot lands and rolls faster
    /// than the horizontal tolerance allows: at 0.25 the CMU jog kept contact at 15 of its 46
    /// steps and lost 95% of its travel, at 0.5 it keeps it within 6.3%).
    pub vertical_speed: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams { height: 0.04, speed: 0.25, vertical_speed: 0.5 }
    }
}

/// One vertex in contact with the ground during one frame step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundContact {
    pub vertex: u32,
    /// How low the vertex is over the step: 1 on the ground, 0 at the contact height (above 1
    /// below the ground).
    pub weight: f64,
}

/// The ground contacts of a clip.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundContacts {
    /// Frames of the clip.
    pub frames: usize,
    /// The ground height found (along the up axis, signed as the up axis points).
    pub ground: f64,
    /// The subject's height: the largest vertical extent of a frame of the clip.
    pub subject_height: f64,
    /// The highest a contact vertex may be: `ground + height x subject_height`.
    pub contact_height: f64,
    /// One entry per frame step f -> f+1 (frames - 1 of them, none for an empty clip): its
    /// contact vertices in increasing vertex order.
    pub steps: Vec<Vec<GroundContact>>,
}

/// Height of vertex `k` of a frame along the up axis (`w` its coordinate, `sign` its direction).
#[inline]
pub(crate) fn vertex_height(frame: &[f32], k: usize, w: usize, sign: f64) -> f64 {
    sign * frame[3 * k + w] as f64
}

/// Detects the ground contacts of one clip, `positions` being `[frames][n_vertices][3]` (see
/// the module doc). Steps are examined in parallel; the result does not depend on the thread
/// count.
pub fn ground_contacts(
    positions: &[f32],
    n_vertices: usize,
    fps: f64,
    up: UpAxis,
    params: &ContactParams,
) -> GroundContacts {
    let (_, _, w) = plane_axes(up);
    let sign = up.axis_and_sign().1;
    let per_frame = 3 * n_vertices;
    let frames: Vec<&[f32]> = if per_frame == 0 { Vec::new() } else { positions.chunks_exact(per_frame).collect() };
    let extents: Vec<(f64, f64)> = frames
        .par_iter()
        .map(|f| {
            (0..n_vertices).fold((f64::MAX, f64::MIN), |(lo, hi), k| {
                let h = vertex_height(f, k, w, sign);
                (lo.min(h), hi.max(h))
            })
        })
        .collect();
    let size = extents.iter().fold(0.0f64, |s, &(lo, hi)| s.max(hi - lo));
    let mut sorted: Vec<f64> = extents.iter().map(|e| e.0).collect();
    sorted.sort_by(f64::total_cmp);
    let ground = sorted.get(sorted.len() / 5).copied().unwrap_or(0.0);
    let low = ground + params.height * size;
    let rise = params.vertical_speed * size / fps;
    let steps = frames
        .par_windows(2)
        .map(|pair| {
            let (a, b) = (pair[0], pair[1]);
            (0..n_vertices)
                .filter_map(|k| {
                    let (ha, hb) = (vertex_height(a, k, w, sign), vertex_height(b, k, w, sign));
                    let planted = ha < low && hb < low && (hb - ha).abs() < rise;
                    planted.then(|| GroundContact {
                        vertex: k as u32,
                        weight: (low - ha.max(hb)) / (low - ground).max(f64::MIN_POSITIVE),
                    })
                })
                .collect()
        })
        .collect();
    GroundContacts { frames: frames.len(), ground, subject_height: size, contact_height: low, steps }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_still_vertices_touch_and_rising_or_high_ones_do_not() {
        // Four vertices at 10 fps, +y up: 0 stays on the ground, 1 lifts off fast, 2 stays high
        // (it gives the subject its height of 2), 3 sits a little above the ground.
        let frame = |t: f32| [0.0, 0.0, 0.0, 0.0, 0.5 * t, 0.0, 0.0, 2.0, 0.0, 1.0, 0.05, 0.0];
        let positions: Vec<f32> = (0..3).flat_map(|f| frame(f as f32)).collect();
        let c = ground_contacts(&positions, 4, 10.0, UpAxis::PosY, &ContactParams::default());
        assert_eq!(c.ground, 0.0);
        assert_eq!(c.subject_height, 2.0);
        assert!((c.contact_height - 0.08).abs() < 1e-12);
        assert_eq!(c.steps.len(), 2);
        assert_eq!(c.frames, 3);
        for s in &c.steps {
            let v: Vec<u32> = s.iter().map(|x| x.vertex).collect();
            assert_eq!(v, vec![0, 3]);
            assert!((s[0].weight - 1.0).abs() < 1e-12);
            assert!((s[1].weight - (0.08 - 0.05f32 as f64) / 0.08).abs() < 1e-9, "{}", s[1].weight);
        }
        // Slow enough, the rising vertex is still in contact while low: 0.5 per second at 10 fps
        // moves 0.05 a step (< 0.5 x 2 / 10) and stays under 0.08 for one step.
        let slow: Vec<f32> = (0..3).flat_map(|f| frame(f as f32 / 10.0)).collect();
        let c = ground_contacts(&slow, 4, 10.0, UpAxis::PosY, &ContactParams::default());
        assert!(c.steps[0].iter().any(|x| x.vertex == 1));
        assert!(!c.steps[1].iter().any(|x| x.vertex == 1));
        let none = ground_contacts(&[], 0, 30.0, UpAxis::PosY, &ContactParams::default());
        assert!(none.steps.is_empty() && none.frames == 0);
    }
}
