//! `surfcap eval interpolation`: linear vs non-linear interpolation (thesis 2.4, Fig. 2.8;
//! `surfcap_eval::interpolation_eval` computes it; this command prints the table and, with
//! `-o`, writes interpolation.json and the curves over lambda).

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde_json::json;
use surfcap_eval::interpolation_eval::{InterpolationEval, InterpolationOptions, interpolation_eval};
use surfcap_geometry::pose_interpolation::StretchInterpolation;
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::SubjectArgs;
use crate::output::write_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Pose pairs as FROM,TO (each sequence:frame or a global frame), repeatable.
    #[arg(long = "pair", required = true)]
    pub pairs: Vec<String>,
    /// Interpolation parameter.
    #[arg(long, default_value_t = 0.5, value_parser = crate::options::fraction)]
    pub lambda: f64,
    /// Stretch interpolation: linear (eq. 2.45) or log (eq. 2.46).
    #[arg(long, default_value = "linear")]
    pub stretch: StretchInterpolation,
    /// Also write interpolation.json and distortion.svg/png (both measures over lambda in
    /// 0, 0.1, ..., 1, linear dashed, non-linear solid) into this folder.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = match &a.output {
        Some(o) => Some(super::folder::claim(ctx, o, &[&a.subject.path], "eval-interpolation")?),
        None => None,
    };
    let Args { pairs, lambda, stretch, output, subject } = a;
    let opts = InterpolationOptions { pairs, lambda, stretch, sweeps: output.is_some() };
    let r = interpolation_eval(&subject.open(ctx)?, &opts)?;
    if let Some(dir) = &output {
        write_plots(dir, &r)?;
    }
    ctx.result(&json!({ "subject": r.subject, "rows": r.rows }), || {
        println!("subject {} ({} vertices, {} triangles), lambda = {lambda}", r.subject, r.n_vertices, r.n_triangles);
        println!(
            "{:<28} {:>14} {:>14} {:>14} {:>14} {:>9}",
            "pair", "edge lin.", "edge nonlin.", "volume lin.", "volume nonlin.", "time"
        );
        for x in &r.rows {
            println!(
                "{:<28} {:>14.5} {:>14.5} {:>14.5} {:>14.5} {:>8.3}s",
                x.pair,
                x.linear.edge_distortion,
                x.nonlinear.edge_distortion,
                x.linear.volume_change,
                x.nonlinear.volume_change,
                x.nonlinear_seconds
            );
        }
    });
    match outs {
        Some(outs) => ctx.commit(outs),
        None => Ok(()),
    }
}

/// `interpolation.json` and `distortion.svg/png`, `volume.svg/png`: each measure over lambda,
/// one colour per pair, linear dashed and non-linear solid (thesis Fig. 2.8 reads them at
/// lambda = 0.5).
fn write_plots(dir: &Path, r: &InterpolationEval) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let palette = [(31, 95, 191), (208, 48, 48), (46, 158, 68), (224, 138, 0), (120, 60, 170)];
    let sweeps = r.sweeps.as_deref().unwrap_or_default();
    type Measure = fn(&surfcap_eval::interpolation_eval::SweepPoint) -> f64;
    let charts: [(&str, &str, Measure, Measure); 2] = [
        (
            "distortion",
            "edge-length distortion over lambda",
            |p| p.linear_edge_distortion,
            |p| p.nonlinear_edge_distortion,
        ),
        ("volume", "volume change over lambda", |p| p.linear_volume_change, |p| p.nonlinear_volume_change),
    ];
    for (stem, title, lin, non) in charts {
        let mut series = Vec::new();
        for (k, sweep) in sweeps.iter().enumerate() {
            let color = palette[k % palette.len()];
            for (f, dashed, kind) in [(lin, true, "linear"), (non, false, "non-linear")] {
                series.push(Series {
                    name: format!("{} {kind}", sweep.pair),
                    points: sweep.points.iter().map(|p| (p.lambda, f(p))).collect(),
                    color,
                    dashed,
                    markers: false,
                });
            }
        }
        let chart = LineChart {
            title: format!("{}: {title}", r.subject),
            x_label: "lambda".into(),
            y_label: if stem == "volume" { "relative volume change".into() } else { "relative edge distortion".into() },
            series,
        };
        write_line_chart(&dir.join(stem), &chart)?;
    }
    let sweeps_json: Vec<serde_json::Value> = sweeps
        .iter()
        .map(
            |s| json!({ "pair": s.pair, "lambda_linear_edge_nonlinear_edge_linear_volume_nonlinear_volume": s.points }),
        )
        .collect();
    write_json(&dir.join("interpolation.json"), &json!({ "subject": r.subject, "rows": r.rows, "sweeps": sweeps_json }))
}
