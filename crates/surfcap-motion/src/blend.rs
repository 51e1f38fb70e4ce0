//! Blend (thesis Algorithm 2, 3.4.1): the synthetic transition segment between a source segment
//! and a destination segment, following the DTW warp, with recurring motion-plane alignment of
//! the remaining segments, non-linear interpolation with lambda = (t - 1)/(L - 1), and
//! integration of the centre of mass.
//!
//! Readings (PAPER-NOTES and ours):
//! - Align(M_n, M_m) is the up-axis angle theta that rotates M_m onto M_n (eq. 2.3); it is split
//!   as -lambda theta for the source and (1 - lambda) theta for the destination, each rotating the
//!   remaining segment about its current frame's centre of mass.
//! - "Planar translations towards P": T_n and T_m move the remaining segments in the ground plane
//!   only; the vertical coordinate stays as captured. P advances by the lambda-weighted average of
//!   the two segments' own (moved) ground-plane centre-of-mass steps; at a segment's last frame
//!   its step is taken as zero.
//! - The centre of mass of a frame is its vertex mean.

use std::sync::Arc;
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, motion_plane_alignment, plane_axes};

use surfcap_geometry::poisson_reconstruction::PoissonPattern;
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation, linear_interpolation};
use surfcap_mesh::{Topology, UpAxis};

use crate::subject_placement::{Placement, captured_placements};

/// How each output frame mixes its source and destination frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lambda {
    /// lambda = (t - 1)/(L - 1): the transition of Algorithm 2.
    Ramp,
    /// A fixed lambda for every frame (Fig. 3.14 blends two sequences with 0.5).
    Constant(f64),
}

/// Pose interpolation used for each output frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mixing {
    /// Gradient-domain interpolation (thesis 2.4.3).
    Nonlinear,
    /// Vertex blending (eq. 2.23), for comparison.
    Linear,
}

/// Centre of mass of a frame (its vertex mean).
pub fn centre(p: &[f32]) -> [f64; 3] {
    let n = (p.len() / 3).max(1) as f64;
    let mut c = [0.0; 3];
    for v in p.chunks_exact(3) {
        for k in 0..3 {
            c[k] += v[k] as f64;
        }
    }
    c.map(|x| x / n)
}

/// One output frame of Blend as rigid placements: output frame t interpolates source frame
/// `n` moved by `src` with destination frame `m` moved by `dst`, at `lambda`; its centre of
/// mass is `centre` (in the plane that is P of Algorithm 2, vertically the lambda-mix).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendStep {
    pub n: usize,
    pub m: usize,
    pub lambda: f64,
    pub src: PlaneMotion,
    pub dst: PlaneMotion,
    pub centre: [f64; 3],
}

/// The rigid part of Algorithm 2: for every output frame, where the remaining source and
/// destination segments have been moved, without interpolating a single pose. Only the frames'
/// centres and the raw alignment angles are needed, so the search can predict a transition's
/// centre-of-mass track and final placement cheaply; [`blend`] builds its frames from these.
///
/// Align on the moved frames equals Align on the raw ones plus the difference of the two
/// segments' accumulated rotations (eq. 2.3 is equivariant under ground-plane motions); it is
/// wrapped back to (-pi, pi] as the atan2 of eq. 2.3 on the moved frames would give.
pub fn blend_placements(
    up: UpAxis,
    source: &[&[f32]],
    destination: &[&[f32]],
    path: &[(usize, usize)],
    lambda: Lambda,
) -> Vec<BlendStep> {
    let cs: Vec<[f64; 3]> = source.iter().map(|f| centre(f)).collect();
    let cd: Vec<[f64; 3]> = destination.iter().map(|f| centre(f)).collect();
    let angle = |n: usize, m: usize| motion_plane_alignment(source[n], destination[m], None, up).0.theta;
    blend_placements_from(up, &cs, &cd, path, lambda, angle)
}

/// [`blend_placements`] from the segments' centres of mass and `raw_angle(n, m)`, the eq. 2.3
/// angle aligning destination frame m onto source frame n as captured (e.g. read from the
/// subject's alignment Gram matrices, see surfcap-geometry's `alignment_gram`).
pub fn blend_placements_from(
    up: UpAxis,
    cs: &[[f64; 3]],
    cd: &[[f64; 3]],
    path: &[(usize, usize)],
    lambda: Lambda,
    raw_angle: impl Fn(usize, usize) -> f64,
) -> Vec<BlendStep> {
    let (iu, iv, _) = plane_axes(up);
    let (mut gs, mut gd) = (PlaneMotion::identity(up), PlaneMotion::identity(up));
    let l = path.len();
    let mut p = cs[0];
    let mut out = Vec::with_capacity(l);
    for (t, &(n, m)) in path.iter().enumerate() {
        let lam = match lambda {
            Lambda::Ramp if l > 1 => t as f64 / (l - 1) as f64,
            Lambda::Ramp => 1.0,
            Lambda::Constant(x) => x,
        };
        let theta = wrap_angle(raw_angle(n, m) + gs.theta - gd.theta);
        let (cn, cm) = (gs.apply_point(cs[n]), gd.apply_point(cd[m]));
        gs = PlaneMotion::about(-lam * theta, cn, [p[iu] - cn[iu], p[iv] - cn[iv]], up).after(&gs);
        gd = PlaneMotion::about((1.0 - lam) * theta, cm, [p[iu] - cm[iu], p[iv] - cm[iv]], up).after(&gd);
        let mut c = p;
        let (yn, ym) = (gs.apply_point(cs[n]), gd.apply_point(cd[m]));
        for k in 0..3 {
            if k != iu && k != iv {
                c[k] = (1.0 - lam) * yn[k] + lam * ym[k];
            }
        }
        out.push(BlendStep { n, m, lambda: lam, src: gs, dst: gd, centre: c });
        let step = |g: &PlaneMotion, cs: &[[f64; 3]], k: usize| -> [f64; 2] {
            if k + 1 < cs.len() {
                let (a, b) = (g.apply_point(cs[k]), g.apply_point(cs[k + 1]));
                [b[iu] - a[iu], b[iv] - a[iv]]
            } else {
                [0.0, 0.0]
            }
        };
        let (sn, sm) = (step(&gs, cs, n), step(&gd, cd, m));
        p[iu] += (1.0 - lam) * sn[0] + lam * sm[0];
        p[iv] += (1.0 - lam) * sn[1] + lam * sm[1];
    }
    out
}

/// An angle wrapped to (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a - t * (a / t).round();
    if w <= -std::f64::consts::PI { w + t } else { w }
}

/// Blends `source` (frames i .. i + l^i - 1) into `destination` (frames j - l^j + 1 .. j) along
/// the warp `path` (pairs of offsets into the two segments, from (0, 0) to their ends).
pub fn blend(
    topology: &Topology,
    up: UpAxis,
    source: &[&[f32]],
    destination: &[&[f32]],
    path: &[(usize, usize)],
    lambda: Lambda,
    mixing: Mixing,
) -> Result<Vec<Vec<f32>>, surfcap_geometry::Error> {
    let segments = (source, destination);
    blend_placed(topology, up, segments, segments, path, lambda, mixing, Placement::Aligned)
}

/// Blend whose rigid part (every alignment and translation of Algorithm 2) is computed from the
/// segments `placed` (source, destination: the captured frames) while the poses interpolated are
/// `played` (frames of the same vertex count shown in their stead, e.g. learned variants of
/// those frames, thesis 6.6), each moved as its captured frame is. The transition's rigid track
/// is then the captured one, which the walk model predicted and the constrained searches solved
/// for; only the poses differ. The rigid part is chosen by `placement`: Algorithm 2's
/// re-placement ([`Placement::Aligned`]) or the frames where they were captured
/// ([`Placement::Captured`], for a subject that does not travel, see
/// [`crate::subject_placement`]); the poses are interpolated alike. With `played` = `placed`
/// and [`Placement::Aligned`] this is [`blend`], to the bit.
#[allow(clippy::too_many_arguments)]
pub fn blend_placed(
    topology: &Topology,
    up: UpAxis,
    placed: (&[&[f32]], &[&[f32]]),
    played: (&[&[f32]], &[&[f32]]),
    path: &[(usize, usize)],
    lambda: Lambda,
    mixing: Mixing,
    placement: Placement,
) -> Result<Vec<Vec<f32>>, surfcap_geometry::Error> {
    let pattern = match mixing {
        Mixing::Nonlinear => Some(Arc::new(PoissonPattern::new(topology)?)),
        Mixing::Linear => None,
    };
    let (source, destination) = played;
    let steps = match placement {
        Placement::Aligned => blend_placements(up, placed.0, placed.1, path, lambda),
        Placement::Captured => {
            let (cs, cd): (Vec<[f64; 3]>, Vec<[f64; 3]>) =
                (placed.0.iter().map(|f| centre(f)).collect(), placed.1.iter().map(|f| centre(f)).collect());
            captured_placements(up, &cs, &cd, path, lambda)
        }
    };
    steps
        .iter()
        .map(|st| {
            let (mut a, mut b) = (source[st.n].to_vec(), destination[st.m].to_vec());
            st.src.apply(&mut a);
            st.dst.apply(&mut b);
            Ok(match &pattern {
                Some(pat) => match placement {
                    Placement::Aligned => NonlinearInterpolator::with_pattern(pat, topology, &a, &b, up)?,
                    Placement::Captured => NonlinearInterpolator::as_placed(pat, topology, &a, &b)?,
                }
                .at(st.lambda, StretchInterpolation::Linear),
                None => linear_interpolation(&a, &b, st.lambda),
            })
        })
        .collect()
}

/// Length of the ground-plane path of the frames' centres of mass.
pub fn centre_path_length(frames: &[Vec<f32>], up: UpAxis) -> f64 {
    let (iu, iv, _) = plane_axes(up);
    frames
        .windows(2)
        .map(|w| {
            let (a, b) = (centre(&w[0]), centre(&w[1]));
            ((b[iu] - a[iu]).powi(2) + (b[iv] - a[iv]).powi(2)).sqrt()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};

    /// The built-in tube's straight crawl bent onto a circle of radius 1 (left for `sign` = 1,
    /// right for -1): each frame's body is turned to the circle's tangent and placed at the arc
    /// length it has crawled.
    fn turning(sign: f64) -> (Topology, Vec<Vec<f32>>) {
        let w = worm_subject(&WormParams { rings: 12, segments: 8, frames: 40, ..Default::default() }).unwrap();
        let seq = &w.sequences()[0];
        let c0 = centre(seq.frame(0));
        let frames = (0..seq.n_frames())
            .map(|f| {
                let mut p = seq.frame(f).to_vec();
                let c = centre(&p);
                let s = c[0] - c0[0];
                let theta = sign * s;
                let (x, z) = (s.sin(), -sign * (1.0 - s.cos()));
                for v in p.chunks_exact_mut(3) {
                    v[0] -= c[0] as f32;
                    v[2] -= c[2] as f32;
                }
                PlaneMotion { theta, t: [c0[0] + x, c0[2] + z], up: UpAxis::PosY }.apply(&mut p);
                p
            })
            .collect();
        (w.topology().clone(), frames)
    }

    #[test]
    fn blending_a_left_and_a_right_turn_keeps_the_path_where_linear_blending_shortens_it() {
        let (topo, left) = turning(1.0);
        let (_, right) = turning(-1.0);
        // Start the right turn facing the other way, as two captures rarely share a heading.
        let right: Vec<Vec<f32>> = right
            .into_iter()
            .map(|mut p| {
                PlaneMotion { theta: 2.5, t: [0.3, -0.2], up: UpAxis::PosY }.apply(&mut p);
                p
            })
            .collect();
        let path: Vec<(usize, usize)> = (0..left.len()).map(|k| (k, k)).collect();
        let (l, r): (Vec<&[f32]>, Vec<&[f32]>) =
            (left.iter().map(|f| &f[..]).collect(), right.iter().map(|f| &f[..]).collect());
        let ours = blend(&topo, UpAxis::PosY, &l, &r, &path, Lambda::Constant(0.5), Mixing::Nonlinear).unwrap();
        let plain: Vec<Vec<f32>> = left.iter().zip(&right).map(|(a, b)| linear_interpolation(a, b, 0.5)).collect();
        let (len_l, len_r) = (centre_path_length(&left, UpAxis::PosY), centre_path_length(&right, UpAxis::PosY));
        let (len_ours, len_plain) = (centre_path_length(&ours, UpAxis::PosY), centre_path_length(&plain, UpAxis::PosY));
        let mean = 0.5 * (len_l + len_r);
        assert!((len_ours - mean).abs() < 0.1 * mean, "Blend path {len_ours} vs inputs' mean {mean}");
        assert!(len_plain < 0.6 * mean, "linear blending should collapse: {len_plain} vs {mean}");
        eprintln!("centre-of-mass path: inputs {len_l:.3} / {len_r:.3}, Blend {len_ours:.3}, linear {len_plain:.3}");
    }

    #[test]
    fn ramp_starts_at_the_source_frame() {
        let (topo, left) = turning(1.0);
        let (_, right) = turning(-1.0);
        let path: Vec<(usize, usize)> = (0..10).map(|k| (k, k + 5)).collect();
        let (l, r): (Vec<&[f32]>, Vec<&[f32]>) =
            (left[..10].iter().map(|f| &f[..]).collect(), right[5..15].iter().map(|f| &f[..]).collect());
        let out = blend(
            &topo,
            UpAxis::PosY,
            &l,
            &r,
            &path.iter().map(|&(a, b)| (a, b - 5)).collect::<Vec<_>>(),
            Lambda::Ramp,
            Mixing::Nonlinear,
        )
        .unwrap();
        assert_eq!(out.len(), 10);
        // First frame: the source's first frame, unmoved (P starts at its centre).
        let d0 = out[0].iter().zip(&left[0]).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
        assert!(d0 < 1e-4, "{d0}");
    }
}
