//! Differential operators of a triangle mesh (thesis eq. 2.24-2.42): the per-triangle gradient
//! G (3M x N), the area-weighted mass D (3M x 3M diagonal), the Laplacian L = G^T D G and the
//! divergence G^T D.
//!
//! Conventions: the gradient of the coordinate function on triangle m is the 3x3 matrix
//! G_m = sum_k grad(phi_k) v_k^T (eq. 2.26): row d is the derivative along axis d, column c the
//! coordinate c. grad(phi_k) comes from eq. 2.33. L here is the positive semi-definite
//! stiffness matrix: L_ab = sum_m area_m grad(phi_a) . grad(phi_b), which equals minus the
//! cotangent Laplacian of eq. 2.40 off the diagonal (-1/2 (cot alpha + cot beta)) and the sum
//! of the cotangent weights on it. Zero-area triangles get zero gradients and zero area: they
//! add nothing to L (a mesh where a vertex touches only such triangles is handled by the
//! Poisson solver's regularisation).

use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{Matrix3, Vector3};
use surfcap_mesh::Topology;

use crate::deformation_gradient::vertex;

/// Hat-function gradients and areas of every triangle of one pose.
#[derive(Debug, Clone)]
pub struct GradientOperator {
    n_vertices: usize,
    triangles: Vec<[u32; 3]>,
    /// Per triangle, the gradients of the three hat functions (eq. 2.33).
    pub basis: Vec<[Vector3<f64>; 3]>,
    /// Per triangle area (eq. 2.39); 0 for degenerate triangles.
    pub areas: Vec<f64>,
}

impl GradientOperator {
    /// The operator of `topology` in the pose `positions` (`[n][3]`).
    pub fn new(topology: &Topology, positions: &[f32]) -> Self {
        let mut basis = Vec::with_capacity(topology.n_triangles());
        let mut areas = Vec::with_capacity(topology.n_triangles());
        for t in topology.triangles() {
            let (v1, v2, v3) = (vertex(positions, t[0]), vertex(positions, t[1]), vertex(positions, t[2]));
            let (e1, e2) = (v1 - v3, v2 - v3);
            let c = e1.cross(&e2);
            let len = c.norm();
            let scale = e1.norm_squared().max(e2.norm_squared());
            let inv = if len > 1e-12 * scale {
                Matrix3::from_rows(&[e1.transpose(), e2.transpose(), (c / len).transpose()]).try_inverse()
            } else {
                None
            };
            match inv {
                Some(inv) => {
                    // eq. 2.33: (grad phi_1, grad phi_2, grad phi_3) = E^-1 [[1,0,-1],[0,1,-1],[0,0,0]].
                    let (g1, g2) = (inv.column(0).into_owned(), inv.column(1).into_owned());
                    basis.push([g1, g2, -g1 - g2]);
                    areas.push(0.5 * len);
                }
                None => {
                    basis.push([Vector3::zeros(); 3]);
                    areas.push(0.0);
                }
            }
        }
        GradientOperator { n_vertices: topology.n_vertices(), triangles: topology.triangles().to_vec(), basis, areas }
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// G_m of every triangle for vertex values `values` (`[n][3]`, e.g. positions) (eq. 2.27).
    pub fn gradients(&self, values: &[f32]) -> Vec<Matrix3<f64>> {
        self.triangles
            .iter()
            .zip(&self.basis)
            .map(|(t, g)| (0..3).map(|k| g[k] * vertex(values, t[k]).transpose()).sum())
            .collect()
    }

    /// The 3M x N sparse matrix G of eq. 2.35-2.37.
    pub fn matrix(&self) -> SparseColMat<usize, f64> {
        let mut trip = Vec::with_capacity(9 * self.triangles.len());
        for (m, (t, g)) in self.triangles.iter().zip(&self.basis).enumerate() {
            for (k, &v) in t.iter().enumerate() {
                for (d, &gd) in g[k].iter().enumerate() {
                    trip.push(Triplet::new(3 * m + d, v as usize, gd));
                }
            }
        }
        SparseColMat::try_new_from_triplets(3 * self.triangles.len(), self.n_vertices, &trip)
            .expect("indices are in range by construction")
    }

    /// The diagonal of the mass matrix D (each triangle's area, three times).
    pub fn mass_diagonal(&self) -> Vec<f64> {
        self.areas.iter().flat_map(|&a| [a, a, a]).collect()
    }

    /// Triplets of L = G^T D G (eq. 2.48), summed per triangle without forming G.
    pub fn laplacian_triplets(&self) -> Vec<Triplet<usize, usize, f64>> {
        let mut trip = Vec::with_capacity(9 * self.triangles.len());
        for ((t, g), &area) in self.triangles.iter().zip(&self.basis).zip(&self.areas) {
            for a in 0..3 {
                for b in 0..3 {
                    trip.push(Triplet::new(t[a] as usize, t[b] as usize, area * g[a].dot(&g[b])));
                }
            }
        }
        trip
    }

    /// L = G^T D G as a sparse N x N matrix (duplicates summed).
    pub fn laplacian(&self) -> SparseColMat<usize, f64> {
        SparseColMat::try_new_from_triplets(self.n_vertices, self.n_vertices, &self.laplacian_triplets())
            .expect("indices are in range by construction")
    }

    /// Divergence G^T D of per-triangle 3x3 gradients (eq. 2.38, 2.48): one row per vertex.
    pub fn divergence(&self, grads: &[Matrix3<f64>]) -> Vec<Vector3<f64>> {
        let mut out = vec![Vector3::zeros(); self.n_vertices];
        for ((t, g), (&area, gm)) in self.triangles.iter().zip(&self.basis).zip(self.areas.iter().zip(grads)) {
            for k in 0..3 {
                out[t[k] as usize] += area * gm.transpose() * g[k];
            }
        }
        out
    }
}

/// The cotangent Laplacian of eq. 2.40 as triplets (positive semi-definite sign convention):
/// off-diagonal -1/2 (cot alpha + cot beta) per edge, diagonal the sum of the weights.
pub fn cotangent_laplacian_triplets(topology: &Topology, positions: &[f32]) -> Vec<Triplet<usize, usize, f64>> {
    let mut trip = Vec::new();
    for t in topology.triangles() {
        for k in 0..3 {
            let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (pa, pb, po) = (vertex(positions, a), vertex(positions, b), vertex(positions, o));
            let (u, v) = (pa - po, pb - po);
            let cr = u.cross(&v).norm();
            if cr <= 0.0 {
                continue;
            }
            let w = 0.5 * u.dot(&v) / cr;
            let (a, b) = (a as usize, b as usize);
            trip.extend([Triplet::new(a, b, -w), Triplet::new(b, a, -w), Triplet::new(a, a, w), Triplet::new(b, b, w)]);
        }
    }
    trip
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Topology, Vec<f32>) {
        let t = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        (t, vec![0.1, 0.0, 0.0, 1.0, 0.2, 0.0, 0.0, 1.3, 0.1, 0.2, 0.1, 1.5])
    }

    #[test]
    fn gradient_of_a_linear_function_is_exact() {
        let (t, p) = tetra();
        let op = GradientOperator::new(&t, &p);
        // f(x) = M x + c, evaluated at the vertices.
        let m = Matrix3::new(1.0, 2.0, -1.0, 0.5, 0.0, 3.0, -2.0, 1.0, 0.25);
        let f: Vec<f32> = p
            .chunks(3)
            .flat_map(|v| {
                let y = m * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64) + Vector3::new(1.0, -2.0, 0.5);
                [y.x as f32, y.y as f32, y.z as f32]
            })
            .collect();
        for (tri, g) in t.triangles().iter().zip(op.gradients(&f)) {
            // The gradient is M^T restricted to the triangle's plane: G n = 0, and G maps
            // edge directions e (as G^T e) to M e.
            let (v1, v2, v3) = (vertex(&p, tri[0]), vertex(&p, tri[1]), vertex(&p, tri[2]));
            for e in [v1 - v3, v2 - v3] {
                assert!((g.transpose() * e - m * e).norm() < 1e-5, "{}", (g.transpose() * e - m * e).norm());
            }
        }
    }

    #[test]
    fn laplacian_is_the_cotangent_laplacian() {
        let (t, p) = tetra();
        let op = GradientOperator::new(&t, &p);
        let l = op.laplacian().to_dense();
        let c = SparseColMat::<usize, f64>::try_new_from_triplets(4, 4, &cotangent_laplacian_triplets(&t, &p))
            .unwrap()
            .to_dense();
        assert!((&l - &c).norm_max() < 1e-12 * c.norm_max());
        // G^T D G from the explicit matrices agrees too.
        let g = op.matrix().to_dense();
        let d = faer::Mat::<f64>::from_fn(3 * t.n_triangles(), 3 * t.n_triangles(), |i, j| {
            if i == j { op.mass_diagonal()[i] } else { 0.0 }
        });
        let l2 = g.transpose() * &d * &g;
        assert!((&l - &l2).norm_max() < 1e-12 * c.norm_max());
    }
}
