//! The length of the path a motion's centroid travels: the sum, over consecutive frames, of the
//! distance between their centroids ([`crate::pose_centroid`]). A variant placed on the source's
//! path (thesis 6.6, `VariantPath::Source`) travels about as far as the learnt motion.

use crate::pose_centroid::{centroid, distance3};

/// Length of the path of the centroids of `frames`; 0 for fewer than two frames.
pub fn centroid_path_length(frames: &[Vec<f32>]) -> f64 {
    frames.windows(2).map(|w| distance3(centroid(&w[0]), centroid(&w[1]))).sum()
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_point_moving_along_a_line() {
        let frames = vec![vec![0.0f32, 0.0, 0.0], vec![1.0, 0.0, 0.0], vec![1.0, 2.0, 0.0]];
        assert_eq!(super::centroid_path_length(&frames), 3.0);
        assert_eq!(super::centroid_path_length(&frames[..1]), 0.0);
    }
}
