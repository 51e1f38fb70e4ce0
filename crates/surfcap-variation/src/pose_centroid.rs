//! The centroid of a pose (the unweighted mean of its vertices) and the distance between two
//! centroids: where a variant or a learnt motion is, and how far apart two of them end.

/// The mean of a pose's vertices (`[x, y, z, x, y, z, ...]`); the origin for no vertex.
pub fn centroid(pose: &[f32]) -> [f64; 3] {
    let n = (pose.len() / 3).max(1) as f64;
    std::array::from_fn(|k| pose.chunks_exact(3).map(|v| v[k] as f64).sum::<f64>() / n)
}

/// Euclidean distance between two points.
pub fn distance3(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_centroid_is_the_mean_vertex() {
        assert_eq!(centroid(&[0.0, 0.0, 0.0, 2.0, 4.0, -2.0]), [1.0, 2.0, -1.0]);
        assert_eq!(centroid(&[]), [0.0; 3]);
        assert_eq!(distance3([0.0; 3], [3.0, 4.0, 0.0]), 5.0);
    }
}
