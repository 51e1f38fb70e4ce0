//! `surfcap eval pose-metric <subject>`: thesis 2.3.2, Evaluation (Fig. 2.5-2.7).

use std::path::Path;

use anyhow::Context;
use serde_json::json;
use surfcap_eval::correlation::{distance_correlation, pearson};
use surfcap_eval::mantel_test::{correlogram, mantel};
use surfcap_eval::skeleton_distance::{euler_distance, joint_selection, local_euler_angles};
use surfcap_eval::{condensed, pair_index};
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_mesh::Sequence;
use surfcap_plot::{LineChart, Series, write_line_chart};

use super::PoseMetricOpts;
use crate::options::{SourceOpts, open};
use crate::output::print_json;

/// Permutations behind each correlogram class's 95% null limits.
const CLASS_PERMUTATIONS: usize = 999;

pub fn run(ctx: &crate::Ctx, path: &Path, source: &SourceOpts, o: &PoseMetricOpts) -> anyhow::Result<()> {
    let s = open(ctx, path, source)?;
    for q in s.sequences() {
        anyhow::ensure!(
            q.joints.is_some(),
            "sequence {:?} has no ground-truth joints: eval pose-metric needs joint matrices \
             (joints.npy, as in the KayKit and robot datasets)",
            q.name
        );
    }
    let first = s.sequences()[0].joints.as_ref().expect("checked");
    for q in s.sequences() {
        anyhow::ensure!(
            q.joints.as_ref().expect("checked").names == first.names,
            "sequence {:?} has another skeleton",
            q.name
        );
    }
    let joints = joint_selection(first);
    anyhow::ensure!(!joints.is_empty(), "no joints left after leaving out roots and rig helpers");
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
    let pipe = o.cache.pipeline(ctx, sub);
    let dist = |metric| -> anyhow::Result<Vec<f64>> {
        let params = DistanceParams { metric, ..Default::default() };
        Ok(condensed(n, &pipe.distances(&params)?.value.values))
    };
    let ours = dist(PoseMetric::Deformation)?;
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
        json!({
            "pearson": pearson(&truth, d),
            "distance_correlation": distance_correlation(&truth, d),
            "mantel_p_value": m.p_value,
            "mantel_exceed": m.exceed,
            "mantel_null_mean": m.null_mean,
            "mantel_null_std": m.null_std,
        })
    };
    let (s_ours, s_eucl) = (stats(&ours, o.seed), stats(&eucl, o.seed));
    let c_ours = correlogram(&truth, &ours, o.classes, CLASS_PERMUTATIONS, o.seed);
    let c_eucl = correlogram(&truth, &eucl, o.classes, CLASS_PERMUTATIONS, o.seed);
    let mid = |c: &surfcap_eval::mantel_test::CorrelogramClass| 0.5 * (c.lo + c.hi);
    let line = |name: &str, pts: Vec<(f64, f64)>, color, dashed, markers| Series {
        name: name.into(),
        points: pts,
        color,
        dashed,
        markers,
    };
    let red = (210, 30, 30);
    let blue = (30, 70, 210);
    let chart = LineChart {
        title: format!("Mantel correlogram: {} ({} frames)", s.name, n),
        x_label: "ground-truth distance (class centre, rad)".into(),
        y_label: "Pearson r within class".into(),
        series: vec![
            line("ours (eq. 2.13)", c_ours.iter().map(|c| (mid(c), c.r)).collect(), red, false, true),
            line("Euclidean (eq. 2.2)", c_eucl.iter().map(|c| (mid(c), c.r)).collect(), blue, false, true),
            line("95% null, ours", c_ours.iter().map(|c| (mid(c), c.null_hi)).collect(), red, true, false),
            line("", c_ours.iter().map(|c| (mid(c), c.null_lo)).collect(), red, true, false),
            line("95% null, Euclidean", c_eucl.iter().map(|c| (mid(c), c.null_hi)).collect(), blue, true, false),
            line("", c_eucl.iter().map(|c| (mid(c), c.null_lo)).collect(), blue, true, false),
        ],
    };
    let plots = write_line_chart(&o.output.join("correlogram"), &chart).map_err(|e| anyhow::anyhow!("{e}"))?;
    let classes = |c: &[surfcap_eval::mantel_test::CorrelogramClass]| {
        c.iter()
            .map(|k| json!({"lo": k.lo, "hi": k.hi, "pairs": k.pairs, "r": k.r, "null_lo": k.null_lo, "null_hi": k.null_hi}))
            .collect::<Vec<_>>()
    };
    let report = json!({
        "subject": s.name,
        "frames_used": n,
        "frames_total": n_all,
        "joints_used": joints.iter().map(|&j| first.names[j].clone()).collect::<Vec<_>>(),
        "permutations": o.permutations,
        "seed": o.seed,
        "ours": s_ours,
        "euclidean": s_eucl,
        "correlogram": { "ours": classes(&c_ours), "euclidean": classes(&c_eucl), "class_permutations": CLASS_PERMUTATIONS },
        "plots": plots,
    });
    let rp = o.output.join("pose-metric.json");
    surfcap_mesh::atomic::write_file(&rp, |w| {
        serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)
    })
    .with_context(|| format!("writing {}", rp.display()))?;
    if ctx.json {
        print_json(&report);
        return Ok(());
    }
    println!(
        "subject {}: {n} of {n_all} frames, {} joints (roots and rig helpers left out), {} Mantel permutations",
        s.name,
        joints.len(),
        o.permutations
    );
    println!("{:<18} {:>10} {:>10}", "", "Eucl.", "Ours");
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    for (label, key) in
        [("Pearson Corr.", "pearson"), ("Distance Corr.", "distance_correlation"), ("Mantel p-value", "mantel_p_value")]
    {
        println!("{label:<18} {:>10.4} {:>10.4}", f(&s_eucl, key), f(&s_ours, key));
    }
    println!(
        "wrote {}, {}",
        rp.display(),
        plots.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}
