//! Behavioural path synthesis (thesis 3.5.1, eq. 3.5): the walk whose centre of mass (or the
//! centre of any vertex set) follows a user curve by arc length, optionally restricted to some
//! motion types on parts of the curve; found by depth-first branch-and-bound in the graph.
//!
//! Cost of appending a node (j_c of eq. 3.5): every output frame the appended edge adds (one for
//! successive frames, the Blend's frames and the destination for a transition) costs the
//! distance from its tracked centre to the curve point at the same arc length as the walk's
//! centre trajectory so far. The thesis evaluates only the appended node; counting the
//! transition's inner frames too keeps a long transition from cutting corners unseen. Halting:
//! the walk's travelled length reaches the curve's length.
//!
//! Search (our decision): an exhaustive depth-first search over
//! walks of a whole curve is exponential in its length (a 15 m path is some 400 frames), so the
//! branch-and-bound runs over a receding window, as Kovar et al. 2002 did for their path
//! synthesis: from the current state, every walk that covers the next `window` of arc length
//! with at most `max_transitions` transitions is explored depth-first, successive frames before
//! transitions and transitions by increasing edge weight; a branch is cut as soon as its cost
//! reaches the best complete one (costs only grow). The first half of the best walk is kept and
//! the search goes on from there. A walk that cannot cover its window within `max_frames` frames
//! is ranked after every walk that can, by its remaining length, so standing still (which stays
//! close to the curve's start at no cost) never wins over walking.
//!
//! The walk starts where the user says, or at the best of all frames: each candidate is placed
//! with its centre on the curve's start and its direction of travel (the centre's displacement
//! over the next half second of its own sequence) along the curve's first tangent. A frame that
//! stands (its centre moves less than [`STANDING_FRACTION`] of the subject's fastest half-second
//! travel) has no direction of travel: aligning its few millimetres of sway sent a knight
//! starting from frame 17 of its idle clip off at right angles to a straight line (9.6 m mean
//! error, against 0.006 m from frame 0, whose sway happened to point forward). Such a frame is
//! tried at [`STANDING_START_HEADINGS`] headings instead, each searched over the first window
//! like a start candidate, and the cheapest is kept (`surfcap-synthesis`'s
//! `tests/path_from_a_standing_start.rs`: the procedural mannequin from its idle frames, 5.2-7.1
//! m of mean error on a 10 m line before, under 0.01 m now).

use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;

use surfcap_geometry::motion_plane_alignment::PlaneMotion;

use crate::dead_ends::live_nodes;
use crate::error::{Error, Result};
use crate::graph::{Edge, Graph};
use crate::walk_sequence::{Step, TransitionTrack, WalkModel};

/// A polyline parametrised by arc length. In planar mode only the ground-plane coordinates
/// count (for the arc length of the curve and of the walk, and for the error).
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    points: Vec<[f64; 3]>,
    cumulative: Vec<f64>,
    /// Indices of the coordinates that count: the two ground-plane axes, or all three.
    axes: Vec<usize>,
}

impl Curve {
    /// `points` in the subject's coordinates; `axes` the coordinates that count. Consecutive
    /// duplicate points are dropped. Errors when fewer than two distinct points remain.
    pub fn new(points: Vec<[f64; 3]>, axes: Vec<usize>) -> Result<Self> {
        if points.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::CurveNonFinite);
        }
        let mut kept: Vec<[f64; 3]> = Vec::with_capacity(points.len());
        let mut cumulative = Vec::with_capacity(points.len());
        for p in points {
            match kept.last() {
                None => cumulative.push(0.0),
                Some(q) => {
                    let d = dist(&axes, q, &p);
                    if d <= 0.0 {
                        continue;
                    }
                    cumulative.push(cumulative.last().unwrap() + d);
                }
            }
            kept.push(p);
        }
        if kept.len() < 2 {
            return Err(Error::CurveTooShort);
        }
        Ok(Curve { points: kept, cumulative, axes })
    }

    pub fn length(&self) -> f64 {
        *self.cumulative.last().expect("two points at least")
    }

    pub fn axes(&self) -> &[usize] {
        &self.axes
    }

    /// The point at arc length `s` (clamped to the curve).
    pub fn at(&self, s: f64) -> [f64; 3] {
        let s = s.clamp(0.0, self.length());
        let k = self.cumulative.partition_point(|&c| c <= s).clamp(1, self.points.len() - 1);
        let (a, b) = (self.points[k - 1], self.points[k]);
        let t = (s - self.cumulative[k - 1]) / (self.cumulative[k] - self.cumulative[k - 1]);
        std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
    }

    /// Distance between two points in the curve's coordinates.
    pub fn distance(&self, a: &[f64; 3], b: &[f64; 3]) -> f64 {
        dist(&self.axes, a, b)
    }
}

fn dist(axes: &[usize], a: &[f64; 3], b: &[f64; 3]) -> f64 {
    axes.iter().map(|&k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Only sequences marked in `allowed` (one flag per sequence) between arc lengths `from` and
/// `to` (a node is checked at the arc length where it is shown).
#[derive(Debug, Clone, PartialEq)]
pub struct Restriction {
    pub from: f64,
    pub to: f64,
    pub allowed: Vec<bool>,
}

/// Search settings.
#[derive(Debug, Clone, PartialEq)]
pub struct PathSearch {
    /// Arc length each branch-and-bound window covers (half of it is kept).
    pub window: f64,
    /// Transitions allowed inside one window.
    pub max_transitions: usize,
    /// Frames a walk may take to cover a window before it counts as stalled.
    pub max_frames: usize,
    /// Candidate start frames kept for the full first-window search when no start is given.
    pub start_candidates: usize,
    /// Transitions tried at each node (its cheapest ones): essential graphs keep tens of
    /// transitions per frame, and trying all of them at every frame of a window is what makes
    /// the exhaustive search exponential.
    pub branching: usize,
    /// Bin of the dominance rule, in subject units (and radians for the heading).
    pub state_bin: f64,
}

impl PathSearch {
    /// Defaults for a subject in metres at `fps`: 3 m windows (the first half kept), two
    /// transitions each, the 8 cheapest (round robin over destination sequences) tried per
    /// frame, and a walker must cover a window within 6 seconds. Branching is the speed knob:
    /// on the 2,000-frame bench graph (~337 transitions per frame) a 15 m path took 3.6 s with
    /// 16, 0.7 s with 10 and 0.4 s with 8, mean errors 0.012, 0.015 and 0.018 m (`surfcap-bench
    /// synth --branching B`); on the CMU-16 subject 8 and 10 both give 0.08 m.
    pub fn for_fps(fps: f64) -> Self {
        PathSearch {
            window: 3.0,
            max_transitions: 2,
            max_frames: (6.0 * fps).round() as usize,
            start_candidates: 8,
            branching: 8,
            state_bin: 0.1,
        }
    }

    /// [`PathSearch::for_fps`] for a subject whose shortest looping clip lasts `seconds`
    /// (`None`: no clip loops). A clip captured at length turns on its own between transitions;
    /// a one-cycle loop plays the same cycle again and again, so every change of heading comes
    /// from a transition. When some loop is shorter than [`SHORT_LOOP_SECONDS`] the search
    /// allows one transition per 0.67 m instead of per 1.5 m: windows of 2 m with 3 transitions
    /// (on a one-cycle KayKit knight and mannequin, the 15 m S-curve's mean error drops from
    /// 0.43 and 0.96 m to 0.02 and 0.01 m, the search staying near a second).
    pub fn for_clips(fps: f64, shortest_loop_seconds: Option<f64>) -> Self {
        let p = PathSearch::for_fps(fps);
        match shortest_loop_seconds {
            Some(t) if t < SHORT_LOOP_SECONDS => PathSearch { window: 2.0, max_transitions: 3, ..p },
            _ => p,
        }
    }
}

/// Loops shorter than this (two seconds, the longest transition segment of thesis 2.5.3) make
/// [`PathSearch::for_clips`] allow more transitions.
pub const SHORT_LOOP_SECONDS: f64 = 2.0;

/// The walk found, with its predicted per-frame errors.
#[derive(Debug, Clone, PartialEq)]
pub struct PathResult {
    pub walk: Vec<u32>,
    pub start: PlaneMotion,
    /// Predicted tracked centre and curve error of every output frame.
    pub centres: Vec<[f64; 3]>,
    pub errors: Vec<f64>,
    /// Arc length the walk travelled.
    pub travelled: f64,
    pub windows: usize,
    /// Nodes visited by the depth-first searches.
    pub expanded: u64,
    pub seconds: f64,
}

#[derive(Debug, Clone, Copy)]
struct State {
    node: u32,
    g: PlaneMotion,
    s: f64,
    last: [f64; 3],
    cost: f64,
    frames: usize,
}

/// The query, shared by every window.
struct Query<'a> {
    model: &'a WalkModel,
    curve: &'a Curve,
    restrictions: &'a [Restriction],
    /// Transition edges leaving each node: the cheapest into each sequence, then the second
    /// cheapest into each, and so on.
    transitions: Vec<Vec<(u32, &'a TransitionTrack)>>,
    /// Whether a walk can go on from a node for as long as needed (see [`crate::dead_ends`]):
    /// the search only enters such nodes, so it never walks into the end of a sequence.
    live: Vec<bool>,
}

impl<'a> Query<'a> {
    fn new(model: &'a WalkModel, graph: &Graph, curve: &'a Curve, restrictions: &'a [Restriction]) -> Self {
        let n = model.centres.len();
        let transitions: Vec<Vec<(u32, &TransitionTrack)>> = (0..n)
            .map(|u| {
                let mut out: Vec<(f64, u32, &TransitionTrack)> = graph
                    .out(u)
                    .iter()
                    .filter_map(|e| match model.step(e.from, e.to) {
                        Some(Step::Transition(t)) => Some((e.weight, e.to, t)),
                        _ => None,
                    })
                    .collect();
                out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                // Round robin over destination sequences (cheapest first within each), so the
                // first few transitions tried reach every kind of motion, not only the many
                // near-identical poses of the closest sequence.
                let seq = |v: u32| model.index.locate(v as usize).map_or(0, |l| l.0);
                let mut rank = vec![0usize; model.index.n_sequences()];
                let mut keyed: Vec<(usize, usize, u32, &TransitionTrack)> = out
                    .into_iter()
                    .enumerate()
                    .map(|(k, (_, v, t))| {
                        let r = rank[seq(v)];
                        rank[seq(v)] += 1;
                        (r, k, v, t)
                    })
                    .collect();
                keyed.sort_by_key(|x| (x.0, x.1));
                keyed.into_iter().map(|(_, _, v, t)| (v, t)).collect()
            })
            .collect();
        // The edges the search can play: successive frames and the transitions with a track.
        let playable: Vec<Edge> = (0..n as u32)
            .flat_map(|u| {
                let next = model.next(u).map(|(v, _)| v);
                next.into_iter().chain(transitions[u as usize].iter().map(|&(v, _)| v)).map(move |to| Edge {
                    from: u,
                    to,
                    weight: 1.0,
                })
            })
            .collect();
        let live = live_nodes(&Graph::new(n, playable));
        Query { model, curve, restrictions, transitions, live }
    }

    fn allowed(&self, node: u32, s: f64) -> bool {
        let seq = self.model.index.locate(node as usize).map_or(usize::MAX, |l| l.0);
        self.restrictions.iter().all(|r| s < r.from || s > r.to || r.allowed.get(seq).copied().unwrap_or(false))
    }

    /// Appends edge `step` to `st` (j_c of eq. 3.5 added to the cost); `None` when a
    /// restriction forbids its destination.
    fn append(&self, st: &State, step: Step<'_>, v: u32) -> Option<State> {
        let mut n = *st;
        let g = self.model.advance(step, &st.g, v, |c, _| {
            let ds = self.curve.distance(&n.last, &c);
            n.s += ds;
            n.last = c;
            n.cost += self.curve.distance(&c, &self.curve.at(n.s)) * ds;
            n.frames += 1;
        });
        n.g = g;
        n.node = v;
        self.allowed(v, n.s).then_some(n)
    }
}

/// Penalty per unit of arc length a stalled walk leaves uncovered: above any complete walk.
const STALL: f64 = 1e6;

/// One depth-first branch-and-bound over the walks that cover [s, end].
struct Window<'a> {
    q: &'a Query<'a>,
    end: f64,
    max_frames: usize,
    best: f64,
    best_walk: Vec<u32>,
    path: Vec<u32>,
    expanded: u64,
    /// Cheapest cost seen per coarse state (see [`state_key`]).
    seen: HashMap<StateKey, f64>,
    branching: usize,
    bin: f64,
}

/// Node, arc length, position and heading (in bins of `state_bin`) and transitions left.
type StateKey = (u32, i32, i32, i32, i32, u8);

/// Two partial walks at the same node with nearly the same arc length, placement and
/// transition budget have the same futures: the dearer one is cut (a dominance rule that
/// turns the depth-first search from exponential into a search over coarse states).
fn state_key(q: &Query<'_>, st: &State, left: usize, bin: f64) -> StateKey {
    let (iu, iv) = q.model.plane();
    let b = |x: f64| (x / bin).round() as i32;
    let theta = crate::blend::wrap_angle(st.g.theta);
    (st.node, b(st.s), b(st.last[iu]), b(st.last[iv]), b(theta), left.min(255) as u8)
}

impl Window<'_> {
    fn finish(&mut self, st: &State, complete: bool) {
        let cost = if complete { st.cost } else { st.cost + (self.end - st.s) * STALL };
        if cost < self.best {
            self.best = cost;
            self.best_walk = self.path.clone();
        }
    }

    fn dfs(&mut self, st: State, transitions_left: usize) {
        self.expanded += 1;
        if st.cost >= self.best {
            return;
        }
        if st.s >= self.end {
            return self.finish(&st, true);
        }
        if st.frames >= self.max_frames {
            return self.finish(&st, false);
        }
        let key = state_key(self.q, &st, transitions_left, self.bin);
        match self.seen.get_mut(&key) {
            Some(c) if *c <= st.cost => return,
            Some(c) => *c = st.cost,
            None => {
                self.seen.insert(key, st.cost);
            }
        }
        let (q, u) = (self.q, st.node);
        let open = |v: u32| q.live[v as usize];
        // Children: the next original frame (or a looping clip's wrap), then up to `branching` transitions; explored
        // cheapest first so that good complete walks tighten the bound early.
        let mut children: Vec<(State, usize)> = Vec::new();
        // The next frame as captured: u + 1, or the start of a looping clip after its last frame.
        if let Some((v, step)) = q.model.next(u)
            && open(v)
            && let Some(next) = q.append(&st, step, v)
        {
            children.push((next, transitions_left));
        }
        if transitions_left > 0 {
            for &(v, t) in q.transitions[u as usize].iter().filter(|(v, _)| open(*v)).take(self.branching) {
                if let Some(next) = q.append(&st, Step::Transition(t), v) {
                    children.push((next, transitions_left - 1));
                }
            }
        }
        if children.is_empty() {
            return self.finish(&st, false);
        }
        children.sort_by(|a, b| a.0.cost.total_cmp(&b.0.cost).then(b.1.cmp(&a.1)).then(a.0.node.cmp(&b.0.node)));
        for (next, left) in children {
            self.path.push(next.node);
            self.dfs(next, left);
            self.path.pop();
        }
    }
}

/// A frame stands when its centre moves less than this fraction of the subject's fastest
/// half-second travel over the next half second: 0.1 is 0.28 m/s on the CMU mannequin (fastest
/// 2.8 m/s) and 0.38 m/s on the KayKit knight (3.8 m/s), about the 0.2 heights a second below
/// which the interactive controller calls a frame idle.
pub const STANDING_FRACTION: f64 = 0.1;

/// Headings (evenly spaced) tried for a start frame that stands.
pub const STANDING_START_HEADINGS: usize = 16;

/// The centre's displacement on the ground over the half second after node `u` in its own
/// sequence (before it, at the sequence's end).
fn travel_direction(model: &WalkModel, u: u32) -> [f64; 2] {
    let (iu, iv) = model.plane();
    let range = model.index.range(model.index.locate(u as usize).expect("node is a frame").0);
    let h = (model.fps / 2.0).round().max(1.0) as usize;
    let (a, b) = if u as usize + h < range.end {
        (u as usize, u as usize + h)
    } else {
        (u as usize - h.min(u as usize - range.start), u as usize)
    };
    let (ca, cb) = (model.centres[a], model.centres[b]);
    [cb[iu] - ca[iu], cb[iv] - ca[iv]]
}

/// The subject's fastest half-second travel (the longest [`travel_direction`] over its frames).
fn fastest_travel(model: &WalkModel) -> f64 {
    (0..model.centres.len() as u32).map(|u| norm2(travel_direction(model, u))).fold(0.0, f64::max)
}

fn norm2(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// The placement that puts node `u` at the curve's start, heading along its first tangent.
pub fn start_placement(model: &WalkModel, curve: &Curve, u: u32) -> PlaneMotion {
    let (iu, iv) = model.plane();
    let dir = travel_direction(model, u);
    let c0 = curve.at(0.0);
    let c1 = curve.at((0.5f64).min(curve.length()));
    let tan = [c1[iu] - c0[iu], c1[iv] - c0[iv]];
    // Rotation by theta maps (u, v) to (u cos + v sin, -u sin + v cos): the angle from dir to tan.
    let theta =
        if norm2(dir) > 1e-3 && norm2(tan) > 1e-9 { (dir[1].atan2(dir[0])) - (tan[1].atan2(tan[0])) } else { 0.0 };
    turned_start_placement(model, curve, u, theta)
}

/// The placement that puts node `u`'s centre at the curve's start, turned by `theta` about the
/// up axis.
fn turned_start_placement(model: &WalkModel, curve: &Curve, u: u32, theta: f64) -> PlaneMotion {
    let (iu, iv) = model.plane();
    let c0 = curve.at(0.0);
    let cu = model.centres[u as usize];
    let rot = PlaneMotion { theta, t: [0.0, 0.0], up: model.up };
    let r = rot.apply_point(cu);
    PlaneMotion { theta, t: [c0[iu] - r[iu], c0[iv] - r[iv]], up: model.up }
}

/// Error of every frame of a centre trajectory against `curve` (distance to the curve point at
/// the trajectory's arc length so far), and the trajectory's length.
pub fn path_errors(curve: &Curve, centres: &[[f64; 3]]) -> (Vec<f64>, f64) {
    let mut s = 0.0;
    let mut errors = Vec::with_capacity(centres.len());
    for (k, c) in centres.iter().enumerate() {
        if k > 0 {
            s += curve.distance(&centres[k - 1], c);
        }
        errors.push(curve.distance(c, &curve.at(s)));
    }
    (errors, s)
}

/// Follows `curve` (thesis 3.5.1). `start`: the first node, or `None` to try every frame.
pub fn follow_path(
    model: &WalkModel,
    graph: &Graph,
    curve: &Curve,
    restrictions: &[Restriction],
    start: Option<u32>,
    p: &PathSearch,
) -> Result<PathResult> {
    let t0 = Instant::now();
    if !(p.window > 0.0 && p.window.is_finite()) || p.max_frames == 0 {
        return Err(Error::PathSearchParameters { window: p.window, max_frames: p.max_frames });
    }
    if p.branching == 0 {
        return Err(Error::Parameter { name: "branching", value: 0.0, expected: "a whole number >= 1" });
    }
    let q = Query::new(model, graph, curve, restrictions);
    let placed = |u: u32, g: PlaneMotion| -> State {
        let c = g.apply_point(model.centres[u as usize]);
        State { node: u, g, s: 0.0, last: c, cost: curve.distance(&c, &curve.at(0.0)), frames: 1 }
    };
    let initial = |u: u32| placed(u, start_placement(model, curve, u));
    let mut expanded = 0;
    // Best walk over the next window from `st` (its cost, its nodes after st.node).
    let window = |st: State, max_transitions: usize, expanded: &mut u64| -> (f64, Vec<u32>) {
        let mut w = Window {
            q: &q,
            end: (st.s + p.window).min(curve.length()),
            max_frames: st.frames + p.max_frames,
            best: f64::INFINITY,
            best_walk: Vec::new(),
            path: Vec::new(),
            expanded: 0,
            seen: HashMap::new(),
            branching: p.branching,
            bin: p.state_bin,
        };
        w.dfs(st, max_transitions);
        *expanded += w.expanded;
        (w.best, w.best_walk)
    };
    let starts: Vec<u32> = match start {
        Some(u) => vec![u],
        None => {
            // Rank every frame by playing its own sequence over the first window, then search
            // the best few with transitions.
            let mut scored: Vec<(f64, u32)> = (0..model.centres.len() as u32)
                .filter(|&u| q.live[u as usize] && q.allowed(u, 0.0))
                .map(|u| (window(initial(u), 0, &mut expanded).0, u))
                .collect();
            scored.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            scored.into_iter().take(p.start_candidates.max(1)).map(|(_, u)| u).collect()
        }
    };
    if let Some(&u) = starts.first() {
        if !q.allowed(u, 0.0) {
            return Err(Error::StartNotAllowed { frame: model.index.label(u as usize) });
        }
        if !q.live[u as usize] {
            return Err(Error::StartIsDeadEnd { frame: model.index.label(u as usize) });
        }
    }
    // Each candidate placed along its direction of travel, or, standing, at every heading.
    let standing = STANDING_FRACTION * fastest_travel(model);
    let candidates: Vec<State> = starts
        .iter()
        .flat_map(|&u| {
            if norm2(travel_direction(model, u)) < standing {
                (0..STANDING_START_HEADINGS)
                    .map(|k| {
                        let theta = std::f64::consts::TAU * k as f64 / STANDING_START_HEADINGS as f64;
                        placed(u, turned_start_placement(model, curve, u, theta))
                    })
                    .collect()
            } else {
                vec![initial(u)]
            }
        })
        .collect();
    // The candidates' first windows are independent: searched in parallel, the first of the
    // cheapest wins (the same choice whatever the number of threads).
    let searched: Vec<(f64, u64)> = candidates
        .par_iter()
        .map(|&st| {
            let mut e = 0;
            let (c, _) = window(st, p.max_transitions, &mut e);
            (c, e)
        })
        .collect();
    let mut best_start: Option<(f64, usize)> = None;
    for (k, (c, e)) in searched.into_iter().enumerate() {
        expanded += e;
        if best_start.is_none_or(|(b, _)| c < b) {
            best_start = Some((c, k));
        }
    }
    let (_, k0) = best_start.ok_or(Error::NoStartFrame)?;
    let mut st = candidates[k0];
    let u0 = st.node;
    let start_g = st.g;
    let mut walk = vec![u0];
    let mut windows = 0;
    // A walk that stalls (covers no ground window after window) is stopped with an error.
    let frame_budget = ((curve.length() / p.window).ceil() as usize + 2) * p.max_frames;
    while st.s < curve.length() {
        windows += 1;
        let (_, found) = window(st, p.max_transitions, &mut expanded);
        if found.is_empty() {
            // Every node searched can go on, so only a restriction can leave no way on.
            return Err(Error::PathStuck {
                frame: model.index.label(st.node as usize),
                travelled: st.s,
                length: curve.length(),
            });
        }
        // Keep the first half of the window (at least one step).
        let keep_until = st.s + 0.5 * p.window;
        for &v in &found {
            let step = model.step(st.node, v).expect("the search only takes edges");
            st = q.append(&st, step, v).expect("the search only takes allowed edges");
            walk.push(v);
            if st.s >= keep_until {
                break;
            }
        }
        if st.frames > frame_budget {
            return Err(Error::PathStalls { frames: st.frames, travelled: st.s, length: curve.length() });
        }
    }
    let centres = model.walk_centres(&walk, &start_g)?;
    let (errors, travelled) = path_errors(curve, &centres);
    Ok(PathResult {
        walk,
        start: start_g,
        centres,
        errors,
        travelled,
        windows,
        expanded,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_loops_get_more_transitions_per_metre() {
        let long = PathSearch::for_fps(30.0);
        assert_eq!(PathSearch::for_clips(30.0, None), long);
        assert_eq!(PathSearch::for_clips(30.0, Some(2.5)), long);
        let short = PathSearch::for_clips(30.0, Some(0.8));
        assert_eq!((short.window, short.max_transitions), (2.0, 3));
        assert!(short.max_transitions as f64 / short.window > long.max_transitions as f64 / long.window);
    }

    #[test]
    fn curve_by_arc_length_and_planar_distances() {
        let c =
            Curve::new(vec![[0.0, 5.0, 0.0], [3.0, 9.0, 0.0], [3.0, 9.0, 0.0], [3.0, 0.0, 4.0]], vec![0, 2]).unwrap();
        assert_eq!(c.length(), 7.0); // 3 then 4 in the ground plane; the duplicate is dropped
        let p = c.at(5.0);
        assert!((p[0] - 3.0).abs() < 1e-12 && (p[2] - 2.0).abs() < 1e-12);
        assert_eq!(c.at(99.0), [3.0, 0.0, 4.0]);
        assert_eq!(c.distance(&[0.0, 100.0, 0.0], &[3.0, -7.0, 4.0]), 5.0);
        assert!(Curve::new(vec![[1.0, 2.0, 3.0], [1.0, 7.0, 3.0]], vec![0, 2]).is_err(), "one point on the ground");
        let (e, len) = path_errors(&c, &[[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 0.0, 1.0]]);
        assert_eq!((e, len), (vec![0.0, 0.0, 0.0], 4.0));
    }

    #[test]
    fn the_tube_follows_a_straight_line_and_restrictions_hold() {
        let (s, g, model, _) = crate::walk_sequence::tests::setup();
        // The tube crawls along +x: a straight line as long as about two sequences' crawl.
        let (c0, c1) = (model.centres[0], model.centres[29]);
        let crawl = c1[0] - c0[0];
        assert!(crawl > 0.05);
        let pts = vec![[0.0, 0.0, 0.0], [1.8 * crawl, 0.0, 0.0]];
        let curve = Curve::new(pts, vec![0, 2]).unwrap();
        let p = PathSearch { window: crawl / 2.0, ..PathSearch::for_fps(s.fps) };
        let r = follow_path(&model, &g, &curve, &[], None, &p).unwrap();
        let mean = r.errors.iter().sum::<f64>() / r.errors.len() as f64;
        assert!(r.travelled >= curve.length() && mean < 0.1 * crawl, "mean error {mean} for a crawl of {crawl}");
        let played = model.walk_centres(&r.walk, &r.start).unwrap();
        assert_eq!(played, r.centres);
        // Only the second sequence after a fifth of the curve.
        let only_second = Restriction { from: 0.2 * curve.length(), to: curve.length(), allowed: vec![false, true] };
        let r = follow_path(&model, &g, &curve, std::slice::from_ref(&only_second), None, &p).unwrap();
        // Replay the walk: every node shown inside the restricted stretch is of sequence 1.
        let (mut g0, mut last, mut arc, mut checked) = (r.start, r.centres[0], 0.0, 0);
        for w in r.walk.windows(2) {
            let step = model.step(w[0], w[1]).unwrap();
            g0 = model.advance(step, &g0, w[1], |c, _| {
                arc += curve.distance(&last, &c);
                last = c;
            });
            if arc > only_second.from + 1e-9 && arc <= only_second.to {
                assert_eq!(s.frame_index().locate(w[1] as usize).unwrap().0, 1, "node {} at {arc}", w[1]);
                checked += 1;
            }
        }
        assert!(checked >= 3, "{checked}");
    }

    /// The search never enters a frame from which the walk cannot go on ("the walk is
    /// stuck at frame 463"), and a given start that is such a frame is refused by name.
    #[test]
    fn walks_avoid_dead_ends_and_a_dead_start_is_refused() {
        let (s, g, model, _) = crate::walk_sequence::tests::setup();
        let crawl = model.centres[29][0] - model.centres[0][0];
        let curve = Curve::new(vec![[0.0, 0.0, 0.0], [3.0 * crawl, 0.0, 0.0]], vec![0, 2]).unwrap();
        let p = PathSearch { window: crawl / 2.0, ..PathSearch::for_fps(s.fps) };
        let q = Query::new(&model, &g, &curve, &[]);
        let last = s.frame_index().range(0).end as u32 - 1;
        assert!(!q.live[last as usize] && q.live.iter().any(|&l| l), "the last frame of a sequence is a dead end");
        let r = follow_path(&model, &g, &curve, &[], None, &p).unwrap();
        assert!(r.travelled >= curve.length());
        assert!(r.walk.iter().all(|&v| q.live[v as usize]), "{:?}", r.walk);
        let err = follow_path(&model, &g, &curve, &[], Some(last), &p).unwrap_err();
        let name = s.sequences()[0].name.clone();
        assert!(err.to_string().starts_with(&format!("the start frame {name}:{} is a dead end", last)), "{err}");
    }

    /// Same walk whatever the number of threads (the start candidates are searched in parallel).
    #[test]
    fn one_and_two_threads_find_the_same_walk() {
        let (s, g, model, _) = crate::walk_sequence::tests::setup();
        let crawl = model.centres[29][0] - model.centres[0][0];
        let curve = Curve::new(vec![[0.0, 0.0, 0.0], [1.8 * crawl, 0.0, 0.4 * crawl]], vec![0, 2]).unwrap();
        let p = PathSearch { window: crawl / 2.0, ..PathSearch::for_fps(s.fps) };
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| follow_path(&model, &g, &curve, &[], None, &p).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!((a.walk, a.start, a.errors), (b.walk, b.start, b.errors));
    }

    /// A 3D curve counts the height: at the tube's own centre height it is followed as well as
    /// on the ground plane; lifted above it, every frame misses by at least the lift.
    #[test]
    fn three_dimensional_curves_count_the_height() {
        let (s, g, model, _) = crate::walk_sequence::tests::setup();
        let (iu, iv) = model.plane();
        let up = 3 - iu - iv;
        let crawl = model.centres[29][0] - model.centres[0][0];
        let height = model.centres.iter().map(|c| c[up]).sum::<f64>() / model.centres.len() as f64;
        let p = PathSearch { window: crawl / 2.0, ..PathSearch::for_fps(s.fps) };
        let mut means = Vec::new();
        for lift in [0.0, 0.5 * crawl] {
            let point = |x: f64| {
                let mut q = [0.0; 3];
                q[0] = x;
                q[up] = height + lift;
                q
            };
            let curve = Curve::new(vec![point(0.0), point(1.8 * crawl)], vec![0, 1, 2]).unwrap();
            let r = follow_path(&model, &g, &curve, &[], None, &p).unwrap();
            assert!(r.travelled >= curve.length());
            let min = r.errors.iter().copied().fold(f64::INFINITY, f64::min);
            means.push((r.errors.iter().sum::<f64>() / r.errors.len() as f64, min));
        }
        let ((level, _), (lifted, lifted_min)) = (means[0], means[1]);
        assert!(level < 0.1 * crawl, "level curve: mean error {level} for a crawl of {crawl}");
        assert!(lifted_min >= 0.45 * crawl && lifted >= 0.5 * crawl - level, "lifted: {lifted} (min {lifted_min})");
    }
}
