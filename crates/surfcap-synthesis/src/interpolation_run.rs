//! Poses between two frames of a subject (thesis 2.4): `surfcap interpolate` and
//! `surfcap.interpolate` make the same animation with this function.
//!
//! `steps` poses, both ends included: the first is frame `from` as captured, the last frame `to`
//! moved onto it by the motion-plane alignment (eq. 2.3), and the poses in between either the
//! non-linear interpolation of the triangles' rotations and stretches solved back into a mesh
//! by the Poisson system (eq. 2.45-2.49, stretch linear or log) or the linear blend of the
//! aligned positions (eq. 2.23), at lambda = k / (steps - 1).

use std::str::FromStr;

use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_mesh::{FrameLabel, Sequence, Subject};
use surfcap_motion::transition_frames::FrameMix;

use crate::error::{Error, Result};

/// How the poses in between are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InterpolationMethod {
    /// Rotations and stretches interpolated, then solved into a mesh (eq. 2.45-2.49).
    Nonlinear,
    /// The aligned positions blended linearly (eq. 2.23).
    Linear,
}

impl InterpolationMethod {
    pub fn name(self) -> &'static str {
        match self {
            InterpolationMethod::Nonlinear => "nonlinear",
            InterpolationMethod::Linear => "linear",
        }
    }
}

impl FromStr for InterpolationMethod {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "nonlinear" => Ok(InterpolationMethod::Nonlinear),
            "linear" => Ok(InterpolationMethod::Linear),
            _ => Err(format!("{s:?}: expected nonlinear or linear")),
        }
    }
}

/// An interpolation between two frames: the animation, each pose's mix of the two frames (for
/// textures interpolated with the same weights) and the set-up time of the interpolator.
#[derive(Debug, Clone)]
pub struct Interpolation {
    /// One sequence of `steps` poses named `<from>_to_<to>`, tagged `interpolation`, in a
    /// subject named `<subject>-interpolation`.
    pub animation: Subject,
    pub mix: Vec<FrameMix>,
    pub setup_seconds: f64,
}

/// The `steps` poses from global frame `from` to global frame `to` of `subject`; `from_name` and
/// `to_name` are the frames as the caller wrote them (the sequence is named after them).
pub fn interpolate(
    subject: &Subject,
    (from, from_name): (usize, &str),
    (to, to_name): (usize, &str),
    steps: usize,
    method: InterpolationMethod,
    stretch: StretchInterpolation,
) -> Result<Interpolation> {
    if steps < 2 {
        return Err(Error::Request(format!("steps {steps}: expected a whole number >= 2 (both ends are written)")));
    }
    let frame = |g: usize, name: &str| {
        subject.frame(g).ok_or_else(|| {
            Error::Request(format!(
                "frame {name}: the subject has frames 0 to {}",
                subject.n_frames().saturating_sub(1)
            ))
        })
    };
    let (pi, pj) = (frame(from, from_name)?, frame(to, to_name)?);
    let t0 = std::time::Instant::now();
    let interp = NonlinearInterpolator::new(subject.topology(), pi, pj, subject.up_axis)?;
    let setup_seconds = t0.elapsed().as_secs_f64();
    let nv = subject.topology().n_vertices();
    let mut positions = Vec::with_capacity(steps * 3 * nv);
    let mut mix = Vec::with_capacity(steps);
    for k in 0..steps {
        let lambda = k as f64 / (steps - 1) as f64;
        mix.push(FrameMix { from: from as u32, to: to as u32, weight: lambda as f32 });
        let p = match (k, method) {
            (0, _) => pi.to_vec(),
            (k, _) if k == steps - 1 => interp.aligned_target().to_vec(),
            (_, InterpolationMethod::Nonlinear) => interp.at(lambda, stretch),
            (_, InterpolationMethod::Linear) => interp.linear(lambda),
        };
        positions.extend_from_slice(&p);
    }
    let name = format!("{from_name}_to_{to_name}").replace(':', "_");
    let seq = Sequence::new(name, nv, positions)?
        .with_labels(FrameLabel::original_ends(steps))?
        .with_tags(vec!["interpolation".into()]);
    let animation = subject.derived(format!("{}-interpolation", subject.name), seq)?;
    Ok(Interpolation { animation, mix, setup_seconds })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};

    fn worm() -> Subject {
        worm_subject(&WormParams { rings: 6, segments: 5, frames: 8, ..Default::default() }).unwrap()
    }

    #[test]
    fn the_ends_are_the_captured_frame_and_the_aligned_target() {
        let s = worm();
        let out = interpolate(&s, (1, "1"), (6, "6"), 4, InterpolationMethod::Nonlinear, StretchInterpolation::Linear)
            .unwrap();
        let a = &out.animation;
        assert_eq!(a.n_frames(), 4);
        assert_eq!(a.frame(0).unwrap(), s.frame(1).unwrap());
        assert_eq!(a.sequences()[0].name, "1_to_6");
        assert_eq!(out.mix.iter().map(|m| m.weight).collect::<Vec<_>>(), vec![0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]);
    }

    #[test]
    fn fewer_than_two_steps_and_unknown_methods_are_refused_by_name() {
        let s = worm();
        let e = interpolate(&s, (0, "0"), (1, "1"), 1, InterpolationMethod::Linear, StretchInterpolation::Linear)
            .unwrap_err();
        assert!(e.to_string().starts_with("steps 1: expected a whole number >= 2"), "{e}");
        assert_eq!("cubic".parse::<InterpolationMethod>().unwrap_err(), "\"cubic\": expected nonlinear or linear");
    }
}
