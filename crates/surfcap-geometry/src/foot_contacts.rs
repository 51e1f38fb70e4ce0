//! Per-foot contact signals: for every foot (a vertex set the caller gives, e.g. a leg body
//! part) and every frame, how firmly the foot is planted, in [0, 1]. The thesis aligns
//! sequences "with dynamic time warping guided with feet contact annotation" (6.4, 6.8); mesh
//! data has no annotation (2.5.5), so the signals come from [`crate::ground_contacts`]:
//!
//! - a vertex's contact at frame f is the larger of its contact weights (how low it is, 1 on
//!   the ground, 0 at the contact height; clamped to 1 below the ground) over the two steps
//!   f-1 -> f and f -> f+1 that frame f belongs to, 0 when it is in contact at neither;
//! - the foot's load at frame f is the sum of its vertices' contacts: how many of its vertices
//!   are down, and how low;
//! - the foot's signal is its load divided by its full load, clamped to 1: 1 where the foot is
//!   planted (a flat foot on a walk, the toes on a run), falling as the heel or toes lift, 0 in
//!   the swing; all 0 for a foot that never touches the ground. The full load is the 90th
//!   percentile of the foot's positive loads over the clip, not their largest: on a CMU walk
//!   the mannequin's stance loads vary by a factor of 1.6 from step to step, and normalised by
//!   their largest the lighter stances stayed near 0.5 (measured).
//!
//! The per-clip normaliser makes the signals of a walk and a run of one subject comparable in
//! timing (both reach 1 when planted) even though a running foot puts fewer vertices down. A
//! swinging foot that grazes the ground within the contact height gets a small value (few
//! vertices, low weights), not 0.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::ground_contacts::{GroundContact, GroundContacts};

/// Contact signals of the feet of one clip.
#[derive(Debug, Clone, PartialEq)]
pub struct FootContacts {
    /// `[foot][frame]`, each in [0, 1].
    pub feet: Vec<Vec<f64>>,
    /// Frames of the clip.
    pub frames: usize,
}

impl FootContacts {
    /// The feet's signals at frame `f` (one value per foot).
    pub fn at_frame(&self, f: usize) -> Vec<f64> {
        self.feet.iter().map(|s| s[f]).collect()
    }

    /// `[frame][foot]`: the per-frame contact vectors [`crate`]'s callers pass to time
    /// alignment.
    pub fn by_frame(&self) -> Vec<Vec<f64>> {
        (0..self.frames).map(|f| self.at_frame(f)).collect()
    }
}

/// Checks that every vertex of every foot is one of the mesh's `n_vertices`, and returns the
/// feet as membership masks.
pub(crate) fn foot_masks(feet: &[Vec<u32>], n_vertices: usize) -> Result<Vec<Vec<bool>>> {
    feet.iter()
        .enumerate()
        .map(|(foot, set)| {
            let mut mask = vec![false; n_vertices];
            for &vertex in set {
                *mask.get_mut(vertex as usize).ok_or(Error::FootVertex { foot, vertex, n_vertices })? = true;
            }
            Ok(mask)
        })
        .collect()
}

/// The per-foot contact signals of a clip (see the module doc) from its ground contacts
/// (detected on a mesh of `n_vertices`); `feet` are vertex sets, which may overlap. Frames are
/// computed in parallel; the result does not depend on the thread count.
pub fn foot_contacts(contacts: &GroundContacts, n_vertices: usize, feet: &[Vec<u32>]) -> Result<FootContacts> {
    let masks = foot_masks(feet, n_vertices)?;
    let frames = contacts.frames;
    let empty: &[GroundContact] = &[];
    let step = |s: Option<usize>| s.and_then(|s| contacts.steps.get(s)).map_or(empty, |v| v.as_slice());
    // [frame][foot] loads.
    let loads: Vec<Vec<f64>> = (0..frames)
        .into_par_iter()
        .map(|f| {
            let mut load = vec![0.0; masks.len()];
            let mut add = |vertex: u32, w: f64| {
                for (l, m) in load.iter_mut().zip(&masks) {
                    if m[vertex as usize] {
                        *l += w.min(1.0);
                    }
                }
            };
            // Merge the two steps' contacts (each in increasing vertex order), a vertex's
            // larger weight counted once.
            let (a, b) = (step(f.checked_sub(1)), step(Some(f)));
            let (mut i, mut j) = (0, 0);
            while i < a.len() || j < b.len() {
                match (a.get(i), b.get(j)) {
                    (Some(x), Some(y)) if x.vertex == y.vertex => {
                        add(x.vertex, x.weight.max(y.weight));
                        i += 1;
                        j += 1;
                    }
                    (Some(x), Some(y)) if x.vertex < y.vertex => {
                        add(x.vertex, x.weight);
                        i += 1;
                    }
                    (Some(x), None) => {
                        add(x.vertex, x.weight);
                        i += 1;
                    }
                    (_, Some(y)) => {
                        add(y.vertex, y.weight);
                        j += 1;
                    }
                    (None, None) => unreachable!("the loop runs while one list has contacts left"),
                }
            }
            load
        })
        .collect();
    let feet = (0..masks.len())
        .map(|k| {
            let mut down: Vec<f64> = loads.iter().map(|l| l[k]).filter(|&x| x > 0.0).collect();
            down.sort_by(f64::total_cmp);
            let full = down.get((down.len() * 9) / 10).copied().unwrap_or(0.0);
            loads.iter().map(|l| if full > 0.0 { (l[k] / full).min(1.0) } else { 0.0 }).collect()
        })
        .collect();
    Ok(FootContacts { feet, frames })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ground_contacts::{ContactParams, ground_contacts};
    use surfcap_mesh::UpAxis;

    /// Two feet of 3 vertices each and a head vertex 2 high, +y up, 10 fps: the left foot
    /// down at frames 0-3 and up (0.5 high) at 4-7, the right foot the opposite; at frame 2 the
    /// left foot's third vertex is half-way up the contact band.
    fn alternating() -> Vec<f32> {
        let mut out = Vec::new();
        for f in 0..8 {
            let (l, r) = if f < 4 { (0.0, 0.5) } else { (0.5, 0.0) };
            for k in 0..3 {
                let lift = if f == 2 && k == 2 { 0.04 } else { 0.0 };
                out.extend([k as f32 * 0.1, l + lift, 0.0]);
            }
            for k in 0..3 {
                out.extend([k as f32 * 0.1, r, 0.3]);
            }
            out.extend([0.0, 2.0, 0.0]);
        }
        out
    }

    #[test]
    fn the_feet_alternate_and_partial_contact_is_partial() {
        let p = alternating();
        // Slow vertical tolerance irrelevant: the feet jump 0.5 in one step (10 x 0.5 = 5/s,
        // above 0.5 x 2 per second), so no contact at the switch step.
        let c = ground_contacts(&p, 7, 10.0, UpAxis::PosY, &ContactParams::default());
        let fc = foot_contacts(&c, 7, &[vec![0, 1, 2], vec![3, 4, 5]]).unwrap();
        assert_eq!(fc.frames, 8);
        let (l, r) = (&fc.feet[0], &fc.feet[1]);
        for f in 0..8 {
            let (wl, wr) = if f < 4 { (1.0, 0.0) } else { (0.0, 1.0) };
            if f == 2 || f == 3 {
                // Vertex 2 at 0.04 at frame 2: weight (0.08 - 0.04) / 0.08 over the steps 1 -> 2
                // and 2 -> 3, the only step with contact that frame 3 belongs to (the foot
                // lifts over 3 -> 4).
                let want = (2.0 + (0.08 - 0.04f32 as f64) / 0.08) / 3.0;
                assert!((l[f] - want).abs() < 1e-6, "frame {f}: {} vs {want}", l[f]);
            } else {
                assert!((l[f] - wl).abs() < 1e-12, "left foot, frame {f}: {}", l[f]);
            }
            assert!((r[f] - wr).abs() < 1e-12, "right foot, frame {f}: {}", r[f]);
        }
        assert_eq!(fc.by_frame()[5], vec![0.0, 1.0]);
        // The head never touches; an unknown vertex is refused by name.
        let head = foot_contacts(&c, 7, &[vec![6]]).unwrap();
        assert!(head.feet[0].iter().all(|&x| x == 0.0));
        let e = foot_contacts(&c, 7, &[vec![0], vec![7]]).unwrap_err();
        assert_eq!(e.to_string(), "foot 1: vertex 7 is not a vertex of the mesh (expected 0 to 6)");
    }
}
