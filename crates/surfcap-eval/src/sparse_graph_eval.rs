//! What the sparse essential graph (`surfcap_motion::sparse_essential_graph`)
//! loses against the exact one (thesis 3.3.1) on a subject where the exact one is feasible:
//! for each k, the fraction of all-pairs shortest-path costs within 1% of the exact ones, the
//! mean cost ratio sparse / exact over the pairs both connect, the pairs that became
//! unreachable, the edges kept and the build times; and the effect on synthesis: path following
//! (thesis 3.5.1: a straight line and a curve) and key-pose timing (3.5.2: a walk between two
//! key frames lasting a given time) run on both graphs, their curve errors, realism costs and
//! time errors compared.
//!
//! The subject by default ([`cmu_subject`]): the built-in mannequin moved by every CMU clip of
//! the shared data (subject 16's walks, turns, jog, jump, stop and subject 5's dance) resampled
//! to 50 fps: about 1,900 frames, where the exact build is O(V^3) but feasible.
//!
//! Both graphs' queries use one walk model (the rigid track of every transition), built over the
//! union of the exact and every sparse essential graph, so a query differs only by the graph it
//! searches.
//!
//! Choice of k ([`SparseGraphEval::chosen_k`]): the smallest k whose costs are within 1% of the
//! exact ones for at least 99% of the pairs and whose queries are none more than 1% worse (curve
//! error for paths, realism cost and time error for key poses). Measured on the default subject
//! no k up to 512 meets it; `surfcap_motion::sparse_essential_graph::DEFAULT_K` says what was
//! chosen instead and why.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_mesh::{Progress, Subject};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::essential_graph::essential_graph;
use surfcap_motion::graph::{Edge, Graph};
use surfcap_motion::path_following::{Curve, PathSearch, follow_path};
use surfcap_motion::sparse_essential_graph::{sparse_essential_graph, sparse_transition_graph};
use surfcap_motion::timed_walk::TimedGraph;
use surfcap_motion::walk_sequence::{Step, WalkModel};
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::error::{Error, Result};

/// Every CMU clip of the shared data: subject 16's (walk, turns, from standstill, jog, jump,
/// stop) and subject 5's dance.
pub const CMU_CLIPS: [&str; 8] = ["16_15", "16_17", "16_19", "16_31", "16_36", "16_07", "16_57", "05_18"];

/// The mannequin of about `vertices` vertices moved by [`CMU_CLIPS`] resampled to `fps` (metres).
pub fn cmu_subject(data: &Path, vertices: usize, fps: f64) -> Result<Subject> {
    let m = mannequin(&BodyShape::average(), vertices)?;
    let mut clips = Vec::new();
    for c in CMU_CLIPS {
        let path = data.join("cmu_bvh").join(format!("{c}.bvh"));
        let bvh = read_bvh(&path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        clips.push(Clip::from_bvh(&path, &bvh, &m, mpu)?);
    }
    Ok(mannequin_subject(&format!("mannequin-cmu-{fps}fps"), &m, &clips, fps)?)
}

/// A path-following query: a polyline on the ground, in subject units.
#[derive(Debug, Clone, Serialize)]
pub struct PathQuery {
    pub name: String,
    pub points: Vec<[f64; 2]>,
}

/// A key-pose query: from one frame to another (`sequence:frame`) in `seconds`.
#[derive(Debug, Clone, Serialize)]
pub struct KeyPoseQuery {
    pub from: String,
    pub to: String,
    pub seconds: f64,
}

/// Options of [`sparse_graph_eval`].
#[derive(Debug, Clone)]
pub struct SparseGraphEvalOptions {
    /// Values of k (transitions kept per frame).
    pub ks: Vec<usize>,
    /// The table and alpha of both graphs (the kind is ignored).
    pub graph: GraphParams,
    pub paths: Vec<PathQuery>,
    pub key_poses: Vec<KeyPoseQuery>,
    /// A cost is "preserved" within this relative tolerance (0.01); a query is "worse" by more
    /// than it too.
    pub tolerance: f64,
}

impl SparseGraphEvalOptions {
    /// k in {2, 4, ..., 64}, a 12 m straight line and a 12 m S-curve, and key poses between the
    /// CMU subject's clips (walk to jog, walk to jump, standstill to stop, walk to dance).
    pub fn cmu(graph: GraphParams) -> Self {
        let s_curve: Vec<[f64; 2]> = (0..=24)
            .map(|i| {
                let t = i as f64 / 24.0;
                [1.5 * (2.0 * std::f64::consts::PI * t).sin(), 10.0 * t]
            })
            .collect();
        let key = |from: &str, to: &str, seconds| KeyPoseQuery { from: from.into(), to: to.into(), seconds };
        SparseGraphEvalOptions {
            ks: vec![2, 4, 8, 16, 32, 64],
            graph,
            paths: vec![
                PathQuery { name: "straight 12 m".into(), points: vec![[0.0, 0.0], [0.0, 12.0]] },
                PathQuery { name: "S-curve 10 m".into(), points: s_curve },
            ],
            key_poses: vec![
                key("16_15:0", "16_36:last", 4.0),
                key("16_15:0", "16_07:last", 6.0),
                key("16_31:0", "16_57:last", 8.0),
                key("16_17:0", "05_18:middle", 10.0),
            ],
            tolerance: 0.01,
        }
    }
}

/// One query's outcome on one graph.
#[derive(Debug, Clone, Serialize)]
pub struct QueryOutcome {
    /// Path: mean curve error (subject units); key pose: absolute time error (frames).
    pub error: f64,
    /// Path: largest curve error; key pose: the walk's frames.
    pub extent: f64,
    /// Realism cost: the sum of the transitions' edge weights.
    pub cost: f64,
    pub transitions: usize,
    pub seconds: f64,
    /// Why the query failed, if it did.
    pub failed: Option<String>,
}

/// A query on the exact graph and on one sparse graph.
#[derive(Debug, Clone, Serialize)]
pub struct QueryComparison {
    pub query: String,
    pub kind: &'static str,
    pub sparse: QueryOutcome,
    /// Relative change of the error and the cost (sparse / exact - 1; 0 when both are 0).
    pub error_change: f64,
    pub cost_change: f64,
    /// Worse by more than the tolerance (error or cost; a failure is worse).
    pub worse: bool,
}

/// One k against the exact graph.
#[derive(Debug, Clone, Serialize)]
pub struct KRow {
    pub k: usize,
    /// Edges of the k-cheapest graph, and of its essential graph.
    pub sparse_edges: usize,
    pub edges: usize,
    pub transitions: usize,
    /// Of the pairs the exact graph connects (off the diagonal): the fraction whose sparse cost
    /// is within the tolerance of the exact one.
    pub within_tolerance: f64,
    /// Mean and largest sparse / exact over the pairs both connect (exact cost > 0).
    pub mean_ratio: f64,
    pub max_ratio: f64,
    /// Pairs the exact graph connects and the sparse one does not.
    pub unreachable: usize,
    pub seconds: f64,
    pub queries: Vec<QueryComparison>,
    /// Largest relative worsening over the queries (error or cost; infinity for a failure).
    pub worst_query_change: f64,
    /// Meets the rule of the choice.
    pub acceptable: bool,
}

/// The exact graph's side.
#[derive(Debug, Clone, Serialize)]
pub struct ExactSide {
    pub edges: usize,
    pub transitions: usize,
    pub seconds: f64,
    /// Each query: its name, kind and outcome.
    pub queries: Vec<(String, &'static str, QueryOutcome)>,
}

/// The result of [`sparse_graph_eval`].
#[derive(Debug, Clone, Serialize)]
pub struct SparseGraphEval {
    pub subject: String,
    pub frames: usize,
    pub vertices: usize,
    pub triangles: usize,
    pub alpha: Alpha,
    pub l_min: usize,
    pub l_max: usize,
    /// Distance matrix and transition table, seconds (0 when read from the cache), and whether
    /// they were.
    pub distances_seconds: f64,
    pub table_seconds: f64,
    pub cached: bool,
    /// Pairs the exact graph connects, off the diagonal.
    pub connected_pairs: usize,
    pub tolerance: f64,
    pub exact: ExactSide,
    pub rows: Vec<KRow>,
    /// The smallest acceptable k, if any.
    pub chosen_k: Option<usize>,
    pub rule: String,
    /// The walk model's transitions (over the union of all graphs) and its build time.
    pub model_transitions: usize,
    pub model_seconds: f64,
    pub seconds: f64,
}

/// A frame named `sequence:frame`, where frame may be `last` or `middle`.
fn frame_of(s: &Subject, text: &str) -> Result<u32> {
    let bad = |why: &str| Error::Parameter {
        option: "key pose",
        value: Some(text.into()),
        expected: format!("expected sequence:frame (a frame number, last or middle): {why}"),
    };
    let (name, frame) = text.rsplit_once(':').ok_or_else(|| bad("no ':'"))?;
    let index = s.frame_index();
    let seq =
        (0..index.n_sequences()).find(|&k| index.sequence_name(k) == name).ok_or_else(|| bad("no such sequence"))?;
    let len = index.range(seq).len();
    let f = match frame {
        "last" => len - 1,
        "middle" => len / 2,
        other => other.parse::<usize>().map_err(|_| bad("not a frame number"))?,
    };
    let g = index.global(seq, f).ok_or_else(|| bad(&format!("the sequence has {len} frames")))?;
    Ok(g as u32)
}

/// Realism cost (the transitions' weights) and transitions of a walk on `graph`.
fn realism(graph: &Graph, model: &WalkModel, walk: &[u32]) -> (f64, usize) {
    let (mut cost, mut count) = (0.0, 0);
    for uv in walk.windows(2) {
        if matches!(model.step(uv[0], uv[1]), Some(Step::Transition(_))) {
            count += 1;
            cost += graph.find(uv[0] as usize, uv[1] as usize).map_or(f64::NAN, |e| graph.edges()[e].weight);
        }
    }
    (cost, count)
}

fn failed(why: String) -> QueryOutcome {
    QueryOutcome {
        error: f64::INFINITY,
        extent: f64::INFINITY,
        cost: f64::INFINITY,
        transitions: 0,
        seconds: 0.0,
        failed: Some(why),
    }
}

/// Every query on `graph`: paths first, then key poses.
fn run_queries(
    s: &Subject,
    graph: &Graph,
    model: &WalkModel,
    curves: &[(String, Curve)],
    keys: &[(String, u32, u32, i64)],
) -> Vec<(String, &'static str, QueryOutcome)> {
    let search = PathSearch::for_fps(s.fps);
    let mut out = Vec::new();
    for (name, curve) in curves {
        let t = Instant::now();
        let o = match follow_path(model, graph, curve, &[], None, &search) {
            Ok(r) => {
                let (cost, transitions) = realism(graph, model, &r.walk);
                let mean = r.errors.iter().sum::<f64>() / r.errors.len().max(1) as f64;
                let max = r.errors.iter().copied().fold(0.0, f64::max);
                QueryOutcome {
                    error: mean,
                    extent: max,
                    cost,
                    transitions,
                    seconds: t.elapsed().as_secs_f64(),
                    failed: None,
                }
            }
            Err(e) => failed(e.to_string()),
        };
        out.push((name.clone(), "path", o));
    }
    let tg = TimedGraph::new(graph, model);
    let longest = tg.longest_edge();
    for (name, a, b, frames) in keys {
        let t = Instant::now();
        let o = match tg.walk_with_duration(*a, *b, *frames, longest) {
            Ok(w) => {
                let (_, transitions) = realism(graph, model, &w.walk);
                QueryOutcome {
                    error: (w.frames as i64 - frames).abs() as f64,
                    extent: w.frames as f64,
                    cost: w.cost,
                    transitions,
                    seconds: t.elapsed().as_secs_f64(),
                    failed: None,
                }
            }
            Err(e) => failed(e.to_string()),
        };
        out.push((name.clone(), "key pose", o));
    }
    out
}

/// Relative change b / a - 1 (0 when both are 0; infinity when only a is 0 or b failed).
fn change(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else if a == 0.0 || !b.is_finite() {
        f64::INFINITY
    } else {
        b / a - 1.0
    }
}

/// The sparse essential graph against the exact one on `pipe`'s subject (see the module
/// documentation).
pub fn sparse_graph_eval(
    pipe: &Pipeline,
    opts: &SparseGraphEvalOptions,
    progress: &dyn Progress,
) -> Result<SparseGraphEval> {
    let t_all = Instant::now();
    if opts.ks.is_empty() || opts.ks.contains(&0) {
        return Err(Error::Parameter {
            option: "--k",
            value: None,
            expected: "expected at least one whole number >= 1".into(),
        });
    }
    if !(opts.tolerance.is_finite() && opts.tolerance >= 0.0) {
        return Err(Error::Parameter {
            option: "tolerance",
            value: Some(opts.tolerance.to_string()),
            expected: "expected a number >= 0".into(),
        });
    }
    let s = pipe.subject();
    let n = s.n_frames();
    let index = s.frame_index();
    let p = &opts.graph;
    let t = Instant::now();
    let d = pipe.chain_distances()?;
    let distances_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let table = pipe.table(&p.table)?;
    let table_seconds = t.elapsed().as_secs_f64();
    let w = pipe.edge_weights(&p.table, p.alpha)?;
    // The queries, checked before any graph is built.
    let keys: Vec<(String, u32, u32, i64)> = opts
        .key_poses
        .iter()
        .map(|q| {
            let frames = (q.seconds * s.fps).round() as i64;
            Ok((
                format!("{} -> {} in {} s", q.from, q.to, q.seconds),
                frame_of(s, &q.from)?,
                frame_of(s, &q.to)?,
                frames,
            ))
        })
        .collect::<Result<_>>()?;

    progress.note("exact essential graph (O(V^3))");
    let t = Instant::now();
    let exact = essential_graph(&w, progress);
    let exact_seconds = t.elapsed().as_secs_f64();
    let mut sparse = Vec::new();
    for &k in &opts.ks {
        let t = Instant::now();
        let g = sparse_essential_graph(&w, index, k, progress);
        let secs = t.elapsed().as_secs_f64();
        let base_edges = sparse_transition_graph(&w, index, k).edges().len();
        sparse.push((k, g, secs, base_edges));
    }
    // One walk model over the union of every graph's edges.
    let t = Instant::now();
    let union: Vec<Edge> =
        exact.graph.edges().iter().chain(sparse.iter().flat_map(|(_, g, _, _)| g.graph.edges())).copied().collect();
    let union = Graph::new(n, union);
    let model = WalkModel::new(s, pipe.loops(), &union, &table.value, &d.value.values, p.table.slope, None);
    let model_seconds = t.elapsed().as_secs_f64();
    let (iu, iv) = model.plane();
    let curves: Vec<(String, Curve)> = opts
        .paths
        .iter()
        .map(|q| {
            let points = q
                .points
                .iter()
                .map(|xy| {
                    let mut p = [0.0; 3];
                    (p[iu], p[iv]) = (xy[0], xy[1]);
                    p
                })
                .collect();
            let c = Curve::new(points, vec![iu, iv]).map_err(|e| Error::Parameter {
                option: "path",
                value: Some(q.name.clone()),
                expected: e.to_string(),
            })?;
            Ok((q.name.clone(), c))
        })
        .collect::<Result<_>>()?;
    let transitions = |g: &Graph| g.edges().iter().filter(|e| !is_original(s, e)).count();
    progress.start("queries on the exact graph", 1);
    let exact_queries = run_queries(s, &exact.graph, &model, &curves, &keys);
    progress.finish();

    let connected: Vec<usize> = (0..n * n).filter(|&q| q / n != q % n && exact.costs[q].is_finite()).collect();
    let mut rows = Vec::new();
    progress.start("queries on the sparse graphs", sparse.len() as u64);
    for (k, g, secs, base_edges) in &sparse {
        let (mut within, mut unreachable, mut ratio_sum, mut ratios, mut max_ratio) =
            (0usize, 0usize, 0.0, 0usize, 1.0f64);
        for &q in &connected {
            let (e, c) = (exact.costs[q], g.costs[q]);
            if !c.is_finite() {
                unreachable += 1;
                continue;
            }
            if c <= e * (1.0 + opts.tolerance) {
                within += 1;
            }
            if e > 0.0 {
                ratio_sum += c / e;
                ratios += 1;
                max_ratio = max_ratio.max(c / e);
            }
        }
        let within_tolerance = within as f64 / connected.len().max(1) as f64;
        let queries: Vec<QueryComparison> = run_queries(s, &g.graph, &model, &curves, &keys)
            .into_iter()
            .zip(&exact_queries)
            .map(|((name, kind, o), (_, _, x))| {
                let (error_change, cost_change) = (change(x.error, o.error), change(x.cost, o.cost));
                // A time error within a frame of the exact one is no worse.
                let error_worse =
                    if kind == "key pose" { o.error > x.error + 1.0 } else { error_change > opts.tolerance };
                let worse = o.failed.is_some() && x.failed.is_none()
                    || error_worse
                    || cost_change > opts.tolerance && kind == "key pose";
                QueryComparison { query: name, kind, sparse: o, error_change, cost_change, worse }
            })
            .collect();
        progress.advance(1);
        let worst_query_change = queries
            .iter()
            .map(|q| if q.kind == "key pose" { q.error_change.max(q.cost_change) } else { q.error_change })
            .fold(f64::NEG_INFINITY, f64::max);
        let acceptable = within_tolerance >= 0.99 && queries.iter().all(|q| !q.worse);
        rows.push(KRow {
            k: *k,
            sparse_edges: *base_edges,
            edges: g.graph.edges().len(),
            transitions: transitions(&g.graph),
            within_tolerance,
            mean_ratio: ratio_sum / ratios.max(1) as f64,
            max_ratio,
            unreachable,
            seconds: *secs,
            queries,
            worst_query_change,
            acceptable,
        });
    }
    progress.finish();
    let chosen_k = rows.iter().filter(|r| r.acceptable).map(|r| r.k).min();
    let pct = opts.tolerance * 100.0;
    Ok(SparseGraphEval {
        subject: s.name.clone(),
        frames: n,
        vertices: s.topology().n_vertices(),
        triangles: s.topology().n_triangles(),
        alpha: p.alpha,
        l_min: p.table.l_min,
        l_max: p.table.l_max,
        distances_seconds: if d.from_cache { 0.0 } else { distances_seconds },
        table_seconds: if table.from_cache { 0.0 } else { table_seconds },
        cached: d.from_cache && table.from_cache,
        connected_pairs: connected.len(),
        tolerance: opts.tolerance,
        exact: ExactSide {
            edges: exact.graph.edges().len(),
            transitions: transitions(&exact.graph),
            seconds: exact_seconds,
            queries: exact_queries,
        },
        rows,
        chosen_k,
        rule: format!(
            "the smallest k with at least 99% of the all-pairs costs within {pct}% of the exact ones, no query failing \
             where the exact graph's succeeds, no path's mean curve error more than {pct}% above the exact graph's, \
             no key pose's realism cost more than {pct}% above nor its time error more than one frame above"
        ),
        model_transitions: model.n_transitions(),
        model_seconds,
        seconds: t_all.elapsed().as_secs_f64(),
    })
}

fn is_original(s: &Subject, e: &Edge) -> bool {
    surfcap_motion::edge_weights::EdgeWeights::is_original(s.frame_index(), e.from as usize, e.to as usize)
}
