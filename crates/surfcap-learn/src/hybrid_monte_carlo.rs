//! Hybrid (Hamiltonian) Monte Carlo (Duane et al. 1987; MacKay 2003, ch. 30), the sampler
//! thesis 6.6.2 uses to draw whole latent trajectories from the GPDM (after Wang et al. 2008).
//!
//! Unit mass matrix, leapfrog integration, Metropolis acceptance on the Hamiltonian. The thesis
//! gives no tuning; the choices here:
//! - step size: the usual start heuristic (double or halve until one leapfrog step's acceptance
//!   crosses 1/2), then dual averaging towards a target acceptance (Hoffman and Gelman 2014,
//!   section 3.2; default 0.75) during warm-up, frozen afterwards;
//! - path length: after the first half of warm-up, the trajectory duration is set to
//!   `pi/2` times the largest marginal standard deviation seen so far (a quarter period of the
//!   widest direction of a Gaussian: the point of the orbit least correlated with its start),
//!   i.e. `L = ceil(duration / step)` leapfrog steps, capped; the step size is then re-tuned for
//!   that L in the second half of warm-up;
//! - during sampling the step is jittered uniformly by +-10% per iteration (avoids periodic
//!   orbits that a fixed `L * step` can fall into);
//! - a trajectory whose energy is not finite is rejected and counted as a divergence.
//!
//! Randomness comes from one `ChaCha8Rng` seeded by the caller: same seed, same chain.

use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};

/// A standard normal draw (Box-Muller on two uniforms; deterministic for a seeded RNG).
pub fn standard_normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// An unnormalised log density with its gradient.
pub trait LogDensity {
    /// Number of variables.
    fn dim(&self) -> usize;
    /// `log p(x)` (up to a constant), writing `d log p / dx` into `grad`. A non-finite value
    /// marks a point outside the support.
    fn log_density(&self, x: &[f64], grad: &mut [f64]) -> f64;
}

/// Options of [`sample`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct HmcOptions {
    /// Warm-up iterations (tuning; not returned).
    pub warmup: usize,
    /// Samples returned.
    pub samples: usize,
    /// Iterations between returned samples (1: every iteration).
    pub thin: usize,
    /// Acceptance rate the step size is tuned for.
    pub target_accept: f64,
    /// Upper bound on leapfrog steps per iteration.
    pub max_leapfrog: usize,
    /// Fixed leapfrog count instead of the tuned path length.
    pub leapfrog_steps: Option<usize>,
    pub seed: u64,
}

impl Default for HmcOptions {
    fn default() -> Self {
        HmcOptions {
            warmup: 500,
            samples: 1000,
            thin: 1,
            target_accept: 0.75,
            max_leapfrog: 100,
            leapfrog_steps: None,
            seed: 0,
        }
    }
}

/// A chain and its statistics.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HmcChain {
    /// Returned samples, each of `dim` values.
    pub samples: Vec<Vec<f64>>,
    /// Fraction of accepted proposals after warm-up.
    pub acceptance_rate: f64,
    /// Mean Metropolis acceptance probability after warm-up.
    pub mean_accept_prob: f64,
    /// Tuned leapfrog step size.
    pub step_size: f64,
    /// Leapfrog steps per iteration.
    pub leapfrog_steps: usize,
    /// Trajectories rejected for a non-finite energy (after warm-up).
    pub divergences: usize,
    /// Gradient evaluations in total (warm-up included).
    pub gradient_evals: usize,
}

struct State {
    x: Vec<f64>,
    logp: f64,
    grad: Vec<f64>,
}

/// One HMC transition; returns the Metropolis acceptance probability and whether it diverged.
fn transition(
    target: &impl LogDensity,
    s: &mut State,
    step: f64,
    steps: usize,
    rng: &mut impl Rng,
    evals: &mut usize,
) -> (f64, bool) {
    let n = s.x.len();
    // The target may run faer's AVX-512 code; the scalar code below calls libm.
    surfcap_linalg::clear_upper_vector_state();
    let p0: Vec<f64> = (0..n).map(|_| standard_normal(rng)).collect();
    let h0 = -s.logp + 0.5 * p0.iter().map(|v| v * v).sum::<f64>();
    let mut x = s.x.clone();
    let mut g = s.grad.clone();
    let mut p = p0;
    let mut logp = s.logp;
    for (pi, gi) in p.iter_mut().zip(&g) {
        *pi += 0.5 * step * gi;
    }
    for l in 0..steps {
        for (xi, pi) in x.iter_mut().zip(&p) {
            *xi += step * pi;
        }
        logp = target.log_density(&x, &mut g);
        *evals += 1;
        surfcap_linalg::clear_upper_vector_state();
        if !logp.is_finite() || g.iter().any(|v| !v.is_finite()) {
            return (0.0, true);
        }
        let w = if l + 1 == steps { 0.5 } else { 1.0 };
        for (pi, gi) in p.iter_mut().zip(&g) {
            *pi += w * step * gi;
        }
    }
    let h1 = -logp + 0.5 * p.iter().map(|v| v * v).sum::<f64>();
    if !h1.is_finite() {
        return (0.0, true);
    }
    let accept = (h0 - h1).exp().min(1.0);
    if rng.random::<f64>() < accept {
        s.x = x;
        s.grad = g;
        s.logp = logp;
    }
    (accept, false)
}

/// Dual averaging of log step size (Hoffman and Gelman 2014, eq. 6).
struct DualAveraging {
    mu: f64,
    h_bar: f64,
    log_step_bar: f64,
    t: f64,
    target: f64,
}

impl DualAveraging {
    fn new(step: f64, target: f64) -> Self {
        DualAveraging { mu: (10.0 * step).ln(), h_bar: 0.0, log_step_bar: step.ln(), t: 0.0, target }
    }

    /// Records an acceptance probability; returns the next step size.
    fn update(&mut self, accept: f64) -> f64 {
        const GAMMA: f64 = 0.05;
        const T0: f64 = 10.0;
        const KAPPA: f64 = 0.75;
        self.t += 1.0;
        let eta = 1.0 / (self.t + T0);
        self.h_bar = (1.0 - eta) * self.h_bar + eta * (self.target - accept);
        let log_step = self.mu - self.t.sqrt() / GAMMA * self.h_bar;
        let w = self.t.powf(-KAPPA);
        self.log_step_bar = w * log_step + (1.0 - w) * self.log_step_bar;
        log_step.exp()
    }

    fn final_step(&self) -> f64 {
        self.log_step_bar.exp()
    }
}

/// Runs a chain from `x0`.
pub fn sample(target: &impl LogDensity, x0: &[f64], opts: &HmcOptions) -> Result<HmcChain> {
    let n = target.dim();
    if x0.len() != n {
        return Err(LearnError::Dimension(format!("start of {} values for a density of {n} variables", x0.len())));
    }
    if opts.samples == 0 || opts.thin == 0 || opts.max_leapfrog == 0 {
        return Err(LearnError::Invalid("HMC needs samples, thin and max_leapfrog >= 1".into()));
    }
    if !(opts.target_accept > 0.0 && opts.target_accept < 1.0) {
        return Err(LearnError::Invalid(format!("target acceptance {}: expected in (0, 1)", opts.target_accept)));
    }
    crate::matrix::check_finite_slice(x0, "HMC start")?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let mut grad = vec![0.0; n];
    let logp = target.log_density(x0, &mut grad);
    if !logp.is_finite() || grad.iter().any(|v| !v.is_finite()) {
        return Err(LearnError::Invalid(format!("HMC start outside the support (log density {logp})")));
    }
    let mut s = State { x: x0.to_vec(), logp, grad };
    let mut evals = 1;
    // Initial step: double or halve until a one-step acceptance crosses 1/2.
    let mut step = 0.1;
    {
        let probe = |step: f64, rng: &mut rand_chacha::ChaCha8Rng, evals: &mut usize| {
            let mut t = State { x: s.x.clone(), logp: s.logp, grad: s.grad.clone() };
            transition(target, &mut t, step, 1, rng, evals).0
        };
        let up = probe(step, &mut rng, &mut evals) > 0.5;
        for _ in 0..60 {
            let a = probe(step, &mut rng, &mut evals);
            if up && a <= 0.5 {
                break;
            }
            if !up && a > 0.5 {
                break;
            }
            step = if up { step * 2.0 } else { step * 0.5 };
        }
    }
    let mut steps = opts.leapfrog_steps.unwrap_or(10).clamp(1, opts.max_leapfrog);
    let half = opts.warmup / 2;
    let mut da = DualAveraging::new(step, opts.target_accept);
    // Running moments for the path length (Welford).
    let mut mean = vec![0.0; n];
    let mut m2 = vec![0.0; n];
    let mut count = 0.0;
    for it in 0..opts.warmup {
        let (a, _) = transition(target, &mut s, step, steps, &mut rng, &mut evals);
        step = da.update(a);
        if it >= half / 2 {
            count += 1.0;
            for k in 0..n {
                let d = s.x[k] - mean[k];
                mean[k] += d / count;
                m2[k] += d * (s.x[k] - mean[k]);
            }
        }
        if it + 1 == half && opts.leapfrog_steps.is_none() && count > 1.0 {
            let sd_max = m2.iter().map(|v| (v / (count - 1.0)).sqrt()).fold(0.0, f64::max);
            let tuned = da.final_step();
            if sd_max > 0.0 {
                steps = ((std::f64::consts::FRAC_PI_2 * sd_max / tuned).ceil() as usize).clamp(1, opts.max_leapfrog);
            }
            da = DualAveraging::new(tuned, opts.target_accept);
            step = tuned;
        }
    }
    if opts.warmup > 0 {
        step = da.final_step();
    }
    let mut samples = Vec::with_capacity(opts.samples);
    let (mut accepted, mut total, mut prob_sum, mut divergences) = (0usize, 0usize, 0.0, 0usize);
    while samples.len() < opts.samples {
        for _ in 0..opts.thin {
            let before = s.logp;
            let jittered = step * rng.random_range(0.9..1.1);
            let x_before = s.x.clone();
            let (a, div) = transition(target, &mut s, jittered, steps, &mut rng, &mut evals);
            total += 1;
            prob_sum += a;
            divergences += usize::from(div);
            accepted += usize::from(s.x != x_before || (s.logp != before));
        }
        samples.push(s.x.clone());
    }
    Ok(HmcChain {
        samples,
        acceptance_rate: accepted as f64 / total as f64,
        mean_accept_prob: prob_sum / total as f64,
        step_size: step,
        leapfrog_steps: steps,
        divergences,
        gradient_evals: evals,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// N(mu, S) through its precision matrix.
    struct Gaussian {
        mu: Vec<f64>,
        prec: Vec<Vec<f64>>,
    }

    impl LogDensity for Gaussian {
        fn dim(&self) -> usize {
            self.mu.len()
        }
        fn log_density(&self, x: &[f64], grad: &mut [f64]) -> f64 {
            let n = self.mu.len();
            let d: Vec<f64> = (0..n).map(|i| x[i] - self.mu[i]).collect();
            for (i, g) in grad.iter_mut().enumerate() {
                *g = -(0..n).map(|j| self.prec[i][j] * d[j]).sum::<f64>();
            }
            // log p = -d^T P d / 2 = d^T grad / 2.
            0.5 * d.iter().zip(grad.iter()).map(|(a, b)| a * b).sum::<f64>()
        }
    }

    #[test]
    fn correlated_gaussian_mean_and_covariance_within_5_percent() {
        // Covariance with correlations 0.9 and -0.5 and scales 1, 2, 0.5.
        let sd = [1.0, 2.0, 0.5];
        let r = [[1.0, 0.9, -0.5], [0.9, 1.0, -0.3], [-0.5, -0.3, 1.0]];
        let cov: Vec<Vec<f64>> = (0..3).map(|i| (0..3).map(|j| r[i][j] * sd[i] * sd[j]).collect()).collect();
        let c = faer::Mat::from_fn(3, 3, |i, j| cov[i][j]);
        let inv = crate::matrix::cholesky_jitter(c.as_ref(), "cov").unwrap().inverse();
        let g = Gaussian {
            mu: vec![1.0, -2.0, 3.0],
            prec: (0..3).map(|i| (0..3).map(|j| inv[(i, j)]).collect()).collect(),
        };
        let opts = HmcOptions { warmup: 1000, samples: 20000, seed: 3, ..Default::default() };
        let chain = sample(&g, &[0.0, 0.0, 0.0], &opts).unwrap();
        let n = chain.samples.len() as f64;
        let m: Vec<f64> = (0..3).map(|k| chain.samples.iter().map(|x| x[k]).sum::<f64>() / n).collect();
        let scale = 4.0; // largest variance
        for k in 0..3 {
            assert!((m[k] - g.mu[k]).abs() < 0.05 * sd[k], "mean {k}: {} vs {}", m[k], g.mu[k]);
            for l in 0..3 {
                let s = chain.samples.iter().map(|x| (x[k] - m[k]) * (x[l] - m[l])).sum::<f64>() / (n - 1.0);
                assert!((s - cov[k][l]).abs() < 0.05 * scale, "cov[{k}][{l}] {s} vs {}", cov[k][l]);
                if k == l {
                    assert!((s / cov[k][k] - 1.0).abs() < 0.05, "var {k}: {s} vs {}", cov[k][k]);
                }
            }
        }
        assert!((0.5..0.95).contains(&chain.acceptance_rate), "{chain:?}");
        eprintln!(
            "HMC correlated Gaussian: acceptance {:.3}, step {:.3}, {} leapfrog steps, mean {m:?}",
            chain.acceptance_rate, chain.step_size, chain.leapfrog_steps
        );
        // Same seed, same chain.
        let again = sample(&g, &[0.0, 0.0, 0.0], &HmcOptions { samples: 50, ..opts }).unwrap();
        assert_eq!(again.samples[..50], chain.samples[..50]);
        assert!(sample(&g, &[0.0], &opts).is_err());
    }
}
