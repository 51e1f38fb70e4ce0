//! Huang et al. 2009's surface motion graph as a synthesis run, on a subject or on a frame set
//! (every frame its own topology): the input opened, its shape similarity computed (or read
//! back from the derived cache), the two-level graph built from the user's higher level and the
//! key frames (3.3), then a query (the path between two key frames that covers a distance in a
//! time at the least transition cost, eq. 6-20) played and written with its report
//! ([`SmgQueryReport`]), or the graph itself reported ([`SmgGraphReport`]). The engine is
//! `surfcap_smg`; this module only opens, plays, writes and reports.

use std::ops::RangeInclusive;
use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;
use surfcap_formats::import::{ImportOptions, ImportedData, open_any};
use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_mesh::frame_set::{FrameSet, FrameSetSequence};
use surfcap_mesh::{Progress, Sequence, Topology, Units};
use surfcap_smg::loop_exclusion::{Exclusion, LoopFilter, LoopRule};
use surfcap_smg::motion_frames::MotionFrames;
use surfcap_smg::path_optimisation::{
    PathQuery, PathSolution, PlayedFrame, Tolerance, Unreachable, optimise_planned, path_segments,
    plan_paths_excluding, play_path,
};
use surfcap_smg::shape_similarity::HistogramParams;
use surfcap_smg::surface_motion_graph::{
    EdgeKind, GraphInput, LoopChoice, SurfaceMotionGraph, build_graph, build_graph_choosing,
};

use surfcap_pipeline::constraint_files::{TimeSpec, TimeUnit};

use crate::animation_output::{Animation, Travel, write_animation, write_report};
use crate::constraint::{Constraint, Tolerances};
use crate::error::{Context, Error, Result, refuse};
use crate::prepared::Output;
use crate::words::unit_name;

/// What the graph is built from: the input, the user's higher level, the transitions.
#[derive(Debug, Clone)]
pub struct SmgGraphRequest {
    /// A subject or a frame set, or any source `surfcap import` reads.
    pub input: PathBuf,
    /// Sequence pairs `FROM:TO` that may follow each other.
    pub connect: Vec<String>,
    /// Transition windows searched, frames: `MIN-MAX` (eq. 5's adaptive window).
    pub windows: String,
    /// Transitions per connection (1: the paper's).
    pub transitions: usize,
    /// Least distance between the switches of one connection's transitions, frames.
    pub separation: usize,
    /// Voxels along the frames' largest extent (the shape histograms' lattice).
    pub resolution: usize,
    /// Self-transitions (`X -> X`) chosen among the loops this rule lets pad time, spanning each
    /// sequence's cross transitions and key frames (`surfcap_smg::self_transition_choice`, the
    /// graph `surfcap eval smg` measures by default); `None`: eq. 5 alone, the paper's graph as
    /// printed (a clip's stillest 3 frames may be its loop).
    pub loops: Option<LoopRule>,
    /// With `loops`: self-transitions per sequence, the spanning one then the cheapest
    /// admissible loops inside it.
    pub loops_per_sequence: usize,
}

impl SmgGraphRequest {
    /// The default graph's self-transitions (as `surfcap eval smg` builds them): chosen among
    /// the loops of [`LoopRule::default`], two per sequence.
    pub const DEFAULT_LOOPS_PER_SEQUENCE: usize = 2;
}

/// Where the similarity is cached: the folder, and whether to recompute.
#[derive(Debug, Clone)]
pub struct SimilarityCache {
    pub dir: PathBuf,
    pub refresh: bool,
}

/// An opened input with its similarity and graph.
pub struct SmgGraph {
    pub data: ImportedData,
    pub frames: MotionFrames,
    pub ground: Vec<[f64; 2]>,
    pub similarity_seconds: f64,
    pub similarity_cached: bool,
    pub graph: SurfaceMotionGraph,
    /// The key frames asked for (global frames), in order.
    pub keys: Vec<usize>,
    /// The shape similarity (eq. 2) the graph was built from, `frames x frames`: the excluded
    /// loops' pose variation is measured on it.
    pub similarity: Vec<f64>,
}

/// The key frames as pairs (start, end) in the order given, as a query's `--from` and `--to`:
/// the self-transitions span them. An odd last key is paired with itself (spanned as an entry
/// and an exit), so `keys = [a, b]` gives the graph a query from `a` to `b` uses.
pub fn key_pairs(keys: &[usize]) -> Vec<(usize, usize)> {
    keys.chunks(2).map(|c| (c[0], *c.last().expect("chunks are not empty"))).collect()
}

/// The window lengths of `--windows MIN-MAX`: windows of at least
/// [`MIN_WINDOW`](surfcap_smg::temporal_shape_similarity::MIN_WINDOW) frames (a 1-frame window
/// maps a frame onto itself and the walk freezes).
fn windows(text: &str) -> Result<RangeInclusive<usize>> {
    use surfcap_smg::temporal_shape_similarity::MIN_WINDOW;
    let parse = |s: &str| s.trim().parse::<usize>().ok();
    let (a, b) = text.split_once('-').unwrap_or((text, text));
    match (parse(a), parse(b)) {
        (Some(a), Some(b)) if MIN_WINDOW <= a && a <= b => Ok(a..=b),
        (Some(a), Some(_)) if a < MIN_WINDOW => refuse!(
            "--windows {text:?}: windows of at least {MIN_WINDOW} frames are needed (a shorter window maps a frame \
             onto itself): expected MIN-MAX frames, {MIN_WINDOW} <= MIN <= MAX"
        ),
        _ => refuse!("--windows {text:?}: expected MIN-MAX frames, {MIN_WINDOW} <= MIN <= MAX"),
    }
}

impl SmgGraph {
    /// Opens the request's input, computes (or reads back) its similarity and builds the graph
    /// with the key frames `keys` (`(option, sequence:frame)`, the option named in errors).
    pub fn open(
        request: &SmgGraphRequest,
        import: &ImportOptions,
        cache: &SimilarityCache,
        keys: &[(&str, &str)],
        progress: &dyn Progress,
    ) -> Result<Self> {
        windows(&request.windows)?;
        let data = open_any(&request.input, import, progress)?;
        Self::from_data(data, request, Some(cache), keys, progress)
    }

    /// [`SmgGraph::open`] on data already in memory (a subject or a frame set; `request.input`
    /// only names it in reports): the similarity is read from or stored in `cache` when there
    /// is one, computed in memory otherwise.
    pub fn from_data(
        data: ImportedData,
        request: &SmgGraphRequest,
        cache: Option<&SimilarityCache>,
        keys: &[(&str, &str)],
        progress: &dyn Progress,
    ) -> Result<Self> {
        let lengths = windows(&request.windows)?;
        let frames = match &data {
            ImportedData::Subject(i) => MotionFrames::from_subject(&i.subject),
            ImportedData::FrameSet(f) => MotionFrames::from_frame_set(&f.frame_set),
        };
        let t0 = Instant::now();
        let store = cache.map(|c| (DerivedCache::new(c.dir.clone()), c.refresh));
        let params = HistogramParams { resolution: request.resolution, ..Default::default() };
        let (similarity, similarity_cached) =
            frames.shape_similarity(params, store.as_ref().map(|(s, r)| (s, *r)), progress)?;
        let similarity_seconds = t0.elapsed().as_secs_f64();
        let seq = |name: &str| {
            frames.names.iter().position(|n| n == name).ok_or_else(|| {
                Error::Request(format!("--connect: no sequence {name:?}: expected one of {}", frames.names.join(", ")))
            })
        };
        let mut connections = Vec::new();
        for c in &request.connect {
            let Some((x, y)) = c.split_once(':') else { refuse!("--connect {c:?}: expected FROM:TO") };
            connections.push((seq(x)?, seq(y)?));
        }
        let keys = keys
            .iter()
            .map(|(option, spec)| frames.resolve(spec).with_context(|| format!("{option} {spec:?}")))
            .collect::<Result<Vec<usize>>>()?;
        let ground = frames.ground_centroids();
        let input = GraphInput {
            sequences: &frames.sequences,
            similarity: &similarity,
            ground: &ground,
            connections: &connections,
            key_frames: &keys,
            lengths,
            per_connection: request.transitions,
            separation: request.separation,
        };
        let graph = match request.loops {
            Some(rule) => {
                let filter = LoopFilter::new(rule, &similarity, &frames.sequences)?;
                let key_pairs = key_pairs(&keys);
                let choice =
                    LoopChoice { filter: &filter, key_pairs: &key_pairs, per_sequence: request.loops_per_sequence };
                build_graph_choosing(&input, &choice)?
            }
            None => build_graph(&input)?,
        };
        for (x, y) in &graph.missing {
            progress.note(&format!(
                "no transition {} -> {}: a sequence is shorter than the smallest window",
                frames.names[*x], frames.names[*y]
            ));
        }
        Ok(SmgGraph { data, frames, ground, similarity_seconds, similarity_cached, graph, keys, similarity })
    }

    /// The graph's transitions for reports.
    pub fn transitions(&self) -> Vec<TransitionReport> {
        let f = &self.frames;
        self.graph
            .transitions
            .iter()
            .map(|(x, y, t)| TransitionReport {
                from: f.name_of(f.sequences[*x].start + t.last_x),
                to: f.name_of(f.sequences[*y].start + t.first_y),
                window: t.length,
                cost: t.cost,
            })
            .collect()
    }

    /// The report of the graph itself (`smg build`).
    pub fn report(&self, request: &SmgGraphRequest) -> SmgGraphReport {
        let (f, g) = (&self.frames, &self.graph);
        let name = |node: usize| f.name_of(g.nodes[node]);
        SmgGraphReport {
            input: request.input.clone(),
            frames: f.n_frames(),
            sequences: f.names.clone(),
            connections: request.connect.clone(),
            key_frames: self.keys.iter().map(|&k| f.name_of(k)).collect(),
            similarity_seconds: self.similarity_seconds,
            similarity_cached: self.similarity_cached,
            nodes: g.nodes.iter().map(|&n| f.name_of(n)).collect(),
            edges: g
                .edges
                .iter()
                .map(|e| EdgeReport {
                    from: name(e.from),
                    to: name(e.to),
                    kind: e.kind.clone(),
                    frames: e.frames,
                    distance: e.distance,
                    cost: e.cost,
                })
                .collect(),
            transitions: self.transitions(),
            missing_transitions: g.missing.iter().map(|&(x, y)| format!("{}:{}", f.names[x], f.names[y])).collect(),
            self_transitions: SelfTransitions::of(request),
        }
    }
}

/// A transition of the graph: last frame played, first frame switched to (`sequence:frame`),
/// window and cost.
#[derive(Debug, Clone, Serialize)]
pub struct TransitionReport {
    pub from: String,
    pub to: String,
    pub window: usize,
    pub cost: f64,
}

/// An edge of the lower level.
#[derive(Debug, Clone, Serialize)]
pub struct EdgeReport {
    pub from: String,
    pub to: String,
    pub kind: EdgeKind,
    pub frames: usize,
    pub distance: f64,
    pub cost: f64,
}

/// The report of `smg build`: the graph, for inspection.
#[derive(Debug, Clone, Serialize)]
pub struct SmgGraphReport {
    pub input: PathBuf,
    pub frames: usize,
    pub sequences: Vec<String>,
    pub connections: Vec<String>,
    pub key_frames: Vec<String>,
    pub similarity_seconds: f64,
    pub similarity_cached: bool,
    pub nodes: Vec<String>,
    pub edges: Vec<EdgeReport>,
    pub transitions: Vec<TransitionReport>,
    pub missing_transitions: Vec<String>,
    pub self_transitions: SelfTransitions,
}

/// How the graph's self-transitions were chosen.
#[derive(Debug, Clone, Serialize)]
pub struct SelfTransitions {
    /// `spanning` (among the loops `loop_rule` lets pad time, spanning each sequence's cross
    /// transitions and key frames: `surfcap eval smg`'s default graph) or `eq5` (eq. 5 alone,
    /// the paper's graph as printed).
    pub choice: &'static str,
    pub loop_rule: Option<LoopRule>,
    /// Self-transitions per sequence (`spanning` only; eq. 5 gives `transitions`).
    pub per_sequence: Option<usize>,
}

impl SelfTransitions {
    fn of(request: &SmgGraphRequest) -> Self {
        match request.loops {
            Some(rule) => SelfTransitions {
                choice: "spanning",
                loop_rule: Some(rule),
                per_sequence: Some(request.loops_per_sequence),
            },
            None => SelfTransitions { choice: "eq5", loop_rule: None, per_sequence: None },
        }
    }
}

/// A query: the key frames (the graph's first two keys), distance, time and weights.
#[derive(Debug, Clone)]
pub struct SmgQuery {
    /// The key frames as the user wrote them.
    pub from: String,
    pub to: String,
    /// Ground distance, subject units.
    pub distance: f64,
    /// Duration: seconds (bare or `3s`) or frames shown (`90f`). T seconds show round(T x fps)
    /// frames, start included, as `synth reach` and `eval smg` count them.
    pub time: TimeSpec,
    /// Weight of a distance error per unit and of a time error per frame.
    pub distance_weight: f64,
    pub time_weight: f64,
    /// Take eq. 6's optimum as the paper does, instead of the least-cost path within 1% and 1
    /// frame where one exists.
    pub paper_cost: bool,
    /// Which loops may pad time (the others are excluded loops, reported).
    pub loops: LoopRule,
}

/// An excluded loop: a loop of the graph the query never repeats.
#[derive(Debug, Clone, Serialize)]
pub struct ExcludedLoopReport {
    /// The frames one repetition plays, as runs `sequence:first-last`.
    pub frames: Vec<String>,
    pub played_frames: usize,
    /// The largest dissimilarity between its frames over the typical frame-to-frame one.
    pub pose_variation: f64,
    /// `too_short` (under the minimum length) or `too_still` (under the pose-variation floor).
    pub kind: &'static str,
    pub why: String,
}

/// A repeated loop of the path.
#[derive(Debug, Clone, Serialize)]
pub struct LoopReport {
    pub edges: usize,
    pub repetitions: u64,
}

/// The report's `graph` of a query.
#[derive(Debug, Clone, Serialize)]
pub struct QueryGraphReport {
    pub nodes: usize,
    pub edges: usize,
    pub transitions: Vec<TransitionReport>,
    pub self_transitions: SelfTransitions,
    pub walks: usize,
    pub loops: usize,
}

/// Why no path meets the targets within the tolerance.
#[derive(Debug, Clone, Serialize)]
pub struct UnreachableReport {
    pub kind: &'static str,
    pub why: String,
    pub detail: Unreachable,
}

/// The report of a surface motion graph query.
#[derive(Debug, Clone, Serialize)]
pub struct SmgQueryReport {
    pub input: PathBuf,
    pub engine: &'static str,
    pub fps: f64,
    pub from: String,
    pub to: String,
    pub connections: Vec<String>,
    pub frames: usize,
    pub distance: f64,
    pub unit: String,
    pub transition_cost: f64,
    pub cost: f64,
    /// The path's runs, `sequence:first-last`.
    pub path: Vec<String>,
    pub loops: Vec<LoopReport>,
    pub graph: QueryGraphReport,
    pub similarity_seconds: f64,
    pub similarity_cached: bool,
    pub query_seconds: f64,
    pub ilp_solves: usize,
    pub constraints: Vec<Constraint>,
    pub outputs: Vec<PathBuf>,
    pub target_distance: f64,
    pub target_seconds: f64,
    /// The frames the duration shows, start included: round(T x fps), the time constraint's
    /// target (as `synth reach` counts it).
    pub target_frames: usize,
    pub seconds: f64,
    /// Output frames where the path jumps to another sequence or back (the transitions play
    /// captured frames only, nothing is blended, so every frame is labelled original):
    /// `surfcap view` marks them on its timeline.
    pub transition_frames: Vec<usize>,
    /// With the tolerance: whether the path meets it, and why no path can when it does not.
    pub tolerance: Option<Tolerance>,
    pub within_tolerance: Option<bool>,
    pub unreachable: Option<UnreachableReport>,
    pub unconverged_subproblems: usize,
    /// The rule deciding which loops may pad time, and the loops it excluded.
    pub loop_rule: LoopRule,
    pub excluded_loops: Vec<ExcludedLoopReport>,
    #[serde(flatten)]
    pub travel: Travel,
}

/// A query's animation: one sequence of the subject, or a frame set (every frame its own mesh)
/// for a frame set's query.
pub enum SmgAnimation {
    Subject(surfcap_mesh::Subject),
    FrameSet(FrameSet),
}

impl SmgAnimation {
    /// The animation as [`write_animation`] takes it.
    pub fn as_animation(&self) -> Animation<'_> {
        match self {
            SmgAnimation::Subject(s) => Animation::Subject(s),
            SmgAnimation::FrameSet(f) => Animation::FrameSet(f),
        }
    }
}

/// A query answered and played, nothing written: the animation, its report (no `outputs`
/// yet), the path and the constraints judged.
pub struct SmgPlayed {
    pub animation: SmgAnimation,
    pub report: SmgQueryReport,
    pub path: PathSolution,
    pub constraints: Vec<Constraint>,
}

/// A query's outcome: the animation and report written, and the path.
pub struct SmgQueryOutcome {
    pub animation: SmgAnimation,
    pub report: SmgQueryReport,
    /// Where the report was written (`None`: nothing was, the output had no path).
    pub report_path: Option<PathBuf>,
    pub written: Vec<PathBuf>,
    pub path: PathSolution,
    pub constraints: Vec<Constraint>,
}

impl SmgGraph {
    /// Answers `q` (its key frames are the graph's first two keys) and writes the animation
    /// and its report to `out`: a subject's frames as one sequence of the subject, a frame
    /// set's as a frame set (every frame its own mesh).
    pub fn query(
        &self,
        request: &SmgGraphRequest,
        q: &SmgQuery,
        out: &Output,
        progress: &dyn Progress,
    ) -> Result<SmgQueryOutcome> {
        let SmgPlayed { animation, mut report, path, constraints } = self.play(request, q, &out.tolerances)?;
        let written = match &out.path {
            Some(p) => write_animation(animation.as_animation(), out.format, p, out.export_options(), progress)?,
            None => Vec::new(),
        };
        report.outputs = written.clone();
        let report_path = out.report_path();
        if let Some(p) = &report_path {
            write_report(p, &report)?;
        }
        Ok(SmgQueryOutcome { animation, report, report_path, written, path, constraints })
    }

    /// Answers `q` (its key frames are the graph's first two keys) and plays the path, writing
    /// nothing: the constraints judged with `tolerances`.
    pub fn play(&self, request: &SmgGraphRequest, q: &SmgQuery, tolerances: &Tolerances) -> Result<SmgPlayed> {
        let (frames, graph) = (&self.frames, &self.graph);
        let (from, to) = (self.keys[0], self.keys[1]);
        let (set_name, units) = match &self.data {
            ImportedData::Subject(i) => (i.subject.name.clone(), i.subject.units.clone()),
            ImportedData::FrameSet(f) => (f.frame_set.name.clone(), f.frame_set.units.clone()),
        };
        // A duration shows round(T x fps) frames, start included (`synth reach`'s count).
        let shown = match q.time.frames(frames.fps, TimeUnit::Seconds) {
            Some(f) if f >= 1 => f,
            _ => refuse!(
                "--time {}: expected a duration of at least one frame shown (at {} fps), e.g. 90f or 3s",
                time_text(&q.time),
                frames.fps
            ),
        };
        let pq = PathQuery {
            w_d: q.distance_weight,
            w_t: q.time_weight,
            tolerance: (!q.paper_cost).then(Tolerance::default),
            ..PathQuery::new(from, to, q.distance, shown as f64)
        };
        let t1 = Instant::now();
        let filter = LoopFilter::new(q.loops, &self.similarity, &frames.sequences)?;
        let plan = plan_paths_excluding(graph, pq.start, pq.end, pq.max_paths, &filter)?;
        let path = optimise_planned(graph, &self.ground, &plan, &pq)?;
        let excluded_loops =
            plan.excluded_loops().iter().map(|x| excluded_report(frames, &x.frames, x.variation, &x.why)).collect();
        let query_seconds = t1.elapsed().as_secs_f64();
        let played = play_path(frames, &path);
        let animation = self.animation(played, format!("{set_name}-smg"), &units)?;
        let unit = unit_name(&units).to_string();
        let constraints = vec![
            Constraint::new(
                "distance",
                unit.clone(),
                q.distance,
                path.distance,
                path.distance_error,
                tolerances.distance(q.distance),
            )
            .relative_to(q.distance),
            Constraint::new(
                "time",
                "frames",
                pq.frames,
                path.frames.len() as f64,
                path.time_error,
                tolerances.frames(),
            )
            .relative_to(pq.frames),
        ];
        let report = SmgQueryReport {
            input: request.input.clone(),
            engine: "surface motion graph (Huang et al. 2009)",
            fps: frames.fps,
            from: q.from.clone(),
            to: q.to.clone(),
            connections: request.connect.clone(),
            frames: path.frames.len(),
            distance: path.distance,
            unit,
            transition_cost: path.transition_cost,
            cost: path.cost,
            path: path_segments(frames, &path),
            loops: path.loops.iter().map(|(c, n)| LoopReport { edges: c.len(), repetitions: *n }).collect(),
            graph: QueryGraphReport {
                nodes: graph.nodes.len(),
                edges: graph.edges.len(),
                transitions: self.transitions(),
                self_transitions: SelfTransitions::of(request),
                walks: path.walks,
                loops: path.loops_in_graph,
            },
            similarity_seconds: self.similarity_seconds,
            similarity_cached: self.similarity_cached,
            query_seconds,
            ilp_solves: path.ilp_solves,
            constraints: constraints.clone(),
            outputs: Vec::new(),
            target_distance: q.distance,
            target_seconds: match q.time.unit {
                Some(TimeUnit::Frames) => q.time.value / frames.fps,
                Some(TimeUnit::Seconds) | None => q.time.value,
            },
            target_frames: shown as usize,
            seconds: path.frames.len() as f64 / frames.fps,
            transition_frames: path.switches.clone(),
            tolerance: pq.tolerance,
            within_tolerance: path.within_tolerance,
            unreachable: path.unreachable.as_ref().map(|u| UnreachableReport {
                kind: u.kind(),
                why: u.to_string(),
                detail: u.clone(),
            }),
            unconverged_subproblems: path.unconverged_subproblems,
            loop_rule: q.loops,
            excluded_loops,
            travel: Travel::of(&played_centres(frames, &path), frames.up),
        };
        Ok(SmgPlayed { animation, report, path, constraints })
    }

    /// The played path as an animation: a subject's frames as one sequence of the subject, a
    /// frame set's as a frame set.
    fn animation(&self, played: Vec<PlayedFrame>, name: String, units: &Units) -> Result<SmgAnimation> {
        match &self.data {
            ImportedData::Subject(i) => {
                let s = &i.subject;
                let positions: Vec<f32> = played.iter().flat_map(|(p, _)| p.iter().copied()).collect();
                let sequence = Sequence::new("smg", s.topology().n_vertices(), positions)?;
                Ok(SmgAnimation::Subject(s.derived(name, sequence)?))
            }
            ImportedData::FrameSet(_) => {
                let per_frame = played
                    .into_iter()
                    .map(|(p, t)| Ok((Topology::new(p.len() / 3, t.to_vec(), None)?, p)))
                    .collect::<Result<Vec<_>>>()?;
                let sequence = FrameSetSequence::from_frames("smg", per_frame)?;
                Ok(SmgAnimation::FrameSet(FrameSet::new(
                    name,
                    vec![sequence],
                    self.frames.fps,
                    self.frames.up,
                    units.clone(),
                )?))
            }
        }
    }
}

/// A duration as the user wrote it (`3s`, `90f`).
fn time_text(t: &TimeSpec) -> String {
    match t.unit {
        Some(TimeUnit::Frames) => format!("{}f", t.value),
        Some(TimeUnit::Seconds) | None => format!("{}s", t.value),
    }
}

/// An excluded loop in the user's terms: its frames as runs of consecutive frames.
fn excluded_report(frames: &MotionFrames, played: &[usize], variation: f64, why: &Exclusion) -> ExcludedLoopReport {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < played.len() {
        let mut j = i;
        while j + 1 < played.len() && played[j + 1] == played[j] + 1 {
            j += 1;
        }
        let last = frames.name_of(played[j]);
        let last = last.rsplit_once(':').map(|(_, f)| f.to_string()).unwrap_or(last);
        runs.push(format!("{}-{last}", frames.name_of(played[i])));
        i = j + 1;
    }
    ExcludedLoopReport {
        frames: runs,
        played_frames: played.len(),
        pose_variation: variation,
        kind: why.kind(),
        why: why.to_string(),
    }
}

/// The area-weighted centroid of every output frame: its source frame's, moved by the ground
/// offset the path adds there (as `play_path` moves the vertices).
fn played_centres(frames: &MotionFrames, path: &PathSolution) -> Vec<[f64; 3]> {
    let centroids = frames.centroids();
    let (axis, _) = frames.up.axis_and_sign();
    let (x, y) = ((axis + 1) % 3, (axis + 2) % 3);
    path.frames
        .iter()
        .zip(&path.offsets)
        .map(|(&f, o)| {
            let mut c = centroids[f];
            c[x] += o[0];
            c[y] += o[1];
            c
        })
        .collect()
}
