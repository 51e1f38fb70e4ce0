//! Our pose distance and the Euclidean one against the skeleton ground truth (thesis 2.3.2,
//! Evaluation, Fig. 2.5-2.7): Pearson and distance correlation, Mantel test and Mantel
//! correlogram.

use serde::Serialize;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_mesh::{Progress, Sequence, Subject};
use surfcap_pipeline::{CacheStore, Pipeline};

use crate::correlation::{distance_correlation, pearson};
use crate::error::{Error, Result};
use crate::mantel_test::{CorrelogramClass, correlogram, mantel};
use crate::skeleton_distance::{euler_distance, joint_selection, local_euler_angles};
use crate::{condensed, pair_index};

/// Permutations behind each correlogram class's 95% null limits.
pub const CLASS_PERMUTATIONS: usize = 999;

/// Options of [`pose_metric_eval`] (`surfcap eval pose-metric`).
#[derive(Debug, Clone)]
pub struct PoseMetricOptions {
    /// Frames used (evenly spaced over the global index when the subject has more; at least 3).
    pub max_frames: usize,
    /// Permutations of the Mantel test.
    pub permutations: usize,
    /// Distance classes of the correlogram.
    pub classes: usize,
    /// Seed of the permutations.
    pub seed: u64,
    /// Reading of eq. 2.6 behind our distance: surfcap's (the default) or the literal one.
    pub gradient: GradientReading,
}

/// The readings of eq. 2.6, the deformation gradient behind our distance (PAPER-NOTES): with
/// A = (v1 - v3, v2 - v3, n) of pose i and B that of pose j as matrix columns, surfcap's J =
/// B A^-1 (the spatial gradient, the default) or the printed A^-1 B.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum GradientReading {
    /// J = B A^-1.
    #[default]
    Surfcap,
    /// A^-1 B, eq. 2.6 read literally.
    Literal,
}

impl GradientReading {
    /// The name used on the command line and in the report: "surfcap" or "literal".
    pub fn name(self) -> &'static str {
        match self {
            GradientReading::Surfcap => "surfcap",
            GradientReading::Literal => "literal",
        }
    }

    /// The pose metric of our distance under this reading (eq. 2.13).
    pub fn metric(self) -> PoseMetric {
        match self {
            GradientReading::Surfcap => PoseMetric::Deformation,
            GradientReading::Literal => PoseMetric::DeformationLiteral,
        }
    }
}

/// How well one mesh distance agrees with the ground truth.
#[derive(Debug, Clone, Serialize)]
pub struct MetricAgreement {
    /// Eq. 2.18.
    pub pearson: f64,
    /// Eq. 2.19-2.22.
    pub distance_correlation: f64,
    pub mantel_p_value: f64,
    /// Permutations whose correlation reached the observed one.
    pub mantel_exceed: usize,
    pub mantel_null_mean: f64,
    pub mantel_null_std: f64,
}

/// The Mantel correlograms of both distances (the `correlogram` plot).
#[derive(Debug, Clone, Serialize)]
pub struct Correlograms {
    pub ours: Vec<CorrelogramClass>,
    pub euclidean: Vec<CorrelogramClass>,
    /// Permutations behind each class's null limits ([`CLASS_PERMUTATIONS`]).
    pub class_permutations: usize,
}

/// Result of [`pose_metric_eval`]; serialised, the report `pose-metric.json` without its
/// `plots`.
#[derive(Debug, Clone, Serialize)]
pub struct PoseMetricEval {
    pub subject: String,
    pub frames_used: usize,
    pub frames_total: usize,
    /// The joints of the ground truth (roots and rig helpers left out).
    pub joints_used: Vec<String>,
    pub permutations: usize,
    pub seed: u64,
    /// Reading of eq. 2.6 behind our distance: "surfcap" (J = B A^-1) or "literal" (A^-1 B).
    pub deformation_gradient: &'static str,
    /// Our deformation distance (eq. 2.13).
    pub ours: MetricAgreement,
    /// The Euclidean distance after alignment (eq. 2.2).
    pub euclidean: MetricAgreement,
    pub correlogram: Correlograms,
}

/// Thesis 2.3.2, Evaluation (Fig. 2.5-2.7): the deformation and Euclidean distances between up
/// to `max_frames` evenly spaced frames against the skeleton ground truth (eq. 2.15-2.16).
///
/// The mesh distances are those of a derived subject of the chosen frames (named
/// `<subject>-eval`), produced by a [`Pipeline`] over `store` that reports to `progress`.
pub fn pose_metric_eval(
    s: &Subject,
    store: &CacheStore,
    progress: Box<dyn Progress + Send>,
    o: &PoseMetricOptions,
) -> Result<PoseMetricEval> {
    for q in s.sequences() {
        if q.joints.is_none() {
            return Err(Error::Unsuitable(format!(
                "sequence {:?} has no ground-truth joints: eval pose-metric needs joint matrices \
                 (joints.npy, as in the KayKit and robot datasets)",
                q.name
            )));
        }
    }
    let first = s.sequences()[0].joints.as_ref().expect("checked");
    for q in s.sequences() {
        if q.joints.as_ref().expect("checked").names != first.names {
            return Err(Error::Unsuitable(format!("sequence {:?} has another skeleton", q.name)));
        }
    }
    let joints = joint_selection(first);
    if joints.is_empty() {
        return Err(Error::Unsuitable("no joints left after leaving out roots and rig helpers".into()));
    }
    let n_all = s.n_frames();
    let n = n_all.min(o.max_frames.max(3));
    let chosen: Vec<usize> = (0..n).map(|k| k * n_all / n).collect();

    // A subject of the chosen frames, in order, for the mesh distances.
    let nv = s.topology().n_vertices();
    let mut pos = Vec::with_capacity(n * 3 * nv);
    for &g in &chosen {
        pos.extend_from_slice(s.frame(g).expect("in range"));
    }
    let sub = s.derived(format!("{}-eval", s.name), Sequence::new("frames", nv, pos)?)?;
    let pipe = Pipeline::new(sub, store.clone(), progress);
    let dist = |metric| -> Result<Vec<f64>> {
        let params = DistanceParams { metric, ..Default::default() };
        Ok(condensed(n, &pipe.distances(&params)?.value.values))
    };
    let ours = dist(o.gradient.metric())?;
    let eucl = dist(PoseMetric::Euclidean)?;
    let angles: Vec<Vec<[f64; 3]>> = chosen
        .iter()
        .map(|&g| {
            let (si, f) = s.frame_index().locate(g).expect("in range");
            local_euler_angles(s.sequences()[si].joints.as_ref().expect("checked"), f, &joints)
        })
        .collect();
    let mut truth = vec![0.0; n * (n - 1) / 2];
    for i in 0..n {
        for j in i + 1..n {
            truth[pair_index(n, i, j)] = euler_distance(&angles[i], &angles[j]);
        }
    }
    let stats = |d: &[f64], seed: u64| {
        let m = mantel(n, &truth, d, o.permutations, seed);
        MetricAgreement {
            pearson: pearson(&truth, d),
            distance_correlation: distance_correlation(&truth, d),
            mantel_p_value: m.p_value,
            mantel_exceed: m.exceed,
            mantel_null_mean: m.null_mean,
            mantel_null_std: m.null_std,
        }
    };
    let (s_ours, s_eucl) = (stats(&ours, o.seed), stats(&eucl, o.seed));
    let c_ours = correlogram(&truth, &ours, o.classes, CLASS_PERMUTATIONS, o.seed);
    let c_eucl = correlogram(&truth, &eucl, o.classes, CLASS_PERMUTATIONS, o.seed);
    Ok(PoseMetricEval {
        subject: s.name.clone(),
        frames_used: n,
        frames_total: n_all,
        joints_used: joints.iter().map(|&j| first.names[j].clone()).collect(),
        permutations: o.permutations,
        seed: o.seed,
        deformation_gradient: o.gradient.name(),
        ours: s_ours,
        euclidean: s_eucl,
        correlogram: Correlograms { ours: c_ours, euclidean: c_eucl, class_permutations: CLASS_PERMUTATIONS },
    })
}

#[cfg(test)]
mod tests {
    use serde_json::json;
    use surfcap_builtin::locomotion::Gait;
    use surfcap_builtin::mannequin::{BodyShape, mannequin};
    use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
    use surfcap_mesh::NoProgress;

    use super::*;
    use crate::test_subjects::worm;

    fn options() -> PoseMetricOptions {
        PoseMetricOptions { max_frames: 16, permutations: 99, classes: 4, seed: 3, gradient: GradientReading::Surfcap }
    }

    #[test]
    fn agreement_with_the_skeleton_and_the_report_is_the_cli_json() {
        let m = mannequin(&BodyShape::average(), 1000).unwrap();
        let clips: Vec<Clip> =
            [Gait::Walk, Gait::Jump].into_iter().map(|g| Clip::procedural(&m, g, 10.0, 1.0, 5).unwrap()).collect();
        let s = mannequin_subject("m", &m, &clips, 10.0).unwrap();
        let store = CacheStore::memory_only();
        let r = pose_metric_eval(&s, &store, Box::new(NoProgress), &options()).unwrap();
        assert_eq!((r.frames_used, r.frames_total), (16, s.n_frames()));
        assert!(!r.joints_used.is_empty() && r.joints_used.len() < 15, "the root is left out");
        for a in [&r.ours, &r.euclidean] {
            assert!(a.pearson > 0.0 && a.pearson <= 1.0, "{a:?}");
            assert!(a.distance_correlation > 0.0 && a.distance_correlation <= 1.0, "{a:?}");
            assert!(a.mantel_p_value > 0.0 && a.mantel_p_value <= 1.0);
            assert_eq!(a.mantel_p_value, (1 + a.mantel_exceed) as f64 / 100.0);
        }
        assert_eq!((r.correlogram.ours.len(), r.correlogram.euclidean.len()), (4, 4));
        let pairs: usize = r.correlogram.ours.iter().map(|c| c.pairs).sum();
        assert_eq!(pairs, 16 * 15 / 2);
        // Seeded: the same numbers again.
        let again = pose_metric_eval(&s, &store, Box::new(NoProgress), &options()).unwrap();
        assert_eq!(serde_json::to_value(&again).unwrap(), serde_json::to_value(&r).unwrap());
        // pose-metric.json as the CLI wrote it, without "plots".
        let stats = |a: &MetricAgreement| {
            json!({
                "pearson": a.pearson, "distance_correlation": a.distance_correlation,
                "mantel_p_value": a.mantel_p_value, "mantel_exceed": a.mantel_exceed,
                "mantel_null_mean": a.mantel_null_mean, "mantel_null_std": a.mantel_null_std,
            })
        };
        let classes = |c: &[CorrelogramClass]| {
            c.iter()
                .map(|k| json!({"lo": k.lo, "hi": k.hi, "pairs": k.pairs, "r": k.r, "null_lo": k.null_lo, "null_hi": k.null_hi}))
                .collect::<Vec<_>>()
        };
        let cli = json!({
            "subject": "m", "frames_used": 16, "frames_total": s.n_frames(), "joints_used": r.joints_used,
            "permutations": 99, "seed": 3, "deformation_gradient": "surfcap", "ours": stats(&r.ours), "euclidean": stats(&r.euclidean),
            "correlogram": { "ours": classes(&r.correlogram.ours), "euclidean": classes(&r.correlogram.euclidean), "class_permutations": 999 },
        });
        assert_eq!(serde_json::to_value(&r).unwrap(), cli);
    }

    #[test]
    fn the_literal_gradient_changes_our_distance_only_and_is_recorded() {
        let m = mannequin(&BodyShape::average(), 1000).unwrap();
        let clips = [Clip::procedural(&m, Gait::Walk, 10.0, 1.5, 5).unwrap()];
        let s = mannequin_subject("m", &m, &clips, 10.0).unwrap();
        let store = CacheStore::memory_only();
        let run = |gradient| {
            let o = PoseMetricOptions { gradient, ..options() };
            pose_metric_eval(&s, &store, Box::new(NoProgress), &o).unwrap()
        };
        let (ours, literal) = (run(GradientReading::Surfcap), run(GradientReading::Literal));
        assert_eq!((ours.deformation_gradient, literal.deformation_gradient), ("surfcap", "literal"));
        assert_eq!(serde_json::to_value(&literal).unwrap()["deformation_gradient"], "literal");
        assert_eq!(serde_json::to_value(&ours.euclidean).unwrap(), serde_json::to_value(&literal.euclidean).unwrap());
        assert_ne!(ours.ours.pearson, literal.ours.pearson, "the readings give the same distances");
    }

    #[test]
    fn a_subject_without_joints_is_refused() {
        let e =
            pose_metric_eval(&worm(30.0), &CacheStore::memory_only(), Box::new(NoProgress), &options()).unwrap_err();
        assert!(matches!(e, Error::Unsuitable(_)) && e.to_string().contains("no ground-truth joints"), "{e}");
    }
}
