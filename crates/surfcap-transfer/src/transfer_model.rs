//! The pose and displacement mapping between two subjects (thesis 5.5.2, eq. 5.11-5.17; CVPR
//! 2017 sec. 5.2): one GP regression per body part from the source part's PCA coefficients to
//! the target part's, and one from the source's rigid displacement (eq. 5.3) to the target's.
//!
//! - **Kernels**: the neural-network kernel of eq. 5.13 by default, with the bias input
//!   (PAPER-NOTES: the printed form has none; with centred PCA coefficients the augmented input
//!   (1, x) behaves better); the squared-exponential and linear kernels of eq. 5.14 for the
//!   comparison of 5.7.1. A GP with the linear kernel is Bayesian linear regression, the
//!   thesis's "linear" model.
//! - **Hyper-parameters**: fitted by maximising the marginal likelihood (the thesis uses
//!   conjugate gradients; here L-BFGS, `surfcap_learn::gp_regression`), the noise variance
//!   included. The thesis fixes `s_n^2 = 0.1` in its own (unstated) coefficient units; we
//!   start the fit at 0.1 of the output variance and let the likelihood choose, so the model
//!   does not depend on whether a subject is measured in metres or centimetres.
//! - **Prediction**: the predictive mean, eq. 5.17, for every output of a part.
//!
//! The per-part GPs are independent (5.4: "independent regressions"); they are fitted in
//! parallel, each with its own seeded restarts, so the result does not depend on the threads.

use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use surfcap_learn::gp_regression::{GpFitOptions, GpRegression};
use surfcap_learn::kernels::Kernel;

use crate::error::{Error, Result};

/// Which covariance the transfer GPs use (5.7.1 compares them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TransferKernel {
    /// Eq. 5.13 (with bias input): the thesis's choice.
    NeuralNetwork,
    /// Eq. 5.14, first line.
    SquaredExponential,
    /// Eq. 5.14, second line (Bayesian linear regression).
    Linear,
}

impl TransferKernel {
    pub const ALL: [TransferKernel; 3] =
        [TransferKernel::NeuralNetwork, TransferKernel::SquaredExponential, TransferKernel::Linear];

    pub fn name(self) -> &'static str {
        match self {
            TransferKernel::NeuralNetwork => "nn",
            TransferKernel::SquaredExponential => "se",
            TransferKernel::Linear => "linear",
        }
    }

    /// Parses `nn`, `se` or `linear`.
    pub fn parse(s: &str) -> Result<TransferKernel> {
        match s {
            "nn" => Ok(TransferKernel::NeuralNetwork),
            "se" => Ok(TransferKernel::SquaredExponential),
            "linear" => Ok(TransferKernel::Linear),
            _ => Err(Error::Invalid(format!("kernel \"{s}\": expected nn, se or linear"))),
        }
    }

    /// The starting kernel for inputs whose mean squared norm is `scale2`.
    fn initial(self, scale2: f64, output_variance: f64) -> Kernel {
        let l = scale2.max(1e-12).sqrt();
        match self {
            TransferKernel::NeuralNetwork => Kernel::neural_network(output_variance.max(1e-12), l),
            TransferKernel::SquaredExponential => Kernel::squared_exponential(output_variance.max(1e-12), l),
            TransferKernel::Linear => Kernel::linear((output_variance / scale2.max(1e-12)).max(1e-12)),
        }
    }
}

/// Options of [`PoseMapping::fit`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct MappingOptions {
    pub kernel: TransferKernel,
    /// Starting noise variance, relative to the output variance (0.1: the thesis's value
    /// read as relative, see the module comment).
    pub relative_noise: f64,
    /// Fit hyper-parameters (otherwise the starting values are kept).
    pub fit_hyper_parameters: bool,
    pub fit: GpFitOptions,
}

impl Default for MappingOptions {
    fn default() -> Self {
        MappingOptions {
            kernel: TransferKernel::NeuralNetwork,
            relative_noise: 0.1,
            fit_hyper_parameters: true,
            fit: GpFitOptions { restarts: 1, ..GpFitOptions::default() },
        }
    }
}

/// What a fit of one GP did.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MappingFit {
    /// Inputs and outputs.
    pub input_dimension: usize,
    pub output_dimension: usize,
    /// Negative log marginal likelihood at the optimum.
    pub nlml: f64,
    /// The fitted hyper-parameters by name (natural logs, as the kernel stores them).
    pub hyper_parameters: Vec<(String, f64)>,
    pub noise_variance: f64,
}

/// One GP regression from source vectors to target vectors (a part's coefficients, or the
/// rigid displacement).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseMapping {
    pub gp: GpRegression,
}

impl PoseMapping {
    /// Fits the mapping from rows of `x` (N x p) to rows of `y` (N x q).
    pub fn fit(x: Mat<f64>, y: Mat<f64>, opts: &MappingOptions) -> Result<(PoseMapping, MappingFit)> {
        if x.nrows() != y.nrows() {
            return Err(Error::Invalid(format!("{} source rows but {} target rows", x.nrows(), y.nrows())));
        }
        if x.nrows() < 2 {
            return Err(Error::Invalid(format!("{} training pairs: expected at least 2", x.nrows())));
        }
        let n = x.nrows() as f64;
        let scale2 =
            (0..x.nrows()).map(|i| (0..x.ncols()).map(|j| x[(i, j)] * x[(i, j)]).sum::<f64>()).sum::<f64>() / n;
        let var_y = output_variance(&y);
        let kernel = opts.kernel.initial(scale2, var_y);
        let noise = (opts.relative_noise * var_y).max(1e-12);
        let (input_dimension, output_dimension) = (x.ncols(), y.ncols());
        let gp = if opts.fit_hyper_parameters {
            GpRegression::fit(kernel, noise, x, y, &opts.fit)?.0
        } else {
            GpRegression::new(kernel, noise, x, y)?
        };
        let fit = MappingFit {
            input_dimension,
            output_dimension,
            nlml: gp.negative_log_marginal_likelihood(),
            hyper_parameters: gp.kernel().param_names().into_iter().zip(gp.kernel().params()).collect(),
            noise_variance: gp.noise_variance(),
        };
        Ok((PoseMapping { gp }, fit))
    }

    /// Predictive means (eq. 5.17) at the rows of `x`.
    pub fn predict(&self, x: &Mat<f64>) -> Result<Mat<f64>> {
        Ok(self.gp.predict(x.as_ref())?.mean)
    }
}

/// Mean per-column variance of `y`.
fn output_variance(y: &Mat<f64>) -> f64 {
    let n = y.nrows() as f64;
    let mut total = 0.0;
    for j in 0..y.ncols() {
        let mean = (0..y.nrows()).map(|i| y[(i, j)]).sum::<f64>() / n;
        total += (0..y.nrows()).map(|i| (y[(i, j)] - mean).powi(2)).sum::<f64>() / n;
    }
    total / y.ncols().max(1) as f64
}

/// Fits one mapping per (x, y) pair in parallel, in order; each with its own seed
/// (`opts.fit.seed + index`), so the result does not depend on the thread count.
pub fn fit_all(pairs: Vec<(Mat<f64>, Mat<f64>)>, opts: &MappingOptions) -> Result<Vec<(PoseMapping, MappingFit)>> {
    pairs
        .into_par_iter()
        .enumerate()
        .map(|(i, (x, y))| {
            let mut o = *opts;
            o.fit.seed = opts.fit.seed.wrapping_add(i as u64);
            PoseMapping::fit(x, y, &o)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nn_mapping_learns_a_smooth_nonlinear_map_better_than_linear() {
        let f = |a: f64, b: f64| [(1.5 * a).sin() + 0.3 * b, a * b];
        let grid: Vec<(f64, f64)> =
            (0..60).map(|i| ((i % 10) as f64 / 4.5 - 1.0, (i / 10) as f64 / 2.5 - 1.0)).collect();
        let x = Mat::from_fn(grid.len(), 2, |i, j| if j == 0 { grid[i].0 } else { grid[i].1 });
        let y = Mat::from_fn(grid.len(), 2, |i, j| f(grid[i].0, grid[i].1)[j]);
        let test: Vec<(f64, f64)> = (0..20).map(|i| (-0.9 + 0.09 * i as f64, 0.7 - 0.06 * i as f64)).collect();
        let xt = Mat::from_fn(test.len(), 2, |i, j| if j == 0 { test[i].0 } else { test[i].1 });
        let err = |k: TransferKernel| {
            let opts = MappingOptions { kernel: k, ..MappingOptions::default() };
            let (m, fit) = PoseMapping::fit(x.clone(), y.clone(), &opts).unwrap();
            assert_eq!((fit.input_dimension, fit.output_dimension), (2, 2));
            let p = m.predict(&xt).unwrap();
            (0..test.len())
                .map(|i| {
                    let t = f(test[i].0, test[i].1);
                    (p[(i, 0)] - t[0]).powi(2) + (p[(i, 1)] - t[1]).powi(2)
                })
                .sum::<f64>()
                .sqrt()
        };
        let (nn, se, lin) =
            (err(TransferKernel::NeuralNetwork), err(TransferKernel::SquaredExponential), err(TransferKernel::Linear));
        assert!(nn < 0.2 * lin && se < 0.2 * lin, "nn {nn} se {se} linear {lin}");
    }

    #[test]
    fn kernel_names_parse_and_bad_ones_are_named() {
        for k in TransferKernel::ALL {
            assert_eq!(TransferKernel::parse(k.name()).unwrap(), k);
        }
        let e = TransferKernel::parse("rbf").unwrap_err().to_string();
        assert_eq!(e, "kernel \"rbf\": expected nn, se or linear");
    }
}
