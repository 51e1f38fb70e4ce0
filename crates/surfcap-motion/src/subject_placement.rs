//! Where transitions place a subject: Blend's rigid re-placement (Algorithm 2's motion-plane
//! alignment of the destination onto the source, and the translation of both towards the
//! integrated centre P) for a subject that travels, the captured placement for one that does
//! not.
//!
//! Algorithm 2 is written for locomotion: two walks meet in arbitrary headings and places, and
//! the destination is turned and moved onto the source so that the motion continues. On a
//! subject that stays where it was captured (a head turning on its shoulders, a dancer in
//! place) every frame already shares one placement, and re-placing it turns and slides the whole
//! subject: on the moving head, a transition from `turn` to `nod` turned the bust by about 60
//! degrees about the vertical, as the alignment matched the turned skull. There the frames keep
//! their captured placement: no rotation about the vertical, no ground translation, the poses
//! still interpolated.
//!
//! The subject **travels** when the centre of mass (vertex mean) of some frame lies farther
//! than [`TRAVEL_FRACTION`] of the subject's size (the largest extent of one frame's bounding
//! box, over all frames) from the centre of its sequence's first frame, in the ground plane. Ground
//! travel alone decides: a head turning or a dancer spinning changes heading without going
//! anywhere, and needs no re-placement for it.

use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_mesh::{Subject, UpAxis};

use crate::blend::{BlendStep, Lambda, centre};

/// A subject travels when a frame's centre gets farther than this fraction of its size from
/// its sequence's start. Half the size: a 1.75 m person walking at 1.3 m/s is past it in 0.7 s,
/// while the sway of an in-place game clip stays well within it (under 0.1 of the height for
/// in-place walks and jumps) and the moving head's centre within 0.17 of its size (its nod). The Vlasic
/// crane (0.74) and samba (0.62) and the Briceno dance (0.57) travel.
pub const TRAVEL_FRACTION: f64 = 0.5;

/// How transitions place the subject.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// Algorithm 2's rigid re-placement: the destination aligned onto the source.
    Aligned,
    /// The frames where they were captured.
    Captured,
}

/// The decision and what it was made from.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SubjectTravel {
    /// The largest ground distance of a frame's centre from its sequence's first frame's.
    pub excursion: f64,
    /// The subject's size: the largest extent of one frame's bounding box, over all frames.
    pub size: f64,
    pub placement: Placement,
}

/// Whether `subject` travels (see the module documentation), and so which placement its
/// transitions use.
pub fn subject_travel(subject: &Subject) -> SubjectTravel {
    let (iu, iv, _) = plane_axes(subject.up_axis);
    let mut excursion: f64 = 0.0;
    let mut size: f64 = 0.0;
    for q in subject.sequences() {
        let nv = q.n_vertices();
        let mut first = None;
        for f in q.positions().chunks_exact(3 * nv) {
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for v in f.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            size = (0..3).map(|k| f64::from(hi[k] - lo[k])).filter(|x| x.is_finite()).fold(size, f64::max);
            let c = centre(f);
            let c0 = *first.get_or_insert(c);
            excursion = excursion.max((c[iu] - c0[iu]).hypot(c[iv] - c0[iv]));
        }
    }
    let placement = if excursion > TRAVEL_FRACTION * size { Placement::Aligned } else { Placement::Captured };
    SubjectTravel { excursion, size, placement }
}

/// [`crate::blend::blend_placements_from`] for the captured placement: every frame stays where
/// it was captured (both motions the identity) and the centre of output frame t is the
/// lambda-mix of its two frames' centres.
pub fn captured_placements(
    up: UpAxis,
    cs: &[[f64; 3]],
    cd: &[[f64; 3]],
    path: &[(usize, usize)],
    lambda: Lambda,
) -> Vec<BlendStep> {
    let l = path.len();
    path.iter()
        .enumerate()
        .map(|(t, &(n, m))| {
            let lam = match lambda {
                Lambda::Ramp if l > 1 => t as f64 / (l - 1) as f64,
                Lambda::Ramp => 1.0,
                Lambda::Constant(x) => x,
            };
            let centre = std::array::from_fn(|k| (1.0 - lam) * cs[n][k] + lam * cd[m][k]);
            BlendStep { n, m, lambda: lam, src: PlaneMotion::identity(up), dst: PlaneMotion::identity(up), centre }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};

    #[test]
    fn a_crawling_subject_travels_and_one_held_in_place_does_not() {
        let w = worm_subject(&WormParams { rings: 12, segments: 8, frames: 40, ..Default::default() }).unwrap();
        let t = subject_travel(&w);
        assert_eq!(t.placement, Placement::Aligned, "{t:?}");
        // The same frames, each moved back so its centre stays at the first frame's.
        let seq = &w.sequences()[0];
        let c0 = centre(seq.frame(0));
        let mut positions = Vec::new();
        for f in 0..seq.n_frames() {
            let mut p = seq.frame(f).to_vec();
            let c = centre(&p);
            for v in p.chunks_exact_mut(3) {
                v[0] -= (c[0] - c0[0]) as f32;
                v[2] -= (c[2] - c0[2]) as f32;
            }
            positions.extend(p);
        }
        let still = surfcap_mesh::Sequence::new("still", seq.n_vertices(), positions).unwrap();
        let held = w.derived("held", still).unwrap();
        let t = subject_travel(&held);
        assert!(t.excursion < 1e-5 && t.size > 0.0, "{t:?}");
        assert_eq!(t.placement, Placement::Captured);
    }

    #[test]
    fn captured_placements_move_nothing_and_mix_the_centres() {
        let cs = [[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let cd = [[5.0, 1.0, 5.0], [6.0, 3.0, 5.0]];
        let steps = captured_placements(UpAxis::PosY, &cs, &cd, &[(0, 0), (1, 1)], Lambda::Ramp);
        assert_eq!(steps.len(), 2);
        assert_eq!(steps[0].centre, cs[0]);
        assert_eq!(steps[1].centre, cd[1]);
        assert!(steps.iter().all(|s| s.src == PlaneMotion::identity(UpAxis::PosY) && s.dst == s.src));
    }
}
