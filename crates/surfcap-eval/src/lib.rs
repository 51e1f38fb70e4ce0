//! Evaluations of surfcap's algorithms against ground truth and baselines: the computations
//! behind `surfcap eval ...`, one file each, each a function returning a typed `Serialize` result
//! whose JSON is the front end's report minus the files it writes, plus the data it prints and
//! plots (sampled curves, matrices, warps, fitted models) in `#[serde(skip)]` fields. They never
//! print, open files (except [`interchange_eval()`], which writes into the scratch folder it is
//! given) or draw.
//!
//! Statistics (thesis 2.3.2): the skeleton ground-truth pose distance ([`skeleton_distance`], eq.
//! 2.15-2.16), Pearson correlation (eq. 2.18) and distance correlation (eq. 2.19-2.22, O(P log P)
//! row means plus one O(P^2) pass, no P x P matrix) in [`correlation`], the Mantel permutation
//! test and correlogram ([`mantel_test`], per-permutation seeded streams). Pairwise distances are
//! passed as the condensed upper triangle of an N x N matrix (`i < j`, row by row), as in scipy's
//! `squareform`.
//!
//! Experiments:
//! - [`interpolation_eval()`]: linear vs non-linear interpolation (2.4, Fig. 2.8);
//! - [`pose_metric_eval()`]: our and the Euclidean distance against the skeleton (2.3.2, Fig.
//!   2.5-2.7);
//! - [`transition_costs_eval()`]: standard vs DTW vs DTW + variable lengths (2.5.5, Fig. 2.15);
//! - [`graph_comparison_eval()`]: essential vs motion graph (3.3.3, Fig. 3.2 and 3.8);
//! - [`sparse_graph_eval`]: the sparse essential graph against the exact one per k (pair costs,
//!   unreachable pairs, build times, path and key-pose queries), on the CMU-driven mannequin;
//! - [`root_motion_eval()`]: root motion from ground contacts against the real travel of BVH clips
//!   on the mannequin;
//! - [`transfer_eval`]: motion transfer against ground truth (5.7, Fig. 5.8-5.10: learning curves of
//!   GP-NN/SE/linear and Baran et al., whole body vs parts, unseen motions, seams, cat/lion);
//! - [`interchange_eval()`]: every sequence of a data folder through Alembic and USD and back,
//!   compared to the bit;
//! - [`smg_eval`]: Huang et al. 2009's Table 1 (per key pair distance/time errors, smoothness, CPU
//!   time) on the CMU-driven mannequin, shared topology or re-meshed; [`smg_comparison`]: the
//!   essential graph's distance-and-time search on the same key frames and targets;
//!   [`transition_measures`]: the two measures both engines' transitions get (triangularly weighted
//!   Hausdorff distance and deformation distance eq. 2.13 over the frame pairs a transition
//!   matches);
//! - [`appearance_eval()`]: eigen appearance maps on generated textures with ground truth (4.5-4.6:
//!   flow error, Poisson vs direct warping, compactness and generalisation against naive PCA in the
//!   texture and image domains, completion of occlusion holes); the flow estimator is passed in;
//! - [`gpdm_eval()`]: GPDM vs PCA, HMC trajectories (6.4-6.5, Fig. 6.4);
//! - [`variation_eval()`]: motion variation (6.5-6.8): Fig. 6.4 per part and stitched, on training
//!   and held-out frames; Fig. 6.7 guided vs direct latent interpolation; seeded variants against
//!   five criteria (distance to the source, nearest to its source, edge distortion, foot sliding, no
//!   two alike);
//! - [`play_eval`]: the interactive controller on scripted inputs (heading and speed errors,
//!   response latency, foot sliding, transitions) against offline path following on the same
//!   trajectories.
//!
//! Reproduction (`surfcap reproduce`): [`published_values`] (the papers' numbers, typed in,
//! and surfcap's own checks), [`reproduce_report`] (each value beside ours with a status, the
//! HTML page, JSON and CSV, a column per other paper reading) and [`reproduce_markdown`] (the
//! same tables as markdown pages for docs/results).
//!
//! Randomness comes from ChaCha8 streams, so a seed gives the same permutations on every platform
//! and thread count. One [`Error`] (thiserror); option errors are worded as the command line's
//! `--option value: expected ...`.

pub mod appearance_eval;
pub mod correlation;
pub mod error;
pub mod gpdm_eval;
pub mod graph_comparison_eval;
pub mod interchange_eval;
pub mod interpolation_eval;
pub mod mantel_test;
pub mod play_eval;
pub mod pose_metric_eval;
pub mod published_values;
pub mod reproduce_markdown;
pub mod reproduce_report;
pub mod root_motion_eval;
pub mod skeleton_distance;
pub mod smg_comparison;
pub mod smg_eval;
pub mod sparse_graph_eval;
pub mod transfer_eval;
pub mod transition_costs_eval;
pub mod transition_measures;
pub mod variation_eval;

pub use appearance_eval::{AppearanceEval, AppearanceEvalOptions, appearance_eval};
pub use error::{Error, Result};
pub use gpdm_eval::{GpdmEval, GpdmEvalOptions, gpdm_eval};
pub use graph_comparison_eval::{GraphComparisonEval, GraphComparisonOptions, graph_comparison_eval};
pub use interchange_eval::{InterchangeEval, InterchangeOptions, interchange_eval};
pub use interpolation_eval::{InterpolationEval, InterpolationOptions, interpolation_eval};
pub use pose_metric_eval::{PoseMetricEval, PoseMetricOptions, pose_metric_eval};
pub use root_motion_eval::{RootMotionEval, RootMotionOptions, root_motion_eval};
pub use transition_costs_eval::{TransitionCostsEval, TransitionCostsOptions, transition_costs_eval};
pub use variation_eval::{VariationEval, VariationEvalOptions, variation_eval};

/// The condensed upper triangle (i < j, row-major) of a row-major N x N matrix.
pub fn condensed(n: usize, full: &[f64]) -> Vec<f64> {
    (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).map(|(i, j)| full[i * n + j]).collect()
}

/// Index of pair (i, j), i < j, in a condensed vector of N objects.
#[inline]
pub fn pair_index(n: usize, i: usize, j: usize) -> usize {
    debug_assert!(i < j && j < n);
    i * n - i * (i + 1) / 2 + (j - i - 1)
}

/// Mean and population standard deviation of some values, serialised as `{"mean", "std"}`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MeanStd {
    pub mean: f64,
    pub std: f64,
}

impl MeanStd {
    /// (0, 0) for no values.
    pub fn of(v: &[f64]) -> MeanStd {
        let (mean, std) = mean_std(v);
        MeanStd { mean, std }
    }
}

/// Mean and (population) standard deviation; (0, 0) for no values.
pub fn mean_std(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        // Not the -0.0 that a float sum of nothing gives.
        return (0.0, 0.0);
    }
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt())
}

#[cfg(test)]
pub(crate) mod test_subjects {
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_mesh::{NoProgress, Subject};
    use surfcap_pipeline::{CacheStore, Pipeline};

    /// The procedural tube: 8 rings of 6 vertices, 24 frames at `fps`.
    pub fn worm(fps: f64) -> Subject {
        worm_subject(&WormParams { rings: 8, segments: 6, frames: 24, fps, ..Default::default() }).unwrap()
    }

    /// A pipeline without a disk cache.
    pub fn pipeline(s: Subject) -> Pipeline {
        Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress))
    }

    /// The keys of a JSON object, sorted (serde_json keeps insertion order in this workspace:
    /// zarrs turns on its `preserve_order` feature).
    pub fn keys(v: &serde_json::Value) -> Vec<&str> {
        let mut k: Vec<&str> = v.as_object().expect("an object").keys().map(String::as_str).collect();
        k.sort_unstable();
        k
    }
}
