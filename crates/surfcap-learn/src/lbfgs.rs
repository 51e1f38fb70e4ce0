//! L-BFGS minimisation (Nocedal and Wright, *Numerical Optimization*, Algorithm 7.4 with the
//! strong-Wolfe line search of Algorithms 3.5-3.6), used to fit GP hyper-parameters (thesis
//! 5.5.2: "optimized using conjugate gradients") and the GPDM MAP estimate (thesis eq. 6.7).
//!
//! Written here rather than taken from `argmin`: the objective and its gradient share one
//! Cholesky factorisation, so they are always evaluated together (argmin's separate
//! `CostFunction`/`Gradient` traits would either factorise twice or need a hidden cache), and a
//! trial point where the objective is not finite (a kernel matrix that cannot be factorised) is
//! simply a step that is too long: the line search shrinks it instead of failing.

use crate::error::{LearnError, Result};

/// Stopping rules and memory of [`minimize`].
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct LbfgsOptions {
    /// Correction pairs kept (m in Nocedal and Wright).
    pub memory: usize,
    /// Iterations (line searches) at most.
    pub max_iters: usize,
    /// Objective evaluations at most (each evaluation also gives the gradient).
    pub max_evals: usize,
    /// Stop when the largest gradient entry is below this.
    pub grad_tol: f64,
    /// Stop when an iteration lowers the objective by less than `f_tol * max(1, |f|)`.
    pub f_tol: f64,
    /// Length (in the variables' units) of the first, steepest-descent trial step, before any
    /// curvature is known: 1 by default; smaller when starting near an optimum.
    pub initial_step: f64,
}

impl Default for LbfgsOptions {
    fn default() -> Self {
        LbfgsOptions { memory: 10, max_iters: 200, max_evals: 300, grad_tol: 1e-6, f_tol: 1e-10, initial_step: 1.0 }
    }
}

/// Result of [`minimize`].
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Minimum {
    pub x: Vec<f64>,
    pub f: f64,
    pub iters: usize,
    pub evals: usize,
    /// True when a tolerance was met (false: a budget ran out or the line search stalled).
    pub converged: bool,
    /// The objective at the start and after every iteration (a learning curve).
    #[serde(default)]
    pub history: Vec<f64>,
}

struct Trial {
    a: f64,
    f: f64,
    g: Vec<f64>,
    dphi: f64,
}

const C1: f64 = 1e-4;
const C2: f64 = 0.9;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Minimises `f`, which returns the objective at `x` and writes its gradient into the second
/// argument. A non-finite return value marks an infeasible point. Errors when the starting point
/// is infeasible or the dimensions are inconsistent.
pub fn minimize<F: FnMut(&[f64], &mut [f64]) -> f64>(mut f: F, x0: &[f64], opts: &LbfgsOptions) -> Result<Minimum> {
    let n = x0.len();
    if n == 0 {
        return Err(LearnError::Invalid("L-BFGS: no variables".into()));
    }
    let mut x = x0.to_vec();
    let mut g = vec![0.0; n];
    let mut fx = f(&x, &mut g);
    let mut evals = 1;
    if !fx.is_finite() || g.iter().any(|v| !v.is_finite()) {
        return Err(LearnError::Optimisation(format!("L-BFGS: objective {fx} at the starting point")));
    }
    let mut s_hist: Vec<Vec<f64>> = Vec::new();
    let mut y_hist: Vec<Vec<f64>> = Vec::new();
    let mut iters = 0;
    let mut converged = false;
    let mut history = vec![fx];
    let mut xt = vec![0.0; n];
    while iters < opts.max_iters && evals < opts.max_evals {
        if g.iter().fold(0.0f64, |m, v| m.max(v.abs())) <= opts.grad_tol {
            converged = true;
            break;
        }
        // Two-loop recursion.
        let mut d: Vec<f64> = g.iter().map(|v| -v).collect();
        let k = s_hist.len();
        let mut alphas = vec![0.0; k];
        for i in (0..k).rev() {
            let rho = 1.0 / dot(&y_hist[i], &s_hist[i]);
            alphas[i] = rho * dot(&s_hist[i], &d);
            for (dj, yj) in d.iter_mut().zip(&y_hist[i]) {
                *dj -= alphas[i] * yj;
            }
        }
        if k > 0 {
            let gamma = dot(&s_hist[k - 1], &y_hist[k - 1]) / dot(&y_hist[k - 1], &y_hist[k - 1]);
            d.iter_mut().for_each(|v| *v *= gamma);
        }
        for i in 0..k {
            let rho = 1.0 / dot(&y_hist[i], &s_hist[i]);
            let beta = rho * dot(&y_hist[i], &d);
            for (dj, sj) in d.iter_mut().zip(&s_hist[i]) {
                *dj += (alphas[i] - beta) * sj;
            }
        }
        let mut dphi0 = dot(&g, &d);
        if dphi0 >= 0.0 || !dphi0.is_finite() {
            // Not a descent direction: forget the curvature pairs and go downhill.
            s_hist.clear();
            y_hist.clear();
            d = g.iter().map(|v| -v).collect();
            dphi0 = dot(&g, &d);
        }
        let a0 = if s_hist.is_empty() { (opts.initial_step / dphi0.abs().sqrt()).min(1.0) } else { 1.0 };
        let mut eval = |a: f64, xt: &mut Vec<f64>, evals: &mut usize| -> Trial {
            for i in 0..n {
                xt[i] = x[i] + a * d[i];
            }
            let mut gt = vec![0.0; n];
            let ft = f(xt, &mut gt);
            *evals += 1;
            let ok = ft.is_finite() && gt.iter().all(|v| v.is_finite());
            let dphi = dot(&gt, &d);
            Trial { a, f: if ok { ft } else { f64::INFINITY }, g: gt, dphi }
        };
        let budget = opts.max_evals.saturating_sub(evals).min(30);
        let found = line_search(&mut eval, &mut xt, &mut evals, fx, dphi0, a0, budget);
        iters += 1;
        let Some(t) = found else { break };
        let s: Vec<f64> = d.iter().map(|v| t.a * v).collect();
        let y: Vec<f64> = t.g.iter().zip(&g).map(|(a, b)| a - b).collect();
        let f_old = fx;
        for i in 0..n {
            x[i] += s[i];
        }
        fx = t.f;
        history.push(fx);
        g = t.g;
        let sy = dot(&s, &y);
        if sy > 1e-12 * dot(&y, &y).sqrt() * dot(&s, &s).sqrt() {
            s_hist.push(s);
            y_hist.push(y);
            if s_hist.len() > opts.memory {
                s_hist.remove(0);
                y_hist.remove(0);
            }
        }
        if f_old - fx <= opts.f_tol * f_old.abs().max(fx.abs()).max(1.0) {
            converged = true;
            break;
        }
    }
    Ok(Minimum { x, f: fx, iters, evals, converged, history })
}

/// Strong-Wolfe line search: bracketing (Algorithm 3.5) then zoom by safeguarded quadratic
/// interpolation (Algorithm 3.6). Returns the accepted trial, or `None` when no decrease was
/// found within `budget` evaluations. A point satisfying only the sufficient-decrease condition
/// is accepted when the budget runs out (the minimisation still makes progress).
fn line_search(
    eval: &mut impl FnMut(f64, &mut Vec<f64>, &mut usize) -> Trial,
    xt: &mut Vec<f64>,
    evals: &mut usize,
    f0: f64,
    dphi0: f64,
    a0: f64,
    budget: usize,
) -> Option<Trial> {
    let start = *evals;
    let armijo = |t: &Trial| t.f <= f0 + C1 * t.a * dphi0;
    let mut prev = Trial { a: 0.0, f: f0, g: Vec::new(), dphi: dphi0 };
    let mut a = a0;
    let mut first = true;
    loop {
        if *evals - start >= budget {
            return None;
        }
        let t = eval(a, xt, evals);
        if !t.f.is_finite() {
            // Infeasible: shrink towards the last good point.
            a = prev.a + 0.1 * (a - prev.a);
            continue;
        }
        if !armijo(&t) || (!first && t.f >= prev.f) {
            return zoom(eval, xt, evals, f0, dphi0, prev, t, start + budget);
        }
        if t.dphi.abs() <= -C2 * dphi0 {
            return Some(t);
        }
        if t.dphi >= 0.0 {
            return zoom(eval, xt, evals, f0, dphi0, t, prev, start + budget);
        }
        first = false;
        a *= 2.0;
        prev = t;
    }
}

#[allow(clippy::too_many_arguments)]
fn zoom(
    eval: &mut impl FnMut(f64, &mut Vec<f64>, &mut usize) -> Trial,
    xt: &mut Vec<f64>,
    evals: &mut usize,
    f0: f64,
    dphi0: f64,
    mut lo: Trial,
    mut hi: Trial,
    end: usize,
) -> Option<Trial> {
    loop {
        if *evals >= end || (hi.a - lo.a).abs() < 1e-16 * lo.a.abs().max(1e-300) {
            // Out of budget: the low end satisfies sufficient decrease (when it moved at all).
            return if lo.a > 0.0 && !lo.g.is_empty() { Some(lo) } else { None };
        }
        let w = hi.a - lo.a;
        let mut a = if hi.f.is_finite() {
            let den = 2.0 * (hi.f - lo.f - lo.dphi * w);
            if den > 0.0 { lo.a - lo.dphi * w * w / den } else { lo.a + 0.5 * w }
        } else {
            lo.a + 0.1 * w
        };
        let (l, h) = (lo.a.min(hi.a), lo.a.max(hi.a));
        let margin = 0.1 * (h - l);
        if !(a > l + margin && a < h - margin) {
            a = 0.5 * (lo.a + hi.a);
        }
        let t = eval(a, xt, evals);
        if !t.f.is_finite() || t.f > f0 + C1 * a * dphi0 || t.f >= lo.f {
            hi = t;
        } else {
            if t.dphi.abs() <= -C2 * dphi0 {
                return Some(t);
            }
            if t.dphi * (hi.a - lo.a) >= 0.0 {
                hi = lo;
            }
            lo = t;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rosenbrock_and_an_infeasible_region() {
        let rosen = |x: &[f64], g: &mut [f64]| {
            let n = x.len();
            let mut f = 0.0;
            g.iter_mut().for_each(|v| *v = 0.0);
            for i in 0..n - 1 {
                let a = x[i + 1] - x[i] * x[i];
                let b = 1.0 - x[i];
                f += 100.0 * a * a + b * b;
                g[i] += -400.0 * a * x[i] - 2.0 * b;
                g[i + 1] += 200.0 * a;
            }
            f
        };
        let x0 = vec![-1.2; 20];
        let opts = LbfgsOptions { max_iters: 2000, max_evals: 4000, ..Default::default() };
        let m = minimize(rosen, &x0, &opts).unwrap();
        // The learning curve starts at the start and never goes up.
        assert_eq!(m.history.len(), m.iters + 1);
        assert!(m.history.windows(2).all(|w| w[1] <= w[0]));
        assert!(m.x.iter().all(|v| (v - 1.0).abs() < 1e-4), "{m:?}");
        // log barrier: f = x - ln(x) is infinite for x <= 0; minimum at x = 1.
        let barrier = |x: &[f64], g: &mut [f64]| {
            if x[0] <= 0.0 {
                return f64::INFINITY;
            }
            g[0] = 1.0 - 1.0 / x[0];
            x[0] - x[0].ln()
        };
        let m = minimize(barrier, &[20.0], &LbfgsOptions::default()).unwrap();
        assert!((m.x[0] - 1.0).abs() < 1e-5, "{m:?}");
        assert!(minimize(barrier, &[-1.0], &LbfgsOptions::default()).is_err());
    }
}
