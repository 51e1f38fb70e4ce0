//! One rectangular tile of the all-pairs transition table (thesis 2.5.3-2.5.4, eq. 2.55-2.57):
//! the unit of work of the table on one machine and on a cluster (`surfcap tiles`).
//!
//! A tile is the block of source frames `rows` x end frames `cols` (the table is not symmetric:
//! its tiles cover the whole matrix). Entry (i, j) is the best of the shared DTW tables started
//! at (i, j') for every destination start j' = j - l^j + 1, so a tile reads the distances of the
//! frames its windows span, its halo ([`TableSpan::halo`]): rows i .. i + l_max - 1 and columns
//! j - l_max + 1 .. j. A DTW table started at j' is filled only over the columns that end inside
//! the tile: a cell's value depends only on the cells before it, so the cut changes nothing.
//!
//! For a given (i, j) the candidates are scanned in the order of the whole-table scan
//! (destination start ascending, then l^i ascending) and the first minimum kept, so an entry is
//! the same bits whatever the tiling and the thread count.

use std::ops::Range;

use rayon::prelude::*;
use surfcap_mesh::Progress;

use crate::dtw::{DtwReading, DtwTables, FirstStep, dtw_fill_from};
use crate::error::{Error, Result};
use crate::transition_table::TableParams;

/// Frames per side of a table tile on one machine and by default on a cluster: a tile of
/// 1,024 x 1,024 holds 20 MB of results and about 9 MB of distances.
pub const TABLE_TILE: usize = 1024;

/// A block of the transition table: source frames `rows`, end frames `cols`.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TableSpan {
    pub rows: Range<usize>,
    pub cols: Range<usize>,
}

impl TableSpan {
    /// The block of the n x n distance matrix the tile reads: (rows, cols).
    pub fn halo(&self, n: usize, l_max: usize) -> (Range<usize>, Range<usize>) {
        let reach = l_max.saturating_sub(1);
        (self.rows.start..(self.rows.end + reach).min(n), self.cols.start.saturating_sub(reach)..self.cols.end)
    }
}

/// Every tile of an n x n table in blocks of `tile` frames, row-major. `tile` 0 is taken as n.
pub fn plan_table_tiles(n: usize, tile: usize) -> Vec<TableSpan> {
    let tile = if tile == 0 { n.max(1) } else { tile };
    let blocks: Vec<Range<usize>> = (0..n).step_by(tile).map(|s| s..(s + tile).min(n)).collect();
    blocks.iter().flat_map(|r| blocks.iter().map(|c| TableSpan { rows: r.clone(), cols: c.clone() })).collect()
}

/// A block of the distance matrix, row-major: `values[(i - rows.start) * cols.len() + j -
/// cols.start]` is d(i, j).
#[derive(Debug, Clone)]
pub struct DistanceBlock<'a> {
    pub rows: Range<usize>,
    pub cols: Range<usize>,
    pub values: &'a [f64],
}

impl<'a> DistanceBlock<'a> {
    /// A whole n x n matrix.
    pub fn whole(n: usize, values: &'a [f64]) -> Self {
        DistanceBlock { rows: 0..n, cols: 0..n, values }
    }

    /// Checks its size and that every entry is a finite distance >= 0; an error names the entry
    /// by its global frame indices.
    pub fn check(&self) -> Result<()> {
        let expected = self.rows.len() * self.cols.len();
        if self.values.len() != expected {
            return Err(Error::MatrixSize {
                what: "distance block",
                len: self.values.len(),
                expected,
                frames: self.rows.len(),
            });
        }
        match self.values.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            None => Ok(()),
            Some(k) => Err(Error::MatrixEntry {
                what: "distance matrix",
                row: self.rows.start + k / self.cols.len(),
                col: self.cols.start + k % self.cols.len(),
                value: self.values[k],
                expected: "a finite distance >= 0",
            }),
        }
    }

    #[inline]
    fn at(&self, i: usize, j: usize) -> f64 {
        self.values[(i - self.rows.start) * self.cols.len() + j - self.cols.start]
    }
}

/// A computed tile: D, L, l^i, l^j of its pairs, row-major over `span` (infinity / 0 where no
/// windows fit).
#[derive(Debug, Clone, PartialEq)]
pub struct TableTile {
    pub span: TableSpan,
    pub cost: Vec<f64>,
    pub len: Vec<u32>,
    pub li: Vec<u32>,
    pub lj: Vec<u32>,
}

/// Computes one tile from `d`, which must hold the tile's halo; `after[g]` is the number of
/// frames from g to the end of its sequence (`SegmentRoom::after`, over all frames).
pub fn transition_tile(
    d: &DistanceBlock,
    after: &[usize],
    p: &TableParams,
    span: &TableSpan,
    progress: &dyn Progress,
) -> Result<TableTile> {
    transition_tile_from(d, after, p, FirstStep::Straight, span, progress)
}

/// [`transition_tile`] with a reading of the DTW (its first step, eq. 2.53, and its
/// normalisation, eq. 2.55; PAPER-NOTES).
pub fn transition_tile_from(
    d: &DistanceBlock,
    after: &[usize],
    p: &TableParams,
    first: impl Into<DtwReading>,
    span: &TableSpan,
    progress: &dyn Progress,
) -> Result<TableTile> {
    let first: DtwReading = first.into();
    if p.l_min < 1 || p.l_min > p.l_max {
        return Err(Error::Parameter { name: "l-min", value: p.l_min as f64, expected: "1 <= l-min <= l-max" });
    }
    let n = after.len();
    let (hr, hc) = span.halo(n, p.l_max);
    if d.rows.start > hr.start || d.rows.end < hr.end || d.cols.start > hc.start || d.cols.end < hc.end {
        return Err(Error::MatrixSize {
            what: "distance block (the tile's halo)",
            len: d.values.len(),
            expected: hr.len() * hc.len(),
            frames: n,
        });
    }
    let nc = span.cols.len();
    let size = span.rows.len() * nc;
    let mut tile = TableTile {
        span: span.clone(),
        cost: vec![f64::INFINITY; size],
        len: vec![0; size],
        li: vec![0; size],
        lj: vec![0; size],
    };
    progress.start("transition table", span.rows.len() as u64);
    tile.cost
        .par_chunks_mut(nc.max(1))
        .zip(tile.len.par_chunks_mut(nc.max(1)))
        .zip(tile.li.par_chunks_mut(nc.max(1)).zip(tile.lj.par_chunks_mut(nc.max(1))))
        .enumerate()
        .for_each_init(DtwTables::default, |t, (r, ((cost, len), (li, lj)))| {
            let mut row = RowBest { cost, len, li, lj };
            source_row(d, span.rows.start + r, &span.cols, after, (p, first), t, &mut row);
            progress.advance(1);
        });
    progress.finish();
    Ok(tile)
}

/// Best (normalised cost, length, l^i, l^j) per end frame of one tile row.
struct RowBest<'a> {
    cost: &'a mut [f64],
    len: &'a mut [u32],
    li: &'a mut [u32],
    lj: &'a mut [u32],
}

fn source_row(
    d: &DistanceBlock,
    i: usize,
    cols: &Range<usize>,
    after: &[usize],
    (p, first_step): (&TableParams, DtwReading),
    t: &mut DtwTables,
    row: &mut RowBest,
) {
    let rows = after[i].min(p.l_max);
    if rows < p.l_min {
        return;
    }
    let first = cols.start.saturating_sub(p.l_max - 1);
    for (js, &room) in after.iter().enumerate().take(cols.end).skip(first) {
        // Only the columns ending inside the tile: j = js + l < cols.end.
        let width = room.min(p.l_max).min(cols.end - js);
        if width < p.l_min {
            continue;
        }
        dtw_fill_from(rows, width, |k, l| d.at(i + k, js + l), p.slope, first_step, t);
        for l in p.l_min - 1..width {
            let j = js + l;
            if j < cols.start {
                continue;
            }
            let c_j = j - cols.start;
            for k in p.l_min - 1..rows {
                let (c, len) = t.at(k, l);
                if !c.is_finite() {
                    continue;
                }
                let norm = c / len as f64;
                if norm < row.cost[c_j] {
                    row.cost[c_j] = norm;
                    row.len[c_j] = len;
                    row.li[c_j] = k as u32 + 1;
                    row.lj[c_j] = l as u32 + 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transition_table::tests::toy;
    use crate::transition_table::{SegmentRoom, transition_table_in_tiles};
    use surfcap_mesh::{FrameIndex, NoProgress};

    /// Tiles of 1, 5 and 7 frames (windows crossing tile edges and sequence ends) give the
    /// one-tile table to the bit, and a tile computed from only its halo equals the same tile
    /// computed from the whole matrix.
    #[test]
    fn tiles_give_the_one_tile_table_to_the_bit_and_need_only_their_halo() {
        let index = FrameIndex::new([14, 11, 9]);
        let n = index.len();
        let d = toy(n);
        for slope in [Some(2), None] {
            let p = TableParams { l_min: 3, l_max: 6, slope };
            let whole = transition_table_in_tiles(&d, &index, &p, &NoProgress, 0).unwrap();
            for tile in [1, 5, 7] {
                let tiled = transition_table_in_tiles(&d, &index, &p, &NoProgress, tile).unwrap();
                assert!(tiled.cost.iter().zip(&whole.cost).all(|(a, b)| a.to_bits() == b.to_bits()), "{tile}");
                assert_eq!((&tiled.len, &tiled.li, &tiled.lj), (&whole.len, &whole.li, &whole.lj), "{tile}");
            }
            let after = SegmentRoom::new(&index).after;
            for span in plan_table_tiles(n, 8) {
                let (hr, hc) = span.halo(n, p.l_max);
                let values: Vec<f64> =
                    hr.clone().flat_map(|i| hc.clone().map(move |j| (i, j))).map(|(i, j)| d[i * n + j]).collect();
                let halo = DistanceBlock { rows: hr, cols: hc, values: &values };
                let from_halo = transition_tile(&halo, &after, &p, &span, &NoProgress).unwrap();
                let from_whole = transition_tile(&DistanceBlock::whole(n, &d), &after, &p, &span, &NoProgress).unwrap();
                assert_eq!(from_halo, from_whole);
                // A block short of the halo is an error, not a panic.
                if span.rows.end < n {
                    let (hr, hc) = span.halo(n, p.l_max);
                    let short = DistanceBlock { rows: hr.start..hr.end - 1, cols: hc, values: &values };
                    assert!(transition_tile(&short, &after, &p, &span, &NoProgress).is_err());
                }
            }
        }
    }
}
