//! Path optimisation on the surface motion graph (Huang et al. 2009, section 4): the path between
//! two key frames that best meets a target distance and time at the least transition cost.
//!
//! Cost of a path F (eq. 6-9): `C(F) = C_s + w_d |d(F) - d_T| + w_t |t(F) - t_T|` with `C_s` the
//! sum of its transition costs, `d(F)` the ground distance travelled and `t(F)` its frame count.
//!
//! Decomposition (4.2.1, Algorithm 1): every path from the start to the end key frame is a walk
//! (a path visiting no node twice) plus a number of repetitions of elementary cycles ("loops"),
//! each loop sharing a node with the walk or with another loop of the path. Walks are enumerated
//! by depth-first search, loops as the graph's elementary cycles (each found once, from its
//! smallest node); a walk's loops are those connected to it through shared nodes, nested
//! sub-loops included (a loop inside a loop shares its nodes).
//!
//! Repetitions (4.2.2, eq. 15-20): for a walk `l0` and its loops `l1 ... lm`, `d`, `t` and `C_s`
//! are linear in the repetitions `n` (`n0 = 1`). Each of the four sign combinations of
//! `d(F) - d_T` and `t(F) - t_T` gives an integer linear program without absolute values: minimise
//! `C_s(n) + sd w_d (d(n) - d_T) + st w_t (t(n) - t_T)` subject to `sd (d(n) - d_T) >= 0` and
//! `st (t(n) - t_T) >= 0`; the best of the four is the walk's optimum (eq. 20). Eq. 19 writes the
//! target inside every element's coefficient; with `n0 = 1` it belongs to the walk's only (the
//! target is subtracted once, not once per loop repetition), which is how it is folded here.
//! Each ILP is solved by a real MILP solver (`good_lp` with the pure-Rust `microlp`).
//!
//! Feedback (4.2.3, Algorithm 2): a loop attached only through other loops cannot be played when
//! none of those is. After each solve, used loops not connected to the walk through used loops
//! form groups; for each group `G` a cut `sum over G of n <= M * sum over the loops adjacent to
//! G of n` is added (valid for every playable path: a used group needs a used neighbour) and the
//! ILP solved again, until every used loop is reachable.
//!
//! Targets within a tolerance (an extension, beyond the paper; [`PathQuery::tolerance`]): eq. 6
//! trades transition cost against the constraint errors, so its optimum may miss a target that
//! some path meets. With a tolerance (1% of the distance and 1 frame by default), each sign
//! combination's ILP also bounds the errors (`0 <= sd (d(n) - d_T) <= 1% d_T`, `0 <= st (t(n) -
//! t_T) <= 1`), and the least eq. 6 cost among the paths within the tolerance is taken. When no
//! walk has one, the paper's optimum is returned with the reason ([`Unreachable`]): the target
//! is shorter than every path, asks for a speed outside what the loops travel, there is no loop
//! to repeat, or the loops' lengths do not combine to within the tolerance.
//!
//! Composition (4.2.3): the walk's edges, each loop's repetitions inserted where it first meets
//! the path built so far (loops attached through loops after their hosts). The frames follow;
//! at each transition the next sequence is moved on the ground so that its first frame's
//! centroid lies where the last frame's was (the paper matches the centroids; the height is
//! kept, so feet stay on the floor).

use good_lp::{Expression, ProblemVariables, Solution, SolverModel, Variable, microlp, variable};

use crate::error::{Error, Result};
use crate::loop_exclusion::{ExcludedLoop, LoopFilter};
use crate::surface_motion_graph::{EdgeKind, SurfaceMotionGraph};

/// A synthesis request: from key frame to key frame, covering a distance in a time.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct PathQuery {
    /// Global frames of the start and end key frames.
    pub start: usize,
    pub end: usize,
    /// Target ground distance, in the subject's units.
    pub distance: f64,
    /// Target length, in frames.
    pub frames: f64,
    /// Weights of eq. 6: the paper's `1/0.3` per metre and `1/10` per frame by default.
    pub w_d: f64,
    pub w_t: f64,
    /// The most walks (and loops) enumerated before the query is refused as too large.
    pub max_paths: usize,
    /// Meet the targets within this tolerance where the graph allows it (an extension; `None`:
    /// the paper's eq. 6 optimum).
    pub tolerance: Option<Tolerance>,
}

/// How close a path must come to the targets to meet them.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Tolerance {
    /// Of the target distance (0.01: 1%).
    pub distance_relative: f64,
    /// Frames.
    pub frames: f64,
}

impl Default for Tolerance {
    /// 1% of the distance and 1 frame (our goal for this engine, beyond the paper's).
    fn default() -> Self {
        Tolerance { distance_relative: 0.01, frames: 1.0 }
    }
}

pub use surfcap_mesh::reachability::Unreachable;

/// The frames a duration of `seconds` shows at `fps`, start included: round(T x fps), the count
/// a path's `t(F)` is compared with (and the count the essential graph's timed searches ask
/// for, so both engines answer the same target).
pub fn frames_shown(seconds: f64, fps: f64) -> f64 {
    (seconds * fps).round()
}

impl PathQuery {
    /// A query with the paper's weights (`w_d = 1/0.3` per unit, for subjects in metres).
    pub fn new(start: usize, end: usize, distance: f64, frames: f64) -> Self {
        PathQuery { start, end, distance, frames, w_d: 1.0 / 0.3, w_t: 1.0 / 10.0, max_paths: 100_000, tolerance: None }
    }
}

/// The optimal path found for a query.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PathSolution {
    /// Edges of the composed path, in order.
    pub edges: Vec<usize>,
    /// The global frame played at each output frame.
    pub frames: Vec<usize>,
    /// The ground offset added to each output frame (centroids matched at the transitions).
    pub offsets: Vec<[f64; 2]>,
    /// Output frames that start a new sequence after a transition.
    pub switches: Vec<usize>,
    /// The walk (edges) and the repetitions of its loops (edges, count).
    pub walk: Vec<usize>,
    pub loops: Vec<(Vec<usize>, u64)>,
    pub distance: f64,
    pub transition_cost: f64,
    /// `C(F)` of eq. 6, and the two constraint errors (distance in units, time in frames).
    pub cost: f64,
    pub distance_error: f64,
    pub time_error: f64,
    pub walks: usize,
    pub loops_in_graph: usize,
    pub ilp_solves: usize,
    /// Sub-problems given up because their feedback cuts did not settle (normally 0).
    pub unconverged_subproblems: usize,
    /// With a tolerance: whether the path meets it, and if not why no path can.
    pub within_tolerance: Option<bool>,
    pub unreachable: Option<Unreachable>,
}

/// Totals of a list of edges.
fn totals(g: &SurfaceMotionGraph, edges: &[usize]) -> (f64, f64, f64) {
    edges.iter().fold((0.0, 0.0, 0.0), |(d, t, s), &e| {
        let e = &g.edges[e];
        (d + e.distance, t + e.frames as f64, s + e.cost)
    })
}

fn nodes_of(g: &SurfaceMotionGraph, edges: &[usize]) -> Vec<usize> {
    edges.iter().flat_map(|&e| [g.edges[e].from, g.edges[e].to]).collect()
}

/// Every path from `s` that visits no node twice and ends with an edge into `t`, going only
/// through nodes `allowed`, as edge lists (iterative depth-first search); `what` names them in
/// the error when there are more than `max`.
fn simple_paths(
    g: &SurfaceMotionGraph,
    out: &[Vec<usize>],
    s: usize,
    t: usize,
    allowed: impl Fn(usize) -> bool,
    max: usize,
    what: &str,
) -> Result<Vec<Vec<usize>>> {
    let mut found = Vec::new();
    let mut on_path = vec![false; g.nodes.len()];
    on_path[s] = true;
    // (node, next out-edge position)
    let mut stack: Vec<(usize, usize)> = vec![(s, 0)];
    let mut path: Vec<usize> = Vec::new();
    while let Some(&mut (node, ref mut next)) = stack.last_mut() {
        if *next >= out[node].len() {
            stack.pop();
            on_path[node] = false;
            path.pop();
            continue;
        }
        let e = out[node][*next];
        *next += 1;
        let to = g.edges[e].to;
        if to == t {
            let mut w = path.clone();
            w.push(e);
            found.push(w);
            if found.len() > max {
                return Err(Error::Invalid(format!("more than {max} {what}: the graph is too dense")));
            }
        } else if !on_path[to] && allowed(to) {
            on_path[to] = true;
            path.push(e);
            stack.push((to, 0));
        }
    }
    Ok(found)
}

/// Every walk (node-simple path) from `s` to `t`, as edge lists.
fn walks(g: &SurfaceMotionGraph, out: &[Vec<usize>], s: usize, t: usize, max: usize) -> Result<Vec<Vec<usize>>> {
    if s == t {
        return Ok(vec![Vec::new()]);
    }
    simple_paths(g, out, s, t, |_| true, max, "walks between the key frames")
}

/// Every elementary cycle, each from its smallest node, as edge lists.
fn cycles(g: &SurfaceMotionGraph, out: &[Vec<usize>], max: usize) -> Result<Vec<Vec<usize>>> {
    let mut found = Vec::new();
    for s in 0..g.nodes.len() {
        found.extend(simple_paths(g, out, s, s, |v| v > s, max.saturating_sub(found.len()), "loops in the graph")?);
    }
    Ok(found)
}

/// The loops connected to `walk` through shared nodes, and for each loop its neighbours (other
/// loops sharing a node) and whether it touches the walk.
struct Attached {
    loops: Vec<usize>,
    touches_walk: Vec<bool>,
    neighbours: Vec<Vec<usize>>,
}

fn attach(g: &SurfaceMotionGraph, walk_nodes: &[usize], all: &[Vec<usize>]) -> Attached {
    let node_sets: Vec<Vec<usize>> = all.iter().map(|c| nodes_of(g, c)).collect();
    let shares = |a: &[usize], b: &[usize]| a.iter().any(|x| b.contains(x));
    let mut chosen: Vec<usize> = Vec::new();
    let mut is_chosen = vec![false; all.len()];
    for (i, ns) in node_sets.iter().enumerate() {
        if shares(ns, walk_nodes) {
            chosen.push(i);
            is_chosen[i] = true;
        }
    }
    let mut k = 0;
    while k < chosen.len() {
        let c = chosen[k];
        for (i, ns) in node_sets.iter().enumerate() {
            if !is_chosen[i] && shares(ns, &node_sets[c]) {
                chosen.push(i);
                is_chosen[i] = true;
            }
        }
        k += 1;
    }
    chosen.sort_unstable();
    let touches_walk = chosen.iter().map(|&c| shares(&node_sets[c], walk_nodes)).collect();
    let neighbours = chosen
        .iter()
        .map(|&a| {
            chosen
                .iter()
                .enumerate()
                .filter(|&(_, &b)| b != a && shares(&node_sets[a], &node_sets[b]))
                .map(|(j, _)| j)
                .collect()
        })
        .collect();
    Attached { loops: chosen, touches_walk, neighbours }
}

/// Used loops (by position in `attached`) not reachable from the walk through used loops,
/// grouped by their connections.
fn isolated_groups(a: &Attached, n: &[u64]) -> Vec<Vec<usize>> {
    let m = a.loops.len();
    let mut reached = vec![false; m];
    let mut queue: Vec<usize> = (0..m).filter(|&i| n[i] > 0 && a.touches_walk[i]).collect();
    for &i in &queue {
        reached[i] = true;
    }
    while let Some(i) = queue.pop() {
        for &j in &a.neighbours[i] {
            if n[j] > 0 && !reached[j] {
                reached[j] = true;
                queue.push(j);
            }
        }
    }
    let mut seen = reached.clone();
    let mut groups = Vec::new();
    for i in 0..m {
        if n[i] == 0 || seen[i] {
            continue;
        }
        let mut group = vec![i];
        seen[i] = true;
        let mut k = 0;
        while k < group.len() {
            for &j in &a.neighbours[group[k]] {
                if n[j] > 0 && !seen[j] {
                    seen[j] = true;
                    group.push(j);
                }
            }
            k += 1;
        }
        group.sort_unstable();
        groups.push(group);
    }
    groups
}

/// Solves one sign combination with the feedback cuts; `None` when infeasible.
#[allow(clippy::too_many_arguments)]
fn solve_signs(
    base: (f64, f64, f64),
    per_loop: &[(f64, f64, f64)],
    a: &Attached,
    q: &PathQuery,
    sd: f64,
    st: f64,
    caps: &Caps,
    within: Option<(f64, f64)>,
    counts: &mut SolveCounts,
) -> Result<Option<Vec<u64>>> {
    let mut cuts: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
    // Each round cuts off at least one group of loops; groups grow as cuts accumulate, so a
    // handful of rounds usually suffice. Past this many the sub-problem is given up (and
    // counted in the solution) rather than the whole query.
    for _ in 0..MAX_CUT_ROUNDS.max(per_loop.len() + 2) {
        let mut vars = ProblemVariables::new();
        let n: Vec<Variable> = caps.n.iter().map(|&c| vars.add(variable().integer().min(0.0).max(c))).collect();
        let lin = |f: &dyn Fn(&(f64, f64, f64)) -> f64, c0: f64| -> Expression {
            let mut e = Expression::from(c0);
            for (v, l) in n.iter().zip(per_loop) {
                e += f(l) * *v;
            }
            e
        };
        let d = lin(&|l| l.0, base.0 - q.distance);
        let t = lin(&|l| l.1, base.1 - q.frames);
        let s = lin(&|l| l.2, base.2);
        let objective = s + sd * q.w_d * d.clone() + st * q.w_t * t.clone();
        let mut model = vars.minimise(objective).using(microlp);
        model = model.with((sd * d.clone()).geq(0.0));
        model = model.with((st * t.clone()).geq(0.0));
        if let Some((tol_d, tol_t)) = within {
            model = model.with((sd * d).leq(tol_d));
            model = model.with((st * t).leq(tol_t));
        }
        if caps.frames.is_finite() {
            model = model.with(lin(&|l| l.1, 0.0).leq(caps.frames));
        }
        if caps.distance.is_finite() {
            model = model.with(lin(&|l| l.0, 0.0).leq(caps.distance));
        }
        for (group, adjacent) in &cuts {
            let mut lhs = Expression::from(0.0);
            for &i in group {
                lhs += n[i];
            }
            // No more than the group's caps: the cut binds only when no neighbour plays.
            let big: f64 = group.iter().map(|&i| caps.n[i]).sum();
            let mut rhs = Expression::from(0.0);
            for &j in adjacent {
                rhs += big * n[j];
            }
            model = model.with(lhs.leq(rhs));
        }
        counts.solves += 1;
        let sol = match model.solve() {
            Ok(s) => s,
            Err(good_lp::ResolutionError::Infeasible) => return Ok(None),
            Err(e) => return Err(Error::Invalid(format!("the ILP solver failed: {e}"))),
        };
        let values: Vec<u64> = n.iter().map(|&v| sol.value(v).round().max(0.0) as u64).collect();
        let groups = isolated_groups(a, &values);
        if groups.is_empty() {
            return Ok(Some(values));
        }
        for g in groups {
            let mut adjacent: Vec<usize> =
                g.iter().flat_map(|&i| a.neighbours[i].iter().copied()).filter(|j| !g.contains(j)).collect();
            adjacent.sort_unstable();
            adjacent.dedup();
            cuts.push((g, adjacent));
        }
    }
    counts.unconverged += 1;
    Ok(None)
}

/// What a walk's loops may add and still beat the best cost known (`ub`): every path cheaper
/// than `ub` overshoots the targets by less than `(ub - C_s(walk)) / w`, which caps the frames
/// and distance its loops add and each loop's repetitions. Valid cuts: they remove only paths
/// that cost more than `ub`, so the optimum is unchanged, and they make the ILPs far smaller.
struct Caps {
    n: Vec<f64>,
    frames: f64,
    distance: f64,
}

impl Caps {
    fn new(
        base: (f64, f64, f64),
        per_loop: &[(f64, f64, f64)],
        q: &PathQuery,
        ub: f64,
        within: Option<(f64, f64)>,
    ) -> Self {
        let over = |w: f64| if ub.is_finite() && w > 0.0 { (ub - base.2).max(0.0) / w } else { f64::INFINITY };
        let mut frames = (q.frames - base.1) + over(q.w_t);
        let mut distance = (q.distance - base.0) + over(q.w_d);
        if let Some((tol_d, tol_t)) = within {
            frames = frames.min(q.frames + tol_t - base.1);
            distance = distance.min(q.distance + tol_d - base.0);
        }
        if !frames.is_finite() {
            // Without a known cost: repetitions beyond this cannot help, every loop adding at
            // least one frame.
            frames = (4.0 * (q.frames + base.1)).ceil() + 10.0;
        }
        // A hair of slack so that rounding never removes a path of exactly the bound.
        let (frames, distance) = (frames + 1e-9, distance + 1e-9);
        let n = per_loop
            .iter()
            .map(|l| {
                let by_frames = (frames / l.1.max(1.0)).floor();
                let by_distance = if l.0 > 0.0 { (distance / l.0).floor() } else { f64::INFINITY };
                by_frames.min(by_distance).max(0.0)
            })
            .collect();
        Caps { n, frames, distance }
    }
}

/// Rounds of feedback cuts tried on one sub-problem.
const MAX_CUT_ROUNDS: usize = 64;

/// ILP solves of a query, and sub-problems whose feedback cuts did not settle in
/// [`MAX_CUT_ROUNDS`] rounds (skipped).
#[derive(Debug, Clone, Copy, Default)]
struct SolveCounts {
    solves: usize,
    unconverged: usize,
}

/// Inserts each used loop's repetitions into the walk (see the module documentation).
fn compose(g: &SurfaceMotionGraph, walk: &[usize], loops: &[(Vec<usize>, u64)], start: usize) -> Result<Vec<usize>> {
    let mut path = walk.to_vec();
    let mut pending: Vec<usize> = (0..loops.len()).filter(|&i| loops[i].1 > 0).collect();
    while !pending.is_empty() {
        let before = pending.len();
        pending.retain(|&i| {
            let (cycle, count) = &loops[i];
            // Path nodes in visiting order: the start, then each edge's end.
            let visits: Vec<usize> = std::iter::once(start).chain(path.iter().map(|&e| g.edges[e].to)).collect();
            let Some((pos, rot)) = visits
                .iter()
                .enumerate()
                .find_map(|(p, &v)| cycle.iter().position(|&e| g.edges[e].from == v).map(|r| (p, r)))
            else {
                return true;
            };
            let rotated: Vec<usize> = cycle[rot..].iter().chain(&cycle[..rot]).copied().collect();
            let insert: Vec<usize> = (0..*count).flat_map(|_| rotated.iter().copied()).collect();
            path.splice(pos..pos, insert);
            false
        });
        if pending.len() == before {
            return Err(Error::Invalid("a loop could not be attached to the path".into()));
        }
    }
    Ok(path)
}

/// The target-independent part of a query between two key frames (4.2.1, Algorithm 1): the
/// walks, the graph's loops and each walk's attached loops with their totals. Computed once
/// per key-frame pair ([`plan_paths`]) and shared by every target ([`optimise_planned`]).
pub struct PathPlan {
    start: usize,
    end: usize,
    start_node: usize,
    all_loops: Vec<Vec<usize>>,
    prepared: Vec<Prepared>,
    /// Loops the plan does not repeat ([`plan_paths_excluding`]).
    excluded: Vec<ExcludedLoop>,
}

impl PathPlan {
    /// Walks between the key frames.
    pub fn walks(&self) -> usize {
        self.prepared.len()
    }

    /// Elementary loops of the whole graph that may pad time.
    pub fn loops_in_graph(&self) -> usize {
        self.all_loops.len()
    }

    /// The excluded loops: those of the graph the plan never repeats, with why.
    pub fn excluded_loops(&self) -> &[ExcludedLoop] {
        &self.excluded
    }
}

/// The walks and loops between the key frames `start` and `end` (global frames); more than
/// `max_paths` of either is refused.
pub fn plan_paths(g: &SurfaceMotionGraph, start: usize, end: usize, max_paths: usize) -> Result<PathPlan> {
    plan_with_loops(g, start, end, max_paths, |loops| (loops, Vec::new()))
}

/// [`plan_paths`] without the excluded loops: those `filter` judges too short or below its
/// pose-variation floor ([`crate::loop_exclusion`]) are never repeated to pad time, and the
/// plan lists them ([`PathPlan::excluded_loops`]). When none is left, a target the walks alone
/// miss is [`Unreachable::NoLoop`].
pub fn plan_paths_excluding(
    g: &SurfaceMotionGraph,
    start: usize,
    end: usize,
    max_paths: usize,
    filter: &LoopFilter<'_>,
) -> Result<PathPlan> {
    plan_with_loops(g, start, end, max_paths, |loops| filter.partition(g, loops))
}

/// [`plan_paths`] with the graph's loops split by `select` into those that may pad time and
/// the excluded loops.
fn plan_with_loops(
    g: &SurfaceMotionGraph,
    start: usize,
    end: usize,
    max_paths: usize,
    select: impl FnOnce(Vec<Vec<usize>>) -> (Vec<Vec<usize>>, Vec<ExcludedLoop>),
) -> Result<PathPlan> {
    let (Some(s), Some(t)) = (g.node_of(start), g.node_of(end)) else {
        return Err(Error::Invalid(format!(
            "key frames {start} and {end}: both must be nodes of the graph (build it with them)"
        )));
    };
    let out = g.out_edges();
    let all_walks = walks(g, &out, s, t, max_paths)?;
    if all_walks.is_empty() {
        return Err(Error::Invalid(format!(
            "no path from frame {start} to frame {end}: the higher-level graph does not connect them"
        )));
    }
    let (all_loops, excluded) = select(cycles(g, &out, max_paths)?);
    let prepared: Vec<Prepared> = all_walks
        .into_iter()
        .map(|walk| {
            let mut walk_nodes = nodes_of(g, &walk);
            walk_nodes.push(s);
            let a = attach(g, &walk_nodes, &all_loops);
            let (d0, t0, s0) = totals(g, &walk);
            let per_loop: Vec<(f64, f64, f64)> = a.loops.iter().map(|&c| totals(g, &all_loops[c])).collect();
            Prepared { walk, a, base: (d0, t0 + 1.0, s0), per_loop }
        })
        .collect();
    Ok(PathPlan { start, end, start_node: s, all_loops, prepared, excluded })
}

/// The optimal path for `q` on `g` (eq. 10-20), with `ground` each frame's ground centroid.
pub fn optimise_path(g: &SurfaceMotionGraph, ground: &[[f64; 2]], q: &PathQuery) -> Result<PathSolution> {
    check_targets(q)?;
    let plan = plan_paths(g, q.start, q.end, q.max_paths)?;
    optimise_planned(g, ground, &plan, q)
}

fn check_targets(q: &PathQuery) -> Result<()> {
    if !(q.distance.is_finite() && q.distance >= 0.0 && q.frames.is_finite() && q.frames >= 1.0) {
        return Err(Error::Invalid(format!(
            "target distance {} and time {} frames: expected a distance >= 0 and at least one frame",
            q.distance, q.frames
        )));
    }
    Ok(())
}

/// [`optimise_path`] with the walks and loops already planned for `q`'s key frames.
pub fn optimise_planned(
    g: &SurfaceMotionGraph,
    ground: &[[f64; 2]],
    plan: &PathPlan,
    q: &PathQuery,
) -> Result<PathSolution> {
    check_targets(q)?;
    if (plan.start, plan.end) != (q.start, q.end) {
        return Err(Error::Invalid(format!(
            "the plan is for frames {} -> {}, the query for {} -> {}",
            plan.start, plan.end, q.start, q.end
        )));
    }
    let (s, prepared, all_loops) = (plan.start_node, &plan.prepared, &plan.all_loops);
    let mut counts = SolveCounts::default();
    let (best, within_tolerance, unreachable) = match q.tolerance {
        None => (best_path(prepared, all_loops, q, None, &mut counts)?, None, None),
        Some(tol) => {
            let within = (tol.distance_relative * q.distance, tol.frames);
            match best_path(prepared, all_loops, q, Some(within), &mut counts)? {
                Some(b) => (Some(b), Some(true), None),
                None => (
                    best_path(prepared, all_loops, q, None, &mut counts)?,
                    Some(false),
                    Some(unreachable_reason(prepared, q, within)),
                ),
            }
        }
    };
    let Some((cost, walk, loops)) = best else {
        return Err(Error::Invalid("no sub-problem was feasible".into()));
    };
    let edges = compose(g, &walk, &loops, s)?;
    // Frames and ground offsets.
    let mut frames = vec![g.nodes[s]];
    let mut offsets = vec![[0.0, 0.0]];
    let mut switches = Vec::new();
    let mut offset = [0.0, 0.0];
    for &e in &edges {
        let edge = &g.edges[e];
        let (from, to) = (g.nodes[edge.from], g.nodes[edge.to]);
        match edge.kind {
            EdgeKind::Segment { .. } => {
                for f in from + 1..=to {
                    frames.push(f);
                    offsets.push(offset);
                }
            }
            EdgeKind::Transition { .. } => {
                offset = [offset[0] + ground[from][0] - ground[to][0], offset[1] + ground[from][1] - ground[to][1]];
                switches.push(frames.len());
                frames.push(to);
                offsets.push(offset);
            }
        }
    }
    let (distance, _, transition_cost) = totals(g, &edges);
    Ok(PathSolution {
        distance_error: (distance - q.distance).abs(),
        time_error: (frames.len() as f64 - q.frames).abs(),
        edges,
        frames,
        offsets,
        switches,
        walk,
        loops,
        distance,
        transition_cost,
        cost,
        walks: plan.walks(),
        loops_in_graph: plan.loops_in_graph(),
        ilp_solves: counts.solves,
        unconverged_subproblems: counts.unconverged,
        within_tolerance,
        unreachable,
    })
}

/// A walk ready for its ILPs: its attached loops, and `(d, t, C_s)` of the walk (with the
/// start frame) and of each loop.
struct Prepared {
    walk: Vec<usize>,
    a: Attached,
    base: (f64, f64, f64),
    per_loop: Vec<(f64, f64, f64)>,
}

/// (cost, walk, loops with their repetitions)
type Candidate = (f64, Vec<usize>, Vec<(Vec<usize>, u64)>);

/// The least eq. 6 cost over every walk and sign combination (eq. 20), the errors bounded by
/// `within` (distance, frames) when given; `None` when no sub-problem is feasible. Walks are
/// tried by increasing lower bound of their paths' costs (see `lower_bound`): once it reaches
/// the best cost found, no later walk can do better.
fn best_path(
    prepared: &[Prepared],
    all_loops: &[Vec<usize>],
    q: &PathQuery,
    within: Option<(f64, f64)>,
    counts: &mut SolveCounts,
) -> Result<Option<Candidate>> {
    let mut best: Option<Candidate> = None;
    // Loops only add distance, frames and cost, so a walk's paths cost at least its transition
    // cost plus the errors by which the walk alone already overshoots the targets.
    let lower_bound =
        |p: &Prepared| p.base.2 + q.w_d * (p.base.0 - q.distance).max(0.0) + q.w_t * (p.base.1 - q.frames).max(0.0);
    let mut order: Vec<(f64, usize)> = prepared.iter().enumerate().map(|(i, p)| (lower_bound(p), i)).collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    for (bound_cost, i) in order {
        if best.as_ref().is_some_and(|b| bound_cost >= b.0) {
            break;
        }
        let p = &prepared[i];
        let (base, per_loop) = (p.base, &p.per_loop);
        if within.is_some_and(|w| !may_meet(base, per_loop, q, w)) {
            continue;
        }
        // The best cost known: the best path so far, or this walk played without loops (a
        // path, though perhaps not within the tolerance).
        let mut ub = best.as_ref().map_or(f64::INFINITY, |b| b.0);
        if within.is_none() {
            ub = ub.min(base.2 + q.w_d * (base.0 - q.distance).abs() + q.w_t * (base.1 - q.frames).abs());
        }
        let caps = Caps::new(base, per_loop, q, ub, within);
        for (sd, st) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            // Staying under a target the walk alone exceeds is infeasible: skip the solve.
            if (sd < 0.0 && base.0 > q.distance) || (st < 0.0 && base.1 > q.frames) {
                continue;
            }
            let Some(n) = solve_signs(base, per_loop, &p.a, q, sd, st, &caps, within, counts)? else { continue };
            let sum = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
                n.iter().zip(per_loop).map(|(&k, l)| k as f64 * f(l)).sum::<f64>()
            };
            let d = base.0 + sum(&|l| l.0);
            let tt = base.1 + sum(&|l| l.1);
            let cs = base.2 + sum(&|l| l.2);
            let cost = cs + q.w_d * (d - q.distance).abs() + q.w_t * (tt - q.frames).abs();
            if best.as_ref().is_none_or(|b| cost < b.0) {
                let loops =
                    p.a.loops
                        .iter()
                        .zip(&n)
                        .filter(|&(_, &k)| k > 0)
                        .map(|(&c, &k)| (all_loops[c].clone(), k))
                        .collect();
                best = Some((cost, p.walk.clone(), loops));
            }
        }
    }
    Ok(best)
}

/// Whether some non-negative (not necessarily whole) repetitions of the loops bring the walk
/// within `(tol_d, tol_t)` of the targets: the box of what the loops must add, `[D - d0 -
/// tol_d, D - d0 + tol_d] x [T - t0 - tol_t, T - t0 + tol_t]` (distance x frames), meets the
/// cone the loops' `(d, t)` span (speeds from the slowest to the fastest loop). A necessary
/// condition for the ILP with the tolerance, checked first because proving such an ILP
/// infeasible can take the solver long.
fn may_meet(base: (f64, f64, f64), per_loop: &[(f64, f64, f64)], q: &PathQuery, (tol_d, tol_t): (f64, f64)) -> bool {
    let (x0, x1) = (q.distance - base.0 - tol_d, q.distance - base.0 + tol_d);
    let (y0, y1) = (q.frames - base.1 - tol_t, q.frames - base.1 + tol_t);
    if y1 < 0.0 || x1 < 0.0 {
        return false;
    }
    if x0 <= 0.0 && y0 <= 0.0 {
        return true; // the walk alone
    }
    if per_loop.is_empty() {
        return false;
    }
    let (slowest, fastest) = speed_range(per_loop);
    // Frames y the loops add with slowest * y <= x1 and fastest * y >= x0.
    let lo = y0.max(0.0).max(if x0 <= 0.0 {
        0.0
    } else if fastest > 0.0 {
        x0 / fastest
    } else {
        f64::INFINITY
    });
    let hi = y1.min(if slowest > 0.0 { x1 / slowest } else { f64::INFINITY });
    lo <= hi
}

/// The slowest and fastest of the loops' speeds (distance per frame).
fn speed_range(per_loop: &[(f64, f64, f64)]) -> (f64, f64) {
    per_loop.iter().map(|l| l.0 / l.1).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}

/// Why no walk meets the targets within `(tol_d, tol_t)`: checked in order, the length and
/// distance of the shortest walks, then for each walk the speed its loops must make up
/// (`(d_T - d0) / (t_T - t0)`, units per frame) against the range of its loops' speeds (every
/// repetition count mixes them, so any reachable target lies in that cone up to the tolerance).
/// When some walk's cone holds the target, only the integer repetitions stand in the way.
fn unreachable_reason(prepared: &[Prepared], q: &PathQuery, (tol_d, tol_t): (f64, f64)) -> Unreachable {
    let shortest_frames = prepared.iter().map(|p| p.base.1).fold(f64::INFINITY, f64::min);
    if shortest_frames > q.frames + tol_t {
        return Unreachable::TooShort { shortest_frames };
    }
    let shortest_distance = prepared.iter().map(|p| p.base.0).fold(f64::INFINITY, f64::min);
    if shortest_distance > q.distance + tol_d {
        return Unreachable::TooNear { shortest_distance };
    }
    if prepared.iter().all(|p| p.per_loop.is_empty()) {
        return Unreachable::NoLoop;
    }
    // (needed, fastest) over the walks whose target asks more speed than their loops make, and
    // (needed, slowest) over those asking less; a walk in neither is kept from the target only
    // by whole repetitions.
    let mut too_fast: Option<(f64, f64)> = None;
    let mut too_slow: Option<(f64, f64)> = None;
    for p in prepared.iter().filter(|p| !p.per_loop.is_empty()) {
        let (dd, dt) = (q.distance - p.base.0, q.frames - p.base.1);
        let (slowest, fastest) = speed_range(&p.per_loop);
        // With the tolerance, the loops must cover dd +- tol_d in dt +- tol_t frames.
        let (lo, hi) = ((dd - tol_d) / (dt + tol_t).max(1e-9), (dd + tol_d) / (dt - tol_t).max(1e-9));
        if dt + tol_t <= 0.0 {
            continue;
        }
        if lo > fastest {
            too_fast = Some(too_fast.map_or((lo, fastest), |(n, f)| (n.min(lo), f.max(fastest))));
        } else if hi < slowest {
            too_slow = Some(too_slow.map_or((hi, slowest), |(n, s)| (n.max(hi), s.min(slowest))));
        } else {
            return Unreachable::Granularity;
        }
    }
    match (too_fast, too_slow) {
        (Some((needed, fastest)), _) => Unreachable::TooFast { needed, fastest },
        (None, Some((needed, slowest))) => Unreachable::TooSlow { needed, slowest },
        (None, None) => Unreachable::Granularity,
    }
}

/// One played frame: its positions and its own triangles.
pub type PlayedFrame = (Vec<f32>, std::sync::Arc<Vec<[u32; 3]>>);

/// The frames of a solved path as meshes: each frame's positions moved on the ground by its
/// offset (centroids matched at every switch, 4.2.3), with its own triangles.
pub fn play_path(frames: &crate::motion_frames::MotionFrames, p: &PathSolution) -> Vec<PlayedFrame> {
    let (axis, _) = frames.up.axis_and_sign();
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    p.frames
        .iter()
        .zip(&p.offsets)
        .map(|(&f, o)| {
            let mut pos = frames.positions[f].clone();
            for v in pos.chunks_exact_mut(3) {
                v[a] = (f64::from(v[a]) + o[0]) as f32;
                v[b] = (f64::from(v[b]) + o[1]) as f32;
            }
            (pos, frames.triangles[f].clone())
        })
        .collect()
}

/// The path as runs of consecutive frames `sequence:first-last`, for reports.
pub fn path_segments(frames: &crate::motion_frames::MotionFrames, p: &PathSolution) -> Vec<String> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < p.frames.len() {
        let mut j = i;
        while j + 1 < p.frames.len() && p.frames[j + 1] == p.frames[j] + 1 && !p.switches.contains(&(j + 1)) {
            j += 1;
        }
        let (first, last) = (frames.name_of(p.frames[i]), frames.name_of(p.frames[j]));
        let last_frame = last.rsplit_once(':').map(|(_, f)| f.to_string()).unwrap_or(last);
        out.push(format!("{first}-{last_frame}"));
        i = j + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface_motion_graph::{GraphInput, build_graph};

    /// A "walk" sequence of 20 frames moving 0.1 per frame, with a self-transition (loop) from
    /// its frame 15 back to frame 5, and a "stand" sequence of 10 still frames reachable from
    /// the walk's end.
    fn graph() -> (SurfaceMotionGraph, Vec<[f64; 2]>) {
        let f = 30;
        let mut s = vec![1.0; f * f];
        for i in 0..f {
            s[i * f + i] = 0.0;
        }
        // Walk frames 14..=16 look like 4..=6: the loop 15 -> 6.
        for k in 0..3 {
            s[(14 + k) * f + 4 + k] = 0.1;
            s[(4 + k) * f + 14 + k] = 0.1;
        }
        // Walk 17..=19 look like stand 20..=22: 18 -> 22.
        for k in 0..3 {
            s[(17 + k) * f + 20 + k] = 0.2;
            s[(20 + k) * f + 17 + k] = 0.2;
        }
        let ground: Vec<[f64; 2]> = (0..f).map(|i| if i < 20 { [0.1 * i as f64, 0.0] } else { [5.0, 0.0] }).collect();
        let seqs = [0..20, 20..30];
        let g = build_graph(&GraphInput {
            sequences: &seqs,
            similarity: &s,
            ground: &ground,
            connections: &[(0, 0), (0, 1)],
            key_frames: &[0, 29],
            lengths: 3..=3,
            per_connection: 1,
            separation: 0,
        })
        .unwrap();
        (g, ground)
    }

    #[test]
    fn loops_are_repeated_to_meet_the_distance_and_time() {
        let (g, ground) = graph();
        let loop_edges: Vec<_> = g
            .edges
            .iter()
            .filter(|e| matches!(e.kind, EdgeKind::Transition { from_sequence: 0, to_sequence: 0, .. }))
            .collect();
        assert_eq!(loop_edges.len(), 1);
        // The walk alone: 0..=18 (19 frames), switch to stand 22, then 23..=29: 27 frames, 1.8 units.
        let q = PathQuery { w_d: 1.0 / 0.3, w_t: 0.1, ..PathQuery::new(0, 29, 1.8, 27.0) };
        let p = optimise_path(&g, &ground, &q).unwrap();
        assert!(p.loops.is_empty(), "{:?}", p.loops);
        assert_eq!(p.frames.len(), 27);
        assert!((p.distance - 1.8).abs() < 1e-9);
        // Each loop repetition (frames 6..=15: 10 frames, 0.9 units) adds 10 frames and 0.9:
        // three repetitions meet 4.5 units in 57 frames exactly.
        let q = PathQuery::new(0, 29, 4.5, 57.0);
        let p = optimise_path(&g, &ground, &q).unwrap();
        assert_eq!(p.loops.iter().map(|l| l.1).collect::<Vec<_>>(), vec![3]);
        assert_eq!(p.frames.len(), 57);
        assert!(p.distance_error < 1e-9 && p.time_error == 0.0, "{} {}", p.distance_error, p.time_error);
        // The frames play the walk, loop back three times, then stand; offsets keep the ground
        // track continuous across each switch.
        assert_eq!(&p.frames[..17], &(0..=15).chain([6]).collect::<Vec<_>>()[..]);
        for &k in &p.switches {
            let (a, b) = (p.frames[k - 1], p.frames[k]);
            let pa = [ground[a][0] + p.offsets[k - 1][0], ground[a][1] + p.offsets[k - 1][1]];
            let pb = [ground[b][0] + p.offsets[k][0], ground[b][1] + p.offsets[k][1]];
            assert!((pa[0] - pb[0]).abs() < 1e-12 && (pa[1] - pb[1]).abs() < 1e-12);
        }
        assert!(p.ilp_solves >= 4);
    }

    /// Loop B (which travels) touches only loop A (which does not): the solver's first answer
    /// plays B alone, which no path can; the feedback cut makes it play A once to reach B.
    #[test]
    fn a_loop_attached_through_another_needs_its_host() {
        use crate::surface_motion_graph::Edge;
        let seg = |from, to, distance| Edge {
            from,
            to,
            kind: EdgeKind::Segment { sequence: 0 },
            frames: 1,
            distance,
            cost: 0.0,
        };
        let jump = |from, to, distance, cost| Edge {
            from,
            to,
            kind: EdgeKind::Transition { from_sequence: 0, to_sequence: 0, window: 3 },
            frames: 1,
            distance,
            cost,
        };
        let g = SurfaceMotionGraph {
            nodes: vec![0, 1, 2, 3],
            edges: vec![seg(0, 1, 0.0), seg(1, 2, 0.0), jump(2, 1, 0.0, 1.0), seg(2, 3, 1.0), jump(3, 2, 1.0, 0.05)],
            transitions: Vec::new(),
            missing: Vec::new(),
        };
        let ground = vec![[0.0, 0.0]; 4];
        // The walk 0 -> 1 is 2 frames; B twice adds 4 frames and 4 units: 6 frames would be
        // exact, but B needs A (2 frames, cost 1).
        let p = optimise_path(&g, &ground, &PathQuery::new(0, 1, 4.0, 6.0)).unwrap();
        let reps: Vec<(usize, u64)> = p.loops.iter().map(|(c, k)| (c.len(), *k)).collect();
        assert_eq!(p.loops.len(), 2, "{reps:?}");
        assert!(p.loops.iter().all(|(_, k)| *k >= 1), "{reps:?}");
        assert!((p.distance - 4.0).abs() < 1e-9 && p.frames.len() == 8, "{} {}", p.distance, p.frames.len());
        assert!(p.ilp_solves > 4, "a cut was added: {} solves", p.ilp_solves);
    }

    /// With weights that make the loop not worth its transition cost, the paper's optimum misses
    /// the targets; with a tolerance the loop is played and the targets met.
    #[test]
    fn a_tolerance_meets_targets_the_paper_cost_trades_away() {
        let (g, ground) = graph();
        let q = PathQuery { w_d: 0.01, w_t: 0.001, ..PathQuery::new(0, 29, 2.7, 37.0) };
        let paper = optimise_path(&g, &ground, &q).unwrap();
        assert!(paper.loops.is_empty() && paper.frames.len() == 27, "{:?}", paper.loops);
        assert_eq!((paper.within_tolerance, paper.unreachable.clone()), (None, None));
        let q = PathQuery { tolerance: Some(Tolerance::default()), ..q };
        let p = optimise_path(&g, &ground, &q).unwrap();
        assert_eq!(p.within_tolerance, Some(true));
        assert_eq!(p.loops.iter().map(|l| l.1).collect::<Vec<_>>(), vec![1]);
        assert!(p.distance_error <= 0.027 && p.time_error <= 1.0, "{} {}", p.distance_error, p.time_error);
        assert!(p.cost > paper.cost, "the tolerance costs realism: {} vs {}", p.cost, paper.cost);
    }

    /// The caps drawn from the best known cost never change the optimum: on the one-loop graph
    /// every target's cost equals the least over every repetition count, by enumeration.
    #[test]
    fn the_optimum_equals_enumeration_over_repetitions() {
        let (g, ground) = graph();
        let stand_edges: f64 = 8.0; // the switch frame and 23..=29 after the walk's 0..=18
        for d in [0.5, 1.8, 3.0, 4.4, 9.0, 20.0] {
            for t in [10.0, 27.0, 40.0, 61.0, 130.0, 400.0] {
                let q = PathQuery::new(0, 29, d, t);
                let p = optimise_path(&g, &ground, &q).unwrap();
                let loop_cost = p.loops.first().map(|(c, _)| totals(&g, c).2);
                let cost_of = |n: f64, lc: f64| {
                    let (dn, tn) = (1.8 + 0.9 * n, 19.0 + stand_edges + 10.0 * n);
                    let walk_cost = p.transition_cost - p.loops.iter().map(|l| l.1 as f64).sum::<f64>() * lc;
                    walk_cost + n * lc + q.w_d * (dn - d).abs() + q.w_t * (tn - t).abs()
                };
                if let Some(lc) = loop_cost {
                    let best = (0..200).map(|n| cost_of(f64::from(n), lc)).fold(f64::INFINITY, f64::min);
                    assert!((p.cost - best).abs() < 1e-9, "d {d} t {t}: {} vs {best}", p.cost);
                } else {
                    // No loop played: playing one (at its cost, read from the graph) is no better.
                    let lc = g
                        .edges
                        .iter()
                        .find(|e| matches!(e.kind, EdgeKind::Transition { from_sequence: 0, to_sequence: 0, .. }))
                        .unwrap()
                        .cost;
                    let best = (0..200).map(|n| cost_of(f64::from(n), lc)).fold(f64::INFINITY, f64::min);
                    assert!((p.cost - best).abs() < 1e-9, "d {d} t {t}: {} vs {best}", p.cost);
                }
            }
        }
    }

    /// Each reason a target cannot be met: the walk alone is 27 frames and 1.8 units, the loop
    /// adds 10 frames and 0.9 units (0.09 per frame).
    #[test]
    fn unreachable_targets_say_why() {
        let (g, ground) = graph();
        let reason = |d: f64, t: f64| {
            let q = PathQuery { tolerance: Some(Tolerance::default()), ..PathQuery::new(0, 29, d, t) };
            let p = optimise_path(&g, &ground, &q).unwrap();
            assert_eq!(p.within_tolerance, Some(p.unreachable.is_none()));
            p.unreachable
        };
        assert_eq!(reason(1.8, 27.0), None);
        assert_eq!(reason(4.5, 57.0), None);
        assert_eq!(reason(1.0, 10.0), Some(Unreachable::TooShort { shortest_frames: 27.0 }));
        assert!(matches!(reason(1.0, 40.0), Some(Unreachable::TooNear { .. })));
        assert!(
            matches!(reason(10.0, 40.0), Some(Unreachable::TooFast { fastest, .. }) if (fastest - 0.09).abs() < 1e-9)
        );
        assert!(
            matches!(reason(1.8, 100.0), Some(Unreachable::TooSlow { slowest, .. }) if (slowest - 0.09).abs() < 1e-9)
        );
        // One and a half loops: the right speed, but no whole number of repetitions.
        assert_eq!(reason(3.15, 42.0), Some(Unreachable::Granularity));
        // A walk without loops: from the stand's first frame to its last.
        let stand = g.nodes.iter().position(|&f| f == 29).unwrap();
        let first = g.edges.iter().find(|e| e.to == stand).map(|e| g.nodes[e.from]).unwrap();
        let q = PathQuery { tolerance: Some(Tolerance::default()), ..PathQuery::new(first, 29, 3.0, 60.0) };
        assert_eq!(optimise_path(&g, &ground, &q).unwrap().unreachable, Some(Unreachable::NoLoop));
    }

    /// The walk's only loop plays 10 frames: with a minimum length of 11 it is an excluded
    /// loop, never repeated, and a target only it could meet is unreachable for want of a loop.
    #[test]
    fn excluded_loops_never_pad_time() {
        use crate::loop_exclusion::{Exclusion, LoopFilter, LoopRule};
        let (g, ground) = graph();
        let mut s = vec![1.0; 30 * 30];
        for i in 0..30 {
            s[i * 30 + i] = 0.0;
        }
        let seqs = [0..20, 20..30];
        let q = PathQuery { tolerance: Some(Tolerance::default()), ..PathQuery::new(0, 29, 4.5, 57.0) };
        let kept = LoopFilter::new(LoopRule { min_frames: 10, variation_floor: 1.0 }, &s, &seqs).unwrap();
        let plan = plan_paths_excluding(&g, 0, 29, q.max_paths, &kept).unwrap();
        assert!(plan.excluded_loops().is_empty());
        assert_eq!(optimise_planned(&g, &ground, &plan, &q).unwrap().loops.len(), 1);
        let rule = LoopRule { min_frames: 11, variation_floor: 1.0 };
        let filter = LoopFilter::new(rule, &s, &seqs).unwrap();
        let plan = plan_paths_excluding(&g, 0, 29, q.max_paths, &filter).unwrap();
        let excluded = plan.excluded_loops();
        assert_eq!(excluded.len(), 1);
        assert_eq!(excluded[0].why, Exclusion::TooShort { frames: 10, minimum: 11 });
        assert_eq!(excluded[0].frames, (7..=15).chain([6]).collect::<Vec<_>>());
        assert_eq!(plan.loops_in_graph(), 0);
        let p = optimise_planned(&g, &ground, &plan, &q).unwrap();
        assert!(p.loops.is_empty() && p.frames.len() == 27, "{:?}", p.loops);
        assert_eq!(p.unreachable, Some(Unreachable::NoLoop));
    }

    #[test]
    fn unreachable_and_unknown_key_frames_are_refused() {
        let (g, ground) = graph();
        let e = optimise_path(&g, &ground, &PathQuery::new(29, 0, 1.0, 10.0)).unwrap_err().to_string();
        assert!(e.contains("no path from frame 29 to frame 0"), "{e}");
        let e = optimise_path(&g, &ground, &PathQuery::new(3, 29, 1.0, 10.0)).unwrap_err().to_string();
        assert!(e.contains("must be nodes"), "{e}");
    }
}
