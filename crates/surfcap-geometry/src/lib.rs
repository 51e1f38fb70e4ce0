//! surfcap pose geometry (thesis 2.3-2.4), one algorithm per module, named after what it computes,
//! each citing the equations it implements; expensive precomputation (per-frame triangle frames,
//! Cholesky factorisations) is separate from per-query work.
//!
//! - Rigid alignment: [`motion_plane_alignment`] (about the up axis) and Procrustes;
//!   [`deformation_gradient`], [`polar_decomposition`], [`rotation_log_exp`].
//! - Pose distances ([`pose_distance`]: eq. 2.2, 2.13, 2.14; [`literal_deformation_distance`]:
//!   eq. 2.13 with eq. 2.6 read literally, A^-1 B, the metric `deformation-literal`) and the
//!   all-pairs matrix
//!   ([`distance_matrix`]) assembled from tiles ([`distance_tiles`]): any upper-triangle block of
//!   rows x columns is computed from its own frames through the [`distance_tiles::PoseFrames`]
//!   trait (a subject in memory, or only a tile's frames read from disk); each pair is aligned
//!   about the up axis from its own inner products in eight fixed partial sums, and per-frame
//!   triangle data is held one 64 MB slab at a time, so an entry is the same bits whatever the
//!   tiling, the slab or the thread count. Tiles are `DISTANCE_TILE` (1,024) frames;
//!   `tile_memory_bytes` bounds a tile job's memory.
//! - Differential operators ([`gradient_operator`]: gradient, mass, Laplacian, divergence),
//!   [`poisson_reconstruction`] (factor once, solve many), linear and non-linear interpolation
//!   ([`pose_interpolation`], eq. 2.45-2.49) and [`shape_distortion`] measures.
//! - Per-vertex fields the viewer colours a mesh by: [`vertex_edge_strain`] (mean edge-length
//!   strain against a rest pose) and [`vertex_rigid_distance`] (distance to a reference pose after
//!   the best rigid alignment).
//! - Ground contacts shared by everything that needs them ([`ground_contacts`]: `ContactParams`,
//!   the ground as the 20th percentile of the per-frame lowest vertex, the subject's height from
//!   the clip itself, per frame step the low and vertically still vertices with a lowness weight);
//!   root motion of an in-place clip from them ([`root_motion_from_contacts`]: contacts grouped by
//!   displacement, the planted group per step chosen as the smoothest chain by dynamic
//!   programming, flight keeping the last velocity; `planted_contacts` gives those groups'
//!   vertices); per-foot contact signals in [0, 1] for caller-given vertex sets ([`foot_contacts`],
//!   for thesis 6.4's contact-guided alignment); [`foot_sliding`]: the contact-weighted mean
//!   horizontal speed of the planted vertices, in subject units per second.
//!
//! # The deformation distance's kernels
//!
//! The per-triangle loop of the deformation distance runs in one of three kernels chosen at run
//! time ([`pose_distance::DistanceKernel::best`]): AVX-512F, eight triangles per instruction (its
//! 8-lane costs added to a 4-lane sum half by half, so it gives the AVX2 loop's bits), else AVX2 +
//! FMA, four per instruction, else the portable scalar loop, which differs at about 1e-13
//! relative. [`pose_distance::kernel_name`] is recorded with results;
//! [`pose_distance::deformation_distance_with`] picks a kernel for tests and benchmarks. All are
//! tested against the scalar loop (1e-12 relative) and the two SIMD ones against each other (to
//! the bit).
//!
//! Each frame's triangle data is stored as structure-of-arrays blocks of 64 triangles, in f64 (in
//! f32 the small angles between similar poses get a noise floor: up to 9.2e-6 relative error on
//! the Vlasic crane and samba). A triangle pair is evaluated in closed form (2x2 polar factor, no
//! SVD, one division shared by the rotation's cosine and sine), acos inline (argument reduction +
//! arcsine series, no libm call); a rotation about a coordinate axis skips its exact zeros and
//! ones. Rows are computed 32 at a time over 64-triangle chunks (16 rows: 217 M pairs/s, 32:
//! 250 M/s on the crane; 8 x 256 was 15-25% slower with AVX-512: the loop partly waits on loading
//! frame j's data). Tried and dropped (slower here): an Estrin polynomial, `wide`'s portable
//! f64x4, a libm acos with a per-call SSE/AVX transition.
//!
//! faer's dense kernels are AVX-512 and leave the upper vector state dirty on the threads that ran
//! them; scalar SSE code calling libm afterwards on those threads ran 5-6x slower, so the loop
//! clears the state first (`vzeroupper`). Sparse Cholesky runs sequentially (`Par::Seq`, through
//! faer's low-level API, no global state changed): faer's parallel sparse solve was 40x slower on
//! 2 cores. The alignment's Gram matrices use faer's dense GEMM.

pub mod deformation_gradient;
pub mod distance_matrix;
pub mod distance_tiles;
pub mod error;
pub mod foot_contacts;
pub mod foot_sliding;
pub mod gradient_operator;
pub mod ground_contacts;
pub mod literal_deformation_distance;
pub mod motion_plane_alignment;
pub mod poisson_reconstruction;
pub mod polar_decomposition;
pub mod pose_distance;
pub mod pose_interpolation;
pub mod root_motion_from_contacts;
pub mod rotation_log_exp;
pub mod shape_distortion;
pub mod vertex_edge_strain;
pub mod vertex_rigid_distance;

pub use error::{Error, Result};
