//! `surfcap eval transitions <subject>`: thesis 2.5.5, Fig. 2.15 (`surfcap_eval::
//! transition_costs_eval` computes it; this command writes the report and plots and prints
//! the table).

use std::path::PathBuf;

use surfcap_eval::transition_costs_eval::{TransitionCostsOptions, transition_costs_eval};
use surfcap_motion::dtw::{FirstStep, Normalisation};
use surfcap_plot::{LineChart, Series, write_line_chart};

use super::folder::{claim, print_wrote, save_report};
use crate::options::{CacheOpts, SubjectArgs};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Slope constraints to compare.
    #[arg(long, value_delimiter = ',', default_value = "2,3,4,5", value_parser = crate::options::count)]
    pub slopes: Vec<usize>,
    /// Fixed segment length of the standard and DTW-only transitions (default: one second).
    #[arg(long, value_parser = crate::options::count)]
    pub fixed: Option<usize>,
    /// Frame pairs in the plots.
    #[arg(long, default_value_t = 100, value_parser = crate::options::count)]
    pub plot_pairs: usize,
    /// Reading of the DTW's first step (thesis eq. 2.53): surfcap (up to p - 1 straight steps may
    /// open the warping path, as the words of 2.5.2 allow) or literal (eq. 2.53 read from g(1, 1):
    /// every path opens with a diagonal step); the report records which
    #[arg(long, value_enum, default_value_t = FirstStepArg::Surfcap)]
    pub dtw_first_step: FirstStepArg,
    /// Normalisation of the DTW's cost (thesis eq. 2.50 and 2.55): surfcap (the DP minimises the
    /// summed cost over the warping path and divides it by the path length L) or exact (eq. 2.55's
    /// least normalised cost found exactly: the path of least sum / L, with L a second index of
    /// the DP, several times slower); the report records which
    #[arg(long, value_enum, default_value_t = RatioArg::Surfcap)]
    pub dtw_ratio: RatioArg,
    /// Folder for the report and the plots.
    #[arg(short, long, default_value = "transitions-eval")]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

/// The readings of the DTW's first step, as `--dtw-first-step` names them.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FirstStepArg {
    /// Up to p - 1 straight steps may open the path (surfcap's reading).
    Surfcap,
    /// A diagonal step first (eq. 2.53 read literally).
    Literal,
}

impl From<FirstStepArg> for FirstStep {
    fn from(a: FirstStepArg) -> Self {
        match a {
            FirstStepArg::Surfcap => FirstStep::Straight,
            FirstStepArg::Literal => FirstStep::Diagonal,
        }
    }
}

/// The readings of the DTW's normalisation, as `--dtw-ratio` names them.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RatioArg {
    /// The least summed cost divided by its path length (surfcap's reading).
    Surfcap,
    /// The least ratio of summed cost to path length (eq. 2.55 minimised exactly).
    Exact,
}

impl From<RatioArg> for Normalisation {
    fn from(a: RatioArg) -> Self {
        match a {
            RatioArg::Surfcap => Normalisation::SumThenDivide,
            RatioArg::Exact => Normalisation::ExactRatio,
        }
    }
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = claim(ctx, &a.output, &[&a.subject.path], "eval-transitions")?;
    let opts = TransitionCostsOptions {
        slopes: a.slopes,
        fixed: a.fixed,
        plot_pairs: a.plot_pairs,
        first_step: a.dtw_first_step.into(),
        normalisation: a.dtw_ratio.into(),
    };
    let pipe = a.cache.pipeline(ctx, a.subject.open(ctx)?)?;
    let output = a.output.as_path();
    let r = transition_costs_eval(&pipe, &opts)?;
    let (name, fixed, p_plot, sample) = (&r.subject, r.fixed_length, r.plot.slope, &r.plot.sample);
    let xs = |f: &dyn Fn(usize) -> f64| (0..sample.len()).map(|x| (x as f64, f(x))).collect::<Vec<_>>();
    let series = |name: String, points, color| Series { name, points, color, dashed: false, markers: false };
    let costs = LineChart {
        title: format!("Normalised transition costs, {name} ({} pairs)", sample.len()),
        x_label: "frame pair (sample)".into(),
        y_label: "normalised deformation cost".into(),
        series: vec![
            series(format!("standard (l = {fixed})"), xs(&|k| sample[k].standard), (30, 70, 210)),
            series(format!("DTW + variable lengths (p = {p_plot})"), xs(&|k| sample[k].dtw_vls), (210, 30, 30)),
        ],
    };
    let durations = LineChart {
        title: format!("Transition durations, {name}"),
        x_label: "frame pair (sample)".into(),
        y_label: "frames".into(),
        series: vec![
            series(format!("standard (l = {fixed})"), xs(&|_| fixed as f64), (30, 70, 210)),
            series(format!("DTW + variable lengths (p = {p_plot})"), xs(&|k| sample[k].duration as f64), (210, 30, 30)),
        ],
    };
    let mut plots = write_line_chart(&output.join("costs"), &costs)?;
    plots.extend(write_line_chart(&output.join("durations"), &durations)?);
    let d = &r.plot.distances;
    let heat = surfcap_plot::HeatMap {
        title: match &r.plot.shown {
            Some(w) => format!(
                "{name}: pose distances, DTW warp of transition {} -> {} (p = {p_plot})",
                w.source, w.destination
            ),
            None => format!("{name}: pose distances"),
        },
        x_label: "destination frame".into(),
        y_label: "source frame".into(),
        values: d.values.clone(),
        rows: d.n,
        cols: d.n,
        origin: (0, 0),
        range: None,
        path: r.plot.shown.as_ref().map(|w| w.path.clone()).unwrap_or_default(),
        value_label: "pose distance".into(),
    };
    plots.extend(surfcap_plot::write_heat_map(&output.join("distances"), &heat)?);
    let (report, rp) = save_report(output, "transitions.json", &r, "plots", &plots)?;
    ctx.result(&report, || {
        println!(
            "subject {name}: {} frames at {} fps; segments {}..{}; standard and DTW-only length {fixed}; DTW first step: {}; DTW ratio: {}",
            r.frames, r.fps, r.l_min, r.l_max, r.dtw_first_step, r.dtw_ratio
        );
        println!(
            "{:>6} {:>8} {:>22} {:>22} {:>22} {:>10}",
            "slope", "pairs", "standard mean (std)", "DTW mean (std)", "DTW+VLS mean (std)", "VLS L"
        );
        for row in &r.rows {
            let f = |m: &surfcap_eval::MeanStd| format!("{:.2} ({:.2})", m.mean, m.std);
            println!(
                "{:>6} {:>8} {:>22} {:>22} {:>22} {:>10.1}",
                row.slope,
                row.pairs,
                f(&row.standard),
                f(&row.dtw),
                f(&row.dtw_vls),
                row.dtw_vls_mean_duration
            );
        }
        print_wrote(&rp, &plots);
    });
    ctx.commit(outs)
}
