//! `surfcap-bench distance`: the all-pairs deformation distance matrix against the machine's
//! dense f64 GEMM rate; the rate of every distance kernel this CPU has on 2 threads and 1; and
//! what storing the per-frame triangle data in f32 would do to the matrix.

use std::path::PathBuf;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;
use surfcap_builtin::{WormParams, worm_subject};
use surfcap_geometry::distance_matrix::{DistanceMatrix, SLAB_BYTES, alignment_gram, slab_triangles};
use surfcap_geometry::motion_plane_alignment::rotation_about_up;
use surfcap_geometry::pose_distance::{
    BLOCK, BLOCK_FLOATS, DistanceKernel, FRAME_FLOATS, deformation_distance_with, kernel_name, triangle_frames,
};
use surfcap_mesh::{NoProgress, Sequence, Subject};

use crate::measure::{FpsOpt, cpu_seconds, load_average, peak_rss};

/// Rate of a 1000 x 1000 f64 matrix product on all cores (faer), in FLOP/s: the reference
/// "peak" that the distance benchmark's arithmetic rate is compared with.
fn gemm_rate() -> f64 {
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

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject; default: the built-in tube with --frames frames of about --triangles triangles.
    #[arg(long)]
    pub subject: Option<PathBuf>,
    #[arg(long, default_value_t = 175, value_parser = crate::options::count)]
    pub frames: usize,
    #[arg(long, default_value_t = 20000, value_parser = crate::options::count)]
    pub triangles: usize,
    #[command(flatten)]
    pub fps: FpsOpt,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    let Args { subject, frames, triangles, fps } = a;
    if subject.is_none() {
        // The matrix (f64) and every frame's deformation gradients (a 3x3 f64 per triangle).
        let (f, t) = (frames as f64, triangles as f64);
        let what = format!("--frames {frames} --triangles {triangles}");
        crate::check_size(ctx, what, f * f * 8.0 + f * t * 72.0 + f * t * 6.0, 0.0, "--frames or --triangles")?;
    }
    let s = match subject {
        Some(p) => fps.open_quietly(&p)?,
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
    // The matrix's own peak, before the measurements below add theirs.
    let peak_matrix = peak_rss();
    let pairs = (n * (n - 1) / 2) as f64 * m as f64;
    let rate = pairs / secs;
    let peak = gemm_rate();
    let load_before = load_average();
    let whole = thread_counts()
        .into_iter()
        .map(|threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
            let (t0, c0) = (Instant::now(), cpu_seconds());
            let d1 = pool.install(|| distance_matrix(&s, &DistanceParams::default(), &NoProgress));
            let (secs, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
            anyhow::ensure!(d1 == d, "the matrix on {threads} threads differs from the default pool's");
            Ok(json!({"threads": threads, "seconds": secs, "triangle_pairs_per_second": pairs / secs,
                "cpu_seconds": cpu, "triangle_pairs_per_cpu_second": pairs / cpu}))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let kernels = kernel_rates(&s)?;
    let precision = f32_storage_errors(&s, &d)?;
    let load_after = load_average();
    let report = json!({
        "frames": n, "triangles": m, "seconds": secs, "triangle_pairs_per_second": rate,
        "threads": rayon::current_num_threads(),
        "kernel": kernel_name(),
        "whole_matrix_by_threads": whole,
        "kernels": kernels,
        "f32_storage": precision,
        "load_average_before": load_before, "load_average_after": load_after,
        "estimated_flops_per_triangle_pair": FLOPS_PER_TRIANGLE_PAIR,
        "gemm_flops_per_second": peak,
        "fraction_of_gemm_rate": rate * FLOPS_PER_TRIANGLE_PAIR / peak,
        "max_skipped_triangles": d.max_skipped_triangles,
        "peak_rss_bytes_before_matrix": before,
        "peak_rss_bytes": peak_matrix,
        "peak_rss_bytes_with_kernel_and_f32_measurements": peak_rss(),
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
            peak_matrix.unwrap_or(0) as f64 / 1e6,
            before.unwrap_or(0) as f64 / 1e6
        );
        println!("kernel {} (run-time detection); 1-minute load average {:.2} before, {:.2} after", kernel_name(), load_before.unwrap_or(f64::NAN), load_after.unwrap_or(f64::NAN));
        for r in &whole {
            println!(
                "  whole matrix on {} thread(s): {:.2} s, {:.1} M triangle pairs/s ({:.1} M per CPU second)",
                r["threads"],
                r["seconds"].as_f64().unwrap_or(0.0),
                r["triangle_pairs_per_second"].as_f64().unwrap_or(0.0) / 1e6,
                r["triangle_pairs_per_cpu_second"].as_f64().unwrap_or(0.0) / 1e6
            );
        }
        println!("pair loop only, per kernel (the first {} triangles, all frame pairs):", kernels.first().map_or(0, |k| k["triangles"].as_u64().unwrap_or(0)));
        for k in &kernels {
            println!(
                "  {:>7} on {} thread(s): {:.1} M triangle pairs/s ({:.1} M per CPU second)",
                k["kernel"].as_str().unwrap_or(""),
                k["threads"],
                k["triangle_pairs_per_second"].as_f64().unwrap_or(0.0) / 1e6,
                k["triangle_pairs_per_cpu_second"].as_f64().unwrap_or(0.0) / 1e6
            );
        }
        println!("per-frame data stored in f32, relative error of the matrix entries against f64 ({} pairs, {} of them neighbours i, i+1):", precision.first().map_or(0, |p| p["pairs"].as_u64().unwrap_or(0)), precision.first().map_or(0, |p| p["neighbour_pairs"].as_u64().unwrap_or(0)));
        println!("  {:<24} {:>10} {:>10} {:>14} {:>14}  worst pair", "fields in f32", "max", "median", "neighbour max", "neighbour med");
        for p in &precision {
            let f = |k: &str| p[k].as_f64().unwrap_or(f64::NAN);
            println!(
                "  {:<24} {:>10.2e} {:>10.2e} {:>14.2e} {:>14.2e}  {}",
                p["fields"].as_str().unwrap_or(""), f("max"), f("median"), f("neighbour_max"), f("neighbour_median"), p["worst_pair"].as_str().unwrap_or("")
            );
        }
    });
    Ok(())
}

/// Thread counts the kernels are timed on: 2 and 1 (the targets are for 2 cores).
fn thread_counts() -> Vec<usize> {
    vec![2, 1]
}

/// Rows and triangles taken together by the pair loop, as `distance_matrix.rs` takes them.
const ROW_BLOCK: usize = 16;
const TRIANGLE_CHUNK: usize = 64;

/// Sums of the deformation distances of all frame pairs i < j (row-major over the upper
/// triangle) over the triangles whose storage `frames` holds, with `kernel`, in the distance
/// matrix's blocking: `ROW_BLOCK` rows share each chunk of `TRIANGLE_CHUNK` triangles of frame j.
fn pair_sums(frames: &[Vec<f64>], rot: &[Vec<Matrix>], kernel: DistanceKernel, sums: &mut [Vec<f64>]) {
    let n = frames.len();
    let step = TRIANGLE_CHUNK * FRAME_FLOATS;
    let len = frames.first().map_or(0, Vec::len);
    sums.par_chunks_mut(ROW_BLOCK).enumerate().for_each(|(b, rows)| {
        let i0 = b * ROW_BLOCK;
        for start in (0..len).step_by(step) {
            let end = (start + step).min(len);
            for j in i0 + 1..n {
                let fj = &frames[j][start..end];
                for (r, row) in rows.iter_mut().enumerate().take(j - i0) {
                    let i = i0 + r;
                    row[j - i - 1] +=
                        deformation_distance_with(kernel, &frames[i][start..end], fj, &rot[i][j - i - 1], 0.01, false);
                }
            }
        }
    });
}

type Matrix = nalgebra::Matrix3<f64>;

/// The up-axis rotations of all pairs i < j (eq. 2.3).
fn pair_rotations(s: &Subject) -> Vec<Vec<Matrix>> {
    let gram = alignment_gram(s, None);
    let n = s.n_frames();
    (0..n).map(|i| (i + 1..n).map(|j| rotation_about_up(s.up_axis, gram.theta(i, j))).collect()).collect()
}

/// The per-frame triangle data of all frames over `part`.
fn all_frames(s: &Subject, part: &[[u32; 3]]) -> Vec<Vec<f64>> {
    (0..s.n_frames())
        .into_par_iter()
        .map(|g| {
            let mut out = Vec::new();
            triangle_frames(part, s.frame(g).expect("in range"), &mut out);
            out
        })
        .collect()
}

/// Triangle pairs per second of the pair loop with every kernel this CPU has, on 2 threads and
/// 1, over the first slab of triangles (as many as `distance_matrix` holds at once) and all
/// frame pairs; each kernel's largest difference to the scalar sums is reported.
fn kernel_rates(s: &Subject) -> anyhow::Result<Vec<serde_json::Value>> {
    let n = s.n_frames();
    let triangles = s.topology().triangles();
    let part = &triangles[..slab_triangles(n, SLAB_BYTES).min(triangles.len())];
    let frames = all_frames(s, part);
    let rot = pair_rotations(s);
    let pairs = (n * n.saturating_sub(1) / 2 * part.len()) as f64;
    let mut out = Vec::new();
    let mut first: Option<Vec<Vec<f64>>> = None;
    for threads in thread_counts() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        for kernel in DistanceKernel::available() {
            let mut sums: Vec<Vec<f64>> = (0..n).map(|i| vec![0.0; n - i - 1]).collect();
            let (t0, c0) = (Instant::now(), cpu_seconds());
            pool.install(|| pair_sums(&frames, &rot, kernel, &mut sums));
            let (secs, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
            // Sums of (nearly) identical frames are rounding noise (acos near 1 amplifies the
            // kernels' different roundings), so the kernels are compared relative to the largest.
            let difference = match &first {
                Some(want) => {
                    let scale = want.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
                    sums.iter().flatten().zip(want.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
                        / scale
                }
                None => {
                    first = Some(sums);
                    0.0
                }
            };
            out.push(json!({"kernel": kernel.name(), "threads": threads, "triangles": part.len(), "seconds": secs, "triangle_pairs_per_second": pairs / secs,
                "cpu_seconds": cpu, "triangle_pairs_per_cpu_second": pairs / cpu,
                "max_difference_to_scalar_over_largest_sum": difference}));
        }
    }
    Ok(out)
}

/// Field sets tried in f32: floats 0-8 are the orientation (t, b, n), 9-14 the edge coordinates
/// a11, a12, a22 and their inverse's entries.
const F32_VARIANTS: [(&str, std::ops::Range<usize>); 4] =
    [("all 15", 0..15), ("orientation t, b, n", 0..9), ("edges a11..a22 + inverse", 9..15), ("inverse only", 12..15)];

/// The matrix with the per-frame triangle data rounded to f32 (the values f32 storage would
/// hold) for each of [`F32_VARIANTS`], against `d` (the f64 matrix, computed with the same
/// kernel): relative error of each entry, max and median over all pairs and over neighbours
/// (i, i + 1 of one sequence), and the worst pair by name.
fn f32_storage_errors(s: &Subject, d: &DistanceMatrix) -> anyhow::Result<Vec<serde_json::Value>> {
    let n = s.n_frames();
    let triangles = s.topology().triangles();
    let rot = pair_rotations(s);
    let kernel = DistanceKernel::best();
    let slab = slab_triangles(n, SLAB_BYTES / 2);
    let mut sums: Vec<Vec<Vec<f64>>> =
        F32_VARIANTS.iter().map(|_| (0..n).map(|i| vec![0.0; n - i - 1]).collect()).collect();
    for t0 in (0..triangles.len()).step_by(slab) {
        let frames = all_frames(s, &triangles[t0..(t0 + slab).min(triangles.len())]);
        for ((_, fields), sums) in F32_VARIANTS.iter().zip(&mut sums) {
            let rounded: Vec<Vec<f64>> = frames
                .par_iter()
                .map(|f| {
                    let mut f = f.clone();
                    for block in f.chunks_exact_mut(BLOCK_FLOATS) {
                        for x in &mut block[fields.start * BLOCK..fields.end * BLOCK] {
                            *x = *x as f32 as f64;
                        }
                    }
                    f
                })
                .collect();
            pair_sums(&rounded, &rot, kernel, sums);
        }
    }
    let index = s.frame_index();
    let neighbours = |i: usize, j: usize| j == i + 1 && index.locate(i).map(|l| l.0) == index.locate(j).map(|l| l.0);
    let mut out = Vec::new();
    for ((name, _), sums) in F32_VARIANTS.iter().zip(&sums) {
        let mut all = Vec::new();
        let mut near = Vec::new();
        let mut worst = (0.0f64, 0, 0);
        for (i, row) in sums.iter().enumerate() {
            for (k, &x) in row.iter().enumerate() {
                let j = i + 1 + k;
                let want = d.get(i, j);
                let e = if want == 0.0 { if x == 0.0 { 0.0 } else { f64::INFINITY } } else { (x - want).abs() / want };
                if e >= worst.0 {
                    worst = (e, i, j);
                }
                all.push(e);
                if neighbours(i, j) {
                    near.push(e);
                }
            }
        }
        let stats = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            (v.last().copied().unwrap_or(0.0), v.get(v.len() / 2).copied().unwrap_or(0.0))
        };
        let (max, median) = stats(&mut all);
        let (nmax, nmedian) = stats(&mut near);
        out.push(json!({
            "fields": name, "pairs": all.len(), "neighbour_pairs": near.len(),
            "max": max, "median": median, "neighbour_max": nmax, "neighbour_median": nmedian,
            "worst_pair": format!("{} - {}", index.label(worst.1), index.label(worst.2)),
            "within_1e-6": max <= 1e-6,
        }));
    }
    Ok(out)
}
