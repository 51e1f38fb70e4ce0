//! surfcap-learn: the Gaussian-process toolkit of thesis chapters 5 and 6 (Boukhayma 2017).
//!
//! One algorithm per file:
//! - [`pca`]: principal component analysis (thin SVD, or the N x N Gram matrix when the dimension
//!   far exceeds the samples; thesis 5.4.3 and the GPDM initialisation of 6.5.1); projection,
//!   reconstruction, explained variance.
//! - [`kernels`]: covariance functions (NN/arcsine eq. 5.13 with optional bias input, SE and linear
//!   eq. 5.14, white, sums as in eq. 6.4 and 6.6) with log hyper-parameters and analytic
//!   derivatives w.r.t. parameters and inputs, all from one set of inner products per training set.
//! - [`gp_regression`]: several outputs sharing one kernel, Cholesky with adaptive jitter, NLML with
//!   analytic gradients, L-BFGS fit with seeded restarts, predictive mean and variance (eq.
//!   5.11-5.17); serialised as inputs + hyper-parameters, refactorised on load.
//! - [`bayesian_linear_regression`]: the predictive distribution of eq. 5.4-5.8 (association cost).
//! - [`gpdm`]: the Gaussian Process Dynamical Model (eq. 6.1-6.13): MAP over latents and
//!   alpha/beta with the 6.5.1 priors, PCA start, several sequences (6.5.2), Y Y^T precomputed so
//!   an evaluation is O(N^3) whatever D, mean prediction, trajectory density, HMC trajectories.
//! - [`hybrid_monte_carlo`]: leapfrog steps, dual-averaging step size, path length from the
//!   warm-up spread, seeded (6.6.2).
//! - [`lbfgs`]: L-BFGS with a strong-Wolfe line search. Written here rather than taken from
//!   `argmin`: objective and gradient share one factorisation, and infeasible trial points must
//!   shrink the step, which argmin's separate cost/gradient traits make awkward.
//! - [`matrix`]: serde and `.npy` for matrices, Cholesky with adaptive jitter.
//!
//! The library never prints, exits or reads the environment; every randomised routine takes a
//! seed and uses ChaCha8 streams, and kernel matrices and gradient sums are added in column order,
//! so the same seed gives the same result on any thread count. faer does the dense work (a
//! 2000 x 2000 Cholesky in about 60 ms).
//!
//! # Performance
//!
//! faer's dense product of a short-and-wide by a square matrix, (99 x 398)(398 x 398) on one
//! thread, ran 6-7x slower in about half of the runs of the same binary (faer's `m8`
//! micro-kernel); the transposed layout (398 x 398)(398 x 99) was fast in every run. The GPDM's
//! HMC trajectory density therefore uses the transposed layout, and plain loops for products with
//! a side of size d = 3.

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
