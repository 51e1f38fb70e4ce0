//! `surfcap eval gpdm`: a Gaussian-process dynamical model of a subject's motion (thesis 6.4-6.5,
//! eq. 6.1-6.13) with what shows whether it learnt: the learning curve, the latent trajectories
//! with HMC-sampled variations, and the training-frame reconstruction error against PCA with as
//! many components as latent dimensions (Fig. 6.4). `surfcap_eval::gpdm_eval` computes it; this
//! command writes the plots, `latent.npy`, the model and the report, and prints the summary.

use std::path::{Path, PathBuf};

use surfcap_eval::gpdm_eval::{GpdmEvalOptions, gpdm_eval};
use surfcap_learn::Mat;
use surfcap_mesh::Subject;
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{SeedOpt, SubjectArgs};
use crate::output::write_json;

/// The learning curve and the latent trajectories (dimensions 1 and 2) with the HMC variations.
fn plots(
    dir: &Path,
    name: &str,
    history: &[f64],
    latents: &[(String, &Mat<f64>)],
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

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Sequences to learn (comma-separated; default: all, sharing one latent space, 6.5.2).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    /// Vertices describing a frame (evenly spaced over the mesh).
    #[arg(long, default_value_t = 300, value_parser = crate::options::count)]
    pub vertices: usize,
    /// Frames at most (longer subjects are subsampled in time by one stride).
    #[arg(long, default_value_t = 400, value_parser = |s: &str| crate::options::at_least(s, 4))]
    pub max_frames: usize,
    /// Latent dimension d.
    #[arg(long, default_value_t = 3, value_parser = crate::options::count)]
    pub latent_dim: usize,
    /// HMC latent trajectories to sample, 0 (none) to 1000.
    #[arg(long, default_value_t = 3, value_parser = |s: &str| crate::options::whole_in(s, 0, 1000))]
    pub samples: usize,
    /// L-BFGS iterations at most, 1 to 10000 (default 400; as `vary train --iterations`).
    #[arg(long, value_parser = |s: &str| crate::options::whole_in(s, 1, 10_000))]
    pub iterations: Option<usize>,
    #[command(flatten)]
    pub seed: SeedOpt,
    /// Folder for gpdm.json, the plots, latent.npy and the model.
    #[arg(short, long, default_value = "gpdm-eval")]
    pub output: PathBuf,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.subject.path], "eval-gpdm")?;
    let Args { sequences, vertices, max_frames, latent_dim, samples, iterations, seed, output, subject } = a;
    let opts = GpdmEvalOptions { sequences, vertices, max_frames, latent_dim, samples, seed: seed.seed, iterations };
    evaluate(ctx, &subject.open(ctx)?, &opts, &output)?;
    ctx.commit(outs)
}

fn evaluate(ctx: &crate::Ctx, s: &Subject, opts: &GpdmEvalOptions, output: &Path) -> anyhow::Result<()> {
    let r = gpdm_eval(s, opts)?;
    std::fs::create_dir_all(output).map_err(|e| anyhow::anyhow!("creating {}: {e}", output.display()))?;
    let latents: Vec<(String, &Mat<f64>)> = r.sequences.iter().map(|q| q.name.clone()).zip(r.latents.iter()).collect();
    let mut written = plots(output, &r.subject, &r.fit.history, &latents, &r.trajectories)?;
    let latent_path = output.join("latent.npy");
    // Written in the folder's temporary (`save_npy` does not go through `surfcap_mesh::atomic`).
    surfcap_learn::matrix::save_npy(&surfcap_mesh::output_set::write_place(&latent_path), r.model.latent())?;
    written.push(latent_path);
    let model_path = output.join("gpdm.model.json");
    write_json(&model_path, &r.model)?;
    written.push(model_path);
    let (report, rp) = super::folder::save_report(output, "gpdm.json", &r, "written", &written)?;
    ctx.result(&report, || {
        let (fit, e) = (&r.fit, &r.training_mean_vertex_error);
        let n: usize = r.sequences.iter().map(|q| q.frames).sum();
        println!(
            "GPDM of {} ({n} frames, stride {}, {} vertices, d = {}): fit {:.1} s, {} iterations{}, objective {:.1} -> {:.1}",
            r.subject,
            r.frame_stride,
            r.vertices,
            r.latent_dim,
            r.fit_seconds,
            fit.iters,
            if fit.converged { "" } else { " (iteration budget reached)" },
            fit.initial_objective,
            fit.objective
        );
        println!(
            "training frames, mean vertex error: GPDM {:.5}, PCA with {} components {:.5} ({})",
            e.gpdm,
            r.latent_dim,
            e.pca,
            if e.gpdm < e.pca { "GPDM better, as in Fig. 6.4" } else { "PCA better" }
        );
        if let Some(h) = &r.hmc {
            println!(
                "HMC: {} latent trajectories of {} frames in {:.1} s, acceptance {:.2}, {} divergences",
                h.samples, h.frames, h.seconds, h.acceptance_rate, h.divergences
            );
        }
        println!("wrote {} and {} more files in {}", rp.display(), written.len(), output.display());
    });
    Ok(())
}
