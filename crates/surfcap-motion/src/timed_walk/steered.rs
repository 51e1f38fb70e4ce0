//! A walk of a given duration between two frames whose travelled distance lies in a window, by
//! a depth-first search steered by bounds.
//!
//! Three layered searches backward from the end frame give, for every (node, remaining time)
//! state, the least and the greatest ground-plane distance of the walks on to the end frame in
//! exactly that time, and the least realism cost of such a walk. From the start frame the search
//! then only takes edges after which the distance travelled so far plus that span can still
//! land in the window, trying them in order of realism (the edge's weight plus the cheapest walk
//! on), so it follows the realism optimum for as long as the distance allows. Where the
//! distances the walks actually reach skip the window (the span is a bound, not a promise), it
//! backtracks.
//!
//! Every walk that meets the window passes every check on its way, so the search finds one
//! whenever one exists and its budget of steps allows; when it runs out of edges to try within
//! the budget, no walk of that duration meets the window: a proof, not a miss.

use super::{EdgeCosts, Layers, TimedGraph, layered};

/// Steps (edges taken) one steered search may make before giving up.
pub(super) const BUDGET: usize = 200_000;

/// Distances are sums in different orders along different routes: a walk whose distance lies
/// within this much of the window is kept for the exact check.
const SLACK: f64 = 1e-9;

/// What a steered search found.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Steered {
    /// A walk (its nodes) of the duration whose distance lies in the window.
    Found(Vec<u32>),
    /// Every walk of the duration was ruled out: none meets the window.
    Exhausted,
    /// The budget ran out first.
    GaveUp,
}

/// Per (node, remaining time) state, for remaining times below `times`: the least and the
/// greatest distance of the walks from that node to the end frame in exactly that time, and the
/// least realism cost of such a walk.
pub(super) struct ToEnd {
    near: Layers,
    far: Layers,
    real: Layers,
}

impl ToEnd {
    pub(super) fn new(g: &TimedGraph, b: u32, times: usize) -> Self {
        let costs = |f: &dyn Fn(&super::TimedEdge) -> f64| EdgeCosts {
            cost: g.edges.iter().map(f).collect(),
            length: &g.length,
        };
        let (near, far, real) = (costs(&|e| e.length), costs(&|e| -e.length), costs(&|e| e.weight));
        let run = |ec: &EdgeCosts| layered(g, &g.backward, ec, b, times, times);
        let ((near, far), real) = rayon::join(|| rayon::join(|| run(&near), || run(&far)), || run(&real));
        ToEnd { near, far, real }
    }

    /// Remaining times covered.
    pub(super) fn times(&self) -> usize {
        self.near.times
    }

    /// Least and greatest distance of the walks from `v` to the end frame in exactly `r` frames;
    /// `None` when there is none.
    pub(super) fn span(&self, r: usize, v: usize) -> Option<(f64, f64)> {
        self.near.at(r, v).is_finite().then(|| (self.near.dist(r, v), self.far.dist(r, v)))
    }

    /// For every remaining time in `range`, the walk from `v` to the end frame of least
    /// (`sign` > 0) or greatest distance (indexed by the time; `None` where there is none).
    pub(super) fn extreme_walks(
        &self,
        g: &TimedGraph,
        sign: f64,
        v: usize,
        range: std::ops::RangeInclusive<usize>,
    ) -> Vec<Option<Vec<u32>>> {
        let ec = EdgeCosts { cost: g.edges.iter().map(|e| sign * e.length).collect(), length: &g.length };
        let layers = if sign > 0.0 { &self.near } else { &self.far };
        let mut walks = vec![None; range.end() + 1];
        for r in range.filter(|&r| r < self.times()) {
            if self.span(r, v).is_some() {
                walks[r] = Some(super::trace(&g.backward, &ec, layers, layers.times, r, v));
            }
        }
        walks
    }
}

/// A walk from `a` to `b` of exactly `duration` frames whose distance lies in `window`
/// (see the module documentation), spending at most `budget` steps.
pub(super) fn steered_walk(
    g: &TimedGraph,
    to_end: &ToEnd,
    (a, b): (u32, u32),
    duration: usize,
    (lo, hi): (f64, f64),
    budget: usize,
) -> Steered {
    let fits = |w: usize, r: usize, dist: f64| match to_end.span(r, w) {
        Some((near, far)) => dist + near <= hi + SLACK && dist + far >= lo - SLACK,
        None => false,
    };
    if duration == 0 || duration >= to_end.times() || !fits(a as usize, duration, 0.0) {
        return Steered::Exhausted;
    }
    // The edges on from v at time t after `dist` that can still meet the window, cheapest first.
    let options = |v: u32, t: usize, dist: f64| -> Vec<u32> {
        let r = duration - t;
        let mut o: Vec<(f64, u32)> = g.out[v as usize]
            .iter()
            .filter_map(|&k| {
                let e = &g.edges[k];
                let f = e.frames as usize;
                (f >= 1 && f <= r && fits(e.to as usize, r - f, dist + e.length))
                    .then(|| (e.weight + to_end.real.at(r - f, e.to as usize), k as u32))
            })
            .collect();
        o.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        o.into_iter().map(|x| x.1).collect()
    };
    struct Level {
        v: u32,
        t: usize,
        dist: f64,
        options: Vec<u32>,
        next: usize,
    }
    let mut steps = 0usize;
    let mut stack = vec![Level { v: a, t: 0, dist: 0.0, options: options(a, 0, 0.0), next: 0 }];
    while let Some(top) = stack.last_mut() {
        let Some(&k) = top.options.get(top.next) else {
            stack.pop();
            continue;
        };
        top.next += 1;
        let e = g.edges[k as usize];
        let (t, dist) = (top.t + e.frames as usize, top.dist + e.length);
        if t == duration {
            // Only the end frame is reachable in no time, and `fits` held: the walk is found.
            debug_assert_eq!(e.to, b);
            let mut walk: Vec<u32> = stack.iter().map(|l| l.v).collect();
            walk.push(e.to);
            return Steered::Found(walk);
        }
        if steps == budget {
            return Steered::GaveUp;
        }
        steps += 1;
        stack.push(Level { v: e.to, t, dist, options: options(e.to, t, dist), next: 0 });
    }
    Steered::Exhausted
}
