//! Essential graph vs motion graph for several alphas (thesis 3.3.3, Fig. 3.2 and 3.8):
//! densities and the mean and standard deviation of all-pairs shortest-path costs.
//!
//! The essential graph's tie rule has two readings (PAPER-NOTES on the essential graph; module
//! `surfcap_motion::essential_graph`): surfcap's (eq. 3.2 gives a same-sequence pair an edge
//! only when the transition is strictly cheaper than the original frames; a predecessor is
//! replaced only by a strictly cheaper path), the default, and eq. 3.2 read literally (every
//! forward same-sequence pair has an edge, and one that ties with the original frames is kept).
//! [`GraphComparisonOptions::ties`] picks one and the report records it. The literal reading's
//! essential graphs are built here, not cached by the pipeline; the motion graph is the same
//! under both.

use std::time::Instant;

use serde::Serialize;
use surfcap_mesh::NoProgress;
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::essential_graph::{TieRule, essential_graph_with, with_skip_edges};
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{GraphKind, GraphParams, Pipeline};

use crate::MeanStd;
use crate::error::{Error, Result};

/// Options of [`graph_comparison_eval`] (`surfcap eval graphs`).
#[derive(Debug, Clone)]
pub struct GraphComparisonOptions {
    /// Values of alpha.
    pub alphas: Vec<Alpha>,
    /// Frame pairs in the sampled shortest-path curves ([`PathCostCurves`]).
    pub plot_pairs: usize,
    /// The transition table both graphs are built on.
    pub table: TableParams,
    /// Reading of the essential graph's ties: surfcap's (the default) or eq. 3.2's literal one.
    pub ties: TieReading,
}

/// The readings of the essential graph's ties, as `--tie-rule` names them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TieReading {
    /// No same-sequence edge that only matches the original frames; strictly cheaper paths win.
    #[default]
    Surfcap,
    /// Eq. 3.2 read literally: every forward same-sequence pair has an edge of weight
    /// min(alpha (j - i), D + alpha L), and an edge tying with the original frames is kept.
    Literal,
}

impl TieReading {
    /// The name used on the command line and in the report: "surfcap" or "literal".
    pub fn name(self) -> &'static str {
        match self {
            TieReading::Surfcap => "surfcap",
            TieReading::Literal => "literal",
        }
    }
}

/// The motion graph at one alpha; `mean`/`std` over the compared pairs.
#[derive(Debug, Clone, Serialize)]
pub struct MotionGraphStats {
    pub mean: f64,
    pub std: f64,
    /// Eq. 3.4.
    pub density: f64,
    pub edges: usize,
    /// Frames with an outgoing edge (the rest were pruned as dead ends).
    pub frames: usize,
}

/// The essential graph at one alpha; `mean`/`std` over the compared pairs, `*_all_pairs` over
/// every pair it connects.
#[derive(Debug, Clone, Serialize)]
pub struct EssentialGraphStats {
    pub mean: f64,
    pub std: f64,
    /// Eq. 3.4.
    pub density: f64,
    pub edges: usize,
    pub mean_all_pairs: f64,
    pub std_all_pairs: f64,
    /// Ordered pairs (i != j) the essential graph connects.
    pub pairs: usize,
}

/// Both graphs at one alpha.
#[derive(Debug, Clone, Serialize)]
pub struct AlphaRow {
    pub alpha: Alpha,
    pub motion_graph: MotionGraphStats,
    pub essential_graph: EssentialGraphStats,
    /// Ordered pairs (i != j) the motion graph connects: both graphs are compared on these.
    pub pairs_compared: usize,
    /// Compared pairs where the motion graph's path is cheaper (relative tolerance 1e-12).
    pub pairs_where_motion_graph_is_cheaper: usize,
}

/// A sample of the compared pairs at one alpha, sorted by the essential graph's cost
/// (Fig. 3.8b-c): points (index in the sample, path cost) of each graph.
#[derive(Debug, Clone, Serialize)]
pub struct PathCostCurves {
    pub alpha: Alpha,
    pub essential_graph: Vec<(f64, f64)>,
    pub motion_graph: Vec<(f64, f64)>,
}

/// Result of [`graph_comparison_eval`]; serialised, the report `graphs.json` without its
/// `plots`.
#[derive(Debug, Clone, Serialize)]
pub struct GraphComparisonEval {
    pub subject: String,
    pub frames: usize,
    pub l_min: usize,
    pub l_max: usize,
    /// Reading of the essential graph's ties: "surfcap" or "literal" (eq. 3.2 read literally).
    pub tie_rule: &'static str,
    pub rows: Vec<AlphaRow>,
    /// Time to build (or read) the graphs and compare them, seconds.
    pub seconds: f64,
    /// One per alpha, in the order of `rows` (the `paths_alpha_*` plots).
    #[serde(skip)]
    pub path_costs: Vec<PathCostCurves>,
}

/// Thesis 3.3.3, Fig. 3.2 and 3.8: for each alpha, both graphs' densities and the mean and
/// standard deviation of all-pairs shortest-path costs. Pairs: ordered (i, j), i != j, that
/// the motion graph connects (its dead ends are pruned), so both graphs are compared on the
/// same pairs; the essential graph's mean over all its pairs is reported beside.
pub fn graph_comparison_eval(pipe: &Pipeline, o: &GraphComparisonOptions) -> Result<GraphComparisonEval> {
    if o.alphas.is_empty() {
        return Err(Error::parameter("--alpha", None, "expected at least one value"));
    }
    let s = pipe.subject();
    let n = s.n_frames();
    let mut rows = Vec::new();
    let mut path_costs = Vec::new();
    let t0 = Instant::now();
    for &alpha in &o.alphas {
        let graph = |kind| pipe.graph(&GraphParams { table: o.table, kind, alpha });
        let eg = match o.ties {
            TieReading::Surfcap => graph(GraphKind::Essential)?.value,
            TieReading::Literal => {
                let w = with_skip_edges(&*pipe.edge_weights(&o.table, alpha)?, s.frame_index());
                std::sync::Arc::new(essential_graph_with(&w, TieRule::FirstFound, &NoProgress).graph)
            }
        };
        let mg = graph(GraphKind::Motion)?.value;
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
        let (m, e, all) = (MeanStd::of(&on_mg), MeanStd::of(&on_eg), MeanStd::of(&eg_all));
        rows.push(AlphaRow {
            alpha,
            motion_graph: MotionGraphStats {
                mean: m.mean,
                std: m.std,
                density: mg.density(),
                edges: mg.edges().len(),
                frames: (0..n).filter(|&i| !mg.out(i).is_empty()).count(),
            },
            essential_graph: EssentialGraphStats {
                mean: e.mean,
                std: e.std,
                density: eg.density(),
                edges: eg.edges().len(),
                mean_all_pairs: all.mean,
                std_all_pairs: all.std,
                pairs: eg_all.len(),
            },
            pairs_compared: on_mg.len(),
            pairs_where_motion_graph_is_cheaper: lower_in_motion,
        });
        // A sample of the compared pairs, sorted by the essential graph's cost (Fig. 3.8b-c).
        let step = (on_mg.len() / o.plot_pairs.max(1)).max(1);
        let mut sample: Vec<(f64, f64)> = on_eg.iter().zip(&on_mg).step_by(step).map(|(&e, &m)| (e, m)).collect();
        sample.sort_by(|a, b| a.0.total_cmp(&b.0));
        path_costs.push(PathCostCurves {
            alpha,
            essential_graph: sample.iter().enumerate().map(|(x, v)| (x as f64, v.0)).collect(),
            motion_graph: sample.iter().enumerate().map(|(x, v)| (x as f64, v.1)).collect(),
        });
    }
    Ok(GraphComparisonEval {
        subject: s.name.clone(),
        frames: n,
        l_min: o.table.l_min,
        l_max: o.table.l_max,
        tie_rule: o.ties.name(),
        rows,
        seconds: t0.elapsed().as_secs_f64(),
        path_costs,
    })
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::test_subjects::{pipeline, worm};

    fn options(alphas: Vec<f64>) -> GraphComparisonOptions {
        let alphas = alphas.into_iter().map(|a| Alpha::new(a).unwrap()).collect();
        GraphComparisonOptions {
            alphas,
            plot_pairs: 20,
            table: TableParams { l_min: 3, l_max: 6, slope: Some(3) },
            ties: TieReading::Surfcap,
        }
    }

    #[test]
    fn essential_paths_are_never_dearer_and_the_report_is_the_cli_json() {
        let pipe = pipeline(worm(30.0));
        let r = graph_comparison_eval(&pipe, &options(vec![0.05, 0.2])).unwrap();
        let n = pipe.subject().n_frames();
        assert_eq!((r.frames, r.l_min, r.l_max), (n, 3, 6));
        assert_eq!(r.rows.len(), 2);
        assert_eq!(r.path_costs.iter().map(|c| c.alpha.get()).collect::<Vec<_>>(), [0.05, 0.2]);
        for (row, curves) in r.rows.iter().zip(&r.path_costs) {
            assert!(row.pairs_compared > 0, "{row:?}");
            // Thesis 3.3.3: the essential graph keeps every shortest path.
            assert_eq!(row.pairs_where_motion_graph_is_cheaper, 0);
            assert!(row.essential_graph.mean <= row.motion_graph.mean, "{row:?}");
            assert!(row.essential_graph.pairs >= row.pairs_compared);
            assert!(row.motion_graph.frames <= n);
            assert!(curves.essential_graph.len() <= 20 + 1 && !curves.essential_graph.is_empty());
            assert_eq!(curves.essential_graph.len(), curves.motion_graph.len());
            assert!(curves.essential_graph.windows(2).all(|w| w[0].1 <= w[1].1), "sorted by essential cost");
            assert!(curves.essential_graph.iter().zip(&curves.motion_graph).all(|(e, m)| e.1 <= m.1 * (1.0 + 1e-12)));
        }
        // graphs.json as the CLI wrote it, without "plots".
        let rows: Vec<_> = r
            .rows
            .iter()
            .map(|x| {
                let (m, e) = (&x.motion_graph, &x.essential_graph);
                json!({
                    "alpha": x.alpha,
                    "motion_graph": { "mean": m.mean, "std": m.std, "density": m.density, "edges": m.edges, "frames": m.frames },
                    "essential_graph": { "mean": e.mean, "std": e.std, "density": e.density, "edges": e.edges, "mean_all_pairs": e.mean_all_pairs, "std_all_pairs": e.std_all_pairs, "pairs": e.pairs },
                    "pairs_compared": x.pairs_compared,
                    "pairs_where_motion_graph_is_cheaper": x.pairs_where_motion_graph_is_cheaper,
                })
            })
            .collect();
        let cli = json!({ "subject": r.subject, "frames": n, "l_min": 3, "l_max": 6, "tie_rule": "surfcap", "rows": rows, "seconds": r.seconds });
        assert_eq!(serde_json::to_value(&r).unwrap(), cli);
    }

    #[test]
    fn alphas_are_checked_first() {
        let pipe = pipeline(worm(30.0));
        let e = |alphas| graph_comparison_eval(&pipe, &options(alphas)).unwrap_err().to_string();
        assert_eq!(e(vec![]), "--alpha: expected at least one value");
        // An alpha of 0 cannot reach the comparison: it is refused where it is made.
        assert_eq!(Alpha::new(0.0).unwrap_err().to_string(), "alpha 0: expected a positive number");
    }

    #[test]
    fn the_literal_tie_rule_keeps_more_edges_at_the_same_path_costs_and_is_recorded() {
        let pipe = pipeline(worm(30.0));
        let ours = graph_comparison_eval(&pipe, &options(vec![0.05])).unwrap();
        let o = GraphComparisonOptions { ties: TieReading::Literal, ..options(vec![0.05]) };
        let literal = graph_comparison_eval(&pipe, &o).unwrap();
        assert_eq!((ours.tie_rule, literal.tie_rule), ("surfcap", "literal"));
        assert_eq!(serde_json::to_value(&literal).unwrap()["tie_rule"], "literal");
        let (a, b) = (&ours.rows[0], &literal.rows[0]);
        assert!(b.essential_graph.edges > a.essential_graph.edges, "{a:?} vs {b:?}");
        assert!(b.essential_graph.density > a.essential_graph.density);
        assert!((a.essential_graph.mean - b.essential_graph.mean).abs() <= 1e-9 * a.essential_graph.mean);
        assert_eq!(a.motion_graph.edges, b.motion_graph.edges, "the motion graph is the same");
    }
}
