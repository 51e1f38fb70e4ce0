//! Principal component analysis (thesis 5.4.3: body-part poses reduced to PCA coefficients;
//! thesis 6.5.1: GPDM latent positions initialised with PCA coordinates).
//!
//! The data (N samples x D dimensions) is centred, then either decomposed by a thin SVD
//! (`Yc = U S V^T`, components = rows of V^T), or, when D is much larger than N (meshes: a few
//! hundred frames of thousands of coordinates), through the N x N Gram matrix `Yc Yc^T = U S^2
//! U^T`, whose eigenvectors give the components `V = Yc^T U S^-1` at O(N^2 D) cost instead of
//! O(N D min(N, D)) with a D-sized workspace. Both give the same subspace (tested).

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};
use crate::matrix::{centred, check_finite, column_means, serde_mat};

/// How the decomposition was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PcaMethod {
    /// Thin SVD of the centred data.
    Svd,
    /// Eigen-decomposition of the N x N Gram matrix (D >> N).
    Gram,
    /// Gram when D > 4 N, SVD otherwise.
    Auto,
}

/// A fitted PCA: mean, orthonormal components and their variances.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Pca {
    /// Mean of the training samples (D).
    pub mean: Vec<f64>,
    /// Components as rows (k x D), orthonormal, by decreasing variance.
    #[serde(with = "serde_mat")]
    pub components: Mat<f64>,
    /// Variance along each component (squared singular value / (N - 1)).
    pub variances: Vec<f64>,
    /// Total variance of the training data (sum over all directions).
    pub total_variance: f64,
    /// The method actually used.
    pub method: PcaMethod,
}

impl Pca {
    /// Fits `k` components to the rows of `y` (N x D). `k` is capped at min(N - 1, D) (more
    /// components than that have zero variance).
    pub fn fit(y: MatRef<'_, f64>, k: usize, method: PcaMethod) -> Result<Pca> {
        let (n, d) = (y.nrows(), y.ncols());
        if n < 2 || d == 0 {
            return Err(LearnError::Invalid(format!("PCA of {n} samples of {d} dimensions: expected at least 2 x 1")));
        }
        if k == 0 {
            return Err(LearnError::Invalid("PCA with 0 components".into()));
        }
        check_finite(y, "PCA data")?;
        let k = k.min(n - 1).min(d);
        let mean = column_means(y);
        let yc = centred(y, &mean);
        let total_variance =
            (0..d).map(|j| (0..n).map(|i| yc[(i, j)].powi(2)).sum::<f64>()).sum::<f64>() / (n - 1) as f64;
        let method = match method {
            PcaMethod::Auto if d > 4 * n => PcaMethod::Gram,
            PcaMethod::Auto => PcaMethod::Svd,
            m => m,
        };
        let (components, sv2) = match method {
            PcaMethod::Gram => {
                // Products on the calling thread: faer's parallel product splits the long inner
                // dimension across threads, so its sums (and the components) would change in
                // the last bit with the thread count.
                let g = crate::matrix::matmul_seq(yc.as_ref(), yc.transpose());
                let (u, s) = crate::matrix::symmetric_eigen_seq(g.as_ref(), "Gram eigen-decomposition")?;
                // Eigenvalues ascend: take the last k.
                let mut comps = Mat::zeros(k, d);
                let mut sv2 = Vec::with_capacity(k);
                for c in 0..k {
                    let col = n - 1 - c;
                    let lambda = s[col].max(0.0);
                    sv2.push(lambda);
                    if lambda <= 1e-300 {
                        continue;
                    }
                    let inv = 1.0 / lambda.sqrt();
                    let v = crate::matrix::matmul_seq(yc.transpose(), u.col(col).as_mat());
                    for j in 0..d {
                        comps[(c, j)] = v[(j, 0)] * inv;
                    }
                }
                (comps, sv2)
            }
            _ => {
                let (_, s, v) = crate::matrix::thin_svd_seq(yc.as_ref(), "thin SVD")?;
                let comps = Mat::from_fn(k, d, |c, j| v[(j, c)]);
                ((comps), (0..k).map(|c| s[c] * s[c]).collect())
            }
        };
        let mut components = components;
        // Deterministic signs: the largest-magnitude coordinate of each component is positive.
        for c in 0..k {
            let jmax =
                (0..d).max_by(|&a, &b| components[(c, a)].abs().total_cmp(&components[(c, b)].abs())).unwrap_or(0);
            if components[(c, jmax)] < 0.0 {
                for j in 0..d {
                    components[(c, j)] = -components[(c, j)];
                }
            }
        }
        let variances = sv2.iter().map(|s| s / (n - 1) as f64).collect();
        Ok(Pca { mean, components, variances, total_variance, method })
    }

    /// Number of components.
    pub fn n_components(&self) -> usize {
        self.components.nrows()
    }

    /// Fraction of the total variance along each component.
    pub fn explained_variance_ratio(&self) -> Vec<f64> {
        self.variances.iter().map(|v| if self.total_variance > 0.0 { v / self.total_variance } else { 0.0 }).collect()
    }

    fn check_dim(&self, d: usize) -> Result<()> {
        if d != self.mean.len() {
            return Err(LearnError::Dimension(format!("samples of {d} dimensions: PCA fitted on {}", self.mean.len())));
        }
        Ok(())
    }

    /// Coordinates of the rows of `y` (M x D) on the components (M x k).
    pub fn project(&self, y: MatRef<'_, f64>) -> Result<Mat<f64>> {
        self.check_dim(y.ncols())?;
        check_finite(y, "PCA input")?;
        Ok(centred(y, &self.mean) * self.components.transpose())
    }

    /// Samples from coordinates (M x k) back in the data space (M x D).
    pub fn reconstruct(&self, coords: MatRef<'_, f64>) -> Result<Mat<f64>> {
        if coords.ncols() != self.n_components() {
            return Err(LearnError::Dimension(format!(
                "{} coordinates per sample: PCA has {} components",
                coords.ncols(),
                self.n_components()
            )));
        }
        let mut y = coords * &self.components;
        for i in 0..y.nrows() {
            for j in 0..y.ncols() {
                y[(i, j)] += self.mean[j];
            }
        }
        Ok(y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Rank-3 data plus small noise, N x D.
    fn data(n: usize, d: usize) -> Mat<f64> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let basis = Mat::from_fn(3, d, |_, _| rng.random_range(-1.0..1.0));
        let coef = Mat::from_fn(n, 3, |_, c| rng.random_range(-1.0..1.0) * [5.0, 2.0, 1.0][c]);
        let mut y = coef * basis;
        for i in 0..n {
            for j in 0..d {
                y[(i, j)] += 3.0 + 1e-3 * rng.random_range(-1.0..1.0);
            }
        }
        y
    }

    #[test]
    fn svd_and_gram_routes_agree_and_reconstruct() {
        let y = data(30, 200);
        let a = Pca::fit(y.as_ref(), 3, PcaMethod::Svd).unwrap();
        let b = Pca::fit(y.as_ref(), 3, PcaMethod::Gram).unwrap();
        assert_eq!(Pca::fit(y.as_ref(), 3, PcaMethod::Auto).unwrap().method, PcaMethod::Gram);
        for c in 0..3 {
            assert!((a.variances[c] - b.variances[c]).abs() < 1e-8 * a.variances[0]);
            let dotp: f64 = (0..200).map(|j| a.components[(c, j)] * b.components[(c, j)]).sum();
            assert!((dotp - 1.0).abs() < 1e-8, "component {c}: {dotp}");
        }
        let ratio: f64 = a.explained_variance_ratio().iter().sum();
        assert!(ratio > 0.999 && ratio <= 1.0 + 1e-12, "{ratio}");
        let r = a.reconstruct(a.project(y.as_ref()).unwrap().as_ref()).unwrap();
        let err = (0..30).flat_map(|i| (0..200).map(move |j| (i, j))).map(|(i, j)| (r[(i, j)] - y[(i, j)]).abs());
        assert!(err.fold(0.0, f64::max) < 1e-2);
        let s = serde_json::to_string(&a).unwrap();
        let back: Pca = serde_json::from_str(&s).unwrap();
        assert_eq!(back.variances, a.variances);
        assert!(a.project(Mat::<f64>::zeros(1, 5).as_ref()).is_err());
        assert!(Pca::fit(Mat::<f64>::zeros(1, 5).as_ref(), 1, PcaMethod::Auto).is_err());
    }
}

#[cfg(test)]
mod thread_count_tests {
    use super::*;

    /// The same components, to the bit, on one thread and on several (faer's parallel kernels
    /// would otherwise split sums differently).
    #[test]
    fn pca_is_the_same_on_one_and_several_threads() {
        for (n, d) in [(124, 3200), (300, 900)] {
            let y = Mat::from_fn(n, d, |i, j| ((i * 31 + j * 17) % 97) as f64 * 0.01 + ((i * j) % 13) as f64 * 1e-3);
            let fit = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| Pca::fit(y.as_ref(), 20, PcaMethod::Auto).unwrap())
            };
            let (a, b) = (fit(1), fit(4));
            assert_eq!(a.variances, b.variances, "{n} x {d}");
            for c in 0..a.components.nrows() {
                for j in 0..d {
                    assert_eq!(a.components[(c, j)].to_bits(), b.components[(c, j)].to_bits(), "{n} x {d} ({c}, {j})");
                }
            }
        }
    }
}
