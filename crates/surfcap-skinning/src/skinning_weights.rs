//! One vertex's skinning weights: non-negative, summing to one, at most K of them non-zero; the
//! weight update of Smooth Skinning Decomposition with Rigid Bones (Le and Deng 2012, "skinning
//! weights update"). With the bone transforms fixed, vertex i's weights w minimise
//!
//! `sum_t || v_i^t - sum_j w_j (R_j^t p_i + T_j^t) ||^2 = w^T G w - 2 c^T w + const`
//!
//! subject to `w >= 0`, `sum_j w_j = 1` and `|w|_0 <= K`. As in the paper the affinity constraint
//! is a heavily weighted extra equation (`lambda (1^T w - 1)^2`), the problem is solved as a
//! non-negative least-squares (Lawson and Hanson's active set), the K largest weights are kept
//! and the problem is solved again on those bones only; the result is normalised to sum to one.
//!
//! The normal equations are formed without the 3T x B design matrix: with the bone's affine
//! map `M_j^t = [R_j^t | T_j^t]` and `p~ = (p_i, 1)`,
//! `G_jk = p~^T (sum_t M_j^tT M_k^t) p~`, whose 4x4 inner sums are the same for every vertex
//! ([`BonePairSums`], computed once per update), and `c_j = p~ . sum_t M_j^tT v_i^t`.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use crate::rigid_bone_fit::BoneTransform;

/// `sum_t M_j^tT M_k^t` (4x4, row-major) for every pair of bones: what every vertex's normal
/// matrix is made of.
pub struct BonePairSums {
    n_bones: usize,
    /// `[j][k][4][4]`
    sums: Vec<[f64; 16]>,
}

/// The 3x4 affine matrix of a transform, row-major.
fn affine(b: &BoneTransform) -> [[f64; 4]; 3] {
    let r = &b.rotation;
    let t = &b.translation;
    [
        [r[(0, 0)], r[(0, 1)], r[(0, 2)], t[0]],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)], t[1]],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)], t[2]],
    ]
}

impl BonePairSums {
    /// From the transforms `[frame][bone]`.
    pub fn new(transforms: &[BoneTransform], n_bones: usize) -> Self {
        let n_frames = transforms.len() / n_bones.max(1);
        let mats: Vec<[[f64; 4]; 3]> = transforms.iter().map(affine).collect();
        let sums: Vec<[f64; 16]> = (0..n_bones * n_bones)
            .into_par_iter()
            .map(|jk| {
                let (j, k) = (jk / n_bones, jk % n_bones);
                let mut s = [0.0; 16];
                if k < j {
                    return s; // filled from the transpose below
                }
                for t in 0..n_frames {
                    let (a, b) = (&mats[t * n_bones + j], &mats[t * n_bones + k]);
                    for r in 0..4 {
                        for c in 0..4 {
                            s[r * 4 + c] += a[0][r] * b[0][c] + a[1][r] * b[1][c] + a[2][r] * b[2][c];
                        }
                    }
                }
                s
            })
            .collect();
        let mut out = BonePairSums { n_bones, sums };
        for j in 0..n_bones {
            for k in 0..j {
                let src = out.sums[k * n_bones + j];
                let dst = &mut out.sums[j * n_bones + k];
                for r in 0..4 {
                    for c in 0..4 {
                        dst[r * 4 + c] = src[c * 4 + r];
                    }
                }
            }
        }
        out
    }

    /// Vertex `p`'s normal matrix G (B x B).
    pub fn normal_matrix(&self, p: [f64; 3]) -> DMatrix<f64> {
        let b = self.n_bones;
        let pt = [p[0], p[1], p[2], 1.0];
        let mut g = DMatrix::zeros(b, b);
        for j in 0..b {
            for k in j..b {
                let h = &self.sums[j * b + k];
                let mut v = 0.0;
                for r in 0..4 {
                    let mut row = 0.0;
                    for c in 0..4 {
                        row += h[r * 4 + c] * pt[c];
                    }
                    v += pt[r] * row;
                }
                g[(j, k)] = v;
                g[(k, j)] = v;
            }
        }
        g
    }
}

/// Lawson and Hanson's active-set non-negative least squares on the normal equations:
/// minimises `w^T G w - 2 c^T w` over `w >= 0` (G symmetric positive semi-definite).
pub fn nonnegative_least_squares(g: &DMatrix<f64>, c: &DVector<f64>) -> DVector<f64> {
    let n = c.len();
    let mut w = DVector::zeros(n);
    let mut passive = vec![false; n];
    let scale = (0..n).map(|i| g[(i, i)].abs()).fold(0.0, f64::max).max(1e-300);
    let tol = 1e-12 * scale * (1.0 + c.amax());
    for _outer in 0..3 * n + 10 {
        let grad = c - g * &w;
        let next = (0..n)
            .filter(|&i| !passive[i] && grad[i] > tol)
            .max_by(|&a, &b| grad[a].total_cmp(&grad[b]).then(b.cmp(&a)));
        let Some(j) = next else { break };
        passive[j] = true;
        for _inner in 0..3 * n + 10 {
            let idx: Vec<usize> = (0..n).filter(|&i| passive[i]).collect();
            let Some(z) = solve_on(g, c, &idx) else {
                // Singular on this set: drop the newest bone and stop growing.
                passive[j] = false;
                return w;
            };
            if z.iter().all(|&x| x > 0.0) {
                for (a, &i) in idx.iter().enumerate() {
                    w[i] = z[a];
                }
                break;
            }
            // Step towards z until the first passive weight hits zero.
            let mut alpha = f64::INFINITY;
            for (a, &i) in idx.iter().enumerate() {
                if z[a] <= 0.0 {
                    let d = w[i] - z[a];
                    if d > 0.0 {
                        alpha = alpha.min(w[i] / d);
                    }
                }
            }
            if !alpha.is_finite() {
                alpha = 0.0;
            }
            for (a, &i) in idx.iter().enumerate() {
                w[i] += alpha * (z[a] - w[i]);
                if w[i] <= 1e-14 {
                    w[i] = 0.0;
                    passive[i] = false;
                }
            }
        }
    }
    w
}

/// The unconstrained minimiser restricted to bones `idx` (others zero), by Cholesky.
fn solve_on(g: &DMatrix<f64>, c: &DVector<f64>, idx: &[usize]) -> Option<DVector<f64>> {
    let m = idx.len();
    let sub = DMatrix::from_fn(m, m, |a, b| g[(idx[a], idx[b])]);
    let rhs = DVector::from_fn(m, |a, _| c[idx[a]]);
    let chol = nalgebra::Cholesky::new(sub)?;
    let z = chol.solve(&rhs);
    z.iter().all(|x| x.is_finite()).then_some(z)
}

/// Vertex weights with the affinity constraint and at most `max_influences` non-zero: the
/// bones and weights, largest first. `g` and `c` are the vertex's normal equations; `None` when
/// the problem is degenerate (the caller keeps the previous weights).
pub fn affine_sparse_weights(g: &DMatrix<f64>, c: &DVector<f64>, max_influences: usize) -> Option<Vec<(usize, f64)>> {
    let n = c.len();
    // The affinity equation, weighted well above the data (the paper's soft constraint).
    let lambda = 1e3 * (0..n).map(|i| g[(i, i)]).sum::<f64>() / n as f64 + 1e-12;
    let ga = g.add_scalar(lambda);
    let ca = c.add_scalar(lambda);
    let w = nonnegative_least_squares(&ga, &ca);
    let mut order: Vec<usize> = (0..n).filter(|&i| w[i] > 0.0).collect();
    order.sort_by(|&a, &b| w[b].total_cmp(&w[a]).then(a.cmp(&b)));
    order.truncate(max_influences);
    if order.is_empty() {
        return None;
    }
    order.sort_unstable();
    let sub_g = DMatrix::from_fn(order.len(), order.len(), |a, b| ga[(order[a], order[b])]);
    let sub_c = DVector::from_fn(order.len(), |a, _| ca[order[a]]);
    let sub_w = nonnegative_least_squares(&sub_g, &sub_c);
    let total: f64 = sub_w.iter().sum();
    if !total.is_finite() || total <= 0.0 {
        return None;
    }
    let mut out: Vec<(usize, f64)> =
        order.iter().zip(sub_w.iter()).filter(|&(_, &x)| x > 0.0).map(|(&j, &x)| (j, x / total)).collect();
    out.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nnls_matches_a_hand_solved_case() {
        // min ||A w - b||^2, A = I, b = (1, -2, 3): w = (1, 0, 3).
        let g = DMatrix::identity(3, 3);
        let c = DVector::from_vec(vec![1.0, -2.0, 3.0]);
        let w = nonnegative_least_squares(&g, &c);
        assert!((&w - DVector::from_vec(vec![1.0, 0.0, 3.0])).norm() < 1e-12, "{w}");
    }

    #[test]
    fn nnls_with_correlated_columns_respects_the_bound() {
        // A = [[1, 1], [0, 1]], b = (2, -1): unconstrained w = (3, -1); constrained: w2 = 0,
        // w1 = argmin (w1 - 2)^2 + 1 = 2.
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 0.0, 1.0]);
        let b = DVector::from_vec(vec![2.0, -1.0]);
        let w = nonnegative_least_squares(&(a.transpose() * &a), &(a.transpose() * b));
        assert!((w[0] - 2.0).abs() < 1e-12 && w[1] == 0.0, "{w}");
    }

    #[test]
    fn recovers_a_blend_of_two_bones_out_of_four() {
        // Bone columns (3 rows per "frame"): the vertex is 0.3 of bone 1 and 0.7 of bone 3.
        let cols: Vec<DVector<f64>> = (0..4)
            .map(|j| {
                DVector::from_fn(12, |r, _| ((r * 7 + j * 3) as f64 * 0.37).sin() + if r % 4 == j { 2.0 } else { 0.0 })
            })
            .collect();
        let a = DMatrix::from_columns(&cols);
        let b = &cols[1] * 0.3 + &cols[3] * 0.7;
        let w = affine_sparse_weights(&(a.transpose() * &a), &(a.transpose() * b), 2).unwrap();
        assert_eq!(w.len(), 2);
        assert_eq!((w[0].0, w[1].0), (3, 1));
        assert!((w[0].1 - 0.7).abs() < 1e-6 && (w[1].1 - 0.3).abs() < 1e-6, "{w:?}");
    }

    #[test]
    fn at_most_k_weights_summing_to_one() {
        let cols: Vec<DVector<f64>> =
            (0..6).map(|j| DVector::from_fn(9, |r, _| ((r + 1) as f64 * (j + 2) as f64).cos())).collect();
        let a = DMatrix::from_columns(&cols);
        let b = DVector::from_fn(9, |r, _| (r as f64).sin());
        for k in 1..=4 {
            let w = affine_sparse_weights(&(a.transpose() * &a), &(a.transpose() * &b), k).unwrap();
            assert!(w.len() <= k && !w.is_empty());
            assert!((w.iter().map(|x| x.1).sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(w.iter().all(|x| x.1 > 0.0));
        }
    }

    #[test]
    fn pair_sums_give_the_design_matrix_normal_equations() {
        use nalgebra::{Matrix3, Vector3};
        let bones = 3;
        let frames = 4;
        let tr: Vec<BoneTransform> = (0..frames * bones)
            .map(|i| {
                let a = i as f64 * 0.41;
                BoneTransform {
                    rotation: *nalgebra::Rotation3::from_euler_angles(a, 0.5 * a, -a).matrix() * Matrix3::identity(),
                    translation: Vector3::new(a.sin(), a.cos(), 0.3 * a),
                }
            })
            .collect();
        let p = Vector3::new(0.2, -1.0, 0.7);
        let sums = BonePairSums::new(&tr, bones);
        let g = sums.normal_matrix([p.x, p.y, p.z]);
        let a = DMatrix::from_fn(3 * frames, bones, |r, j| tr[(r / 3) * bones + j].apply(&p)[r % 3]);
        assert!((g - a.transpose() * &a).norm() < 1e-10);
    }
}
