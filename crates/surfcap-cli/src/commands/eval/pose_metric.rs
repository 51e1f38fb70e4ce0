//! `surfcap eval pose-metric`: our pose distance and the Euclidean one against the skeleton
//! ground truth (thesis 2.3.2, Fig. 2.5-2.7; `surfcap_eval::pose_metric_eval` computes it; this
//! command writes the report and the correlogram plot and prints the table).

use std::path::PathBuf;

use surfcap_eval::mantel_test::CorrelogramClass;
use surfcap_eval::pose_metric_eval::{GradientReading, MetricAgreement, PoseMetricOptions, pose_metric_eval};
use surfcap_plot::{LineChart, Series, write_line_chart};

use super::folder::{claim, print_wrote, save_report};
use crate::options::{CacheOpts, SourceOpts, open};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject whose sequences carry ground-truth joint matrices.
    pub subject: PathBuf,
    /// Frames used (evenly spaced over the global index when the subject has more).
    #[arg(long, default_value_t = 200, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub max_frames: usize,
    /// Permutations of the Mantel test.
    #[arg(long, default_value_t = 10000, value_parser = crate::options::count)]
    pub permutations: usize,
    /// Distance classes of the correlogram.
    #[arg(long, default_value_t = 10, value_parser = crate::options::count)]
    pub classes: usize,
    /// Seed of the permutations.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Reading of eq. 2.6, the deformation gradient behind our distance: surfcap (J = B A^-1,
    /// the spatial gradient) or literal (eq. 2.6 read literally: A^-1 B, with A and B the
    /// triangle's (v1 - v3, v2 - v3, n) in poses i and j as matrix columns).
    #[arg(long, value_enum, default_value_t = GradientArg::Surfcap)]
    pub deformation_gradient: GradientArg,
    /// Folder for the report (JSON) and the correlogram plot (SVG, PNG).
    #[arg(short, long, default_value = "pose-metric")]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// The readings of eq. 2.6, as `--deformation-gradient` names them.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum GradientArg {
    /// J = B A^-1 (surfcap's reading).
    Surfcap,
    /// A^-1 B (eq. 2.6 read literally).
    Literal,
}

impl From<GradientArg> for GradientReading {
    fn from(a: GradientArg) -> Self {
        match a {
            GradientArg::Surfcap => GradientReading::Surfcap,
            GradientArg::Literal => GradientReading::Literal,
        }
    }
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = claim(ctx, &a.output, &[&a.subject], "eval-pose-metric")?;
    let opts = PoseMetricOptions {
        max_frames: a.max_frames,
        permutations: a.permutations,
        classes: a.classes,
        seed: a.seed,
        gradient: a.deformation_gradient.into(),
    };
    let s = open(ctx, &a.subject, &a.source)?;
    let (cache, output) = (&a.cache, a.output.as_path());
    let progress = Box::new(crate::progress::Bar::new(ctx));
    let r = pose_metric_eval(&s, &cache.store()?, progress, &opts)?;
    let mid = |c: &CorrelogramClass| 0.5 * (c.lo + c.hi);
    let line = |name: &str, points: Vec<(f64, f64)>, color, dashed, markers| Series {
        name: name.into(),
        points,
        color,
        dashed,
        markers,
    };
    let (red, blue) = ((210, 30, 30), (30, 70, 210));
    let (c_ours, c_eucl) = (&r.correlogram.ours, &r.correlogram.euclidean);
    let chart = LineChart {
        title: format!("Mantel correlogram: {} ({} frames)", r.subject, r.frames_used),
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
    let plots = write_line_chart(&output.join("correlogram"), &chart)?;
    let (report, rp) = save_report(output, "pose-metric.json", &r, "plots", &plots)?;
    ctx.result(&report, || {
        println!(
            "subject {}: {} of {} frames, {} joints (roots and rig helpers left out), {} Mantel permutations, \
             deformation gradient {} (eq. 2.6)",
            r.subject,
            r.frames_used,
            r.frames_total,
            r.joints_used.len(),
            opts.permutations,
            if r.deformation_gradient == "literal" {
                "A^-1 B, read literally"
            } else {
                "J = B A^-1, surfcap's reading"
            }
        );
        println!("{:<18} {:>10} {:>10}", "", "Eucl.", "Ours");
        type Field = fn(&MetricAgreement) -> f64;
        let rows: [(&str, Field); 3] = [
            ("Pearson Corr.", |m| m.pearson),
            ("Distance Corr.", |m| m.distance_correlation),
            ("Mantel p-value", |m| m.mantel_p_value),
        ];
        for (label, f) in rows {
            println!("{label:<18} {:>10.4} {:>10.4}", f(&r.euclidean), f(&r.ours));
        }
        print_wrote(&rp, &plots);
    });
    ctx.commit(outs)
}
