//! The all-pairs transition table with variable segment lengths (thesis 2.5.3-2.5.4,
//! eq. 2.55-2.57): for every ordered pair of frames (i, j), the source and destination segment
//! lengths l^i, l^j in [l_min, l_max] and the warp that minimise the normalised DTW cost, that
//! cost D(i, j) and the transition duration L(i, j).
//!
//! Shared dynamic programming: for a source start i and a destination start j', one DTW table
//! over the l_max x l_max grid of frames (i + k, j' + l) holds the best path to every cell; cell
//! (l^i - 1, l^j - 1) is the transition from i to j = j' + l^j - 1 with lengths (l^i, l^j). So one
//! DP per (i, j') serves every length pair and every end frame: O(N^2 l_max^2 p) in all, instead of
//! one DTW per length pair, O(N^2 l_max^4 p) (the naive loop, kept here as a reference for tests
//! and the speed-up benchmark).
//!
//! Windows must lie inside their own sequences (source [i, i + l^i - 1], destination
//! [j - l^j + 1, j]); pairs whose windows cannot fit get D = infinity, L = 0.
//! Ties are broken by the first minimum in a fixed scan order, so the table does not depend on
//! the number of threads.

use surfcap_mesh::{FrameIndex, Progress};

use crate::dtw::{DtwReading, DtwTables, FirstStep, Slope, dtw_fill_from};
use crate::error::{Error, Result};
use crate::transition_tiles::{DistanceBlock, TABLE_TILE, TableTile, plan_table_tiles, transition_tile_from};

/// Parameters of a transition table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableParams {
    pub l_min: usize,
    pub l_max: usize,
    pub slope: Slope,
}

/// D, L, l^i, l^j for all ordered frame pairs (row-major N x N over global frames).
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionTable {
    pub n: usize,
    /// Normalised cost (eq. 2.50/2.55); infinity where no windows fit.
    pub cost: Vec<f64>,
    /// Duration: the warp path length L (eq. 2.56).
    pub len: Vec<u32>,
    pub li: Vec<u32>,
    pub lj: Vec<u32>,
}

impl TransitionTable {
    /// Checks that the table fits the frames of `index` and its own rules, so that code
    /// indexing frames with it cannot go out of bounds: N x N entries, every cost >= 0 or
    /// +infinity (no NaN), and every finite entry with segment lengths in `lengths`, windows
    /// inside their sequences (source [i, i + l^i - 1], destination [j - l^j + 1, j]) and a
    /// warp length between max(l^i, l^j) and l^i + l^j - 1. A table read from a cache is
    /// checked before use.
    pub fn check(&self, index: &FrameIndex, lengths: std::ops::RangeInclusive<usize>) -> Result<()> {
        let n = index.len();
        for (what, len) in [
            ("transition costs", self.cost.len()),
            ("transition durations", self.len.len()),
            ("source lengths", self.li.len()),
            ("destination lengths", self.lj.len()),
        ] {
            if self.n != n || len != n * n {
                return Err(Error::MatrixSize { what, len, expected: n * n, frames: n });
            }
        }
        let room = SegmentRoom::new(index);
        for (k, &c) in self.cost.iter().enumerate() {
            let (i, j) = (k / n, k % n);
            let entry = |what, value: f64, expected| Error::MatrixEntry { what, row: i, col: j, value, expected };
            if c.is_nan() || c < 0.0 {
                return Err(entry("transition costs", c, "a cost >= 0 or inf"));
            }
            if c.is_infinite() {
                continue;
            }
            let (li, lj, len) = (self.li[k] as usize, self.lj[k] as usize, self.len[k] as usize);
            if !lengths.contains(&li) || li > room.after[i] {
                return Err(entry("source lengths", li as f64, "a segment length that fits the source's sequence"));
            }
            if !lengths.contains(&lj) || lj > room.before[j] {
                return Err(entry(
                    "destination lengths",
                    lj as f64,
                    "a segment length that fits the destination's sequence",
                ));
            }
            if len < li.max(lj) || len > li + lj - 1 {
                return Err(entry(
                    "transition durations",
                    len as f64,
                    "a warp length between max(l^i, l^j) and l^i + l^j - 1",
                ));
            }
        }
        Ok(())
    }
}

/// Checks that `d` is an N x N matrix of finite distances >= 0 over the frames of `index`.
pub fn check_distances(d: &[f64], index: &FrameIndex) -> Result<()> {
    let n = index.len();
    if d.len() != n * n {
        return Err(Error::MatrixSize { what: "distance matrix", len: d.len(), expected: n * n, frames: n });
    }
    match d.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
        None => Ok(()),
        Some(k) => Err(Error::MatrixEntry {
            what: "distance matrix",
            row: k / n,
            col: k % n,
            value: d[k],
            expected: "a finite distance >= 0",
        }),
    }
}

/// Frames available around each global frame inside its own sequence: `after[g]` from g to the
/// sequence's end (g included), `before[g]` from the sequence's start to g (g included).
/// Computed once per subject and passed to the per-pair functions.
#[derive(Debug, Clone)]
pub struct SegmentRoom {
    pub after: Vec<usize>,
    pub before: Vec<usize>,
}

impl SegmentRoom {
    pub fn new(index: &FrameIndex) -> Self {
        let n = index.len();
        let mut after = vec![0; n];
        let mut before = vec![0; n];
        for s in 0..index.n_sequences() {
            let r = index.range(s);
            for g in r.clone() {
                after[g] = r.end - g;
                before[g] = g - r.start + 1;
            }
        }
        SegmentRoom { after, before }
    }

    pub fn len(&self) -> usize {
        self.after.len()
    }

    pub fn is_empty(&self) -> bool {
        self.after.is_empty()
    }
}

/// The table with shared dynamic programming over the distance matrix `d` (checked first: a
/// matrix of another size or with NaN is an error, not a panic or a table of NaN), assembled
/// from the tiles of [`plan_table_tiles`] computed by [`transition_tile`], the function a
/// cluster's tile jobs run: bit-identical for every tiling.
pub fn transition_table(
    d: &[f64],
    index: &FrameIndex,
    p: &TableParams,
    progress: &dyn Progress,
) -> Result<TransitionTable> {
    transition_table_in_tiles(d, index, p, progress, TABLE_TILE)
}

/// [`transition_table`] with a reading of the DTW: its first step (eq. 2.53 read literally or
/// surfcap's reading, PAPER-NOTES) and its normalisation (eq. 2.55's least ratio found exactly,
/// or surfcap's sum then divide); [`FirstStep::Straight`] gives [`transition_table`]'s table.
pub fn transition_table_from(
    d: &[f64],
    index: &FrameIndex,
    p: &TableParams,
    first: impl Into<DtwReading>,
    progress: &dyn Progress,
) -> Result<TransitionTable> {
    table_in_tiles(d, index, p, first.into(), progress, TABLE_TILE)
}

/// [`transition_table`] with tiles of `tile` frames (0: one tile).
pub fn transition_table_in_tiles(
    d: &[f64],
    index: &FrameIndex,
    p: &TableParams,
    progress: &dyn Progress,
    tile: usize,
) -> Result<TransitionTable> {
    table_in_tiles(d, index, p, FirstStep::Straight.into(), progress, tile)
}

fn table_in_tiles(
    d: &[f64],
    index: &FrameIndex,
    p: &TableParams,
    first: DtwReading,
    progress: &dyn Progress,
    tile: usize,
) -> Result<TransitionTable> {
    check_distances(d, index)?;
    if p.l_min < 1 || p.l_min > p.l_max {
        return Err(Error::Parameter { name: "l-min", value: p.l_min as f64, expected: "1 <= l-min <= l-max" });
    }
    let n = index.len();
    let after = SegmentRoom::new(index).after;
    let block = DistanceBlock::whole(n, d);
    let mut table = TransitionTable {
        n,
        cost: vec![f64::INFINITY; n * n],
        len: vec![0; n * n],
        li: vec![0; n * n],
        lj: vec![0; n * n],
    };
    for span in plan_table_tiles(n, tile) {
        let t = transition_tile_from(&block, &after, p, first, &span, progress)?;
        table.place_tile(&t);
    }
    Ok(table)
}

impl TransitionTable {
    /// Copies a tile into the table.
    pub fn place_tile(&mut self, t: &TableTile) {
        let (n, nc) = (self.n, t.span.cols.len());
        for (r, i) in t.span.rows.clone().enumerate() {
            let (dst, src) = (i * self.n + t.span.cols.start..i * n + t.span.cols.end, r * nc..(r + 1) * nc);
            self.cost[dst.clone()].copy_from_slice(&t.cost[src.clone()]);
            self.len[dst.clone()].copy_from_slice(&t.len[src.clone()]);
            self.li[dst.clone()].copy_from_slice(&t.li[src.clone()]);
            self.lj[dst].copy_from_slice(&t.lj[src]);
        }
    }
}

/// The naive reference: one DTW per (l^i, l^j) for the pair (i, j); (cost, L, l^i, l^j).
pub fn naive_transition(
    d: &[f64],
    room: &SegmentRoom,
    i: usize,
    j: usize,
    p: &TableParams,
) -> Option<(f64, u32, u32, u32)> {
    let n = room.len();
    let (after, before) = (&room.after, &room.before);
    let mut best: Option<(f64, u32, u32, u32)> = None;
    let mut t = DtwTables::default();
    // Same scan order as the shared version: destination start ascending (l^j descending), then
    // l^i ascending.
    for lj in (p.l_min..=p.l_max.min(before[j])).rev() {
        let js = j + 1 - lj;
        for li in p.l_min..=p.l_max.min(after[i]) {
            dtw_fill_from(li, lj, |k, l| d[(i + k) * n + js + l], p.slope, FirstStep::Straight, &mut t);
            let (c, len) = t.at(li - 1, lj - 1);
            if c.is_finite() && best.is_none_or(|b| c / (len as f64) < b.0) {
                best = Some((c / len as f64, len, li as u32, lj as u32));
            }
        }
    }
    best
}

/// The standard transition (no time warping, l^i = l^j = l fixed): mean of
/// d(i + t, j - l + 1 + t), t = 0..l; `None` when the windows do not fit.
pub fn standard_transition(d: &[f64], room: &SegmentRoom, i: usize, j: usize, l: usize) -> Option<f64> {
    let n = room.len();
    let (after, before) = (&room.after, &room.before);
    if after[i] < l || before[j] < l {
        return None;
    }
    let js = j + 1 - l;
    Some((0..l).map(|t| d[(i + t) * n + js + t]).sum::<f64>() / l as f64)
}

/// DTW with fixed equal lengths l^i = l^j = l: (normalised cost, L).
pub fn fixed_length_dtw(
    d: &[f64],
    room: &SegmentRoom,
    i: usize,
    j: usize,
    l: usize,
    slope: Slope,
) -> Option<(f64, u32)> {
    fixed_length_dtw_from(d, room, (i, j), l, slope, FirstStep::Straight)
}

/// [`fixed_length_dtw`] with the reading of the DTW's first step.
pub fn fixed_length_dtw_from(
    d: &[f64],
    room: &SegmentRoom,
    (i, j): (usize, usize),
    l: usize,
    slope: Slope,
    first: impl Into<DtwReading>,
) -> Option<(f64, u32)> {
    let n = room.len();
    let (after, before) = (&room.after, &room.before);
    if after[i] < l || before[j] < l {
        return None;
    }
    let js = j + 1 - l;
    let mut t = DtwTables::default();
    dtw_fill_from(l, l, |k, m| d[(i + k) * n + js + m], slope, first, &mut t);
    let (c, len) = t.at(l - 1, l - 1);
    c.is_finite().then(|| (c / len as f64, len))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use surfcap_mesh::NoProgress;

    /// A distance matrix for tests (also the tiles' tests).
    pub(crate) fn toy(n: usize) -> Vec<f64> {
        // A distance between frames on two sequences of a 1D "pose" that moves at varying speed.
        let pose = |g: usize| (g as f64 * 0.37).sin() * 3.0 + (g as f64 * 0.11).cos();
        (0..n * n).map(|k| (pose(k / n) - pose(k % n)).abs() + 0.01).collect()
    }

    #[test]
    fn the_first_step_reading_changes_the_table_only_when_asked() {
        let index = FrameIndex::new([14, 11, 9]);
        let d = toy(index.len());
        for slope in [Some(2), Some(3), None] {
            let p = TableParams { l_min: 3, l_max: 8, slope };
            let default = transition_table(&d, &index, &p, &NoProgress).unwrap();
            let ours = transition_table_from(&d, &index, &p, FirstStep::Straight, &NoProgress).unwrap();
            assert_eq!(default, ours);
            let literal = transition_table_from(&d, &index, &p, FirstStep::Diagonal, &NoProgress).unwrap();
            // Without a slope (eq. 2.52) the readings agree; with one, some pairs change.
            assert_eq!(literal == default, slope.is_none(), "slope {slope:?}");
        }
    }

    #[test]
    fn shared_dp_equals_the_naive_loop() {
        let index = FrameIndex::new([14, 11, 9]);
        let n = index.len();
        let d = toy(n);
        for slope in [Some(1), Some(2), Some(3), None] {
            let p = TableParams { l_min: 3, l_max: 6, slope };
            let t = transition_table(&d, &index, &p, &NoProgress).unwrap();
            for i in 0..n {
                for j in 0..n {
                    let naive = naive_transition(&d, &SegmentRoom::new(&index), i, j, &p);
                    let k = i * n + j;
                    match naive {
                        None => assert!(t.cost[k].is_infinite(), "({i},{j}) {slope:?}"),
                        Some((c, len, li, lj)) => {
                            assert!((t.cost[k] - c).abs() < 1e-12, "({i},{j}) {slope:?}: {} vs {c}", t.cost[k]);
                            assert_eq!((t.len[k], t.li[k], t.lj[k]), (len, li, lj), "({i},{j}) {slope:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn inconsistent_matrices_are_errors_not_panics() {
        let index = FrameIndex::new([10, 10]);
        let p = TableParams { l_min: 4, l_max: 7, slope: Some(3) };
        // Another subject's 16 x 16 matrix for 20 frames.
        let e = transition_table(&toy(16), &index, &p, &NoProgress).unwrap_err();
        assert!(matches!(e, Error::MatrixSize { len: 256, expected: 400, .. }), "{e}");
        let mut d = toy(20);
        d[21] = f64::NAN;
        let e = transition_table(&d, &index, &p, &NoProgress).unwrap_err().to_string();
        assert!(e.contains("(1, 1) is NaN"), "{e}");
        let good = transition_table(&toy(20), &index, &p, &NoProgress).unwrap();
        good.check(&index, 4..=7).unwrap();
        assert!(good.check(&FrameIndex::new([16]), 4..=7).is_err(), "another frame count");
        assert!(good.check(&index, 5..=7).is_err(), "other segment lengths");
        let mut bad = good.clone();
        let k = bad.cost.iter().position(|c| c.is_finite()).unwrap();
        bad.li[k] = 11;
        assert!(matches!(bad.check(&index, 4..=11), Err(Error::MatrixEntry { what: "source lengths", .. })));
        bad = good.clone();
        bad.cost[k] = -1.0;
        assert!(bad.check(&index, 4..=7).is_err());
        use crate::edge_weights::{Alpha, edge_weights};
        let alpha = Alpha::new(0.1).unwrap();
        let edges = edge_weights(&bad, &index, alpha).unwrap_err().to_string();
        assert!(edges.contains("is -1, expected a cost >= 0 or inf"), "{edges}");
        assert!(edge_weights(&good, &FrameIndex::new([16]), alpha).is_err());
        // A NaN alpha is refused where it is made: no edge weights can be asked for with one.
        assert!(Alpha::new(f64::NAN).is_err());
    }

    #[test]
    fn windows_stay_inside_sequences_and_lengths_in_bounds() {
        let index = FrameIndex::new([10, 10]);
        let d = toy(20);
        let p = TableParams { l_min: 4, l_max: 7, slope: Some(3) };
        let t = transition_table(&d, &index, &p, &NoProgress).unwrap();
        // Source frame 8 of sequence 0 has only 2 frames left: no transition starts there.
        assert!((0..20).all(|j| t.cost[8 * 20 + j].is_infinite()));
        // Destination frame 12 (third of sequence 1) has only 3 frames before it.
        assert!((0..20).all(|i| t.cost[i * 20 + 12].is_infinite()));
        for k in 0..400 {
            if t.cost[k].is_finite() {
                assert!((4..=7).contains(&t.li[k]) && (4..=7).contains(&t.lj[k]));
                assert!(t.len[k] >= t.li[k].max(t.lj[k]));
            }
        }
        // DTW with variable lengths is never worse than the standard transition of any length.
        for (i, j) in [(0, 15), (2, 19), (5, 9)] {
            for l in 4..=7 {
                if let Some(s) = standard_transition(&d, &SegmentRoom::new(&index), i, j, l) {
                    assert!(t.cost[i * 20 + j] <= s + 1e-12);
                }
            }
        }
    }
}
