//! Two measures of one transition, applied alike to the surface motion graph (Huang et al.
//! 2009) and the essential graph (thesis 3.3) so that their outputs can be compared.
//!
//! A transition is seen as the frame pairs it matches, in order, each with the rigid ground
//! motion its engine applies to the destination frame of the pair ([`MatchedTransition`]):
//! - the surface motion graph matches the eq. 4 window frame by frame (`x0 + k` with `y0 + k`)
//!   and moves Y on the ground so that the centroids of the switch's frames meet (4.2.3), one
//!   translation for the whole window;
//! - the essential graph matches the DTW warp of its transition (thesis eq. 2.50-2.57) and Blend
//!   (Algorithm 2) aligns each destination frame onto its source frame by motion-plane alignment
//!   (eq. 2.3-2.5: a rotation about the up axis and a ground translation).
//!
//! Both measures are the triangularly weighted mean (eq. 4's `w(m) = min(m + 1, n - m)`,
//! normalised, over the `n` pairs) of a per-pair quantity:
//! - **smoothness** (Huang et al.'s Table 1): the symmetric Hausdorff distance between the
//!   source frame and the placed destination frame, in subject units;
//! - **deformation cost**: the thesis's deformation distance (eq. 2.13, the pose distance the
//!   essential graph is built on, invariant to the placement) between the two frames.

use rayon::prelude::*;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_smg::temporal_shape_similarity::window_weights;

/// The frame pairs a transition matches and where its engine places each destination frame.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchedTransition {
    /// (source, destination) global frames, in playing order.
    pub pairs: Vec<(usize, usize)>,
    /// The ground motion applied to each pair's destination frame (one per pair).
    pub placements: Vec<PlaneMotion>,
}

/// The symmetric Hausdorff distance between two point sets `[n][3]` (brute force, points in
/// parallel).
pub fn hausdorff(a: &[f32], b: &[f32]) -> f64 {
    let one_way = |p: &[f32], q: &[f32]| -> f64 {
        p.par_chunks_exact(3)
            .map(|x| {
                q.chunks_exact(3)
                    .map(|y| {
                        let d = |k: usize| f64::from(x[k]) - f64::from(y[k]);
                        d(0) * d(0) + d(1) * d(1) + d(2) * d(2)
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .reduce(|| 0.0, f64::max)
            .sqrt()
    };
    one_way(a, b).max(one_way(b, a))
}

/// Smoothness: the weighted mean Hausdorff distance between each pair's source frame and its
/// placed destination frame; `positions[f]` holds global frame `f` as `[n][3]` (frames may
/// have different vertex counts). 0 for a transition without pairs.
pub fn smoothness(positions: &[Vec<f32>], t: &MatchedTransition) -> f64 {
    let w = window_weights(t.pairs.len());
    t.pairs
        .iter()
        .zip(&t.placements)
        .zip(&w)
        .map(|((&(a, b), place), w)| {
            let mut moved = positions[b].clone();
            place.apply(&mut moved);
            w * hausdorff(&positions[a], &moved)
        })
        .sum()
}

/// Deformation cost: the weighted mean of `d[a * n + b]` over the pairs, with `d` the
/// row-major `n x n` deformation distances (thesis eq. 2.13). 0 for a transition without pairs.
pub fn deformation_cost(d: &[f64], n: usize, t: &MatchedTransition) -> f64 {
    let w = window_weights(t.pairs.len());
    t.pairs.iter().zip(&w).map(|(&(a, b), w)| w * d[a * n + b]).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::UpAxis;

    #[test]
    fn hausdorff_of_point_sets_with_a_known_answer() {
        // {0, (1,0,0)} vs {(0,0,0.5)}: from the first set the farthest point is (1,0,0) at
        // sqrt(1.25); from the second, its one point is 0.5 from the origin.
        let a = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
        let b = [0.0, 0.0, 0.5];
        assert!((hausdorff(&a, &b) - 1.25f64.sqrt()).abs() < 1e-7);
        assert_eq!(hausdorff(&a, &a), 0.0);
    }

    #[test]
    fn weighted_means_over_the_pairs() {
        // Frames: one point each, at x = 0, 1, 2, 3 (y up; ground axes x and z).
        let positions: Vec<Vec<f32>> = (0..4).map(|k| vec![k as f32, 0.0, 0.0]).collect();
        let id = PlaneMotion::identity(UpAxis::PosY);
        // Three pairs, weights (1, 2, 1) / 4: distances 2, 2, 2 -> 2.
        let t = MatchedTransition { pairs: vec![(0, 2), (1, 3), (0, 2)], placements: vec![id; 3] };
        assert!((smoothness(&positions, &t) - 2.0).abs() < 1e-12);
        // Placing each destination on its source (x -= 2) gives 0.
        let back = PlaneMotion { t: [-2.0, 0.0], ..id };
        let placed = MatchedTransition { placements: vec![back; 3], ..t.clone() };
        assert!(smoothness(&positions, &placed).abs() < 1e-12);
        // A rotation by pi about y through the origin sends frame 2 to x = -2: 2 from frame 0.
        let turn = MatchedTransition {
            pairs: vec![(0, 2)],
            placements: vec![PlaneMotion { theta: std::f64::consts::PI, ..id }],
        };
        assert!((smoothness(&positions, &turn) - 2.0).abs() < 1e-6);
        // Deformation cost on a 4 x 4 matrix d[a][b] = 10 a + b: (1 x 2 + 2 x 13 + 1 x 2) / 4.
        let d: Vec<f64> = (0..16).map(|k| (10 * (k / 4) + k % 4) as f64).collect();
        assert!((deformation_cost(&d, 4, &t) - 7.5).abs() < 1e-12);
        let empty = MatchedTransition { pairs: vec![], placements: vec![] };
        assert_eq!((smoothness(&positions, &empty), deformation_cost(&d, 4, &empty)), (0.0, 0.0));
    }
}
