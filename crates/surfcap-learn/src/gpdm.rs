//! Gaussian Process Dynamical Model (thesis 6.5-6.6, eq. 6.1-6.13; Wang, Fleet and Hertzmann
//! 2006, 2008).
//!
//! Frames `y_i` (D values, e.g. body-part vertex coordinates) get latent positions `x_i` (d
//! values, default 3). Two GPs share them: the reconstruction GP `X -> Y` with the RBF + white
//! kernel of eq. 6.4 (likelihood eq. 6.3), and the dynamics GP `x_{i-1} -> x_i` with the
//! RBF + linear + white kernel of eq. 6.6 (density eq. 6.5). The fit is the MAP of eq. 6.7 over
//! the latent positions and both hyper-parameter vectors, minimising
//!
//! ```text
//! D/2 ln|K_Y| + 1/2 tr(K_Y^-1 Y Y^T) + d/2 ln|K_X| + 1/2 tr(K_X^-1 X' X'^T)
//!     + 1/2 sum_seq |x_1|^2 + sum_k ln alpha_k + sum_k ln beta_k
//! ```
//!
//! with analytic gradients (kernel derivatives from [`crate::kernels`]) and L-BFGS.
//!
//! Choices where the thesis is silent or loose (each said where it is made):
//! - **Centring**: Y is centred by its mean frame (the reconstruction GP has a zero mean).
//! - **Units**: the thesis initialises alpha, beta to 1 and the noise variances to 0.1. Here the
//!   output variance alpha_1 starts at the mean per-coordinate variance of Y and the noise
//!   1/alpha_3 at 0.1 times it, so the start does not depend on the data's units; the latent PCA
//!   coordinates are scaled so the first has unit standard deviation (then alpha_2 = beta_2 = 1
//!   span the data). beta_1 = beta_3 = 1 as in the thesis, and the dynamics noise 1/beta_4 starts
//!   at 1e-3, not 0.1: consecutive latent points of a sequence of hundreds of frames are a few
//!   hundredths apart, and a noise of 0.1 would make the dynamics term flat.
//! - **Noise floors**: each white-noise variance is `floor + exp(theta)` with theta optimised
//!   (floor 1e-6 times the data variance for K_Y, 1e-8 for K_X): on noise-free data (synthetic
//!   meshes) the likelihood otherwise drives the noise to 0 and K_Y singular.
//! - **Balance**: eq. 6.7 weighs the D-dimensional reconstruction term against the d-dimensional
//!   dynamics term as they are; [`GpdmOptions::dynamics_weight`] (default 1, the thesis) allows
//!   Wang et al. 2008's balanced GPDM (D / d).
//! - **Priors** (6.5.1): `P(alpha) = prod alpha_k^-1` in the thesis's parametrisation (alpha_2 a
//!   precision, alpha_3 an inverse variance), i.e. `sum ln alpha_k` is added to the negative log
//!   posterior (PAPER-NOTES.md); optimisation is over the logarithms. `x_1` of each sequence has
//!   a unit isotropic Gaussian prior.
//! - **Several sequences** (6.5.2): frames are concatenated, `X'` holds all but the first latent
//!   point of each sequence and `K_X` is built on all but the last one of each sequence.
//! - **Speed**: `Y Y^T` (N x N) is computed once, so an evaluation costs O(N^3), independent of
//!   D (400 frames of 3,186 coordinates: about 25 ms per evaluation on 2 busy cores, 400
//!   L-BFGS iterations in about 11 s; `surfcap-bench learn`).
//! - **Trajectory density for HMC** (6.6.2): `P(X~ | x_1, X, Y, alpha, beta)` is taken as the
//!   product of the one-step predictive densities of eq. 6.8-6.10 (each new point given the
//!   previous one, the dynamics GP conditioned on the training pairs). The exact joint would also
//!   condition each step on the new trajectory's earlier pairs, an (N + n)-sized factorisation per
//!   leapfrog step; the one-step product is what eq. 6.8 writes and needs no factorisation: one
//!   product with the precomputed `K_X^-1` per evaluation, O(n N^2).
//! - Predictive variances (eq. 6.10, 6.13) include the white term: they are those of a noisy
//!   new point, which is what eq. 6.8 and 6.11 sample.

use faer::{Mat, MatRef};
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};
use crate::hybrid_monte_carlo::{HmcChain, HmcOptions, LogDensity, standard_normal};
use crate::kernels::{Kernel, Pairwise, PreparedKernel, row_norms};
use crate::lbfgs::{LbfgsOptions, minimize};
use crate::matrix::{centred, check_finite, check_finite_slice, cholesky_jitter, column_means, matmul_seq, serde_mat};
use crate::pca::{Pca, PcaMethod};

/// Options of [`Gpdm::fit`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct GpdmOptions {
    /// Latent dimension d (thesis: 3).
    pub latent_dim: usize,
    pub lbfgs: LbfgsOptions,
    /// Weight of the dynamics term `-ln P(X | beta)` in the objective. 1 is the thesis's eq. 6.7;
    /// Wang et al. 2008's "balanced GPDM" uses D / d, which stops the D-dimensional
    /// reconstruction term from drowning the dynamics (smoother latent trajectories).
    pub dynamics_weight: f64,
}

impl Default for GpdmOptions {
    fn default() -> Self {
        GpdmOptions {
            latent_dim: 3,
            lbfgs: LbfgsOptions {
                memory: 10,
                max_iters: 400,
                max_evals: 500,
                grad_tol: 1e-4,
                f_tol: 1e-10,
                initial_step: 1.0,
            },
            dynamics_weight: 1.0,
        }
    }
}

/// What a fit did.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GpdmFitReport {
    /// Negative log posterior at the PCA start and at the optimum.
    pub initial_objective: f64,
    pub objective: f64,
    pub iters: usize,
    pub evals: usize,
    pub converged: bool,
    /// The objective at the start and after every L-BFGS iteration (a learning curve).
    #[serde(default)]
    pub history: Vec<f64>,
}

/// The serialised form of a [`Gpdm`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GpdmSpec {
    /// Latent positions (N x d), sequences concatenated.
    #[serde(with = "serde_mat")]
    pub latent: Mat<f64>,
    /// Frames per sequence.
    pub sequence_lengths: Vec<usize>,
    /// Training frames (N x D), not centred.
    #[serde(with = "serde_mat")]
    pub y: Mat<f64>,
    /// Eq. 6.4 kernel (SE + white).
    pub kernel_y: Kernel,
    /// Eq. 6.6 kernel (SE + linear + white).
    pub kernel_x: Kernel,
}

/// A fitted GPDM with the factorisations its predictions need.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "GpdmSpec", into = "GpdmSpec")]
pub struct Gpdm {
    spec: GpdmSpec,
    y_mean: Vec<f64>,
    /// `K_Y^-1 (Y - mean)` (N x D).
    a_y: Mat<f64>,
    /// `K_Y^-1` (N x N).
    ky_inv: Mat<f64>,
    /// Dynamics inputs (M x d), their norms, `K_X^-1 X'` (M x d) and `K_X^-1`.
    x_in: Mat<f64>,
    x_in_norms: Vec<f64>,
    a_x: Mat<f64>,
    kx_inv: Mat<f64>,
}

impl TryFrom<GpdmSpec> for Gpdm {
    type Error = LearnError;
    fn try_from(s: GpdmSpec) -> Result<Self> {
        Gpdm::from_spec(s)
    }
}

impl From<Gpdm> for GpdmSpec {
    fn from(g: Gpdm) -> GpdmSpec {
        g.spec
    }
}

/// Row indices of the dynamics pairs and of the first frames (thesis 6.5.2).
fn pair_rows(lengths: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let (mut rows_in, mut rows_out, mut firsts) = (Vec::new(), Vec::new(), Vec::new());
    let mut start = 0;
    for &n in lengths {
        firsts.push(start);
        for i in start..start + n - 1 {
            rows_in.push(i);
            rows_out.push(i + 1);
        }
        start += n;
    }
    (rows_in, rows_out, firsts)
}

fn select_rows(x: MatRef<'_, f64>, rows: &[usize]) -> Mat<f64> {
    Mat::from_fn(rows.len(), x.ncols(), |i, j| x[(rows[i], j)])
}

/// The MAP objective of eq. 6.7 on one training set.
pub struct GpdmObjective {
    yyt: Mat<f64>,
    n_dims: usize,
    d: usize,
    lengths: Vec<usize>,
    kernel_y: Kernel,
    kernel_x: Kernel,
    /// Lower bounds of the two white-noise variances: the optimiser sees
    /// `variance = floor + exp(theta)`, so noise-free data cannot drive K_Y or K_X singular.
    floor_y: f64,
    floor_x: f64,
    dynamics_weight: f64,
}

/// Index of the white-noise parameter in the eq. 6.4 and eq. 6.6 kernels.
const WHITE_Y: usize = 2;
const WHITE_X: usize = 3;

impl GpdmObjective {
    /// Number of variables: N d latent coordinates, then the kernel log-parameters of eq. 6.4
    /// and eq. 6.6.
    pub fn n_vars(&self) -> usize {
        self.yyt.nrows() * self.d + self.kernel_y.n_params() + self.kernel_x.n_params()
    }

    fn unpack(&self, v: &[f64]) -> Result<(Mat<f64>, Kernel, Kernel)> {
        let (n, d) = (self.yyt.nrows(), self.d);
        let x = Mat::from_fn(n, d, |i, j| v[i * d + j]);
        let (mut ky, mut kx) = (self.kernel_y.clone(), self.kernel_x.clone());
        let ny = ky.n_params();
        let mut py = v[n * d..n * d + ny].to_vec();
        let mut px = v[n * d + ny..].to_vec();
        py[WHITE_Y] = (self.floor_y + py[WHITE_Y].exp()).ln();
        px[WHITE_X] = (self.floor_x + px[WHITE_X].exp()).ln();
        ky.set_params(&py)?;
        kx.set_params(&px)?;
        Ok((x, ky, kx))
    }

    fn pack(&self, x: MatRef<'_, f64>, ky: &Kernel, kx: &Kernel) -> Vec<f64> {
        let mut v: Vec<f64> = (0..x.nrows()).flat_map(|i| (0..x.ncols()).map(move |j| x[(i, j)])).collect();
        let (mut py, mut px) = (ky.params(), kx.params());
        py[WHITE_Y] = (py[WHITE_Y].exp() - self.floor_y).max(self.floor_y).ln();
        px[WHITE_X] = (px[WHITE_X].exp() - self.floor_x).max(self.floor_x).ln();
        v.extend(py);
        v.extend(px);
        v
    }

    /// Negative log posterior (up to a constant) and its gradient.
    pub fn eval(&self, v: &[f64], grad: &mut [f64]) -> Result<f64> {
        let (n, d) = (self.yyt.nrows(), self.d);
        let (x, ky, kx) = self.unpack(v)?;
        grad.iter_mut().for_each(|g| *g = 0.0);
        // Reconstruction term (eq. 6.3).
        let py = Pairwise::new(x.as_ref());
        let kym = ky.matrix(&py);
        let fy = cholesky_jitter(kym.as_ref(), "GPDM K_Y")?;
        let ky_inv = fy.inverse();
        let b = &ky_inv * &self.yyt;
        let dd = self.n_dims as f64;
        let tr: f64 = (0..n).map(|i| b[(i, i)]).sum();
        let mut f = 0.5 * dd * fy.log_det() + 0.5 * tr;
        let bkb = &b * &ky_inv;
        let wy = Mat::from_fn(n, n, |i, j| 0.5 * (dd * ky_inv[(i, j)] - bkb[(i, j)]));
        let gx_y = ky.input_gradient(x.as_ref(), &py, wy.as_ref());
        let gy = ky.param_gradients(&py, wy.as_ref());
        // Dynamics term (eq. 6.5).
        let (rows_in, rows_out, firsts) = pair_rows(&self.lengths);
        let x_in = select_rows(x.as_ref(), &rows_in);
        let x_out = select_rows(x.as_ref(), &rows_out);
        let px = Pairwise::new(x_in.as_ref());
        let kxm = kx.matrix(&px);
        let fx = cholesky_jitter(kxm.as_ref(), "GPDM K_X")?;
        let kx_inv = fx.inverse();
        let a = &kx_inv * &x_out;
        let fit: f64 = (0..a.nrows()).map(|i| (0..d).map(|j| a[(i, j)] * x_out[(i, j)]).sum::<f64>()).sum();
        let lambda = self.dynamics_weight;
        f += lambda * (0.5 * d as f64 * fx.log_det() + 0.5 * fit);
        let aat = &a * a.transpose();
        let m = rows_in.len();
        let wx = Mat::from_fn(m, m, |i, j| 0.5 * lambda * (d as f64 * kx_inv[(i, j)] - aat[(i, j)]));
        let gx_in = kx.input_gradient(x_in.as_ref(), &px, wx.as_ref());
        let gxp = kx.param_gradients(&px, wx.as_ref());
        // Latent gradient.
        for i in 0..n {
            for j in 0..d {
                grad[i * d + j] += gx_y[(i, j)];
            }
        }
        for (r, (&ri, &ro)) in rows_in.iter().zip(&rows_out).enumerate() {
            for j in 0..d {
                grad[ri * d + j] += gx_in[(r, j)];
                grad[ro * d + j] += lambda * a[(r, j)];
            }
        }
        for &s in &firsts {
            for j in 0..d {
                f += 0.5 * x[(s, j)].powi(2);
                grad[s * d + j] += x[(s, j)];
            }
        }
        // Hyper-parameters with the priors sum ln alpha + sum ln beta, then the chain rule of
        // the noise floors (d ln(floor + e^t) / dt = e^t / (floor + e^t)).
        let at = n * d;
        let (py_c, px_c) = (ky.thesis_log_coefficients(), kx.thesis_log_coefficients());
        let (pyv, pxv) = (ky.params(), kx.params());
        for (k, (&g, &c)) in gy.iter().zip(&py_c).enumerate() {
            grad[at + k] = g + c;
            f += c * pyv[k];
        }
        grad[at + WHITE_Y] *= v[at + WHITE_Y].exp() / pyv[WHITE_Y].exp();
        let at = at + gy.len();
        for (k, (&g, &c)) in gxp.iter().zip(&px_c).enumerate() {
            grad[at + k] = g + c;
            f += c * pxv[k];
        }
        grad[at + WHITE_X] *= v[at + WHITE_X].exp() / pxv[WHITE_X].exp();
        if !f.is_finite() {
            return Err(LearnError::NonFinite(format!("GPDM objective {f}")));
        }
        Ok(f)
    }
}

/// Checks and concatenates the sequences (each N_j x D, at least 3 frames).
fn concatenate(sequences: &[MatRef<'_, f64>]) -> Result<(Mat<f64>, Vec<usize>)> {
    let Some(first) = sequences.first() else {
        return Err(LearnError::Invalid("GPDM with no sequence".into()));
    };
    let dims = first.ncols();
    for (k, s) in sequences.iter().enumerate() {
        if s.ncols() != dims || dims == 0 {
            return Err(LearnError::Dimension(format!(
                "sequence {k} has {} values per frame, sequence 0 {dims}",
                s.ncols()
            )));
        }
        if s.nrows() < 3 {
            return Err(LearnError::Invalid(format!("sequence {k} has {} frames: expected at least 3", s.nrows())));
        }
        check_finite(*s, &format!("sequence {k}"))?;
    }
    let lengths: Vec<usize> = sequences.iter().map(|s| s.nrows()).collect();
    let n: usize = lengths.iter().sum();
    let mut y = Mat::zeros(n, dims);
    let mut at = 0;
    for s in sequences {
        for i in 0..s.nrows() {
            for j in 0..dims {
                y[(at + i, j)] = s[(i, j)];
            }
        }
        at += s.nrows();
    }
    Ok((y, lengths))
}

impl Gpdm {
    /// The objective of eq. 6.7 for these sequences (for gradient checks and custom fits).
    pub fn objective(sequences: &[MatRef<'_, f64>], opts: &GpdmOptions) -> Result<(GpdmObjective, Vec<f64>)> {
        let latent_dim = opts.latent_dim;
        if !(opts.dynamics_weight.is_finite() && opts.dynamics_weight >= 0.0) {
            return Err(LearnError::Invalid(format!("dynamics weight {}: expected >= 0", opts.dynamics_weight)));
        }
        let (y, lengths) = concatenate(sequences)?;
        let n = y.nrows();
        if latent_dim == 0 || latent_dim >= n {
            return Err(LearnError::Invalid(format!("latent dimension {latent_dim} for {n} frames")));
        }
        let mean = column_means(y.as_ref());
        let yc = centred(y.as_ref(), &mean);
        let var_y = (0..yc.ncols()).map(|j| (0..n).map(|i| yc[(i, j)].powi(2)).sum::<f64>()).sum::<f64>()
            / (n * yc.ncols()) as f64;
        if var_y <= 0.0 {
            return Err(LearnError::Invalid("all frames are identical".into()));
        }
        let yyt = &yc * yc.transpose();
        // PCA initialisation (6.5.1), scaled so the first coordinate has unit spread.
        let pca = Pca::fit(y.as_ref(), latent_dim, PcaMethod::Auto)?;
        let mut x0 = pca.project(y.as_ref())?;
        let s0 = pca.variances[0].sqrt().max(f64::MIN_POSITIVE);
        let mut x = Mat::zeros(n, latent_dim);
        for i in 0..n {
            for j in 0..x0.ncols() {
                x0[(i, j)] /= s0;
                x[(i, j)] = x0[(i, j)];
            }
        }
        let kernel_y = Kernel::rbf_white([var_y, 1.0, 10.0 / var_y]);
        let kernel_x = Kernel::rbf_linear_white([1.0, 1.0, 1.0, 1000.0]);
        let obj = GpdmObjective {
            yyt,
            n_dims: yc.ncols(),
            d: latent_dim,
            lengths,
            kernel_y,
            kernel_x,
            floor_y: 1e-6 * var_y,
            floor_x: 1e-8,
            dynamics_weight: opts.dynamics_weight,
        };
        let v0 = obj.pack(x.as_ref(), &obj.kernel_y, &obj.kernel_x);
        Ok((obj, v0))
    }

    /// Fits latent positions and hyper-parameters (MAP of eq. 6.7) to one or more sequences
    /// (each N_j frames x D values) sharing one latent space.
    pub fn fit(sequences: &[MatRef<'_, f64>], opts: &GpdmOptions) -> Result<(Gpdm, GpdmFitReport)> {
        let (obj, v0) = Gpdm::objective(sequences, opts)?;
        let mut g = vec![0.0; v0.len()];
        let initial_objective = obj.eval(&v0, &mut g)?;
        let m = minimize(|v, g| obj.eval(v, g).unwrap_or(f64::INFINITY), &v0, &opts.lbfgs)?;
        let (x, ky, kx) = obj.unpack(&m.x)?;
        let (y, lengths) = concatenate(sequences)?;
        let gpdm = Gpdm::from_spec(GpdmSpec { latent: x, sequence_lengths: lengths, y, kernel_y: ky, kernel_x: kx })?;
        let report = GpdmFitReport {
            initial_objective,
            objective: m.f,
            iters: m.iters,
            evals: m.evals,
            converged: m.converged,
            history: m.history,
        };
        Ok((gpdm, report))
    }

    /// Rebuilds the factorisations from a spec.
    pub fn from_spec(spec: GpdmSpec) -> Result<Gpdm> {
        let n: usize = spec.sequence_lengths.iter().sum();
        if spec.sequence_lengths.iter().any(|&l| l < 2)
            || n != spec.latent.nrows()
            || n != spec.y.nrows()
            || spec.latent.ncols() == 0
        {
            return Err(LearnError::Dimension(format!(
                "sequence lengths {:?} for {} latent points and {} frames",
                spec.sequence_lengths,
                spec.latent.nrows(),
                spec.y.nrows()
            )));
        }
        check_finite(spec.latent.as_ref(), "latent positions")?;
        check_finite(spec.y.as_ref(), "frames")?;
        let y_mean = column_means(spec.y.as_ref());
        let yc = centred(spec.y.as_ref(), &y_mean);
        let kym = spec.kernel_y.matrix(&Pairwise::new(spec.latent.as_ref()));
        let fy = cholesky_jitter(kym.as_ref(), "GPDM K_Y")?;
        let a_y = fy.solve(yc.as_ref());
        let ky_inv = fy.inverse();
        let (rows_in, rows_out, _) = pair_rows(&spec.sequence_lengths);
        let x_in = select_rows(spec.latent.as_ref(), &rows_in);
        let x_out = select_rows(spec.latent.as_ref(), &rows_out);
        let kxm = spec.kernel_x.matrix(&Pairwise::new(x_in.as_ref()));
        let fx = cholesky_jitter(kxm.as_ref(), "GPDM K_X")?;
        let a_x = fx.solve(x_out.as_ref());
        let kx_inv = fx.inverse();
        let x_in_norms = row_norms(x_in.as_ref());
        Ok(Gpdm { spec, y_mean, a_y, ky_inv, x_in, x_in_norms, a_x, kx_inv })
    }

    /// Number of training sequences.
    pub fn sequence_count(&self) -> usize {
        self.spec.sequence_lengths.len()
    }

    /// Values per frame (D).
    pub fn output_dim(&self) -> usize {
        self.spec.y.ncols()
    }

    /// The serialised form (latents, frames, kernels).
    pub fn spec(&self) -> &GpdmSpec {
        &self.spec
    }

    /// Latent dimension d.
    pub fn latent_dim(&self) -> usize {
        self.spec.latent.ncols()
    }

    /// Latent positions of all training frames (N x d), sequences concatenated.
    pub fn latent(&self) -> MatRef<'_, f64> {
        self.spec.latent.as_ref()
    }

    /// Latent positions of training sequence `k`.
    pub fn sequence_latent(&self, k: usize) -> Option<MatRef<'_, f64>> {
        let len = *self.spec.sequence_lengths.get(k)?;
        let start: usize = self.spec.sequence_lengths[..k].iter().sum();
        Some(self.spec.latent.as_ref().subrows(start, len))
    }

    /// The kernels of eq. 6.4 and 6.6 with their fitted parameters.
    pub fn kernels(&self) -> (&Kernel, &Kernel) {
        (&self.spec.kernel_y, &self.spec.kernel_x)
    }

    /// The fitted hyper-parameters in the thesis's parametrisation: `alpha` of eq. 6.4
    /// (RBF variance, RBF precision, inverse noise variance) and `beta` of eq. 6.6 (RBF variance,
    /// RBF precision, linear variance, inverse noise variance).
    pub fn thesis_parameters(&self) -> ([f64; 3], [f64; 4]) {
        let a = self.spec.kernel_y.params();
        let b = self.spec.kernel_x.params();
        ([a[0].exp(), (-2.0 * a[1]).exp(), (-a[2]).exp()], [b[0].exp(), (-2.0 * b[1]).exp(), b[2].exp(), (-b[3]).exp()])
    }

    fn check_latent(&self, xs: MatRef<'_, f64>) -> Result<()> {
        if xs.ncols() != self.latent_dim() {
            return Err(LearnError::Dimension(format!(
                "latent points of {} values: expected {}",
                xs.ncols(),
                self.latent_dim()
            )));
        }
        check_finite(xs, "latent points")
    }

    /// Reconstruction GP at latent points `xs` (M x d): mean poses (M x D, eq. 6.12) and
    /// variances (eq. 6.13, white term included).
    pub fn reconstruct(&self, xs: MatRef<'_, f64>) -> Result<(Mat<f64>, Vec<f64>)> {
        self.check_latent(xs)?;
        let k = &self.spec.kernel_y;
        let ks = k.cross(xs, self.spec.latent.as_ref())?;
        let mut mean = &ks * &self.a_y;
        for i in 0..mean.nrows() {
            for j in 0..mean.ncols() {
                mean[(i, j)] += self.y_mean[j];
            }
        }
        let v = &ks * &self.ky_inv;
        let white = k.white_variance();
        let var = (0..xs.nrows())
            .map(|i| {
                let row: Vec<f64> = (0..xs.ncols()).map(|j| xs[(i, j)]).collect();
                let q: f64 = (0..ks.ncols()).map(|j| ks[(i, j)] * v[(i, j)]).sum();
                (k.self_covariance(&row) + white - q).max(white)
            })
            .collect();
        Ok((mean, var))
    }

    /// Poses sampled from the reconstruction GP at `xs` (eq. 6.11), seeded.
    pub fn sample_poses(&self, xs: MatRef<'_, f64>, seed: u64) -> Result<Mat<f64>> {
        let (mut mean, var) = self.reconstruct(xs)?;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        for (i, v) in var.iter().enumerate() {
            let sd = v.sqrt();
            for j in 0..mean.ncols() {
                mean[(i, j)] += sd * standard_normal(&mut rng);
            }
        }
        Ok(mean)
    }

    /// One-step dynamics prediction from `x` (eq. 6.9-6.10): mean and variance.
    pub fn dynamics(&self, x: &[f64]) -> Result<(Vec<f64>, f64)> {
        let xs = Mat::from_fn(1, x.len(), |_, j| x[j]);
        self.check_latent(xs.as_ref())?;
        let k = &self.spec.kernel_x;
        let kv = k.cross(xs.as_ref(), self.x_in.as_ref())?;
        let mean =
            (0..self.latent_dim()).map(|a| (0..kv.ncols()).map(|j| kv[(0, j)] * self.a_x[(j, a)]).sum()).collect();
        let v = &kv * &self.kx_inv;
        let q: f64 = (0..kv.ncols()).map(|j| kv[(0, j)] * v[(0, j)]).sum();
        let white = k.white_variance();
        Ok((mean, (k.self_covariance(x) + white - q).max(white)))
    }

    /// Mean prediction of a trajectory of `n` frames from `x1` (thesis 6.6.1): n x d.
    pub fn mean_trajectory(&self, x1: &[f64], n: usize) -> Result<Mat<f64>> {
        if n == 0 {
            return Err(LearnError::Invalid("trajectory of 0 frames".into()));
        }
        check_finite_slice(x1, "x_1")?;
        let d = self.latent_dim();
        let mut out = Mat::zeros(n, d);
        let mut x = x1.to_vec();
        if x.len() != d {
            return Err(LearnError::Dimension(format!("x_1 of {} values: expected {d}", x.len())));
        }
        for i in 0..n {
            for j in 0..d {
                out[(i, j)] = x[j];
            }
            if i + 1 < n {
                x = self.dynamics(&x)?.0;
            }
        }
        Ok(out)
    }

    /// The density of trajectories of `n` frames starting at `x1` (variables x_2..x_n).
    pub fn trajectory_density(&self, x1: &[f64], n: usize) -> Result<TrajectoryDensity<'_>> {
        if x1.len() != self.latent_dim() || n < 2 {
            return Err(LearnError::Dimension(format!(
                "x_1 of {} values and {n} frames: expected {} values and at least 2 frames",
                x1.len(),
                self.latent_dim()
            )));
        }
        check_finite_slice(x1, "x_1")?;
        let rows = |m: &Mat<f64>| crate::matrix::to_rows(m.as_ref());
        Ok(TrajectoryDensity {
            gpdm: self,
            kernel: self.spec.kernel_x.prepare(),
            x_in_rows: rows(&self.x_in),
            a_x_rows: rows(&self.a_x),
            x1: x1.to_vec(),
            n,
        })
    }

    /// Samples whole latent trajectories of `n` frames conditioned on `x1` by Hybrid Monte
    /// Carlo (thesis 6.6.2), starting the chain at the mean prediction. Each trajectory is
    /// n x d, `x1` first; `opts.samples` of them.
    pub fn sample_trajectories(&self, x1: &[f64], n: usize, opts: &HmcOptions) -> Result<(Vec<Mat<f64>>, HmcChain)> {
        let start = self.mean_trajectory(x1, n)?;
        self.sample_trajectories_from(start.as_ref(), opts)
    }

    /// As [`Gpdm::sample_trajectories`], the chain started at `start` (n x d; its first row
    /// is the fixed `x_1`) instead of the mean prediction: e.g. a learnt trajectory, when the
    /// mean prediction drifts away from it (surfcap-variation's sampling).
    pub fn sample_trajectories_from(
        &self,
        start: MatRef<'_, f64>,
        opts: &HmcOptions,
    ) -> Result<(Vec<Mat<f64>>, HmcChain)> {
        self.check_latent(start)?;
        let n = start.nrows();
        let x1: Vec<f64> = (0..start.ncols()).map(|j| start[(0, j)]).collect();
        let density = self.trajectory_density(&x1, n)?;
        let d = self.latent_dim();
        let z0: Vec<f64> = (1..n).flat_map(|i| (0..d).map(move |j| (i, j))).map(|(i, j)| start[(i, j)]).collect();
        let chain = crate::hybrid_monte_carlo::sample(&density, &z0, opts)?;
        let trajectories = chain
            .samples
            .iter()
            .map(|z| Mat::from_fn(n, d, |i, j| if i == 0 { x1[j] } else { z[(i - 1) * d + j] }))
            .collect();
        Ok((trajectories, chain))
    }
}

/// `log P(x_2..x_n | x_1)` as the product of one-step predictive densities (eq. 6.8-6.10).
pub struct TrajectoryDensity<'a> {
    gpdm: &'a Gpdm,
    kernel: PreparedKernel,
    /// Dynamics inputs and `K_X^-1 X'`, row-major (M x d).
    x_in_rows: Vec<f64>,
    a_x_rows: Vec<f64>,
    x1: Vec<f64>,
    n: usize,
}

impl LogDensity for TrajectoryDensity<'_> {
    fn dim(&self) -> usize {
        (self.n - 1) * self.gpdm.latent_dim()
    }

    fn log_density(&self, z: &[f64], grad: &mut [f64]) -> f64 {
        let g = self.gpdm;
        let d = g.latent_dim();
        let steps = self.n - 1;
        let k = &g.spec.kernel_x;
        let pk = &self.kernel;
        let m = g.x_in.nrows();
        let (xin, ax, xn) = (&self.x_in_rows, &self.a_x_rows, &g.x_in_norms);
        // Previous points x_1..x_{n-1} (row-major, steps x d); the next ones are z.
        let prev: Vec<f64> = (0..steps * d).map(|k| if k < d { self.x1[k] } else { z[k - d] }).collect();
        // Kernel values and product derivatives against the M training inputs, and the mean
        // (eq. 6.9) in the same pass. The products with a d-sized side are plain loops, the large
        // product in the (M x steps) layout: (steps x M)(M x M) ran 6-7x slower in about half of
        // the runs on this machine (faer's m8 micro-kernel); the transposed layout ran fast in all
        // the runs measured.
        // Stored transposed (M x steps) so the large product below is K_X^-1 (M x M) times it.
        let mut kc = Mat::<f64>::zeros(m, steps);
        let mut cm = vec![0.0; steps * m];
        let mut em = vec![0.0; steps * m];
        let mut mu = vec![0.0; steps * d];
        let mut pn = vec![0.0; steps];
        surfcap_linalg::clear_upper_vector_state();
        for i in 0..steps {
            let xi = &prev[i * d..(i + 1) * d];
            pn[i] = xi.iter().map(|v| v * v).sum();
            for j in 0..m {
                let xj = &xin[j * d..(j + 1) * d];
                let dot: f64 = xi.iter().zip(xj).map(|(a, b)| a * b).sum();
                let (kv, c, e) = pk.value_and_product_derivatives(dot, pn[i], xn[j]);
                kc[(j, i)] = kv;
                cm[i * m + j] = c;
                em[i * m + j] = e;
                for a in 0..d {
                    mu[i * d + a] += kv * ax[j * d + a];
                }
            }
        }
        // V^T = K_X^-1 k(x) for every step at once (the one large product; M x steps).
        let v = matmul_seq(g.kx_inv.as_ref(), kc.as_ref());
        let white = pk.white_variance();
        let mut logp = 0.0;
        let mut u = vec![0.0; steps * d];
        let mut gamma = vec![0.0; steps];
        grad.iter_mut().for_each(|v| *v = 0.0);
        surfcap_linalg::clear_upper_vector_state();
        for i in 0..steps {
            let q: f64 = (0..m).map(|j| kc[(j, i)] * v[(j, i)]).sum();
            let s2 = (pk.value(pn[i], pn[i], pn[i]) + white - q).max(1e-3 * white);
            let mut r2 = 0.0;
            for a in 0..d {
                let r = z[i * d + a] - mu[i * d + a];
                r2 += r * r;
                u[i * d + a] = r / s2;
                grad[i * d + a] -= r / s2;
            }
            logp += -0.5 * d as f64 * s2.ln() - 0.5 * r2 / s2;
            gamma[i] = -0.5 * d as f64 / s2 + 0.5 * r2 / (s2 * s2);
        }
        // Gradient through x_{i-1} (rows 1.. of prev are variables): with
        // w_ij = (A u_i)_j - 2 gamma_i V_ij, d/dx_{i-1} = sum_j w_ij (c_ij x_in[j] + 2 e_ij x_{i-1})
        // + gamma_i d k(x, x)/dx.
        let mut acc = vec![0.0; d];
        for i in 1..steps {
            let xi = &prev[i * d..(i + 1) * d];
            acc.iter_mut().for_each(|a| *a = 0.0);
            let mut esum = 0.0;
            for j in 0..m {
                let ua: f64 = (0..d).map(|a| u[i * d + a] * ax[j * d + a]).sum();
                let w = ua - 2.0 * gamma[i] * v[(j, i)];
                let wc = w * cm[i * m + j];
                for a in 0..d {
                    acc[a] += wc * xin[j * d + a];
                }
                esum += w * em[i * m + j];
            }
            let sg = k.self_covariance_gradient(xi);
            for a in 0..d {
                grad[(i - 1) * d + a] += acc[a] + 2.0 * esum * xi[a] + gamma[i] * sg[a];
            }
        }
        logp
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two noisy cycles of a 3-D curve lifted to D dimensions by a fixed random map.
    pub(crate) fn toy_sequences(frames: &[usize], dims: usize, seed: u64) -> Vec<Mat<f64>> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let lift = Mat::from_fn(4, dims, |_, _| rng.random_range(-1.0..1.0));
        frames
            .iter()
            .enumerate()
            .map(|(s, &n)| {
                let t0 = 0.3 * s as f64;
                let z = Mat::from_fn(n, 4, |i, c| {
                    let t = t0 + 4.0 * std::f64::consts::PI * i as f64 / n as f64;
                    [t.sin(), t.cos(), (2.0 * t).sin() * 0.5, (3.0 * t).cos() * 0.2][c]
                });
                let mut y = z * &lift;
                for v in y.col_iter_mut().flat_map(|c| c.iter_mut()) {
                    *v += 0.01 * standard_normal(&mut rng);
                }
                y
            })
            .collect()
    }

    #[test]
    fn objective_gradient_matches_finite_differences() {
        let seqs = toy_sequences(&[9, 7], 12, 1);
        let refs: Vec<MatRef<'_, f64>> = seqs.iter().map(|s| s.as_ref()).collect();
        let opts = GpdmOptions { dynamics_weight: 2.5, ..Default::default() };
        let (obj, mut v) = Gpdm::objective(&refs, &opts).unwrap();
        // Move away from the start so every term is generic.
        for (k, x) in v.iter_mut().enumerate() {
            *x += 0.05 * ((k * 7919 % 13) as f64 - 6.0) / 6.0;
        }
        let mut g = vec![0.0; v.len()];
        obj.eval(&v, &mut g).unwrap();
        let mut scratch = vec![0.0; v.len()];
        for q in 0..v.len() {
            let h = 1e-5;
            let (mut vp, mut vm) = (v.clone(), v.clone());
            vp[q] += h;
            vm[q] -= h;
            let fd = (obj.eval(&vp, &mut scratch).unwrap() - obj.eval(&vm, &mut scratch).unwrap()) / (2.0 * h);
            assert!((fd - g[q]).abs() < 1e-5 * (1.0 + fd.abs()), "variable {q}: fd {fd} analytic {}", g[q]);
        }
    }

    #[test]
    fn fit_reconstructs_better_than_pca_predicts_and_samples() {
        let seqs = toy_sequences(&[60, 50], 30, 2);
        let refs: Vec<MatRef<'_, f64>> = seqs.iter().map(|s| s.as_ref()).collect();
        let mut opts = GpdmOptions::default();
        opts.lbfgs.max_iters = 150;
        let (gpdm, rep) = Gpdm::fit(&refs, &opts).unwrap();
        assert!(rep.objective < rep.initial_objective, "{} -> {}", rep.initial_objective, rep.objective);
        let (rec, var) = gpdm.reconstruct(gpdm.latent()).unwrap();
        let (y, _) = concatenate(&refs).unwrap();
        let pca = Pca::fit(y.as_ref(), 3, PcaMethod::Auto).unwrap();
        let prec = pca.reconstruct(pca.project(y.as_ref()).unwrap().as_ref()).unwrap();
        let err = |r: &Mat<f64>| {
            (0..y.nrows())
                .map(|i| (0..y.ncols()).map(|j| (r[(i, j)] - y[(i, j)]).powi(2)).sum::<f64>().sqrt())
                .sum::<f64>()
                / y.nrows() as f64
        };
        let (eg, ep) = (err(&rec), err(&prec));
        assert!(eg < ep, "GPDM {eg} vs PCA {ep}");
        assert!(var.iter().all(|v| *v > 0.0));
        // Mean prediction and HMC samples from the first latent point of sequence 0.
        let x1: Vec<f64> = (0..3).map(|j| gpdm.latent()[(0, j)]).collect();
        let mean = gpdm.mean_trajectory(&x1, 20).unwrap();
        assert_eq!(mean.nrows(), 20);
        let density = gpdm.trajectory_density(&x1, 6).unwrap();
        let z: Vec<f64> = (1..6)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| mean[(i, j)] + 0.01 * (i + j) as f64)
            .collect();
        let mut g = vec![0.0; z.len()];
        density.log_density(&z, &mut g);
        let mut s = vec![0.0; z.len()];
        // The predictive variance is a small difference of O(1) terms (k(x,x) - k^T K^-1 k), so
        // central differences need a step of 1e-4 to rise above its rounding noise.
        for q in 0..z.len() {
            let h = 1e-4;
            let (mut zp, mut zm) = (z.clone(), z.clone());
            zp[q] += h;
            zm[q] -= h;
            let fd = (density.log_density(&zp, &mut s) - density.log_density(&zm, &mut s)) / (2.0 * h);
            assert!((fd - g[q]).abs() < 1e-3 * (1.0 + fd.abs()), "trajectory variable {q}: fd {fd} analytic {}", g[q]);
        }
        let opts = HmcOptions { warmup: 100, samples: 5, thin: 2, seed: 9, ..Default::default() };
        let (trajs, chain) = gpdm.sample_trajectories(&x1, 20, &opts).unwrap();
        assert_eq!(trajs.len(), 5);
        assert!(chain.acceptance_rate > 0.3, "{chain:?}");
        let poses = gpdm.sample_poses(trajs[0].as_ref(), 1).unwrap();
        assert_eq!((poses.nrows(), poses.ncols()), (20, 30));
        // Serde round trip.
        let s = serde_json::to_string(&gpdm).unwrap();
        let back: Gpdm = serde_json::from_str(&s).unwrap();
        let (rec2, _) = back.reconstruct(gpdm.latent()).unwrap();
        assert!((rec2[(3, 4)] - rec[(3, 4)]).abs() < 1e-8);
        assert!(gpdm.reconstruct(Mat::<f64>::zeros(1, 2).as_ref()).is_err());
        eprintln!(
            "toy GPDM: mean frame error {eg:.4} vs PCA {ep:.4}; objective {:.1} -> {:.1} in {} iterations; HMC acceptance {:.2}, step {:.4}, {} leapfrog steps",
            rep.initial_objective,
            rep.objective,
            rep.iters,
            chain.acceptance_rate,
            chain.step_size,
            chain.leapfrog_steps
        );
    }

    #[test]
    fn bad_sequences_are_errors() {
        let a = Mat::<f64>::zeros(5, 4);
        let b = Mat::<f64>::zeros(5, 3);
        assert!(Gpdm::fit(&[a.as_ref(), b.as_ref()], &GpdmOptions::default()).is_err());
        assert!(Gpdm::fit(&[a.as_ref()], &GpdmOptions::default()).is_err(), "identical frames");
        assert!(Gpdm::fit(&[Mat::<f64>::zeros(2, 4).as_ref()], &GpdmOptions::default()).is_err());
        assert!(Gpdm::fit(&[], &GpdmOptions::default()).is_err());
    }
}
