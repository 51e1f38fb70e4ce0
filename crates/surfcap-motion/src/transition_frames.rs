//! The frames of one optimal transition: its DTW warp (thesis eq. 2.50-2.54) recomputed from the
//! distance matrix, then Blend (Algorithm 2: recurring motion-plane alignment and non-linear
//! interpolation along the warp, lambda ramping from 0 to 1). Used both to play walks
//! (Algorithm 3, [`crate::walk_sequence::walk_sequence`]) and to show one transition.

use surfcap_mesh::Subject;

use crate::blend::{Lambda, Mixing, blend_placed};
use crate::dtw::{Slope, Warp, dtw_window};
use crate::subject_placement::Placement;

/// A transition's frames and its warp.
#[derive(Debug, Clone)]
pub struct TransitionFrames {
    /// One frame per warp cell, in the source's placement: the first is source frame `i`
    /// itself, the last destination frame `j` moved by the transition's rigid end placement.
    pub frames: Vec<Vec<f32>>,
    /// The warp over global frame numbers (source frame, destination frame) per cell.
    pub warp: Warp,
}

impl TransitionFrames {
    /// What each frame mixes: (source frame, destination frame, destination weight), global
    /// frame numbers, the weight the ramp of Algorithm 2 gives the cell (`Lambda::Ramp`: cell
    /// t of l has weight t / (l - 1)). Whatever else a frame carries (its texture, thesis
    /// 4.6.1 and Fig. 7.1) is blended with these weights so it follows the geometry.
    pub fn mix(&self) -> Vec<FrameMix> {
        let l = self.warp.path.len();
        self.warp
            .path
            .iter()
            .enumerate()
            .map(|(t, &(a, b))| FrameMix {
                from: a as u32,
                to: b as u32,
                weight: if l > 1 { t as f32 / (l - 1) as f32 } else { 1.0 },
            })
            .collect()
    }
}

/// The frames an output frame is made from: `from` with weight `1 - weight`, `to` with
/// `weight` (global frame numbers; an original frame is itself with weight 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameMix {
    pub from: u32,
    pub to: u32,
    pub weight: f32,
}

impl FrameMix {
    /// An original frame.
    pub fn original(frame: u32) -> FrameMix {
        FrameMix { from: frame, to: frame, weight: 0.0 }
    }
}

/// The transition from global frame `i` (source segment `i .. i + li`) to global frame `j`
/// (destination segment `j + 1 - lj ..= j`) of `subject`, whose all-pairs distances are `d`
/// (row-major over the global frame index). `None` when the segments do not fit in the subject
/// or the slope constraint admits no warp.
pub fn transition_frames(
    subject: &Subject,
    d: &[f64],
    source: (usize, usize),
    destination: (usize, usize),
    slope: Slope,
) -> Result<Option<TransitionFrames>, surfcap_geometry::Error> {
    let placement = crate::subject_placement::subject_travel(subject).placement;
    transition_frames_played(subject, d, source, destination, slope, placement, |_, g| subject.frame(g))
}

/// Which segment of a transition a frame belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Segment {
    Source,
    Destination,
}

/// [`transition_frames`] whose poses are `played(segment, g)` for global frame `g` of either
/// segment (the captured frame, or one of the same vertex count shown in its stead, e.g. a
/// learned variant of it), while the warp and every rigid placement of Blend come from the
/// captured frames ([`crate::blend::blend_placed`], by `placement`: Algorithm 2's re-placement
/// or, for a subject that does not travel, the captured one); `None` from `played` when `g` is
/// not a frame. The warp is the captured transition's too: a substitute follows its frame closely
/// enough that the same frames still match (thesis 6.6).
pub fn transition_frames_played<'a>(
    subject: &'a Subject,
    d: &[f64],
    (i, li): (usize, usize),
    (j, lj): (usize, usize),
    slope: Slope,
    placement: Placement,
    played: impl Fn(Segment, usize) -> Option<&'a [f32]>,
) -> Result<Option<TransitionFrames>, surfcap_geometry::Error> {
    let Some(warp) = dtw_window(d, subject.n_frames(), i, li, j, lj, slope) else {
        return Ok(None);
    };
    let d0 = j + 1 - lj;
    let frames = |seg: Segment, range: std::ops::Range<usize>, f: &dyn Fn(Segment, usize) -> Option<&'a [f32]>| {
        range.map(|g| f(seg, g)).collect::<Option<Vec<&[f32]>>>()
    };
    let captured = |_: Segment, g: usize| subject.frame(g);
    let (Some(src), Some(dst), Some(src_played), Some(dst_played)) = (
        frames(Segment::Source, i..i + li, &captured),
        frames(Segment::Destination, d0..j + 1, &captured),
        frames(Segment::Source, i..i + li, &played),
        frames(Segment::Destination, d0..j + 1, &played),
    ) else {
        return Ok(None);
    };
    let offsets: Vec<(usize, usize)> = warp.path.iter().map(|&(a, b)| (a - i, b - d0)).collect();
    let frames = blend_placed(
        subject.topology(),
        subject.up_axis,
        (&src, &dst),
        (&src_played, &dst_played),
        &offsets,
        Lambda::Ramp,
        Mixing::Nonlinear,
        placement,
    )?;
    Ok(Some(TransitionFrames { frames, warp }))
}
