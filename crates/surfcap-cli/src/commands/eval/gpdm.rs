//! `surfcap eval gpdm`: a Gaussian-process dynamical model of a subject's motion (thesis 6.4-6.5,
//! eq. 6.1-6.13) with what shows whether it learnt: the learning curve, the latent trajectories
//! with HMC-sampled variations, and the training-frame reconstruction error against PCA with as
//! many components as latent dimensions (Fig. 6.4).
//!
//! Frames are described by a few hundred evenly spaced vertices, each frame centred on its
//! centroid (the thesis aligns frames rigidly before learning, 6.4.1; centring removes the
//! travel, the heading is kept). Subjects longer than `--max-frames` are subsampled in time by
//! one stride for every sequence (reported), which keeps the O(N^3) fit bounded.

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde_json::json;
use surfcap_learn::Mat;
use surfcap_learn::gpdm::{Gpdm, GpdmOptions};
use surfcap_learn::hybrid_monte_carlo::HmcOptions;
use surfcap_learn::pca::{Pca, PcaMethod};
use surfcap_mesh::Subject;
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{SourceOpts, open};
use crate::output::print_json;

#[derive(Debug)]
pub struct Opts {
    pub sequences: Vec<String>,
    pub vertices: usize,
    pub max_frames: usize,
    pub latent_dim: usize,
    pub samples: usize,
    pub seed: u64,
    /// L-BFGS iterations at most (None: the library's default).
    pub iterations: Option<usize>,
    pub output: PathBuf,
}

/// A sequence's name and its frames x (3 x kept vertices) matrix.
type Named = (String, Mat<f64>);

/// One matrix per sequence, the time stride used and the number of vertices kept.
fn training_data(s: &Subject, o: &Opts) -> anyhow::Result<(Vec<Named>, usize, usize)> {
    let chosen: Vec<&surfcap_mesh::Sequence> = if o.sequences.is_empty() {
        s.sequences().iter().collect()
    } else {
        o.sequences
            .iter()
            .map(|n| {
                s.sequence(n).map(|(_, q)| q).ok_or_else(|| {
                    let names: Vec<&str> = s.sequences().iter().map(|q| q.name.as_str()).collect();
                    anyhow::anyhow!("--sequences {n}: no such sequence (the subject has {})", names.join(", "))
                })
            })
            .collect::<anyhow::Result<_>>()?
    };
    let total: usize = chosen.iter().map(|q| q.n_frames()).sum();
    anyhow::ensure!(o.max_frames >= 4, "--max-frames {}: expected at least 4", o.max_frames);
    anyhow::ensure!(o.vertices >= 1, "--vertices: expected at least 1");
    let stride = total.div_ceil(o.max_frames).max(1);
    let nv = s.topology().n_vertices();
    let kept: Vec<usize> = (0..o.vertices.min(nv)).map(|k| k * nv / o.vertices.min(nv)).collect();
    let mut out = Vec::new();
    for q in chosen {
        let frames: Vec<usize> = (0..q.n_frames()).step_by(stride).collect();
        anyhow::ensure!(
            frames.len() >= 3,
            "sequence {}: {} frames after a stride of {stride}: a dynamical model needs at least 3 (choose --sequences or raise --max-frames)",
            q.name,
            frames.len()
        );
        let mut y = Mat::<f64>::zeros(frames.len(), 3 * kept.len());
        for (i, &f) in frames.iter().enumerate() {
            let p = q.frame(f);
            let c = surfcap_motion::blend::centre(p);
            for (col, &v) in kept.iter().enumerate() {
                for k in 0..3 {
                    y[(i, 3 * col + k)] = p[3 * v + k] as f64 - c[k];
                }
            }
        }
        out.push((q.name.clone(), y));
    }
    Ok((out, stride, kept.len()))
}

/// Mean distance between corresponding vertices of two frames x (3 x vertices) matrices.
fn vertex_error(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let (n, m) = (a.nrows(), a.ncols() / 3);
    let mut sum = 0.0;
    for i in 0..n {
        for v in 0..m {
            sum += (0..3).map(|k| (a[(i, 3 * v + k)] - b[(i, 3 * v + k)]).powi(2)).sum::<f64>().sqrt();
        }
    }
    sum / (n * m).max(1) as f64
}

fn plots(
    dir: &Path,
    name: &str,
    history: &[f64],
    latents: &[Named],
    samples: &[Mat<f64>],
) -> anyhow::Result<Vec<PathBuf>> {
    let palette = [(31, 95, 191), (208, 48, 48), (46, 158, 68), (224, 138, 0), (120, 60, 170), (90, 90, 90)];
    let curve = LineChart {
        title: format!("{name}: GPDM learning curve (negative log posterior, eq. 6.7)"),
        x_label: "L-BFGS iteration".into(),
        y_label: "objective".into(),
        series: vec![Series {
            name: String::new(),
            points: history.iter().enumerate().map(|(k, &f)| (k as f64, f)).collect(),
            color: palette[0],
            dashed: false,
            markers: false,
        }],
    };
    let mut written = write_line_chart(&dir.join("learning_curve"), &curve)?;
    let two = |m: &Mat<f64>| -> Vec<(f64, f64)> {
        (0..m.nrows()).map(|i| (m[(i, 0)], if m.ncols() > 1 { m[(i, 1)] } else { i as f64 })).collect()
    };
    let mut series: Vec<Series> = latents
        .iter()
        .enumerate()
        .map(|(k, (n, x))| Series {
            name: n.clone(),
            points: two(x),
            color: palette[k % palette.len()],
            dashed: false,
            markers: false,
        })
        .collect();
    for (k, t) in samples.iter().enumerate() {
        series.push(Series {
            name: if k == 0 { "HMC variations (from the first sequence's x1)".into() } else { String::new() },
            points: two(t),
            color: (150, 150, 150),
            dashed: true,
            markers: false,
        });
    }
    let latent = LineChart {
        title: format!("{name}: latent trajectories (dimensions 1 and 2)"),
        x_label: "x1".into(),
        y_label: "x2".into(),
        series,
    };
    written.extend(write_line_chart(&dir.join("latent"), &latent)?);
    Ok(written)
}

pub fn run(ctx: &crate::Ctx, path: &Path, source: &SourceOpts, o: &Opts) -> anyhow::Result<()> {
    let s = open(ctx, path, source)?;
    anyhow::ensure!(o.latent_dim >= 1, "--latent-dim: expected at least 1");
    let (data, stride, kept) = training_data(&s, o)?;
    let refs: Vec<_> = data.iter().map(|(_, y)| y.as_ref()).collect();
    let t0 = std::time::Instant::now();
    let mut opts = GpdmOptions { latent_dim: o.latent_dim, ..Default::default() };
    if let Some(n) = o.iterations {
        opts.lbfgs.max_iters = n;
        opts.lbfgs.max_evals = n + n / 4;
    }
    let (gpdm, rep) = Gpdm::fit(&refs, &opts).context("fitting the GPDM")?;
    let fit_secs = t0.elapsed().as_secs_f64();
    // Training frames: GPDM reconstruction (eq. 6.12-6.13 at the learnt latents) vs PCA.
    let n: usize = data.iter().map(|(_, y)| y.nrows()).sum();
    let all = Mat::from_fn(n, data[0].1.ncols(), |i, j| {
        let mut i = i;
        for (_, y) in &data {
            if i < y.nrows() {
                return y[(i, j)];
            }
            i -= y.nrows();
        }
        unreachable!("row index below the total")
    });
    let (rec, _) = gpdm.reconstruct(gpdm.latent()).context("reconstructing the training frames")?;
    let pca = Pca::fit(all.as_ref(), o.latent_dim.min(n - 1).max(1), PcaMethod::Auto).context("fitting PCA")?;
    let prec = pca.reconstruct(pca.project(all.as_ref())?.as_ref())?;
    let (e_gpdm, e_pca) = (vertex_error(&rec, &all), vertex_error(&prec, &all));
    // Variations: seeded HMC over whole latent trajectories from the first sequence's x1.
    let x1: Vec<f64> = (0..gpdm.latent_dim()).map(|j| gpdm.latent()[(0, j)]).collect();
    let len = data[0].1.nrows();
    let hmc = HmcOptions { warmup: 300, samples: o.samples, thin: 5, seed: o.seed, ..Default::default() };
    let t1 = std::time::Instant::now();
    let (samples, chain) = if o.samples > 0 {
        let (t, c) = gpdm.sample_trajectories(&x1, len, &hmc).context("sampling latent trajectories")?;
        (t, Some(c))
    } else {
        (Vec::new(), None)
    };
    let hmc_secs = t1.elapsed().as_secs_f64();
    std::fs::create_dir_all(&o.output).with_context(|| format!("creating {}", o.output.display()))?;
    let latents: Vec<Named> = (0..data.len())
        .map(|k| (data[k].0.clone(), gpdm.sequence_latent(k).expect("one latent block per sequence").to_owned()))
        .collect();
    let mut written = plots(&o.output, &s.name, &rep.history, &latents, &samples)?;
    let latent_path = o.output.join("latent.npy");
    surfcap_learn::matrix::save_npy(&latent_path, gpdm.latent())?;
    written.push(latent_path);
    let model_path = o.output.join("gpdm.model.json");
    surfcap_mesh::atomic::write_file(&model_path, |w| {
        serde_json::to_writer(&mut *w, &gpdm).map_err(std::io::Error::other)
    })?;
    written.push(model_path);
    let report = json!({
        "subject": s.name,
        "sequences": data.iter().map(|(n, y)| json!({ "name": n, "frames": y.nrows() })).collect::<Vec<_>>(),
        "frame_stride": stride, "vertices": kept, "latent_dim": gpdm.latent_dim(),
        "fit": rep, "fit_seconds": fit_secs,
        "thesis_alpha_beta": gpdm.thesis_parameters(),
        "training_mean_vertex_error": { "gpdm": e_gpdm, "pca": e_pca, "pca_explained_variance": pca.explained_variance_ratio().iter().sum::<f64>() },
        "hmc": chain.as_ref().map(|c| json!({
            "samples": samples.len(), "frames": len, "acceptance_rate": c.acceptance_rate, "step_size": c.step_size,
            "leapfrog_steps": c.leapfrog_steps, "divergences": c.divergences, "seed": o.seed, "seconds": hmc_secs,
        })),
        "written": written,
    });
    let rp = o.output.join("gpdm.json");
    surfcap_mesh::atomic::write_file(&rp, |w| {
        serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)
    })?;
    if ctx.json {
        print_json(&report);
    } else {
        println!(
            "GPDM of {} ({} frames, stride {stride}, {kept} vertices, d = {}): fit {fit_secs:.1} s, {} iterations{}, objective {:.1} -> {:.1}",
            s.name,
            n,
            gpdm.latent_dim(),
            rep.iters,
            if rep.converged { "" } else { " (iteration budget reached)" },
            rep.initial_objective,
            rep.objective
        );
        println!(
            "training frames, mean vertex error: GPDM {e_gpdm:.5}, PCA with {} components {e_pca:.5} ({})",
            gpdm.latent_dim(),
            if e_gpdm < e_pca { "GPDM better, as in Fig. 6.4" } else { "PCA better" }
        );
        if let Some(c) = &chain {
            println!(
                "HMC: {} latent trajectories of {len} frames in {hmc_secs:.1} s, acceptance {:.2}, {} divergences",
                samples.len(),
                c.acceptance_rate,
                c.divergences
            );
        }
        println!("wrote {} and {} more files in {}", rp.display(), written.len(), o.output.display());
    }
    Ok(())
}
