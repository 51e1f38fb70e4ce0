//! The trajectory an input asks for over the next second, which the controller's moves are
//! matched against: the character's ground velocity and facing approach the asked ones
//! exponentially with a half-life (the damper of motion matching's trajectory prediction, as
//! in Clavet 2016 and Holden's open implementation: a stick pushed sideways does not teleport
//! the character's future, it bends it).
//!
//! With `tau = halflife / ln 2`, current velocity `v0` and asked velocity `vg`:
//! `v(t) = vg + (v0 - vg) e^(-t / tau)`, so the position is
//! `p(t) = p0 + vg t + (v0 - vg) tau (1 - e^(-t / tau))`. The facing approaches the asked one
//! (the shorter way round) likewise; when none is asked the character faces where it goes
//! (the direction of `v(t)`), and has no asked facing while it stands.

use surfcap_motion::blend::wrap_angle;

/// Samples of the asked trajectory, one per output frame from now (sample 0 is now).
#[derive(Debug, Clone, PartialEq)]
pub struct DesiredTrajectory {
    /// Ground-plane positions (subject units, world coordinates).
    pub positions: Vec<[f64; 2]>,
    /// Facing, radians (`atan2(v, u)`); `NaN` where none is asked.
    pub facing: Vec<f64>,
}

/// Where the character is and goes now, and what is asked of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectoryGoal {
    pub position: [f64; 2],
    pub velocity: [f64; 2],
    /// Current facing (`NaN`: none, e.g. standing).
    pub facing: f64,
    pub goal_velocity: [f64; 2],
    pub goal_facing: Option<f64>,
    /// Seconds for half of a change of velocity or facing.
    pub halflife: f64,
}

/// Speeds under this (subject units per second) have no direction to face.
const STILL: f64 = 1e-3;

/// `frames + 1` samples of the asked trajectory at `fps`.
pub fn desired_trajectory(goal: &TrajectoryGoal, fps: f64, frames: usize) -> DesiredTrajectory {
    let tau = (goal.halflife / std::f64::consts::LN_2).max(1e-6);
    let (p0, v0, vg) = (goal.position, goal.velocity, goal.goal_velocity);
    let mut positions = Vec::with_capacity(frames + 1);
    let mut facing = Vec::with_capacity(frames + 1);
    for k in 0..=frames {
        let t = k as f64 / fps;
        let e = (-t / tau).exp();
        positions.push(std::array::from_fn(|a| p0[a] + vg[a] * t + (v0[a] - vg[a]) * tau * (1.0 - e)));
        let f = match goal.goal_facing {
            Some(hg) if goal.facing.is_finite() => hg + wrap_angle(goal.facing - hg) * e,
            Some(hg) => hg,
            None => {
                let v: [f64; 2] = std::array::from_fn(|a| vg[a] + (v0[a] - vg[a]) * e);
                if v[0].hypot(v[1]) > STILL { v[1].atan2(v[0]) } else { f64::NAN }
            }
        };
        facing.push(f);
    }
    DesiredTrajectory { positions, facing }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Walking along +u at 1 unit/s and asked to go along +v at 2 units/s with a 0.25 s
    /// half-life: half the change of velocity after 0.25 s, the position the integral of the
    /// velocity (checked by summing it), the facing turning from 0 to 90 degrees.
    #[test]
    fn velocity_and_facing_approach_the_goal_with_the_half_life() {
        let goal = TrajectoryGoal {
            position: [1.0, 2.0],
            velocity: [1.0, 0.0],
            facing: 0.0,
            goal_velocity: [0.0, 2.0],
            goal_facing: None,
            halflife: 0.25,
        };
        let fps = 1000.0;
        let d = desired_trajectory(&goal, fps, 1000);
        assert_eq!(d.positions.len(), 1001);
        assert_eq!(d.positions[0], [1.0, 2.0]);
        let vel = |k: usize| [0, 1].map(|a| (d.positions[k + 1][a] - d.positions[k - 1][a]) * fps / 2.0);
        let v = vel(250);
        assert!((v[0] - 0.5).abs() < 1e-3 && (v[1] - 1.0).abs() < 1e-3, "{v:?}");
        let mut sum = [1.0, 2.0];
        for k in 0..1000 {
            let t = (k as f64 + 0.5) / fps;
            let e = (-t * std::f64::consts::LN_2 / 0.25).exp();
            sum[0] += e / fps;
            sum[1] += 2.0 * (1.0 - e) / fps;
        }
        assert!((sum[0] - d.positions[1000][0]).abs() < 1e-5 && (sum[1] - d.positions[1000][1]).abs() < 1e-5);
        assert!(d.facing[0].abs() < 1e-9);
        assert!((d.facing[1000] - std::f64::consts::FRAC_PI_2).abs() < 0.1);
        // Asked to stop: no facing once still; an asked facing is approached the short way.
        let stop = TrajectoryGoal { goal_velocity: [0.0, 0.0], velocity: [0.0, 0.0], ..goal };
        assert!(desired_trajectory(&stop, 30.0, 30).facing.iter().all(|f| f.is_nan()));
        let turn = TrajectoryGoal { facing: 3.0, goal_facing: Some(-3.0), ..stop };
        let f = desired_trajectory(&turn, 30.0, 30).facing;
        assert!(f[15].cos() < -0.98, "turned through pi, not through 0: {}", f[15]);
    }
}
