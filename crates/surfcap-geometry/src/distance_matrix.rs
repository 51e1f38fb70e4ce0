//! All-pairs pose distance matrix of a subject (thesis 2.3.2), computed in parallel, tile by
//! tile (`distance_tiles.rs`: the same tiles a cluster computes one job each).
//!
//! Every pair (i, j) is aligned about the up axis (eq. 2.3) from the pair's own weighted inner
//! products of centred horizontal coordinates, then its deformation distance costs one pass over
//! the triangles, with per-frame triangle frames precomputed once per tile and slab.
//! [`alignment_gram`] keeps the all-frames Gram matrices (three dense products) for callers that
//! want every pair's alignment at once (walk playback).
//!
//! Memory: those triangle frames are 120 bytes per triangle and frame (f64, needed for exact
//! small angles), 1.8 GB for 547 frames of 28,000 triangles if held for the whole mesh. They are
//! held one slab of triangles at a time instead (all the tile's frames, [`SLAB_BYTES`]); each
//! pair's sum still takes the triangle chunks in mesh order, so the matrix is the same to the bit.
//!
//! The matrix is symmetric by construction: d(i, j) is computed for i < j (deforming i into j)
//! and mirrored, as the thesis treats the distance as symmetric ("to deform pose i into j or
//! vice versa"); the two directions differ only in the stretch term's ||S - I|| vs ||S^-1 - I||.
//! Every entry is computed independently in a fixed order: the result depends neither on the
//! number of threads nor on the tiling.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat};
use surfcap_mesh::{NoProgress, Progress, Subject};

use crate::distance_tiles::{DistanceTile, TRIANGLE_CHUNK, TileSpan, distance_tile, plan_distance_tiles};
use crate::motion_plane_alignment::plane_axes;
use crate::pose_distance::{FRAME_FLOATS, PoseMetric};

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

/// Memory for the triangle data of all frames over one slab of triangles. Holding every frame's
/// whole data at once cost 120 bytes per triangle and frame (1.8 GB for 547 frames of 28,000
/// triangles); a slab of this size keeps the peak near the subject's own size.
pub const SLAB_BYTES: usize = 64 << 20;

/// Frames per side of a tile of the matrix, on one machine and by default on a cluster
/// (`surfcap tiles plan --tile`): a tile of 1,024 x 1,024 frames of 10,000 triangles holds about
/// 0.5 GB and takes about a minute on 2 cores.
pub const DISTANCE_TILE: usize = 1024;

/// Triangles per slab for `n` frames within `budget` bytes: whole chunks, at least one.
pub fn slab_triangles(n: usize, budget: usize) -> usize {
    let per_triangle = n.max(1) * FRAME_FLOATS * std::mem::size_of::<f64>();
    (budget / per_triangle / TRIANGLE_CHUNK).max(1) * TRIANGLE_CHUNK
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
    distance_matrix_in_tiles(subject, params, progress, slab_bytes, DISTANCE_TILE)
}

/// The matrix assembled from the tiles of [`plan_distance_tiles`]`(n, tile)`, each computed by
/// [`distance_tile`], the same function a cluster's tile jobs run: bit-identical for every tile
/// size and slab budget.
pub fn distance_matrix_in_tiles(
    subject: &Subject,
    params: &DistanceParams,
    progress: &dyn Progress,
    slab_bytes: usize,
    tile: usize,
) -> DistanceMatrix {
    let n = subject.n_frames();
    let mut values = vec![0.0f64; n * n];
    let mut max_skipped = 0usize;
    let triangles = subject.topology().triangles();
    for span in plan_distance_tiles(n, tile) {
        let t = distance_tile(subject, triangles, subject.up_axis, &span, params, slab_bytes, progress);
        max_skipped = max_skipped.max(t.max_skipped_triangles);
        place_tile(&mut values, n, &t);
    }
    DistanceMatrix { n, values, max_skipped_triangles: max_skipped }
}

/// The distance d(i, j) of one pair of global frames alone: the one-pair tile of
/// [`distance_tile`] (the row the smaller frame, as the matrix computes it), so the same bits as
/// entry (i, j) of [`distance_matrix`]; 0 when `i == j`. `None` when a frame is not the
/// subject's.
pub fn pair_distance(subject: &Subject, params: &DistanceParams, i: usize, j: usize) -> Option<f64> {
    let n = subject.n_frames();
    if i >= n || j >= n {
        return None;
    }
    if i == j {
        return Some(0.0);
    }
    let (a, b) = (i.min(j), i.max(j));
    let span = TileSpan { rows: a..a + 1, cols: b..b + 1 };
    let t =
        distance_tile(subject, subject.topology().triangles(), subject.up_axis, &span, params, SLAB_BYTES, &NoProgress);
    Some(t.values[0])
}

/// Writes a tile and its mirror image into the row-major n x n `values`.
pub fn place_tile(values: &mut [f64], n: usize, t: &DistanceTile) {
    let nc = t.span.cols.len();
    for (r, i) in t.span.rows.clone().enumerate() {
        for (c, j) in t.span.cols.clone().enumerate() {
            let d = t.values[r * nc + c];
            values[i * n + j] = d;
            values[j * n + i] = d;
        }
    }
}

#[cfg(test)]
mod pair_tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};

    #[test]
    fn one_pair_alone_is_the_matrix_entry_to_the_bit_for_every_metric() {
        let s = worm_subject(&WormParams { rings: 6, segments: 5, frames: 7, ..Default::default() }).unwrap();
        for metric in [PoseMetric::Deformation, PoseMetric::DeformationLog, PoseMetric::Euclidean] {
            let p = DistanceParams { metric, w: 0.01, vertex_weights: None };
            let m = distance_matrix(&s, &p, &NoProgress);
            let n = s.n_frames();
            assert!(n >= 7);
            for i in 0..n {
                for j in 0..n {
                    let d = pair_distance(&s, &p, i, j).unwrap();
                    assert_eq!(d.to_bits(), m.get(i, j).to_bits(), "{metric:?} ({i}, {j})");
                }
            }
        }
        assert_eq!(pair_distance(&s, &DistanceParams::default(), s.n_frames(), 0), None);
    }
}
