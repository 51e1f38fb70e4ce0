//! Covariance functions of thesis chapters 5 and 6, with analytic derivatives with respect to
//! their (log) hyper-parameters and to their inputs.
//!
//! - [`Kernel::NeuralNetwork`]: the neural-network (arcsine) kernel of thesis eq. 5.13,
//!   `s^2 asin(a x.x' / sqrt((1 + a x.x)(1 + a x'.x')))` with `a = 1 / (2 l^2)`. As printed it
//!   has no bias term, so every function it describes vanishes at x = 0 and is odd; with
//!   `bias: true` the inputs are augmented to (1, x) (x.x' becomes 1 + x.x', Rasmussen and
//!   Williams eq. 4.29), which suits centred PCA coefficients better (see PAPER-NOTES.md).
//! - [`Kernel::SquaredExponential`]: thesis eq. 5.14 and the RBF terms of eq. 6.4 and 6.6
//!   (`alpha_1 exp(-alpha_2 / 2 |x - x'|^2)`, i.e. variance alpha_1 and length scale
//!   `l = alpha_2^-1/2`).
//! - [`Kernel::Linear`]: thesis eq. 5.14 (variance 1) and the `beta_3 x.x'` term of eq. 6.6.
//! - [`Kernel::White`]: the `delta / alpha_3` term of eq. 6.4 and 6.6 (variance `1 / alpha_3`).
//!   It is a function of the sample index, not of the position: it adds to the diagonal of a
//!   training matrix only, never to a cross-covariance.
//! - [`Kernel::Sum`]: sums of the above, e.g. eq. 6.6 = SE + linear + white.
//!
//! Every hyper-parameter is stored and optimised as a logarithm (variances and length scales
//! are positive; see [`Kernel::thesis_log_coefficients`] for the map to the thesis's alpha and
//! beta). All kernels are functions of the inner products `x.x'`, `x.x` and `x'.x'`, so a
//! training set's [`Pairwise`] products are computed once (one matrix product) and every
//! hyper-parameter evaluation reuses them.

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};

/// A covariance function; hyper-parameters are natural logarithms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Kernel {
    /// `s^2 exp(-|x - x'|^2 / (2 l^2))` (thesis eq. 5.14, 6.4, 6.6).
    SquaredExponential { log_variance: f64, log_length_scale: f64 },
    /// The arcsine kernel of thesis eq. 5.13, optionally with the bias input (see module doc).
    NeuralNetwork { log_variance: f64, log_length_scale: f64, bias: bool },
    /// `s^2 x.x'` (thesis eq. 5.14 with s = 1; `beta_3` of eq. 6.6).
    Linear { log_variance: f64 },
    /// `s^2 delta_ij` on training matrices (`1 / alpha_3` of eq. 6.4, `1 / beta_4` of eq. 6.6).
    White { log_variance: f64 },
    /// Sum of kernels; parameters are concatenated in order.
    Sum(Vec<Kernel>),
}

/// Inner products of a set of inputs (N x d), computed once per training set.
#[derive(Debug, Clone)]
pub struct Pairwise {
    /// `x_i . x_j` (N x N).
    pub dot: Mat<f64>,
    /// `|x_i|^2`.
    pub norms: Vec<f64>,
}

impl Pairwise {
    /// Inner products of the rows of `x`.
    pub fn new(x: MatRef<'_, f64>) -> Pairwise {
        let dot = x * x.transpose();
        let norms = (0..x.nrows()).map(|i| dot[(i, i)]).collect();
        Pairwise { dot, norms }
    }

    pub fn len(&self) -> usize {
        self.norms.len()
    }

    pub fn is_empty(&self) -> bool {
        self.norms.is_empty()
    }
}

/// Squared norms of the rows of `x`.
pub fn row_norms(x: MatRef<'_, f64>) -> Vec<f64> {
    (0..x.nrows()).map(|i| (0..x.ncols()).map(|j| x[(i, j)] * x[(i, j)]).sum()).collect()
}

/// A kernel with its hyper-parameters exponentiated once: the form the O(N^2) loops evaluate
/// (one `exp` per squared-exponential entry instead of one per parameter per entry).
#[derive(Debug, Clone)]
pub struct PreparedKernel {
    terms: Vec<Term>,
    white: f64,
}

#[derive(Debug, Clone, Copy)]
enum Term {
    Se { var: f64, inv_l2: f64, at: usize },
    Nn { var: f64, a: f64, b: f64, at: usize },
    Lin { var: f64, at: usize },
}

impl PreparedKernel {
    fn push(&mut self, k: &Kernel, at: &mut usize) {
        match k {
            Kernel::SquaredExponential { log_variance, log_length_scale } => {
                self.terms.push(Term::Se { var: log_variance.exp(), inv_l2: (-2.0 * log_length_scale).exp(), at: *at });
                *at += 2;
            }
            Kernel::NeuralNetwork { log_variance, log_length_scale, bias } => {
                self.terms.push(Term::Nn {
                    var: log_variance.exp(),
                    a: 0.5 * (-2.0 * log_length_scale).exp(),
                    b: if *bias { 1.0 } else { 0.0 },
                    at: *at,
                });
                *at += 2;
            }
            Kernel::Linear { log_variance } => {
                self.terms.push(Term::Lin { var: log_variance.exp(), at: *at });
                *at += 1;
            }
            Kernel::White { log_variance } => {
                self.white += log_variance.exp();
                *at += 1;
            }
            Kernel::Sum(ks) => ks.iter().for_each(|k| self.push(k, at)),
        }
    }

    /// Variance of the white-noise terms.
    pub fn white_variance(&self) -> f64 {
        self.white
    }

    /// The covariance from the products (no white noise), as [`Kernel::from_products`].
    #[inline]
    pub fn value(&self, dot: f64, n1: f64, n2: f64) -> f64 {
        let mut v = 0.0;
        for t in &self.terms {
            v += match *t {
                Term::Se { var, inv_l2, .. } => var * (-0.5 * (n1 + n2 - 2.0 * dot).max(0.0) * inv_l2).exp(),
                Term::Nn { var, a, b, .. } => {
                    let z = a * (b + dot) / ((1.0 + a * (b + n1)) * (1.0 + a * (b + n2))).sqrt();
                    var * z.clamp(-Z_MAX, Z_MAX).asin()
                }
                Term::Lin { var, .. } => var * dot,
            };
        }
        v
    }

    /// `(k, dk/d dot, dk/d n1)`, as [`Kernel::value_and_product_derivatives`].
    #[inline]
    pub fn value_and_product_derivatives(&self, dot: f64, n1: f64, n2: f64) -> (f64, f64, f64) {
        let (mut v, mut c, mut e) = (0.0, 0.0, 0.0);
        for t in &self.terms {
            match *t {
                Term::Se { var, inv_l2, .. } => {
                    let k = var * (-0.5 * (n1 + n2 - 2.0 * dot).max(0.0) * inv_l2).exp();
                    v += k;
                    c += k * inv_l2;
                    e -= 0.5 * k * inv_l2;
                }
                Term::Nn { var, a, b, .. } => {
                    let (p, q) = (1.0 + a * (b + n1), 1.0 + a * (b + n2));
                    let z = (a * (b + dot) / (p * q).sqrt()).clamp(-Z_MAX, Z_MAX);
                    let dk_dz = var / (1.0 - z * z).sqrt();
                    v += var * z.asin();
                    c += dk_dz * a / (p * q).sqrt();
                    e += dk_dz * (-0.5 * z * a / p);
                }
                Term::Lin { var, .. } => {
                    v += var * dot;
                    c += var;
                }
            }
        }
        (v, c, e)
    }

    /// Adds `w * dk/d theta_p` (no white noise) to `out`.
    #[inline]
    fn add_param_grads(&self, dot: f64, n1: f64, n2: f64, w: f64, out: &mut [f64]) {
        for t in &self.terms {
            match *t {
                Term::Se { var, inv_l2, at } => {
                    let r2 = (n1 + n2 - 2.0 * dot).max(0.0);
                    let k = var * (-0.5 * r2 * inv_l2).exp();
                    out[at] += w * k;
                    out[at + 1] += w * k * r2 * inv_l2;
                }
                Term::Nn { var, a, b, at } => {
                    let (p, q) = (1.0 + a * (b + n1), 1.0 + a * (b + n2));
                    let z = (a * (b + dot) / (p * q).sqrt()).clamp(-Z_MAX, Z_MAX);
                    out[at] += w * var * z.asin();
                    let dz = -2.0 * z * (1.0 - 0.5 * a * ((b + n1) / p + (b + n2) / q));
                    out[at + 1] += w * var * dz / (1.0 - z * z).sqrt();
                }
                Term::Lin { var, at } => out[at] += w * var * dot,
            }
        }
    }
}

const Z_MAX: f64 = 1.0 - 1e-12;

impl Kernel {
    /// The kernel with its parameters exponentiated, for evaluation loops.
    pub fn prepare(&self) -> PreparedKernel {
        let mut p = PreparedKernel { terms: Vec::new(), white: 0.0 };
        p.push(self, &mut 0);
        p
    }

    /// `s^2 exp(-r^2 / (2 l^2))` with the given variance and length scale (not logarithms).
    pub fn squared_exponential(variance: f64, length_scale: f64) -> Kernel {
        Kernel::SquaredExponential { log_variance: variance.ln(), log_length_scale: length_scale.ln() }
    }

    /// Thesis eq. 5.13 with the bias input, variance `s^2` and length scale `l`.
    pub fn neural_network(variance: f64, length_scale: f64) -> Kernel {
        Kernel::NeuralNetwork { log_variance: variance.ln(), log_length_scale: length_scale.ln(), bias: true }
    }

    /// `s^2 x.x'`.
    pub fn linear(variance: f64) -> Kernel {
        Kernel::Linear { log_variance: variance.ln() }
    }

    /// White noise of the given variance.
    pub fn white(variance: f64) -> Kernel {
        Kernel::White { log_variance: variance.ln() }
    }

    /// Thesis eq. 6.4: `alpha_1 exp(-alpha_2/2 |x - x'|^2) + delta / alpha_3`.
    pub fn rbf_white(alpha: [f64; 3]) -> Kernel {
        Kernel::Sum(vec![Kernel::squared_exponential(alpha[0], alpha[1].powf(-0.5)), Kernel::white(1.0 / alpha[2])])
    }

    /// Thesis eq. 6.6: `beta_1 exp(-beta_2/2 |x - x'|^2) + beta_3 x.x' + delta / beta_4`.
    pub fn rbf_linear_white(beta: [f64; 4]) -> Kernel {
        Kernel::Sum(vec![
            Kernel::squared_exponential(beta[0], beta[1].powf(-0.5)),
            Kernel::linear(beta[2]),
            Kernel::white(1.0 / beta[3]),
        ])
    }

    /// Number of hyper-parameters.
    pub fn n_params(&self) -> usize {
        match self {
            Kernel::SquaredExponential { .. } | Kernel::NeuralNetwork { .. } => 2,
            Kernel::Linear { .. } | Kernel::White { .. } => 1,
            Kernel::Sum(ks) => ks.iter().map(Kernel::n_params).sum(),
        }
    }

    /// The log hyper-parameters, in order.
    pub fn params(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.n_params());
        self.push_params(&mut out);
        out
    }

    fn push_params(&self, out: &mut Vec<f64>) {
        match self {
            Kernel::SquaredExponential { log_variance, log_length_scale }
            | Kernel::NeuralNetwork { log_variance, log_length_scale, .. } => {
                out.extend([*log_variance, *log_length_scale])
            }
            Kernel::Linear { log_variance } | Kernel::White { log_variance } => out.push(*log_variance),
            Kernel::Sum(ks) => ks.iter().for_each(|k| k.push_params(out)),
        }
    }

    /// Sets the log hyper-parameters (as many as [`Kernel::n_params`]).
    pub fn set_params(&mut self, p: &[f64]) -> Result<()> {
        if p.len() != self.n_params() {
            return Err(LearnError::Dimension(format!("{} kernel parameters: expected {}", p.len(), self.n_params())));
        }
        crate::matrix::check_finite_slice(p, "kernel parameters")?;
        self.take_params(p);
        Ok(())
    }

    fn take_params<'a>(&mut self, p: &'a [f64]) -> &'a [f64] {
        match self {
            Kernel::SquaredExponential { log_variance, log_length_scale }
            | Kernel::NeuralNetwork { log_variance, log_length_scale, .. } => {
                *log_variance = p[0];
                *log_length_scale = p[1];
                &p[2..]
            }
            Kernel::Linear { log_variance } | Kernel::White { log_variance } => {
                *log_variance = p[0];
                &p[1..]
            }
            Kernel::Sum(ks) => ks.iter_mut().fold(p, |rest, k| k.take_params(rest)),
        }
    }

    /// Names of the hyper-parameters, for reports.
    pub fn param_names(&self) -> Vec<String> {
        match self {
            Kernel::SquaredExponential { .. } => vec!["se.log_variance".into(), "se.log_length_scale".into()],
            Kernel::NeuralNetwork { .. } => vec!["nn.log_variance".into(), "nn.log_length_scale".into()],
            Kernel::Linear { .. } => vec!["linear.log_variance".into()],
            Kernel::White { .. } => vec!["white.log_variance".into()],
            Kernel::Sum(ks) => ks.iter().flat_map(Kernel::param_names).collect(),
        }
    }

    /// Coefficients c with `sum_k ln(thesis parameter k) = sum_p c_p theta_p`: the thesis writes
    /// variances as themselves (alpha_1, beta_1, beta_3), the RBF width as a precision
    /// (`alpha_2 = 1 / l^2`: coefficient -2 on ln l) and the noise as an inverse variance
    /// (`alpha_3`: coefficient -1). Used for the GPDM priors `P(alpha) = prod alpha_k^-1`.
    pub fn thesis_log_coefficients(&self) -> Vec<f64> {
        match self {
            Kernel::SquaredExponential { .. } | Kernel::NeuralNetwork { .. } => vec![1.0, -2.0],
            Kernel::Linear { .. } => vec![1.0],
            Kernel::White { .. } => vec![-1.0],
            Kernel::Sum(ks) => ks.iter().flat_map(Kernel::thesis_log_coefficients).collect(),
        }
    }

    /// Variance of the white-noise terms (0 without any).
    pub fn white_variance(&self) -> f64 {
        match self {
            Kernel::White { log_variance } => log_variance.exp(),
            Kernel::Sum(ks) => ks.iter().map(Kernel::white_variance).sum(),
            _ => 0.0,
        }
    }

    /// The covariance of two inputs given their products (no white noise).
    pub fn from_products(&self, dot: f64, n1: f64, n2: f64) -> f64 {
        match self {
            Kernel::SquaredExponential { log_variance, log_length_scale } => {
                let r2 = (n1 + n2 - 2.0 * dot).max(0.0);
                (log_variance - 0.5 * r2 * (-2.0 * log_length_scale).exp()).exp()
            }
            Kernel::NeuralNetwork { log_variance, log_length_scale, bias } => {
                let b = if *bias { 1.0 } else { 0.0 };
                let a = 0.5 * (-2.0 * log_length_scale).exp();
                let z = a * (b + dot) / ((1.0 + a * (b + n1)) * (1.0 + a * (b + n2))).sqrt();
                log_variance.exp() * z.clamp(-Z_MAX, Z_MAX).asin()
            }
            Kernel::Linear { log_variance } => log_variance.exp() * dot,
            Kernel::White { .. } => 0.0,
            Kernel::Sum(ks) => ks.iter().map(|k| k.from_products(dot, n1, n2)).sum(),
        }
    }

    /// Adds `w * d(white variance)/d theta_p` (the diagonal contribution of white terms).
    fn add_white_grads(&self, w: f64, out: &mut [f64]) {
        match self {
            Kernel::White { log_variance } => out[0] += w * log_variance.exp(),
            Kernel::Sum(ks) => {
                let mut at = 0;
                for k in ks {
                    let m = k.n_params();
                    k.add_white_grads(w, &mut out[at..at + m]);
                    at += m;
                }
            }
            _ => {}
        }
    }

    /// `(dk/d dot, dk/d n1)`: derivatives with respect to `x.x'` and `x.x` (white excluded).
    pub fn product_derivatives(&self, dot: f64, n1: f64, n2: f64) -> (f64, f64) {
        match self {
            Kernel::SquaredExponential { log_variance, log_length_scale } => {
                let inv_l2 = (-2.0 * log_length_scale).exp();
                let r2 = (n1 + n2 - 2.0 * dot).max(0.0);
                let k = (log_variance - 0.5 * r2 * inv_l2).exp();
                (k * inv_l2, -0.5 * k * inv_l2)
            }
            Kernel::NeuralNetwork { log_variance, log_length_scale, bias } => {
                let b = if *bias { 1.0 } else { 0.0 };
                let a = 0.5 * (-2.0 * log_length_scale).exp();
                let (p, q) = (1.0 + a * (b + n1), 1.0 + a * (b + n2));
                let z = (a * (b + dot) / (p * q).sqrt()).clamp(-Z_MAX, Z_MAX);
                let dk_dz = log_variance.exp() / (1.0 - z * z).sqrt();
                (dk_dz * a / (p * q).sqrt(), dk_dz * (-0.5 * z * a / p))
            }
            Kernel::Linear { log_variance } => (log_variance.exp(), 0.0),
            Kernel::White { .. } => (0.0, 0.0),
            Kernel::Sum(ks) => ks.iter().fold((0.0, 0.0), |(a, b), k| {
                let (c, d) = k.product_derivatives(dot, n1, n2);
                (a + c, b + d)
            }),
        }
    }

    /// `(k, dk/d dot, dk/d n1)` in one pass (one `exp` per SE term): the value of
    /// [`Kernel::from_products`] and the derivatives of [`Kernel::product_derivatives`].
    pub fn value_and_product_derivatives(&self, dot: f64, n1: f64, n2: f64) -> (f64, f64, f64) {
        match self {
            Kernel::SquaredExponential { log_variance, log_length_scale } => {
                let inv_l2 = (-2.0 * log_length_scale).exp();
                let r2 = (n1 + n2 - 2.0 * dot).max(0.0);
                let k = (log_variance - 0.5 * r2 * inv_l2).exp();
                (k, k * inv_l2, -0.5 * k * inv_l2)
            }
            Kernel::Linear { log_variance } => {
                let s2 = log_variance.exp();
                (s2 * dot, s2, 0.0)
            }
            Kernel::White { .. } => (0.0, 0.0, 0.0),
            Kernel::NeuralNetwork { .. } => {
                let (c, e) = self.product_derivatives(dot, n1, n2);
                (self.from_products(dot, n1, n2), c, e)
            }
            Kernel::Sum(ks) => ks.iter().fold((0.0, 0.0, 0.0), |(a, b, c), k| {
                let (x, y, z) = k.value_and_product_derivatives(dot, n1, n2);
                (a + x, b + y, c + z)
            }),
        }
    }

    /// Training covariance matrix K (N x N), white noise on the diagonal. Columns are filled in
    /// parallel (each entry is computed on its own: the result does not depend on the threads).
    pub fn matrix(&self, p: &Pairwise) -> Mat<f64> {
        use rayon::prelude::*;
        let n = p.len();
        let pk = self.prepare();
        let white = pk.white_variance();
        let mut k = Mat::zeros(n, n);
        k.par_col_iter_mut().enumerate().for_each(|(j, mut col)| {
            surfcap_linalg::clear_upper_vector_state();
            for i in 0..n {
                col[i] = pk.value(p.dot[(i, j)], p.norms[i], p.norms[j]);
            }
            col[j] += white;
        });
        k
    }

    /// Cross-covariances `k(a_i, b_j)` (no white noise), `a` M x d, `b` N x d.
    pub fn cross(&self, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Result<Mat<f64>> {
        if a.ncols() != b.ncols() {
            return Err(LearnError::Dimension(format!("inputs of {} and {} dimensions", a.ncols(), b.ncols())));
        }
        let dot = a * b.transpose();
        let (na, nb) = (row_norms(a), row_norms(b));
        let pk = self.prepare();
        surfcap_linalg::clear_upper_vector_state();
        Ok(Mat::from_fn(a.nrows(), b.nrows(), |i, j| pk.value(dot[(i, j)], na[i], nb[j])))
    }

    /// `k(x, x)` of one input (no white noise).
    pub fn self_covariance(&self, x: &[f64]) -> f64 {
        let n: f64 = x.iter().map(|v| v * v).sum();
        self.from_products(n, n, n)
    }

    /// `sum_ij W_ij dK_ij / d theta_p` for every hyper-parameter, for a symmetric `w` (the
    /// derivative of any objective of K whose matrix gradient is `w`).
    ///
    /// Columns are summed in parallel and their partial sums added in column order, so the
    /// result is the same whatever the number of threads.
    pub fn param_gradients(&self, p: &Pairwise, w: MatRef<'_, f64>) -> Vec<f64> {
        use rayon::prelude::*;
        let n = p.len();
        let np = self.n_params();
        let pk = self.prepare();
        let partial: Vec<Vec<f64>> = (0..n)
            .into_par_iter()
            .map(|j| {
                surfcap_linalg::clear_upper_vector_state();
                let mut g = vec![0.0; np];
                for i in j..n {
                    let wij = if i == j { w[(i, i)] } else { w[(i, j)] + w[(j, i)] };
                    pk.add_param_grads(p.dot[(i, j)], p.norms[i], p.norms[j], wij, &mut g);
                }
                g
            })
            .collect();
        let mut g = vec![0.0; np];
        for col in &partial {
            for (a, b) in g.iter_mut().zip(col) {
                *a += b;
            }
        }
        let trace: f64 = (0..n).map(|j| w[(j, j)]).sum();
        self.add_white_grads(trace, &mut g);
        g
    }

    /// `dL/dx_i = sum_j (W_ij + W_ji) d k(x_i, x_j) / d x_i` (first argument), for inputs `x`
    /// (N x d) and a matrix gradient `w` of an objective L of K(x). The white term depends on
    /// the index, not the position, and contributes nothing.
    pub fn input_gradient(&self, x: MatRef<'_, f64>, p: &Pairwise, w: MatRef<'_, f64>) -> Mat<f64> {
        let pk = self.prepare();
        surfcap_linalg::clear_upper_vector_state();
        let n = p.len();
        // dk(x_i,x_j)/dx_i = c_ij x_j + 2 e_ij x_i with (c, e) the product derivatives.
        let mut cw = Mat::<f64>::zeros(n, n);
        let mut ew = vec![0.0; n];
        for j in 0..n {
            for i in j..n {
                let wij = w[(i, j)] + w[(j, i)];
                let (_, c, e) = pk.value_and_product_derivatives(p.dot[(i, j)], p.norms[i], p.norms[j]);
                cw[(i, j)] = wij * c;
                cw[(j, i)] = wij * c;
                // e_ji = d k/d n1 at (x_j, x_i): same function with n1 and n2 swapped.
                ew[i] += wij * e;
                if i != j {
                    let (_, _, e2) = pk.value_and_product_derivatives(p.dot[(i, j)], p.norms[j], p.norms[i]);
                    ew[j] += wij * e2;
                }
            }
        }
        let mut g = &cw * x;
        for i in 0..n {
            for k in 0..x.ncols() {
                g[(i, k)] += 2.0 * ew[i] * x[(i, k)];
            }
        }
        g
    }

    /// `d k(x, b_j) / d x` for one input `x` against every row of `b` (N x d result).
    pub fn cross_input_gradient(&self, x: &[f64], b: MatRef<'_, f64>, b_norms: &[f64]) -> Mat<f64> {
        let nx: f64 = x.iter().map(|v| v * v).sum();
        let d = x.len();
        let pk = self.prepare();
        let mut g = Mat::zeros(b.nrows(), d);
        for j in 0..b.nrows() {
            let dot: f64 = (0..d).map(|k| x[k] * b[(j, k)]).sum();
            let (_, c, e) = pk.value_and_product_derivatives(dot, nx, b_norms[j]);
            for k in 0..d {
                g[(j, k)] = c * b[(j, k)] + 2.0 * e * x[k];
            }
        }
        g
    }

    /// `d k(x, x) / d x` (no white noise).
    pub fn self_covariance_gradient(&self, x: &[f64]) -> Vec<f64> {
        let n: f64 = x.iter().map(|v| v * v).sum();
        // k(x, x) = f(n, n, n): total derivative 2 x (c + 2 e) by symmetry of the two arguments.
        let (c, e) = self.product_derivatives(n, n, n);
        x.iter().map(|v| 2.0 * (c + 2.0 * e) * v).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn kernels() -> Vec<Kernel> {
        vec![
            Kernel::squared_exponential(1.3, 0.7),
            Kernel::neural_network(0.8, 1.4),
            Kernel::NeuralNetwork { log_variance: 0.1, log_length_scale: -0.2, bias: false },
            Kernel::rbf_linear_white([1.1, 2.0, 0.3, 50.0]),
            Kernel::rbf_white([0.9, 1.5, 20.0]),
        ]
    }

    fn random_x(n: usize, d: usize, seed: u64) -> Mat<f64> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        Mat::from_fn(n, d, |_, _| rng.random_range(-1.5..1.5))
    }

    /// L(K) = sum W∘K with a fixed random symmetric W: its gradients are the contractions.
    fn objective(k: &Kernel, x: MatRef<'_, f64>, w: MatRef<'_, f64>) -> f64 {
        let km = k.matrix(&Pairwise::new(x));
        let mut s = 0.0;
        for i in 0..x.nrows() {
            for j in 0..x.nrows() {
                s += w[(i, j)] * km[(i, j)];
            }
        }
        s
    }

    #[test]
    fn parameter_and_input_gradients_match_finite_differences() {
        let x = random_x(7, 3, 1);
        let wr = random_x(7, 7, 2);
        let w = Mat::from_fn(7, 7, |i, j| wr[(i, j)] + wr[(j, i)]);
        for k in kernels() {
            let p = Pairwise::new(x.as_ref());
            let g = k.param_gradients(&p, w.as_ref());
            let theta = k.params();
            for q in 0..theta.len() {
                let h = 1e-6;
                let (mut kp, mut km) = (k.clone(), k.clone());
                let (mut tp, mut tm) = (theta.clone(), theta.clone());
                tp[q] += h;
                tm[q] -= h;
                kp.set_params(&tp).unwrap();
                km.set_params(&tm).unwrap();
                let fd = (objective(&kp, x.as_ref(), w.as_ref()) - objective(&km, x.as_ref(), w.as_ref())) / (2.0 * h);
                assert!((fd - g[q]).abs() <= 1e-6 * (1.0 + fd.abs()), "{k:?} param {q}: fd {fd} analytic {}", g[q]);
            }
            let gx = k.input_gradient(x.as_ref(), &p, w.as_ref());
            for i in 0..x.nrows() {
                for d in 0..x.ncols() {
                    let h = 1e-6;
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[(i, d)] += h;
                    xm[(i, d)] -= h;
                    let fd =
                        (objective(&k, xp.as_ref(), w.as_ref()) - objective(&k, xm.as_ref(), w.as_ref())) / (2.0 * h);
                    assert!(
                        (fd - gx[(i, d)]).abs() <= 1e-6 * (1.0 + fd.abs()),
                        "{k:?} x[{i},{d}]: fd {fd} vs {}",
                        gx[(i, d)]
                    );
                }
            }
            // Cross and self-covariance gradients.
            let b = random_x(4, 3, 3);
            let bn = row_norms(b.as_ref());
            let x0 = [0.3, -0.4, 0.9];
            let gc = k.cross_input_gradient(&x0, b.as_ref(), &bn);
            let gs = k.self_covariance_gradient(&x0);
            for d in 0..3 {
                let h = 1e-6;
                let (mut xp, mut xm) = (x0, x0);
                xp[d] += h;
                xm[d] -= h;
                let cp = k.cross(Mat::from_fn(1, 3, |_, j| xp[j]).as_ref(), b.as_ref()).unwrap();
                let cm = k.cross(Mat::from_fn(1, 3, |_, j| xm[j]).as_ref(), b.as_ref()).unwrap();
                for j in 0..4 {
                    let fd = (cp[(0, j)] - cm[(0, j)]) / (2.0 * h);
                    assert!((fd - gc[(j, d)]).abs() < 1e-6 * (1.0 + fd.abs()), "{k:?} cross");
                }
                let (v, c, e) = k.value_and_product_derivatives(0.3, 1.1, 0.7);
                assert!((v - k.from_products(0.3, 1.1, 0.7)).abs() < 1e-14);
                assert_eq!((c, e), k.product_derivatives(0.3, 1.1, 0.7));
                let (pv, pc, pe) = k.prepare().value_and_product_derivatives(0.3, 1.1, 0.7);
                assert!((pv - v).abs() < 1e-12 && (pc - c).abs() < 1e-12 && (pe - e).abs() < 1e-12);
                assert!((k.prepare().value(0.3, 1.1, 0.7) - v).abs() < 1e-12);
                let fd = (k.self_covariance(&xp) - k.self_covariance(&xm)) / (2.0 * h);
                assert!((fd - gs[d]).abs() < 1e-6 * (1.0 + fd.abs()), "{k:?} self: {fd} vs {}", gs[d]);
            }
        }
    }

    #[test]
    fn thesis_forms_and_parameter_round_trip() {
        // eq. 6.4 at distance r: alpha_1 exp(-alpha_2 r^2 / 2), plus 1/alpha_3 on the diagonal.
        let k = Kernel::rbf_white([2.0, 4.0, 10.0]);
        let x = crate::matrix::from_rows(2, 1, &[0.0, 0.5]).unwrap();
        let m = k.matrix(&Pairwise::new(x.as_ref()));
        assert!((m[(0, 1)] - 2.0 * (-4.0f64 * 0.25 / 2.0).exp()).abs() < 1e-12);
        assert!((m[(0, 0)] - 2.1).abs() < 1e-12);
        let c = k.cross(x.as_ref(), x.as_ref()).unwrap();
        assert!((c[(0, 0)] - 2.0).abs() < 1e-12, "no white noise in cross-covariances");
        // eq. 5.13 without bias: s^2 asin(a x.x' / sqrt(...)), a = 1/(2 l^2).
        let nn = Kernel::NeuralNetwork { log_variance: 0.0, log_length_scale: 0.0, bias: false };
        let v = nn.from_products(2.0, 1.0, 4.0);
        assert!((v - (1.0f64 / (1.5f64 * 3.0).sqrt()).asin()).abs() < 1e-12);
        let mut s = Kernel::rbf_linear_white([1.0, 2.0, 3.0, 4.0]);
        let p = s.params();
        assert_eq!(p.len(), 4);
        s.set_params(&p).unwrap();
        assert!(s.set_params(&p[..3]).is_err());
        assert!(s.set_params(&[f64::NAN; 4]).is_err());
        assert_eq!(s.thesis_log_coefficients(), vec![1.0, -2.0, 1.0, -1.0]);
        assert!(s.cross(x.as_ref(), Mat::<f64>::zeros(1, 2).as_ref()).is_err());
    }
}
