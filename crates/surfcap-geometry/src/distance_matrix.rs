//! All-pairs pose distance matrix of a subject (thesis 2.3.2), computed in parallel.
//!
//! The motion-plane alignment of every pair (eq. 2.3) needs only weighted inner products of the
//! frames' centred horizontal coordinates, so they come from three dense matrix products (faer)
//! instead of F^2 passes over the vertices. The deformation distances then cost one pass over
//! the triangles per pair, with per-frame triangle frames precomputed once per triangle.
//!
//! Memory: those triangle frames are 120 bytes per triangle and frame (f64, needed for exact
//! small angles), 1.8 GB for 547 frames of 28,000 triangles if held for the whole mesh. They are
//! held one slab of triangles at a time instead (all frames, [`SLAB_BYTES`]); each pair's sum
//! still takes the triangle chunks in mesh order, so the matrix is the same to the bit.
//!
//! The matrix is symmetric by construction: d(i, j) is computed for i < j (deforming i into j)
//! and mirrored, as the thesis treats the distance as symmetric ("to deform pose i into j or
//! vice versa"); the two directions differ only in the stretch term's ||S - I|| vs ||S^-1 - I||.
//! Every entry is computed independently in a fixed order: the result does not depend on the
//! number of threads.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat};
use nalgebra::Matrix3;
use rayon::prelude::*;
use surfcap_mesh::{Progress, Subject};

use crate::motion_plane_alignment::{plane_axes, rotation_about_up};
use crate::pose_distance::{
    BLOCK, FRAME_FLOATS, PoseMetric, deformation_distance, degenerate_triangles, triangle_frames, union_count,
};

/// Parameters of a distance matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceParams {
    pub metric: PoseMetric,
    /// Weight of the stretch term (eq. 2.13: w_m = 0.01 for all triangles).
    pub w: f64,
    /// Per-vertex alignment weights of eq. 2.2-2.5 (`None`: all ones).
    pub vertex_weights: Option<Vec<f64>>,
}

impl Default for DistanceParams {
    fn default() -> Self {
        DistanceParams { metric: PoseMetric::Deformation, w: 0.01, vertex_weights: None }
    }
}

/// An F x F matrix over the subject's global frame index, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceMatrix {
    pub n: usize,
    pub values: Vec<f64>,
    /// Largest number of zero-area triangles skipped in one pair (deformation metrics).
    pub max_skipped_triangles: usize,
}

impl DistanceMatrix {
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.values[i * self.n + j]
    }
}

/// Pairwise alignment data: for frames i (target) and j (moved onto i),
/// `cross[i][j]` = sum w (u_i u_j + v_i v_j) and `wedge[i][j]` = sum w (u_i v_j - v_i u_j) over
/// centred horizontal coordinates, and `vert[i][j]` = sum w y_i y_j over vertical coordinates.
pub struct AlignmentGram {
    pub n: usize,
    pub cross: Mat<f64>,
    pub wedge: Mat<f64>,
    pub vert: Mat<f64>,
}

impl AlignmentGram {
    /// The up-axis angle that aligns frame j onto frame i (eq. 2.3, with atan2).
    pub fn theta(&self, i: usize, j: usize) -> f64 {
        self.wedge[(i, j)].atan2(self.cross[(i, j)])
    }

    /// The residual of eq. 2.2 after the optimal motion-plane alignment.
    pub fn euclidean(&self, i: usize, j: usize) -> f64 {
        let (a, b) = (self.cross[(i, j)], self.wedge[(i, j)]);
        let horizontal = self.cross[(i, i)] + self.cross[(j, j)] - 2.0 * (a * a + b * b).sqrt();
        let vertical = self.vert[(i, i)] + self.vert[(j, j)] - 2.0 * self.vert[(i, j)];
        horizontal.max(0.0) + vertical.max(0.0)
    }
}

/// Frames whose rows are computed together: each chunk of frame j's triangle data is loaded
/// once and used for all of them (the data of one frame is 120 bytes per triangle, so without
/// this blocking the all-pairs loop is bound by memory bandwidth, not arithmetic). Measured with
/// the AVX-512 kernel on the crane (one thread's CPU time, issue 21 item 5): 8 rows x 256
/// triangles 120-138 M triangle pairs/s, 16 x 64 156-167, 32 x 64 167-187, 64 x 64 180-195;
/// 16 keeps enough row blocks to share 175 frames evenly between 2 threads.
const ROW_BLOCK: usize = 16;
/// Triangles per chunk: a block of frames' chunks stays in the L2 cache (16 x 7.5 KB).
const TRIANGLE_CHUNK: usize = BLOCK;
/// Memory for the triangle data of all frames over one slab of triangles. Holding every frame's
/// whole data at once cost 120 bytes per triangle and frame (1.8 GB for 547 frames of 28,000
/// triangles); a slab of this size keeps the peak near the subject's own size.
pub const SLAB_BYTES: usize = 64 << 20;

/// Triangles per slab for `n` frames within `budget` bytes: whole chunks, at least one.
pub fn slab_triangles(n: usize, budget: usize) -> usize {
    let per_triangle = n.max(1) * FRAME_FLOATS * std::mem::size_of::<f64>();
    (budget / per_triangle / TRIANGLE_CHUNK).max(1) * TRIANGLE_CHUNK
}

/// Rows `i0..i0 + ROW_BLOCK` of the matrix: the up-axis rotations of their pairs (j > i) and the
/// running sums of their distances.
struct RowBlock {
    i0: usize,
    rot: Vec<Vec<Matrix3<f64>>>,
    acc: Vec<Vec<f64>>,
}

impl RowBlock {
    fn new(subject: &Subject, gram: &AlignmentGram, i0: usize) -> Self {
        let n = gram.n;
        let rows = i0..(i0 + ROW_BLOCK).min(n);
        let rot = rows
            .clone()
            .map(|i| (i + 1..n).map(|j| rotation_about_up(subject.up_axis, gram.theta(i, j))).collect())
            .collect();
        RowBlock { i0, rot, acc: rows.map(|i| vec![0.0; n - i - 1]).collect() }
    }

    /// Adds the distances over one slab's triangles, chunk by chunk. Every pair's sum takes the
    /// chunks in mesh order whatever the slab size (slabs are whole chunks), so the sums depend
    /// neither on the slabs nor on the thread count.
    fn add_slab(&mut self, frames: &[Vec<f64>], w: f64, log_s: bool) {
        let (n, i0) = (frames.len(), self.i0);
        let i1 = (i0 + ROW_BLOCK).min(n);
        let len = frames.first().map_or(0, Vec::len);
        // Whole storage blocks per chunk (TRIANGLE_CHUNK is a multiple of BLOCK).
        let step = TRIANGLE_CHUNK * FRAME_FLOATS;
        for start in (0..len).step_by(step) {
            let end = (start + step).min(len);
            for j in i0 + 1..n {
                let fj = &frames[j][start..end];
                for (r, fi) in frames[i0..i1.min(j)].iter().enumerate() {
                    let k = j - (i0 + r) - 1;
                    self.acc[r][k] += deformation_distance(&fi[start..end], fj, &self.rot[r][k], w, log_s);
                }
            }
        }
    }
}

/// Builds the alignment Gram matrices of all frames.
pub fn alignment_gram(subject: &Subject, weights: Option<&[f64]>) -> AlignmentGram {
    let (iu, iv, iw) = plane_axes(subject.up_axis);
    let f = subject.n_frames();
    let nv = subject.topology().n_vertices();
    let w = |k: usize| weights.map_or(1.0, |w| w[k]);
    let sw: f64 = (0..nv).map(w).sum::<f64>().max(f64::MIN_POSITIVE);
    let mut u = Mat::<f64>::zeros(f, nv);
    let mut v = Mat::<f64>::zeros(f, nv);
    let mut y = Mat::<f64>::zeros(f, nv);
    for g in 0..f {
        let p = subject.frame(g).expect("global index in range");
        let (mut cu, mut cv) = (0.0, 0.0);
        for k in 0..nv {
            cu += w(k) * p[3 * k + iu] as f64;
            cv += w(k) * p[3 * k + iv] as f64;
        }
        let (cu, cv) = (cu / sw, cv / sw);
        for k in 0..nv {
            let sq = w(k).sqrt();
            u[(g, k)] = sq * (p[3 * k + iu] as f64 - cu);
            v[(g, k)] = sq * (p[3 * k + iv] as f64 - cv);
            y[(g, k)] = sq * p[3 * k + iw] as f64;
        }
    }
    // faer's GEMM kernels are AVX-512; the distance loop clears the upper vector state before it
    // runs (see `pose_distance::clear_upper_vector_state`), so the parallel product is safe.
    let product = |a: &Mat<f64>, b: &Mat<f64>, sign: f64, dst: &mut Mat<f64>, accum: Accum| {
        matmul(dst.as_mut(), accum, a.as_ref(), b.transpose(), sign, faer::get_global_parallelism())
    };
    let mut cross = Mat::<f64>::zeros(f, f);
    product(&u, &u, 1.0, &mut cross, Accum::Replace);
    product(&v, &v, 1.0, &mut cross, Accum::Add);
    let mut wedge = Mat::<f64>::zeros(f, f);
    product(&u, &v, 1.0, &mut wedge, Accum::Replace);
    product(&v, &u, -1.0, &mut wedge, Accum::Add);
    let mut vert = Mat::<f64>::zeros(f, f);
    product(&y, &y, 1.0, &mut vert, Accum::Replace);
    AlignmentGram { n: f, cross, wedge, vert }
}

/// The all-pairs distance matrix of the subject's frames (global frame index order), with the
/// triangle data held one slab of [`SLAB_BYTES`] at a time.
pub fn distance_matrix(subject: &Subject, params: &DistanceParams, progress: &dyn Progress) -> DistanceMatrix {
    distance_matrix_in_slabs(subject, params, progress, SLAB_BYTES)
}

/// [`distance_matrix`] with the per-frame triangle data of at most about `slab_bytes` held at
/// once (at least one chunk of triangles). The result is bit-identical for every budget.
pub fn distance_matrix_in_slabs(
    subject: &Subject,
    params: &DistanceParams,
    progress: &dyn Progress,
    slab_bytes: usize,
) -> DistanceMatrix {
    let n = subject.n_frames();
    let gram = alignment_gram(subject, params.vertex_weights.as_deref());
    let mut values = vec![0.0f64; n * n];
    let mut max_skipped = 0usize;
    match params.metric {
        PoseMetric::Euclidean => {
            for i in 0..n {
                for j in 0..n {
                    values[i * n + j] = if i == j { 0.0 } else { gram.euclidean(i.min(j), i.max(j)) };
                }
            }
        }
        PoseMetric::Deformation | PoseMetric::DeformationLog => {
            let log_s = params.metric == PoseMetric::DeformationLog;
            let triangles = subject.topology().triangles();
            let slab = slab_triangles(n, slab_bytes);
            let blocks: Vec<usize> = (0..n).step_by(ROW_BLOCK).collect();
            let mut work: Vec<RowBlock> = blocks.par_iter().map(|&i0| RowBlock::new(subject, &gram, i0)).collect();
            let mut degenerate: Vec<Vec<u32>> = vec![Vec::new(); n];
            let n_slabs = triangles.len().div_ceil(slab).max(1);
            progress.start("pose distances", (n_slabs * n * n.saturating_sub(1) / 2) as u64);
            for t0 in (0..triangles.len()).step_by(slab) {
                let part = &triangles[t0..(t0 + slab).min(triangles.len())];
                let frames: Vec<Vec<f64>> = (0..n)
                    .into_par_iter()
                    .map(|g| {
                        let mut out = Vec::new();
                        triangle_frames(part, subject.frame(g).expect("in range"), &mut out);
                        out
                    })
                    .collect();
                for (list, f) in degenerate.iter_mut().zip(&frames) {
                    list.extend(degenerate_triangles(f, part.len()).into_iter().map(|k| k + t0 as u32));
                }
                work.par_iter_mut().for_each(|block| {
                    block.add_slab(&frames, params.w, log_s);
                    progress.advance(block.acc.iter().map(Vec::len).sum::<usize>() as u64);
                });
            }
            progress.finish();
            if degenerate.iter().any(|d| !d.is_empty()) {
                for i in 0..n {
                    for j in i + 1..n {
                        max_skipped = max_skipped.max(union_count(&degenerate[i], &degenerate[j]));
                    }
                }
            }
            for block in work {
                for (r, row) in block.acc.into_iter().enumerate() {
                    let i = block.i0 + r;
                    for (k, d) in row.into_iter().enumerate() {
                        let j = i + 1 + k;
                        values[i * n + j] = d;
                        values[j * n + i] = d;
                    }
                }
            }
        }
    }
    DistanceMatrix { n, values, max_skipped_triangles: max_skipped }
}
