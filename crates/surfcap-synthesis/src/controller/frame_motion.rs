//! What each captured frame is doing, as the interactive controller matches inputs against it:
//! the direction of travel (heading) and the speed of its tracked centre on the ground plane,
//! and its gait (idle, walk or run).
//!
//! Heading and speed: the central difference of the tracked centre over a quarter of a second
//! either side of the frame, within its own sequence (one-sided at the sequence's ends), in the
//! ground plane. The sway of the centre within a step averages out over half a second. A frame
//! slower than [`IDLE_HEIGHTS_PER_SECOND`] has no heading (`NaN`): standing, the centre's
//! direction of travel is noise.
//!
//! Gait: a frame of a sequence tagged `idle` is idle; otherwise by speed relative to the
//! subject's height (so that it holds for subjects in any unit): under
//! [`IDLE_HEIGHTS_PER_SECOND`] idle, from [`RUN_HEIGHTS_PER_SECOND`] run, walk between. For a
//! 1.75 m person these are 0.35 m/s and 1.84 m/s (people walk at 1.2-1.6 m/s and jog from 2 m/s).

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_mesh::Subject;

/// Below this speed, in subject heights per second, a frame is idle.
pub const IDLE_HEIGHTS_PER_SECOND: f64 = 0.2;
/// From this speed, in subject heights per second, a frame runs.
pub const RUN_HEIGHTS_PER_SECOND: f64 = 1.05;

/// A gait, as inputs ask for it and frames show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Gait {
    Idle,
    Walk,
    Run,
}

impl Gait {
    pub const ALL: [Gait; 3] = [Gait::Idle, Gait::Walk, Gait::Run];

    pub fn name(self) -> &'static str {
        match self {
            Gait::Idle => "idle",
            Gait::Walk => "walk",
            Gait::Run => "run",
        }
    }

    /// `idle`, `walk` or `run` (also `jog`), as a user types it.
    pub fn parse(text: &str) -> Option<Gait> {
        match text.trim().to_ascii_lowercase().as_str() {
            "idle" | "stand" => Some(Gait::Idle),
            "walk" => Some(Gait::Walk),
            "run" | "jog" => Some(Gait::Run),
            _ => None,
        }
    }
}

/// Heading, speed and gait of every captured frame (global frame numbers).
#[derive(Debug, Clone)]
pub struct FrameMotion {
    /// Direction of travel in the frame's captured coordinates, radians from the first ground
    /// axis towards the second (`atan2(v, u)`); `NaN` for an idle frame.
    pub heading: Vec<f64>,
    /// Ground speed of the tracked centre, subject units per second.
    pub speed: Vec<f64>,
    pub gait: Vec<Gait>,
    /// The subject's height (subject units), the scale of the gait thresholds.
    pub height: f64,
}

impl FrameMotion {
    /// The motion of every frame of `s` from the tracked centres `centres` (one per global
    /// frame, e.g. the walk model's).
    pub fn new(s: &Subject, centres: &[[f64; 3]]) -> Self {
        let (iu, iv, _) = plane_axes(s.up_axis);
        let height = surfcap_motion::clip_travel::subject_height(s).max(f64::MIN_POSITIVE);
        let half = (0.25 * s.fps).round().max(1.0) as usize;
        let index = s.frame_index();
        let n = centres.len();
        let (mut heading, mut speed, mut gait) = (vec![f64::NAN; n], vec![0.0; n], vec![Gait::Idle; n]);
        for (q, seq) in s.sequences().iter().enumerate() {
            let r = index.range(q);
            let idle_clip = seq.tags.iter().any(|t| t == "idle");
            for f in r.clone() {
                let (a, b) = (f.saturating_sub(half).max(r.start), (f + half).min(r.end - 1));
                if b <= a {
                    continue;
                }
                let (ca, cb) = (centres[a], centres[b]);
                let (du, dv) = (cb[iu] - ca[iu], cb[iv] - ca[iv]);
                let v = du.hypot(dv) * s.fps / (b - a) as f64;
                speed[f] = v;
                let relative = v / height;
                gait[f] = if idle_clip || relative < IDLE_HEIGHTS_PER_SECOND {
                    Gait::Idle
                } else if relative >= RUN_HEIGHTS_PER_SECOND {
                    Gait::Run
                } else {
                    Gait::Walk
                };
                if relative >= IDLE_HEIGHTS_PER_SECOND {
                    heading[f] = dv.atan2(du);
                }
            }
        }
        FrameMotion { heading, speed, gait, height }
    }

    /// Whether some frame shows `gait`.
    pub fn has(&self, gait: Gait) -> bool {
        self.gait.contains(&gait)
    }

    /// The median speed of the frames of `gait` (`None` when no frame shows it).
    pub fn typical_speed(&self, gait: Gait) -> Option<f64> {
        let mut v: Vec<f64> = self.speed.iter().zip(&self.gait).filter(|x| *x.1 == gait).map(|x| *x.0).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    }

    /// The fastest frame's speed.
    pub fn fastest(&self) -> f64 {
        self.speed.iter().copied().fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{Sequence, Topology, Units, UpAxis};

    /// A quad gliding along +x at 1 height per second (walk), then one standing still (idle).
    #[test]
    fn heading_speed_and_gait_of_a_glide_and_a_stand() {
        let quad = |x: f32| vec![x, 0.0, 0.0, x + 0.1, 1.0, 0.0, x, 0.0, 0.1, x + 0.1, 0.0, 0.1];
        let glide: Vec<f32> = (0..30).flat_map(|f| quad(f as f32 / 30.0)).collect();
        let stand: Vec<f32> = (0..30).flat_map(|_| quad(0.0)).collect();
        let topology = Topology::new(4, vec![[0, 1, 2], [1, 3, 2]], None).unwrap();
        let seqs = vec![Sequence::new("glide", 4, glide).unwrap(), Sequence::new("stand", 4, stand).unwrap()];
        let s = Subject::new("q", topology, seqs, 30.0, UpAxis::parse("+y").unwrap(), Units::metres()).unwrap();
        let centres: Vec<[f64; 3]> =
            (0..s.n_frames()).map(|g| surfcap_motion::blend::centre(s.frame(g).unwrap())).collect();
        let m = FrameMotion::new(&s, &centres);
        assert!((m.height - 1.0).abs() < 1e-6);
        for f in 0..30 {
            assert!((m.speed[f] - 1.0).abs() < 1e-4, "frame {f}: {}", m.speed[f]);
            assert!(m.heading[f].abs() < 1e-6);
            assert_eq!(m.gait[f], Gait::Walk);
            assert_eq!(m.gait[30 + f], Gait::Idle);
            assert!(m.heading[30 + f].is_nan());
        }
        assert_eq!(m.typical_speed(Gait::Run), None);
        assert!(m.has(Gait::Idle) && !m.has(Gait::Run));
        assert_eq!(Gait::parse("Jog"), Some(Gait::Run));
    }
}
