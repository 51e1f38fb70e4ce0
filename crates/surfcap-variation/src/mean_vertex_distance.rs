//! How far a variant's poses are from the learnt motion's: the mean, over every frame and
//! vertex, of the distance between corresponding vertices (in the body frame, thesis 6.6, it
//! measures how much the body's poses vary, not where the variant goes).

/// Mean per-vertex distance between two motions of one frame count and vertex count (frames
/// beyond the shorter motion are ignored); 0 for none.
pub fn mean_vertex_distance(a: &[Vec<f32>], b: &[Vec<f32>]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (x, y) in a.iter().zip(b) {
        for (p, q) in x.chunks_exact(3).zip(y.chunks_exact(3)) {
            s += (0..3).map(|k| ((p[k] - q[k]) as f64).powi(2)).sum::<f64>().sqrt();
            n += 1;
        }
    }
    if n == 0 { 0.0 } else { s / n as f64 }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_motion_moved_by_a_vector_is_that_far_from_itself() {
        let a = vec![vec![0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0]; 2];
        let b: Vec<Vec<f32>> = a
            .iter()
            .map(|p| p.iter().enumerate().map(|(k, x)| x + (k % 3 == 0) as u8 as f32 * 3.0).collect())
            .collect();
        assert_eq!(super::mean_vertex_distance(&a, &b), 3.0);
        assert_eq!(super::mean_vertex_distance(&[], &[]), 0.0);
    }
}
