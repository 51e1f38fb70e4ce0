//! Procedural locomotion for the mannequin, with no file needed: walk, jog, turn left, turn
//! right, jump and idle, at any frame rate, seeded and deterministic.
//!
//! Each motion is a handful of periodic or phased joint angles (hip and knee flexion, arm swing,
//! elbow bend, pelvis sway, torso lean) driving the mannequin's skeleton by forward
//! kinematics, the body then set on the ground by its lower ankle (so bent knees lower the
//! pelvis), plus a root that really travels: along its heading at the gait's speed, the
//! heading turning at a constant rate for the turns, a ballistic arc for the jump. A seed varies
//! every amplitude, speed and frequency by up to +-5% and the gait's starting phase, through a
//! ChaCha8 stream (platform-independent), so seeds give different but reproducible motions.
//!
//! Conventions: the mannequin faces +z with +y up and its left side on +x; a heading of 0 faces
//! +z and a positive heading change is a turn to the left (counter-clockwise seen from above).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use surfcap_mesh::{Error, ErrorKind, Result};

use crate::mannequin::{ARM_DROP, Skeleton};

/// Largest bend of an ankle (radians).
const MAX_ANKLE: f64 = 0.5;

/// A procedural motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gait {
    Walk,
    Jog,
    TurnLeft,
    TurnRight,
    Jump,
    Idle,
}

impl Gait {
    pub const ALL: [Gait; 6] = [Gait::Walk, Gait::Jog, Gait::TurnLeft, Gait::TurnRight, Gait::Jump, Gait::Idle];

    /// The name used on the command line, as the sequence name and as its tag.
    pub fn name(self) -> &'static str {
        match self {
            Gait::Walk => "walk",
            Gait::Jog => "jog",
            Gait::TurnLeft => "turn_left",
            Gait::TurnRight => "turn_right",
            Gait::Jump => "jump",
            Gait::Idle => "idle",
        }
    }

    pub fn parse(name: &str) -> Result<Gait> {
        Gait::ALL.into_iter().find(|g| g.name() == name.trim()).ok_or_else(|| {
            let names: Vec<&str> = Gait::ALL.iter().map(|g| g.name()).collect();
            Error::new(ErrorKind::Unsupported, format!("unknown motion {name:?}: expected one of {}", names.join(", ")))
        })
    }

    /// Tags of the sequence: its name, plus `run` for the jog and `walk` for the turns, so that
    /// a path constraint restricted to a motion type finds them.
    pub fn tags(self) -> Vec<String> {
        let extra: &[&str] = match self {
            Gait::Jog => &["run"],
            Gait::TurnLeft | Gait::TurnRight => &["walk", "turn"],
            _ => &[],
        };
        std::iter::once(self.name()).chain(extra.iter().copied()).map(String::from).collect()
    }

    /// Default duration in seconds.
    pub fn duration(self) -> f64 {
        match self {
            Gait::Jump => 2.0,
            _ => 3.0,
        }
    }
}

/// The angles and root of one frame, before forward kinematics.
#[derive(Debug, Clone, Default)]
struct Angles {
    /// Hip flexion (leg forward, radians) and knee flexion (shin back), left then right.
    hip: [f64; 2],
    knee: [f64; 2],
    /// Arm swing (forward) and elbow bend, left then right.
    arm: [f64; 2],
    elbow: [f64; 2],
    /// Pelvis pitch forward, thorax extra pitch forward, thorax twist about the spine.
    lean: f64,
    chest_lean: f64,
    twist: f64,
    /// Root: horizontal position (x, z), height of the lower ankle above its standing height
    /// (0 while a foot is on the ground: the pelvis height follows from the legs), heading.
    root: [f64; 2],
    lift: f64,
    heading: f64,
}

/// Seeded variation: a factor in [1 - 5%, 1 + 5%].
struct Vary(ChaCha8Rng);

impl Vary {
    fn f(&mut self) -> f64 {
        1.0 + 0.05 * self.0.random_range(-1.0..=1.0)
    }
}

/// World transforms of the skeleton's joints for each frame of `gait` (for `Mannequin::pose`),
/// `duration` seconds at `fps`, varied by `seed`.
pub fn locomotion(sk: &Skeleton, gait: Gait, fps: f64, duration: f64, seed: u64) -> Result<Vec<Vec<Isometry3<f64>>>> {
    if !(fps.is_finite() && fps > 0.0 && duration.is_finite() && duration > 0.0) {
        return Err(Error::new(
            ErrorKind::Unsupported,
            format!("{fps} fps for {duration} s: expected a positive frame rate and duration"),
        ));
    }
    // Frames at 0, 1/fps, ..., duration: the clip lasts `duration` from first to last frame.
    let frames = (duration * fps).round().max(1.0) as usize + 1;
    // One stream per (seed, gait), so adding a motion to a list does not change the others.
    let mut v = Vary(ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ gait as u64));
    let phase0 = v.0.random_range(0.0..TAU);
    let leg = sk.rest[0].y;
    let angles: Vec<Angles> = match gait {
        Gait::Walk | Gait::TurnLeft | Gait::TurnRight => {
            let turn = match gait {
                Gait::TurnLeft => FRAC_PI_2 * v.f(),
                Gait::TurnRight => -FRAC_PI_2 * v.f(),
                _ => 0.0,
            };
            let c = Cycle {
                speed: 1.3 * v.f() * leg / 0.875,
                frequency: 0.9 * v.f(),
                hip: 0.35 * v.f(),
                knee: 0.9 * v.f(),
                knee_rest: 0.1,
                arm: 0.3 * v.f(),
                elbow: 0.25 * v.f(),
                flight: 0.0,
                lean: 0.04,
            };
            (0..frames).map(|f| c.at(f as f64 / fps, phase0, turn / duration)).collect()
        }
        Gait::Jog => {
            let c = Cycle {
                speed: 2.8 * v.f() * leg / 0.875,
                frequency: 1.4 * v.f(),
                hip: 0.55 * v.f(),
                knee: 1.3 * v.f(),
                knee_rest: 0.3,
                arm: 0.45 * v.f(),
                elbow: 1.3 * v.f(),
                flight: 0.04 * v.f(),
                lean: 0.12,
            };
            (0..frames).map(|f| c.at(f as f64 / fps, phase0, 0.0)).collect()
        }
        Gait::Jump => {
            let (distance, height) = (0.8 * v.f() * leg / 0.875, 0.25 * v.f() * leg / 0.875);
            (0..frames).map(|f| jump(f as f64 / (frames - 1) as f64, distance, height)).collect()
        }
        Gait::Idle => {
            let (sway, breathe) = (0.02 * v.f(), 0.02 * v.f());
            (0..frames)
                .map(|f| {
                    let t = f as f64 / fps;
                    let s = (TAU * 0.25 * t + phase0).sin();
                    Angles {
                        root: [sway * s, 0.0],
                        knee: [0.05 + 0.03 * s.max(0.0), 0.05 + 0.03 * (-s).max(0.0)],
                        hip: [0.03, 0.03],
                        chest_lean: breathe * (TAU * 0.3 * t + phase0).sin(),
                        twist: 0.05 * (TAU * 0.1 * t + phase0).sin(),
                        elbow: [0.15, 0.15],
                        ..Default::default()
                    }
                })
                .collect()
        }
    };
    Ok(angles.iter().map(|a| pose(sk, a)).collect())
}

/// A periodic gait: hips swing in antiphase, knees bend in the swing phase, arms swing against
/// the legs, the body leaves the ground twice per cycle when running; the root advances at `speed` along a heading that
/// turns at `turn_rate` (radians per second).
struct Cycle {
    speed: f64,
    frequency: f64,
    hip: f64,
    knee: f64,
    knee_rest: f64,
    arm: f64,
    elbow: f64,
    /// Height reached between steps (a jog's flight phase; 0 for walking).
    flight: f64,
    lean: f64,
}

impl Cycle {
    fn at(&self, t: f64, phase0: f64, turn_rate: f64) -> Angles {
        let p = TAU * self.frequency * t + phase0;
        let heading = turn_rate * t;
        // Position: the integral of the speed along the heading (closed form for a constant
        // turn rate: an arc of a circle).
        let root = if turn_rate.abs() < 1e-12 {
            [0.0, self.speed * t]
        } else {
            let r = self.speed / turn_rate;
            [r * (1.0 - heading.cos()), r * heading.sin()]
        };
        let side = |offset: f64| {
            let q = p + offset;
            // Knee flexes in the swing, peaking just before the hip's forward extreme.
            let knee = self.knee_rest + self.knee * (0.5 + 0.5 * (q + 0.6 * PI).sin()).powi(2);
            (self.hip * q.sin(), knee, -self.arm * q.sin())
        };
        let (l, r) = (side(0.0), side(PI));
        Angles {
            hip: [l.0, r.0],
            knee: [l.1, r.1],
            arm: [l.2, r.2],
            elbow: [self.elbow, self.elbow],
            lean: self.lean,
            chest_lean: 0.0,
            twist: 0.08 * p.sin(),
            root,
            lift: self.flight * (0.5 - 0.5 * (2.0 * p).cos()),
            heading,
        }
    }
}

/// A standing forward jump over normalised time s in [0, 1]: crouch, push off, a ballistic
/// flight of `distance` forward and `height` up, landing crouch, recovery.
fn jump(s: f64, distance: f64, height: f64) -> Angles {
    let smooth = |a: f64, b: f64, x: f64| {
        let u = ((x - a) / (b - a)).clamp(0.0, 1.0);
        u * u * (3.0 - 2.0 * u)
    };
    let (take_off, landing) = (0.35, 0.6);
    // Crouch before take-off and after landing.
    let crouch = smooth(0.05, 0.3, s) * (1.0 - smooth(0.3, take_off, s))
        + smooth(landing, 0.7, s) * (1.0 - smooth(0.75, 0.95, s));
    let flight = ((s - take_off) / (landing - take_off)).clamp(0.0, 1.0);
    let in_air = s > take_off && s < landing;
    let forward = distance * flight;
    let arc = if in_air { 4.0 * height * flight * (1.0 - flight) } else { 0.0 };
    let tuck = if in_air { (PI * flight).sin() } else { 0.0 };
    Angles {
        hip: [0.9 * crouch + 0.5 * tuck; 2],
        knee: [1.5 * crouch + 0.6 * tuck; 2],
        // Arms back in the crouch, forward in the flight.
        arm: [-0.6 * crouch + 0.9 * tuck; 2],
        elbow: [0.3; 2],
        lean: 0.5 * crouch,
        chest_lean: 0.1 * crouch,
        twist: 0.0,
        root: [0.0, forward],
        lift: arc,
        heading: 0.0,
    }
}

/// Forward kinematics: joint world transforms (translation to the joint, rotation relative to
/// the rest pose) from the angles.
fn pose(sk: &Skeleton, a: &Angles) -> Vec<Isometry3<f64>> {
    let n = sk.names.len();
    let x = Vector3::x_axis();
    let about = |axis: &Unit<Vector3<f64>>, angle: f64| UnitQuaternion::from_axis_angle(axis, angle);
    let heading = about(&Vector3::y_axis(), a.heading);
    let mut local = vec![UnitQuaternion::identity(); n];
    local[0] = heading * about(&x, a.lean);
    local[7] = about(&x, a.chest_lean) * about(&Vector3::y_axis(), a.twist);
    // Legs hang straight down at rest: flexion turns the thigh forward (about -x), the knee
    // bends the shin back (about +x).
    for (side, (hip, knee)) in [(1usize, 2usize), (4, 5)].into_iter().enumerate() {
        local[hip] = about(&x, -a.hip[side]);
        local[knee] = about(&x, a.knee[side]);
    }
    // Arms: from the A-pose down to the sides (about z, leaving 10 degrees of clearance), then
    // swung forward about the lateral axis; elbows bend the forearm forward, about the axis
    // perpendicular to the forearm and to the facing direction.
    let lower = FRAC_PI_2 - ARM_DROP - 0.17;
    for (side, (shoulder, elbow), sign) in [(0usize, (9usize, 10usize), 1.0), (1, (12, 13), -1.0)] {
        local[shoulder] = about(&x, -a.arm[side]) * about(&Vector3::z_axis(), -sign * lower);
        let forearm = sk.rest[elbow + 1] - sk.rest[elbow];
        let axis = Unit::new_normalize(forearm.cross(&Vector3::z()));
        local[elbow] = about(&axis, a.elbow[side]);
    }
    let mut world_q = vec![UnitQuaternion::identity(); n];
    let mut pos = vec![Point3::origin(); n];
    for j in 0..n {
        match sk.parents[j] {
            None => {
                world_q[j] = local[j];
                // Height is set below, from the feet.
                pos[j] = Point3::new(a.root[0], sk.rest[j].y, a.root[1]);
            }
            Some(p) => {
                world_q[j] = if sk.names[j].ends_with("foot") {
                    // Feet keep as flat as an ankle allows (turned by the heading only, the
                    // ankle bending at most MAX_ANKLE): a foot rigid with its shin would dig its
                    // toes into the floor, one always flat would fold the ankle in a jog's swing.
                    let flat = world_q[p].inverse() * heading;
                    let t = (MAX_ANKLE / flat.angle().max(1e-12)).min(1.0);
                    world_q[p] * UnitQuaternion::identity().slerp(&flat, t)
                } else {
                    world_q[p] * local[j]
                };
                pos[j] = pos[p] + world_q[p] * (sk.rest[j] - sk.rest[p]);
            }
        }
    }
    // Feet on the ground: the whole body moves vertically so that the lower ankle is at its
    // standing height (plus the lift in the air): bent knees lower the pelvis instead of
    // sinking the feet into the floor.
    let ankles = sk.names.iter().enumerate().filter(|(_, n)| n.ends_with("foot")).map(|(j, _)| j);
    let lowest = ankles.clone().map(|j| pos[j].y).fold(f64::INFINITY, f64::min);
    let standing = ankles.map(|j| sk.rest[j].y).fold(f64::INFINITY, f64::min);
    let dy = standing + a.lift - lowest;
    (0..n).map(|j| Isometry3::from_parts(Translation3::new(pos[j].x, pos[j].y + dy, pos[j].z), world_q[j])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mannequin::{BodyShape, skeleton};

    #[test]
    fn gaits_travel_turn_and_repeat_with_their_seed() {
        let sk = skeleton(&BodyShape::average());
        let root = |w: &[Vec<Isometry3<f64>>], f: usize| w[f][0].translation.vector;
        let walk = locomotion(&sk, Gait::Walk, 30.0, 3.0, 1).unwrap();
        assert_eq!(walk.len(), 91);
        let d = root(&walk, 90) - root(&walk, 0);
        // 1.3 m/s +-5% for 3 s, straight ahead (+z).
        assert!((d.z - 1.3 * 3.0).abs() < 0.07 * 1.3 * 3.0, "walked {d}");
        assert!(d.x.abs() < 1e-9);
        assert_eq!(walk, locomotion(&sk, Gait::Walk, 30.0, 3.0, 1).unwrap(), "same seed, same motion");
        assert_ne!(walk, locomotion(&sk, Gait::Walk, 30.0, 3.0, 2).unwrap());
        let jog = locomotion(&sk, Gait::Jog, 30.0, 3.0, 1).unwrap();
        assert!((root(&jog, 90) - root(&jog, 0)).z > 2.0 * d.z);
        // Turns: the root's heading changes by 90 degrees +-5%, left = positive (towards +x).
        for (g, sign) in [(Gait::TurnLeft, 1.0), (Gait::TurnRight, -1.0)] {
            let w = locomotion(&sk, g, 30.0, 3.0, 1).unwrap();
            let heading = |f: usize| {
                let facing = w[f][0].rotation * Vector3::z();
                facing.x.atan2(facing.z)
            };
            let turned = sign * (heading(90) - heading(0));
            assert!((turned - FRAC_PI_2).abs() < 0.06 * FRAC_PI_2, "{g:?} turned {turned}");
            assert!(sign * (root(&w, 90) - root(&w, 0)).x > 0.5, "{g:?} ends to its side");
        }
        // The jump leaves the ground and lands forward.
        let jump = locomotion(&sk, Gait::Jump, 60.0, 2.0, 3).unwrap();
        let top = jump.iter().map(|w| w[0].translation.vector.y).fold(f64::MIN, f64::max);
        assert!(top > sk.rest[0].y + 0.15, "jump top {top}");
        assert!((root(&jump, jump.len() - 1) - root(&jump, 0)).z > 0.7);
        // Idle stays on the spot.
        let idle = locomotion(&sk, Gait::Idle, 30.0, 3.0, 0).unwrap();
        assert!((root(&idle, 90) - root(&idle, 0)).norm() < 0.05);
        assert!(locomotion(&sk, Gait::Walk, 0.0, 3.0, 0).is_err());
        assert!(Gait::parse("moonwalk").is_err());
        assert_eq!(Gait::parse("turn_left").unwrap(), Gait::TurnLeft);
    }
}
