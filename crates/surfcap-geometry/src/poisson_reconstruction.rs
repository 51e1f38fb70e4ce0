//! Poisson reconstruction from target per-triangle gradients (thesis eq. 2.48):
//! G^T D G X = G^T D G~, with G and D of a fixed pose.
//!
//! The system is singular: X + a constant per connected component solves it too. We remove that
//! null space by pinning the first vertex of every component to 0, factor the reduced matrix
//! once (sparse Cholesky, `surfcap_linalg::sparse_cholesky`, sequential: the solve of a 2-core
//! rayon run was 40 times slower, see DEPENDENCIES.md), and after each solve translate every component so its vertex mean is
//! where the caller wants it (eq. 2.49 needs each one-sided solution pinned to the linearly
//! interpolated centroid, PAPER-NOTES). A tiny diagonal shift (1e-10 of the mean diagonal)
//! keeps the factorisation defined when some vertex touches only zero-area triangles.
//!
//! Precompute/solve split (libigl's `*_precomputation` / `*_solve`): `PoissonSolver::new` does
//! the symbolic and numeric factorisation; `solve` is two triangular solves and a divergence.

use std::sync::Arc;

use faer::Mat;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{Matrix3, Vector3};
use surfcap_linalg::{NumericLlt, SymbolicLlt};
use surfcap_mesh::{Components, Topology, connected_components};

use crate::error::{Error, Result};
use crate::gradient_operator::GradientOperator;

/// What a Poisson system owes to its topology alone: the connected components, the pinned
/// vertices, and the symbolic Cholesky factorisation (fill-reducing ordering and elimination
/// tree) of the reduced Laplacian's sparsity pattern. Shared by every pose of the same mesh.
pub struct PoissonPattern {
    components: Components,
    /// Reduced unknown index of each vertex; `None` for the pinned ones.
    reduced: Vec<Option<usize>>,
    n_reduced: usize,
    symbolic: SymbolicLlt,
}

/// A factorised Poisson system for one pose of a mesh.
pub struct PoissonSolver {
    op: GradientOperator,
    pattern: Arc<PoissonPattern>,
    numeric: NumericLlt,
}

/// Lower-triangle triplets of the reduced Laplacian (values from `op`, or 1 for the pattern)
/// plus the diagonal shift; the same entries in the same order for every pose of a topology.
fn reduced_triplets(
    topology: &Topology,
    op: Option<&GradientOperator>,
    reduced: &[Option<usize>],
    n_reduced: usize,
) -> Vec<Triplet<usize, usize, f64>> {
    let full = match op {
        Some(op) => op.laplacian_triplets(),
        None => topology
            .triangles()
            .iter()
            .flat_map(|t| (0..9).map(move |k| Triplet::new(t[k / 3] as usize, t[k % 3] as usize, 1.0)))
            .collect(),
    };
    let mut trip: Vec<Triplet<usize, usize, f64>> = full
        .into_iter()
        .filter_map(|t| Some(Triplet::new(reduced[t.row]?, reduced[t.col]?, t.val)))
        .filter(|t| t.row >= t.col)
        .collect();
    let mean_diag = {
        let d: f64 = trip.iter().filter(|t| t.row == t.col).map(|t| t.val).sum();
        if n_reduced > 0 { (d / n_reduced as f64).max(f64::MIN_POSITIVE) } else { 1.0 }
    };
    trip.extend((0..n_reduced).map(|k| Triplet::new(k, k, 1e-10 * mean_diag)));
    trip
}

impl PoissonPattern {
    /// Components, pinned vertices and the symbolic factorisation for `topology`.
    pub fn new(topology: &Topology) -> Result<Self> {
        let components = connected_components(topology);
        let mut pinned = vec![false; components.count];
        let mut reduced = vec![None; topology.n_vertices()];
        let mut next = 0usize;
        for (r, &c) in reduced.iter_mut().zip(&components.labels) {
            let c = c as usize;
            if pinned[c] {
                *r = Some(next);
                next += 1;
            } else {
                pinned[c] = true;
            }
        }
        let trip = reduced_triplets(topology, None, &reduced, next);
        let mat =
            SparseColMat::<usize, f64>::try_new_from_triplets(next, next, &trip).map_err(Error::PoissonAssemble)?;
        let symbolic = SymbolicLlt::new(mat.symbolic()).map_err(Error::PoissonSymbolic)?;
        Ok(PoissonPattern { components, reduced, n_reduced: next, symbolic })
    }
}

impl PoissonSolver {
    /// Builds and factorises the system for `topology` in the pose `positions`.
    pub fn new(topology: &Topology, positions: &[f32]) -> Result<Self> {
        Self::with_pattern(Arc::new(PoissonPattern::new(topology)?), topology, positions)
    }

    /// Factorises the system of another pose of a topology whose pattern is already known (the
    /// symbolic factorisation is reused: only the numeric one is done).
    pub fn with_pattern(pattern: Arc<PoissonPattern>, topology: &Topology, positions: &[f32]) -> Result<Self> {
        let op = GradientOperator::new(topology, positions);
        let trip = reduced_triplets(topology, Some(&op), &pattern.reduced, pattern.n_reduced);
        let n = pattern.n_reduced;
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).map_err(Error::PoissonAssemble)?;
        let numeric = pattern.symbolic.factorize(mat.as_ref()).map_err(Error::PoissonNumeric)?;
        Ok(PoissonSolver { op, pattern, numeric })
    }

    pub fn operator(&self) -> &GradientOperator {
        &self.op
    }

    pub fn components(&self) -> &Components {
        &self.pattern.components
    }

    /// Vertex mean of every component of `positions`.
    pub fn component_centroids(&self, positions: &[f32]) -> Vec<Vector3<f64>> {
        let mut sum = vec![Vector3::zeros(); self.pattern.components.count];
        let mut cnt = vec![0usize; self.pattern.components.count];
        for (v, &c) in self.pattern.components.labels.iter().enumerate() {
            sum[c as usize] += crate::deformation_gradient::vertex(positions, v as u32);
            cnt[c as usize] += 1;
        }
        sum.iter().zip(&cnt).map(|(s, &n)| s / n.max(1) as f64).collect()
    }

    /// Vertices whose gradients best match `targets` (one 3x3 G~_m per triangle, in the
    /// convention of [`GradientOperator::gradients`]), each component translated so that its
    /// vertex mean is `centroids[c]`.
    pub fn solve(&self, targets: &[Matrix3<f64>], centroids: &[Vector3<f64>]) -> Vec<f32> {
        let div = self.op.divergence(targets);
        let m = self.pattern.n_reduced;
        let mut rhs = Mat::<f64>::zeros(m, 3);
        for (v, r) in self.pattern.reduced.iter().enumerate() {
            if let Some(k) = r {
                for c in 0..3 {
                    rhs[(*k, c)] = div[v][c];
                }
            }
        }
        self.pattern.symbolic.solve_in_place(&self.numeric, rhs.as_mut());
        let n = self.pattern.reduced.len();
        let mut x = vec![Vector3::zeros(); n];
        for (v, r) in self.pattern.reduced.iter().enumerate() {
            if let Some(k) = r {
                x[v] = Vector3::new(rhs[(*k, 0)], rhs[(*k, 1)], rhs[(*k, 2)]);
            }
        }
        // Translate every component onto its requested centroid.
        let mut sum = vec![Vector3::zeros(); self.pattern.components.count];
        let mut cnt = vec![0usize; self.pattern.components.count];
        for (v, &c) in self.pattern.components.labels.iter().enumerate() {
            sum[c as usize] += x[v];
            cnt[c as usize] += 1;
        }
        let shift: Vec<Vector3<f64>> =
            (0..self.pattern.components.count).map(|c| centroids[c] - sum[c] / cnt[c].max(1) as f64).collect();
        x.iter()
            .zip(&self.pattern.components.labels)
            .flat_map(|(p, &c)| {
                let q = p + shift[c as usize];
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_a_mesh_from_its_own_gradients_with_several_components() {
        // Two separate tetrahedra.
        let t = Topology::new(
            8,
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2], [4, 6, 5], [4, 5, 7], [5, 6, 7], [4, 7, 6]],
            None,
        )
        .unwrap();
        let p: Vec<f32> = vec![
            0.1, 0.0, 0.0, 1.0, 0.2, 0.0, 0.0, 1.3, 0.1, 0.2, 0.1, 1.5, 5.0, 0.0, 0.0, 6.0, 0.1, 0.3, 5.2, 1.0, 0.0,
            5.1, 0.2, 1.0,
        ];
        let s = PoissonSolver::new(&t, &p).unwrap();
        assert_eq!(s.components().count, 2);
        let g = s.operator().gradients(&p);
        let back = s.solve(&g, &s.component_centroids(&p));
        for (a, b) in back.iter().zip(&p) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }
}
