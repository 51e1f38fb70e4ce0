//! The surface motion graph (Huang et al. 2009) side by side with the essential graph (thesis
//! 3.3) on data with a shared topology: the same key frames as start and end
//! frames, the same (distance, time) targets, one row per key pair and engine.
//!
//! - The essential graph answers each target with its own distance-and-time search
//!   (`surfcap_motion::timed_walk`, the search of `surfcap synth reach`: eq. 6 of Huang et al.
//!   with the same weights `w_d` and `w_t`, its realism cost in place of `C_s`), on the graph,
//!   walk model and search tables precomputed once (reported as `precompute_seconds`, apart
//!   from the per-query times). Graph parameters: the library's defaults unless given.
//! - Time is counted as the surface motion graph counts it: the frames the output shows, the
//!   start frame included, against round(seconds x fps)
//!   (`surfcap_smg::path_optimisation::frames_shown`, the count `synth reach` and `smg query`
//!   ask). A walk of `k` frame intervals
//!   shows `k + 1` frames, so the essential graph is asked for `round(seconds x fps) - 1`
//!   intervals.
//! - Distance: each engine's own ground-plane length of the centre's path (the surface motion
//!   graph: the area-weighted centroid along its sub-sequences, nothing across a switch; the
//!   essential graph: the centre of mass along the played frames and blends, as its walk model
//!   predicts it).
//! - Transition cost and smoothness: [`crate::transition_measures`] on every transition each
//!   output takes (repeats counted), the same two functions for both engines: the deformation
//!   distance (thesis eq. 2.13, the essential graph's own metric, from the pipeline's cached
//!   matrix) and the Hausdorff distance, each weighted triangularly over the frame pairs the
//!   transition matches (the surface motion graph: its eq. 4 window; the essential graph: its
//!   DTW warp), each engine placing the destination frame as it does when playing.

use std::collections::{BTreeMap, HashMap};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::motion_plane_alignment;
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::segment_bounds;
use surfcap_motion::timed_walk::{DistanceTimeWalk, LoopRule, TimedGraph};
use surfcap_motion::walk_sequence::{Step, WalkModel};
use surfcap_pipeline::{GraphKind, GraphParams, Pipeline};
use surfcap_smg::motion_frames::MotionFrames;
use surfcap_smg::path_optimisation::frames_shown;

use crate::MeanStd;
use crate::error::{Error, Result};
use crate::smg_eval::{MinRmsMax, SmgEval, SmgEvalOptions};
use crate::transition_measures::{MatchedTransition, deformation_cost, smoothness};

/// The engines compared, as rows name them.
pub const SURFACE_MOTION_GRAPH: &str = "surface motion graph";
pub const ESSENTIAL_GRAPH: &str = "essential graph";

/// Minimum, mean and maximum.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MinMeanMax {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

impl MinMeanMax {
    /// Of some values; all 0 for none.
    pub fn of(v: &[f64]) -> Self {
        if v.is_empty() {
            return MinMeanMax { min: 0.0, mean: 0.0, max: 0.0 };
        }
        MinMeanMax {
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// One engine on one key pair.
#[derive(Debug, Clone, Serialize)]
pub struct EngineRow {
    pub engine: &'static str,
    pub from: String,
    pub to: String,
    /// Queries answered; the statistics are over these.
    pub queries: usize,
    /// Queries the engine found no path for, and the first one's reason.
    pub failed: usize,
    pub first_failure: Option<String>,
    /// Subject units.
    pub distance_error: MinRmsMax,
    pub time_error_frames: MinRmsMax,
    /// Transitions per output, on average.
    pub transitions_per_query: f64,
    /// Over every transition taken (repeats counted): the weighted deformation distance of its
    /// matched frames (thesis eq. 2.13).
    pub transition_cost: MinMeanMax,
    /// Over every transition taken: the weighted Hausdorff distance, subject units.
    pub smoothness: MinMeanMax,
    /// Per query, the search only (precomputation apart).
    pub cpu_seconds: MeanStd,
    /// The targets within the tolerance (`SmgEvalOptions::tolerance`): how many each engine
    /// meets, how many no walk of its graph can meet and why (the reasons of
    /// `surfcap_smg::path_optimisation::Unreachable`, counted by name), and how many it missed
    /// though no reason proves them unreachable (a search defect; 0 for both engines).
    pub met: usize,
    pub unreachable: BTreeMap<String, usize>,
    pub missed_reachable: usize,
    /// The worst errors among the met targets: distance relative to the target, and frames.
    pub met_distance_relative_max: f64,
    pub met_time_error_max: f64,
    /// Each query's (distance error, time error in frames), in the order of the targets; NaN
    /// for a failed query.
    #[serde(skip)]
    pub errors: Vec<(f64, f64)>,
}

/// The essential graph's precomputation.
#[derive(Debug, Clone, Serialize)]
pub struct EssentialGraphSetup {
    pub alpha: Alpha,
    pub l_min: usize,
    pub l_max: usize,
    pub nodes: usize,
    pub edges: usize,
    pub transitions: usize,
    /// Distances, transition table, graph, walk model (from the cache when there) and the
    /// search's adjacency, seconds.
    pub precompute_seconds: f64,
    /// Whether the graph and walk model came from the disk cache.
    pub graph_cached: bool,
    /// Loops the searches never play to pad time (too short or too still), and the rule.
    pub loop_rule: LoopRule,
    pub excluded_loops: usize,
}

/// The result of [`smg_comparison`].
#[derive(Debug, Clone, Serialize)]
pub struct SmgComparison {
    /// How time, distance, transition cost and smoothness are measured (the module's summary).
    pub measures: String,
    /// The surface motion graph's precomputation: similarity and lower-level graph, seconds.
    pub smg_precompute_seconds: f64,
    pub essential_graph: EssentialGraphSetup,
    /// Per key pair, the surface motion graph's row then the essential graph's.
    pub rows: Vec<EngineRow>,
}

/// The essential graph's parameters by default: the library's segment bounds for the rate,
/// slope 3, alpha 0.05 (as `surfcap synth reach` uses them).
pub fn default_graph_params(fps: f64) -> GraphParams {
    let (l_min, l_max) = segment_bounds(fps);
    GraphParams {
        table: surfcap_motion::transition_table::TableParams { l_min, l_max, slope: Some(3) },
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05).expect("0.05 is a positive number"),
    }
}

/// The transition u -> v of the essential graph as the measures see it: its DTW warp, each
/// destination frame aligned onto its source frame by motion-plane alignment (what Blend does
/// before interpolating).
fn essential_transition(
    model: &WalkModel,
    d: &[f64],
    positions: &[Vec<f32>],
    u: u32,
    v: u32,
) -> Option<MatchedTransition> {
    let Some(Step::Transition(track)) = model.step(u, v) else { return None };
    let warp = model.warp(d, u, v)?;
    let d0 = v as usize + 1 - track.lj as usize;
    let pairs: Vec<(usize, usize)> = warp.iter().map(|&(a, b)| (u as usize + a, d0 + b)).collect();
    let placements =
        pairs.iter().map(|&(a, b)| motion_plane_alignment(&positions[a], &positions[b], None, model.up).0).collect();
    Some(MatchedTransition { pairs, placements })
}

/// Both measures of a transition, once per transition.
struct Measured<K> {
    cache: HashMap<K, (f64, f64)>,
}

impl<K: std::hash::Hash + Eq + Copy> Measured<K> {
    fn get(&mut self, k: K, make: impl FnOnce() -> Result<(f64, f64)>) -> Result<(f64, f64)> {
        if let Some(&m) = self.cache.get(&k) {
            return Ok(m);
        }
        let m = make()?;
        self.cache.insert(k, m);
        Ok(m)
    }
}

/// The targets within the tolerance: met, unreachable by reason, missed while reachable, and the
/// worst relative distance and time errors of the met.
#[derive(Debug, Clone, Default)]
struct Goal {
    met: usize,
    unreachable: BTreeMap<String, usize>,
    missed_reachable: usize,
    met_distance_relative_max: f64,
    met_time_error_max: f64,
}

/// One essential-graph search's answer, or why there is none.
type Answer = std::result::Result<DistanceTimeWalk, String>;

/// A row from per-query errors, times and the measures of the transitions taken.
fn row(
    engine: &'static str,
    (from, to): (&str, &str),
    errors: Vec<(f64, f64)>,
    cpu_seconds: MeanStd,
    taken: &[(f64, f64)],
    first_failure: Option<String>,
    goal: Goal,
) -> EngineRow {
    let (d, t): (Vec<f64>, Vec<f64>) = errors.iter().copied().filter(|e| e.0.is_finite()).unzip();
    let (cost, smooth): (Vec<f64>, Vec<f64>) = taken.iter().copied().unzip();
    EngineRow {
        engine,
        from: from.into(),
        to: to.into(),
        queries: d.len(),
        failed: errors.len() - d.len(),
        first_failure,
        distance_error: MinRmsMax::of(&d),
        time_error_frames: MinRmsMax::of(&t),
        transitions_per_query: if d.is_empty() { 0.0 } else { taken.len() as f64 / d.len() as f64 },
        transition_cost: MinMeanMax::of(&cost),
        smoothness: MinMeanMax::of(&smooth),
        cpu_seconds,
        met: goal.met,
        unreachable: goal.unreachable,
        missed_reachable: goal.missed_reachable,
        met_distance_relative_max: goal.met_distance_relative_max,
        met_time_error_max: goal.met_time_error_max,
        errors,
    }
}

/// Runs the essential graph on `smg`'s key pairs and `opts.targets` and measures both engines'
/// outputs alike (see the module documentation). `frames` must be
/// `MotionFrames::from_subject(pipe.subject())` and `smg` its [`crate::smg_eval::smg_eval`] with
/// `opts`.
pub fn smg_comparison(
    pipe: &Pipeline,
    frames: &MotionFrames,
    smg: &SmgEval,
    opts: &SmgEvalOptions,
    params: &GraphParams,
    progress: &dyn surfcap_mesh::Progress,
) -> Result<SmgComparison> {
    let s = pipe.subject();
    if s.n_frames() != frames.n_frames() || smg.frames != frames.n_frames() {
        return Err(Error::Unsuitable(format!(
            "the essential graph needs the surface motion graph's frames with their shared topology: \
             {} frames in the subject, {} evaluated",
            s.n_frames(),
            smg.frames
        )));
    }
    let t0 = Instant::now();
    let d = pipe.chain_distances()?.value;
    let graph = pipe.graph(params)?;
    let model = pipe.walk_model(params, None)?;
    let (graph_cached, graph, model) = (graph.from_cache && model.from_cache, graph.value, model.value);
    // Degenerate loops (too short, or too still) never pad time, as in `surfcap synth reach`.
    let loop_rule = LoopRule::default();
    let (tg, excluded) =
        TimedGraph::new(&graph, &model).without_degenerate_loops(loop_rule, &|i, j| d.values[i * d.n + j]);
    let longest = tg.longest_edge();
    let precompute_seconds = t0.elapsed().as_secs_f64();
    let n = d.n;
    let scales = (1.0 / opts.w_d, 1.0 / opts.w_t);
    let mut smg_measured = Measured { cache: HashMap::new() };
    let mut eg_measured = Measured { cache: HashMap::new() };
    let mut rows = Vec::new();
    progress.start("essential graph queries", (smg.key_frames.len() * opts.targets.len()) as u64);
    for (p, &(a, b)) in smg.pairs.iter().zip(&smg.key_frames) {
        let names = (p.from.as_str(), p.to.as_str());
        // The surface motion graph's outputs, as smg_eval found them.
        let mut taken = Vec::new();
        for q in &p.outcomes {
            for &e in &q.transitions {
                let m = smg_measured.get(e, || {
                    let t = smg.matched[e].as_ref().expect("outcomes list transition edges");
                    Ok((deformation_cost(&d.values, n, t), smoothness(&frames.positions, t)))
                })?;
                taken.push(m);
            }
        }
        let errors = p.outcomes.iter().map(|q| (q.distance_error, q.time_error)).collect();
        let g = &p.goal;
        let smg_goal = Goal {
            met: g.met,
            unreachable: g.unreachable.clone(),
            missed_reachable: p.queries.saturating_sub(g.met + g.unreachable.values().sum::<usize>()),
            met_distance_relative_max: g.met_distance_relative_max,
            met_time_error_max: g.met_time_error_max,
        };
        rows.push(row(SURFACE_MOTION_GRAPH, names, errors, p.cpu_seconds, &taken, None, smg_goal));
        // The essential graph on the same key frames and targets.
        let (mut errors, mut cpu, mut taken, mut first_failure) = (Vec::new(), Vec::new(), Vec::new(), None);
        let mut goal = Goal::default();
        // The targets of one duration share their searches' distance-free part
        // (`walk_within_each`); the durations in parallel, the answers used in the targets'
        // order (each search is deterministic). A target's CPU time is its duration's share.
        let mut durations: Vec<(f64, Vec<usize>)> = Vec::new();
        for (i, &(_, secs)) in opts.targets.iter().enumerate() {
            match durations.iter_mut().find(|(s, _)| *s == secs) {
                Some((_, members)) => members.push(i),
                None => durations.push((secs, vec![i])),
            }
        }
        let answered: Vec<Vec<(usize, Answer, f64)>> = durations
            .par_iter()
            .map(|(secs, members)| {
                let intervals = (frames_shown(*secs, frames.fps) as usize).saturating_sub(1).max(1);
                let t = Instant::now();
                let targets: Vec<(f64, f64)> = members
                    .iter()
                    .map(|&i| (opts.targets[i].0, opts.tolerance.distance_relative * opts.targets[i].0))
                    .collect();
                let tol_t = opts.tolerance.frames.floor() as usize;
                let found = tg.walk_within_each(a as u32, b as u32, intervals, &targets, scales, tol_t, longest);
                progress.advance(members.len() as u64);
                let share = t.elapsed().as_secs_f64() / members.len() as f64;
                match found {
                    Ok(answers) => members.iter().zip(answers).map(|(&i, r)| (i, Ok(r), share)).collect(),
                    Err(e) => members.iter().map(|&i| (i, Err(e.to_string()), share)).collect(),
                }
            })
            .collect();
        let mut searches: Vec<Option<(Answer, f64)>> = (0..opts.targets.len()).map(|_| None).collect();
        for (i, found, seconds) in answered.into_iter().flatten() {
            searches[i] = Some((found, seconds));
        }
        for (&(dist, secs), answer) in opts.targets.iter().zip(searches) {
            let (found, seconds) = answer.expect("every target belongs to its duration");
            let shown = frames_shown(secs, frames.fps);
            let w = match found {
                Ok(r) => {
                    match &r.unreachable {
                        _ if r.met => {
                            goal.met += 1;
                            let rel = (r.walk.distance - dist).abs() / dist.max(f64::MIN_POSITIVE);
                            goal.met_distance_relative_max = goal.met_distance_relative_max.max(rel);
                            let t_err = ((r.walk.frames + 1) as f64 - shown).abs();
                            goal.met_time_error_max = goal.met_time_error_max.max(t_err);
                        }
                        Some(why) => *goal.unreachable.entry(why.kind().to_string()).or_insert(0) += 1,
                        None => goal.missed_reachable += 1,
                    }
                    r.walk
                }
                // A target the graph cannot meet (e.g. key frames it does not connect): counted,
                // the first reason kept.
                Err(e) => {
                    first_failure.get_or_insert_with(|| format!("{dist} in {secs} s: {e}"));
                    errors.push((f64::NAN, f64::NAN));
                    continue;
                }
            };
            cpu.push(seconds);
            errors.push(((w.distance - dist).abs(), ((w.frames + 1) as f64 - shown).abs()));
            for uv in w.walk.windows(2) {
                let (u, v) = (uv[0], uv[1]);
                if !matches!(model.step(u, v), Some(Step::Transition(_))) {
                    continue;
                }
                taken.push(eg_measured.get((u, v), || {
                    let t = essential_transition(&model, &d.values, &frames.positions, u, v).ok_or_else(|| {
                        Error::Unsuitable(format!(
                            "essential graph transition {} -> {}: no warp",
                            frames.name_of(u as usize),
                            frames.name_of(v as usize)
                        ))
                    })?;
                    Ok((deformation_cost(&d.values, n, &t), smoothness(&frames.positions, &t)))
                })?);
            }
        }
        rows.push(row(ESSENTIAL_GRAPH, names, errors, MeanStd::of(&cpu), &taken, first_failure, goal));
    }
    progress.finish();
    Ok(SmgComparison {
        measures: MEASURES.into(),
        smg_precompute_seconds: smg.similarity_seconds + smg.graph_seconds,
        essential_graph: EssentialGraphSetup {
            alpha: params.alpha,
            l_min: params.table.l_min,
            l_max: params.table.l_max,
            nodes: graph.n,
            edges: graph.edges().len(),
            transitions: model.n_transitions(),
            precompute_seconds,
            graph_cached,
            loop_rule,
            excluded_loops: excluded.len(),
        },
        rows,
    })
}

/// The report's summary of the measures.
const MEASURES: &str = "time: frames shown (start included) against round(seconds x fps); distance: each engine's ground \
     length of the centre's path; transition cost: deformation distance (thesis eq. 2.13), smoothness: Hausdorff \
     distance, both weighted triangularly over the frame pairs a transition matches (SMG: its window; essential \
     graph: its DTW warp) with each engine's placement of the destination frame; cpu: the search per query";
