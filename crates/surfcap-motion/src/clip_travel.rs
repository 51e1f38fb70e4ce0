//! How far a clip's centre of mass travels over the ground, and whether the clip is "in place"
//! (authored with its root pinned, as most game animations are), so that path and distance
//! constraints (thesis 3.5.1, Huang et al.'s distance) are not attempted with clips that
//! cannot cover ground.
//!
//! Travel is the **net displacement** of the centre, first to last frame, in the ground plane:
//! the path length of the centre also adds up the back-and-forth sway of an in-place clip (a
//! 1 s in-place jump "travels" a metre of wobble and ends 0.2 m from its start), so it is
//! reported beside it but does not decide.

use surfcap_mesh::{Sequence, Subject, UpAxis};

use crate::walk_sequence::tracked_centre;

/// A clip is in place when its net horizontal displacement is under this fraction of the
/// subject's height per second of the clip (durations under a second count as one second).
/// 0.15 height/s is 0.26 m/s for a 1.75 m person: half the slowest walking speed (about
/// 0.35 height/s, 0.6 m/s), while the sway of a clip that does not travel stays within a
/// fraction of a step (under 0.1 height per clip for the KayKit characters' in-place walks,
/// runs and jumps).
pub const IN_PLACE_HEIGHTS_PER_SECOND: f64 = 0.15;

/// The ground travel of one sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipTravel {
    pub sequence: String,
    /// Horizontal distance between the centres of the first and last frames.
    pub net_displacement: f64,
    /// Length of the centre's horizontal track over the frames.
    pub path_length: f64,
    pub duration_seconds: f64,
    /// Whether the net displacement is negligible for the duration (see
    /// [`IN_PLACE_HEIGHTS_PER_SECOND`]).
    pub in_place: bool,
}

/// Net displacement and path length of the horizontal track of some points (subject units).
pub fn horizontal_travel(points: &[[f64; 3]], up: UpAxis) -> (f64, f64) {
    let w = up.axis_and_sign().0;
    let flat =
        |a: &[f64; 3], b: &[f64; 3]| (0..3).filter(|&k| k != w).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    let net = match (points.first(), points.last()) {
        (Some(a), Some(b)) => flat(a, b),
        _ => 0.0,
    };
    (net, points.windows(2).map(|p| flat(&p[0], &p[1])).sum())
}

/// The subject's height: the largest extent of a frame along the up axis, over all frames.
pub fn subject_height(s: &Subject) -> f64 {
    let w = s.up_axis.axis_and_sign().0;
    s.sequences()
        .iter()
        .flat_map(|q| q.positions().chunks_exact(3 * q.n_vertices()))
        .map(|f| {
            let (lo, hi) = f.chunks_exact(3).fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[w]), hi.max(p[w])));
            (hi - lo) as f64
        })
        .fold(0.0, f64::max)
}

/// The travel of one sequence of a subject of height `height` (see [`subject_height`]).
pub fn clip_travel(q: &Sequence, fps: f64, up: UpAxis, height: f64) -> ClipTravel {
    let centres: Vec<[f64; 3]> =
        q.positions().chunks_exact(3 * q.n_vertices()).map(|f| tracked_centre(f, None)).collect();
    let (net_displacement, path_length) = horizontal_travel(&centres, up);
    let duration_seconds = (q.n_frames().saturating_sub(1)) as f64 / fps;
    let in_place = net_displacement < IN_PLACE_HEIGHTS_PER_SECOND * height * duration_seconds.max(1.0);
    ClipTravel { sequence: q.name.clone(), net_displacement, path_length, duration_seconds, in_place }
}

/// The travel of every sequence of a subject.
pub fn subject_travel(s: &Subject) -> Vec<ClipTravel> {
    let height = subject_height(s);
    s.sequences().iter().map(|q| clip_travel(q, s.fps, s.up_axis, height)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{Topology, Units};

    /// A 2-tall triangle moved along x by `step` per frame, with a sideways sway of `sway`.
    fn clip(name: &str, frames: usize, step: f64, sway: f64) -> Sequence {
        let mut p = Vec::new();
        for f in 0..frames {
            let x = (step * f as f64) as f32;
            let z = (sway * (f as f64).sin()) as f32;
            p.extend([x, 0.0, z, x + 0.1, 0.0, z, x, 2.0, z]);
        }
        Sequence::new(name, 3, p).unwrap()
    }

    #[test]
    fn net_displacement_decides_not_the_swaying_path() {
        let t = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        // 2 s at 30 fps: a walker at 1 unit/s and a swaying clip that ends where it started.
        let s = Subject::new(
            "s",
            t,
            vec![clip("walk", 61, 1.0 / 30.0, 0.0), clip("sway", 61, 0.0, 0.2)],
            30.0,
            UpAxis::PosY,
            Units::metres(),
        )
        .unwrap();
        assert_eq!(subject_height(&s), 2.0);
        let t = subject_travel(&s);
        assert!(!t[0].in_place && (t[0].net_displacement - 2.0).abs() < 1e-6 && (t[0].path_length - 2.0).abs() < 1e-6);
        assert!(t[1].in_place, "{:?}", t[1]);
        assert!(t[1].net_displacement < 0.2 && t[1].path_length > 5.0, "{:?}", t[1]);
        assert_eq!(horizontal_travel(&[], UpAxis::PosY), (0.0, 0.0));
    }
}
