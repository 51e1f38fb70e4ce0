//! Pose distances between two frames of one topology (thesis 2.3.2):
//! - Euclidean after motion-plane alignment (eq. 2.2);
//! - deformation-gradient distance (eq. 2.13): sum over triangles of the rotation angle of the
//!   polar factor R of J plus w ||S - I||_F, w = 0.01;
//! - its log-S variant (eq. 2.14): angle + w ||log S||_F. We read the 1/sqrt 2 of eq. 2.14 as
//!   applying to the rotation term only, as in eq. 2.13 (1/sqrt 2 ||log R||_F is the angle);
//!   scaling the S term as well would only rescale w.
//!
//! Before the deformation distances, pose j is rotated about the up axis onto pose i with
//! eq. 2.3 (end of 2.3.2: the metric is not rotation invariant); that rotation multiplies J on
//! the left and leaves S unchanged.
//!
//! Speed: J = B A^-1 maps triangle i's frame (e1, e2, n) onto triangle j's. Writing each frame
//! as an orthonormal basis Q = (t, b, n) times the upper-triangular 2x2 matrix of its edges in
//! that basis (plus 1 for the normal), J = G Q_j (m (+) 1) Q_i^T with m = a_j a_i^-1 upper
//! triangular 2x2. Its polar factors are R = G Q_j (r (+) 1) Q_i^T and S = Q_i (s (+) 1) Q_i^T
//! where m = r s is the 2x2 polar decomposition, which has a closed form. So each triangle pair
//! costs a few dot products and one acos instead of a 3x3 SVD, with the same result (checked
//! against the SVD route in the tests). Zero-area triangles (in either pose) have no
//! deformation gradient: they are skipped and counted.
//!
//! Layout and machine code: a frame's data is stored in blocks of 64 triangles, field by field;
//! acos is computed inline (no libm call); the block loop runs in AVX-512F intrinsics, eight
//! triangles at a time (module `avx512`), on CPUs that have it, else in AVX2 + FMA intrinsics,
//! four at a time (module `avx2`), else in the portable scalar loop ([`DistanceKernel`], chosen
//! at run time; AVX-512 and AVX2 give the same bits, record [`kernel_name`] with results).

use crate::deformation_gradient::vertex;
use nalgebra::Matrix3;

/// Which pose distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseMetric {
    /// eq. 2.2: residual of the motion-plane alignment.
    Euclidean,
    /// eq. 2.13.
    Deformation,
    /// eq. 2.14.
    DeformationLog,
    /// eq. 2.13 with eq. 2.6 read literally, T = A^-1 B instead of J = B A^-1 (PAPER-NOTES;
    /// `crate::literal_deformation_distance`): offered to show what that reading changes.
    DeformationLiteral,
}

impl PoseMetric {
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "euclidean" => PoseMetric::Euclidean,
            "deformation" => PoseMetric::Deformation,
            "deformation-log" => PoseMetric::DeformationLog,
            "deformation-literal" => PoseMetric::DeformationLiteral,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            PoseMetric::Euclidean => "euclidean",
            PoseMetric::Deformation => "deformation",
            PoseMetric::DeformationLog => "deformation-log",
            PoseMetric::DeformationLiteral => "deformation-literal",
        }
    }
}

/// Parses `euclidean`, `deformation`, `deformation-log` or `deformation-literal`; the error says
/// what was expected.
impl std::str::FromStr for PoseMetric {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        PoseMetric::parse(s).ok_or_else(|| UnknownName {
            given: s.to_string(),
            expected: "deformation, deformation-log, deformation-literal or euclidean",
        })
    }
}

/// A name that is not one of a parameter's values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownName {
    pub given: String,
    pub expected: &'static str,
}

impl std::fmt::Display for UnknownName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}: expected {}", self.given, self.expected)
    }
}

impl std::error::Error for UnknownName {}

/// Floats stored per triangle and frame: t, b, n (9), edge coordinates a11, a12, a22 (3) and
/// the inverse's 1/a11, -a12/(a11 a22), 1/a22 (3). Zero-area triangles store zeros.
pub const FRAME_FLOATS: usize = 15;

/// Triangles per storage block. A frame's data is stored block by block, and inside a block
/// field by field (structure of arrays): the loop over a block's triangles reads each field
/// contiguously, so the compiler can run it on vector registers. The last block is padded with
/// zero-area triangles.
pub const BLOCK: usize = 64;

/// Floats of one storage block.
pub const BLOCK_FLOATS: usize = BLOCK * FRAME_FLOATS;

/// Per-frame precomputation for the deformation distances (the expensive part is per pair).
/// Stored in f64 (f32 would do only where the matrix stays within 1e-6 relative;
/// measured with `surfcap-bench distance`, the values rounded to f32 as storage would hold them,
/// 175 x 175 matrices, max / median relative error over the 15,225 pairs):
///
/// | fields in f32 | crane | samba |
/// |---|---|---|
/// | all 15 | 5.7e-6 / 6.8e-10 | 9.2e-6 / 8.3e-10 |
/// | orientation t, b, n | 5.7e-6 / 6.4e-10 | 9.2e-6 / 8.0e-10 |
/// | edges a11..a22 + inverse | 2.3e-8 / 2.0e-10 | 4.0e-8 / 1.6e-10 |
///
/// The worst pairs are neighbours (crane:5 - crane:6, samba:9 - samba:10): the rotation angle
/// comes from acos of a trace near 3, whose rounding in f32 (~6e-8) is amplified for small
/// angles, so the orientation must stay f64. The six edge fields alone pass (2-4e-8), but they
/// are 6 of the 25 loads per pair (2 x 24 of the 192 bytes it reads) and would need 6 conversions
/// back to f64; storing them in f32 would change this function's and `degenerate_triangles`'
/// signatures, which the distance matrix (being restructured into tiles) is built on. Not
/// adopted: at most a few percent to gain, not measured. Layout: blocks of
/// [`BLOCK`] triangles, each block `FRAME_FLOATS` arrays of `BLOCK` values. `triangles` may be
/// any run of a topology's triangles (the distance matrix takes them a slab at a time); a
/// triangle's values do not depend on the others.
pub fn triangle_frames(triangles: &[[u32; 3]], p: &[f32], out: &mut Vec<f64>) {
    let m = triangles.len();
    out.clear();
    out.resize(m.div_ceil(BLOCK) * BLOCK_FLOATS, 0.0);
    for (k, t) in triangles.iter().enumerate() {
        let (v1, v2, v3) = (vertex(p, t[0]), vertex(p, t[1]), vertex(p, t[2]));
        let (e1, e2) = (v1 - v3, v2 - v3);
        let c = e1.cross(&e2);
        let (len1, area2) = (e1.norm(), c.norm());
        let scale = e1.norm_squared().max(e2.norm_squared());
        if area2 <= 1e-12 * scale || len1 == 0.0 {
            continue; // stays zero: skipped by the distance
        }
        let tt = e1 / len1;
        let n = c / area2;
        let b = n.cross(&tt);
        let (a11, a12, a22) = (len1, e2.dot(&tt), e2.dot(&b));
        let inv = [1.0 / a11, -a12 / (a11 * a22), 1.0 / a22];
        let base = (k / BLOCK) * BLOCK_FLOATS + k % BLOCK;
        let fields = [tt.x, tt.y, tt.z, b.x, b.y, b.z, n.x, n.y, n.z, a11, a12, a22, inv[0], inv[1], inv[2]];
        for (f, v) in fields.into_iter().enumerate() {
            out[base + f * BLOCK] = v;
        }
    }
}

/// Triangles of a frame that have no deformation gradient (zero area), from its
/// [`triangle_frames`]; the distance skips a triangle when either frame lists it.
pub fn degenerate_triangles(frames: &[f64], n_triangles: usize) -> Vec<u32> {
    (0..n_triangles)
        .filter(|&k| frames[(k / BLOCK) * BLOCK_FLOATS + 11 * BLOCK + k % BLOCK] == 0.0)
        .map(|k| k as u32)
        .collect()
}

/// Number of triangles in the union of two sorted lists.
pub fn union_count(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() || j < b.len() {
        match (a.get(i), b.get(j)) {
            (Some(x), Some(y)) if x == y => {
                i += 1;
                j += 1;
            }
            (Some(x), Some(y)) if x < y => i += 1,
            (Some(_), None) => i += 1,
            _ => j += 1,
        }
        n += 1;
    }
    n
}

/// Terms of the arcsine series used by [`acos_branchless`].
const ASIN_TERMS: usize = 22;

/// asin(x) = x sum_k c_k x^(2k), c_k = (2k)! / (4^k (k!)^2 (2k + 1)).
const ASIN_COEFFS: [f64; ASIN_TERMS] = {
    let mut c = [0.0; ASIN_TERMS];
    let mut ratio = 1.0;
    let mut k = 0;
    while k < ASIN_TERMS {
        if k > 0 {
            ratio *= (2 * k - 1) as f64 / (2 * k) as f64;
        }
        c[k] = ratio / (2 * k + 1) as f64;
        k += 1;
    }
    c
};

/// acos on [-1, 1] without branches or calls, so that the block loop vectorises: the argument is
/// reduced to an arcsine on [0, 0.5] (acos c = 2 asin sqrt((1 - c)/2) for c >= 0.5, where 1 - c is
/// exact and small angles keep full precision; pi - 2 asin sqrt((1 + c)/2) for c <= -0.5;
/// pi/2 -+ asin |c| between), and the arcsine summed from its series (truncation below 3e-16 on
/// [0, 0.5]). Agrees with libm's `acos` to 1e-14 (tested).
#[inline(always)]
pub fn acos_branchless(c: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let hi = c >= 0.5;
    let lo = c <= -0.5;
    let y = if hi {
        0.5 - 0.5 * c
    } else if lo {
        0.5 + 0.5 * c
    } else {
        c * c
    };
    let y = y.max(0.0);
    let x = if hi || lo { y.sqrt() } else { c.abs() };
    let mut p = ASIN_COEFFS[ASIN_TERMS - 1];
    let mut k = ASIN_TERMS - 1;
    while k > 0 {
        k -= 1;
        p = p * y + ASIN_COEFFS[k];
    }
    let a = x * p;
    if hi {
        2.0 * a
    } else if lo {
        PI - 2.0 * a
    } else if c >= 0.0 {
        FRAC_PI_2 - a
    } else {
        FRAC_PI_2 + a
    }
}

/// The machine code that runs the plain metric's block loop (eq. 2.13). All three compute the
/// same arithmetic per triangle; [`DistanceKernel::Avx2`] and [`DistanceKernel::Avx512`] also sum
/// in the same order (the AVX-512 loop folds its two 4-lane halves into a 4-lane accumulator as
/// the AVX2 loop adds its two successive vectors), so their results are identical to the bit;
/// the scalar loop rounds twice where they use fused multiply-adds and sums in another order
/// (agreement to 1e-12 relative, tested). Results computed with different kernels must not be
/// mixed silently: record [`kernel_name`] with them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DistanceKernel {
    /// The portable loop (any CPU).
    Scalar,
    /// AVX2 + FMA intrinsics, four triangles per instruction.
    Avx2,
    /// AVX-512F intrinsics, eight triangles per instruction.
    Avx512,
}

impl DistanceKernel {
    /// Every kernel, slowest first.
    pub const ALL: [DistanceKernel; 3] = [DistanceKernel::Scalar, DistanceKernel::Avx2, DistanceKernel::Avx512];

    /// Whether this CPU can run the kernel (run-time detection).
    pub fn is_available(self) -> bool {
        match self {
            DistanceKernel::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            DistanceKernel::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            DistanceKernel::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The kernels this CPU can run, slowest first.
    pub fn available() -> Vec<DistanceKernel> {
        Self::ALL.into_iter().filter(|k| k.is_available()).collect()
    }

    /// The fastest kernel this CPU can run: AVX-512, else AVX2, else scalar (detected once per
    /// process: the all-pairs loop asks for it for every chunk of every pair).
    pub fn best() -> DistanceKernel {
        static BEST: std::sync::OnceLock<DistanceKernel> = std::sync::OnceLock::new();
        *BEST.get_or_init(|| *Self::available().last().expect("the scalar kernel is always available"))
    }

    pub fn name(self) -> &'static str {
        match self {
            DistanceKernel::Scalar => "scalar",
            DistanceKernel::Avx2 => "avx2",
            DistanceKernel::Avx512 => "avx512",
        }
    }
}

/// Name of the kernel [`deformation_distance`] runs on this CPU (`scalar`, `avx2` or `avx512`),
/// to be recorded with results: AVX2 and AVX-512 give the same bits, the scalar loop differs from
/// them at about 1e-13 relative.
pub fn kernel_name() -> &'static str {
    DistanceKernel::best().name()
}

/// Sum over triangles of the per-triangle deformation cost from frame i to frame j, where `g`
/// is the rotation about the up axis that aligns pose j onto pose i. `fi`, `fj` are whole
/// storage blocks of [`triangle_frames`] (the same blocks of both frames); zero-area triangles
/// (and the padding) contribute nothing (see [`degenerate_triangles`] to count them). Runs the
/// [`DistanceKernel::best`] kernel.
pub fn deformation_distance(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
    let kernel = DistanceKernel::best();
    // SAFETY: `best` returns only a kernel this CPU has.
    unsafe { run_kernel(kernel, fi, fj, g, w, log_s) }
}

/// [`deformation_distance`] with a chosen kernel (for tests and benchmarks).
///
/// # Panics
/// If the CPU cannot run `kernel` (check [`DistanceKernel::is_available`]): a programming error,
/// as running it would be undefined behaviour.
pub fn deformation_distance_with(
    kernel: DistanceKernel,
    fi: &[f64],
    fj: &[f64],
    g: &Matrix3<f64>,
    w: f64,
    log_s: bool,
) -> f64 {
    assert!(kernel.is_available(), "the {} distance kernel needs a CPU feature this machine lacks", kernel.name());
    // SAFETY: checked just above.
    unsafe { run_kernel(kernel, fi, fj, g, w, log_s) }
}

/// # Safety
/// The CPU must have the features of `kernel` ([`DistanceKernel::is_available`]).
#[inline]
unsafe fn run_kernel(kernel: DistanceKernel, fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the caller guarantees the features the function is compiled for.
        DistanceKernel::Avx512 => unsafe { deformation_distance_avx512(fi, fj, g, w, log_s) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above.
        DistanceKernel::Avx2 => unsafe { deformation_distance_avx2(fi, fj, g, w, log_s) },
        _ => {
            surfcap_linalg::clear_upper_vector_state();
            deformation_distance_body(fi, fj, g, w, log_s)
        }
    }
}

/// The axis `k` that the row-major rotation `gm` turns about when it is exactly a rotation about
/// a coordinate axis (entry (k, k) one, the rest of row and column k zero), as every up-axis
/// alignment (eq. 2.3) is; 3 otherwise. The SIMD kernels then skip the products by the exact
/// zeros and ones (4 of the rotation's 9 multiply-adds per vector are left), which gives the same
/// values as the full product.
#[inline]
fn rotation_axis(gm: &[f64; 9]) -> usize {
    (0..3)
        .find(|&k| {
            let (u, v) = off_axis(k);
            gm[4 * k] == 1.0 && [gm[3 * k + u], gm[3 * k + v], gm[3 * u + k], gm[3 * v + k]].iter().all(|&x| x == 0.0)
        })
        .unwrap_or(3)
}

/// The two coordinate indices other than `k`, in increasing order.
#[inline(always)]
const fn off_axis(k: usize) -> (usize, usize) {
    match k {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// The rotation's nine entries, row by row.
#[inline(always)]
fn row_major(g: &Matrix3<f64>) -> [f64; 9] {
    [g[(0, 0)], g[(0, 1)], g[(0, 2)], g[(1, 0)], g[(1, 1)], g[(1, 2)], g[(2, 0)], g[(2, 1)], g[(2, 2)]]
}

/// The same loops compiled for AVX2 + FMA; the plain metric's block loop is written with AVX2
/// intrinsics, four triangles per instruction ([`avx2::block_cost`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn deformation_distance_avx2(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
    if log_s {
        return deformation_distance_body(fi, fj, g, w, true);
    }
    let gm = row_major(g);
    let blocks = fi.chunks_exact(BLOCK_FLOATS).zip(fj.chunks_exact(BLOCK_FLOATS));
    let sum = |total: f64, x: f64| total + x;
    // SAFETY (all four): this function only runs where AVX2 and FMA were detected.
    match rotation_axis(&gm) {
        0 => blocks.map(|(a, b)| unsafe { avx2::block_cost::<0>(a, b, &gm, w) }).fold(0.0, sum),
        1 => blocks.map(|(a, b)| unsafe { avx2::block_cost::<1>(a, b, &gm, w) }).fold(0.0, sum),
        2 => blocks.map(|(a, b)| unsafe { avx2::block_cost::<2>(a, b, &gm, w) }).fold(0.0, sum),
        _ => blocks.map(|(a, b)| unsafe { avx2::block_cost::<3>(a, b, &gm, w) }).fold(0.0, sum),
    }
}

/// The plain metric's loop on AVX-512 ([`avx512::block_cost`]); the log-S metric runs the
/// portable loop compiled for these features (it calls libm's `ln` and `acos`), after clearing
/// the upper vector state.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn deformation_distance_avx512(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
    if log_s {
        return deformation_distance_body(fi, fj, g, w, true);
    }
    let gm = row_major(g);
    let blocks = fi.chunks_exact(BLOCK_FLOATS).zip(fj.chunks_exact(BLOCK_FLOATS));
    let sum = |total: f64, x: f64| total + x;
    // SAFETY (all four): this function only runs where AVX-512F, AVX2 and FMA were detected.
    match rotation_axis(&gm) {
        0 => blocks.map(|(a, b)| unsafe { avx512::block_cost::<0>(a, b, &gm, w) }).fold(0.0, sum),
        1 => blocks.map(|(a, b)| unsafe { avx512::block_cost::<1>(a, b, &gm, w) }).fold(0.0, sum),
        2 => blocks.map(|(a, b)| unsafe { avx512::block_cost::<2>(a, b, &gm, w) }).fold(0.0, sum),
        _ => blocks.map(|(a, b)| unsafe { avx512::block_cost::<3>(a, b, &gm, w) }).fold(0.0, sum),
    }
}

/// The plain metric's block loop in AVX-512F intrinsics, eight triangles per instruction: the
/// arithmetic of [`avx2::block_cost`] lane by lane (compare masks and masked blends where it uses
/// blendv), so each triangle's cost is the same to the bit. The running sum is kept in four
/// lanes, as the AVX2 loop keeps it: each 8-lane cost vector is added as its low half, then its
/// high half, which are the AVX2 loop's two successive vectors. The block's sum, and so the
/// whole distance, is therefore identical to the AVX2 kernel's (tested) and does not depend on
/// anything but the data.
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::{ASIN_COEFFS, ASIN_TERMS, BLOCK, FRAME_FLOATS, field};

    #[inline]
    #[target_feature(enable = "avx512f,avx2,fma")]
    fn acos8(c: __m512d) -> __m512d {
        use std::f64::consts::{FRAC_PI_2, PI};
        let half = _mm512_set1_pd(0.5);
        let zero = _mm512_setzero_pd();
        let two = _mm512_set1_pd(2.0);
        let hi = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(c, half);
        let lo = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(c, _mm512_set1_pd(-0.5));
        let ext = hi | lo;
        // y = (1 - c)/2 (hi), (1 + c)/2 (lo), c^2 (between)
        let y_hi = _mm512_fnmadd_pd(half, c, half);
        let y_lo = _mm512_fmadd_pd(half, c, half);
        let y_ext = _mm512_mask_blend_pd(hi, y_lo, y_hi);
        let y = _mm512_max_pd(_mm512_mask_blend_pd(ext, _mm512_mul_pd(c, c), y_ext), zero);
        let x = _mm512_mask_blend_pd(ext, _mm512_abs_pd(c), _mm512_sqrt_pd(y));
        let mut p = _mm512_set1_pd(ASIN_COEFFS[ASIN_TERMS - 1]);
        let mut k = ASIN_TERMS - 1;
        while k > 0 {
            k -= 1;
            p = _mm512_fmadd_pd(p, y, _mm512_set1_pd(ASIN_COEFFS[k]));
        }
        let a = _mm512_mul_pd(x, p);
        let pos = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(c, zero);
        let mid = _mm512_mask_blend_pd(
            pos,
            _mm512_add_pd(_mm512_set1_pd(FRAC_PI_2), a),
            _mm512_sub_pd(_mm512_set1_pd(FRAC_PI_2), a),
        );
        let low = _mm512_fnmadd_pd(two, a, _mm512_set1_pd(PI));
        _mm512_mask_blend_pd(hi, _mm512_mask_blend_pd(lo, mid, low), _mm512_mul_pd(two, a))
    }

    /// # Safety
    /// The CPU must have AVX-512F, AVX2 and FMA; `a` and `b` must be whole storage blocks.
    #[target_feature(enable = "avx512f,avx2,fma")]
    pub(super) unsafe fn block_cost<const AXIS: usize>(a: &[f64], b: &[f64], gm: &[f64; 9], w: f64) -> f64 {
        let at: [&[f64; BLOCK]; FRAME_FLOATS] = std::array::from_fn(|k| field(a, k));
        let bt: [&[f64; BLOCK]; FRAME_FLOATS] = std::array::from_fn(|k| field(b, k));
        // SAFETY: k + 8 <= BLOCK for every k the loop below uses (BLOCK is a multiple of 8).
        let ld = |s: &[f64; BLOCK], k: usize| unsafe { _mm512_loadu_pd(s.as_ptr().add(k)) };
        let g: [__m512d; 9] = gm.map(|x| _mm512_set1_pd(x));
        let zero = _mm512_setzero_pd();
        let one = _mm512_set1_pd(1.0);
        let two = _mm512_set1_pd(2.0);
        let half = _mm512_set1_pd(0.5);
        let w8 = _mm512_set1_pd(w);
        let mut acc = _mm256_setzero_pd();
        let mut k = 0;
        while k < BLOCK {
            // 1/a22 of frame i is zero exactly when its triangle is (one load fewer than a11).
            let (a14, b11) = (ld(at[14], k), ld(bt[11], k));
            let valid = _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(a14, zero) & _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(b11, zero);
            let b9 = ld(bt[9], k);
            let p = _mm512_mul_pd(b9, ld(at[12], k));
            let q = _mm512_fmadd_pd(b9, ld(at[13], k), _mm512_mul_pd(ld(bt[10], k), a14));
            let t = _mm512_mul_pd(b11, a14);
            let pt = _mm512_add_pd(p, t);
            let h2 = _mm512_fmadd_pd(pt, pt, _mm512_mul_pd(q, q));
            let h = _mm512_mask_blend_pd(valid, one, _mm512_sqrt_pd(h2));
            let rot = |f: usize| {
                let x = [ld(bt[f], k), ld(bt[f + 1], k), ld(bt[f + 2], k)];
                let r = |i: usize| {
                    if AXIS == i {
                        x[i]
                    } else if AXIS < 3 {
                        // The two entries off the axis; the zeros' terms are exact, so this is
                        // the generic expression's value.
                        let (u, v) = super::off_axis(AXIS);
                        _mm512_fmadd_pd(g[3 * i + u], x[u], _mm512_mul_pd(g[3 * i + v], x[v]))
                    } else {
                        _mm512_fmadd_pd(
                            g[3 * i],
                            x[0],
                            _mm512_fmadd_pd(g[3 * i + 1], x[1], _mm512_mul_pd(g[3 * i + 2], x[2])),
                        )
                    }
                };
                [r(0), r(1), r(2)]
            };
            let (gt, gb, gn) = (rot(0), rot(3), rot(6));
            let dot = |u: usize, v: &[__m512d; 3]| {
                _mm512_fmadd_pd(
                    ld(at[u], k),
                    v[0],
                    _mm512_fmadd_pd(ld(at[u + 1], k), v[1], _mm512_mul_pd(ld(at[u + 2], k), v[2])),
                )
            };
            let p00_p11 = _mm512_add_pd(dot(0, &gt), dot(3, &gb));
            let p01_p10 = _mm512_sub_pd(dot(0, &gb), dot(3, &gt));
            // (cos phi, sin phi) = (p + t, -q) / h: one division.
            let trace =
                _mm512_add_pd(_mm512_div_pd(_mm512_fmsub_pd(pt, p00_p11, _mm512_mul_pd(q, p01_p10)), h), dot(6, &gn));
            let c =
                _mm512_min_pd(_mm512_max_pd(_mm512_mul_pd(half, _mm512_sub_pd(trace, one)), _mm512_set1_pd(-1.0)), one);
            // ||s - I||^2 = p^2 + q^2 + t^2 - 2h + 2
            let s2 = _mm512_fmadd_pd(p, p, _mm512_fmadd_pd(q, q, _mm512_mul_pd(t, t)));
            let stretch = _mm512_sqrt_pd(_mm512_max_pd(_mm512_add_pd(_mm512_fnmadd_pd(two, h, s2), two), zero));
            let cost = _mm512_maskz_mov_pd(valid, _mm512_fmadd_pd(w8, stretch, acos8(c)));
            // The AVX2 loop's order: triangles k..k+4, then k+4..k+8.
            acc = _mm256_add_pd(acc, _mm512_castpd512_pd256(cost));
            acc = _mm256_add_pd(acc, _mm512_extractf64x4_pd::<1>(cost));
            k += 8;
        }
        let mut lanes = [0.0f64; 4];
        // SAFETY: `lanes` holds four f64.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), acc) };
        (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
    }
}

/// The plain metric's block loop in AVX2 intrinsics: the same arithmetic as
/// [`block_cost`]`::<false>`, lane by lane (fused multiply-adds round once where the scalar loop
/// rounds twice; the two agree to 1e-12 relative, tested).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::{ASIN_COEFFS, ASIN_TERMS, BLOCK, FRAME_FLOATS, field};

    #[target_feature(enable = "avx2,fma")]
    fn acos4(c: __m256d) -> __m256d {
        use std::f64::consts::{FRAC_PI_2, PI};
        let half = _mm256_set1_pd(0.5);
        let zero = _mm256_setzero_pd();
        let two = _mm256_set1_pd(2.0);
        let hi = _mm256_cmp_pd::<_CMP_GE_OQ>(c, half);
        let lo = _mm256_cmp_pd::<_CMP_LE_OQ>(c, _mm256_set1_pd(-0.5));
        let ext = _mm256_or_pd(hi, lo);
        // y = (1 - c)/2 (hi), (1 + c)/2 (lo), c^2 (between)
        let y_hi = _mm256_fnmadd_pd(half, c, half);
        let y_lo = _mm256_fmadd_pd(half, c, half);
        let y_ext = _mm256_blendv_pd(y_lo, y_hi, hi);
        let y = _mm256_max_pd(_mm256_blendv_pd(_mm256_mul_pd(c, c), y_ext, ext), zero);
        let abs_c = _mm256_andnot_pd(_mm256_set1_pd(-0.0), c);
        let x = _mm256_blendv_pd(abs_c, _mm256_sqrt_pd(y), ext);
        let mut p = _mm256_set1_pd(ASIN_COEFFS[ASIN_TERMS - 1]);
        let mut k = ASIN_TERMS - 1;
        while k > 0 {
            k -= 1;
            p = _mm256_fmadd_pd(p, y, _mm256_set1_pd(ASIN_COEFFS[k]));
        }
        let a = _mm256_mul_pd(x, p);
        let pos = _mm256_cmp_pd::<_CMP_GE_OQ>(c, zero);
        let mid = _mm256_blendv_pd(
            _mm256_add_pd(_mm256_set1_pd(FRAC_PI_2), a),
            _mm256_sub_pd(_mm256_set1_pd(FRAC_PI_2), a),
            pos,
        );
        let low = _mm256_fnmadd_pd(two, a, _mm256_set1_pd(PI));
        _mm256_blendv_pd(_mm256_blendv_pd(mid, low, lo), _mm256_mul_pd(two, a), hi)
    }

    /// # Safety
    /// The CPU must have AVX2 and FMA; `a` and `b` must be whole storage blocks.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn block_cost<const AXIS: usize>(a: &[f64], b: &[f64], gm: &[f64; 9], w: f64) -> f64 {
        let at: [&[f64; BLOCK]; FRAME_FLOATS] = std::array::from_fn(|k| field(a, k));
        let bt: [&[f64; BLOCK]; FRAME_FLOATS] = std::array::from_fn(|k| field(b, k));
        // SAFETY: k + 4 <= BLOCK for every k the loop below uses (BLOCK is a multiple of 4).
        let ld = |s: &[f64; BLOCK], k: usize| unsafe { _mm256_loadu_pd(s.as_ptr().add(k)) };
        let g: [__m256d; 9] = gm.map(|x| _mm256_set1_pd(x));
        let zero = _mm256_setzero_pd();
        let one = _mm256_set1_pd(1.0);
        let two = _mm256_set1_pd(2.0);
        let half = _mm256_set1_pd(0.5);
        let w4 = _mm256_set1_pd(w);
        let mut acc = zero;
        let mut k = 0;
        while k < BLOCK {
            // 1/a22 of frame i is zero exactly when its triangle is (one load fewer than a11).
            let (a14, b11) = (ld(at[14], k), ld(bt[11], k));
            let valid = _mm256_and_pd(_mm256_cmp_pd::<_CMP_NEQ_UQ>(a14, zero), _mm256_cmp_pd::<_CMP_NEQ_UQ>(b11, zero));
            let b9 = ld(bt[9], k);
            let p = _mm256_mul_pd(b9, ld(at[12], k));
            let q = _mm256_fmadd_pd(b9, ld(at[13], k), _mm256_mul_pd(ld(bt[10], k), a14));
            let t = _mm256_mul_pd(b11, a14);
            let pt = _mm256_add_pd(p, t);
            let h2 = _mm256_fmadd_pd(pt, pt, _mm256_mul_pd(q, q));
            let h = _mm256_blendv_pd(one, _mm256_sqrt_pd(h2), valid);
            let rot = |f: usize| {
                let x = [ld(bt[f], k), ld(bt[f + 1], k), ld(bt[f + 2], k)];
                let r = |i: usize| {
                    if AXIS == i {
                        x[i]
                    } else if AXIS < 3 {
                        // The two entries off the axis; the zeros' terms are exact, so this is
                        // the generic expression's value.
                        let (u, v) = super::off_axis(AXIS);
                        _mm256_fmadd_pd(g[3 * i + u], x[u], _mm256_mul_pd(g[3 * i + v], x[v]))
                    } else {
                        _mm256_fmadd_pd(
                            g[3 * i],
                            x[0],
                            _mm256_fmadd_pd(g[3 * i + 1], x[1], _mm256_mul_pd(g[3 * i + 2], x[2])),
                        )
                    }
                };
                [r(0), r(1), r(2)]
            };
            let (gt, gb, gn) = (rot(0), rot(3), rot(6));
            let dot = |u: usize, v: &[__m256d; 3]| {
                _mm256_fmadd_pd(
                    ld(at[u], k),
                    v[0],
                    _mm256_fmadd_pd(ld(at[u + 1], k), v[1], _mm256_mul_pd(ld(at[u + 2], k), v[2])),
                )
            };
            let p00_p11 = _mm256_add_pd(dot(0, &gt), dot(3, &gb));
            let p01_p10 = _mm256_sub_pd(dot(0, &gb), dot(3, &gt));
            // (cos phi, sin phi) = (p + t, -q) / h: one division.
            let trace =
                _mm256_add_pd(_mm256_div_pd(_mm256_fmsub_pd(pt, p00_p11, _mm256_mul_pd(q, p01_p10)), h), dot(6, &gn));
            let c =
                _mm256_min_pd(_mm256_max_pd(_mm256_mul_pd(half, _mm256_sub_pd(trace, one)), _mm256_set1_pd(-1.0)), one);
            // ||s - I||^2 = p^2 + q^2 + t^2 - 2h + 2
            let s2 = _mm256_fmadd_pd(p, p, _mm256_fmadd_pd(q, q, _mm256_mul_pd(t, t)));
            let stretch = _mm256_sqrt_pd(_mm256_max_pd(_mm256_add_pd(_mm256_fnmadd_pd(two, h, s2), two), zero));
            let cost = _mm256_fmadd_pd(w4, stretch, acos4(c));
            acc = _mm256_add_pd(acc, _mm256_and_pd(cost, valid));
            k += 4;
        }
        let mut lanes = [0.0f64; 4];
        // SAFETY: `lanes` holds four f64.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), acc) };
        (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
    }
}

#[inline(always)]
fn deformation_distance_body(fi: &[f64], fj: &[f64], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
    let gm = row_major(g);
    let mut total = 0.0f64;
    for (a, b) in fi.chunks_exact(BLOCK_FLOATS).zip(fj.chunks_exact(BLOCK_FLOATS)) {
        total += if log_s { block_cost::<true>(a, b, &gm, w) } else { block_cost::<false>(a, b, &gm, w) };
    }
    total
}

/// Field `k` of a storage block.
#[inline(always)]
fn field(s: &[f64], k: usize) -> &[f64; BLOCK] {
    s[k * BLOCK..(k + 1) * BLOCK].try_into().expect("whole block")
}

/// Cost of one block of triangles. With `LOG` false the loop has no calls and vectorises.
#[inline(always)]
fn block_cost<const LOG: bool>(a: &[f64], b: &[f64], gm: &[f64; 9], w: f64) -> f64 {
    let at: [&[f64; BLOCK]; FRAME_FLOATS] = std::array::from_fn(|k| field(a, k));
    let bt: [&[f64; BLOCK]; FRAME_FLOATS] = std::array::from_fn(|k| field(b, k));
    let mut acc = [0.0f64; BLOCK];
    for k in 0..BLOCK {
        let valid = at[11][k] != 0.0 && bt[11][k] != 0.0;
        // m = a_j a_i^-1, upper triangular [[p, q], [0, t]].
        let p = bt[9][k] * at[12][k];
        let q = bt[9][k] * at[13][k] + bt[10][k] * at[14][k];
        let t = bt[11][k] * at[14][k];
        let h2 = (p + t) * (p + t) + q * q;
        let h = if valid { h2.sqrt() } else { 1.0 };
        let rot = |x: f64, y: f64, z: f64| {
            [gm[0] * x + gm[1] * y + gm[2] * z, gm[3] * x + gm[4] * y + gm[5] * z, gm[6] * x + gm[7] * y + gm[8] * z]
        };
        let gt = rot(bt[0][k], bt[1][k], bt[2][k]);
        let gb = rot(bt[3][k], bt[4][k], bt[5][k]);
        let gn = rot(bt[6][k], bt[7][k], bt[8][k]);
        let dot = |u: usize, v: &[f64; 3]| at[u][k] * v[0] + at[u + 1][k] * v[1] + at[u + 2][k] * v[2];
        let p00_p11 = dot(0, &gt) + dot(3, &gb);
        let p01_p10 = dot(0, &gb) - dot(3, &gt);
        let p22 = dot(6, &gn);
        // r = [[cos phi, -sin phi], [sin phi, cos phi]] with (cos phi, sin phi) = (p + t, -q) / h,
        // so tr(r P) = ((p + t)(P00 + P11) - q (P01 - P10)) / h: one division.
        let trace = ((p + t) * p00_p11 - q * p01_p10) / h + p22;
        let c = (0.5 * (trace - 1.0)).clamp(-1.0, 1.0);
        let (angle, stretch) = if LOG {
            // Singular values of m: roots of x^2 - h x + p t.
            let disc = (h * h - 4.0 * p * t).max(0.0).sqrt();
            let (s1, s2) = ((0.5 * (h + disc)).max(f64::MIN_POSITIVE), (0.5 * (h - disc)).max(f64::MIN_POSITIVE));
            (c.acos(), (s1.ln().powi(2) + s2.ln().powi(2)).sqrt())
        } else {
            (acos_branchless(c), (p * p + q * q + t * t - 2.0 * h + 2.0).max(0.0).sqrt())
        };
        acc[k] = if valid { angle + w * stretch } else { 0.0 };
    }
    acc.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deformation_gradient::deformation_gradients;
    use crate::motion_plane_alignment::rotation_about_up;
    use crate::polar_decomposition::polar_decomposition;
    use crate::rotation_log_exp::{exp_rotation, log_rotation, rotation_angle};
    use nalgebra::Vector3;
    use surfcap_mesh::Topology;
    use surfcap_mesh::UpAxis;

    /// The SVD route, written as the thesis does, for reference.
    fn reference(topo: &Topology, pi: &[f32], pj: &[f32], g: &Matrix3<f64>, w: f64, log_s: bool) -> f64 {
        deformation_gradients(topo, pi, pj)
            .into_iter()
            .flatten()
            .map(|j| {
                let (r, s) = polar_decomposition(&(g * j));
                let stretch = if log_s {
                    let e = s.symmetric_eigen();
                    e.eigenvalues.map(|x| x.ln().powi(2)).sum().sqrt()
                } else {
                    (s - Matrix3::identity()).norm()
                };
                rotation_angle(&r) + w * stretch
            })
            .sum()
    }

    fn lcg(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 33) as f32 / (1u64 << 31) as f32) - 0.5
    }

    #[test]
    fn branchless_acos_matches_libm_and_degenerate_triangles_are_listed() {
        let mut worst = 0.0f64;
        for k in 0..=200_000 {
            let c = -1.0 + 2.0 * k as f64 / 200_000.0;
            worst = worst.max((acos_branchless(c) - c.acos()).abs());
        }
        for e in [1e-16, 1e-12, 1e-8, 1e-4] {
            for c in [1.0 - e, -1.0 + e] {
                worst = worst.max((acos_branchless(c) - c.acos()).abs());
            }
        }
        assert!(worst < 1e-14, "{worst}");
        assert_eq!(acos_branchless(1.0), 0.0);
        let topo = Topology::new(4, vec![[0, 1, 2], [0, 1, 3]], None).unwrap();
        let p = [0., 0., 0., 1., 0., 0., 0., 1., 0., 2., 0., 0.];
        let mut f = Vec::new();
        triangle_frames(topo.triangles(), &p, &mut f);
        assert_eq!(f.len(), BLOCK_FLOATS);
        assert_eq!(degenerate_triangles(&f, 2), vec![1]);
        assert_eq!(union_count(&[1, 4, 9], &[2, 4]), 4);
    }

    /// Every kernel this CPU has against the portable loop, on five blocks of random triangles
    /// (a few of them degenerate in one frame or the other, rotations of every size so that
    /// acos sees all three branches), for several up-axis rotations. The SIMD kernels must agree
    /// with each other to the bit. Prints which kernels ran; the scalar-vs-SIMD check needs at
    /// least AVX2, and the test says what it could not exercise.
    #[test]
    fn every_available_kernel_matches_the_scalar_loop() {
        let mut seed = 11u64;
        let n_tri = 5 * BLOCK - 7; // a padded last block
        let n = 3 * n_tri;
        let tris: Vec<[u32; 3]> = (0..n_tri as u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let topo = Topology::new(n, tris, None).unwrap();
        let mut pi: Vec<f32> = (0..3 * n).map(|_| lcg(&mut seed)).collect();
        let mut pj: Vec<f32> = pi.iter().map(|&x| x + 0.02 * lcg(&mut seed)).collect();
        // Large rotations for a third of the triangles: c below -0.5 and between.
        for k in (0..n_tri).step_by(3) {
            let r = exp_rotation(
                &Vector3::new(lcg(&mut seed) as f64, lcg(&mut seed) as f64, 1.0 + lcg(&mut seed) as f64).scale(2.5),
            );
            for v in 3 * k..3 * k + 3 {
                let x = r * Vector3::new(pj[3 * v] as f64, pj[3 * v + 1] as f64, pj[3 * v + 2] as f64);
                pj[3 * v..3 * v + 3].copy_from_slice(&[x.x as f32, x.y as f32, x.z as f32]);
            }
        }
        // Degenerate triangles: collapsed in frame i (k = 5), in frame j (k = 70, 200).
        let collapse = |p: &mut [f32], k: usize| p.copy_within(9 * k..9 * k + 3, 9 * k + 3);
        collapse(&mut pi, 5);
        collapse(&mut pj, 70);
        collapse(&mut pj, 200);
        let (mut fi, mut fj) = (Vec::new(), Vec::new());
        triangle_frames(topo.triangles(), &pi, &mut fi);
        triangle_frames(topo.triangles(), &pj, &mut fj);
        assert_eq!(degenerate_triangles(&fi, n_tri), vec![5]);
        assert_eq!(degenerate_triangles(&fj, n_tri), vec![70, 200]);
        let cs: Vec<f64> = (0..n_tri)
            .map(|k| {
                let b = (k / BLOCK) * BLOCK_FLOATS + k % BLOCK;
                let dot: f64 = (0..9).map(|f| fi[b + f * BLOCK] * fj[b + f * BLOCK]).sum();
                0.5 * (dot - 1.0)
            })
            .collect();
        assert!(cs.iter().any(|&c| c < -0.5) && cs.iter().any(|&c| c.abs() < 0.5) && cs.iter().any(|&c| c > 0.5));
        let available = DistanceKernel::available();
        assert_eq!(available[0], DistanceKernel::Scalar);
        assert_eq!(DistanceKernel::best(), *available.last().unwrap());
        assert_eq!(kernel_name(), DistanceKernel::best().name());
        let mut checked = Vec::new();
        // Rotations about each coordinate axis (the kernels' short path) and a general one.
        let rotations = [
            (rotation_about_up(UpAxis::PosY, 0.0), 0), // the identity: about any axis, x first
            (rotation_about_up(UpAxis::PosX, 0.7), 0),
            (rotation_about_up(UpAxis::PosY, -2.9), 1),
            (rotation_about_up(UpAxis::PosZ, 1.3), 2),
            (exp_rotation(&Vector3::new(0.2, 0.7, -0.4)), 3),
        ];
        for (g, axis) in rotations {
            assert_eq!(rotation_axis(&row_major(&g)), axis);
            let portable = deformation_distance_body(&fi, &fj, &g, 0.01, false);
            assert!(portable > 1.0, "{portable}");
            let simd: Vec<f64> = available
                .iter()
                .map(|&kernel| {
                    let d = deformation_distance_with(kernel, &fi, &fj, &g, 0.01, false);
                    assert!((d - portable).abs() <= 1e-12 * portable, "{}: {d} vs {portable}", kernel.name());
                    if kernel == DistanceKernel::Scalar {
                        assert_eq!(d.to_bits(), portable.to_bits());
                    }
                    checked.push(kernel.name());
                    d
                })
                .collect();
            assert!(simd.iter().skip(1).all(|d| d.to_bits() == simd[1].to_bits()), "AVX2 and AVX-512 differ: {simd:?}");
            // The short path about a coordinate axis gives the full product's bits.
            #[cfg(target_arch = "x86_64")]
            if axis < 3 {
                let gm = row_major(&g);
                let blocks = || fi.chunks_exact(BLOCK_FLOATS).zip(fj.chunks_exact(BLOCK_FLOATS));
                for &kernel in &available[1..] {
                    // SAFETY: only kernels this CPU has (`available`).
                    let full: f64 = blocks()
                        .map(|(a, b)| unsafe {
                            match kernel {
                                DistanceKernel::Avx2 => avx2::block_cost::<3>(a, b, &gm, 0.01),
                                _ => avx512::block_cost::<3>(a, b, &gm, 0.01),
                            }
                        })
                        .fold(0.0, |s, x| s + x);
                    let d = deformation_distance_with(kernel, &fi, &fj, &g, 0.01, false);
                    assert_eq!(d.to_bits(), full.to_bits(), "{} about axis {axis}", kernel.name());
                }
            }
            for &kernel in &available {
                let d = deformation_distance_with(kernel, &fi, &fj, &g, 0.01, true);
                let want = deformation_distance_body(&fi, &fj, &g, 0.01, true);
                assert_eq!(d.to_bits(), want.to_bits(), "log-S, {}", kernel.name());
            }
        }
        checked.dedup();
        let missing: Vec<&str> = DistanceKernel::ALL.iter().filter(|k| !k.is_available()).map(|k| k.name()).collect();
        eprintln!(
            "distance kernels checked against the scalar loop: {}; not on this CPU: {}",
            available.iter().map(|k| k.name()).collect::<Vec<_>>().join(", "),
            if missing.is_empty() { "none".to_string() } else { missing.join(", ") }
        );
        assert!(!checked.is_empty());
    }

    #[test]
    fn closed_form_matches_the_svd_route() {
        let mut seed = 7u64;
        let n = 30usize;
        let tris: Vec<[u32; 3]> = (0..n as u32 / 3).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let topo = Topology::new(n, tris, None).unwrap();
        let pi: Vec<f32> = (0..3 * n).map(|_| lcg(&mut seed)).collect();
        let r = exp_rotation(&Vector3::new(0.3, 2.9, -0.4));
        let pj: Vec<f32> = pi
            .chunks(3)
            .flat_map(|v| {
                let x = r * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                [x.x as f32 + 0.3 * lcg(&mut seed), x.y as f32 + 0.3 * lcg(&mut seed), x.z as f32]
            })
            .collect();
        let g = exp_rotation(&Vector3::new(0.0, 0.7, 0.0));
        let (mut fi, mut fj) = (Vec::new(), Vec::new());
        triangle_frames(topo.triangles(), &pi, &mut fi);
        triangle_frames(topo.triangles(), &pj, &mut fj);
        for log_s in [false, true] {
            let fast = deformation_distance(&fi, &fj, &g, 0.01, log_s);
            let skipped = degenerate_triangles(&fi, topo.n_triangles()).len();
            // The portable loop and the AVX2 one (when this machine has it) agree.
            let portable = deformation_distance_body(&fi, &fj, &g, 0.01, log_s);
            assert!((fast - portable).abs() < 1e-12 * fast.max(1.0), "{fast} vs {portable}");
            let slow = reference(&topo, &pi, &pj, &g, 0.01, log_s);
            assert_eq!(skipped, 0);
            assert!((fast - slow).abs() < 1e-4 * slow.max(1.0), "log_s={log_s}: {fast} vs {slow}");
        }
        let zero = deformation_distance(&fi, &fi, &Matrix3::identity(), 0.01, false);
        assert!(zero < 1e-6, "{zero}");
        let _ = log_rotation(&r);
    }
}
