//! surfcap-learn: the Gaussian-process toolkit of thesis chapters 5 and 6 (Boukhayma 2017).
//!
//! One algorithm per file:
//! - [`pca`]: principal component analysis (thin SVD, or the Gram matrix when the dimension far
//!   exceeds the samples; thesis 5.4.3 and the GPDM initialisation of 6.5.1).
//! - [`kernels`]: covariance functions (eq. 5.13, 5.14, 6.4, 6.6) with analytic derivatives.
//! - [`gp_regression`]: GP regression with fitted hyper-parameters (eq. 5.11-5.17).
//! - [`bayesian_linear_regression`]: the predictive distribution of eq. 5.4-5.8.
//! - [`gpdm`]: the Gaussian Process Dynamical Model (eq. 6.1-6.13).
//! - [`hybrid_monte_carlo`]: Hybrid Monte Carlo with leapfrog steps (6.6.2).
//! - [`lbfgs`]: the L-BFGS optimiser used for the fits.
//! - [`matrix`]: serde and `.npy` for matrices, Cholesky with adaptive jitter.
//!
//! The library never prints, exits or reads the environment; every randomised routine takes a
//! seed and uses ChaCha8 streams, so the same seed gives the same result on any thread count.

pub mod bayesian_linear_regression;
pub mod error;
pub mod gp_regression;
pub mod gpdm;
pub mod hybrid_monte_carlo;
pub mod kernels;
pub mod lbfgs;
pub mod matrix;
pub mod pca;

pub use error::{LearnError, Result};
pub use faer::Mat;
