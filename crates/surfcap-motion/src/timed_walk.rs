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
//!   the walk, so it is handled by Lagrangian relaxation: minimise C_s + mu d exactly for a fixed
//!   duration, bisect mu so that d meets d_T, and keep the walk of least true C among every
//!   candidate seen. Distances on the lower convex hull of the achievable (distance, realism)
//!   pairs are reached exactly; the report gives the true errors of the walk found.

use rayon::prelude::*;

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

/// The graph's playable edges with their durations and ground-plane lengths, forward and
/// backward adjacency.
#[derive(Debug, Clone)]
pub struct TimedGraph {
    n: usize,
    edges: Vec<TimedEdge>,
    out: Vec<Vec<usize>>,
    into: Vec<Vec<usize>>,
}

impl TimedGraph {
    pub fn new(graph: &Graph, model: &WalkModel) -> Self {
        let (iu, iv) = model.plane();
        let plane = |a: [f64; 3], b: [f64; 3]| (a[iu] - b[iu]).hypot(a[iv] - b[iv]);
        let mut edges = Vec::new();
        for e in graph.edges() {
            let Some(step) = model.step(e.from, e.to) else { continue };
            let frames = match step {
                Step::Original => 1,
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
            let weight = if matches!(step, Step::Original) { 0.0 } else { e.weight };
            edges.push(TimedEdge { from: e.from, to: e.to, frames, weight, length });
        }
        let mut out = vec![Vec::new(); graph.n];
        let mut into = vec![Vec::new(); graph.n];
        for (k, e) in edges.iter().enumerate() {
            out[e.from as usize].push(k);
            into[e.to as usize].push(k);
        }
        TimedGraph { n: graph.n, edges, out, into }
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

const NONE: u32 = u32::MAX;

/// Layered tables over (time, node): the cheapest cost and the edge that reached the state.
struct Layers {
    n: usize,
    cost: Vec<f64>,
    edge: Vec<u32>,
}

impl Layers {
    fn new(n: usize, times: usize) -> Self {
        Layers { n, cost: vec![f64::INFINITY; n * times], edge: vec![NONE; n * times] }
    }
    fn at(&self, t: usize, v: usize) -> f64 {
        self.cost.get(t * self.n + v).copied().unwrap_or(f64::INFINITY)
    }
    fn times(&self) -> usize {
        self.cost.len() / self.n
    }
}

/// For every duration in `lo..=hi`, the cheapest walk from `a` to `b` of exactly that duration
/// under edge costs `cost(edge weight, edge length)` (`None` where there is none).
fn cheapest_by_duration(
    g: &TimedGraph,
    a: u32,
    b: u32,
    lo: usize,
    hi: usize,
    cost: impl Fn(f64, f64) -> f64,
) -> Vec<Option<(f64, Vec<u32>)>> {
    let h = hi / 2;
    let c: Vec<f64> = g.edges.iter().map(|e| cost(e.weight, e.length)).collect();
    // Forward: states at times 0..=h.
    let mut f = Layers::new(g.n, h + 1);
    f.cost[a as usize] = 0.0;
    for t in 0..=h {
        for v in 0..g.n {
            let here = f.at(t, v);
            if !here.is_finite() {
                continue;
            }
            for &k in &g.out[v] {
                let e = &g.edges[k];
                let t2 = t + e.frames as usize;
                if t2 <= h {
                    let s = t2 * g.n + e.to as usize;
                    if here + c[k] < f.cost[s] {
                        f.cost[s] = here + c[k];
                        f.edge[s] = k as u32;
                    }
                }
            }
        }
    }
    // Backward: cheapest way from a node to b in exactly t frames, t < hi - h.
    let back_times = hi - h;
    let mut bw = Layers::new(g.n, back_times);
    if back_times > 0 {
        bw.cost[b as usize] = 0.0;
    }
    for t in 0..back_times {
        for v in 0..g.n {
            let here = bw.at(t, v);
            if !here.is_finite() {
                continue;
            }
            for &k in &g.into[v] {
                let e = &g.edges[k];
                let t2 = t + e.frames as usize;
                if t2 < back_times {
                    let s = t2 * g.n + e.from as usize;
                    if here + c[k] < bw.cost[s] {
                        bw.cost[s] = here + c[k];
                        bw.edge[s] = k as u32;
                    }
                }
            }
        }
    }
    // Join: durations up to h end in the forward table; longer walks cross h on one edge.
    // Edges are joined in parallel; ties keep the smallest (edge, t1, t2), whatever the split.
    type Best = Vec<Option<(f64, usize, usize, usize)>>; // cost, t1, edge, t2
    fn better(best: &mut Best, d: usize, cand: (f64, usize, usize, usize)) {
        let key = |x: &(f64, usize, usize, usize)| (x.2, x.1, x.3);
        if best[d].is_none_or(|b0| cand.0 < b0.0 || (cand.0 == b0.0 && key(&cand) < key(&b0))) {
            best[d] = Some(cand);
        }
    }
    let join_edge = |mut best: Best, (k, e): (usize, &TimedEdge)| -> Best {
        let dur = e.frames as usize;
        for t1 in (h + 1).saturating_sub(dur)..=h {
            let x = f.at(t1, e.from as usize);
            if !x.is_finite() {
                continue;
            }
            let t_mid = t1 + dur; // > h
            for t2 in lo.saturating_sub(t_mid)..bw.times() {
                let d = t_mid + t2;
                if d > hi {
                    break;
                }
                let y = bw.at(t2, e.to as usize);
                if y.is_finite() {
                    better(&mut best, d, (x + c[k] + y, t1, k, t2));
                }
            }
        }
        best
    };
    let mut best: Best = g.edges.par_iter().enumerate().fold(|| vec![None; hi + 1], join_edge).reduce(
        || vec![None; hi + 1],
        |mut a, b| {
            for (d, x) in b.into_iter().enumerate() {
                if let Some(x) = x {
                    better(&mut a, d, x);
                }
            }
            a
        },
    );
    for (d, slot) in best.iter_mut().enumerate().take(hi.min(h) + 1).skip(lo.max(1)) {
        let x = f.at(d, b as usize);
        if x.is_finite() && slot.is_none_or(|b0| x <= b0.0) {
            *slot = Some((x, d, usize::MAX, 0));
        }
    }
    best.into_iter()
        .enumerate()
        .map(|(d, b0)| {
            let (cost, t1, k, t2) = b0?;
            // Forward part: back from (t1, node) along the stored edges.
            let mut nodes = Vec::new();
            let (mut t, mut v) = if k == usize::MAX { (d, b as usize) } else { (t1, g.edges[k].from as usize) };
            nodes.push(v as u32);
            while f.edge[t * g.n + v] != NONE {
                let e = &g.edges[f.edge[t * g.n + v] as usize];
                t -= e.frames as usize;
                v = e.from as usize;
                nodes.push(v as u32);
            }
            nodes.reverse();
            if k != usize::MAX {
                let (mut t, mut v) = (t2, g.edges[k].to as usize);
                nodes.push(v as u32);
                while bw.edge[t * g.n + v] != NONE {
                    let e = &g.edges[bw.edge[t * g.n + v] as usize];
                    t -= e.frames as usize;
                    v = e.to as usize;
                    nodes.push(v as u32);
                }
            }
            Some((cost, nodes))
        })
        .collect()
}

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

    fn check(&self, a: u32, b: u32) -> Result<(), String> {
        for x in [a, b] {
            if x as usize >= self.n {
                return Err(format!("frame {x} is not in the graph (0..{})", self.n));
            }
        }
        Ok(())
    }

    /// Thesis 3.5.2: the walk from `a` to `b` whose duration is closest to `frames`, then of
    /// least realism cost. Durations within 2 frames of the request are searched first, then
    /// within 8, 32, ..., up to twice the request plus two transitions.
    pub fn walk_with_duration(&self, a: u32, b: u32, frames: i64, longest_edge: usize) -> Result<TimedWalk, String> {
        self.check(a, b)?;
        let target = frames.max(1) as usize;
        let widest = (2 * target).max(target + 2 * longest_edge);
        let mut tol = 2;
        loop {
            let (lo, hi) = (target.saturating_sub(tol).max(1), (target + tol).min(widest));
            let found = cheapest_by_duration(self, a, b, lo, hi, |w, _| w);
            let best = found
                .iter()
                .enumerate()
                .filter_map(|(d, x)| x.as_ref().map(|(c, w)| ((d as i64 - frames).abs(), *c, w)))
                .min_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
            if let Some((_, _, w)) = best {
                return Ok(self.measure(w));
            }
            if lo == 1 && hi == widest {
                return Err(format!("no walk from frame {a} to frame {b} lasts between 1 and {widest} frames"));
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
    ) -> Result<(TimedWalk, f64), String> {
        self.check(a, b)?;
        let (wd, wt) = (1.0 / scales.0, 1.0 / scales.1);
        let total =
            |w: &TimedWalk| w.cost + wd * (w.distance - distance).abs() + wt * (w.frames as f64 - frames as f64).abs();
        // Durations near the target first (a time error of w_t^-1 frames costs as much as one
        // unit of realism), widened when no walk has them.
        let mut tol = (frames / 20).max(3);
        let (lo, hi) = loop {
            let (lo, hi) = (frames.saturating_sub(tol).max(1), frames + tol);
            if cheapest_by_duration(self, a, b, lo, hi, |w, _| w).iter().any(Option::is_some) {
                break (lo, hi);
            }
            if lo == 1 && tol > frames + longest_edge {
                return Err(format!("no walk from frame {a} to frame {b} lasts between 1 and {hi} frames"));
            }
            tol *= 3;
        };
        let mut best: Option<(f64, TimedWalk)> = None;
        let consider = |mu: f64, best: &mut Option<(f64, TimedWalk)>| -> Option<f64> {
            let found = cheapest_by_duration(self, a, b, lo, hi, |w, l| w + mu * l);
            let mut closest: Option<(usize, f64)> = None; // distance at the duration closest to the target
            for (d, x) in found.iter().enumerate() {
                let Some((_, walk)) = x else { continue };
                let m = self.measure(walk);
                let c = total(&m);
                if best.as_ref().is_none_or(|(b0, _)| c < *b0) {
                    *best = Some((c, m.clone()));
                }
                if closest.is_none_or(|(d0, _)| d.abs_diff(frames) < d0) {
                    closest = Some((d.abs_diff(frames), m.distance));
                }
            }
            closest.map(|c| c.1)
        };
        // mu = 0 first; then bisect mu so the distance at the target duration meets the target.
        let d0 = consider(0.0, &mut best)
            .ok_or_else(|| format!("no walk from frame {a} to frame {b} lasts between {lo} and {hi} frames"))?;
        let scale = self.edges.iter().map(|e| e.weight).sum::<f64>()
            / self.edges.iter().map(|e| e.length).sum::<f64>().max(1e-9);
        let (mut lo_mu, mut hi_mu) = if d0 > distance { (0.0, 64.0 * scale) } else { (-64.0 * scale, 0.0) };
        for _ in 0..10 {
            let mu = 0.5 * (lo_mu + hi_mu);
            match consider(mu, &mut best) {
                Some(d) if d > distance => lo_mu = mu,
                Some(_) => hi_mu = mu,
                None => break,
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
        let mut out = vec![Vec::new(); 4];
        let mut into = vec![Vec::new(); 4];
        for (k, x) in edges.iter().enumerate() {
            out[x.from as usize].push(k);
            into[x.to as usize].push(k);
        }
        TimedGraph { n: 4, edges, out, into }
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
            let got = cheapest_by_duration(&g, a, b, 1, hi, |w, _| w);
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
