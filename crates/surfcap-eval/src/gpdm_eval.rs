//! A Gaussian-process dynamical model of a subject's motion (thesis 6.4-6.5, eq. 6.1-6.13) with
//! what shows whether it learnt: the learning curve, the latent trajectories with HMC-sampled
//! variations, and the training-frame reconstruction error against PCA with as many components
//! as latent dimensions (Fig. 6.4).
//!
//! Frames are described by a few hundred evenly spaced vertices, each frame centred on its
//! centroid (the thesis aligns frames rigidly before learning, 6.4.1; centring removes the
//! travel, the heading is kept). Subjects longer than `max_frames` are subsampled in time by
//! one stride for every sequence (reported), which keeps the O(N^3) fit bounded.

use std::time::Instant;

use serde::Serialize;
use surfcap_learn::Mat;
use surfcap_learn::gpdm::{Gpdm, GpdmFitReport, GpdmOptions};
use surfcap_learn::hybrid_monte_carlo::HmcOptions;
use surfcap_learn::pca::{Pca, PcaMethod};
use surfcap_mesh::Subject;

use crate::error::{Error, Result};

/// Options of [`gpdm_eval`] (`surfcap eval gpdm`).
#[derive(Debug, Clone)]
pub struct GpdmEvalOptions {
    /// Sequences to learn (empty: all, sharing one latent space, 6.5.2).
    pub sequences: Vec<String>,
    /// Vertices describing a frame (evenly spaced over the mesh), >= 1.
    pub vertices: usize,
    /// Frames at most (longer subjects are subsampled in time by one stride), >= 4.
    pub max_frames: usize,
    /// Latent dimension d, >= 1.
    pub latent_dim: usize,
    /// HMC latent trajectories to sample (0: none).
    pub samples: usize,
    /// Seed of the HMC chain.
    pub seed: u64,
    /// L-BFGS iterations at most (`None`: the library's default).
    pub iterations: Option<usize>,
}

/// A learnt sequence and its frames after the stride.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceFrames {
    pub name: String,
    pub frames: usize,
}

/// Mean distance between corresponding vertices of the training frames and their
/// reconstructions (Fig. 6.4).
#[derive(Debug, Clone, Serialize)]
pub struct TrainingError {
    /// GPDM reconstruction at the learnt latents (eq. 6.12-6.13).
    pub gpdm: f64,
    /// PCA with as many components as latent dimensions.
    pub pca: f64,
    /// Variance the PCA components explain (fraction).
    pub pca_explained_variance: f64,
}

/// The HMC chain that sampled latent trajectories from the first sequence's x1.
#[derive(Debug, Clone, Serialize)]
pub struct HmcSummary {
    /// Trajectories returned.
    pub samples: usize,
    /// Frames per trajectory (the first sequence's length).
    pub frames: usize,
    pub acceptance_rate: f64,
    pub step_size: f64,
    pub leapfrog_steps: usize,
    pub divergences: usize,
    pub seed: u64,
    pub seconds: f64,
}

/// Result of [`gpdm_eval`]; serialised, the report `gpdm.json` without `written`.
#[derive(Debug, Clone, Serialize)]
pub struct GpdmEval {
    pub subject: String,
    pub sequences: Vec<SequenceFrames>,
    /// Time stride applied to every sequence.
    pub frame_stride: usize,
    /// Vertices describing a frame.
    pub vertices: usize,
    pub latent_dim: usize,
    /// The fit, with its learning curve (`history`, eq. 6.7).
    pub fit: GpdmFitReport,
    pub fit_seconds: f64,
    /// The thesis's alpha and beta of the two kernels ([`Gpdm::thesis_parameters`]).
    pub thesis_alpha_beta: ([f64; 3], [f64; 4]),
    pub training_mean_vertex_error: TrainingError,
    /// `None` when no samples were asked for.
    pub hmc: Option<HmcSummary>,
    /// The fitted model (`gpdm.model.json`; its latent positions are `latent.npy`).
    #[serde(skip)]
    pub model: Gpdm,
    /// Each sequence's latent trajectory (frames x d), in the order of `sequences`.
    #[serde(skip)]
    pub latents: Vec<Mat<f64>>,
    /// The HMC-sampled latent trajectories (frames x d).
    #[serde(skip)]
    pub trajectories: Vec<Mat<f64>>,
}

/// A sequence's name and its frames x (3 x kept vertices) matrix.
type Named = (String, Mat<f64>);

/// One matrix per sequence, the time stride used and the number of vertices kept.
fn training_data(s: &Subject, o: &GpdmEvalOptions) -> Result<(Vec<Named>, usize, usize)> {
    let chosen: Vec<&surfcap_mesh::Sequence> = if o.sequences.is_empty() {
        s.sequences().iter().collect()
    } else {
        o.sequences
            .iter()
            .map(|n| {
                s.sequence(n).map(|(_, q)| q).ok_or_else(|| {
                    let names: Vec<&str> = s.sequences().iter().map(|q| q.name.as_str()).collect();
                    Error::parameter(
                        "--sequences",
                        Some(n.clone()),
                        format!("no such sequence (the subject has {})", names.join(", ")),
                    )
                })
            })
            .collect::<Result<_>>()?
    };
    let total: usize = chosen.iter().map(|q| q.n_frames()).sum();
    if o.max_frames < 4 {
        return Err(Error::parameter("--max-frames", Some(o.max_frames.to_string()), "expected at least 4"));
    }
    if o.vertices < 1 {
        return Err(Error::parameter("--vertices", None, "expected at least 1"));
    }
    let stride = total.div_ceil(o.max_frames).max(1);
    let nv = s.topology().n_vertices();
    let kept: Vec<usize> = (0..o.vertices.min(nv)).map(|k| k * nv / o.vertices.min(nv)).collect();
    let mut out = Vec::new();
    for q in chosen {
        let frames: Vec<usize> = (0..q.n_frames()).step_by(stride).collect();
        if frames.len() < 3 {
            return Err(Error::Unsuitable(format!(
                "sequence {}: {} frames after a stride of {stride}: a dynamical model needs at least 3 (choose --sequences or raise --max-frames)",
                q.name,
                frames.len()
            )));
        }
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

/// Thesis 6.4-6.5 (eq. 6.1-6.13), Fig. 6.4: fits a GPDM to the chosen sequences (one shared
/// latent space), compares its training-frame reconstruction with PCA of as many components,
/// and samples latent trajectories from the first sequence's x1 by seeded HMC.
pub fn gpdm_eval(s: &Subject, o: &GpdmEvalOptions) -> Result<GpdmEval> {
    if o.latent_dim < 1 {
        return Err(Error::parameter("--latent-dim", None, "expected at least 1"));
    }
    let (data, stride, kept) = training_data(s, o)?;
    let refs: Vec<_> = data.iter().map(|(_, y)| y.as_ref()).collect();
    let t0 = Instant::now();
    let mut opts = GpdmOptions { latent_dim: o.latent_dim, ..Default::default() };
    if let Some(n) = o.iterations {
        opts.lbfgs.max_iters = n;
        opts.lbfgs.max_evals = n + n / 4;
    }
    let (gpdm, rep) = Gpdm::fit(&refs, &opts).map_err(Error::learn("fitting the GPDM"))?;
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
    let (rec, _) = gpdm.reconstruct(gpdm.latent()).map_err(Error::learn("reconstructing the training frames"))?;
    let pca =
        Pca::fit(all.as_ref(), o.latent_dim.min(n - 1).max(1), PcaMethod::Auto).map_err(Error::learn("fitting PCA"))?;
    let projected = pca.project(all.as_ref()).map_err(Error::learn("projecting on PCA"))?;
    let prec = pca.reconstruct(projected.as_ref()).map_err(Error::learn("reconstructing from PCA"))?;
    let (e_gpdm, e_pca) = (vertex_error(&rec, &all), vertex_error(&prec, &all));
    // Variations: seeded HMC over whole latent trajectories from the first sequence's x1.
    let x1: Vec<f64> = (0..gpdm.latent_dim()).map(|j| gpdm.latent()[(0, j)]).collect();
    let len = data[0].1.nrows();
    let hmc = HmcOptions { warmup: 300, samples: o.samples, thin: 5, seed: o.seed, ..Default::default() };
    let t1 = Instant::now();
    let (trajectories, chain) = if o.samples > 0 {
        let (t, c) = gpdm.sample_trajectories(&x1, len, &hmc).map_err(Error::learn("sampling latent trajectories"))?;
        (t, Some(c))
    } else {
        (Vec::new(), None)
    };
    let hmc_secs = t1.elapsed().as_secs_f64();
    let latents =
        (0..data.len()).map(|k| gpdm.sequence_latent(k).expect("one latent block per sequence").to_owned()).collect();
    Ok(GpdmEval {
        subject: s.name.clone(),
        sequences: data.iter().map(|(name, y)| SequenceFrames { name: name.clone(), frames: y.nrows() }).collect(),
        frame_stride: stride,
        vertices: kept,
        latent_dim: gpdm.latent_dim(),
        fit: rep,
        fit_seconds: fit_secs,
        thesis_alpha_beta: gpdm.thesis_parameters(),
        training_mean_vertex_error: TrainingError {
            gpdm: e_gpdm,
            pca: e_pca,
            pca_explained_variance: pca.explained_variance_ratio().iter().sum::<f64>(),
        },
        hmc: chain.map(|c| HmcSummary {
            samples: trajectories.len(),
            frames: len,
            acceptance_rate: c.acceptance_rate,
            step_size: c.step_size,
            leapfrog_steps: c.leapfrog_steps,
            divergences: c.divergences,
            seed: o.seed,
            seconds: hmc_secs,
        }),
        model: gpdm,
        latents,
        trajectories,
    })
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::test_subjects::{keys, worm};

    fn options() -> GpdmEvalOptions {
        GpdmEvalOptions {
            sequences: Vec::new(),
            vertices: 20,
            max_frames: 24,
            latent_dim: 2,
            samples: 2,
            seed: 1,
            iterations: Some(40),
        }
    }

    #[test]
    fn a_small_model_learns_and_the_report_is_the_cli_json() {
        let s = worm(30.0);
        let r = gpdm_eval(&s, &options()).unwrap();
        let seqs = s.sequences().len();
        assert_eq!(r.sequences.len(), seqs);
        assert_eq!(r.frame_stride, s.n_frames().div_ceil(24));
        assert_eq!((r.vertices, r.latent_dim), (20, 2));
        let h = &r.fit.history;
        assert!(h.len() > 2 && h.windows(2).all(|w| w[1] <= w[0]), "the learning curve never rises: {h:?}");
        let e = &r.training_mean_vertex_error;
        assert!(e.gpdm.is_finite() && e.pca.is_finite() && e.pca_explained_variance <= 1.0 + 1e-9, "{e:?}");
        assert_eq!(r.latents.len(), seqs);
        for (l, q) in r.latents.iter().zip(&r.sequences) {
            assert_eq!((l.nrows(), l.ncols()), (q.frames, 2));
        }
        let hmc = r.hmc.as_ref().unwrap();
        assert_eq!((hmc.samples, hmc.frames, hmc.seed), (2, r.sequences[0].frames, 1));
        assert_eq!(r.trajectories.len(), 2);
        assert!(r.trajectories.iter().all(|t| (t.nrows(), t.ncols()) == (hmc.frames, 2)));
        // gpdm.json as the CLI wrote it, without "written".
        let cli = json!({
            "subject": s.name,
            "sequences": r.sequences.iter().map(|q| json!({ "name": q.name, "frames": q.frames })).collect::<Vec<_>>(),
            "frame_stride": r.frame_stride, "vertices": 20, "latent_dim": 2,
            "fit": r.fit, "fit_seconds": r.fit_seconds,
            "thesis_alpha_beta": r.model.thesis_parameters(),
            "training_mean_vertex_error": { "gpdm": e.gpdm, "pca": e.pca, "pca_explained_variance": e.pca_explained_variance },
            "hmc": {
                "samples": 2, "frames": hmc.frames, "acceptance_rate": hmc.acceptance_rate, "step_size": hmc.step_size,
                "leapfrog_steps": hmc.leapfrog_steps, "divergences": hmc.divergences, "seed": 1, "seconds": hmc.seconds,
            },
        });
        assert_eq!(serde_json::to_value(&r).unwrap(), cli);
        // Without samples, "hmc" is null.
        let r = gpdm_eval(&s, &GpdmEvalOptions { samples: 0, ..options() }).unwrap();
        let v = serde_json::to_value(&r).unwrap();
        assert!(v["hmc"].is_null() && keys(&v).contains(&"hmc"));
    }

    #[test]
    fn options_are_named_in_errors() {
        let s = worm(30.0);
        let e = |o: GpdmEvalOptions| gpdm_eval(&s, &o).unwrap_err().to_string();
        assert_eq!(e(GpdmEvalOptions { latent_dim: 0, ..options() }), "--latent-dim: expected at least 1");
        assert_eq!(e(GpdmEvalOptions { max_frames: 3, ..options() }), "--max-frames 3: expected at least 4");
        assert_eq!(e(GpdmEvalOptions { vertices: 0, ..options() }), "--vertices: expected at least 1");
        let missing = e(GpdmEvalOptions { sequences: vec!["nope".into()], ..options() });
        assert!(missing.starts_with("--sequences nope: no such sequence (the subject has "), "{missing}");
        assert!(missing.contains(&s.sequences()[0].name));
        let few = e(GpdmEvalOptions { max_frames: 4, ..options() });
        assert!(few.contains("a dynamical model needs at least 3"), "{few}");
    }
}
