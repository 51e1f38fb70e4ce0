//! `surfcap eval sparse-graph`: the sparse essential graph against the exact one
//! (`surfcap_eval::sparse_graph_eval` computes it; this command writes sparse-graph.json and
//! the plots and prints the table).

use std::path::{Path, PathBuf};

use surfcap_eval::sparse_graph_eval::{SparseGraphEval, SparseGraphEvalOptions, cmu_subject, sparse_graph_eval};
use surfcap_pipeline::{GraphKind, GraphParams};
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{AlphaOpt, CacheOpts, TableOpts};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("CMU clips"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Vertices of the mannequin (1000 to 20000).
    #[arg(long, default_value_t = 1000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Frame rate the clips are resampled to (50: about 1,900 frames).
    #[arg(long, default_value_t = 50.0, value_parser = crate::options::positive)]
    pub fps: f64,
    /// Values of k (transitions kept per frame).
    #[arg(long = "k", value_delimiter = ',', default_value = "2,4,8,16,32,64", value_parser = crate::options::count)]
    pub ks: Vec<usize>,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    /// Folder for the report (sparse-graph.json) and the plots.
    #[arg(short, long, default_value = "sparse-graph-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.data], "eval-sparse-graph")?;
    let (data, cache, output) = (a.data.as_path(), &a.cache, a.output.as_path());
    let subject = cmu_subject(data, a.vertices, a.fps)?;
    ctx.note(&format!(
        "subject: the mannequin ({} vertices, {} triangles) moved by every CMU clip of {} at {} fps: {} frames",
        subject.topology().n_vertices(),
        subject.topology().n_triangles(),
        data.join("cmu_bvh").display(),
        a.fps,
        subject.n_frames()
    ));
    let graph = GraphParams { table: a.table.params(subject.fps)?, kind: GraphKind::Essential, alpha: a.alpha.value() };
    let mut opts = SparseGraphEvalOptions::cmu(graph);
    opts.ks.clone_from(&a.ks);
    let bar = crate::progress::Bar::new(ctx);
    let pipe = cache.pipeline(ctx, subject)?;
    let r = sparse_graph_eval(&pipe, &opts, &bar)?;
    drop(bar);
    let plots = plot(&r, output)?;
    let (report, rp) = super::folder::save_report(output, "sparse-graph.json", &r, "plots", &plots)?;
    ctx.result(&report, || print_table(&r, &rp, &plots, output));
    ctx.commit(outs)
}

fn plot(r: &SparseGraphEval, output: &Path) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let (blue, red, green) = ((31, 119, 180), (214, 39, 40), (44, 160, 44));
    let series = |name: &str, points: Vec<(f64, f64)>, color| Series {
        name: name.into(),
        points,
        color,
        dashed: false,
        markers: true,
    };
    let pct = r.tolerance * 100.0;
    let at = |f: &dyn Fn(&surfcap_eval::sparse_graph_eval::KRow) -> f64| {
        r.rows.iter().map(|x| (x.k as f64, f(x))).collect::<Vec<_>>()
    };
    let costs = LineChart {
        title: format!("Sparse vs exact essential graph ({}, {} frames)", r.subject, r.frames),
        x_label: "k (transitions kept per frame)".into(),
        y_label: "% of all-pairs costs".into(),
        series: vec![
            series(&format!("within {pct}% of the exact cost"), at(&|x| 100.0 * x.within_tolerance), blue),
            series("unreachable", at(&|x| 100.0 * x.unreachable as f64 / r.connected_pairs.max(1) as f64), red),
        ],
    };
    let mut plots = write_line_chart(&output.join("costs_within"), &costs)?;
    let ratio = LineChart {
        title: format!("Mean shortest-path cost ratio sparse / exact ({})", r.subject),
        x_label: "k (transitions kept per frame)".into(),
        y_label: "cost ratio".into(),
        series: vec![series("mean", at(&|x| x.mean_ratio), blue), series("largest", at(&|x| x.max_ratio), red)],
    };
    plots.extend(write_line_chart(&output.join("cost_ratio"), &ratio)?);
    let queries = LineChart {
        title: format!("Queries on the sparse graph against the exact graph ({})", r.subject),
        x_label: "k (transitions kept per frame)".into(),
        y_label: "worst change, % (error or cost)".into(),
        series: vec![series(
            "worst query",
            at(&|x| if x.worst_query_change.is_finite() { 100.0 * x.worst_query_change } else { f64::NAN }),
            green,
        )],
    };
    plots.extend(write_line_chart(&output.join("queries"), &queries)?);
    Ok(plots)
}

fn print_table(r: &SparseGraphEval, rp: &Path, plots: &[std::path::PathBuf], output: &Path) {
    let pct = r.tolerance * 100.0;
    println!(
        "subject {}: {} frames, {} vertices, {} triangles; alpha {}, segments {}..{}; distances {:.1} s, table {:.1} s{}",
        r.subject,
        r.frames,
        r.vertices,
        r.triangles,
        r.alpha,
        r.l_min,
        r.l_max,
        r.distances_seconds,
        r.table_seconds,
        if r.cached { " (from the cache)" } else { "" }
    );
    println!(
        "exact essential graph: {} edges ({} transitions), {:.2} s; {} connected pairs",
        r.exact.edges, r.exact.transitions, r.exact.seconds, r.connected_pairs
    );
    println!(
        "{:>4} | {:>8} {:>8} | {:>9} {:>10} {:>9} {:>11} | {:>8} | {:>10} | {:>4}",
        "k",
        "k-graph",
        "edges",
        format!("<={pct}%"),
        "mean ratio",
        "max ratio",
        "unreachable",
        "build s",
        "worst qry",
        "ok"
    );
    for x in &r.rows {
        println!(
            "{:>4} | {:>8} {:>8} | {:>8.3}% {:>10.5} {:>9.4} {:>11} | {:>8.2} | {:>9.2}% | {:>4}",
            x.k,
            x.sparse_edges,
            x.edges,
            100.0 * x.within_tolerance,
            x.mean_ratio,
            x.max_ratio,
            x.unreachable,
            x.seconds,
            100.0 * x.worst_query_change,
            if x.acceptable { "yes" } else { "no" }
        );
    }
    println!("queries (path: mean curve error m / realism cost; key pose: time error frames / realism cost):");
    for (q, (name, kind, e)) in r.exact.queries.iter().enumerate() {
        let cell = |o: &surfcap_eval::sparse_graph_eval::QueryOutcome| match &o.failed {
            Some(_) => "failed".to_string(),
            None if *kind == "path" => format!("{:.3}/{:.2}", o.error, o.cost),
            None => format!("{:.0}/{:.2}", o.error, o.cost),
        };
        let ks: Vec<String> = r.rows.iter().map(|x| format!("k{} {}", x.k, cell(&x.queries[q].sparse))).collect();
        println!("  {kind} {name}: exact {} | {}", cell(e), ks.join(" | "));
    }
    match r.chosen_k {
        Some(k) => println!("chosen k = {k} ({})", r.rule),
        None => println!("no k meets the rule ({})", r.rule),
    }
    println!(
        "walk model: {} transitions, {:.1} s; total {:.1} s; wrote {} and {} plots in {}",
        r.model_transitions,
        r.model_seconds,
        r.seconds,
        rp.display(),
        plots.len(),
        output.display()
    );
}
