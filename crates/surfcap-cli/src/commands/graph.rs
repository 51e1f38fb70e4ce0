//! `surfcap graph build <subject> --kind essential|motion --alpha A`: the essential graph or
//! the motion-graph baseline over a subject's frames (thesis 3.3), cached; and
//! `surfcap eval graphs`: both graphs for several alphas (thesis Fig. 3.2 and 3.8).

use std::cell::{OnceCell, RefCell};
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;
use surfcap_mesh::Subject;
use surfcap_mesh::derived_cache::subject_hash;
use surfcap_mesh::io::npy::{NpyArray, write_npy};
use surfcap_motion::edge_weights::{EdgeWeights, edge_weights};
use surfcap_motion::essential_graph::essential_graph;
use surfcap_motion::graph::{Edge, Graph};
use surfcap_motion::motion_graph::motion_graph;
use surfcap_motion::transition_table::{TableParams, TransitionTable};
use surfcap_plot::{LineChart, Series, write_line_chart};

use super::distance::CacheOpts;
use super::eval_transitions::mean_std;
use super::transitions::{TableOpts, cached_table};
use super::{SourceOpts, print_json};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Build a graph over all frames and write edges.npy (u32 [E, 2]), weights.npy (f64 [E])
    /// and graph.json (density, edge counts).
    Build {
        /// A subject cache, or any source `surfcap import` reads.
        subject: PathBuf,
        /// essential (union of all shortest-path trees) or motion (Kovar's local minima).
        #[arg(long, default_value = "essential")]
        kind: String,
        /// Tolerance alpha between deformation and duration (thesis eq. 3.2-3.3).
        #[arg(long, default_value_t = 0.05)]
        alpha: f64,
        /// Output folder.
        #[arg(short, long, default_value = "graph")]
        output: PathBuf,
        #[command(flatten)]
        table: TableOpts,
        #[command(flatten)]
        cache: CacheOpts,
        #[command(flatten)]
        source: SourceOpts,
    },
}

/// Which graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Essential,
    Motion,
}

impl Kind {
    pub fn parse(s: &str) -> anyhow::Result<Kind> {
        match s {
            "essential" => Ok(Kind::Essential),
            "motion" => Ok(Kind::Motion),
            _ => anyhow::bail!("--kind {s:?}: expected essential or motion"),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Kind::Essential => "essential",
            Kind::Motion => "motion",
        }
    }
}

pub fn check_alpha(alpha: f64) -> anyhow::Result<()> {
    anyhow::ensure!(alpha.is_finite() && alpha > 0.0, "--alpha {alpha}: expected a positive number");
    Ok(())
}

/// The graphs of one subject and table parameters. The transition table is read (from its
/// cache, or computed) at most once, and the edge weights of the last alpha are kept, so the
/// essential and motion graphs of one alpha share them.
pub struct SubjectGraphs<'a> {
    ctx: &'a crate::Ctx,
    s: &'a Subject,
    p: TableParams,
    cache: &'a CacheOpts,
    table: OnceCell<TransitionTable>,
    weights: RefCell<Option<EdgeWeights>>,
}

impl<'a> SubjectGraphs<'a> {
    pub fn new(ctx: &'a crate::Ctx, s: &'a Subject, p: TableParams, cache: &'a CacheOpts) -> Self {
        SubjectGraphs { ctx, s, p, cache, table: OnceCell::new(), weights: RefCell::new(None) }
    }

    pub fn subject(&self) -> &'a Subject {
        self.s
    }

    pub fn params(&self) -> &TableParams {
        &self.p
    }

    /// The transition table (from its cache, or computed), read once.
    pub fn table(&self) -> surfcap_mesh::Result<&TransitionTable> {
        if let Some(t) = self.table.get() {
            return Ok(t);
        }
        let (t, _) = cached_table(self.ctx, self.s, &self.p, self.cache).map_err(|e| {
            surfcap_mesh::Error::new(surfcap_mesh::ErrorKind::Unsupported, format!("transition table: {e}"))
        })?;
        Ok(self.table.get_or_init(|| t))
    }

    fn weights(&self, alpha: f64) -> surfcap_mesh::Result<EdgeWeights> {
        if let Some(w) = self.weights.borrow().as_ref().filter(|w| w.alpha == alpha) {
            return Ok(w.clone());
        }
        let w = edge_weights(self.table()?, self.s.frame_index(), alpha);
        *self.weights.borrow_mut() = Some(w.clone());
        Ok(w)
    }

    /// The graph of `kind` at `alpha` (cached on disk as an [E, 3] array of from, to, weight),
    /// and whether it came from the cache.
    pub fn graph(&self, kind: Kind, alpha: f64) -> anyhow::Result<(Graph, bool)> {
        check_alpha(alpha)?;
        let (s, p) = (self.s, &self.p);
        let store = self.cache.cache();
        let key = format!(
            "distance=deformation w=0.01 l={}..{} slope={:?} kind={} alpha={alpha:e} algo=2",
            p.l_min,
            p.l_max,
            p.slope,
            kind.name()
        );
        let path = store.path("graph", &subject_hash(s), &key);
        if self.cache.no_cache {
            let _ = std::fs::remove_file(&path);
        }
        let (a, cached) = store.get_or_compute(&path, || {
            let w = self.weights(alpha)?;
            let g = build(&w, s, kind, self.ctx);
            let data = g.edges().iter().flat_map(|e| [e.from as f64, e.to as f64, e.weight]).collect();
            Ok::<_, surfcap_mesh::Error>(NpyArray { shape: vec![g.edges().len(), 3], data })
        })?;
        anyhow::ensure!(a.shape.len() == 2 && a.shape[1] == 3, "cached graph has shape {:?}, expected [E, 3]", a.shape);
        let edges = a.data.chunks_exact(3).map(|e| Edge { from: e[0] as u32, to: e[1] as u32, weight: e[2] }).collect();
        Ok((Graph::new(s.n_frames(), edges), cached))
    }
}

fn build(w: &EdgeWeights, s: &Subject, kind: Kind, ctx: &crate::Ctx) -> Graph {
    match kind {
        Kind::Essential => essential_graph(w, &crate::progress::Bar::new(ctx)).graph,
        Kind::Motion => motion_graph(w, s.frame_index()).graph,
    }
}

/// Counts of original (successive-frame) and transition edges.
fn edge_kinds(g: &Graph, s: &Subject) -> (usize, usize) {
    let original =
        g.edges().iter().filter(|e| EdgeWeights::is_original(s.frame_index(), e.from as usize, e.to as usize)).count();
    (original, g.edges().len() - original)
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let What::Build { subject, kind, alpha, output, table, cache, source } = a.what;
    let kind = Kind::parse(&kind)?;
    check_alpha(alpha)?;
    let s = super::open(ctx, &subject, &source)?;
    let p = table.params(s.fps)?;
    let t0 = Instant::now();
    let (g, cached) = SubjectGraphs::new(ctx, &s, p, &cache).graph(kind, alpha)?;
    let secs = t0.elapsed().as_secs_f64();
    let (original, transitions) = edge_kinds(&g, &s);
    std::fs::create_dir_all(&output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", output.display()))?;
    let ends: Vec<u32> = g.edges().iter().flat_map(|e| [e.from, e.to]).collect();
    let weights: Vec<f64> = g.edges().iter().map(|e| e.weight).collect();
    surfcap_mesh::atomic::write_file(&output.join("edges.npy"), |o| write_npy(o, &[g.edges().len(), 2], &ends))?;
    surfcap_mesh::atomic::write_file(&output.join("weights.npy"), |o| write_npy(o, &[g.edges().len()], &weights))?;
    let frames_in_graph = (0..g.n).filter(|&i| !g.out(i).is_empty()).count();
    let report = json!({
        "subject": s.name, "kind": kind.name(), "alpha": alpha, "nodes": g.n, "frames_in_graph": frames_in_graph,
        "edges": g.edges().len(), "original_edges": original, "transition_edges": transitions,
        "density": g.density(), "l_min": p.l_min, "l_max": p.l_max, "slope": p.slope,
        "seconds": secs, "cached": cached, "files": ["edges.npy", "weights.npy", "graph.json"],
    });
    surfcap_mesh::atomic::write_file(&output.join("graph.json"), |o| {
        o.write_all(serde_json::to_string_pretty(&report).expect("JSON").as_bytes())
    })?;
    if ctx.json {
        print_json(&report);
    } else if !ctx.quiet {
        println!(
            "{} graph of {:?}, alpha {alpha}: {} frames ({frames_in_graph} with edges), {} edges ({original} original, {transitions} transitions), density {:.5} -> {} ({}, {secs:.2} s)",
            kind.name(),
            s.name,
            g.n,
            g.edges().len(),
            g.density(),
            output.display(),
            if cached { "from cache" } else { "computed" }
        );
    }
    Ok(())
}

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
        check_alpha(a)?;
    }
    let s = super::open(ctx, path, source)?;
    let p = o.table.params(s.fps)?;
    let n = s.n_frames();
    let mut rows = Vec::new();
    // Per alpha: the sampled pairs' costs in the essential and the motion graph.
    type Curve = Vec<(f64, f64)>;
    let mut path_plots: Vec<(f64, Curve, Curve)> = Vec::new();
    let t0 = Instant::now();
    let graphs = SubjectGraphs::new(ctx, &s, p, &o.cache);
    for &alpha in &o.alphas {
        let (eg, _) = graphs.graph(Kind::Essential, alpha)?;
        let (mg, _) = graphs.graph(Kind::Motion, alpha)?;
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
