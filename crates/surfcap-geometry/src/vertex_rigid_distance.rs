//! Per-vertex distance between a pose and a reference pose of the same mesh after the rigid
//! alignment that fits the reference onto the pose best (rotation and translation, no scale:
//! Kabsch, [`crate::motion_plane_alignment::procrustes`]). It is the per-vertex form of the error
//! a motion transfer is judged by against its ground truth (thesis 5.7: RMS per-vertex distance
//! after aligning the truth onto the prediction) and of a motion variant's distance from the
//! motion it varies, measured in the body frame (thesis 6.8): where the shapes differ, not where
//! the body as a whole stands or faces. Lengths are in the poses' own unit.

use crate::motion_plane_alignment::procrustes;

/// For each vertex, `|pose(k) - (R reference(k) + t)|` with `R`, `t` the rigid motion that
/// best fits `reference` onto `pose` (both `[vertices][3]`, vertices in the same order).
pub fn vertex_rigid_distance(pose: &[f32], reference: &[f32]) -> Vec<f32> {
    let (r, t, _) = procrustes(pose, reference, None, false);
    pose.chunks_exact(3)
        .zip(reference.chunks_exact(3))
        .map(|(p, q)| {
            let q = r * nalgebra::Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64) + t;
            let d = nalgebra::Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) - q;
            d.norm() as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_moved_copy_is_at_zero_and_a_moved_vertex_at_its_offset() {
        let pose: Vec<f32> = vec![0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.];
        // The reference turned a quarter about y and moved: distance 0 everywhere.
        let moved: Vec<f32> = pose.chunks(3).flat_map(|p| [p[2] + 3.0, p[1] - 1.0, -p[0]]).collect();
        assert!(vertex_rigid_distance(&pose, &moved).iter().all(|d| *d < 1e-5));
        // One vertex of many displaced: that vertex is far, the others near.
        let mut grid = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                grid.extend_from_slice(&[i as f32, j as f32, ((i * j) % 3) as f32]);
            }
        }
        let mut bumped = grid.clone();
        bumped[3 * 55 + 2] += 1.0;
        let d = vertex_rigid_distance(&grid, &bumped);
        assert!(d[55] > 0.9 && d[55] < 1.01, "{}", d[55]);
        assert!(d.iter().enumerate().filter(|&(k, _)| k != 55).all(|(_, x)| *x < 0.05), "{d:?}");
    }
}
