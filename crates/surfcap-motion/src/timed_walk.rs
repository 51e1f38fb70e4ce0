//! Walks between two known frames with a given duration (thesis 3.5.2, pose/time constraint),
//! and with a given duration and travelled distance (Huang et al. 2009, eq. 6-9), by
//! bidirectional search.
//!
//! Both ends are known, so the search runs from both (as the thesis does): a forward layered
//! search from the start frame over (node, time) states up to the middle time h, a backward one
//! from the end frame, and a join over the edges that cross h. Each edge lasts a whole number of
//! frames (1 for successive frames, L - 1 for a transition of duration L, see
//! [`crate::walk_sequence`]); every state keeps the cheapest walk reaching it. Unlike a
//! depth-first branch-and-bound over walks, this is exact and polynomial: O(T E) for durations
//! up to T.
//!
//! - Key poses (3.5.2): j_c is the duration error; among the walks whose duration is closest to
//!   the requested one, the one of least realism cost (sum of edge weights, eq. 3.2-3.3) wins.
//!   Successive key pairs are solved in turn, each asking for the requested time minus the time
//!   already obtained, so a timing error is carried into the next pair rather than accumulated.
//! - Distance and time (Huang et al. eq. 6-9): C = C_s + w_d |d - d_T| + w_t |t - t_T| with
//!   w_d = 1/0.3 m and w_t = 1/10 frames as in the paper, C_s our realism cost and d the
//!   ground-plane length of the centre-of-mass path. The distance term is not additive along
//!   the walk, so it is handled by Lagrangian relaxation: every state carries the distance of
//!   its cheapest walk under C_s + mu d, each duration's walk is chosen among all the splits
//!   (t, v) of the bidirectional join by its true C (thousands of candidates with different
//!   distances, not only the Lagrangian optimum). With a tolerance ([`TimedGraph::walk_within`]),
//!   a walk within it that these miss (its distance lies off every trade-off's optimum) is
//!   found by a depth-first search steered by the least and greatest distance on to the end
//!   frame of every state ([`steered`]), which also proves a target no walk meets. The result
//!   is not a proof of eq. 6 optimality (C is not additive), and the report gives the true
//!   errors of the walk found.
//!
//! Speed: the layered tables are node-major, and edges of at least `block` frames are pulled a
//! block of time layers at a time (see [`layered`]), so the dense 2,000-frame graph (~670k
//! edges) is read ~T / block times per search instead of T times.

use rayon::prelude::*;

use surfcap_mesh::FrameIndex;

use crate::error::{Error, Result};
use crate::graph::Graph;
use crate::walk_sequence::{Step, WalkModel};
use steered::{BUDGET as STEERED_BUDGET, Steered, ToEnd, steered_walk};
pub use surfcap_mesh::reachability::{LoopRule, Unreachable};

mod steered;

/// An edge as the timed search sees it.
#[derive(Debug, Clone, Copy)]
struct TimedEdge {
    from: u32,
    to: u32,
    frames: u32,
    weight: f64,
    length: f64,
}

/// Edges grouped by one end (CSR): for node x, the edges `start[x]..start[x + 1]`, each with its
/// other end, its duration and its index in [`TimedGraph::edges`].
#[derive(Debug, Clone, Default)]
struct Adjacency {
    start: Vec<usize>,
    other: Vec<u32>,
    frames: Vec<u32>,
    edge: Vec<u32>,
}

impl Adjacency {
    /// Groups the edges for which `keep` holds by `key(edge)`; `other(edge)` is the far end.
    fn new(
        n: usize,
        edges: &[TimedEdge],
        keep: impl Fn(&TimedEdge) -> bool,
        key: impl Fn(&TimedEdge) -> u32,
        other: impl Fn(&TimedEdge) -> u32,
    ) -> Self {
        let mut start = vec![0usize; n + 1];
        for e in edges.iter().filter(|e| keep(e)) {
            start[key(e) as usize + 1] += 1;
        }
        for x in 0..n {
            start[x + 1] += start[x];
        }
        let m = start[n];
        let (mut o, mut f, mut k) = (vec![0u32; m], vec![0u32; m], vec![0u32; m]);
        let mut fill = start.clone();
        for (i, e) in edges.iter().enumerate().filter(|(_, e)| keep(e)) {
            let slot = &mut fill[key(e) as usize];
            (o[*slot], f[*slot], k[*slot]) = (other(e), e.frames, i as u32);
            *slot += 1;
        }
        Adjacency { start, other: o, frames: f, edge: k }
    }

    fn range(&self, x: usize) -> std::ops::Range<usize> {
        self.start[x]..self.start[x + 1]
    }
}

/// One direction of the layered search: `long` holds the edges of at least `block` frames,
/// pulled in parallel a block of time layers at a time; `short` the others (successive frames),
/// pushed layer by layer.
#[derive(Debug, Clone, Default)]
struct Direction {
    long: Adjacency,
    short: Adjacency,
}

/// The graph's playable edges with their durations and ground-plane lengths, forward and
/// backward adjacency.
#[derive(Debug, Clone)]
pub struct TimedGraph {
    n: usize,
    edges: Vec<TimedEdge>,
    /// Every edge's ground-plane length, in edge order.
    length: Vec<f64>,
    out: Vec<Vec<usize>>,
    /// Width of a block of time layers: the shortest edge of more than one frame (at most 32).
    block: usize,
    /// Forward: edges grouped by their destination (a state pulls from its predecessors).
    forward: Direction,
    /// Backward: edges grouped by their source.
    backward: Direction,
    /// Names the frames of errors as `sequence:frame`.
    index: FrameIndex,
}

impl TimedGraph {
    pub fn new(graph: &Graph, model: &WalkModel) -> Self {
        let (iu, iv) = model.plane();
        let plane = |a: [f64; 3], b: [f64; 3]| (a[iu] - b[iu]).hypot(a[iv] - b[iv]);
        let mut edges = Vec::new();
        for e in graph.edges() {
            let Some(step) = model.step(e.from, e.to) else { continue };
            let frames = match step {
                Step::Original | Step::Wrap(_) => 1,
                Step::Transition(t) => t.duration() as u32,
            };
            let id = surfcap_geometry::motion_plane_alignment::PlaneMotion::identity(model.up);
            let mut last = model.centres[e.from as usize];
            let mut length = 0.0;
            model.advance(step, &id, e.to, |c, _| {
                length += plane(last, c);
                last = c;
            });
            // Realism cost: the transitions' weights (Huang et al.'s C_s sums transition costs
            // only); successive frames cost nothing, so no duration is favoured by it.
            let weight = if matches!(step, Step::Original | Step::Wrap(_)) { 0.0 } else { e.weight };
            edges.push(TimedEdge { from: e.from, to: e.to, frames, weight, length });
        }
        Self::from_edges(graph.n, edges, model.index.clone())
    }

    fn from_edges(n: usize, edges: Vec<TimedEdge>, index: FrameIndex) -> Self {
        let mut out = vec![Vec::new(); n];
        for (k, e) in edges.iter().enumerate() {
            out[e.from as usize].push(k);
        }
        let block = edges.iter().map(|e| e.frames as usize).filter(|&f| f >= 2).min().unwrap_or(1).min(32);
        let direction = |key: fn(&TimedEdge) -> u32, other: fn(&TimedEdge) -> u32| Direction {
            long: Adjacency::new(n, &edges, |e| e.frames as usize >= block, key, other),
            short: Adjacency::new(n, &edges, |e| (e.frames as usize) < block, key, other),
        };
        let forward = direction(|e| e.to, |e| e.from);
        let backward = direction(|e| e.from, |e| e.to);
        let length = edges.iter().map(|e| e.length).collect();
        TimedGraph { n, edges, length, out, block, forward, backward, index }
    }

    /// The graph without its degenerate loops (see [`LoopRule`]): every transition that jumps
    /// back within its own sequence (to `v <= u`), making with the frames from `v` to `u` a
    /// loop of fewer than `rule.min_frames` frames, or one whose poses (`pose(i, j)`: the pose
    /// distance of global frames i and j) vary less than the floor, is removed, so no search
    /// pads time with it; the removed loops are listed. Loops through several transitions are
    /// not examined.
    pub fn without_degenerate_loops(
        &self,
        rule: LoopRule,
        pose: &dyn Fn(usize, usize) -> f64,
    ) -> (Self, Vec<ExcludedLoop>) {
        // Median distance between successive frames, per sequence.
        let typical: Vec<f64> = (0..self.index.n_sequences())
            .map(|q| {
                let r = self.index.range(q);
                let mut steps: Vec<f64> = (r.start..r.end.saturating_sub(1)).map(|i| pose(i, i + 1)).collect();
                steps.sort_by(f64::total_cmp);
                steps.get(steps.len() / 2).copied().unwrap_or(0.0)
            })
            .collect();
        let mut kept = Vec::with_capacity(self.edges.len());
        let mut excluded = Vec::new();
        for e in &self.edges {
            let (u, v) = (e.from as usize, e.to as usize);
            let looped = match (self.index.locate(u), self.index.locate(v)) {
                (Some((qu, _)), Some((qv, _))) => e.frames > 1 && qu == qv && v <= u,
                _ => false,
            };
            if looped {
                let frames = e.frames as usize + (u - v);
                let q = self.index.locate(u).map_or(0, |x| x.0);
                let mut largest = 0.0f64;
                for i in v..=u {
                    for j in i + 1..=u {
                        largest = largest.max(pose(i, j));
                    }
                }
                let variation = if typical[q] > 0.0 { largest / typical[q] } else { f64::INFINITY };
                let reason = if frames < rule.min_frames {
                    Some("too_short")
                } else if variation < rule.variation_floor {
                    Some("too_still")
                } else {
                    None
                };
                if let Some(reason) = reason {
                    excluded.push(ExcludedLoop {
                        from: self.index.label(u),
                        to: self.index.label(v),
                        frames,
                        variation,
                        reason,
                    });
                    continue;
                }
            }
            kept.push(*e);
        }
        (Self::from_edges(self.n, kept, self.index.clone()), excluded)
    }
}

/// A loop the timed searches never play: a transition back into its own sequence, with the
/// frames it replays and why it is excluded.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ExcludedLoop {
    /// The transition's ends, `sequence:frame`.
    pub from: String,
    pub to: String,
    /// Frames of one repetition (the transition plus the frames replayed).
    pub frames: usize,
    /// Largest pose distance among the loop's frames, in typical frame steps.
    pub variation: f64,
    /// `too_short` (fewer frames than the minimum length) or `too_still` (below the
    /// pose-variation floor).
    pub reason: &'static str,
}

/// A walk and what it achieved.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedWalk {
    pub walk: Vec<u32>,
    pub frames: usize,
    /// Sum of the edge weights (realism cost).
    pub cost: f64,
    /// Ground-plane length of the centre-of-mass path.
    pub distance: f64,
}

/// A walk with its eq. 6 cost.
type Scored = (f64, TimedWalk);

/// One distance-and-time target of [`TimedGraph::walk_within_each`].
struct Target {
    distance: f64,
    frames: usize,
    tol_d: f64,
    tol_t: usize,
    scales: (f64, f64),
}

/// The answer of a distance-and-time search with a tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceTimeWalk {
    pub walk: TimedWalk,
    /// Its eq. 6 cost (realism plus weighted distance and timing errors).
    pub total_cost: f64,
    /// Within the tolerance of both targets.
    pub met: bool,
    /// When not met: why no walk can meet the targets, if the graph proves it (`None` with
    /// `met` false: a target within the bounds the search missed).
    pub unreachable: Option<Unreachable>,
}

/// The answer of a duration search with a tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct DurationWalk {
    pub walk: TimedWalk,
    /// Within the tolerance of the asked duration.
    pub met: bool,
    /// When not met: why no walk can be (`too_short`, `no_loop` or `granularity`).
    pub unreachable: Option<Unreachable>,
}

/// Cheapest walk costs over (node, time) states, node-major: `cost[v * times + t]`, and the
/// ground-plane distance of the walk that has that cost.
struct Layers {
    times: usize,
    cost: Vec<f64>,
    dist: Vec<f64>,
}

impl Layers {
    fn at(&self, t: usize, v: usize) -> f64 {
        if t < self.times { self.cost[v * self.times + t] } else { f64::INFINITY }
    }
    fn dist(&self, t: usize, v: usize) -> f64 {
        self.dist[v * self.times + t]
    }
}

/// Edge costs of one search: the Lagrangian cost `weight + mu * length` of every edge.
struct EdgeCosts<'a> {
    cost: Vec<f64>,
    length: &'a [f64],
}

/// Relaxes `row` (costs) and `drow` (distances) with `src + c`, `dsrc + l`.
#[inline]
fn relax(row: &mut [f64], drow: &mut [f64], src: &[f64], dsrc: &[f64], c: f64, l: f64) {
    for (((slot, dslot), &x), &xd) in row.iter_mut().zip(drow.iter_mut()).zip(src).zip(dsrc) {
        let y = x + c;
        if y < *slot {
            *slot = y;
            *dslot = xd + l;
        }
    }
}

/// Bytes of the layer tables of a timed search for a walk of about `frames` frames over a graph
/// of `nodes` nodes: cost and distance (f64) for every (node, time layer) state, forward and
/// backward, the layers together spanning the widest durations searched (twice the request).
/// Callers refuse a request whose tables would not fit in memory before searching.
pub fn search_table_bytes(nodes: usize, frames: usize) -> u64 {
    16 * nodes as u64 * 2 * frames as u64
}

/// [`search_table_bytes`] for a distance-and-time search ([`TimedGraph::walk_within`]): its
/// steered search adds three tables over the durations searched (least and greatest distance
/// and least realism cost on to the end frame), kept beside one bidirectional search's.
pub fn distance_search_table_bytes(nodes: usize, frames: usize) -> u64 {
    16 * nodes as u64 * 5 * frames as u64
}

/// Layered dynamic programme from `origin` at time 0: the cheapest cost of every (node, time)
/// state for times `0..times`, taking edges only from states at times `< from_times`. In the
/// forward direction a state's cost is that of the cheapest walk from the origin reaching it; in
/// the backward direction that of the cheapest walk from it to the origin.
///
/// States are final in time order; edges of at least `block` frames leaving a block of `block`
/// layers all land after it, so once a block's successive-frame steps are done its layers are
/// final and every long edge is read once per block (not once per layer), each node pulling
/// into its own row in parallel: deterministic, whatever the number of threads.
fn layered(g: &TimedGraph, dir: &Direction, ec: &EdgeCosts, origin: u32, times: usize, from_times: usize) -> Layers {
    let (n, b) = (g.n, g.block);
    let mut layers = Layers { times, cost: vec![f64::INFINITY; n * times], dist: vec![0.0; n * times] };
    if times == 0 {
        return layers;
    }
    layers.cost[origin as usize * times] = 0.0;
    let from_times = from_times.min(times);
    // Short edges into layer t (pulled from layers before `from_times`).
    let short = |layers: &mut Layers, t: usize| {
        for v in 0..n {
            for i in dir.short.range(v) {
                let (u, f, k) = (dir.short.other[i] as usize, dir.short.frames[i] as usize, dir.short.edge[i] as usize);
                if t >= f && t - f < from_times {
                    let x = layers.cost[u * times + t - f] + ec.cost[k];
                    if x < layers.cost[v * times + t] {
                        layers.cost[v * times + t] = x;
                        layers.dist[v * times + t] = layers.dist[u * times + t - f] + ec.length[k];
                    }
                }
            }
        }
    };
    let (mut src, mut dsrc) = (vec![f64::INFINITY; n * b], vec![0.0; n * b]);
    for t0 in (0..from_times).step_by(b) {
        let t1 = (t0 + b).min(from_times);
        // Short edges (successive frames), layer by layer: a state is final once every earlier
        // layer has been pushed.
        for t in t0..t1 {
            short(&mut layers, t);
        }
        // The block's layers are final: copy them, then pull every long edge from them.
        let w = t1 - t0;
        for u in 0..n {
            src[u * b..u * b + w].copy_from_slice(&layers.cost[u * times + t0..u * times + t1]);
            dsrc[u * b..u * b + w].copy_from_slice(&layers.dist[u * times + t0..u * times + t1]);
        }
        let rows = layers.cost.par_chunks_mut(times).zip(layers.dist.par_chunks_mut(times));
        rows.enumerate().for_each(|(v, (row, drow))| {
            for i in dir.long.range(v) {
                let (u, f, k) = (dir.long.other[i] as usize, dir.long.frames[i] as usize, dir.long.edge[i] as usize);
                let lo = t0 + f;
                if lo < times {
                    let m = w.min(times - lo);
                    let (s, ds) = (&src[u * b..u * b + m], &dsrc[u * b..u * b + m]);
                    relax(&mut row[lo..lo + m], &mut drow[lo..lo + m], s, ds, ec.cost[k], ec.length[k]);
                }
            }
        });
    }
    // States after the last source layer only receive edges.
    for t in from_times..times {
        short(&mut layers, t);
    }
    layers
}

/// Follows a state back to the origin along edges whose cost explains its own exactly (the
/// first in adjacency order on ties): the nodes from the state to the origin.
fn trace(dir: &Direction, ec: &EdgeCosts, layers: &Layers, from_times: usize, t: usize, v: usize) -> Vec<u32> {
    let (mut t, mut v) = (t, v);
    let mut nodes = vec![v as u32];
    while t > 0 {
        let here = layers.at(t, v);
        let mut prev = None;
        for adj in [&dir.short, &dir.long] {
            for i in adj.range(v) {
                let (u, f) = (adj.other[i] as usize, adj.frames[i] as usize);
                if f <= t && t - f < from_times && layers.at(t - f, u) + ec.cost[adj.edge[i] as usize] == here {
                    prev = Some((t - f, u));
                    break;
                }
            }
            if prev.is_some() {
                break;
            }
        }
        (t, v) = prev.expect("every finite state was reached by an edge whose cost explains it");
        nodes.push(v as u32);
    }
    nodes
}

/// For every duration in `lo..=hi`, a walk from `a` to `b` of exactly that duration and its
/// score (`None` where there is none): the cheapest under edge costs `weight + mu * length`,
/// chosen among its splits by `score(realism, distance)`.
///
/// Bidirectional: forward from `a` pushing only from times before the middle time h, backward
/// from `b`; a walk of duration d >= h is split at its first node at a time t >= h (reached by
/// an edge leaving before h, so t < h + longest edge), and joined there. Every split (t, v) joins
/// the cheapest walk a -> (v, t) to the cheapest (v, t) -> b; with `score` = the Lagrangian cost
/// this is the cheapest walk of duration d, and any other score picks, among these walks (one
/// per split, with different distances), the one it prefers. Durations below h are read from
/// the forward table alone.
fn cheapest_by_duration(
    g: &TimedGraph,
    ends: (u32, u32),
    range: (usize, usize),
    costs: (f64, f64),
    score: impl Fn(f64, f64) -> f64 + Sync,
) -> Vec<Option<(f64, Vec<u32>)>> {
    cheapest_joined(g, ends, range, [costs, costs], score)
}

/// [`cheapest_by_duration`] with the forward half's edge costs `realism * weight + mu * length`
/// from `costs[0]` and the backward half's from `costs[1]`: each split then joins walks
/// cheapest under different trade-offs, whose distances lie between those of either alone.
fn cheapest_joined(
    g: &TimedGraph,
    ends: (u32, u32),
    range: (usize, usize),
    costs: [(f64, f64); 2],
    score: impl Fn(f64, f64) -> f64 + Sync,
) -> Vec<Option<(f64, Vec<u32>)>> {
    JoinTables::new(g, ends, range, costs).pick(score)
}

/// The two halves of one bidirectional search (see [`cheapest_by_duration`]), from which
/// [`JoinTables::pick`] chooses each duration's walk by any score: one search serves every
/// distance target of the same ends and durations.
struct JoinTables<'g> {
    g: &'g TimedGraph,
    ends: (u32, u32),
    range: (usize, usize),
    /// The middle time.
    h: usize,
    back_times: usize,
    mu: (f64, f64),
    ec: EdgeCosts<'g>,
    ecb: EdgeCosts<'g>,
    f: Layers,
    bw: Layers,
}

impl<'g> JoinTables<'g> {
    fn new(g: &'g TimedGraph, (a, b): (u32, u32), (lo, hi): (usize, usize), costs: [(f64, f64); 2]) -> Self {
        let h = (hi / 2).max(1);
        let longest = g.longest_edge();
        let edge_costs = |(realism, mu): (f64, f64)| EdgeCosts {
            cost: g.edges.iter().map(|e| realism * e.weight + mu * e.length).collect(),
            length: &g.length,
        };
        let (ec, ecb) = (edge_costs(costs[0]), edge_costs(costs[1]));
        let back_times = (hi + 1).saturating_sub(h);
        let (f, bw) = rayon::join(
            || layered(g, &g.forward, &ec, a, h + longest, h),
            || layered(g, &g.backward, &ecb, b, back_times, back_times),
        );
        JoinTables { g, ends: (a, b), range: (lo, hi), h, back_times, mu: (costs[0].1, costs[1].1), ec, ecb, f, bw }
    }

    /// Whether some walk lasts a duration of the range.
    fn any(&self) -> bool {
        let (g, (_, b), (lo, hi), h) = (self.g, self.ends, self.range, self.h);
        let longest = g.longest_edge();
        (lo.max(1)..=hi).any(|d| {
            if d < h {
                return self.f.at(d, b as usize).is_finite();
            }
            (h..=d.min(h + longest - 1)).any(|t| (0..g.n).any(|v| (self.f.at(t, v) + self.bw.at(d - t, v)).is_finite()))
        })
    }

    /// Per duration of the range, the walk of the best split by `score(realism, distance)` (the
    /// smallest (t, v) on ties) and its score; `None` where no walk lasts that long.
    fn pick(&self, score: impl Fn(f64, f64) -> f64 + Sync) -> Vec<Option<(f64, Vec<u32>)>> {
        let (g, (_, b), (lo, hi), h) = (self.g, self.ends, self.range, self.h);
        let (f, bw, (mu, mub)) = (&self.f, &self.bw, self.mu);
        let longest = g.longest_edge();
        // The realism of a state's walk is its cost minus mu times its distance.
        let judge = |cost: f64, dist: f64| score(cost - mu * dist, dist);
        let join = |(fc, fd): (f64, f64), (bc, bd): (f64, f64)| score(fc - mu * fd + bc - mub * bd, fd + bd);
        // Per duration: (score, t, v) of the best split, smallest (t, v) on ties.
        let best: Vec<Option<(f64, usize, usize)>> = (0..=hi)
            .into_par_iter()
            .map(|d| {
                if d < lo.max(1) {
                    return None;
                }
                if d < h {
                    let x = f.at(d, b as usize);
                    return x.is_finite().then(|| (judge(x, f.dist(d, b as usize)), d, b as usize));
                }
                let mut best: Option<(f64, usize, usize)> = None;
                for t in h..=d.min(h + longest - 1) {
                    for v in 0..g.n {
                        let (xf, xb) = (f.at(t, v), bw.at(d - t, v));
                        if (xf + xb).is_finite() {
                            let y = join((xf, f.dist(t, v)), (xb, bw.dist(d - t, v)));
                            if best.is_none_or(|b0| y < b0.0) {
                                best = Some((y, t, v));
                            }
                        }
                    }
                }
                best
            })
            .collect();
        best.into_iter()
            .enumerate()
            .map(|(d, b0)| {
                let (y, t, v) = b0?;
                let mut nodes = trace(&g.forward, &self.ec, f, h, t, v);
                nodes.reverse();
                if d > t {
                    let back = trace(&g.backward, &self.ecb, bw, self.back_times, d - t, v);
                    nodes.extend_from_slice(&back[1..]);
                }
                Some((y, nodes))
            })
            .collect()
    }
}

/// Bisection steps on the share of the distance term in the edge cost.
const MU_STEPS: usize = 16;

impl TimedGraph {
    /// Duration, realism cost and distance of a walk of this graph.
    fn measure(&self, walk: &[u32]) -> TimedWalk {
        let (mut frames, mut cost, mut distance) = (0usize, 0.0, 0.0);
        for w in walk.windows(2) {
            let e = self.out[w[0] as usize]
                .iter()
                .map(|&k| &self.edges[k])
                .find(|e| e.to == w[1])
                .expect("walks found by the search use the graph's edges");
            frames += e.frames as usize;
            cost += e.weight;
            distance += e.length;
        }
        TimedWalk { walk: walk.to_vec(), frames, cost, distance }
    }

    /// Both ends are frames of the graph and some walk (of one edge at least) leads from `a`
    /// to `b`; otherwise says why not, in terms of the sequences' ends when that is the cause.
    fn check(&self, a: u32, b: u32) -> Result<()> {
        for x in [a, b] {
            if x as usize >= self.n {
                return Err(Error::FrameNotInGraph { frame: x, frames: self.n });
            }
        }
        let mut seen = vec![false; self.n];
        let mut stack = vec![a as usize];
        while let Some(u) = stack.pop() {
            for &k in &self.out[u] {
                let v = self.edges[k].to as usize;
                if v == b as usize {
                    return Ok(());
                }
                if !seen[v] {
                    seen[v] = true;
                    stack.push(v);
                }
            }
        }
        let (from, to) = (self.index.label(a as usize), self.index.label(b as usize));
        let why = if self.out[a as usize].is_empty() {
            format!(": nothing leaves {from} (the last frame of a sequence, with no transition from it)")
        } else if !self.edges.iter().any(|e| e.to == b) {
            format!(": nothing enters {to} (the first frame of a sequence, with no transition into it)")
        } else {
            format!(": every way on from {from} ends at the last frame of a sequence before reaching {to}")
        };
        Err(Error::Unreachable { from, to, why })
    }

    /// The error for a search that found no walk of any duration in `lo..=hi`.
    fn no_walk(&self, (a, b): (u32, u32), (lo, hi): (usize, usize), asked: usize, longest_edge: usize) -> Error {
        Error::NoWalkWithDuration {
            from: self.index.label(a as usize),
            to: self.index.label(b as usize),
            shortest: lo,
            longest: hi,
            asked,
            longest_edge,
        }
    }

    /// Thesis 3.5.2: the walk from `a` to `b` whose duration is closest to `frames`, then of
    /// least realism cost. Durations within 2 frames of the request are searched first, then
    /// within 8, 32, ..., up to twice the request plus two transitions.
    pub fn walk_with_duration(&self, a: u32, b: u32, frames: i64, longest_edge: usize) -> Result<TimedWalk> {
        self.check(a, b)?;
        let target = frames.max(1) as usize;
        let widest = (2 * target).max(target + 2 * longest_edge);
        let mut tol = 2;
        loop {
            let (lo, hi) = (target.saturating_sub(tol).max(1), (target + tol).min(widest));
            let found = cheapest_by_duration(self, (a, b), (lo, hi), (1.0, 0.0), |w, _| w);
            let best = found
                .iter()
                .enumerate()
                .filter_map(|(d, x)| x.as_ref().map(|(c, w)| ((d as i64 - frames).abs(), *c, w)))
                .min_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
            if let Some((_, _, w)) = best {
                return Ok(self.measure(w));
            }
            if lo == 1 && hi == widest {
                return Err(self.no_walk((a, b), (lo, hi), target, longest_edge));
            }
            tol *= 4;
        }
    }

    /// [`Self::walk_with_duration`] with a tolerance of `tol_t` frames: the walk whose duration
    /// is closest to `frames` (which may be 0 or less when earlier keys came late), met when
    /// within the tolerance; when not, why no walk can be, in the surface motion graph's words
    /// ([`Unreachable`]): too short (every walk takes more frames), no loop (every walk has a
    /// fixed length, so a longer time cannot be padded) or granularity (the cycles' durations do
    /// not combine to it). When every walk is longer than the durations searched, the shortest
    /// walk, too short, rather than an error.
    pub fn walk_with_duration_within(
        &self,
        a: u32,
        b: u32,
        frames: i64,
        tol_t: usize,
        longest_edge: usize,
    ) -> Result<DurationWalk> {
        match self.walk_with_duration(a, b, frames, longest_edge) {
            Ok(walk) => {
                let met = (walk.frames as i64 - frames).unsigned_abs() as usize <= tol_t;
                let unreachable = (!met).then(|| self.duration_reason((a, b), frames, tol_t));
                Ok(DurationWalk { walk, met, unreachable })
            }
            Err(Error::NoWalkWithDuration { .. }) if self.least(a, b, |e| e.frames as f64).is_finite() => {
                let shortest = self.least(a, b, |e| e.frames as f64);
                let walk = self.walk_with_duration(a, b, shortest as i64, longest_edge)?;
                let met = (walk.frames as i64 - frames).unsigned_abs() as usize <= tol_t;
                let unreachable = (!met).then(|| self.duration_reason((a, b), frames, tol_t));
                Ok(DurationWalk { walk, met, unreachable })
            }
            Err(e) => Err(e),
        }
    }

    /// Huang et al.'s constraint: the walk from `a` to `b` minimising
    /// C_s + |d - distance| / w_d_scale + |t - frames| / w_t_scale (eq. 6, with their weights
    /// 1/0.3 m and 1/10 frames when the scales are 0.3 and 10), among the walks within 1% of
    /// the distance and 1 frame of the duration when there is one ([`Self::walk_within`]).
    pub fn walk_with_distance_and_time(
        &self,
        a: u32,
        b: u32,
        distance: f64,
        frames: usize,
        scales: (f64, f64),
        longest_edge: usize,
    ) -> Result<(TimedWalk, f64)> {
        let r = self.walk_within(a, b, (distance, frames), scales, (0.01 * distance, 1), longest_edge)?;
        Ok((r.walk, r.total_cost))
    }

    /// Huang et al.'s constraint with a tolerance (`(distance, frames)`): the walk of least
    /// eq. 6 cost among those within the tolerance of the target distance and duration; when
    /// none is, the eq. 6 optimum found, with the reason no walk can meet the target
    /// ([`Unreachable`]) when the graph proves it.
    ///
    /// The search: realism-cheapest walks of the durations near the target first (Lagrange
    /// multiplier mu = 0); if none meets the target, the walks of least (or greatest) distance
    /// of every duration (realism ignored), which bound what any walk can travel: if even they
    /// miss at every duration within the tolerance, the target is unreachable and the bounds
    /// say why. Otherwise a depth-first search steered by those bounds ([`steered`]) looks for
    /// a walk within the tolerance, duration by duration from the closest: it finds one when
    /// one exists, and when it has ruled out every walk of every duration within the time
    /// tolerance, the target is unreachable (granularity: no combination of the graph's walks
    /// lands within the tolerance). Only when it runs out of budget does the older search run:
    /// the edge cost `(1 - s) weight + s mu_scale length` bisected on `s` (from the realism
    /// optimum at 0 to the distance extreme at 1), each duration's walk chosen among its splits
    /// by realism plus distance error (errors beyond the tolerance counted a thousand times
    /// over), until a walk within the tolerance is found.
    pub fn walk_within(
        &self,
        a: u32,
        b: u32,
        (distance, frames): (f64, usize),
        scales: (f64, f64),
        (tol_d, tol_t): (f64, usize),
        longest_edge: usize,
    ) -> Result<DistanceTimeWalk> {
        let mut answers = self.walk_within_each(a, b, frames, &[(distance, tol_d)], scales, tol_t, longest_edge)?;
        Ok(answers.remove(0))
    }

    /// [`Self::walk_within`] for several targets of the same ends and duration, each a distance
    /// and its tolerance: the searches that do not depend on the distance (the realism optimum
    /// of every duration, the bounds on to the end frame) run once for all of them, and each
    /// answer is the one [`Self::walk_within`] gives for its target alone.
    #[allow(clippy::too_many_arguments)] // walk_within's arguments, with the distances as a list
    pub fn walk_within_each(
        &self,
        a: u32,
        b: u32,
        frames: usize,
        targets: &[(f64, f64)],
        scales: (f64, f64),
        tol_t: usize,
        longest_edge: usize,
    ) -> Result<Vec<DistanceTimeWalk>> {
        self.check(a, b)?;
        for &(distance, _) in targets {
            if !(distance.is_finite() && distance >= 0.0) {
                return Err(Error::Parameter { name: "distance", value: distance, expected: "a finite distance >= 0" });
            }
        }
        for (name, value) in [("distance scale", scales.0), ("time scale", scales.1)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::Parameter { name, value, expected: "a finite number > 0" });
            }
        }
        for &(_, tol_d) in targets {
            if !(tol_d.is_finite() && tol_d >= 0.0) {
                return Err(Error::Parameter {
                    name: "distance tolerance",
                    value: tol_d,
                    expected: "a finite distance >= 0",
                });
            }
        }
        let frames = frames.max(1);
        // mu = 0 over durations near the target first (a time error of w_t^-1 frames costs as
        // much as one unit of realism), widened when no walk has them.
        // The widest range is the one of `walk_with_duration`, so both explain it alike.
        let widest = (2 * frames).max(frames + 2 * longest_edge);
        let mut tol = (frames / 20).max(3).max(tol_t);
        let (lo, hi, zero) = loop {
            let (lo, hi) = (frames.saturating_sub(tol).max(1), (frames + tol).min(widest));
            let tables = JoinTables::new(self, (a, b), (lo, hi), [(1.0, 0.0); 2]);
            if tables.any() {
                break (lo, hi, tables);
            }
            if lo == 1 && hi == widest {
                return Err(self.no_walk((a, b), (lo, hi), frames, longest_edge));
            }
            tol *= 3;
        };
        let to_end = std::sync::OnceLock::new();
        targets
            .par_iter()
            .map(|&(distance, tol_d)| {
                let target = Target { distance, frames, tol_d, tol_t, scales };
                Ok(self.within_target(&target, (lo, hi), &zero, &to_end))
            })
            .collect()
    }

    /// The rest of [`Self::walk_within`] for one target, from the realism optimum's tables
    /// `zero` over the durations `lo..=hi` and the bounds on to the end frame (made on first use).
    fn within_target(
        &self,
        &Target { distance, frames, tol_d, tol_t, scales }: &Target,
        (lo, hi): (usize, usize),
        zero: &JoinTables,
        to_end: &std::sync::OnceLock<ToEnd>,
    ) -> DistanceTimeWalk {
        let (a, b) = zero.ends;
        let frames = frames.max(1);
        let (wd, wt) = (1.0 / scales.0, 1.0 / scales.1);
        let total =
            |w: &TimedWalk| w.cost + wd * (w.distance - distance).abs() + wt * (w.frames as f64 - frames as f64).abs();
        let within = |w: &TimedWalk| (w.distance - distance).abs() <= tol_d && w.frames.abs_diff(frames) <= tol_t;
        let in_window = |d: usize| d.abs_diff(frames) <= tol_t;
        // Each duration's walk is chosen by its realism plus distance error, an error beyond the
        // tolerance weighing a thousand times more, so that a duration's walk is within the
        // tolerance whenever one of its splits is.
        let score = |r: f64, dist: f64| {
            let e = (dist - distance).abs();
            r + wd * e + 1e3 * wd * (e - tol_d).max(0.0)
        };
        // The best walk by eq. 6 among all seen, and among those within the tolerance.
        let (mut best, mut best_met): (Option<Scored>, Option<Scored>) = (None, None);
        // Every walk found is a candidate; returns whether any walk was found, and the distance
        // of the walk closest to the target among the durations within the time tolerance (the
        // quantity the bisection steers).
        let consider = |found: &[Option<(f64, Vec<u32>)>],
                        best: &mut Option<Scored>,
                        best_met: &mut Option<Scored>|
         -> (bool, Option<f64>) {
            let (mut any, mut steer): (bool, Option<f64>) = (false, None);
            for (d, x) in found.iter().enumerate() {
                let Some((_, walk)) = x else { continue };
                any = true;
                let m = self.measure(walk);
                let c = total(&m);
                if in_window(d) && steer.is_none_or(|s| (m.distance - distance).abs() < (s - distance).abs()) {
                    steer = Some(m.distance);
                }
                if within(&m) && best_met.as_ref().is_none_or(|(b0, _)| c < *b0) {
                    *best_met = Some((c, m.clone()));
                }
                if best.as_ref().is_none_or(|(b0, _)| c < *b0) {
                    *best = Some((c, m));
                }
            }
            (any, steer)
        };
        let (_, steer) = consider(&zero.pick(score), &mut best, &mut best_met);
        let done = |best_met: Option<Scored>, best: Option<Scored>, why: Option<Unreachable>| {
            let met = best_met.is_some();
            let (total_cost, walk) = best_met.or(best).expect("mu = 0 found a walk");
            DistanceTimeWalk { walk, total_cost, met, unreachable: if met { None } else { why } }
        };
        // No walk lasts within the time tolerance: the durations say why.
        let Some(d0) = steer else {
            let why = self.duration_reason((a, b), frames as i64, tol_t);
            return done(best_met, best, Some(why));
        };
        if best_met.is_some() {
            return done(best_met, best, None);
        }
        // Per (node, remaining time) state, the least and greatest distance on to the end frame
        // and the least realism cost, over the durations searched.
        let to_end = to_end.get_or_init(|| ToEnd::new(self, b, hi + 1));
        // The distance extreme on the side of the target: the least distance of every duration
        // when the cheapest walk travels too far, the greatest when too little.
        let sign = if d0 > distance { 1.0 } else { -1.0 };
        let extreme: Vec<Option<(f64, Vec<u32>)>> =
            to_end.extreme_walks(self, sign, a as usize, lo..=hi).into_iter().map(|w| w.map(|w| (0.0, w))).collect();
        consider(&extreme, &mut best, &mut best_met);
        if best_met.is_none() {
            let bound: Vec<(usize, f64)> = (lo..=hi)
                .filter(|&d| in_window(d))
                .filter_map(|d| to_end.span(d, a as usize).map(|(near, far)| (d, if sign > 0.0 { near } else { far })))
                .collect();
            let misses = |x: f64| if sign > 0.0 { x > distance + tol_d } else { x < distance - tol_d };
            if !bound.is_empty() && bound.iter().all(|&(_, x)| misses(x)) {
                let why = self.distance_reason((a, b), (distance, frames), tol_d, sign, &bound);
                return done(best_met, best, Some(why));
            }
        }
        // The steered search, duration by duration from the closest to the target: a walk within
        // the tolerance when one exists (and the budget allows); when every duration is
        // exhausted, none does, and no whole number of repetitions lands within the tolerance.
        if best_met.is_none() {
            let mut durations: Vec<usize> = (lo..=hi).filter(|&d| in_window(d)).collect();
            durations.sort_by_key(|&d| (d.abs_diff(frames), d));
            let mut proved = true;
            for d in durations {
                match steered_walk(self, to_end, (a, b), d, (distance - tol_d, distance + tol_d), STEERED_BUDGET) {
                    Steered::Found(walk) => {
                        let m = self.measure(&walk);
                        if within(&m) {
                            let c = total(&m);
                            best_met = Some((c, m.clone()));
                            if best.as_ref().is_none_or(|(b0, _)| c < *b0) {
                                best = Some((c, m));
                            }
                            break;
                        }
                        proved = false;
                    }
                    Steered::GaveUp => proved = false,
                    Steered::Exhausted => {}
                }
            }
            if best_met.is_none() && proved {
                return done(best_met, best, Some(Unreachable::Granularity));
            }
        }
        // Bisect s in [0, 1]: the distance of each duration's Lagrangian walk falls (sign > 0)
        // or rises (sign < 0) with s, from the realism optimum to the extreme that meets it.
        let scale = self.edges.iter().map(|e| e.weight).sum::<f64>()
            / self.edges.iter().map(|e| e.length).sum::<f64>().max(1e-9);
        let (mut s_lo, mut s_hi) = (0.0f64, 1.0f64);
        for _ in 0..MU_STEPS {
            if best_met.is_some() {
                break;
            }
            let s = 0.5 * (s_lo + s_hi);
            let found = cheapest_by_duration(self, (a, b), (lo, hi), (1.0 - s, sign * s * scale), score);
            match consider(&found, &mut best, &mut best_met).1 {
                // Not far enough yet (or not near enough): a stronger push.
                Some(d) if (d - distance) * sign > 0.0 => s_lo = s,
                Some(_) => s_hi = s,
                None => break,
            }
        }
        // The distance may jump across the target between s_lo and s_hi (the Lagrangian walks
        // skip it): join halves cheapest under different trade-offs, whose distances fall
        // between, from the bracket's ends and the extremes.
        let cost_at = |s: f64| (1.0 - s, sign * s * scale);
        for (sf, sb) in [(s_lo, s_hi), (s_hi, s_lo), (0.0, 1.0), (1.0, 0.0), (s_lo, 1.0), (1.0, s_lo)] {
            if best_met.is_some() {
                break;
            }
            let found = cheapest_joined(self, (a, b), (lo, hi), [cost_at(sf), cost_at(sb)], score);
            consider(&found, &mut best, &mut best_met);
        }
        // A target within the bounds that no walk found meets: not proven unreachable (a walk
        // between the bounds may exist), reported as missed.
        done(best_met, best, None)
    }

    /// Why no walk lasts within `tol_t` frames of `frames`: every walk is longer, every walk
    /// has a fixed length, or the cycles' durations do not combine to it.
    fn duration_reason(&self, (a, b): (u32, u32), frames: i64, tol_t: usize) -> Unreachable {
        let shortest = self.least(a, b, |e| e.frames as f64);
        if shortest > (frames + tol_t as i64) as f64 {
            return Unreachable::TooShort { shortest_frames: shortest };
        }
        if !self.has_cycle_between(a, b) {
            return Unreachable::NoLoop;
        }
        Unreachable::Granularity
    }

    /// Why no walk of the durations of `bound` (each with its least distance when `sign` > 0,
    /// its greatest when < 0, all missing the target) meets the distance.
    fn distance_reason(
        &self,
        (a, b): (u32, u32),
        (distance, frames): (f64, usize),
        tol_d: f64,
        sign: f64,
        bound: &[(usize, f64)],
    ) -> Unreachable {
        let needed = distance / frames as f64;
        if sign > 0.0 {
            let shortest_distance = self.least(a, b, |e| e.length);
            if shortest_distance > distance + tol_d {
                return Unreachable::TooNear { shortest_distance };
            }
        }
        if !self.has_cycle_between(a, b) {
            return Unreachable::NoLoop;
        }
        let speeds = bound.iter().map(|&(d, x)| x / d.max(1) as f64);
        if sign > 0.0 {
            Unreachable::TooSlow { needed, slowest: speeds.fold(f64::INFINITY, f64::min) }
        } else {
            Unreachable::TooFast { needed, fastest: speeds.fold(0.0, f64::max) }
        }
    }

    /// The least sum of `cost` (>= 0) over the walks of at least one edge from `a` to `b`
    /// (Dijkstra); infinite when none.
    fn least(&self, a: u32, b: u32, cost: impl Fn(&TimedEdge) -> f64) -> f64 {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        // Non-negative floats order as their bits.
        let mut dist = vec![f64::INFINITY; self.n];
        let mut heap = BinaryHeap::new();
        let mut best = f64::INFINITY;
        for &k in &self.out[a as usize] {
            let e = &self.edges[k];
            let c = cost(e).max(0.0);
            if c < dist[e.to as usize] {
                dist[e.to as usize] = c;
                heap.push(Reverse((c.to_bits(), e.to)));
            }
        }
        while let Some(Reverse((bits, u))) = heap.pop() {
            let du = f64::from_bits(bits);
            if du > dist[u as usize] {
                continue;
            }
            if u == b {
                best = du;
                break;
            }
            for &k in &self.out[u as usize] {
                let e = &self.edges[k];
                let c = du + cost(e).max(0.0);
                if c < dist[e.to as usize] {
                    dist[e.to as usize] = c;
                    heap.push(Reverse((c.to_bits(), e.to)));
                }
            }
        }
        best
    }

    /// Whether some walk from `a` to `b` can repeat a cycle: a cycle among the frames both
    /// reachable from `a` and reaching `b` (Kahn's elimination leaves a node).
    fn has_cycle_between(&self, a: u32, b: u32) -> bool {
        let reach = |start: u32, forward: bool| {
            let mut seen = vec![false; self.n];
            let mut stack = vec![start as usize];
            seen[start as usize] = true;
            while let Some(u) = stack.pop() {
                let next: Vec<usize> = if forward {
                    self.out[u].iter().map(|&k| self.edges[k].to as usize).collect()
                } else {
                    // Forward adjacency groups edges by destination: the predecessors of u.
                    self.forward
                        .long
                        .range(u)
                        .map(|i| self.forward.long.other[i] as usize)
                        .chain(self.forward.short.range(u).map(|i| self.forward.short.other[i] as usize))
                        .collect()
                };
                for v in next {
                    if !seen[v] {
                        seen[v] = true;
                        stack.push(v);
                    }
                }
            }
            seen
        };
        let (from_a, to_b) = (reach(a, true), reach(b, false));
        let useful: Vec<bool> = (0..self.n).map(|v| from_a[v] && to_b[v]).collect();
        let mut indegree = vec![0usize; self.n];
        for e in &self.edges {
            if useful[e.from as usize] && useful[e.to as usize] {
                indegree[e.to as usize] += 1;
            }
        }
        let mut stack: Vec<usize> = (0..self.n).filter(|&v| useful[v] && indegree[v] == 0).collect();
        let mut removed = 0;
        while let Some(u) = stack.pop() {
            removed += 1;
            for &k in &self.out[u] {
                let v = self.edges[k].to as usize;
                if useful[v] {
                    indegree[v] -= 1;
                    if indegree[v] == 0 {
                        stack.push(v);
                    }
                }
            }
        }
        removed < useful.iter().filter(|&&u| u).count()
    }

    /// The longest edge, in frames.
    pub fn longest_edge(&self) -> usize {
        self.edges.iter().map(|e| e.frames as usize).max().unwrap_or(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line_graph() -> TimedGraph {
        // 0 -> 1 -> 2 -> 3 (1 frame each, 1 m each), 3 -> 0 (5 frames, 0 m), 0 -> 3 (2 frames, 4 m).
        let e = |from, to, frames, weight, length| TimedEdge { from, to, frames, weight, length };
        let edges = vec![
            e(0, 1, 1, 1.0, 1.0),
            e(1, 2, 1, 1.0, 1.0),
            e(2, 3, 1, 1.0, 1.0),
            e(3, 0, 5, 2.0, 0.0),
            e(0, 3, 2, 5.0, 4.0),
        ];
        TimedGraph::from_edges(4, edges, FrameIndex::new([4]))
    }

    /// Two sequences of 3 frames (0..3 and 3..6) and one transition 1 -> 4: nothing leaves 2
    /// and 5 (last frames), nothing enters 3 (a first frame). Failures name frames as
    /// `sequence:frame` and say why.
    #[test]
    fn unreachable_ends_and_impossible_durations_are_explained() {
        let e = |from, to, frames| TimedEdge { from, to, frames, weight: 1.0, length: 1.0 };
        let edges = vec![e(0, 1, 1), e(1, 2, 1), e(3, 4, 1), e(4, 5, 1), e(1, 4, 4)];
        let index = FrameIndex::new([3, 3]).with_names(vec!["walk".into(), "run".into()]);
        let g = TimedGraph::from_edges(6, edges, index);
        let msg = |a, b| g.walk_with_duration(a, b, 10, g.longest_edge()).unwrap_err().to_string();
        assert_eq!(
            msg(2, 5),
            "no walk leads from walk:2 to run:2 in the graph, whatever its duration: nothing leaves walk:2 (the last frame of a sequence, with no transition from it)"
        );
        assert_eq!(
            msg(0, 3),
            "no walk leads from walk:0 to run:0 in the graph, whatever its duration: nothing enters run:0 (the first frame of a sequence, with no transition into it)"
        );
        assert_eq!(
            msg(4, 1),
            "no walk leads from run:1 to walk:1 in the graph, whatever its duration: every way on from run:1 ends at the last frame of a sequence before reaching walk:1"
        );
        // 0 -> 5 lasts 6 frames (1 + 4 + 1): asking 1 frame still finds it, as the search goes up
        // to 1 + 2 * 4 frames.
        let far = g.walk_with_duration(0, 5, 1, g.longest_edge()).unwrap();
        assert_eq!((far.walk, far.frames), (vec![0, 1, 4, 5], 6));
        let e = |from, to, frames| TimedEdge { from, to, frames, weight: 1.0, length: 1.0 };
        let long = TimedGraph::from_edges(3, vec![e(0, 1, 30), e(1, 2, 30)], FrameIndex::new([3]));
        let err = long.walk_with_duration(0, 2, 5, 2).unwrap_err();
        assert_eq!(
            err.to_string(),
            "no walk from sequence 0:0 to sequence 0:2 lasts between 1 and 10 frames (the search tries durations up to twice the 5 asked, or 5 plus two of the longest transition's 2 frames, whichever is longer)"
        );
        let err = long.walk_with_distance_and_time(0, 2, 1.0, 5, (0.3, 10.0), 2).unwrap_err();
        assert!(
            err.to_string().starts_with("no walk from sequence 0:0 to sequence 0:2 lasts between 1 and 10 frames"),
            "{err}"
        );
    }

    /// Key-pose times the graph cannot meet say why, in the surface motion graph's words: a
    /// time shorter than the shortest walk is too short (and a walk longer than every duration
    /// searched is still played), a longer one with no loop to pad it has no loop, and one the
    /// loop's repetitions skip is granularity; a reachable time is met with no reason.
    #[test]
    fn duration_targets_that_cannot_be_met_say_why() {
        let e = |from, to, frames| TimedEdge { from, to, frames, weight: 1.0, length: 1.0 };
        // 0 -> 1 -> 2 -> 3, one frame each: every walk 0 -> 3 takes 3 frames.
        let chain = TimedGraph::from_edges(4, vec![e(0, 1, 1), e(1, 2, 1), e(2, 3, 1)], FrameIndex::new([4]));
        let l = chain.longest_edge();
        let r = chain.walk_with_duration_within(0, 3, 1, 0, l).unwrap();
        assert_eq!((r.walk.frames, r.met), (3, false));
        assert_eq!(r.unreachable, Some(Unreachable::TooShort { shortest_frames: 3.0 }));
        assert_eq!(r.unreachable.unwrap().to_string(), "too short: every walk takes at least 3 frames");
        let r = chain.walk_with_duration_within(0, 3, 12, 2, l).unwrap();
        assert_eq!((r.walk.frames, r.met, r.unreachable), (3, false, Some(Unreachable::NoLoop)));
        let r = chain.walk_with_duration_within(0, 3, 2, 1, l).unwrap();
        assert_eq!((r.walk.frames, r.met, r.unreachable), (3, true, None));
        // A time earlier than the previous key (0 or less) is too short as well.
        let r = chain.walk_with_duration_within(0, 3, -4, 1, l).unwrap();
        assert_eq!(r.unreachable, Some(Unreachable::TooShort { shortest_frames: 3.0 }));
        // With a loop 3 -> 1 of 4 frames, walks 0 -> 3 take 3, 9, 15, ... frames.
        let looped =
            TimedGraph::from_edges(4, vec![e(0, 1, 1), e(1, 2, 1), e(2, 3, 1), e(3, 1, 4)], FrameIndex::new([4]));
        let l = looped.longest_edge();
        let r = looped.walk_with_duration_within(0, 3, 6, 1, l).unwrap();
        assert_eq!((r.met, r.unreachable), (false, Some(Unreachable::Granularity)));
        let r = looped.walk_with_duration_within(0, 3, 14, 1, l).unwrap();
        assert_eq!((r.walk.frames, r.met, r.unreachable), (15, true, None));
        // Every walk longer than the durations searched (1..=10): the shortest, too short.
        let long = TimedGraph::from_edges(3, vec![e(0, 1, 30), e(1, 2, 30)], FrameIndex::new([3]));
        let r = long.walk_with_duration_within(0, 2, 5, 2, 2).unwrap();
        assert_eq!((r.walk.walk, r.walk.frames), (vec![0, 1, 2], 60));
        assert_eq!(r.unreachable, Some(Unreachable::TooShort { shortest_frames: 60.0 }));
        // Ends no walk joins are still an error.
        assert!(long.walk_with_duration_within(2, 0, 5, 2, 2).is_err());
    }

    /// Every walk from a to b of duration <= max by brute force: (duration, cost, length).
    fn brute(g: &TimedGraph, a: u32, b: u32, max: usize) -> Vec<(usize, f64, f64)> {
        let mut found = Vec::new();
        #[allow(clippy::too_many_arguments)] // a brute-force enumeration, kept literal
        fn go(
            g: &TimedGraph,
            v: u32,
            b: u32,
            t: usize,
            c: f64,
            l: f64,
            max: usize,
            found: &mut Vec<(usize, f64, f64)>,
        ) {
            if v == b && t > 0 {
                found.push((t, c, l));
            }
            for &k in &g.out[v as usize] {
                let e = &g.edges[k];
                if t + e.frames as usize <= max {
                    go(g, e.to, b, t + e.frames as usize, c + e.weight, l + e.length, max, found);
                }
            }
        }
        go(g, a, b, 0, 0.0, 0.0, max, &mut found);
        found
    }

    #[test]
    fn bidirectional_search_finds_the_cheapest_walk_of_every_duration() {
        let g = line_graph();
        for (a, b) in [(0, 3), (1, 0), (2, 2), (0, 0)] {
            let hi = 24;
            let got = cheapest_by_duration(&g, (a, b), (1, hi), (1.0, 0.0), |w, _| w);
            let all = brute(&g, a, b, hi);
            for (d, got_d) in got.iter().enumerate().skip(1) {
                let want = all.iter().filter(|x| x.0 == d).map(|x| x.1).fold(f64::INFINITY, f64::min);
                match got_d {
                    None => assert!(want.is_infinite(), "{a}->{b} d={d}: missed a walk of cost {want}"),
                    Some((c, walk)) => {
                        assert!((c - want).abs() < 1e-12, "{a}->{b} d={d}: {c} vs {want}");
                        let m = g.measure(walk);
                        assert_eq!((m.frames, walk[0], *walk.last().unwrap()), (d, a, b));
                        assert!((m.cost - c).abs() < 1e-12);
                    }
                }
            }
        }
    }

    /// Random graphs: successive-frame chains plus long edges of 3 to 9 frames (block 3), both
    /// signs of mu; the split chosen by another score is never worse than the cheapest walk.
    #[test]
    fn blocked_layers_match_brute_force_on_random_graphs() {
        let mut state = 0x9e3779b97f4a7c15u64;
        let mut next = move |m: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % m
        };
        for _ in 0..6 {
            let n = 8u32;
            let e = |from, to, frames, weight, length| TimedEdge { from, to, frames, weight, length };
            let mut edges: Vec<TimedEdge> = (0..n - 1).map(|u| e(u, u + 1, 1, 0.0, 0.5)).collect();
            // A walk is a node list: at most one edge per ordered pair, as in the graphs.
            while edges.len() < 19 {
                let (from, to, frames) = (next(8) as u32, next(8) as u32, [3, 4, 6, 9][next(4) as usize]);
                if !edges.iter().any(|x| (x.from, x.to) == (from, to)) {
                    edges.push(e(from, to, frames, next(100) as f64 / 10.0, next(50) as f64 / 10.0));
                }
            }
            let g = TimedGraph::from_edges(n as usize, edges, FrameIndex::new([n as usize]));
            assert_eq!(g.block, 3);
            let hi = 16;
            for mu in [0.0, 0.7, -0.3] {
                for (a, b) in [(0, 7), (3, 3), (5, 1)] {
                    let got = cheapest_by_duration(&g, (a, b), (1, hi), (1.0, mu), |r, l| r + mu * l);
                    let scored = cheapest_by_duration(&g, (a, b), (1, hi), (1.0, mu), |r, l| r + 3.0 * (l - 4.0).abs());
                    let all = brute(&g, a, b, hi);
                    for d in 1..=hi {
                        let lagrangian = |x: &(usize, f64, f64)| x.1 + mu * x.2;
                        let want = all.iter().filter(|x| x.0 == d).map(lagrangian).fold(f64::INFINITY, f64::min);
                        let Some((c, walk)) = &got[d] else {
                            assert!(want.is_infinite(), "{a}->{b} d={d} mu={mu}: missed a walk of cost {want}");
                            continue;
                        };
                        assert!((c - want).abs() < 1e-9, "{a}->{b} d={d} mu={mu}: {c} vs {want}");
                        let m = g.measure(walk);
                        assert_eq!((m.frames, walk[0], *walk.last().unwrap()), (d, a, b));
                        assert!((m.cost + mu * m.distance - c).abs() < 1e-9);
                        let (s, w2) = scored[d].as_ref().expect("the same walks exist");
                        let m2 = g.measure(w2);
                        assert!((m2.cost + 3.0 * (m2.distance - 4.0).abs() - s).abs() < 1e-9);
                        assert!(*s <= m.cost + 3.0 * (m.distance - 4.0).abs() + 1e-9);
                    }
                }
            }
        }
    }

    /// The layered search pulls rows in parallel: one and two threads give the same walks.
    #[test]
    fn one_and_two_threads_give_the_same_walks() {
        let g = line_graph();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                (
                    cheapest_by_duration(&g, (0, 3), (1, 30), (1.0, 0.3), |r, l| r + (l - 5.0).abs()),
                    g.walk_with_distance_and_time(0, 3, 7.0, 10, (0.3, 10.0), 5).unwrap(),
                )
            })
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn durations_and_distances_are_met_when_reachable() {
        let g = line_graph();
        // 0 -> 3 in 3 frames (the line, 3 m) or in 2 (the shortcut, 4 m).
        let w = g.walk_with_duration(0, 3, 3, 5).unwrap();
        assert_eq!((w.walk.clone(), w.frames), (vec![0, 1, 2, 3], 3));
        let w = g.walk_with_duration(0, 3, 2, 5).unwrap();
        assert_eq!(w.walk, vec![0, 3]);
        // A loop lasts 8 frames (3 + 5): 0 -> 3 in 11 frames exists.
        assert_eq!(g.walk_with_duration(0, 3, 11, 5).unwrap().frames, 11);
        // Distance 7 in 10 frames: shortcut (2 frames, 4 m), back (5, 0 m), line (3, 3 m) = 10 frames, 7 m.
        let (w, _) = g.walk_with_distance_and_time(0, 3, 7.0, 10, (0.3, 10.0), 5).unwrap();
        assert_eq!((w.frames, w.distance), (10, 7.0), "{:?}", w.walk);
        // Distance 6 in 11 frames: the line twice.
        let (w, _) = g.walk_with_distance_and_time(0, 3, 6.0, 11, (0.3, 10.0), 5).unwrap();
        assert_eq!((w.frames, w.distance), (11, 6.0), "{:?}", w.walk);
    }

    /// Two walks of 20 frames from 0 to 1: the direct one (8 m, no transition cost) and one
    /// through 2 (10 m, two costly transitions). Eq. 6 alone prefers the direct walk (its
    /// 2 m error costs less than the transitions), so a search that keeps the eq. 6 optimum
    /// misses a distance the graph can meet; with the tolerance the 10 m walk is returned.
    #[test]
    fn a_reachable_distance_is_met_even_when_eq6_prefers_a_cheaper_miss() {
        let e = |from, to, frames, weight, length| TimedEdge { from, to, frames, weight, length };
        let edges = vec![e(0, 1, 20, 0.0, 8.0), e(0, 2, 10, 10.0, 5.0), e(2, 1, 10, 10.0, 5.0)];
        let g = TimedGraph::from_edges(3, edges, FrameIndex::new([3]));
        let r = g.walk_within(0, 1, (10.0, 20), (0.3, 10.0), (0.1, 1), 20).unwrap();
        assert_eq!((r.walk.walk.clone(), r.met, r.unreachable.clone()), (vec![0, 2, 1], true, None));
        let (w, _) = g.walk_with_distance_and_time(0, 1, 10.0, 20, (0.3, 10.0), 20).unwrap();
        assert_eq!((w.frames, w.distance), (20, 10.0));
    }

    /// Three stages in a row, each a choice of three two-edge routes of 10 frames: staying (0 m,
    /// no cost), a short step (1 m, cost 10) or a long one (4 m, cost 10.1). The short step is
    /// never the cheapest under any trade-off of cost and distance (it lies above the line from
    /// staying to the long step), so walks built from Lagrangian halves travel 0, 4, 8 or 12 m
    /// and miss 2 m, which two short steps meet; 7 m no choice of three routes gives.
    fn three_stages() -> TimedGraph {
        let e = |from, to, weight: f64, length: f64| TimedEdge { from, to, frames: 5, weight, length };
        let mut edges = Vec::new();
        for stage in 0..3u32 {
            let (start, end) = (4 * stage, 4 * stage + 4);
            for (k, (weight, length)) in [(0.0, 0.0), (10.0, 1.0), (10.1, 4.0)].into_iter().enumerate() {
                let mid = start + 1 + k as u32;
                edges.push(e(start, mid, weight / 2.0, length / 2.0));
                edges.push(e(mid, end, weight / 2.0, length / 2.0));
            }
        }
        TimedGraph::from_edges(13, edges, FrameIndex::new([13]))
    }

    /// A distance only walks off every trade-off's optimum travel is met (it was missed while
    /// reachable), and one no walk of the duration travels is proved unreachable.
    #[test]
    fn distances_between_the_trade_off_optima_are_met_and_gaps_proved() {
        let g = three_stages();
        let r = g.walk_within(0, 12, (2.0, 30), (0.3, 10.0), (0.02, 0), g.longest_edge()).unwrap();
        assert!(r.met, "{r:?}");
        assert_eq!((r.walk.frames, r.unreachable.clone()), (30, None));
        assert!((r.walk.distance - 2.0).abs() < 1e-9, "{r:?}");
        // Two short steps and a stay, the cheapest such walk first in realism order.
        assert!((r.walk.cost - 20.0).abs() < 1e-9, "{r:?}");
        for d in [1.0, 3.0, 5.0, 6.0, 9.0] {
            let r = g.walk_within(0, 12, (d, 30), (0.3, 10.0), (0.01 * d, 0), g.longest_edge()).unwrap();
            assert!(r.met && (r.walk.distance - d).abs() < 1e-9, "{d} m: {r:?}");
        }
        for d in [7.0, 10.0, 11.0] {
            let r = g.walk_within(0, 12, (d, 30), (0.3, 10.0), (0.01 * d, 0), g.longest_edge()).unwrap();
            assert_eq!((r.met, r.unreachable), (false, Some(Unreachable::Granularity)), "{d} m");
        }
    }

    /// Each reason of an unreachable target, on the line graph (durations 2, 3, 10, 11, ... and
    /// walks of 10 frames travelling 7 m) and on the line without its loop.
    #[test]
    fn unreachable_targets_say_why_in_the_surface_motion_graphs_words() {
        let g = line_graph();
        let why = |g: &TimedGraph, d: f64, t: usize, tol: (f64, usize)| {
            let r = g.walk_within(0, 3, (d, t), (0.3, 10.0), tol, 5).unwrap();
            assert!(!r.met);
            r.unreachable
        };
        assert_eq!(why(&g, 3.0, 1, (0.1, 0)), Some(Unreachable::TooShort { shortest_frames: 2.0 }));
        assert_eq!(why(&g, 1.0, 10, (0.1, 0)), Some(Unreachable::TooNear { shortest_distance: 3.0 }));
        assert_eq!(why(&g, 3.5, 10, (0.1, 0)), Some(Unreachable::TooSlow { needed: 0.35, slowest: 0.7 }));
        assert_eq!(why(&g, 20.0, 10, (0.1, 0)), Some(Unreachable::TooFast { needed: 2.0, fastest: 0.7 }));
        assert_eq!(why(&g, 3.0, 5, (0.1, 0)), Some(Unreachable::Granularity));
        let e = |from, to, frames, weight, length| TimedEdge { from, to, frames, weight, length };
        let edges = vec![e(0, 1, 1, 1.0, 1.0), e(1, 2, 1, 1.0, 1.0), e(2, 3, 1, 1.0, 1.0), e(0, 3, 2, 5.0, 4.0)];
        let acyclic = TimedGraph::from_edges(4, edges, FrameIndex::new([4]));
        assert_eq!(why(&acyclic, 3.0, 5, (0.1, 0)), Some(Unreachable::NoLoop));
        assert_eq!(Unreachable::TooSlow { needed: 0.35, slowest: 0.7 }.kind(), "too_slow");
        // Reachable targets are met, with no reason.
        let r = g.walk_within(0, 3, (7.0, 10), (0.3, 10.0), (0.1, 0), 5).unwrap();
        assert_eq!((r.met, r.unreachable, r.walk.frames), (true, None, 10));
    }

    /// One sequence of 20 frames whose last 5 barely move: a transition 8 -> 5 (a loop of 3 + 3
    /// frames), one 19 -> 15 (13 frames of near-still poses) and one 19 -> 2 (a real cycle).
    /// The first two are excluded with their reasons, the third kept.
    #[test]
    fn degenerate_loops_are_excluded_and_listed() {
        let e = |from, to, frames| TimedEdge { from, to, frames, weight: 1.0, length: 0.0 };
        let mut edges: Vec<TimedEdge> = (0..19).map(|u| e(u, u + 1, 1)).collect();
        edges.extend([e(8, 5, 3), e(19, 15, 9), e(19, 2, 5)]);
        let g = TimedGraph::from_edges(20, edges, FrameIndex::new([20]));
        let f = |i: usize| if i < 15 { i as f64 } else { 15.0 + 0.01 * (i - 15) as f64 };
        let (kept, excluded) = g.without_degenerate_loops(LoopRule::default(), &|i, j| (f(i) - f(j)).abs());
        let got: Vec<(&str, &str, usize, &str)> =
            excluded.iter().map(|x| (x.from.as_str(), x.to.as_str(), x.frames, x.reason)).collect();
        assert_eq!(
            got,
            vec![("sequence 0:8", "sequence 0:5", 6, "too_short"), ("sequence 0:19", "sequence 0:15", 13, "too_still")]
        );
        assert_eq!(kept.edges.len(), 20);
        assert!(kept.edges.iter().any(|x| (x.from, x.to) == (19, 2)));
    }
}
