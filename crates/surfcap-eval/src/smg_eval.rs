//! Huang et al. 2009's evaluation (their Table 1) of the surface motion graph: for each pair of
//! key frames, targets of 1-20 m in 1 m steps by 1-40 s in 1 s steps (800 queries), the
//! minimum, RMS and maximum distance error (subject units) and time error (frames), the
//! smoothness at the transitions used (the triangularly weighted mean, as eq. 4's `w(k)`, of the
//! Hausdorff distance between the overlapped frames of each transition, after the centroid
//! match of the switch) and the CPU time of a query (mean and standard deviation).
//!
//! The subject is the built-in mannequin driven by CMU locomotion (stand, walk, jog, jump, stop:
//! real root travel, which the distance constraint needs), in either form:
//! shared topology, or every frame re-meshed on its own (`MotionFrames` with per-frame
//! triangles; the similarity needs no correspondence). The paper's own figures: distance error
//! RMS 0.17-0.47 m and max below 1 m, time error max 22-25 frames, 5.7-15.0 s per query in Matlab.

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_mesh::Subject;
use surfcap_smg::loop_exclusion::{LoopFilter, LoopRule};
use surfcap_smg::motion_frames::MotionFrames;
use surfcap_smg::path_optimisation::{
    PathQuery, Tolerance, frames_shown, optimise_planned, plan_paths, plan_paths_excluding,
};
use surfcap_smg::shape_similarity::HistogramParams;
use surfcap_smg::surface_motion_graph::{
    EdgeKind, GraphInput, LoopChoice, SurfaceMotionGraph, build_graph, build_graph_choosing,
};

use crate::MeanStd;
use crate::error::{Error, Result};
use crate::transition_measures::{MatchedTransition, smoothness};

/// The CMU clips of the locomotion subject: stand-to-walk, walk, jog, jump, jog-to-stop.
pub const LOCOMOTION_CLIPS: [&str; 5] = ["16_31", "16_15", "16_36", "16_07", "16_57"];

/// The higher-level graph of the locomotion subject (by clip): start walking into the walk
/// cycle, walk and jog loops, walk to and from jog, walk to jump and back, jog to stop.
pub const LOCOMOTION_CONNECTIONS: [(&str, &str); 8] = [
    ("16_31", "16_15"),
    ("16_15", "16_15"),
    ("16_15", "16_36"),
    ("16_36", "16_36"),
    ("16_36", "16_15"),
    ("16_15", "16_07"),
    ("16_07", "16_15"),
    ("16_36", "16_57"),
];

/// Key-frame pairs (`sequence:frame`): walk -> walk, walk -> jog, jog -> stop, walk -> jump,
/// each from a clip's first frame to a clip's last. Eq. 5 gives one transition per connection,
/// so a key pair is useful only when the loops lie on its way: the stand clip's best transition
/// into the walk lands after the walk's loop (on this mannequin), so a stand -> walk pair could
/// only play the clips once; `surfcap eval smg --pairs` takes any other pairs.
pub const LOCOMOTION_KEY_PAIRS: [(&str, &str); 4] =
    [("16_15:0", "16_15:116"), ("16_15:0", "16_36:46"), ("16_36:0", "16_57:66"), ("16_15:0", "16_07:104")];

/// The mannequin of `vertices` vertices moved by the locomotion clips (30 fps, metres).
pub fn locomotion_subject(data: &Path, vertices: usize) -> Result<Subject> {
    let m = mannequin(&BodyShape::average(), vertices)?;
    let mut clips = Vec::new();
    for c in LOCOMOTION_CLIPS {
        let path = data.join("cmu_bvh").join(format!("{c}.bvh"));
        let bvh = read_bvh(&path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        clips.push(Clip::from_bvh(&path, &bvh, &m, mpu)?);
    }
    Ok(mannequin_subject("mannequin-locomotion", &m, &clips, 30.0)?)
}

/// The stand / walk / jog / hit subject (the setting of Huang et al.'s Table 1): the mannequin
/// moved by real CMU clips from `cmu_bvh_loops`, each renamed after its role: `stand` is 113_21
/// ("Standing Still", the upright idle; 140_07 is a stooped wide-stance idle, further from the
/// walk's upright poses), `walk`, `jog` and `hit` are 02_01, 02_03 and 02_05 of subject 2 (one
/// person and skeleton: walk, run/jog and punch with the feet planted). Each entry: role, trial,
/// and the seconds kept after the leading T-pose frame (`None`: all); the idle and the punch are
/// cut to a few loops' worth so the frame count stays near the locomotion set's.
pub const STAND_WALK_JOG_HIT_CLIPS: [(&str, &str, Option<f64>); 4] =
    [("stand", "113_21", Some(6.0)), ("walk", "02_01", None), ("jog", "02_03", None), ("hit", "02_05", Some(8.0))];

/// The higher-level graph of the stand / walk / jog / hit subject (as the paper's Character1):
/// stand, walk, jog and hit loops, stand <-> walk, walk <-> jog, stand <-> hit.
pub const STAND_WALK_JOG_HIT_CONNECTIONS: [(&str, &str); 10] = [
    ("stand", "stand"),
    ("walk", "walk"),
    ("jog", "jog"),
    ("hit", "hit"),
    ("stand", "walk"),
    ("walk", "stand"),
    ("walk", "jog"),
    ("jog", "walk"),
    ("stand", "hit"),
    ("hit", "stand"),
];

/// Key-frame pairs of the stand / walk / jog / hit subject: the paper's four for Character1
/// (Stand#1 -> Hit#45, Stand#1 -> Walk#16, Walk#16 -> Jog#13, Jog#13 -> Hit#45; frames from 0).
pub const STAND_WALK_JOG_HIT_KEY_PAIRS: [(&str, &str); 4] =
    [("stand:0", "hit:45"), ("stand:0", "walk:16"), ("walk:16", "jog:13"), ("jog:13", "hit:45")];

/// The mannequin of `vertices` vertices moved by [`STAND_WALK_JOG_HIT_CLIPS`] (the 120 fps
/// files resampled to 30 fps, metres), one sequence per role.
pub fn stand_walk_jog_hit_subject(data: &Path, vertices: usize) -> Result<Subject> {
    let m = mannequin(&BodyShape::average(), vertices)?;
    let mut clips = Vec::new();
    for (role, trial, keep) in STAND_WALK_JOG_HIT_CLIPS {
        let path = data.join("cmu_bvh_loops").join(format!("{trial}.bvh"));
        let bvh = read_bvh(&path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        let mut clip = Clip::from_bvh(&path, &bvh, &m, mpu)?;
        // The cgspeed conversions start with a T-pose reference frame.
        clip.poses.remove(0);
        if let Some(seconds) = keep {
            clip.poses.truncate((seconds * clip.fps).round() as usize + 1);
        }
        clip.name = role.to_string();
        clips.push(clip);
    }
    Ok(mannequin_subject("mannequin-stand-walk-jog-hit", &m, &clips, 30.0)?)
}

/// Options of [`smg_eval`].
#[derive(Debug, Clone)]
pub struct SmgEvalOptions {
    /// Targets: (distance in subject units, time in seconds).
    pub targets: Vec<(f64, f64)>,
    /// Window lengths of the transitions, in frames.
    pub lengths: std::ops::RangeInclusive<usize>,
    pub histogram: HistogramParams,
    /// eq. 6's weights per subject unit and per frame.
    pub w_d: f64,
    pub w_t: f64,
    /// Transitions per connection (1: the paper's) and the least distance between their
    /// switches, frames.
    pub per_connection: usize,
    pub separation: usize,
    /// The tolerance of the goal queries (1% and 1 frame).
    pub tolerance: Tolerance,
    /// The loops the queries may play (`surfcap_smg::loop_exclusion`), and the self-transitions
    /// chosen among them, spanning each sequence's cross transitions and key frames
    /// (`surfcap_smg::self_transition_choice`). `None`: the paper's graph, every self-transition
    /// by eq. 5 and every loop played.
    pub loops: Option<LoopRule>,
    /// With `loops`: self-transitions per sequence, the spanning one then the cheapest
    /// admissible loops inside it (finer steps of time).
    pub loops_per_sequence: usize,
}

impl Default for SmgEvalOptions {
    /// The paper's: 1-20 m by 1-40 s, `w_d = 1/0.3`, `w_t = 1/10`; windows of 3 to 30 frames;
    /// self-transitions among the loops of at least 10 frames and one typical frame step of
    /// pose variation (the paper's own choice of self-transitions picks a clip's stillest 3
    /// frames, a loop no query may play), two per sequence.
    fn default() -> Self {
        SmgEvalOptions {
            targets: grid(&(1..=20).map(f64::from).collect::<Vec<_>>(), &(1..=40).map(f64::from).collect::<Vec<_>>()),
            lengths: 3..=30,
            histogram: HistogramParams::default(),
            w_d: 1.0 / 0.3,
            w_t: 1.0 / 10.0,
            per_connection: 1,
            separation: 15,
            tolerance: Tolerance::default(),
            loops: Some(LoopRule::default()),
            loops_per_sequence: 2,
        }
    }
}

/// Every (distance, time) of two lists: the paper's 20 x 40 grid.
pub fn grid(distances: &[f64], seconds: &[f64]) -> Vec<(f64, f64)> {
    distances.iter().flat_map(|&d| seconds.iter().map(move |&s| (d, s))).collect()
}

/// Minimum, root mean square and maximum.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MinRmsMax {
    pub min: f64,
    pub rms: f64,
    pub max: f64,
}

impl MinRmsMax {
    /// Of some values; all 0 for none.
    pub fn of(v: &[f64]) -> Self {
        if v.is_empty() {
            return MinRmsMax { min: 0.0, rms: 0.0, max: 0.0 };
        }
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        MinRmsMax {
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            rms,
            max: v.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// One key-frame pair's row of Table 1.
#[derive(Debug, Clone, Serialize)]
pub struct KeyPairRow {
    pub from: String,
    pub to: String,
    pub queries: usize,
    /// Smoothness (weighted Hausdorff distance at the transitions used), subject units.
    pub smoothness_min: f64,
    pub smoothness_max: f64,
    pub distance_error: MinRmsMax,
    pub time_error_frames: MinRmsMax,
    /// The same (eq. 6's optimum) over the targets the graph can meet (those `goal` meets), the
    /// paper's measures on what the data can reach.
    pub reachable_distance_error: MinRmsMax,
    pub reachable_time_error_frames: MinRmsMax,
    pub cpu_seconds: MeanStd,
    /// Why the key frames have no path at all (the higher-level graph's transitions do not
    /// connect them): every target is then unreachable, counted as `not_connected`.
    pub not_connected: Option<String>,
    /// Walks between the key frames and loops in the graph (those the queries may play), and
    /// the loops of the graph never repeated to pad time (too short or too still).
    pub walks: usize,
    pub loops: usize,
    pub excluded_loops: usize,
    /// Enumerating the walks and loops, once per key pair (not in `cpu_seconds`).
    pub plan_seconds: f64,
    /// ILP sub-problems given up because their feedback cuts did not settle.
    pub unconverged_subproblems: usize,
    /// The same targets with our tolerance of 1% and 1 frame (beyond the paper).
    pub goal: GoalRow,
    /// Each query's outcome, in the order of the targets.
    #[serde(skip)]
    pub outcomes: Vec<QueryOutcome>,
}

/// The queries of a key pair asked to meet their targets within a tolerance
/// ([`surfcap_smg::path_optimisation::Tolerance`]): how many do, and why the others cannot.
#[derive(Debug, Clone, Serialize)]
pub struct GoalRow {
    pub tolerance: Tolerance,
    /// Targets met within the tolerance.
    pub met: usize,
    /// Targets no path of the graph meets, by reason (`too_short`, `too_fast`, ...).
    pub unreachable: std::collections::BTreeMap<String, usize>,
    /// Errors of the met targets (within the tolerance by construction) and of all.
    pub met_distance_error: MinRmsMax,
    pub met_time_error_frames: MinRmsMax,
    pub distance_error: MinRmsMax,
    pub time_error_frames: MinRmsMax,
    /// Relative distance error of the met targets, largest.
    pub met_distance_relative_max: f64,
    pub met_time_error_max: f64,
    pub cpu_seconds: MeanStd,
}

/// What one query gave: its errors and the transitions its path took.
#[derive(Debug, Clone)]
pub struct QueryOutcome {
    /// Subject units.
    pub distance_error: f64,
    /// Frames.
    pub time_error: f64,
    /// The path's transition edges (indices into [`SmgEval::matched`]), in order, repeats kept.
    pub transitions: Vec<usize>,
}

/// One transition of the graph.
#[derive(Debug, Clone, Serialize)]
pub struct TransitionRow {
    pub from: String,
    pub to: String,
    pub window: usize,
    pub cost: f64,
    /// Weighted Hausdorff distance of its overlapped frames, subject units.
    pub smoothness: f64,
}

/// The result of [`smg_eval`].
#[derive(Debug, Clone, Serialize)]
pub struct SmgEval {
    pub form: String,
    /// Transitions per connection (1: the paper's).
    pub per_connection: usize,
    /// The loops the queries may play, and the self-transitions chosen among them
    /// ([`SmgEvalOptions::loops`]); `None`: the paper's graph.
    pub loop_rule: Option<LoopRule>,
    pub frames: usize,
    pub vertices_min: usize,
    pub vertices_max: usize,
    pub similarity_seconds: f64,
    pub similarity_cached: bool,
    /// Time to build the lower-level graph from the similarity, seconds.
    pub graph_seconds: f64,
    pub graph_nodes: usize,
    pub graph_edges: usize,
    pub transitions: Vec<TransitionRow>,
    pub missing_transitions: Vec<(String, String)>,
    pub pairs: Vec<KeyPairRow>,
    /// Each key pair's global frames, in the order of `pairs`.
    #[serde(skip)]
    pub key_frames: Vec<(usize, usize)>,
    /// Each graph edge's transition as the measures see it (`None`: a sub-sequence).
    #[serde(skip)]
    pub matched: Vec<Option<MatchedTransition>>,
}

/// Each edge's transition as the measures see it (`None` for a sub-sequence): the eq. 4 window
/// matched frame by frame, Y moved on the ground so that the centroids of the switch's frames
/// meet (4.2.3).
fn matched_transitions(
    m: &MotionFrames,
    g: &SurfaceMotionGraph,
    centroids: &[[f64; 3]],
) -> Vec<Option<MatchedTransition>> {
    let (iu, iv, _) = plane_axes(m.up);
    g.edges
        .iter()
        .map(|e| {
            let EdgeKind::Transition { from_sequence, to_sequence, .. } = e.kind else { return None };
            let (last, first) = (g.nodes[e.from], g.nodes[e.to]);
            let (sx, sy) = (m.sequences[from_sequence].start, m.sequences[to_sequence].start);
            let (_, _, t) = g.transitions.iter().find(|(x, y, t)| {
                *x == from_sequence && *y == to_sequence && sx + t.last_x == last && sy + t.first_y == first
            })?;
            let (x0, y0) = (sx + t.window_x, sy + t.window_y);
            let shift = |k: usize| centroids[last][k] - centroids[first][k];
            let place = PlaneMotion { theta: 0.0, t: [shift(iu), shift(iv)], up: m.up };
            Some(MatchedTransition {
                pairs: (0..t.length).map(|k| (x0 + k, y0 + k)).collect(),
                placements: vec![place; t.length],
            })
        })
        .collect()
}

/// Whether some path of `g` leads from global frame `a` to global frame `b` (breadth-first).
fn connected(g: &SurfaceMotionGraph, a: usize, b: usize) -> bool {
    let (Some(s), Some(t)) = (g.node_of(a), g.node_of(b)) else { return false };
    let out = g.out_edges();
    let mut seen = vec![false; g.nodes.len()];
    let mut queue = vec![s];
    seen[s] = true;
    while let Some(v) = queue.pop() {
        for &e in &out[v] {
            let w = g.edges[e].to;
            if w == t {
                return true;
            }
            if !seen[w] {
                seen[w] = true;
                queue.push(w);
            }
        }
    }
    s == t
}

/// The row of key frames no path joins: no query answered, every target `not_connected`.
fn not_connected_row(from: &str, to: &str, opts: &SmgEvalOptions, why: String) -> KeyPairRow {
    let none = MinRmsMax::of(&[]);
    KeyPairRow {
        from: from.to_string(),
        to: to.to_string(),
        queries: 0,
        smoothness_min: 0.0,
        smoothness_max: 0.0,
        distance_error: none,
        time_error_frames: none,
        reachable_distance_error: none,
        reachable_time_error_frames: none,
        cpu_seconds: MeanStd::of(&[]),
        not_connected: Some(why),
        walks: 0,
        loops: 0,
        excluded_loops: 0,
        plan_seconds: 0.0,
        unconverged_subproblems: 0,
        goal: GoalRow {
            tolerance: opts.tolerance,
            met: 0,
            unreachable: [("not_connected".to_string(), opts.targets.len())].into_iter().collect(),
            met_distance_error: none,
            met_time_error_frames: none,
            distance_error: none,
            time_error_frames: none,
            met_distance_relative_max: 0.0,
            met_time_error_max: 0.0,
            cpu_seconds: MeanStd::of(&[]),
        },
        outcomes: Vec::new(),
    }
}

fn key_frame(m: &MotionFrames, text: &str) -> Result<usize> {
    m.resolve(text).map_err(|e| Error::parameter("--pair", None, e.to_string()))
}

/// Runs the evaluation on `frames` (see the module documentation). `connections` and `pairs`
/// name sequences and `sequence:frame`s.
pub fn smg_eval(
    frames: &MotionFrames,
    form: &str,
    connections: &[(&str, &str)],
    pairs: &[(&str, &str)],
    opts: &SmgEvalOptions,
    cache: Option<(&surfcap_mesh::derived_cache::DerivedCache, bool)>,
    progress: &dyn surfcap_mesh::Progress,
) -> Result<SmgEval> {
    let t0 = Instant::now();
    let (similarity, cached) =
        frames.shape_similarity(opts.histogram, cache, progress).map_err(|e| Error::Unsuitable(e.to_string()))?;
    let similarity_seconds = t0.elapsed().as_secs_f64();
    let seq = |name: &str| {
        frames.names.iter().position(|n| n == name).ok_or_else(|| Error::Unsuitable(format!("no sequence {name:?}")))
    };
    let conns = connections.iter().map(|(x, y)| Ok((seq(x)?, seq(y)?))).collect::<Result<Vec<_>>>()?;
    let keys =
        pairs.iter().map(|(a, b)| Ok((key_frame(frames, a)?, key_frame(frames, b)?))).collect::<Result<Vec<_>>>()?;
    let key_frames: Vec<usize> = keys.iter().flat_map(|&(a, b)| [a, b]).collect();
    let ground = frames.ground_centroids();
    let t_graph = Instant::now();
    let input = GraphInput {
        sequences: &frames.sequences,
        similarity: &similarity,
        ground: &ground,
        connections: &conns,
        key_frames: &key_frames,
        lengths: opts.lengths.clone(),
        per_connection: opts.per_connection,
        separation: opts.separation,
    };
    let filter = match opts.loops {
        Some(rule) => {
            Some(LoopFilter::new(rule, &similarity, &frames.sequences).map_err(|e| Error::Unsuitable(e.to_string()))?)
        }
        None => None,
    };
    let g = match &filter {
        Some(filter) => build_graph_choosing(
            &input,
            &LoopChoice { filter, key_pairs: &keys, per_sequence: opts.loops_per_sequence },
        ),
        None => build_graph(&input),
    }
    .map_err(|e| Error::Unsuitable(e.to_string()))?;
    let graph_seconds = t_graph.elapsed().as_secs_f64();
    let centroids = frames.centroids();
    let matched = matched_transitions(frames, &g, &centroids);
    let smooth: Vec<Option<f64>> =
        matched.iter().map(|t| t.as_ref().map(|t| smoothness(&frames.positions, t))).collect();
    let transitions = g
        .edges
        .iter()
        .zip(&smooth)
        .filter_map(|(e, s)| {
            let EdgeKind::Transition { window, .. } = e.kind else { return None };
            Some(TransitionRow {
                from: frames.name_of(g.nodes[e.from]),
                to: frames.name_of(g.nodes[e.to]),
                window,
                cost: e.cost,
                smoothness: s.unwrap_or(0.0),
            })
        })
        .collect();
    let mut rows = Vec::new();
    progress.start("path queries", (keys.len() * opts.targets.len()) as u64);
    for (&(a, b), (na, nb)) in keys.iter().zip(pairs) {
        let t = Instant::now();
        let max_paths = PathQuery::new(a, b, 0.0, 1.0).max_paths;
        // Key frames the transitions do not connect: every target unreachable, said so.
        if !connected(&g, a, b) {
            progress.advance(opts.targets.len() as u64);
            let why = format!(
                "no path from {na} to {nb}: the transitions of the higher-level graph ({} per connection) do \
                 not lead from one to the other",
                opts.per_connection
            );
            rows.push(not_connected_row(na, nb, opts, why));
            continue;
        }
        let plan = match &filter {
            Some(filter) => plan_paths_excluding(&g, a, b, max_paths, filter),
            None => plan_paths(&g, a, b, max_paths),
        }
        .map_err(|e| Error::Unsuitable(format!("{na} -> {nb}: {e}")))?;
        let excluded_loops = plan.excluded_loops().len();
        let plan_seconds = t.elapsed().as_secs_f64();
        // The queries in parallel, collected in the targets' order (each is deterministic).
        let answers = opts
            .targets
            .par_iter()
            .map(|&(d, s)| {
                let q =
                    PathQuery { w_d: opts.w_d, w_t: opts.w_t, ..PathQuery::new(a, b, d, frames_shown(s, frames.fps)) };
                let t = Instant::now();
                let p = optimise_planned(&g, &ground, &plan, &q);
                let cpu = t.elapsed().as_secs_f64();
                // The goal: the same target within the tolerance where the graph allows it.
                let qg = PathQuery { tolerance: Some(opts.tolerance), ..q };
                let t = Instant::now();
                let pg = optimise_planned(&g, &ground, &plan, &qg);
                let goal_cpu = t.elapsed().as_secs_f64();
                progress.advance(1);
                Ok((p?, cpu, pg?, goal_cpu))
            })
            .collect::<std::result::Result<Vec<_>, surfcap_smg::error::Error>>()
            .map_err(|e| Error::Unsuitable(format!("{na} -> {nb}: {e}")))?;
        let (mut derr, mut terr, mut cpu, mut smooth_used) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut outcomes = Vec::new();
        let (mut walks, mut loops) = (0, 0);
        let (mut goal_derr, mut goal_terr, mut goal_cpu) = (Vec::new(), Vec::new(), Vec::new());
        let (mut met_derr, mut met_terr, mut reach_derr, mut reach_terr) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut met, mut met_rel, mut met_frames) = (0, 0.0_f64, 0.0_f64);
        let mut unreachable = std::collections::BTreeMap::new();
        let mut unconverged = 0;
        for (&(d, _), (p, p_cpu, pg, pg_cpu)) in opts.targets.iter().zip(answers) {
            unconverged += p.unconverged_subproblems + pg.unconverged_subproblems;
            cpu.push(p_cpu);
            derr.push(p.distance_error);
            terr.push(p.time_error);
            smooth_used.extend(p.edges.iter().filter_map(|&e| smooth[e]));
            outcomes.push(QueryOutcome {
                distance_error: p.distance_error,
                time_error: p.time_error,
                transitions: p.edges.iter().copied().filter(|&e| matched[e].is_some()).collect(),
            });
            (walks, loops) = (p.walks, p.loops_in_graph);
            goal_cpu.push(pg_cpu);
            goal_derr.push(pg.distance_error);
            goal_terr.push(pg.time_error);
            match &pg.unreachable {
                None => {
                    met += 1;
                    met_rel = met_rel.max(pg.distance_error / d.max(f64::MIN_POSITIVE));
                    met_frames = met_frames.max(pg.time_error);
                    met_derr.push(pg.distance_error);
                    met_terr.push(pg.time_error);
                    reach_derr.push(p.distance_error);
                    reach_terr.push(p.time_error);
                }
                Some(why) => *unreachable.entry(why.kind().to_string()).or_insert(0) += 1,
            }
        }
        rows.push(KeyPairRow {
            from: na.to_string(),
            to: nb.to_string(),
            queries: cpu.len(),
            // No transition used (a path within one sequence): 0.
            smoothness_min: if smooth_used.is_empty() {
                0.0
            } else {
                smooth_used.iter().copied().fold(f64::INFINITY, f64::min)
            },
            smoothness_max: smooth_used.iter().copied().fold(0.0, f64::max),
            distance_error: MinRmsMax::of(&derr),
            time_error_frames: MinRmsMax::of(&terr),
            reachable_distance_error: MinRmsMax::of(&reach_derr),
            reachable_time_error_frames: MinRmsMax::of(&reach_terr),
            cpu_seconds: MeanStd::of(&cpu),
            not_connected: None,
            walks,
            loops,
            excluded_loops,
            plan_seconds,
            unconverged_subproblems: unconverged,
            goal: GoalRow {
                tolerance: opts.tolerance,
                met,
                unreachable,
                met_distance_error: MinRmsMax::of(&met_derr),
                met_time_error_frames: MinRmsMax::of(&met_terr),
                distance_error: MinRmsMax::of(&goal_derr),
                time_error_frames: MinRmsMax::of(&goal_terr),
                met_distance_relative_max: met_rel,
                met_time_error_max: met_frames,
                cpu_seconds: MeanStd::of(&goal_cpu),
            },
            outcomes,
        });
    }
    progress.finish();
    let counts: Vec<usize> = frames.positions.iter().map(|p| p.len() / 3).collect();
    Ok(SmgEval {
        form: form.into(),
        per_connection: opts.per_connection,
        loop_rule: opts.loops,
        frames: frames.n_frames(),
        vertices_min: counts.iter().copied().min().unwrap_or(0),
        vertices_max: counts.iter().copied().max().unwrap_or(0),
        similarity_seconds,
        similarity_cached: cached,
        graph_seconds,
        graph_nodes: g.nodes.len(),
        graph_edges: g.edges.len(),
        transitions,
        missing_transitions: g
            .missing
            .iter()
            .map(|&(x, y)| (frames.names[x].clone(), frames.names[y].clone()))
            .collect(),
        pairs: rows,
        key_frames: keys,
        matched,
    })
}
