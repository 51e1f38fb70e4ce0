//! `surfcap-bench learn`: the speed targets of the learning toolkit (surfcap-learn, thesis
//! chapters 5-6) on 2 cores: GP regression with fitted hyper-parameters plus prediction on
//! 2,000 points of 20 dimensions (target < 5 s; the fit starts from the median-distance guess,
//! whose cost is included), one GPDM fit on 400 frames of ~3,000
//! coordinates (the procedural mannequin walking and jogging, 1,000 vertices; target < 60 s),
//! and 20 HMC samples of 100-frame latent trajectories from that GPDM (target < 30 s).

use std::time::Instant;

use faer::Mat;
use rand::{Rng, SeedableRng};
use serde_json::json;
use surfcap_learn::gp_regression::{GpFitOptions, GpRegression, squared_exponential_guess};
use surfcap_learn::gpdm::{Gpdm, GpdmOptions};
use surfcap_learn::hybrid_monte_carlo::{HmcOptions, standard_normal};
use surfcap_learn::kernels::Kernel;
use surfcap_learn::pca::{Pca, PcaMethod};

use crate::measure::verdict;
use crate::options::SeedOpt;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// GP training points.
    #[arg(long, default_value_t = 2000, value_parser = crate::options::count)]
    pub gp_points: usize,
    /// GP input dimensions.
    #[arg(long, default_value_t = 20, value_parser = crate::options::count)]
    pub gp_dims: usize,
    /// Random restarts of the GP hyper-parameter fit (besides the first start), screened on 500
    /// points before the best is refined on all of them.
    /// At most 100 (each restart is a fit of its own).
    #[arg(long, default_value_t = 2, value_parser = |s: &str| crate::options::whole_in(s, 0, 100))]
    pub gp_restarts: usize,
    /// GPDM frames (two sequences: walk and jog).
    #[arg(long, default_value_t = 400, value_parser = crate::options::count)]
    pub frames: usize,
    /// Mannequin vertices (3 coordinates each).
    #[arg(long, default_value_t = 1000, value_parser = crate::options::count)]
    pub vertices: usize,
    /// HMC trajectory samples.
    #[arg(long, default_value_t = 20, value_parser = crate::options::count)]
    pub hmc_samples: usize,
    /// Frames per sampled trajectory.
    #[arg(long, default_value_t = 100, value_parser = crate::options::count)]
    pub hmc_frames: usize,
    #[command(flatten)]
    pub seed: SeedOpt,
}

pub fn run(ctx: &crate::Ctx, a: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(a.gp_points >= 10 && a.gp_dims >= 1, "--gp-points >= 10 and --gp-dims >= 1 expected");
    anyhow::ensure!(a.frames >= 20 && a.hmc_frames >= 2 && a.hmc_samples >= 1, "--frames >= 20, --hmc-frames >= 2");
    // Sized before faer allocates: the GP's n x n kernel, its factor and gradient matrices
    // (about six f64 matrices) and inputs; the GPDM's data (f64, 3 per vertex) and its latent
    // kernels (frames x frames); the HMC's trajectories.
    let (n, d, f, v) = (a.gp_points as f64, a.gp_dims as f64, a.frames as f64, a.vertices as f64);
    let memory = n * n * 8.0 * 6.0
        + n * d * 8.0
        + f * v * 3.0 * 8.0 * 4.0
        + f * f * 8.0 * 6.0
        + a.hmc_samples as f64 * a.hmc_frames as f64 * 8.0 * 16.0;
    let what =
        format!("--gp-points {} --gp-dims {} --frames {} --vertices {}", a.gp_points, a.gp_dims, a.frames, a.vertices);
    crate::check_size(ctx, what, memory, 0.0, "--gp-points, --gp-dims, --frames, --vertices or --hmc-samples")?;
    // 1. GP regression: y = sin(x . w1) + 0.5 cos(x . w2) + noise (sd 0.1), inputs in [-1, 1]^d.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed.seed);
    let (n, d) = (a.gp_points, a.gp_dims);
    let w1: Vec<f64> = (0..d).map(|_| rng.random_range(-1.0..1.0) / (d as f64).sqrt()).collect();
    let w2: Vec<f64> = (0..d).map(|_| rng.random_range(-1.0..1.0) / (d as f64).sqrt()).collect();
    let f = |x: &[f64]| {
        let (a1, a2): (f64, f64) =
            (x.iter().zip(&w1).map(|(u, v)| u * v).sum(), x.iter().zip(&w2).map(|(u, v)| u * v).sum());
        (2.0 * a1).sin() + 0.5 * (3.0 * a2).cos()
    };
    let x = Mat::from_fn(n, d, |_, _| rng.random_range(-1.0..1.0));
    let y = Mat::from_fn(n, 1, |i, _| {
        let row: Vec<f64> = (0..d).map(|j| x[(i, j)]).collect();
        f(&row) + 0.1 * standard_normal(&mut rng)
    });
    let xt = Mat::from_fn(1000, d, |_, _| rng.random_range(-1.0..1.0));
    let t0 = Instant::now();
    let opts = GpFitOptions { restarts: a.gp_restarts, seed: a.seed.seed, ..Default::default() };
    let (k0, noise0) = squared_exponential_guess(x.as_ref(), y.as_ref())?;
    let (gp, rep) = GpRegression::fit(k0, noise0, x, y, &opts)?;
    let t_fit = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let p = gp.predict(xt.as_ref())?;
    let t_pred = t1.elapsed().as_secs_f64();
    let gp_secs = t_fit + t_pred;
    let mut se = 0.0;
    let mut z2 = 0.0;
    for i in 0..xt.nrows() {
        let row: Vec<f64> = (0..d).map(|j| xt[(i, j)]).collect();
        let e = p.mean[(i, 0)] - f(&row);
        se += e * e;
        z2 += e * e / p.latent_variance[i].max(1e-300);
    }
    let rmse = (se / xt.nrows() as f64).sqrt();
    let (log_var, log_len) = match gp.kernel() {
        Kernel::SquaredExponential { log_variance, log_length_scale } => (*log_variance, *log_length_scale),
        _ => (f64::NAN, f64::NAN),
    };

    // 2. GPDM on the procedural mannequin (walk + jog), each frame centred on its centroid.
    use surfcap_builtin::locomotion::Gait;
    use surfcap_builtin::mannequin::{BodyShape, mannequin};
    use surfcap_builtin::mannequin_subject::Clip;
    let m = mannequin(&BodyShape::average(), a.vertices)?;
    let fps = 30.0;
    let halves = [a.frames / 2, a.frames - a.frames / 2];
    let mut seqs = Vec::new();
    for (k, (gait, frames)) in [Gait::Walk, Gait::Jog].into_iter().zip(halves).enumerate() {
        let clip = Clip::procedural(&m, gait, fps, frames as f64 / fps + 0.5, a.seed.seed + k as u64)?;
        anyhow::ensure!(clip.poses.len() >= frames, "procedural clip shorter than {frames} frames");
        let nv = m.topology.n_vertices();
        let mut y = Mat::zeros(frames, 3 * nv);
        for (i, w) in clip.poses[..frames].iter().enumerate() {
            let pos = m.pose(w);
            let mut c = [0.0f64; 3];
            for v in pos.chunks_exact(3) {
                for k in 0..3 {
                    c[k] += v[k] as f64 / nv as f64;
                }
            }
            for (j, v) in pos.iter().enumerate() {
                y[(i, j)] = *v as f64 - c[j % 3];
            }
        }
        seqs.push(y);
    }
    let refs: Vec<_> = seqs.iter().map(|s| s.as_ref()).collect();
    let dims = seqs[0].ncols();
    let t2 = Instant::now();
    let (gpdm, grep) = Gpdm::fit(&refs, &GpdmOptions::default())?;
    let gpdm_secs = t2.elapsed().as_secs_f64();
    let (rec, _) = gpdm.reconstruct(gpdm.latent())?;
    let mut all = Mat::zeros(a.frames, dims);
    let mut at = 0;
    for s in &seqs {
        for i in 0..s.nrows() {
            for j in 0..dims {
                all[(at + i, j)] = s[(i, j)];
            }
        }
        at += s.nrows();
    }
    let pca = Pca::fit(all.as_ref(), 3, PcaMethod::Auto)?;
    let prec = pca.reconstruct(pca.project(all.as_ref())?.as_ref())?;
    let vertex_err = |r: &Mat<f64>| {
        let mut s = 0.0;
        for i in 0..all.nrows() {
            for v in 0..dims / 3 {
                s += (0..3).map(|k| (r[(i, 3 * v + k)] - all[(i, 3 * v + k)]).powi(2)).sum::<f64>().sqrt();
            }
        }
        s / (all.nrows() * (dims / 3)) as f64
    };
    let (err_gpdm, err_pca) = (vertex_err(&rec), vertex_err(&prec));

    // 3. HMC: whole trajectories conditioned on the first latent point of the walk.
    let x1: Vec<f64> = (0..gpdm.latent_dim()).map(|j| gpdm.latent()[(0, j)]).collect();
    let hopts = HmcOptions { warmup: 100, samples: a.hmc_samples, thin: 3, seed: a.seed.seed, ..Default::default() };
    let t3 = Instant::now();
    let (trajs, chain) = gpdm.sample_trajectories(&x1, a.hmc_frames, &hopts)?;
    let hmc_secs = t3.elapsed().as_secs_f64();

    let report = json!({
        "threads": rayon::current_num_threads(),
        "gp": {
            "points": n, "dims": d, "fit_seconds": t_fit, "predict_seconds": t_pred, "seconds": gp_secs,
            "target_seconds": 5.0, "target": verdict(gp_secs, 5.0), "evaluations": rep.evals,
            "full_data_evaluations": rep.full_data_evals, "restarts": a.gp_restarts,
            "length_scale": log_len.exp(), "signal_variance": log_var.exp(), "noise_variance": gp.noise_variance(),
            "test_rmse": rmse, "test_mean_squared_z": z2 / xt.nrows() as f64,
        },
        "gpdm": {
            "frames": a.frames, "dims": dims, "latent_dim": gpdm.latent_dim(), "seconds": gpdm_secs,
            "target_seconds": 60.0, "target": verdict(gpdm_secs, 60.0), "iterations": grep.iters,
            "evaluations": grep.evals, "converged": grep.converged, "objective_start": grep.initial_objective,
            "objective": grep.objective, "mean_vertex_error_m": err_gpdm, "pca3_mean_vertex_error_m": err_pca,
        },
        "hmc": {
            "samples": trajs.len(), "frames": a.hmc_frames, "seconds": hmc_secs, "target_seconds": 30.0,
            "target": verdict(hmc_secs, 30.0), "acceptance_rate": chain.acceptance_rate,
            "step_size": chain.step_size, "leapfrog_steps": chain.leapfrog_steps,
            "divergences": chain.divergences, "gradient_evaluations": chain.gradient_evals,
        },
    });
    ctx.result(&report, || {
        println!(
            "GP regression, {n} x {d}: fit with {} restarts {t_fit:.2} s ({} evaluations, {} on all points) + prediction of 1,000 points {t_pred:.3} s = {gp_secs:.2} s (target 5 s: {}); length scale {:.3}, noise variance {:.4} (true 0.01), test RMSE {rmse:.4}",
            a.gp_restarts,
            rep.evals,
            rep.full_data_evals,
            verdict(gp_secs, 5.0),
            log_len.exp(),
            gp.noise_variance()
        );
        println!(
            "GPDM, {} frames x {dims} coordinates, d = {}: fit {gpdm_secs:.2} s (target 60 s: {}), {} iterations, {} evaluations; mean vertex error of the training frames {:.3} mm (PCA with 3 components: {:.3} mm)",
            a.frames,
            gpdm.latent_dim(),
            verdict(gpdm_secs, 60.0),
            grep.iters,
            grep.evals,
            1000.0 * err_gpdm,
            1000.0 * err_pca
        );
        println!(
            "HMC, {} trajectories of {} frames: {hmc_secs:.2} s (target 30 s: {}); acceptance rate {:.3}, step {:.4}, {} leapfrog steps, {} divergences",
            trajs.len(),
            a.hmc_frames,
            verdict(hmc_secs, 30.0),
            chain.acceptance_rate,
            chain.step_size,
            chain.leapfrog_steps,
            chain.divergences
        );
    });
    Ok(())
}
