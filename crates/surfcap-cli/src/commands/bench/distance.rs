//! `surfcap bench distance`: the all-pairs deformation distance matrix against the machine's
//! dense f64 GEMM rate.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_mesh::Sequence;
use surfcap_synth::{WormParams, worm_subject};

use super::{open_quietly, peak_rss};

/// Rate of a 1000 x 1000 f64 matrix product on all cores (faer), in FLOP/s: the reference
/// "peak" that the distance benchmark's arithmetic rate is compared with.
pub(super) fn gemm_rate() -> f64 {
    let n = 1000;
    let a = faer::Mat::<f64>::from_fn(n, n, |i, j| ((i * 31 + j * 17) % 101) as f64 / 101.0);
    let b = a.clone();
    let _ = &a * &b;
    let t0 = Instant::now();
    let reps = 5;
    for _ in 0..reps {
        std::hint::black_box(&a * &b);
    }
    2.0 * (n * n * n) as f64 * reps as f64 / t0.elapsed().as_secs_f64()
}

/// Floating-point operations per triangle pair in `deformation_distance`, counted from the
/// code: 27 mul + 18 add (rotations), 15 mul + 13 add (dot products), 4 mul + 1 add (m),
/// 5 for h, 2 div, 5 for the trace, 8 for the stretch term and sum; sqrt and acos counted as one
/// each. An estimate for the "fraction of peak" figure, not a measurement.
const FLOPS_PER_TRIANGLE_PAIR: f64 = 100.0;

pub(super) fn run(
    ctx: &crate::Ctx,
    subject: Option<PathBuf>,
    frames: usize,
    triangles: usize,
    fps: Option<f64>,
) -> anyhow::Result<()> {
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    let s = match subject {
        Some(p) => open_quietly(&p, fps)?,
        None => {
            let segments = 25usize;
            let rings = (triangles / (2 * segments)).max(2);
            let w = worm_subject(&WormParams { rings, segments, frames: frames.div_ceil(2), ..Default::default() })?;
            let nv = w.topology().n_vertices();
            let mut all = Vec::new();
            for q in w.sequences() {
                all.extend_from_slice(q.positions());
            }
            all.truncate(frames * 3 * nv);
            let seq = Sequence::new("all", nv, all)?;
            w.derived("bench", seq)?
        }
    };
    let n = s.n_frames();
    let m = s.topology().n_triangles();
    // The peak before the matrix is the subject's own (and the loader's); the difference is the
    // matrix's working memory.
    let before = peak_rss();
    let bar = crate::progress::Bar::new(ctx);
    let t0 = Instant::now();
    let d = distance_matrix(&s, &DistanceParams::default(), &bar);
    let secs = t0.elapsed().as_secs_f64();
    let pairs = (n * (n - 1) / 2) as f64 * m as f64;
    let rate = pairs / secs;
    let peak = gemm_rate();
    let report = json!({
        "frames": n, "triangles": m, "seconds": secs, "triangle_pairs_per_second": rate,
        "threads": rayon::current_num_threads(),
        "estimated_flops_per_triangle_pair": FLOPS_PER_TRIANGLE_PAIR,
        "gemm_flops_per_second": peak,
        "fraction_of_gemm_rate": rate * FLOPS_PER_TRIANGLE_PAIR / peak,
        "max_skipped_triangles": d.max_skipped_triangles,
        "peak_rss_bytes_before_matrix": before,
        "peak_rss_bytes": peak_rss(),
    });
    ctx.result(&report, || {
        println!(
            "{n} x {n} deformation distances, {m} triangles: {secs:.2} s, {:.1} M triangle pairs/s on {} threads; \
             ~{:.1} GFLOP/s = {:.1}% of the machine's dense f64 GEMM rate ({:.1} GFLOP/s); peak memory {:.0} MB ({:.0} MB before the matrix)",
            rate / 1e6,
            rayon::current_num_threads(),
            rate * FLOPS_PER_TRIANGLE_PAIR / 1e9,
            100.0 * rate * FLOPS_PER_TRIANGLE_PAIR / peak,
            peak / 1e9,
            peak_rss().unwrap_or(0) as f64 / 1e6,
            before.unwrap_or(0) as f64 / 1e6
        );
    });
    Ok(())
}
