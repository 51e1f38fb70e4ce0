//! Evaluations of surfcap's algorithms against ground truth (thesis 2.3.2, Evaluation): the
//! skeleton ground-truth pose distance (eq. 2.15-2.16), Pearson correlation (eq. 2.18), the
//! Mantel permutation test and correlogram, and distance correlation (eq. 2.19-2.22).
//!
//! Pairwise distances are passed as the condensed upper triangle of an N x N matrix
//! (`i < j`, row by row), as in scipy's `squareform`.

pub mod correlation;
pub mod mantel_test;
pub mod skeleton_distance;

/// The condensed upper triangle (i < j, row-major) of a row-major N x N matrix.
pub fn condensed(n: usize, full: &[f64]) -> Vec<f64> {
    (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).map(|(i, j)| full[i * n + j]).collect()
}

/// Index of pair (i, j), i < j, in a condensed vector of N objects.
#[inline]
pub fn pair_index(n: usize, i: usize, j: usize) -> usize {
    debug_assert!(i < j && j < n);
    i * n - i * (i + 1) / 2 + (j - i - 1)
}
