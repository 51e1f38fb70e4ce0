//! Gaussian-process regression (thesis 5.5.2, eq. 5.11-5.17; Rasmussen and Williams 2006,
//! Algorithm 2.1 and eq. 5.8-5.9).
//!
//! Several outputs share one kernel and one noise variance (the thesis fits one GP per pose
//! parameter `y_i` with the same inputs; sharing the hyper-parameters means one factorisation
//! serves them all). Exact inference: `K + s_n^2 I = L L^T` by Cholesky with adaptive jitter
//! ([`crate::matrix::cholesky_jitter`]), `alpha = K^-1 Y`.
//!
//! The negative log marginal likelihood over m outputs is
//! `m/2 log|K| + 1/2 tr(Y^T K^-1 Y) + N m/2 log 2 pi`, and its gradient with respect to any
//! hyper-parameter `theta` is `tr(W dK/dtheta)` with `W = 1/2 (m K^-1 - alpha alpha^T)`: one
//! inverse per evaluation and an elementwise pass per parameter ([`Kernel::param_gradients`]).
//! Hyper-parameters (kernel and noise) are fitted by L-BFGS in log space with seeded restarts.
//!
//! Outputs are centred by their training mean (a constant mean function estimated from the data);
//! the thesis assumes a zero mean after body-part alignment, which centring keeps true for any
//! input. Expensive work (factorisation, `alpha`) is done once in [`GpRegression::new`] /
//! [`GpRegression::fit`]; [`GpRegression::predict`] costs O(M N (d + m)) plus O(M N^2) for the
//! variances. The model serialises as its inputs, outputs and hyper-parameters, and refactorises
//! when read back.

use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};
use crate::kernels::{Kernel, Pairwise};
use crate::lbfgs::{LbfgsOptions, minimize};
use crate::matrix::{Factor, centred, check_finite, cholesky_jitter, column_means, serde_mat};

/// What a GP is built from; the serialised form of [`GpRegression`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GpSpec {
    pub kernel: Kernel,
    /// Natural log of the observation-noise variance `s_n^2` (eq. 5.11).
    pub log_noise_variance: f64,
    /// Training inputs (N x d).
    #[serde(with = "serde_mat")]
    pub x: Mat<f64>,
    /// Training outputs (N x m), not centred.
    #[serde(with = "serde_mat")]
    pub y: Mat<f64>,
}

/// A GP regression model with its factorisation.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "GpSpec", into = "GpSpec")]
pub struct GpRegression {
    spec: GpSpec,
    y_mean: Vec<f64>,
    l: Mat<f64>,
    alpha: Mat<f64>,
    jitter: f64,
    nlml: f64,
}

impl TryFrom<GpSpec> for GpRegression {
    type Error = LearnError;
    fn try_from(s: GpSpec) -> Result<Self> {
        GpRegression::new(s.kernel, s.log_noise_variance.exp(), s.x, s.y)
    }
}

impl From<GpRegression> for GpSpec {
    fn from(g: GpRegression) -> GpSpec {
        g.spec
    }
}

/// Predictive distribution at M test inputs (eq. 5.16).
#[derive(Debug, Clone)]
pub struct Prediction {
    /// Predictive mean (M x m), eq. 5.17.
    pub mean: Mat<f64>,
    /// Variance of the latent function `f(x*)`, shared by all outputs:
    /// `k(x*, x*) - k*^T K^-1 k*` (eq. 5.16).
    pub latent_variance: Vec<f64>,
    /// Variance of a new observation `y* = f(x*) + noise`: latent variance plus `s_n^2` (plus
    /// any white term of the kernel and the jitter the factorisation needed).
    pub observation_variance: Vec<f64>,
}

/// Options of [`GpRegression::fit`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct GpFitOptions {
    /// Extra starts besides the given hyper-parameters, each a seeded random perturbation
    /// (standard normal in log space) of them; the best optimum wins.
    pub restarts: usize,
    /// With restarts and more training points than this, every start is first optimised on
    /// this many evenly spaced rows (64 times cheaper per evaluation at 2,000 points for 500),
    /// and only the best of those optima is refined on the whole set. Multi-start search is
    /// about finding the right basin, which a subset already shows; the O(N^3) full-data
    /// evaluations are then spent once. 0 disables the screening.
    pub screen_points: usize,
    pub seed: u64,
    pub lbfgs: LbfgsOptions,
    /// Lower bound on the noise variance (relative to the output variance), keeping `K`
    /// well conditioned: the optimiser sees `s_n^2 = floor + exp(theta)`.
    pub min_relative_noise: f64,
}

impl Default for GpFitOptions {
    fn default() -> Self {
        GpFitOptions {
            restarts: 2,
            screen_points: 500,
            seed: 0,
            lbfgs: LbfgsOptions {
                max_iters: 60,
                max_evals: 80,
                grad_tol: 1e-4,
                f_tol: 1e-7,
                memory: 10,
                initial_step: 1.0,
            },
            min_relative_noise: 1e-8,
        }
    }
}

/// What a fit did.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GpFitReport {
    /// Negative log marginal likelihood at the optimum.
    pub nlml: f64,
    /// Objective evaluations over all starts (screening included).
    pub evals: usize,
    /// Of those, evaluations on the whole training set (each O(N^3)).
    pub full_data_evals: usize,
    /// Best value reached from each start (NaN when a start failed); on the screening subset
    /// when `screened_rows` is not `None`.
    pub start_values: Vec<f64>,
    /// Rows of the screening subset, when the starts were screened on one.
    pub screened_rows: Option<usize>,
}

/// Checks the training set shape.
fn check_xy(x: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
    if x.nrows() != y.nrows() {
        return Err(LearnError::Dimension(format!("{} inputs but {} outputs", x.nrows(), y.nrows())));
    }
    if x.nrows() == 0 || x.ncols() == 0 || y.ncols() == 0 {
        return Err(LearnError::Invalid(format!(
            "GP training set of {} x {} inputs and {} outputs",
            x.nrows(),
            x.ncols(),
            y.ncols()
        )));
    }
    check_finite(x, "GP inputs")?;
    check_finite(y, "GP outputs")
}

/// Work shared by the objective evaluations of one training set.
struct Objective<'a> {
    pairwise: Pairwise,
    yc: MatRef<'a, f64>,
    template: Kernel,
    noise_floor: f64,
}

impl Objective<'_> {
    /// NLML and its gradient (kernel parameters, then log noise) at `theta`.
    fn eval(&self, theta: &[f64], grad: &mut [f64]) -> f64 {
        let np = self.template.n_params();
        let mut kernel = self.template.clone();
        if kernel.set_params(&theta[..np]).is_err() {
            return f64::INFINITY;
        }
        let noise = self.noise_floor + theta[np].exp();
        match nlml_parts(&kernel, noise, &self.pairwise, self.yc, true) {
            Ok((f, w, _, _)) => {
                let w = w.expect("asked for the gradient");
                let g = kernel.param_gradients(&self.pairwise, w.as_ref());
                grad[..np].copy_from_slice(&g);
                let trace: f64 = (0..w.nrows()).map(|i| w[(i, i)]).sum();
                grad[np] = trace * theta[np].exp();
                f
            }
            Err(_) => f64::INFINITY,
        }
    }
}

type NlmlParts = (f64, Option<Mat<f64>>, Factor, Mat<f64>);

/// NLML, optionally its matrix gradient W, the factor and alpha.
fn nlml_parts(kernel: &Kernel, noise: f64, p: &Pairwise, yc: MatRef<'_, f64>, want_w: bool) -> Result<NlmlParts> {
    let n = p.len();
    let m = yc.ncols() as f64;
    let mut k = kernel.matrix(p);
    for i in 0..n {
        k[(i, i)] += noise;
    }
    let factor = cholesky_jitter(k.as_ref(), "GP covariance K + s_n^2 I")?;
    let alpha = factor.llt.solve(yc);
    let fit: f64 = (0..yc.ncols()).map(|c| (0..n).map(|i| yc[(i, c)] * alpha[(i, c)]).sum::<f64>()).sum();
    let nlml = 0.5 * fit + 0.5 * m * factor.log_det() + 0.5 * n as f64 * m * (2.0 * std::f64::consts::PI).ln();
    if !nlml.is_finite() {
        return Err(LearnError::NonFinite(format!("negative log marginal likelihood {nlml}")));
    }
    let w = if want_w {
        let mut w = factor.inverse();
        let aat = &alpha * alpha.transpose();
        for j in 0..n {
            for i in 0..n {
                w[(i, j)] = 0.5 * (m * w[(i, j)] - aat[(i, j)]);
            }
        }
        Some(w)
    } else {
        None
    };
    Ok((nlml, w, factor, alpha))
}

/// A starting point for [`GpRegression::fit`] with a squared-exponential kernel: the signal
/// variance is the outputs' mean variance, the length scale the median distance between inputs
/// (over at most 500 evenly spaced rows), the noise a tenth of the signal variance. The usual
/// heuristic (e.g. Rasmussen and Williams 2006, 5.4.1, on scales): it starts the optimiser near
/// the scales of the data, which saves evaluations of the O(N^3) objective.
pub fn squared_exponential_guess(x: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<(Kernel, f64)> {
    check_xy(x, y)?;
    let n = x.nrows();
    let mean = column_means(y);
    let var = (0..y.ncols()).map(|c| (0..n).map(|i| (y[(i, c)] - mean[c]).powi(2)).sum::<f64>()).sum::<f64>()
        / (n * y.ncols()) as f64;
    let var = if var > 0.0 { var } else { 1.0 };
    let step = n.div_ceil(500).max(1);
    let rows: Vec<usize> = (0..n).step_by(step).collect();
    let mut d = Vec::with_capacity(rows.len() * rows.len() / 2);
    for (a, &i) in rows.iter().enumerate() {
        for &j in &rows[a + 1..] {
            d.push((0..x.ncols()).map(|k| (x[(i, k)] - x[(j, k)]).powi(2)).sum::<f64>().sqrt());
        }
    }
    d.sort_by(f64::total_cmp);
    let median = d.get(d.len() / 2).copied().filter(|v| *v > 0.0).unwrap_or(1.0);
    Ok((Kernel::squared_exponential(var, median), 0.1 * var))
}

impl GpRegression {
    /// Builds the model for fixed hyper-parameters: `x` inputs (N x d), `y` outputs (N x m).
    pub fn new(kernel: Kernel, noise_variance: f64, x: Mat<f64>, y: Mat<f64>) -> Result<GpRegression> {
        check_xy(x.as_ref(), y.as_ref())?;
        if !(noise_variance.is_finite() && noise_variance >= 0.0) {
            return Err(LearnError::Invalid(format!("noise variance {noise_variance}: expected >= 0")));
        }
        crate::matrix::check_finite_slice(&kernel.params(), "kernel parameters")?;
        let y_mean = column_means(y.as_ref());
        let yc = centred(y.as_ref(), &y_mean);
        let p = Pairwise::new(x.as_ref());
        let (nlml, _, factor, alpha) = nlml_parts(&kernel, noise_variance, &p, yc.as_ref(), false)?;
        let spec = GpSpec { kernel, log_noise_variance: noise_variance.max(f64::MIN_POSITIVE).ln(), x, y };
        Ok(GpRegression { spec, y_mean, l: factor.llt.L().to_owned(), alpha, jitter: factor.jitter, nlml })
    }

    /// Fits the kernel hyper-parameters and the noise variance by maximising the marginal
    /// likelihood from `kernel` and `noise_variance` (and `opts.restarts` perturbed starts).
    pub fn fit(
        kernel: Kernel,
        noise_variance: f64,
        x: Mat<f64>,
        y: Mat<f64>,
        opts: &GpFitOptions,
    ) -> Result<(GpRegression, GpFitReport)> {
        check_xy(x.as_ref(), y.as_ref())?;
        let y_mean = column_means(y.as_ref());
        let yc = centred(y.as_ref(), &y_mean);
        let var_y = (0..yc.ncols())
            .map(|c| (0..yc.nrows()).map(|i| yc[(i, c)].powi(2)).sum::<f64>() / yc.nrows() as f64)
            .sum::<f64>()
            / yc.ncols() as f64;
        let noise_floor = opts.min_relative_noise * var_y.max(f64::MIN_POSITIVE);
        let obj =
            Objective { pairwise: Pairwise::new(x.as_ref()), yc: yc.as_ref(), template: kernel.clone(), noise_floor };
        let mut theta0 = kernel.params();
        theta0.push((noise_variance - noise_floor).max(noise_floor).ln());
        crate::matrix::check_finite_slice(&theta0, "initial hyper-parameters")?;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
        let starts: Vec<Vec<f64>> = (0..=opts.restarts)
            .map(|s| {
                if s == 0 {
                    theta0.clone()
                } else {
                    theta0.iter().map(|t| t + crate::hybrid_monte_carlo::standard_normal(&mut rng)).collect()
                }
            })
            .collect();
        let n = x.nrows();
        let screen = opts.restarts > 0 && opts.screen_points >= 2 && n > opts.screen_points;
        let mut evals = 0;
        let mut full_data_evals = 0;
        let mut start_values = Vec::new();
        // Runs every start on `o`, returning the best optimum.
        let mut run_all = |o: &Objective<'_>, starts: &[Vec<f64>], evals: &mut usize| {
            let mut best: Option<crate::lbfgs::Minimum> = None;
            for start in starts {
                match minimize(|t, g| o.eval(t, g), start, &opts.lbfgs) {
                    Ok(m) => {
                        *evals += m.evals;
                        start_values.push(m.f);
                        if best.as_ref().is_none_or(|b| m.f < b.f) {
                            best = Some(m);
                        }
                    }
                    Err(_) => start_values.push(f64::NAN),
                }
            }
            best
        };
        let best = if screen {
            let rows: Vec<usize> = (0..opts.screen_points).map(|k| k * n / opts.screen_points).collect();
            let xs = Mat::from_fn(rows.len(), x.ncols(), |i, j| x[(rows[i], j)]);
            let ys = Mat::from_fn(rows.len(), yc.ncols(), |i, j| yc[(rows[i], j)]);
            let sub = Objective {
                pairwise: Pairwise::new(xs.as_ref()),
                yc: ys.as_ref(),
                template: kernel.clone(),
                noise_floor,
            };
            let screened = run_all(&sub, &starts, &mut evals);
            let start = screened.map_or_else(|| theta0.clone(), |m| m.x);
            // Near the optimum already: a first step of 0.1 in log space (10%), not 1.
            let refine = LbfgsOptions { initial_step: 0.1 * opts.lbfgs.initial_step, ..opts.lbfgs };
            let m = minimize(|t, g| obj.eval(t, g), &start, &refine);
            if let Ok(m) = &m {
                evals += m.evals;
                full_data_evals = m.evals;
            }
            m.ok()
        } else {
            let b = run_all(&obj, &starts, &mut evals);
            full_data_evals = evals;
            b
        };
        let best = best.ok_or_else(|| {
            LearnError::Optimisation("no start of the hyper-parameter fit had a finite marginal likelihood".into())
        })?;
        let np = kernel.n_params();
        let mut fitted = kernel;
        fitted.set_params(&best.x[..np])?;
        let gp = GpRegression::new(fitted, noise_floor + best.x[np].exp(), x, y)?;
        let report = GpFitReport {
            nlml: gp.nlml,
            evals,
            full_data_evals,
            start_values,
            screened_rows: screen.then_some(opts.screen_points),
        };
        Ok((gp, report))
    }

    /// The kernel.
    pub fn kernel(&self) -> &Kernel {
        &self.spec.kernel
    }

    /// Observation-noise variance `s_n^2`.
    pub fn noise_variance(&self) -> f64 {
        self.spec.log_noise_variance.exp()
    }

    /// Jitter that the factorisation needed (0 normally).
    pub fn jitter(&self) -> f64 {
        self.jitter
    }

    /// Negative log marginal likelihood of the training outputs.
    pub fn negative_log_marginal_likelihood(&self) -> f64 {
        self.nlml
    }

    /// Training inputs.
    pub fn inputs(&self) -> MatRef<'_, f64> {
        self.spec.x.as_ref()
    }

    /// `alpha = K^-1 (Y - mean)` (N x m), e.g. to save as `.npy`.
    pub fn alpha(&self) -> MatRef<'_, f64> {
        self.alpha.as_ref()
    }

    /// Predictive mean and variances at the rows of `xs` (M x d), eq. 5.16-5.17.
    pub fn predict(&self, xs: MatRef<'_, f64>) -> Result<Prediction> {
        if xs.ncols() != self.spec.x.ncols() {
            return Err(LearnError::Dimension(format!(
                "test inputs of {} dimensions: trained on {}",
                xs.ncols(),
                self.spec.x.ncols()
            )));
        }
        check_finite(xs, "GP test inputs")?;
        let kernel = &self.spec.kernel;
        let ks = kernel.cross(xs, self.spec.x.as_ref())?;
        let mut mean = &ks * &self.alpha;
        for i in 0..mean.nrows() {
            for c in 0..mean.ncols() {
                mean[(i, c)] += self.y_mean[c];
            }
        }
        // v = L^-1 k*^T: variance k** - |v|^2.
        let mut v = ks.transpose().to_owned();
        self.l.as_ref().solve_lower_triangular_in_place(v.as_mut());
        // A white term inside the kernel is observation noise too.
        let noise = self.noise_variance() + self.jitter + kernel.white_variance();
        let latent_variance: Vec<f64> = (0..xs.nrows())
            .map(|i| {
                let row: Vec<f64> = (0..xs.ncols()).map(|j| xs[(i, j)]).collect();
                let vv: f64 = (0..v.nrows()).map(|r| v[(r, i)] * v[(r, i)]).sum();
                (kernel.self_covariance(&row) - vv).max(0.0)
            })
            .collect();
        let observation_variance = latent_variance.iter().map(|v| v + noise).collect();
        Ok(Prediction { mean, latent_variance, observation_variance })
    }

    /// Negative log marginal likelihood and its gradient (kernel log-parameters, then log noise
    /// variance) at other hyper-parameters, on this model's training set (for checks and
    /// custom optimisers).
    pub fn nlml_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        let np = self.spec.kernel.n_params();
        if theta.len() != np + 1 {
            return Err(LearnError::Dimension(format!("{} hyper-parameters: expected {}", theta.len(), np + 1)));
        }
        let yc = centred(self.spec.y.as_ref(), &self.y_mean);
        let obj = Objective {
            pairwise: Pairwise::new(self.spec.x.as_ref()),
            yc: yc.as_ref(),
            template: self.spec.kernel.clone(),
            noise_floor: 0.0,
        };
        let mut g = vec![0.0; np + 1];
        let f = obj.eval(theta, &mut g);
        if !f.is_finite() {
            return Err(LearnError::NotPositiveDefinite(format!("covariance at hyper-parameters {theta:?}")));
        }
        Ok((f, g))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    fn target(x: f64, z: f64) -> f64 {
        (2.0 * x).sin() + 0.5 * z * z
    }

    /// n noisy samples of `target` on [-2, 2]^2 (noise sd 0.1).
    fn samples(n: usize, seed: u64, noise_sd: f64) -> (Mat<f64>, Mat<f64>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let x = Mat::from_fn(n, 2, |_, _| rng.random_range(-2.0..2.0));
        let y = Mat::from_fn(n, 2, |i, c| {
            let f = target(x[(i, 0)], x[(i, 1)]);
            (if c == 0 { f } else { -2.0 * f + 1.0 }) + noise_sd * crate::hybrid_monte_carlo::standard_normal(&mut rng)
        });
        (x, y)
    }

    #[test]
    fn nlml_gradient_matches_finite_differences_for_every_kernel() {
        let (x, y) = samples(25, 1, 0.1);
        for kernel in [
            Kernel::squared_exponential(1.0, 0.8),
            Kernel::neural_network(1.5, 1.2),
            Kernel::Sum(vec![Kernel::squared_exponential(1.0, 0.8), Kernel::linear(0.3)]),
            Kernel::rbf_linear_white([1.0, 2.0, 0.5, 30.0]),
        ] {
            let gp = GpRegression::new(kernel.clone(), 0.05, x.clone(), y.clone()).unwrap();
            let mut theta = kernel.params();
            theta.push(0.05f64.ln());
            let (f, g) = gp.nlml_and_gradient(&theta).unwrap();
            assert!((f - gp.negative_log_marginal_likelihood()).abs() < 1e-8 * f.abs());
            for q in 0..theta.len() {
                let h = 1e-5;
                let (mut tp, mut tm) = (theta.clone(), theta.clone());
                tp[q] += h;
                tm[q] -= h;
                let fd = (gp.nlml_and_gradient(&tp).unwrap().0 - gp.nlml_and_gradient(&tm).unwrap().0) / (2.0 * h);
                assert!((fd - g[q]).abs() < 1e-5 * (1.0 + fd.abs()), "{kernel:?} param {q}: fd {fd} analytic {}", g[q]);
            }
        }
    }

    #[test]
    fn recovers_a_known_function_with_calibrated_variance() {
        let noise_sd = 0.1;
        let (x, y) = samples(200, 2, noise_sd);
        let (gp, rep) =
            GpRegression::fit(Kernel::squared_exponential(1.0, 1.0), 0.1, x, y, &GpFitOptions::default()).unwrap();
        assert!(rep.nlml.is_finite());
        let (xt, yt) = samples(400, 3, noise_sd);
        let p = gp.predict(xt.as_ref()).unwrap();
        let mut z2 = 0.0;
        let mut inside = 0usize;
        let mut rmse = 0.0;
        for i in 0..xt.nrows() {
            let f = target(xt[(i, 0)], xt[(i, 1)]);
            rmse += (p.mean[(i, 0)] - f).powi(2);
            for c in 0..2 {
                let e = yt[(i, c)] - p.mean[(i, c)];
                // Output 1 is -2 f + 1: its noise is the same, its function variance differs;
                // one shared kernel calibrates output 0.
                if c == 0 {
                    z2 += e * e / p.observation_variance[i];
                    inside += usize::from(e.abs() <= 1.96 * p.observation_variance[i].sqrt());
                }
            }
        }
        let rmse = (rmse / xt.nrows() as f64).sqrt();
        let z2 = z2 / xt.nrows() as f64;
        let cover = inside as f64 / xt.nrows() as f64;
        assert!(rmse < 0.05, "latent RMSE {rmse}");
        assert!((0.7..1.4).contains(&z2), "mean squared z-score {z2}");
        assert!((0.90..=0.99).contains(&cover), "95% interval coverage {cover}");
    }

    #[test]
    fn fitting_recovers_length_scale_and_noise_within_20_percent() {
        // Data drawn from a GP prior with l = 0.6, s^2 = 1, noise 0.05: sample f ~ N(0, K).
        let (l_true, noise_true): (f64, f64) = (0.6, 0.05);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let n = 400;
        let x = Mat::from_fn(n, 1, |_, _| rng.random_range(-5.0..5.0));
        let k = Kernel::squared_exponential(1.0, l_true);
        let km = k.matrix(&Pairwise::new(x.as_ref()));
        let f = cholesky_jitter(km.as_ref(), "prior").unwrap();
        let z = Mat::from_fn(n, 3, |_, _| crate::hybrid_monte_carlo::standard_normal(&mut rng));
        let mut y = f.llt.L() * z;
        for v in y.col_iter_mut().flat_map(|c| c.iter_mut()) {
            *v += noise_true.sqrt() * crate::hybrid_monte_carlo::standard_normal(&mut rng);
        }
        let (k0, n0) = squared_exponential_guess(x.as_ref(), y.as_ref()).unwrap();
        let Kernel::SquaredExponential { log_length_scale: l0, .. } = k0 else { unreachable!() };
        assert!(l0.exp() > 2.0 && n0 > 0.0, "the guess is far from the truth: a real test of the fit");
        let (gp, rep) = GpRegression::fit(k0, n0, x, y, &GpFitOptions::default()).unwrap();
        let Kernel::SquaredExponential { log_length_scale, .. } = gp.kernel() else { unreachable!() };
        let l = log_length_scale.exp();
        let nv = gp.noise_variance();
        assert!((l / l_true - 1.0).abs() < 0.2, "length scale {l} vs {l_true}");
        assert!((nv / noise_true - 1.0).abs() < 0.2, "noise {nv} vs {noise_true}");
        eprintln!(
            "GP fit from the median-distance guess (l = {:.2}): length scale {l:.3} (true {l_true}), noise {nv:.4} (true {noise_true}), {} evaluations over {} starts",
            l0.exp(),
            rep.evals,
            rep.start_values.len()
        );
        // Screening the starts on 200 rows ends at the same optimum as running them all on 400.
        let opts = GpFitOptions { screen_points: 200, ..Default::default() };
        let (k0, n0) = squared_exponential_guess(gp.inputs(), gp.spec.y.as_ref()).unwrap();
        let (screened, srep) = GpRegression::fit(k0, n0, gp.spec.x.clone(), gp.spec.y.clone(), &opts).unwrap();
        assert_eq!(srep.screened_rows, Some(200));
        assert!((screened.negative_log_marginal_likelihood() - gp.negative_log_marginal_likelihood()).abs() < 1e-3);
        assert!(
            srep.full_data_evals < rep.full_data_evals,
            "screened {} vs unscreened {} full-data evaluations",
            srep.full_data_evals,
            rep.full_data_evals
        );
        // Round trip through serde gives the same predictions.
        let s = serde_json::to_string(&gp).unwrap();
        let back: GpRegression = serde_json::from_str(&s).unwrap();
        let xt = Mat::from_fn(3, 1, |i, _| i as f64 - 1.0);
        let (a, b) = (gp.predict(xt.as_ref()).unwrap(), back.predict(xt.as_ref()).unwrap());
        assert!((a.mean[(1, 2)] - b.mean[(1, 2)]).abs() < 1e-9);
    }

    #[test]
    fn same_seed_same_fit_on_one_or_two_threads() {
        let (x, y) = samples(120, 4, 0.1);
        let fit = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let opts = GpFitOptions { restarts: 1, seed: 5, ..Default::default() };
                let (gp, _) =
                    GpRegression::fit(Kernel::neural_network(1.0, 1.0), 0.1, x.clone(), y.clone(), &opts).unwrap();
                gp.kernel().params()
            })
        };
        assert_eq!(fit(1), fit(2));
    }

    #[test]
    fn bad_input_is_an_error() {
        let x = Mat::<f64>::zeros(3, 2);
        assert!(GpRegression::new(Kernel::linear(1.0), 0.1, x.clone(), Mat::zeros(2, 1)).is_err());
        let mut y = Mat::<f64>::zeros(3, 1);
        y[(1, 0)] = f64::NAN;
        assert!(GpRegression::new(Kernel::linear(1.0), 0.1, x.clone(), y).is_err());
        let gp = GpRegression::new(Kernel::squared_exponential(1.0, 1.0), 0.1, x, Mat::zeros(3, 1)).unwrap();
        assert!(gp.predict(Mat::<f64>::zeros(1, 3).as_ref()).is_err());
        // A linear kernel on identical inputs and no noise is singular: jitter rescues it.
        let gp = GpRegression::new(Kernel::linear(1.0), 0.0, Mat::from_fn(3, 1, |_, _| 1.0), Mat::zeros(3, 1));
        assert!(gp.unwrap().jitter() > 0.0);
    }
}
