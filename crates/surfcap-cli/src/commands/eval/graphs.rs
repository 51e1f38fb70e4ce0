//! `surfcap eval graphs`: the essential graph vs the motion graph for several alphas (thesis
//! 3.3.3, Fig. 3.2 and 3.8; `surfcap_eval::graph_comparison_eval` computes it; this command
//! writes the report and plots and prints the table).

use std::path::PathBuf;

use surfcap_eval::graph_comparison_eval::{AlphaRow, GraphComparisonOptions, TieReading, graph_comparison_eval};
use surfcap_motion::edge_weights::Alpha;
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{CacheOpts, SubjectArgs, TableOpts};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Values of alpha.
    #[arg(long = "alpha", value_delimiter = ',', default_value = "0.01,0.02,0.03,0.05,0.1,0.2")]
    pub alphas: Vec<Alpha>,
    /// Reading of the essential graph's ties: surfcap (a same-sequence transition gets an edge
    /// only when strictly cheaper than playing the original frames; a shortest path is replaced
    /// only by a strictly cheaper one) or literal (eq. 3.2 read literally: every forward
    /// same-sequence pair has an edge of weight min(alpha (j - i), D + alpha L), and an edge that
    /// ties with the original frames, to 1e-12 relative, is kept). The motion graph is the same.
    #[arg(long, value_enum, default_value_t = TieArg::Surfcap)]
    pub tie_rule: TieArg,
    /// Frame pairs in the shortest-path plots.
    #[arg(long, default_value_t = 200, value_parser = crate::options::count)]
    pub plot_pairs: usize,
    /// Folder for the report (graphs.json) and the plots.
    #[arg(short, long, default_value = "graphs-eval")]
    pub output: PathBuf,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

/// The readings of the essential graph's ties, as `--tie-rule` names them.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum TieArg {
    /// surfcap's reading.
    Surfcap,
    /// Eq. 3.2 read literally.
    Literal,
}

impl From<TieArg> for TieReading {
    fn from(a: TieArg) -> Self {
        match a {
            TieArg::Surfcap => TieReading::Surfcap,
            TieArg::Literal => TieReading::Literal,
        }
    }
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.subject.path], "eval-graphs")?;
    anyhow::ensure!(!a.alphas.is_empty(), "--alpha: expected at least one value");
    let s = a.subject.open(ctx)?;
    let opts = GraphComparisonOptions {
        alphas: a.alphas.clone(),
        plot_pairs: a.plot_pairs,
        table: a.table.params(s.fps)?,
        ties: a.tie_rule.into(),
    };
    let pipe = a.cache.pipeline(ctx, s)?;
    let output = a.output.as_path();
    let r = graph_comparison_eval(&pipe, &opts)?;
    std::fs::create_dir_all(output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", output.display()))?;
    let (blue, red) = ((31, 119, 180), (214, 39, 40));
    let series = |name: &str, points: Vec<(f64, f64)>, color, markers| Series {
        name: name.into(),
        points,
        color,
        dashed: false,
        markers,
    };
    let chart = |title: &str, y: &str, eg: &dyn Fn(&AlphaRow) -> f64, mg: &dyn Fn(&AlphaRow) -> f64| LineChart {
        title: format!("{title} ({})", r.subject),
        x_label: "alpha".into(),
        y_label: y.into(),
        series: vec![
            series("essential graph", r.rows.iter().map(|x| (x.alpha.get(), eg(x))).collect(), blue, true),
            series("motion graph", r.rows.iter().map(|x| (x.alpha.get(), mg(x))).collect(), red, true),
        ],
    };
    let mut plots = write_line_chart(
        &output.join("density"),
        &chart("Graph density (eq. 3.4)", "density", &|x| x.essential_graph.density, &|x| x.motion_graph.density),
    )?;
    plots.extend(write_line_chart(
        &output.join("mean_cost"),
        &chart("Mean shortest-path cost", "mean cost", &|x| x.essential_graph.mean, &|x| x.motion_graph.mean),
    )?);
    for c in &r.path_costs {
        let chart = LineChart {
            title: format!("Shortest-path costs, alpha = {} ({})", c.alpha, r.subject),
            x_label: "frame pairs (sorted by essential-graph cost)".into(),
            y_label: "path cost".into(),
            series: vec![
                series("essential graph", c.essential_graph.clone(), blue, false),
                series("motion graph", c.motion_graph.clone(), red, false),
            ],
        };
        let stem = format!("paths_alpha_{}", c.alpha.to_string().replace('.', "_"));
        plots.extend(write_line_chart(&output.join(stem), &chart)?);
    }
    let (report, rp) = super::folder::save_report(output, "graphs.json", &r, "plots", &plots)?;
    ctx.result(&report, || {
        println!(
            "subject {} ({} frames); shortest-path costs over the pairs the motion graph connects (thesis Fig. 3.8); \
             essential graph's ties: {}",
            r.subject,
            r.frames,
            if r.tie_rule == "literal" { "eq. 3.2 read literally" } else { "surfcap's reading" }
        );
        println!(
            "{:>7} | {:>10} {:>10} | {:>10} {:>10} | {:>9} {:>9} | {:>7}",
            "alpha", "MG mean", "MG std", "EG mean", "EG std", "MG dens.", "EG dens.", "MG<EG"
        );
        for x in &r.rows {
            let (m, e) = (&x.motion_graph, &x.essential_graph);
            println!(
                "{:>7} | {:>10.4} {:>10.4} | {:>10.4} {:>10.4} | {:>9.5} {:>9.5} | {:>7}",
                x.alpha, m.mean, m.std, e.mean, e.std, m.density, e.density, x.pairs_where_motion_graph_is_cheaper
            );
        }
        println!("wrote {} and {} plots in {} ({:.1} s)", rp.display(), plots.len(), output.display(), r.seconds);
    });
    ctx.commit(outs)
}
