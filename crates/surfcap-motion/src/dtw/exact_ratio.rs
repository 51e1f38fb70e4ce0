//! DTW that minimises the normalised cost exactly (PAPER-NOTES on eq. 2.55 vs 2.50): the cost
//! of a transition is the summed cost over its warping path divided by the path length L
//! (eq. 2.50), and eq. 2.55 takes the minimum of that ratio. surfcap's DP
//! ([`Normalisation::SumThenDivide`](super::Normalisation), the default) minimises the sum and
//! divides the best path's sum by its L, as the thesis's recursions (eq. 2.52-2.54) do; this one
//! ([`Normalisation::ExactRatio`](super::Normalisation)) finds the path of least ratio.
//!
//! Method: the same recursions with the path length as a second index. Every path to cell (k, l)
//! has a length between max(k, l) + 1 and k + l + 1, so cell (k, l) holds min(k, l) + 1 layers,
//! the least sum for each length; a route of q cells into (k, l) moves a predecessor's layer L to
//! layer L + q. The cell's answer is its layer of least sum / L (the shortest on ties). The
//! slope constraint and the first step are those of the plain DP. Cost: O(rows cols min(rows,
//! cols) p) instead of O(rows cols p).

use super::{DtwTables, FirstStep, Slope, Step};

/// Per-cell layers (one per path length) of the exact-ratio DP, kept to recover the warp.
#[derive(Debug, Clone, Default)]
pub(super) struct Layers {
    /// Index of cell (k, l)'s first layer (path length max(k, l) + 1) in `sum` and `step`.
    base: Vec<usize>,
    /// Least summed cost per (cell, path length); infinity where no path has that length.
    sum: Vec<f64>,
    /// The route into each (cell, path length).
    step: Vec<Step>,
}

/// Shortest path length to cell (k, l).
fn shortest(k: usize, l: usize) -> usize {
    k.max(l) + 1
}

/// Fills `t` for a `rows x cols` grid with the least ratio per cell: `t.at(k, l)` is (sum, L) of
/// the path of least sum / L, and `t.path_to` recovers it.
pub(super) fn fill(
    rows: usize,
    cols: usize,
    d: impl Fn(usize, usize) -> f64,
    slope: Slope,
    first: FirstStep,
    t: &mut DtwTables,
) {
    let n = rows * cols;
    t.rows = rows;
    t.cols = cols;
    t.cost.clear();
    t.cost.resize(n, f64::INFINITY);
    t.len.clear();
    t.len.resize(n, 0);
    t.steps.clear();
    t.steps.resize(n, Step::Start);
    let mut ly = t.layers.take().unwrap_or_default();
    ly.base.clear();
    let mut total = 0;
    for k in 0..rows {
        for l in 0..cols {
            ly.base.push(total);
            total += k.min(l) + 1;
        }
    }
    ly.sum.clear();
    ly.sum.resize(total, f64::INFINITY);
    ly.step.clear();
    ly.step.resize(total, Step::Start);
    if n == 0 {
        t.layers = Some(ly);
        return;
    }
    let idx = |k: usize, l: usize| k * cols + l;
    let run = match (slope, first) {
        (None, _) => usize::MAX,
        (Some(_), FirstStep::Diagonal) => 0,
        (Some(p), FirstStep::Straight) => p.saturating_sub(1),
    };
    // The first row and column hold one layer each (a straight run has one length).
    ly.sum[0] = d(0, 0);
    for k in 1..rows.min(run.saturating_add(1)) {
        ly.sum[ly.base[idx(k, 0)]] = ly.sum[ly.base[idx(k - 1, 0)]] + d(k, 0);
    }
    for l in 1..cols.min(run.saturating_add(1)) {
        ly.sum[ly.base[idx(0, l)]] = ly.sum[ly.base[idx(0, l - 1)]] + d(0, l);
    }
    for k in 1..rows {
        for l in 1..cols {
            let here = d(k, l);
            let (cur, cur_short) = (ly.base[idx(k, l)], shortest(k, l));
            // A route of `q` cells adding `added` from predecessor (pk, pl).
            let mut relax = |pk: usize, pl: usize, added: f64, q: usize, step: Step| {
                let (pb, p_short) = (ly.base[idx(pk, pl)], shortest(pk, pl));
                for a in 0..=pk.min(pl) {
                    let s = ly.sum[pb + a];
                    if !s.is_finite() {
                        continue;
                    }
                    let o = cur + (p_short + a + q - cur_short);
                    let c = s + added;
                    if c < ly.sum[o] {
                        ly.sum[o] = c;
                        ly.step[o] = step;
                    }
                }
            };
            match slope {
                None => {
                    relax(k - 1, l - 1, here, 1, Step::Diagonal1);
                    relax(k - 1, l, here, 1, Step::Down1);
                    relax(k, l - 1, here, 1, Step::Right1);
                }
                Some(p) => {
                    let (mut vsum, mut hsum) = (here, here);
                    for q in 1..=p.max(1) {
                        if q > 1 {
                            if k >= q {
                                vsum += d(k - q + 1, l);
                            }
                            if l >= q {
                                hsum += d(k, l - q + 1);
                            }
                        }
                        if k >= q {
                            relax(k - q, l - 1, vsum, q, Step::Vertical(q as u16));
                        }
                        if q > 1 && l >= q {
                            relax(k - 1, l - q, hsum, q, Step::Horizontal(q as u16));
                        }
                        if k < q && l < q {
                            break;
                        }
                    }
                }
            }
        }
    }
    // Each cell's layer of least ratio.
    for k in 0..rows {
        for l in 0..cols {
            let (b, short) = (ly.base[idx(k, l)], shortest(k, l));
            let mut best = (f64::INFINITY, f64::INFINITY, 0u32);
            for a in 0..=k.min(l) {
                let s = ly.sum[b + a];
                let len = short + a;
                if s.is_finite() && s / (len as f64) < best.0 {
                    best = (s / len as f64, s, len as u32);
                }
            }
            t.cost[idx(k, l)] = best.1;
            t.len[idx(k, l)] = best.2;
        }
    }
    t.layers = Some(ly);
}

impl Layers {
    /// The warping path of length `len` to cell (k, l), as (source, destination) offsets from
    /// (0, 0).
    pub(super) fn path_to(&self, cols: usize, k: usize, l: usize, len: u32) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let (mut k, mut l, mut len) = (k, l, len as usize);
        while let Some((pk, pl, cells)) =
            self.step[self.base[k * cols + l] + len - shortest(k, l)].trace_back(k, l, &mut out)
        {
            (k, l, len) = (pk, pl, len - cells);
        }
        out.reverse();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::{DtwReading, Normalisation, dtw_fill_from};
    use super::*;

    /// The least ratio over every path the slope rule allows, by enumeration: after each
    /// diagonal step, up to p - 1 straight steps in one direction; before the first diagonal,
    /// as many under surfcap's first step and none under the literal one; any 3-neighbour path
    /// when p = infinity.
    fn brute_ratio(rows: usize, cols: usize, d: &dyn Fn(usize, usize) -> f64, p: Slope, first: FirstStep) -> f64 {
        #[allow(clippy::too_many_arguments)]
        fn go(
            rows: usize,
            cols: usize,
            d: &dyn Fn(usize, usize) -> f64,
            p: Slope,
            (k, l): (usize, usize),
            (dir, run): (u8, usize),
            (sum, len): (f64, usize),
            best: &mut f64,
        ) {
            if (k, l) == (rows - 1, cols - 1) {
                *best = best.min(sum / len as f64);
                return;
            }
            let limit = p.map_or(usize::MAX, |p| p - 1);
            // 0: diagonal, 1: down, 2: right.
            for m in 0..3u8 {
                let (nk, nl) = match m {
                    0 => (k + 1, l + 1),
                    1 => (k + 1, l),
                    _ => (k, l + 1),
                };
                if nk >= rows || nl >= cols {
                    continue;
                }
                let state = if m == 0 {
                    (0, 0)
                } else {
                    if p.is_some() && ((dir != 0 && dir != m) || run >= limit) {
                        continue;
                    }
                    (m, run + 1)
                };
                go(rows, cols, d, p, (nk, nl), state, (sum + d(nk, nl), len + 1), best);
            }
        }
        let mut best = f64::INFINITY;
        // The literal first step: no straight step before the first diagonal.
        let start_run = if first == FirstStep::Diagonal && p.is_some() { usize::MAX / 2 } else { 0 };
        go(rows, cols, d, p, (0, 0), (0, start_run), (d(0, 0), 1), &mut best);
        best
    }

    #[test]
    fn matches_enumeration_and_is_never_above_the_sum_then_divide_ratio() {
        let exact = |first| DtwReading { first_step: first, normalisation: Normalisation::ExactRatio };
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            0.05 + (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut lower = 0;
        for (rows, cols) in [(1, 1), (1, 4), (3, 3), (4, 6), (6, 5)] {
            let grid: Vec<f64> = (0..rows * cols).map(|_| rnd()).collect();
            let d = |k: usize, l: usize| grid[k * cols + l];
            for p in [Some(1), Some(2), Some(3), None] {
                for first in [FirstStep::Straight, FirstStep::Diagonal] {
                    let (mut plain, mut t) = (DtwTables::default(), DtwTables::default());
                    dtw_fill_from(rows, cols, d, p, first, &mut plain);
                    dtw_fill_from(rows, cols, d, p, exact(first), &mut t);
                    let (c, len) = t.at(rows - 1, cols - 1);
                    let want = brute_ratio(rows, cols, &d, p, first);
                    let case = format!("{rows}x{cols} p {p:?} {first:?}");
                    if want.is_infinite() {
                        assert!(c.is_infinite(), "{case}");
                        continue;
                    }
                    assert!((c / len as f64 - want).abs() < 1e-12, "{case}: {} vs {want}", c / len as f64);
                    let (pc, plen) = plain.at(rows - 1, cols - 1);
                    assert!(c / len as f64 <= pc / plen as f64 + 1e-15, "{case}");
                    lower += usize::from(c / (len as f64) < pc / plen as f64 - 1e-12);
                    // The recovered warp has length L and sums to the cost.
                    let path = t.path_to(rows - 1, cols - 1);
                    assert_eq!(path.len(), len as usize, "{case}");
                    assert_eq!((path[0], *path.last().unwrap()), ((0, 0), (rows - 1, cols - 1)));
                    let s: f64 = path.iter().map(|&(k, l)| d(k, l)).sum();
                    assert!((s - c).abs() < 1e-12, "{case}: {s} vs {c}");
                }
            }
        }
        assert!(lower > 0, "the exact ratio is never lower than sum-then-divide on these grids");
    }
}
