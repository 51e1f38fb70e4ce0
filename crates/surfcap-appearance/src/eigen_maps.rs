//! PCA of F vectors of N values through the F x F Gram matrix (thesis 4.4.2, eq. 4.4-4.11,
//! after Turk and Pentland 1991): the eigen textures and the eigen warps are both this basis,
//! of the aligned textures and of the backward warps respectively.
//!
//! With the centred data `M = [x_1 - x̄ ... x_F - x̄]` (N x F, eq. 4.4/4.8), `Mᵀ M = D Σ Dᵀ`
//! (eq. 4.5/4.9) is decomposed instead of the N x N covariance; `T_i = M V_i` are then the
//! eigenvectors of `M Mᵀ` (eq. 4.7/4.11), normalised to unit length. The data stays f32 (100
//! frames of 1024x1024 fit in memory); the mean and the Gram matrix are accumulated in f64 in a
//! fixed order (frames in order for the mean, fixed texel blocks added in order for the Gram
//! matrix), and the F x F eigen-decomposition runs on one thread, so the basis is the same to
//! the bit whatever the thread count. A training vector's coefficients come from the Gram
//! matrix (`c_k,i = (G V_i)_k / √α_i`, the same as projecting it) instead of N·F·k products.

use faer::Mat;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::medoid_shift_alignment::{BLOCK, gram_matrix};

/// An orthonormal basis of the main modes of variation of a set of vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct EigenBasis {
    /// Length of every vector.
    pub dim: usize,
    /// The mean x̄ (eq. 4.4/4.8).
    pub mean: Vec<f32>,
    /// Components, one row of `dim` values each, by decreasing eigenvalue, unit length.
    pub components: Vec<f32>,
    /// Eigenvalues α_i of `Mᵀ M` of every kept component (descending).
    pub eigenvalues: Vec<f64>,
    /// Sum of all eigenvalues (the total squared deviation from the mean), for explained
    /// variance.
    pub total_variance: f64,
    /// Coefficients of each training vector, F rows of `n_components()` values.
    pub coefficients: Vec<f64>,
}

/// Eigen-decomposition of a symmetric F x F matrix (row-major) on the calling thread:
/// eigenvalues ascending, eigenvectors as columns.
fn symmetric_eigen_seq(g: &[f64], f: usize, what: &str) -> Result<(Mat<f64>, Vec<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{ComputeEigenvectors, self_adjoint_evd, self_adjoint_evd_scratch};
    let a = Mat::<f64>::from_fn(f, f, |i, j| g[i * f + j]);
    let mut u = Mat::zeros(f, f);
    let mut s = faer::diag::Diag::zeros(f);
    let par = faer::Par::Seq;
    let mut buf = MemBuffer::new(self_adjoint_evd_scratch::<f64>(f, ComputeEigenvectors::Yes, par, Default::default()));
    self_adjoint_evd(a.as_ref(), s.as_mut(), Some(u.as_mut()), par, MemStack::new(&mut buf), Default::default())
        .map_err(|e| Error::Solver {
            what: format!("the {f} x {f} Gram matrix of the {what}"),
            message: format!("{e:?}"),
        })?;
    Ok((u, (0..f).map(|i| s[i]).collect()))
}

impl EigenBasis {
    /// The basis of `vectors` (all of the same length), keeping at most `max_components`
    /// components with a non-zero eigenvalue (at most F - 1 exist). `what` names the data in
    /// errors ("aligned textures", "backward warps").
    pub fn new(vectors: &[&[f32]], max_components: usize, what: &str) -> Result<EigenBasis> {
        let f = vectors.len();
        let Some(first) = vectors.first() else {
            return Err(Error::Invalid(format!("no {what} to analyse: expected at least one frame")));
        };
        let n = first.len();
        if let Some(k) = vectors.iter().position(|v| v.len() != n) {
            return Err(Error::Mismatch(format!(
                "{what} of frame {k} has {} values: expected {n} like frame 0",
                vectors[k].len()
            )));
        }
        let mut mean64 = vec![0.0f64; n];
        for v in vectors {
            for (m, &x) in mean64.iter_mut().zip(v.iter()) {
                *m += x as f64;
            }
        }
        let mean: Vec<f32> = mean64.iter().map(|m| (m / f as f64) as f32).collect();
        drop(mean64);
        let g = gram_matrix(vectors, Some(&mean));
        let total_variance: f64 = (0..f).map(|k| g[k * f + k]).sum();
        let (v, alpha) = symmetric_eigen_seq(&g, f, what)?;
        let alpha_max = alpha.iter().copied().fold(0.0f64, f64::max);
        // Descending; only eigenvalues clearly above round-off, and at most F - 1: the centring
        // removes one dimension exactly, though f32 data rounded about an f32 mean can leave an
        // eigenvalue just above the relative threshold there.
        let keep: Vec<usize> = (0..f)
            .rev()
            .filter(|&i| alpha[i] > 1e-10 * alpha_max && alpha[i] > 0.0)
            .take(max_components.min(f - 1))
            .collect();
        let k = keep.len();
        // T_i = M V_i by blocks of texels: each block's centred data (F x B, f64) multiplied by
        // the kept eigenvectors (k x F) with a sequential GEMM, blocks in parallel a group at a
        // time and copied into the f32 rows, so at most a group's products are held beside the
        // components (a first, block-wise f64 buffer of every component cost 2.3 GB at 100 maps
        // of 1024 x 1024). The block partition is fixed and norms are summed in block order:
        // the same bits whatever the thread count.
        let mut components = vec![0.0f32; k * n];
        let vt = faer::Mat::<f64>::from_fn(k, f, |c, r| v[(r, keep[c])]);
        let n_blocks = n.div_ceil(BLOCK);
        let mut norms = vec![0.0f64; k];
        const GROUP: usize = 64;
        for group in (0..n_blocks).step_by(GROUP) {
            let products: Vec<(usize, faer::Mat<f64>)> = (group..(group + GROUP).min(n_blocks))
                .into_par_iter()
                .map(|b| {
                    let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
                    let m =
                        faer::Mat::<f64>::from_fn(f, hi - lo, |r, j| vectors[r][lo + j] as f64 - mean[lo + j] as f64);
                    let mut out = faer::Mat::<f64>::zeros(k, hi - lo);
                    faer::linalg::matmul::matmul(
                        out.as_mut(),
                        faer::Accum::Replace,
                        vt.as_ref(),
                        m.as_ref(),
                        1.0,
                        faer::Par::Seq,
                    );
                    (lo, out)
                })
                .collect();
            for (lo, out) in products {
                for c in 0..k {
                    let row = &mut components[c * n + lo..c * n + lo + out.ncols()];
                    for (j, x) in row.iter_mut().enumerate() {
                        let value = out[(c, j)];
                        norms[c] += value * value;
                        *x = value as f32;
                    }
                }
            }
        }
        components.par_chunks_mut(n.max(1)).zip(norms.par_iter()).for_each(|(row, &norm)| {
            let s = 1.0 / norm.sqrt();
            row.iter_mut().for_each(|x| *x = (*x as f64 * s) as f32);
        });
        // c_k,i = (G V_i)_k / √α_i.
        let mut coefficients = vec![0.0f64; f * k];
        for (c, &i) in keep.iter().enumerate() {
            let s = alpha[i].sqrt();
            for r in 0..f {
                let gv: f64 = (0..f).map(|l| g[r * f + l] * v[(l, i)]).sum();
                coefficients[r * k + c] = gv / s;
            }
        }
        let eigenvalues = keep.iter().map(|&i| alpha[i]).collect();
        Ok(EigenBasis { dim: n, mean, components, eigenvalues, total_variance, coefficients })
    }

    pub fn n_components(&self) -> usize {
        self.eigenvalues.len()
    }
    /// Number of training vectors.
    pub fn n_frames(&self) -> usize {
        self.coefficients.len() / self.n_components().max(1)
    }
    /// Component `i` (unit length).
    pub fn component(&self, i: usize) -> &[f32] {
        &self.components[i * self.dim..(i + 1) * self.dim]
    }
    /// Coefficients of training frame `k`.
    pub fn frame_coefficients(&self, k: usize) -> &[f64] {
        let c = self.n_components();
        &self.coefficients[k * c..(k + 1) * c]
    }
    /// Fraction of the total variance each kept component explains.
    pub fn explained_variance(&self) -> Vec<f64> {
        self.eigenvalues.iter().map(|a| if self.total_variance > 0.0 { a / self.total_variance } else { 0.0 }).collect()
    }

    /// The basis restricted to its first `k` components (all when `k` is larger).
    pub fn truncated(&self, k: usize) -> EigenBasis {
        let k = k.min(self.n_components());
        let c = self.n_components();
        let f = self.n_frames();
        EigenBasis {
            dim: self.dim,
            mean: self.mean.clone(),
            components: self.components[..k * self.dim].to_vec(),
            eigenvalues: self.eigenvalues[..k].to_vec(),
            total_variance: self.total_variance,
            coefficients: (0..f).flat_map(|r| self.coefficients[r * c..r * c + k].to_vec()).collect(),
        }
    }

    /// `x̄ + Σ_i c_i T_i` with the first `coefficients.len()` components.
    pub fn reconstruct(&self, coefficients: &[f64]) -> Result<Vec<f32>> {
        if coefficients.len() > self.n_components() {
            return Err(Error::Mismatch(format!(
                "{} coefficients: the basis has {} components",
                coefficients.len(),
                self.n_components()
            )));
        }
        if let Some(i) = coefficients.iter().position(|c| !c.is_finite()) {
            return Err(Error::Invalid(format!("coefficient {i} is {}: expected a finite number", coefficients[i])));
        }
        let n = self.dim;
        let mut out: Vec<f64> = self.mean.iter().map(|&m| m as f64).collect();
        out.par_chunks_mut(4096).enumerate().for_each(|(b, chunk)| {
            let lo = b * 4096;
            for (i, &c) in coefficients.iter().enumerate() {
                let t = &self.components[i * n + lo..i * n + lo + chunk.len()];
                for (o, &x) in chunk.iter_mut().zip(t) {
                    *o += c * x as f64;
                }
            }
        });
        Ok(out.into_iter().map(|x| x as f32).collect())
    }

    /// Coefficients `Tᵀ (x - x̄)` of a vector.
    pub fn project(&self, x: &[f32]) -> Result<Vec<f64>> {
        self.check_len(x.len())?;
        Ok((0..self.n_components())
            .into_par_iter()
            .map(|i| {
                self.component(i)
                    .iter()
                    .zip(x)
                    .zip(&self.mean)
                    .map(|((&t, &v), &m)| t as f64 * (v as f64 - m as f64))
                    .sum()
            })
            .collect())
    }

    /// Coefficients from the entries where `observed` is true only (thesis 4.6.2: an
    /// incomplete map projected into the eigen space). The thesis says "projecting"; plain
    /// least squares on the observed entries, `argmin_c Σ_{j observed} (x̄_j + Σ_i c_i T_ij -
    /// x_j)²`, over-fits: with many components it bends the coefficients to the observed
    /// texels' noise, and inside the hole did worse than the mean texture (MSE 49 against 33.5
    /// on the unit test's frame). So the projection is the MAP estimate of probabilistic PCA
    /// (Tipping & Bishop 1999): coefficient i has the prior variance it has over the training
    /// frames, `α_i / F`, and each observed entry a noise variance σ², the variance per entry
    /// the kept components leave out (PPCA's maximum-likelihood σ²), floored at 1% of the
    /// data's variance per entry so that a basis of every component keeps a prior:
    /// `(T_oᵀ T_o + σ² diag(F / α_i)) c = T_oᵀ (x_o - x̄_o)`. With everything observed and
    /// small σ² it is the orthogonal projection.
    pub fn project_observed(&self, x: &[f32], observed: &[bool]) -> Result<Vec<f64>> {
        self.check_len(x.len())?;
        self.check_len(observed.len())?;
        let k = self.n_components();
        if !observed.iter().any(|&o| o) {
            return Err(Error::Invalid("nothing observed to project: expected some observed texels".into()));
        }
        let mut a = vec![0.0f64; k * k];
        let mut b = vec![0.0f64; k];
        for j in (0..self.dim).filter(|&j| observed[j]) {
            let r = x[j] as f64 - self.mean[j] as f64;
            for p in 0..k {
                let tp = self.components[p * self.dim + j] as f64;
                b[p] += tp * r;
                for q in 0..=p {
                    a[p * k + q] += tp * self.components[q * self.dim + j] as f64;
                }
            }
        }
        let mean_diag = (0..k).map(|p| a[p * k + p]).sum::<f64>() / k.max(1) as f64;
        let frames = self.n_frames().max(1) as f64;
        let per_entry = |v: f64| v / (frames * self.dim as f64);
        let kept: f64 = self.eigenvalues.iter().sum();
        let sigma2 = per_entry(self.total_variance - kept).max(0.01 * per_entry(self.total_variance));
        for p in 0..k {
            let prior_variance = self.eigenvalues[p] / frames;
            a[p * k + p] += if prior_variance > 0.0 { sigma2 / prior_variance } else { 0.0 };
            a[p * k + p] += 1e-9 * mean_diag.max(f64::MIN_POSITIVE);
            for q in 0..p {
                a[q * k + p] = a[p * k + q];
            }
        }
        cholesky_solve(&mut a, &mut b, k)?;
        Ok(b)
    }

    fn check_len(&self, len: usize) -> Result<()> {
        if len == self.dim {
            return Ok(());
        }
        Err(Error::Mismatch(format!("a vector of {len} values: the basis has {} per vector", self.dim)))
    }
}

/// Solves `A x = b` in place (`A` symmetric positive definite, row-major k x k).
fn cholesky_solve(a: &mut [f64], b: &mut [f64], k: usize) -> Result<()> {
    for j in 0..k {
        let mut d = a[j * k + j];
        for p in 0..j {
            d -= a[j * k + p] * a[j * k + p];
        }
        if d.is_nan() || d <= 0.0 {
            return Err(Error::Solver {
                what: "the least-squares projection onto the observed texels".into(),
                message: "the normal matrix is not positive definite".into(),
            });
        }
        let d = d.sqrt();
        a[j * k + j] = d;
        for i in j + 1..k {
            let mut s = a[i * k + j];
            for p in 0..j {
                s -= a[i * k + p] * a[j * k + p];
            }
            a[i * k + j] = s / d;
        }
    }
    for i in 0..k {
        let mut s = b[i];
        for p in 0..i {
            s -= a[i * k + p] * b[p];
        }
        b[i] = s / a[i * k + i];
    }
    for i in (0..k).rev() {
        let mut s = b[i];
        for p in i + 1..k {
            s -= a[p * k + i] * b[p];
        }
        b[i] = s / a[i * k + i];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random_vectors(f: usize, n: usize, seed: u64) -> Vec<Vec<f32>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..f).map(|_| (0..n).map(|_| rng.random_range(-10.0f32..10.0)).collect()).collect()
    }

    #[test]
    fn the_gram_route_gives_orthonormal_components_and_exact_reconstruction() {
        let data = random_vectors(8, 300, 1);
        let refs: Vec<&[f32]> = data.iter().map(Vec::as_slice).collect();
        let b = EigenBasis::new(&refs, 100, "test vectors").unwrap();
        assert_eq!(b.n_components(), 7, "F - 1 components after centring");
        for i in 0..7 {
            for j in 0..7 {
                let d: f64 = b.component(i).iter().zip(b.component(j)).map(|(&x, &y)| x as f64 * y as f64).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((d - want).abs() < 1e-5, "<T{i}, T{j}> = {d}");
            }
        }
        assert!(b.eigenvalues.windows(2).all(|w| w[0] >= w[1]));
        let ev: f64 = b.explained_variance().iter().sum();
        assert!((ev - 1.0).abs() < 1e-9, "all components explain everything: {ev}");
        for (k, v) in data.iter().enumerate() {
            let projected = b.project(v).unwrap();
            for (a, c) in projected.iter().zip(b.frame_coefficients(k)) {
                assert!((a - c).abs() < 1e-3 * (1.0 + c.abs()), "frame {k}: {a} vs {c}");
            }
            let back = b.reconstruct(b.frame_coefficients(k)).unwrap();
            let err = back.iter().zip(v).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
            assert!(err < 1e-3, "frame {k}: max error {err}");
        }
    }

    #[test]
    fn projection_on_observed_entries_recovers_a_vector_of_the_span() {
        let data = random_vectors(6, 200, 2);
        let refs: Vec<&[f32]> = data.iter().map(Vec::as_slice).collect();
        let b = EigenBasis::new(&refs, 100, "test vectors").unwrap();
        let observed: Vec<bool> = (0..200).map(|j| j % 3 != 0).collect();
        let c = b.project_observed(&data[3], &observed).unwrap();
        // The PPCA prior shrinks the coefficients a little (its noise floor is 1% of the
        // variance per entry, against 133 observed entries): within 0.1%.
        for (a, want) in c.iter().zip(b.frame_coefficients(3)) {
            assert!((a - want).abs() < 1e-3 * (1.0 + want.abs()), "{a} vs {want}");
        }
    }

    #[test]
    fn vectors_of_different_lengths_are_refused_by_frame() {
        let a = vec![0.0f32; 4];
        let b = vec![0.0f32; 5];
        let e = EigenBasis::new(&[&a, &b], 3, "aligned textures").unwrap_err().to_string();
        assert!(e.contains("aligned textures of frame 1 has 5 values: expected 4"), "{e}");
    }
}
