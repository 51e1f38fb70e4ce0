//! A stand-in for a transition's Blend frames that a page can draw at once from the captured
//! frames it already holds: for each frame of the transition, the two captured frames Blend
//! mixes (thesis Algorithm 2: source frame n and destination frame m along the DTW warp), their
//! rigid placements, and the weight lambda, so that the frame is drawn as the linear
//! interpolation of the two placed poses (eq. 2.23: the destination aligned onto the source by
//! the motion-plane alignment, eq. 2.3-2.5, then (1 - lambda) v_i + lambda v_j).
//!
//! It has the exact Blend frame's rigid placement and centre of mass (the non-linear
//! interpolation, eq. 2.45-2.49, pins each side to the linearly interpolated centroid), and
//! differs from it only in the pose: shown while the exact frame (made by the server's
//! gradient-domain solves) has not arrived, and replaced by it when it has.

use surfcap_geometry::motion_plane_alignment::{PlaneMotion, motion_plane_alignment};
use surfcap_mesh::Subject;
use surfcap_motion::blend::{Lambda, blend_placements, centre};
use surfcap_motion::subject_placement::{Placement, captured_placements};
use surfcap_motion::walk_sequence::{Step as EdgeStep, WalkModel};

/// One frame of a transition as two placed captured frames and a weight: the frame is
/// `(1 - lambda) * ga(frame a) + lambda * gb(frame b)` (global frame numbers), in the coordinates
/// where the transition's source frame is unmoved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayMix {
    pub a: u32,
    pub b: u32,
    pub lambda: f64,
    pub ga: PlaneMotion,
    /// The destination frame's placement: Blend's rigid motion of the destination segment, then
    /// (when the subject is re-placed, [`Placement::Aligned`]) the alignment onto the placed
    /// source frame that the interpolation starts with.
    pub gb: PlaneMotion,
}

impl DisplayMix {
    /// The stand-in frame's vertices.
    pub fn positions(&self, subject: &Subject) -> Option<Vec<f32>> {
        let (mut a, mut b) = (subject.frame(self.a as usize)?.to_vec(), subject.frame(self.b as usize)?.to_vec());
        self.ga.apply(&mut a);
        self.gb.apply(&mut b);
        let l = self.lambda;
        Some(a.iter().zip(&b).map(|(&x, &y)| ((1.0 - l) * x as f64 + l * y as f64) as f32).collect())
    }
}

/// The stand-ins of the frames transition `u -> v` of `model` adds between `u` and `v` (Blend's
/// frames S(2..L-1), as [`surfcap_motion::walk_sequence::walk_sequence`] plays them with `u`
/// unmoved); `d` is the distance matrix the model was built from. `None` when `u -> v` is not a
/// transition of the model.
pub fn display_blend(subject: &Subject, model: &WalkModel, d: &[f64], u: u32, v: u32) -> Option<Vec<DisplayMix>> {
    let Some(EdgeStep::Transition(t)) = model.step(u, v) else { return None };
    let offsets = model.warp(d, u, v)?;
    let (s0, d0) = (u as usize, (v + 1 - t.lj) as usize);
    let frames = |range: std::ops::Range<usize>| range.map(|g| subject.frame(g)).collect::<Option<Vec<&[f32]>>>();
    let src = frames(s0..s0 + t.li as usize)?;
    let dst = frames(d0..v as usize + 1)?;
    let up = subject.up_axis;
    let steps = match model.placement() {
        Placement::Aligned => blend_placements(up, &src, &dst, &offsets, Lambda::Ramp),
        Placement::Captured => {
            let cs: Vec<[f64; 3]> = src.iter().map(|f| centre(f)).collect();
            let cd: Vec<[f64; 3]> = dst.iter().map(|f| centre(f)).collect();
            captured_placements(up, &cs, &cd, &offsets, Lambda::Ramp)
        }
    };
    let inner = steps.len().saturating_sub(1);
    Some(
        steps
            .iter()
            .take(inner)
            .skip(1)
            .map(|st| {
                let gb = match model.placement() {
                    Placement::Aligned => {
                        let (mut a, mut b) = (src[st.n].to_vec(), dst[st.m].to_vec());
                        st.src.apply(&mut a);
                        st.dst.apply(&mut b);
                        motion_plane_alignment(&a, &b, None, up).0.after(&st.dst)
                    }
                    Placement::Captured => st.dst,
                };
                DisplayMix { a: (s0 + st.n) as u32, b: (d0 + st.m) as u32, lambda: st.lambda, ga: st.src, gb }
            })
            .collect(),
    )
}
