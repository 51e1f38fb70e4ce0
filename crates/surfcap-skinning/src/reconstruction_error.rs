//! How far a skinned rig is from the frames it was made from: per frame, the root mean square
//! and the largest of the per-vertex distances `|| v_i^t - sum_j w_ij (R_j^t p_i + T_j^t) ||`,
//! in the subject's units.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::ssdr::SkinnedRig;

/// One frame's reconstruction error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameError {
    /// sqrt(mean over vertices of the squared distance)
    pub rms: f64,
    /// largest distance of one vertex
    pub max: f64,
}

/// The rig's error at each of `frames` (the frames it was made from, in order).
pub fn reconstruction_errors(rig: &SkinnedRig, frames: &[&[f32]]) -> Vec<FrameError> {
    frames
        .par_iter()
        .enumerate()
        .map(|(t, f)| {
            let p = rig.pose(t);
            let (mut sum, mut max) = (0.0f64, 0.0f64);
            for (a, b) in p.chunks_exact(3).zip(f.chunks_exact(3)) {
                let d2: f64 = (0..3).map(|r| (f64::from(a[r]) - f64::from(b[r])).powi(2)).sum();
                sum += d2;
                max = max.max(d2.sqrt());
            }
            FrameError { rms: (sum / rig.n_vertices.max(1) as f64).sqrt(), max }
        })
        .collect()
}

/// RMS over all frames (the square root of the mean of the frames' squared RMS).
pub fn overall_rms(errors: &[FrameError]) -> f64 {
    (errors.iter().map(|e| e.rms * e.rms).sum::<f64>() / errors.len().max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rigid_bone_fit::BoneTransform;
    use nalgebra::Vector3;

    #[test]
    fn errors_of_a_known_offset() {
        // One bone, identity: a frame moved by (0, 0, 0.5) at one vertex of two.
        let rig = SkinnedRig {
            n_vertices: 2,
            n_bones: 1,
            rest: vec![Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0)],
            weights: vec![vec![(0, 1.0)], vec![(0, 1.0)]],
            transforms: vec![BoneTransform::identity()],
            rms_history: vec![],
        };
        let f = [0.0f32, 0.0, 0.5, 1.0, 0.0, 0.0];
        let e = reconstruction_errors(&rig, &[&f]);
        assert!((e[0].max - 0.5).abs() < 1e-12);
        assert!((e[0].rms - (0.125f64).sqrt()).abs() < 1e-12);
        assert!((overall_rms(&e) - e[0].rms).abs() < 1e-15);
    }
}
