//! `surfcap eval graphs`: the essential graph vs the motion graph for several alphas (thesis
//! Fig. 3.2 and 3.8).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;
use surfcap_pipeline::{GraphKind, GraphParams};
use surfcap_plot::{LineChart, Series, write_line_chart};

use super::transitions::mean_std;
use crate::options::{CacheOpts, SourceOpts, TableOpts, open};
use crate::output::print_json;

/// Options of `surfcap eval graphs`.
pub struct EvalOpts {
    pub alphas: Vec<f64>,
    pub plot_pairs: usize,
    pub output: PathBuf,
    pub table: TableOpts,
    pub cache: CacheOpts,
}

/// Thesis 3.3.3, Fig. 3.2 and 3.8: for each alpha, both graphs' densities and the mean and
/// standard deviation of all-pairs shortest-path costs. Pairs: ordered (i, j), i != j, that
/// the motion graph connects (its dead ends are pruned), so both graphs are compared on the
/// same pairs; the essential graph's mean over all its pairs is reported beside.
pub fn eval(ctx: &crate::Ctx, path: &Path, source: &SourceOpts, o: &EvalOpts) -> anyhow::Result<()> {
    anyhow::ensure!(!o.alphas.is_empty(), "--alpha: expected at least one value");
    for &a in &o.alphas {
        surfcap_pipeline::pipeline::check_alpha(a)?;
    }
    let s = open(ctx, path, source)?;
    let p = o.table.params(s.fps)?;
    let n = s.n_frames();
    let mut rows = Vec::new();
    // Per alpha: the sampled pairs' costs in the essential and the motion graph.
    type Curve = Vec<(f64, f64)>;
    let mut path_plots: Vec<(f64, Curve, Curve)> = Vec::new();
    let t0 = Instant::now();
    let pipe = o.cache.pipeline(ctx, s);
    let s = pipe.subject();
    for &alpha in &o.alphas {
        let graph = |kind| pipe.graph(&GraphParams { table: p, kind, alpha });
        let (eg, mg) = (graph(GraphKind::Essential)?.value, graph(GraphKind::Motion)?.value);
        let (ce, cm) = (eg.all_pairs(), mg.all_pairs());
        let (mut on_mg, mut on_eg, mut eg_all) = (Vec::new(), Vec::new(), Vec::new());
        let mut lower_in_motion = 0usize;
        for k in 0..n * n {
            if k / n == k % n {
                continue;
            }
            if ce[k].is_finite() {
                eg_all.push(ce[k]);
            }
            if cm[k].is_finite() {
                on_mg.push(cm[k]);
                on_eg.push(ce[k]);
                if cm[k] < ce[k] * (1.0 - 1e-12) {
                    lower_in_motion += 1;
                }
            }
        }
        let ((mm, ms), (em, es), (ea, eas)) = (mean_std(&on_mg), mean_std(&on_eg), mean_std(&eg_all));
        let mg_frames = (0..n).filter(|&i| !mg.out(i).is_empty()).count();
        rows.push(json!({
            "alpha": alpha,
            "motion_graph": { "mean": mm, "std": ms, "density": mg.density(), "edges": mg.edges().len(), "frames": mg_frames },
            "essential_graph": { "mean": em, "std": es, "density": eg.density(), "edges": eg.edges().len(), "mean_all_pairs": ea, "std_all_pairs": eas, "pairs": eg_all.len() },
            "pairs_compared": on_mg.len(),
            "pairs_where_motion_graph_is_cheaper": lower_in_motion,
        }));
        // A sample of the compared pairs, sorted by the essential graph's cost (Fig. 3.8b-c).
        let step = (on_mg.len() / o.plot_pairs.max(1)).max(1);
        let mut sample: Vec<(f64, f64)> = on_eg.iter().zip(&on_mg).step_by(step).map(|(&e, &m)| (e, m)).collect();
        sample.sort_by(|a, b| a.0.total_cmp(&b.0));
        let eg_line = sample.iter().enumerate().map(|(x, v)| (x as f64, v.0)).collect();
        let mg_line = sample.iter().enumerate().map(|(x, v)| (x as f64, v.1)).collect();
        path_plots.push((alpha, eg_line, mg_line));
    }
    let secs = t0.elapsed().as_secs_f64();
    std::fs::create_dir_all(&o.output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", o.output.display()))?;
    let (blue, red) = ((31, 119, 180), (214, 39, 40));
    let series = |name: &str, points: Vec<(f64, f64)>, color| Series {
        name: name.into(),
        points,
        color,
        dashed: false,
        markers: true,
    };
    let curve = |graph: &str, field: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .map(|r| (r["alpha"].as_f64().unwrap_or(0.0), r[graph][field].as_f64().unwrap_or(f64::NAN)))
            .collect()
    };
    let mut plots = Vec::new();
    let chart = |title: &str, y: &str, field: &str| LineChart {
        title: format!("{title} ({})", s.name),
        x_label: "alpha".into(),
        y_label: y.into(),
        series: vec![
            series("essential graph", curve("essential_graph", field), blue),
            series("motion graph", curve("motion_graph", field), red),
        ],
    };
    let err = |e: surfcap_plot::Error| anyhow::anyhow!("{e}");
    plots.extend(
        write_line_chart(&o.output.join("density"), &chart("Graph density (eq. 3.4)", "density", "density"))
            .map_err(err)?,
    );
    plots.extend(
        write_line_chart(&o.output.join("mean_cost"), &chart("Mean shortest-path cost", "mean cost", "mean"))
            .map_err(err)?,
    );
    for (alpha, eg_line, mg_line) in path_plots {
        let c = LineChart {
            title: format!("Shortest-path costs, alpha = {alpha} ({})", s.name),
            x_label: "frame pairs (sorted by essential-graph cost)".into(),
            y_label: "path cost".into(),
            series: vec![
                Series { name: "essential graph".into(), points: eg_line, color: blue, dashed: false, markers: false },
                Series { name: "motion graph".into(), points: mg_line, color: red, dashed: false, markers: false },
            ],
        };
        plots.extend(
            write_line_chart(&o.output.join(format!("paths_alpha_{}", alpha.to_string().replace('.', "_"))), &c)
                .map_err(err)?,
        );
    }
    let report = json!({ "subject": s.name, "frames": n, "l_min": p.l_min, "l_max": p.l_max, "rows": rows, "plots": plots, "seconds": secs });
    surfcap_mesh::atomic::write_file(&o.output.join("graphs.json"), |w| {
        w.write_all(serde_json::to_string_pretty(&report).expect("JSON").as_bytes())
    })?;
    if ctx.json {
        print_json(&report);
        return Ok(());
    }
    println!(
        "subject {} ({n} frames); shortest-path costs over the pairs the motion graph connects (thesis Fig. 3.8)",
        s.name
    );
    println!(
        "{:>7} | {:>10} {:>10} | {:>10} {:>10} | {:>9} {:>9} | {:>7}",
        "alpha", "MG mean", "MG std", "EG mean", "EG std", "MG dens.", "EG dens.", "MG<EG"
    );
    for r in &rows {
        let f = |g: &str, k: &str| r[g][k].as_f64().unwrap_or(f64::NAN);
        println!(
            "{:>7} | {:>10.4} {:>10.4} | {:>10.4} {:>10.4} | {:>9.5} {:>9.5} | {:>7}",
            r["alpha"].as_f64().unwrap_or(f64::NAN),
            f("motion_graph", "mean"),
            f("motion_graph", "std"),
            f("essential_graph", "mean"),
            f("essential_graph", "std"),
            f("motion_graph", "density"),
            f("essential_graph", "density"),
            r["pairs_where_motion_graph_is_cheaper"]
        );
    }
    println!(
        "wrote {} and {} plots in {} ({secs:.1} s)",
        o.output.join("graphs.json").display(),
        plots.len(),
        o.output.display()
    );
    Ok(())
}
