//! Clips authored as loops, and the wrap that plays them seamlessly.
//!
//! What it computes: for every sequence of a subject, whether its last pose is as close to its
//! first as the clip's own successive frames are to each other, and if so the wrap edge from the
//! last frame back to the start and the rigid motion that places the start after the last frame
//! so that the clip's travel carries on.
//!
//! Pose distance: the Euclidean distance between two frames after the optimal motion-plane
//! alignment of one onto the other (thesis eq. 2.2-2.5: rotation about the up axis and
//! ground-plane translation removed), i.e. the poses compared in the body frame. A clip imported
//! with recovered root motion travels, so its last and first frames are metres apart in the
//! world but alike in the body frame.
//!
//! Threshold: a clip of n >= [`MIN_LOOP_FRAMES`] frames loops when the gap d(last, first) is no
//! larger than [`LOOP_GAP_IN_STEPS`] = 1.5 times the largest of its own successive-frame
//! distances d(k, k + 1). A wrap no larger than the clip's own largest step pops no more than the
//! clip already does between two captured frames; the half step more admits a cycle whose length
//! is not a whole number of frames (cut at the nearest frame, the next cycle's start is missed
//! by up to half a frame) and a wrap that falls on the clip's fastest phase, where the largest
//! step is the wrap's own. A cut of a clip that does not loop (a walk that starts from standing,
//! half a cycle) has a gap of several of its largest steps.
//! Some exporters repeat the first frame at the
//! end: a gap below [`COPY_IN_STEPS`] = 1% of the clip's largest step means the last frame *is*
//! the first (an exporter's copy is exact up to rounding, while a seam where the motion eases or
//! turns back is a real, if small, step: a fraction of the steps beside it, but not 1% of the
//! largest), and the wrap then goes to the second frame (whose distance from the last must pass the same test), so no pose is
//! shown twice.
//!
//! Wrap placement: with the first frame a copy of the last, the start is placed by aligning it
//! onto the last frame (the second frame then follows as captured). Otherwise the first frame
//! is the one after the last: it is aligned onto the last frame, then moved once more by the
//! clip's last step (the motion-plane alignment of frame n - 2 onto frame n - 1, a rigid motion of
//! the ground plane): for a clip that travels or turns at a steady rate this continues the travel
//! and the turn by one frame's worth, as the clip's own next frame would.
//!
//! Segment bounds (thesis 2.5.3 gives a third of a second to two seconds, as long as a whole
//! 22-32 frame game cycle): [`segment_bounds_for_clips`] keeps a transition window inside half
//! of the shortest clip (one step of a two-step walk cycle, leaving the other half to be played
//! as captured) and its shortest window a third of that.

use surfcap_geometry::motion_plane_alignment::{PlaneMotion, motion_plane_alignment};
use surfcap_mesh::{FrameIndex, Subject, UpAxis};

use crate::edge_weights::EdgeWeights;

/// Shortest clip that can loop (a last step and one more).
pub const MIN_LOOP_FRAMES: usize = 4;

/// The largest wrap gap of a looping clip, in units of its largest successive-frame distance.
pub const LOOP_GAP_IN_STEPS: f64 = 1.5;

/// A last frame closer to the first than this, in units of the clip's largest step, is a copy of it.
pub const COPY_IN_STEPS: f64 = 0.01;

/// A clip that loops, and its wrap edge `last` -> `first` (global frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClipLoop {
    pub sequence: usize,
    pub last: u32,
    /// The wrap's destination: the clip's first frame, or its second when the last frame
    /// repeats the first.
    pub first: u32,
    /// Pose distance from the last frame to the wrap's destination.
    pub gap: f64,
    /// The clip's largest successive-frame distance.
    pub largest_step: f64,
    /// The last frame repeats the first (the wrap goes to the second).
    pub repeats_first: bool,
}

/// The looping clips of `index`, with `dist(i, j)` the body-frame pose distance of two global
/// frames (asked only for successive frames and for the last frame against the first two).
pub fn clip_loops_by(index: &FrameIndex, mut dist: impl FnMut(usize, usize) -> f64) -> Vec<ClipLoop> {
    let mut out = Vec::new();
    for s in 0..index.n_sequences() {
        let r = index.range(s);
        if r.len() < MIN_LOOP_FRAMES {
            continue;
        }
        let steps: Vec<f64> = (r.start..r.end - 1).map(|k| dist(k, k + 1)).collect();
        if steps.iter().any(|x| !x.is_finite()) {
            continue;
        }
        let largest_step = steps.iter().copied().fold(0.0, f64::max);
        let last = r.end - 1;
        let gap = dist(last, r.start);
        let repeats_first = gap < COPY_IN_STEPS * largest_step;
        let (first, gap) = if repeats_first { (r.start + 1, dist(last, r.start + 1)) } else { (r.start, gap) };
        if gap.is_finite() && gap <= LOOP_GAP_IN_STEPS * largest_step {
            out.push(ClipLoop {
                sequence: s,
                last: last as u32,
                first: first as u32,
                gap,
                largest_step,
                repeats_first,
            });
        }
    }
    out
}

/// Body-frame pose distance of two frames: the residual of eq. 2.2 after the motion-plane
/// alignment, as a Euclidean distance.
pub fn body_frame_distance(subject: &Subject, i: usize, j: usize) -> f64 {
    match (subject.frame(i), subject.frame(j)) {
        (Some(a), Some(b)) => motion_plane_alignment(a, b, None, subject.up_axis).1.sqrt(),
        _ => f64::INFINITY,
    }
}

/// The looping clips of `subject` ([`clip_loops_by`] with [`body_frame_distance`]).
pub fn clip_loops(subject: &Subject) -> Vec<ClipLoop> {
    clip_loops_by(subject.frame_index(), |i, j| body_frame_distance(subject, i, j))
}

/// The looping clips of frames read one at a time by `frame(g)` (global frame `g`'s positions,
/// e.g. from a subject cache, as the tile jobs read them): [`clip_loops`] on a subject of those
/// frames, bit for bit (the same [`body_frame_distance`] on the same positions), holding at most
/// four frames at once. The first error of `frame` is returned.
pub fn clip_loops_streamed<E>(
    index: &FrameIndex,
    up: UpAxis,
    mut frame: impl FnMut(usize) -> Result<Vec<f32>, E>,
) -> Result<Vec<ClipLoop>, E> {
    let mut held: Vec<(usize, Vec<f32>)> = Vec::new();
    let mut failed: Option<E> = None;
    let loops = clip_loops_by(index, |i, j| {
        if failed.is_some() {
            return f64::INFINITY;
        }
        // Keep what later calls ask again: the two frames now, and the sequence's first two
        // (its last frame is compared with them).
        let start = index.locate(i).map_or(i, |(s, _)| index.range(s).start);
        held.retain(|(g, _)| *g == i || *g == j || *g == start || *g == start + 1);
        for g in [i, j] {
            if !held.iter().any(|(h, _)| *h == g) {
                match frame(g) {
                    Ok(p) => held.push((g, p)),
                    Err(e) => {
                        failed = Some(e);
                        return f64::INFINITY;
                    }
                }
            }
        }
        let get = |g: usize| &held.iter().find(|(h, _)| *h == g).expect("held above").1;
        motion_plane_alignment(get(i), get(j), None, up).1.sqrt()
    });
    match failed {
        Some(e) => Err(e),
        None => Ok(loops),
    }
}

/// Where the wrap places the clip's `first` frame, in the coordinates where the `last` frame is
/// unmoved (see the module's documentation).
pub fn wrap_placement(subject: &Subject, l: &ClipLoop) -> PlaneMotion {
    let up = subject.up_axis;
    let frame = |g: usize| subject.frame(g).expect("loops are over the subject's frames");
    let (last, start) = (l.last as usize, subject.frame_index().range(l.sequence).start);
    let onto_last = motion_plane_alignment(frame(last), frame(start), None, up).0;
    if l.repeats_first {
        return onto_last;
    }
    let last_step = motion_plane_alignment(frame(last), frame(last - 1), None, up).0;
    last_step.after(&onto_last)
}

/// Gives every wrap edge the weight of a successive-frame step (alpha, Algorithm 1).
pub fn add_wrap_edges(w: &mut EdgeWeights, loops: &[ClipLoop]) {
    let (n, alpha) = (w.n, w.alpha.get());
    for l in loops {
        let k = l.last as usize * n + l.first as usize;
        if k < w.weight.len() {
            w.weight[k] = alpha;
        }
    }
}

/// Default segment bounds for a subject whose looping clips are `loops` over `index`:
/// [`crate::segment_bounds`] with the longest window no longer than half the shortest looping
/// clip (at least 2 frames) and the shortest window no longer than a third of the longest (at
/// least 1). Without looping clips, or with loops of two seconds or more, the thesis's bounds.
pub fn segment_bounds_for_clips(fps: f64, index: &FrameIndex, loops: &[ClipLoop]) -> (usize, usize) {
    let (lo, hi) = crate::segment_bounds(fps);
    let shortest = loops.iter().map(|l| index.range(l.sequence).len()).min().unwrap_or(usize::MAX);
    let hi = hi.min((shortest / 2).max(2));
    let lo = lo.min(hi.div_ceil(3)).max(1);
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Poses on a circle: a clip of n frames that goes once round loops; one that goes half
    /// round does not; one whose last frame repeats the first wraps to the second frame.
    #[test]
    fn loops_are_found_against_the_clips_own_steps() {
        let index = FrameIndex::new([12, 12, 13, 3]);
        let phase = |g: usize| -> f64 {
            let (s, k) = index.locate(g).unwrap();
            let k = k as f64;
            match s {
                0 => k / 12.0, // once round in 12 steps: the 13th would be the first
                1 => k / 24.0, // half round
                2 => k / 12.0, // once round with the first frame repeated at the end
                _ => k / 3.0,  // too short to loop
            }
        };
        let dist = |i: usize, j: usize| {
            let (a, b) = (std::f64::consts::TAU * phase(i), std::f64::consts::TAU * phase(j));
            ((a.cos() - b.cos()).powi(2) + (a.sin() - b.sin()).powi(2)).sqrt()
        };
        let loops = clip_loops_by(&index, dist);
        assert_eq!(loops.len(), 2, "{loops:?}");
        assert_eq!((loops[0].sequence, loops[0].last, loops[0].first, loops[0].repeats_first), (0, 11, 0, false));
        assert!((loops[0].gap - loops[0].largest_step).abs() < 1e-12, "the wrap is one of the circle's equal steps");
        assert_eq!((loops[1].sequence, loops[1].last, loops[1].first, loops[1].repeats_first), (2, 36, 25, true));
    }

    #[test]
    fn wrap_edges_cost_a_step_and_bounds_fit_the_shortest_clip() {
        let alpha = crate::edge_weights::Alpha::new(0.1).unwrap();
        let mut w = EdgeWeights { n: 4, alpha, d_scale: 1.0, weight: vec![f64::INFINITY; 16] };
        let l = ClipLoop { sequence: 0, last: 3, first: 0, gap: 1.0, largest_step: 1.0, repeats_first: false };
        add_wrap_edges(&mut w, &[l]);
        assert_eq!(w.at(3, 0), 0.1);
        let index = FrameIndex::new([300, 25, 33, 20]);
        let looping = |s: usize| ClipLoop { sequence: s, ..l };
        assert_eq!(segment_bounds_for_clips(30.0, &index, &[]), (10, 60), "no loop: the thesis's bounds");
        assert_eq!(segment_bounds_for_clips(30.0, &index, &[looping(0)]), (10, 60));
        assert_eq!(segment_bounds_for_clips(30.0, &index, &[looping(0), looping(1), looping(2)]), (4, 12));
        assert_eq!(segment_bounds_for_clips(30.0, &index, &[looping(2)]), (6, 16), "the short clip does not loop");
    }

    /// Frames read one at a time give the subject's loops (a clip that goes out and back loops,
    /// one that only goes out does not), and a read error is returned, not a loop.
    #[test]
    fn loops_of_streamed_frames_are_the_subjects() {
        use surfcap_mesh::{Sequence, Topology, Units, UpAxis};
        let tri = |a: f32| [0.0f32, 0.0, 0.0, 0.3 + 0.1 * a.cos(), 0.0, 0.1 * a.sin(), 0.1, 0.2 * a, 0.4];
        let there_and_back: Vec<f32> = [0.0f32, 0.2, 0.4, 0.6, 0.4, 0.2, 0.05].iter().flat_map(|&a| tri(a)).collect();
        let out: Vec<f32> = (0..7).flat_map(|k| tri(0.2 * k as f32)).collect();
        let topology = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let seqs = vec![Sequence::new("back", 3, there_and_back).unwrap(), Sequence::new("out", 3, out).unwrap()];
        let s = Subject::new("t", topology, seqs, 30.0, UpAxis::parse("+y").unwrap(), Units::metres()).unwrap();
        let whole = clip_loops(&s);
        assert_eq!(whole.len(), 1, "{whole:?}");
        assert_eq!((whole[0].sequence, whole[0].last, whole[0].first), (0, 6, 0));
        let mut reads = 0;
        let streamed = clip_loops_streamed(s.frame_index(), s.up_axis, |g| {
            reads += 1;
            Ok::<_, String>(s.frame(g).unwrap().to_vec())
        })
        .unwrap();
        assert_eq!(streamed, whole);
        assert!(reads <= 2 * s.n_frames(), "{reads} reads of {} frames", s.n_frames());
        let e = clip_loops_streamed(s.frame_index(), s.up_axis, |g| {
            if g == 9 { Err(format!("frame {g} unreadable")) } else { Ok(s.frame(g).unwrap().to_vec()) }
        })
        .unwrap_err();
        assert_eq!(e, "frame 9 unreadable");
    }

    /// A rigid triangle gliding +1 along x per frame: every pose is alike in the body frame, so
    /// the clip loops, and the wrap places the first frame one step past the last.
    #[test]
    fn the_wrap_carries_the_travel_on() {
        use surfcap_mesh::{Sequence, Topology, Units, UpAxis};
        let tri = [0.0f32, 0.0, 0.0, 0.3, 0.0, 0.1, 0.1, 0.0, 0.4];
        let positions: Vec<f32> =
            (0..5).flat_map(|f| tri.chunks_exact(3).flat_map(move |v| [v[0] + f as f32, v[1], v[2]])).collect();
        let topology = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let seq = Sequence::new("glide", 3, positions).unwrap();
        let s = Subject::new("t", topology, vec![seq], 30.0, UpAxis::parse("+y").unwrap(), Units::metres()).unwrap();
        let loops = clip_loops(&s);
        assert_eq!(loops.len(), 1);
        let g = wrap_placement(&s, &loops[0]);
        let c0 = crate::blend::centre(s.frame(0).unwrap());
        let placed = g.apply_point(c0);
        assert!((placed[0] - (c0[0] + 5.0)).abs() < 1e-5 && (placed[2] - c0[2]).abs() < 1e-5, "{placed:?}");
    }
}
