//! Smoothing of a variant's deviation from the motion it varies, over time.
//!
//! A variant's pose at frame i is the reconstruction GP's mean at the sampled latent point
//! (thesis eq. 6.12). The GP nearly interpolates its training frames, and off the learnt
//! trajectories its mean answers sharply to where the point is: on the mannequin driven by
//! CMU subject 16's walk, jog, turns and jump (`surfcap eval vary`'s CMU case), the feet of
//! 16_15's variants moved with a frame-to-frame second difference of 47 mm (mean of the two
//! feet's centroids, along the ground) against 8 mm in the capture. It is not the chain's
//! noise alone: one HMC iteration from the learnt trajectory already gave 48 mm, and smoothing
//! the latent trajectories over 8 frames on each side still left 35 mm. A planted foot that
//! moves 3-5 cm from one frame to the next slides at 1 m/s: the CMU variants slid 0.7-3.1 m/s
//! before the foot-skate clean-up (0.09-0.29 for the captures), and pinning such feet bent the
//! legs past the captures' edge distortion.
//!
//! The thesis samples whole trajectories so that a variant keeps the motion's dynamics (6.6);
//! what carries the dynamics here is the learnt motion's frame-to-frame change, and what makes
//! a variant is its slower difference from it. So the deviation `D_i = P_i - L_i` of the
//! variant's pose `P_i` from the learnt motion's `L_i` (both body frame, the reference's
//! frames, per vertex coordinate) is averaged over `2 r + 1` frames with triangular weights
//! (the ends renormalised, as [`crate::variation_sampling::smoothed`] does in latent space),
//! and the pose becomes `L_i + D'_i`. Frame 0 keeps its pose (every variant starts in the
//! source's first pose). The average is linear in vertex space, like the reconstruction
//! itself; the learnt stretch ([`crate::learnt_stretch`]) that follows gives the triangles
//! back their stretch.
//!
//! Deterministic and independent of the thread count: each output is a sum in a fixed order.

use rayon::prelude::*;

use crate::error::{Error, Result};

/// The frames a triangular moving average of radius `r` takes around frame `i` of `n`, with
/// their weights: `k` from `i - r` to `i + r` (clipped to the frames there are), weight
/// `r + 1 - |k - i|`. Shared with [`crate::variation_sampling::smoothed`] (latent space).
pub fn triangular_window(i: usize, n: usize, r: usize) -> impl Iterator<Item = (usize, f64)> {
    (i.saturating_sub(r)..=(i + r).min(n.saturating_sub(1))).map(move |k| (k, (r + 1 - k.abs_diff(i)) as f64))
}

/// `poses` (a variant, frame by frame) replaced by `learnt + smoothed(poses - learnt)`, the
/// deviation averaged over `2 radius + 1` frames with triangular weights, frame 0 kept.
/// `radius` 0 leaves the poses as they are.
pub fn smooth_deviation(poses: &mut [Vec<f32>], learnt: &[Vec<f32>], radius: usize) -> Result<()> {
    if poses.len() != learnt.len() {
        return Err(Error::Invalid(format!(
            "smoothing a variant's deviation: {} frames against {} of the learnt motion",
            poses.len(),
            learnt.len()
        )));
    }
    if let Some(i) = (0..poses.len()).find(|&i| poses[i].len() != learnt[i].len()) {
        return Err(Error::Invalid(format!(
            "smoothing a variant's deviation: frame {i} has {} coordinates, the learnt motion's {}",
            poses[i].len(),
            learnt[i].len()
        )));
    }
    let n = poses.len();
    if radius == 0 || n < 3 {
        return Ok(());
    }
    let deviation: Vec<Vec<f64>> =
        poses.iter().zip(learnt).map(|(p, l)| p.iter().zip(l).map(|(a, b)| *a as f64 - *b as f64).collect()).collect();
    poses.par_iter_mut().enumerate().skip(1).for_each(|(i, pose)| {
        let mut sum = vec![0.0f64; pose.len()];
        let mut total = 0.0;
        for (k, w) in triangular_window(i, n, radius) {
            total += w;
            for (s, x) in sum.iter_mut().zip(&deviation[k]) {
                *s += w * x;
            }
        }
        for ((p, s), l) in pose.iter_mut().zip(&sum).zip(&learnt[i]) {
            *p = (*l as f64 + s / total) as f32;
        }
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_jittering_deviation_is_averaged_and_a_slow_one_is_kept() {
        // One vertex: the learnt motion walks along x, the variant adds a constant offset of 1
        // plus an alternating jitter of 0.5 (frame 0 is the learnt pose).
        let learnt: Vec<Vec<f32>> = (0..9).map(|i| vec![i as f32, 0.0, 0.0]).collect();
        let mut poses: Vec<Vec<f32>> = (0..9)
            .map(|i| {
                if i == 0 { learnt[0].clone() } else { vec![i as f32, 1.0 + if i % 2 == 0 { 0.5 } else { -0.5 }, 0.0] }
            })
            .collect();
        smooth_deviation(&mut poses, &learnt, 1).unwrap();
        assert_eq!(poses[0], learnt[0], "frame 0 is kept");
        for (i, p) in poses.iter().enumerate() {
            assert!((p[0] - i as f32).abs() < 1e-6, "the learnt motion's own travel is kept");
        }
        // Frames 2..7 average three frames with weights 1, 2, 1, which cancels a jitter that
        // changes sign every frame, (-0.5 + 2 x 0.5 - 0.5) / 4 = 0; the offset stays.
        for (i, p) in poses.iter().enumerate().take(8).skip(2) {
            assert!((p[1] - 1.0).abs() < 1e-6, "frame {i}: {} against 1", p[1]);
        }
        // A constant deviation is left as it is (away from frame 0, which averages in 0).
        let mut shifted: Vec<Vec<f32>> =
            learnt.iter().enumerate().map(|(i, l)| vec![l[0], if i == 0 { 0.0 } else { 2.0 }, 0.0]).collect();
        smooth_deviation(&mut shifted, &learnt, 2).unwrap();
        for p in shifted.iter().skip(3) {
            assert!((p[1] - 2.0).abs() < 1e-6);
        }
    }

    #[test]
    fn radius_zero_changes_nothing_and_mismatched_sizes_are_errors() {
        let learnt = vec![vec![0.0f32; 3]; 4];
        let mut poses = vec![vec![1.0f32; 3]; 4];
        smooth_deviation(&mut poses, &learnt, 0).unwrap();
        assert_eq!(poses, vec![vec![1.0f32; 3]; 4]);
        let e = smooth_deviation(&mut poses, &learnt[..3], 2).unwrap_err().to_string();
        assert!(e.contains("4 frames against 3"), "{e}");
        let mut odd = vec![vec![1.0f32; 3], vec![1.0f32; 6], vec![1.0f32; 3], vec![1.0f32; 3]];
        let e = smooth_deviation(&mut odd, &learnt, 2).unwrap_err().to_string();
        assert!(e.contains("frame 1 has 6"), "{e}");
    }
}
