//! One rectangular tile of the all-pairs pose distance matrix (thesis 2.3.2, eq. 2.2-2.5 and
//! 2.13-2.14): the unit of work of the distance matrix on one machine and on a cluster (`surfcap tiles`).
//!
//! A tile is the block rows x cols of the matrix with `rows` before or equal to `cols` (the
//! upper triangle: the matrix is symmetric, see `distance_matrix.rs`). A diagonal tile computes
//! its pairs i < j and mirrors them; an off-diagonal tile computes every pair. Each entry is
//! computed from frames i and j alone, in a fixed order:
//! - the motion-plane alignment of eq. 2.3 from the pair's own weighted inner products of
//!   centred horizontal coordinates ([`pair_alignment`], eight fixed partial sums, so it
//!   vectorises yet does not depend on which other frames share the tile);
//! - the deformation sum over the triangles chunk by chunk in mesh order, whatever the slab of
//!   triangles held at once.
//!
//! So an entry is the same bits whatever the tiling, the slab budget or the thread count, and
//! the one-process matrix (one tile, or the default tiling) equals the merged tiles of a cluster
//! run on the same kernel.
//!
//! Memory of a tile: the positions of its frames (f32), their weighted centred coordinates
//! (24 bytes per vertex and frame), the triangle data of one slab for its frames and its output;
//! bounded by the tile, not by the subject ([`tile_memory_bytes`]).

use std::ops::Range;

use nalgebra::Matrix3;
use rayon::prelude::*;
use surfcap_mesh::{Progress, Subject, UpAxis};

use crate::distance_matrix::{DistanceParams, slab_triangles};
use crate::literal_deformation_distance::literal_deformation_distance;
use crate::motion_plane_alignment::{plane_axes, rotation_about_up};
use crate::pose_distance::{
    BLOCK, FRAME_FLOATS, PoseMetric, deformation_distance, degenerate_triangles, triangle_frames, union_count,
};

/// The frames a tile reads, by global frame index (a whole subject in memory, or only a tile's
/// frames read from disk).
pub trait PoseFrames: Sync {
    /// Positions (x, y, z per vertex) of global frame `g`; only the tile's frames are asked for.
    fn pose(&self, g: usize) -> &[f32];
}

impl PoseFrames for Subject {
    fn pose(&self, g: usize) -> &[f32] {
        self.frame(g).expect("a tile's frames are frames of its subject")
    }
}

/// A block of the distance matrix: `rows` x `cols` of global frames, with `rows.start <=
/// cols.start` (diagonal tiles have `rows == cols`).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TileSpan {
    pub rows: Range<usize>,
    pub cols: Range<usize>,
}

impl TileSpan {
    pub fn is_diagonal(&self) -> bool {
        self.rows == self.cols
    }

    /// Frames the tile reads, ascending, without repeats.
    pub fn frames(&self) -> Vec<usize> {
        let mut f: Vec<usize> = self.rows.clone().chain(self.cols.clone()).collect();
        f.sort_unstable();
        f.dedup();
        f
    }

    /// Pairs (i, j), i < j, the tile computes.
    pub fn pairs(&self) -> usize {
        let (r, c) = (self.rows.len(), self.cols.len());
        if self.is_diagonal() { r * r.saturating_sub(1) / 2 } else { r * c }
    }
}

/// The upper-triangle tiles of an n x n matrix in blocks of `tile` frames, row-major
/// ((0, 0), (0, 1), ..., (1, 1), ...). `tile` 0 is taken as n (one tile).
pub fn plan_distance_tiles(n: usize, tile: usize) -> Vec<TileSpan> {
    let tile = if tile == 0 { n.max(1) } else { tile };
    let blocks: Vec<Range<usize>> = (0..n).step_by(tile).map(|s| s..(s + tile).min(n)).collect();
    let mut out = Vec::new();
    for (a, rows) in blocks.iter().enumerate() {
        for cols in &blocks[a..] {
            out.push(TileSpan { rows: rows.clone(), cols: cols.clone() });
        }
    }
    out
}

/// A computed tile: `values[r * cols + c]` is d(rows.start + r, cols.start + c).
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceTile {
    pub span: TileSpan,
    pub values: Vec<f64>,
    /// Largest number of zero-area triangles skipped in one of the tile's pairs.
    pub max_skipped_triangles: usize,
}

/// Bytes a tile job holds at most, besides the program (for planning and reports): the f32
/// positions and f64 centred coordinates of its frames, one slab of triangle data and its output.
pub fn tile_memory_bytes(span: &TileSpan, n_vertices: usize, n_triangles: usize, slab_bytes: usize) -> usize {
    let frames = span.frames().len();
    let slab = slab_triangles(frames, slab_bytes).min(n_triangles.div_ceil(BLOCK) * BLOCK);
    let triangle_data = frames * slab * FRAME_FLOATS * 8;
    let pairs = span.rows.len() * span.cols.len();
    frames * n_vertices * (12 + 24) + triangle_data + pairs * (8 + 72)
}

/// Weighted centred horizontal (u, v) and vertical (y) coordinates of one frame, each scaled by
/// sqrt(w): the inputs of eq. 2.3's sums.
struct PlaneCoords {
    u: Vec<f64>,
    v: Vec<f64>,
    y: Vec<f64>,
}

impl PlaneCoords {
    fn new(p: &[f32], up: UpAxis, weights: Option<&[f64]>) -> Self {
        let (iu, iv, iw) = plane_axes(up);
        let nv = p.len() / 3;
        let w = |k: usize| weights.map_or(1.0, |w| w[k]);
        let sw: f64 = (0..nv).map(w).sum::<f64>().max(f64::MIN_POSITIVE);
        let (mut cu, mut cv) = (0.0, 0.0);
        for k in 0..nv {
            cu += w(k) * p[3 * k + iu] as f64;
            cv += w(k) * p[3 * k + iv] as f64;
        }
        let (cu, cv) = (cu / sw, cv / sw);
        let sq = |k: usize| w(k).sqrt();
        PlaneCoords {
            u: (0..nv).map(|k| sq(k) * (p[3 * k + iu] as f64 - cu)).collect(),
            v: (0..nv).map(|k| sq(k) * (p[3 * k + iv] as f64 - cv)).collect(),
            y: (0..nv).map(|k| sq(k) * p[3 * k + iw] as f64).collect(),
        }
    }
}

/// Lanes of the fixed-order partial sums of [`dot`].
const LANES: usize = 8;

/// sum a_k b_k in eight interleaved partial sums added in a fixed order: vectorises, and gives
/// the same bits on every machine with the same floating-point unit.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    for (l, (x, y)) in ra.iter().zip(rb).enumerate() {
        acc[l] += x * y;
    }
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
}

/// The motion-plane alignment of frame j onto frame i (eq. 2.3 with atan2) and the residual of
/// eq. 2.2 after it: (theta, euclidean distance).
fn pair_alignment(ci: &PlaneCoords, cj: &PlaneCoords) -> (f64, f64) {
    let cross = dot(&ci.u, &cj.u) + dot(&ci.v, &cj.v);
    let wedge = dot(&ci.u, &cj.v) - dot(&ci.v, &cj.u);
    let self_i = dot(&ci.u, &ci.u) + dot(&ci.v, &ci.v);
    let self_j = dot(&cj.u, &cj.u) + dot(&cj.v, &cj.v);
    let horizontal = self_i + self_j - 2.0 * (cross * cross + wedge * wedge).sqrt();
    let vertical = dot(&ci.y, &ci.y) + dot(&cj.y, &cj.y) - 2.0 * dot(&ci.y, &cj.y);
    (wedge.atan2(cross), horizontal.max(0.0) + vertical.max(0.0))
}

/// Rows computed together: each chunk of frame j's triangle data is loaded once and used for all
/// of them (one frame's data is 120 bytes per triangle: without this blocking the loop is bound
/// by memory bandwidth, not arithmetic). Measured with the AVX-512 kernel on the crane (one
/// thread's CPU time): 8 rows x 256 triangles 120-138 M triangle pairs/s,
/// 16 x 64 156-167, 32 x 64 167-187, 64 x 64 180-195. The whole crane matrix on 2 idle cores
/// (`surfcap-bench distance`, wall time): 16 rows 217 M/s, 32 rows 250 M/s, 64 rows 201-216 M/s
/// (three row blocks for 175 frames: one thread idles); a 1,024-frame tile has 32 blocks of 32.
const ROW_BLOCK: usize = 32;
/// Triangles per chunk: a block of frames' chunks stays in the L2 cache (16 x 7.5 KB).
pub(crate) const TRIANGLE_CHUNK: usize = BLOCK;

/// Up to [`ROW_BLOCK`] rows of a tile: per row the columns it computes (j > i), their up-axis
/// rotations and the running sums of their distances.
struct RowBlock {
    rows: Range<usize>,
    /// Per row, the first column (index into the tile's columns) it computes.
    first: Vec<usize>,
    rot: Vec<Vec<Matrix3<f64>>>,
    acc: Vec<Vec<f64>>,
}

/// Position of global frame `g` in the tile's sorted frame list.
fn slot(frames: &[usize], g: usize) -> usize {
    frames.binary_search(&g).expect("a frame of the tile")
}

/// Computes one tile of the distance matrix of frames `frames` (a whole subject or a tile's
/// frames) over the topology's `triangles`, holding the triangle data of at most about
/// `slab_bytes` at once. The result does not depend on the slab budget, the thread count or the
/// other tiles.
pub fn distance_tile(
    frames: &dyn PoseFrames,
    triangles: &[[u32; 3]],
    up: UpAxis,
    span: &TileSpan,
    params: &DistanceParams,
    slab_bytes: usize,
    progress: &dyn Progress,
) -> DistanceTile {
    let ids = span.frames();
    let (nr, nc) = (span.rows.len(), span.cols.len());
    let coords: Vec<PlaneCoords> =
        ids.par_iter().map(|&g| PlaneCoords::new(frames.pose(g), up, params.vertex_weights.as_deref())).collect();
    // First tile column a row computes: j > i on the diagonal, every column elsewhere.
    let first_col = |i: usize| if span.is_diagonal() { i + 1 - span.cols.start } else { 0 };
    let mut values = vec![0.0f64; nr * nc];
    let mut max_skipped = 0usize;
    let alignments: Vec<Vec<(f64, f64)>> = span
        .rows
        .clone()
        .into_par_iter()
        .map(|i| {
            let ci = &coords[slot(&ids, i)];
            (first_col(i)..nc).map(|c| pair_alignment(ci, &coords[slot(&ids, span.cols.start + c)])).collect()
        })
        .collect();
    match params.metric {
        PoseMetric::Euclidean => {
            for (r, row) in alignments.iter().enumerate() {
                let i = span.rows.start + r;
                for (k, &(_, e)) in row.iter().enumerate() {
                    values[r * nc + first_col(i) + k] = e;
                }
            }
        }
        PoseMetric::Deformation | PoseMetric::DeformationLog | PoseMetric::DeformationLiteral => {
            let log_s = params.metric == PoseMetric::DeformationLog;
            let literal = params.metric == PoseMetric::DeformationLiteral;
            let mut work: Vec<RowBlock> = span
                .rows
                .clone()
                .step_by(ROW_BLOCK)
                .map(|i0| {
                    let rows = i0..(i0 + ROW_BLOCK).min(span.rows.end);
                    let first: Vec<usize> = rows.clone().map(first_col).collect();
                    let rot = rows
                        .clone()
                        .map(|i| {
                            alignments[i - span.rows.start]
                                .iter()
                                .map(|&(theta, _)| rotation_about_up(up, theta))
                                .collect()
                        })
                        .collect();
                    let acc = first.iter().map(|&f| vec![0.0; nc - f]).collect();
                    RowBlock { rows, first, rot, acc }
                })
                .collect();
            let slab = slab_triangles(ids.len(), slab_bytes);
            let n_slabs = triangles.len().div_ceil(slab).max(1);
            progress.start("pose distances", (n_slabs * span.pairs()) as u64);
            let mut degenerate: Vec<Vec<u32>> = vec![Vec::new(); ids.len()];
            for t0 in (0..triangles.len()).step_by(slab) {
                let part = &triangles[t0..(t0 + slab).min(triangles.len())];
                let data: Vec<Vec<f64>> = ids
                    .par_iter()
                    .map(|&g| {
                        let mut out = Vec::new();
                        triangle_frames(part, frames.pose(g), &mut out);
                        out
                    })
                    .collect();
                for (list, f) in degenerate.iter_mut().zip(&data) {
                    list.extend(degenerate_triangles(f, part.len()).into_iter().map(|k| k + t0 as u32));
                }
                work.par_iter_mut().for_each(|block| {
                    block.add_slab(&data, &ids, span, params.w, log_s, literal);
                    progress.advance(block.acc.iter().map(Vec::len).sum::<usize>() as u64);
                });
            }
            progress.finish();
            if degenerate.iter().any(|d| !d.is_empty()) {
                for i in span.rows.clone() {
                    for c in first_col(i)..nc {
                        let j = span.cols.start + c;
                        max_skipped =
                            max_skipped.max(union_count(&degenerate[slot(&ids, i)], &degenerate[slot(&ids, j)]));
                    }
                }
            }
            for block in work {
                for ((i, first), acc) in block.rows.clone().zip(block.first).zip(block.acc) {
                    let r = i - span.rows.start;
                    values[r * nc + first..(r + 1) * nc].copy_from_slice(&acc);
                }
            }
        }
    }
    if span.is_diagonal() {
        for r in 0..nr {
            for c in 0..r {
                values[r * nc + c] = values[c * nc + r];
            }
        }
    }
    DistanceTile { span: span.clone(), values, max_skipped_triangles: max_skipped }
}

impl RowBlock {
    /// Adds the distances over one slab's triangles, chunk by chunk in mesh order (slabs are
    /// whole chunks), so a pair's sum depends neither on the slabs nor on the thread count.
    /// `literal`: eq. 2.6 read literally (`literal_deformation_distance`) instead of surfcap's
    /// reading.
    fn add_slab(&mut self, data: &[Vec<f64>], ids: &[usize], span: &TileSpan, w: f64, log_s: bool, literal: bool) {
        let len = data.first().map_or(0, Vec::len);
        let step = TRIANGLE_CHUNK * FRAME_FLOATS;
        let row_data: Vec<&[f64]> = self.rows.clone().map(|i| data[slot(ids, i)].as_slice()).collect();
        let col_data: Vec<&[f64]> = span.cols.clone().map(|j| data[slot(ids, j)].as_slice()).collect();
        let lowest = self.first.iter().copied().min().unwrap_or(0);
        for start in (0..len).step_by(step) {
            let end = (start + step).min(len);
            for (c, fj) in col_data.iter().enumerate().skip(lowest) {
                let fj = &fj[start..end];
                for (r, fi) in row_data.iter().enumerate() {
                    let first = self.first[r];
                    if c < first {
                        continue;
                    }
                    let k = c - first;
                    let (fi, g) = (&fi[start..end], &self.rot[r][k]);
                    self.acc[r][k] += if literal {
                        literal_deformation_distance(fi, fj, g, w, log_s)
                    } else {
                        deformation_distance(fi, fj, g, w, log_s)
                    };
                }
            }
        }
    }
}
