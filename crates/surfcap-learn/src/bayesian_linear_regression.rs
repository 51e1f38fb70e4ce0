//! Bayesian linear regression between paired poses (thesis 5.5.1, eq. 5.4-5.8): the
//! association cost used to densify key-pose correspondences in motion transfer (thesis chapter 5).
//!
//! Model `y = M x + e`, `e ~ N(0, s^2 I)` (eq. 5.4-5.5), prior `row(M) ~ N(0, I)`. With the
//! L training pairs as columns of X (p x L) and Y (q x L), `A = X X^T / s^2 + I` and the
//! posterior of M is Gaussian with mean `Y X^T A^-1 / s^2` (eq. 5.6; A is symmetric, so the
//! printed `A^-T` is `A^-1`). The predictive distribution of `M x` (eq. 5.7) has mean
//! `Y X^T A^-1 x / s^2` and covariance `x^T A^-1 x I`.
//!
//! As PAPER-NOTES.md points out, `x^T A^-1 x` vanishes at x = 0 and the cost of eq. 5.8 would
//! divide by zero; [`Predictive::Observation`] (the default) adds `s^2`, giving the predictive
//! distribution of a new observation y rather than of `M x`. [`Predictive::Function`] is the
//! thesis's literal eq. 5.7.

use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef, Side};
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};
use crate::matrix::{check_finite, check_finite_slice, serde_mat};

/// Which predictive variance to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Predictive {
    /// `x^T A^-1 x` (eq. 5.7 as printed).
    Function,
    /// `x^T A^-1 x + s^2`: the distribution of an observed y (finite cost at x = 0).
    Observation,
}

/// A fitted Bayesian linear map from source poses (p) to target poses (q).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BayesianLinearRegression {
    /// Posterior mean of M (q x p).
    #[serde(with = "serde_mat")]
    pub mean_map: Mat<f64>,
    /// `A^-1` (p x p), the posterior covariance of each row of M.
    #[serde(with = "serde_mat")]
    pub a_inv: Mat<f64>,
    /// Noise variance `s^2` (0.01 in the thesis's experiments).
    pub noise_variance: f64,
    pub predictive: Predictive,
}

impl BayesianLinearRegression {
    /// Fits from L pairs given as rows: `x` (L x p) source poses, `y` (L x q) target poses.
    pub fn fit(x: MatRef<'_, f64>, y: MatRef<'_, f64>, noise_variance: f64, predictive: Predictive) -> Result<Self> {
        if x.nrows() != y.nrows() {
            return Err(LearnError::Dimension(format!("{} source poses but {} target poses", x.nrows(), y.nrows())));
        }
        if x.nrows() == 0 || x.ncols() == 0 || y.ncols() == 0 {
            return Err(LearnError::Invalid("empty training pairs".into()));
        }
        if !(noise_variance.is_finite() && noise_variance > 0.0) {
            return Err(LearnError::Invalid(format!("noise variance {noise_variance}: expected > 0")));
        }
        check_finite(x, "source poses")?;
        check_finite(y, "target poses")?;
        let p = x.ncols();
        // A = X X^T / s^2 + I with X as columns: here x^T x (p x p).
        let mut a = x.transpose() * x;
        for i in 0..p {
            for j in 0..p {
                a[(i, j)] /= noise_variance;
            }
            a[(i, i)] += 1.0;
        }
        let llt = a.llt(Side::Lower).map_err(|e| LearnError::NotPositiveDefinite(format!("A: {e:?}")))?;
        let a_inv = llt.solve(Mat::<f64>::identity(p, p));
        // Mean map = Y X^T A^-1 / s^2 = (y^T x) A^-1 / s^2.
        let mut mean_map = y.transpose() * x * &a_inv;
        for v in mean_map.col_iter_mut().flat_map(|c| c.iter_mut()) {
            *v /= noise_variance;
        }
        Ok(BayesianLinearRegression { mean_map, a_inv, noise_variance, predictive })
    }

    /// Predictive mean (q) and isotropic variance at the source pose `x` (eq. 5.7).
    pub fn predict(&self, x: &[f64]) -> Result<(Vec<f64>, f64)> {
        let p = self.a_inv.nrows();
        if x.len() != p {
            return Err(LearnError::Dimension(format!("source pose of {} values: expected {p}", x.len())));
        }
        check_finite_slice(x, "source pose")?;
        let mean = (0..self.mean_map.nrows()).map(|r| (0..p).map(|c| self.mean_map[(r, c)] * x[c]).sum()).collect();
        let mut v: f64 = 0.0;
        for i in 0..p {
            for j in 0..p {
                v += x[i] * self.a_inv[(i, j)] * x[j];
            }
        }
        if self.predictive == Predictive::Observation {
            v += self.noise_variance;
        }
        Ok((mean, v))
    }

    /// Association cost `-log P` of eq. 5.8: `|y - mu|^2 / (2 v)` for target pose `y`
    /// (infinite when the variance is 0, which [`Predictive::Observation`] avoids).
    pub fn association_cost(&self, x: &[f64], y: &[f64]) -> Result<f64> {
        let (mu, v) = self.predict(x)?;
        if y.len() != mu.len() {
            return Err(LearnError::Dimension(format!("target pose of {} values: expected {}", y.len(), mu.len())));
        }
        check_finite_slice(y, "target pose")?;
        let r2: f64 = y.iter().zip(&mu).map(|(a, b)| (a - b).powi(2)).sum();
        Ok(if v > 0.0 { 0.5 * r2 / v } else { f64::INFINITY })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn posterior_mean_approaches_the_true_map_and_costs_rank_the_right_pose() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let m_true = Mat::from_fn(3, 4, |_, _| rng.random_range(-1.0..1.0));
        let x = Mat::from_fn(40, 4, |_, _| rng.random_range(-1.0..1.0));
        let mut y = &x * m_true.transpose();
        for v in y.col_iter_mut().flat_map(|c| c.iter_mut()) {
            *v += 0.01 * crate::hybrid_monte_carlo::standard_normal(&mut rng);
        }
        let b = BayesianLinearRegression::fit(x.as_ref(), y.as_ref(), 0.01, Predictive::Observation).unwrap();
        for r in 0..3 {
            for c in 0..4 {
                assert!((b.mean_map[(r, c)] - m_true[(r, c)]).abs() < 0.05);
            }
        }
        // With few pairs the prior shrinks the map: mean = Y X^T (X X^T + s^2 I)^-1 by hand.
        let xs = [0.5, -0.2, 0.1, 0.3];
        let (mu, v) = b.predict(&xs).unwrap();
        let right: Vec<f64> = (0..3).map(|r| (0..4).map(|c| m_true[(r, c)] * xs[c]).sum()).collect();
        let wrong: Vec<f64> = right.iter().map(|v| v + 0.5).collect();
        assert!(b.association_cost(&xs, &right).unwrap() < b.association_cost(&xs, &wrong).unwrap());
        assert!(v > 0.01 && mu.len() == 3);
        // Eq. 5.7 literally: zero variance at x = 0, so an infinite cost; the observation form is finite.
        let f = BayesianLinearRegression::fit(x.as_ref(), y.as_ref(), 0.01, Predictive::Function).unwrap();
        assert_eq!(f.predict(&[0.0; 4]).unwrap().1, 0.0);
        assert!(b.association_cost(&[0.0; 4], &[0.1, 0.0, 0.0]).unwrap().is_finite());
        assert!(b.predict(&[0.0; 3]).is_err());
        assert!(BayesianLinearRegression::fit(x.as_ref(), y.as_ref(), 0.0, Predictive::Function).is_err());
    }

    #[test]
    fn one_pair_matches_the_closed_form() {
        // p = q = 1, one pair (x, y): A = x^2/s^2 + 1, mean = y x / (s^2 A).
        let (x, y, s2) = (2.0, 3.0, 0.5);
        let b = BayesianLinearRegression::fit(
            Mat::from_fn(1, 1, |_, _| x).as_ref(),
            Mat::from_fn(1, 1, |_, _| y).as_ref(),
            s2,
            Predictive::Function,
        )
        .unwrap();
        let a = x * x / s2 + 1.0;
        assert!((b.mean_map[(0, 0)] - y * x / (s2 * a)).abs() < 1e-12);
        assert!((b.predict(&[1.0]).unwrap().1 - 1.0 / a).abs() < 1e-12);
    }
}
