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
//!   distances, not only the Lagrangian optimum), and mu is bisected (on a log scale) only while
//!   the distance at the target duration misses d_T by more than 1%. The result is the walk of
//!   least true C among every candidate seen; not a proof of optimality (C is not additive), and
//!   the report gives the true errors of the walk found.
//!
//! Speed: the layered tables are node-major, and edges of at least `block` frames are pulled a
//! block of time layers at a time (see [`layered`]), so the dense 2,000-frame graph (~670k
//! edges) is read ~T / block times per search instead of T times.

use rayon::prelude::*;

use surfcap_mesh::FrameIndex;

use crate::error::{Error, Result};
use crate::graph::Graph;
use crate::walk_sequence::{Step, WalkModel};

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
        TimedGraph { n, edges, out, block, forward, backward, index }
    }
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
    (a, b): (u32, u32),
    (lo, hi): (usize, usize),
    mu: f64,
    score: impl Fn(f64, f64) -> f64 + Sync,
) -> Vec<Option<(f64, Vec<u32>)>> {
    let h = (hi / 2).max(1);
    let longest = g.longest_edge();
    let length: Vec<f64> = g.edges.iter().map(|e| e.length).collect();
    let ec = EdgeCosts { cost: g.edges.iter().map(|e| e.weight + mu * e.length).collect(), length: &length };
    let back_times = (hi + 1).saturating_sub(h);
    let (f, bw) = rayon::join(
        || layered(g, &g.forward, &ec, a, h + longest, h),
        || layered(g, &g.backward, &ec, b, back_times, back_times),
    );
    // The realism of a state's walk is its cost minus mu times its distance.
    let judge = |cost: f64, dist: f64| score(cost - mu * dist, dist);
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
                    let x = f.at(t, v) + bw.at(d - t, v);
                    if x.is_finite() {
                        let y = judge(x, f.dist(t, v) + bw.dist(d - t, v));
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
            let mut nodes = trace(&g.forward, &ec, &f, h, t, v);
            nodes.reverse();
            if d > t {
                let back = trace(&g.backward, &ec, &bw, back_times, d - t, v);
                nodes.extend_from_slice(&back[1..]);
            }
            Some((y, nodes))
        })
        .collect()
}

/// Bisection steps on the Lagrange multiplier of the distance term.
const MU_STEPS: usize = 8;

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
            let found = cheapest_by_duration(self, (a, b), (lo, hi), 0.0, |w, _| w);
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

    /// Huang et al.'s constraint: the walk from `a` to `b` minimising
    /// C_s + |d - distance| / w_d_scale + |t - frames| / w_t_scale (eq. 6, with their weights
    /// 1/0.3 m and 1/10 frames when the scales are 0.3 and 10).
    pub fn walk_with_distance_and_time(
        &self,
        a: u32,
        b: u32,
        distance: f64,
        frames: usize,
        scales: (f64, f64),
        longest_edge: usize,
    ) -> Result<(TimedWalk, f64)> {
        self.check(a, b)?;
        if !(distance.is_finite() && distance >= 0.0) {
            return Err(Error::Parameter { name: "distance", value: distance, expected: "a finite distance >= 0" });
        }
        for (name, value) in [("distance scale", scales.0), ("time scale", scales.1)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::Parameter { name, value, expected: "a finite number > 0" });
            }
        }
        let (wd, wt) = (1.0 / scales.0, 1.0 / scales.1);
        let total =
            |w: &TimedWalk| w.cost + wd * (w.distance - distance).abs() + wt * (w.frames as f64 - frames as f64).abs();
        // Durations near the target first (a time error of w_t^-1 frames costs as much as one
        // unit of realism), widened when no walk has them.
        // Each duration's walk is chosen by its realism plus distance error.
        let score = |r: f64, dist: f64| r + wd * (dist - distance).abs();
        let mut best: Option<(f64, TimedWalk)> = None;
        // Every walk found is a candidate; returns the distance at the duration closest to the
        // target, the quantity the bisection steers.
        let mut consider = |found: Vec<Option<(f64, Vec<u32>)>>| -> Option<f64> {
            let mut closest: Option<(usize, f64)> = None;
            for (d, x) in found.iter().enumerate() {
                let Some((_, walk)) = x else { continue };
                let m = self.measure(walk);
                let c = total(&m);
                if closest.is_none_or(|(d0, _)| d.abs_diff(frames) < d0) {
                    closest = Some((d.abs_diff(frames), m.distance));
                }
                if best.as_ref().is_none_or(|(b0, _)| c < *b0) {
                    best = Some((c, m));
                }
            }
            closest.map(|c| c.1)
        };
        // mu = 0 over durations near the target first (a time error of w_t^-1 frames costs as
        // much as one unit of realism), widened when no walk has them.
        // The widest range is the one of `walk_with_duration`, so both explain it alike.
        let widest = (2 * frames).max(frames + 2 * longest_edge);
        let mut tol = (frames / 20).max(3);
        let (lo, hi, d0) = loop {
            let (lo, hi) = (frames.saturating_sub(tol).max(1), (frames + tol).min(widest));
            if let Some(d0) = consider(cheapest_by_duration(self, (a, b), (lo, hi), 0.0, score)) {
                break (lo, hi, d0);
            }
            if lo == 1 && hi == widest {
                return Err(self.no_walk((a, b), (lo, hi), frames, longest_edge));
            }
            tol *= 3;
        };
        // Then bisect mu so that the distance at the target duration meets the target. The
        // distance falls with mu in steps whose sizes span orders of magnitude, so the bisection
        // runs on log |mu|, between 2^-14 and 2^6 times the graph's realism cost per metre.
        let scale = self.edges.iter().map(|e| e.weight).sum::<f64>()
            / self.edges.iter().map(|e| e.length).sum::<f64>().max(1e-9);
        let sign = if d0 > distance { 1.0 } else { -1.0 };
        let (mut lo_log, mut hi_log) = (-14.0f64, 6.0f64);
        if (d0 - distance).abs() > 0.01 * distance {
            for _ in 0..MU_STEPS {
                let mid = 0.5 * (lo_log + hi_log);
                let mu = sign * scale * mid.exp2();
                match consider(cheapest_by_duration(self, (a, b), (lo, hi), mu, score)) {
                    Some(d) if (d - distance).abs() <= 0.01 * distance => break,
                    // Not far enough yet: a stronger push.
                    Some(d) if (d - distance) * sign > 0.0 => lo_log = mid,
                    Some(_) => hi_log = mid,
                    None => break,
                }
            }
        }
        let (c, w) = best.expect("mu = 0 found a walk");
        Ok((w, c))
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
            let got = cheapest_by_duration(&g, (a, b), (1, hi), 0.0, |w, _| w);
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
                    let got = cheapest_by_duration(&g, (a, b), (1, hi), mu, |r, l| r + mu * l);
                    let scored = cheapest_by_duration(&g, (a, b), (1, hi), mu, |r, l| r + 3.0 * (l - 4.0).abs());
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
                    cheapest_by_duration(&g, (0, 3), (1, 30), 0.3, |r, l| r + (l - 5.0).abs()),
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
}
