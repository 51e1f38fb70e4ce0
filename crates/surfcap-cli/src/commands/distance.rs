//! `surfcap distance <subject> --metric deformation|deformation-log|euclidean -o d.npy`

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_mesh::npy::write_npy;

use crate::options::{CacheOpts, DistanceOpts, SubjectArgs};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub distance: DistanceOpts,
    /// The .npy file to write (F x F float64, global frame order; see `surfcap info`).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.subject.path])?;
    let subject = a.subject.open(ctx)?;
    let params = a.distance.params();
    let pipe = a.cache.pipeline(ctx, subject)?;
    let t0 = Instant::now();
    let d = pipe.distances(&params)?;
    let secs = t0.elapsed().as_secs_f64();
    let n = d.value.n;
    let values = &d.value.values;
    surfcap_mesh::atomic::write_file(&a.output, |w| write_npy(w, &[n, n], values))
        .with_context(|| format!("writing {}", a.output.display()))?;
    let off = (0..n).flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| values[i * n + j]));
    let mean = crate::output::mean(off.clone());
    let max = off.fold(0.0, f64::max);
    let s = pipe.subject();
    let scale = scale(params.metric, params.w, s.topology().n_triangles(), &s.units, mean);
    let result = json!({
        "output": a.output, "frames": n, "metric": params.metric.name(), "w": params.w,
        "cached": d.from_cache, "cache_file": d.file, "seconds": secs, "mean": mean, "max": max,
        "scale": scale,
    });
    ctx.result(&result, || {
        println!(
            "{n} x {n} {} distances -> {} ({}, {secs:.2} s; mean {mean:.4}, max {max:.4})",
            params.metric.name(),
            a.output.display(),
            if d.from_cache { "from cache" } else { "computed" }
        );
        println!("scale: {scale}");
    });
    Ok(())
}

/// What a distance value means (thesis eq. 2.2, 2.13-2.14): the deformation distances add one
/// term per triangle, so their size grows with the mesh; divided by the triangle count, the
/// rotation term is the mean angle, in radians, by which a triangle turns between the poses.
fn scale(metric: PoseMetric, w: f64, triangles: usize, units: &surfcap_mesh::Units, mean: f64) -> String {
    match metric {
        PoseMetric::Euclidean => {
            let unit = units.symbol();
            format!(
                "a distance is the sum over the vertices of the squared distance between the two poses after the best rotation about the up axis and ground-plane shift (eq. 2.2), in {unit} squared"
            )
        }
        PoseMetric::Deformation | PoseMetric::DeformationLog | PoseMetric::DeformationLiteral => {
            let stretch = if metric == PoseMetric::DeformationLog { "||log S||" } else { "||S - I||" };
            let per = mean / triangles.max(1) as f64;
            format!(
                "a distance is the sum over the {triangles} triangles of the angle (radians) by which each turns between the two poses plus {w} x its stretch {stretch} (eq. {}); divided by {triangles}, the mean {mean:.1} is {per:.3} rad ({:.1} degrees) per triangle",
                match metric {
                    PoseMetric::DeformationLog => "2.14",
                    PoseMetric::DeformationLiteral => "2.13, with eq. 2.6 read literally as A^-1 B",
                    _ => "2.13",
                },
                per.to_degrees()
            )
        }
    }
}
