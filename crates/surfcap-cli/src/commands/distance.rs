//! `surfcap distance <subject> --metric deformation|deformation-log|euclidean -o d.npy`

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_mesh::Subject;
use surfcap_mesh::derived_cache::{DerivedCache, subject_hash};
use surfcap_mesh::io::npy::{NpyArray, write_npy};

use super::{SourceOpts, print_json};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// deformation (thesis eq. 2.13), deformation-log (eq. 2.14) or euclidean (eq. 2.2).
    #[arg(long, default_value = "deformation", value_parser = parse_metric)]
    pub metric: MetricArg,
    /// Weight of the stretch term (eq. 2.13).
    #[arg(long, default_value_t = 0.01)]
    pub w: f64,
    /// The .npy file to write (F x F float64, global frame order; see `surfcap info`).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

#[derive(Debug, Clone, Copy)]
pub struct MetricArg(pub PoseMetric);

fn parse_metric(s: &str) -> Result<MetricArg, String> {
    PoseMetric::parse(s)
        .map(MetricArg)
        .ok_or_else(|| format!("{s:?}: expected deformation, deformation-log or euclidean"))
}

/// Where derived matrices are cached.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct CacheOpts {
    /// Cache folder for derived matrices (default: $XDG_CACHE_HOME/surfcap or ~/.cache/surfcap).
    #[arg(long)]
    pub cache_dir: Option<PathBuf>,
    /// Recompute even if a cached result exists.
    #[arg(long)]
    pub no_cache: bool,
}

impl CacheOpts {
    pub fn cache(&self) -> DerivedCache {
        let dir = self.cache_dir.clone().unwrap_or_else(|| {
            std::env::var_os("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))
                .unwrap_or_else(|| PathBuf::from(".cache"))
                .join("surfcap")
        });
        DerivedCache::new(dir)
    }
}

/// Where the distance matrix of `subject` with `params` is (or would be) cached.
pub fn distance_cache_path(subject: &Subject, params: &DistanceParams, cache: &CacheOpts) -> PathBuf {
    let key = format!("metric={} w={} weights=none algo=1", params.metric.name(), params.w);
    cache.cache().path(&format!("distance-{}", params.metric.name()), &subject_hash(subject), &key)
}

/// The distance matrix of a subject, from the cache when possible. Returns it, whether it was
/// cached, and the cache file.
pub fn cached_distance_matrix(
    ctx: &crate::Ctx,
    subject: &Subject,
    params: &DistanceParams,
    cache: &CacheOpts,
) -> anyhow::Result<(NpyArray<f64>, bool, PathBuf)> {
    let store = cache.cache();
    let path = distance_cache_path(subject, params, cache);
    if cache.no_cache {
        let _ = std::fs::remove_file(&path);
    }
    let bar = crate::progress::Bar::new(ctx);
    let (a, cached) = store.get_or_compute(&path, || {
        let d = distance_matrix(subject, params, &bar);
        Ok::<_, surfcap_mesh::Error>(NpyArray { shape: vec![d.n, d.n], data: d.values })
    })?;
    Ok((a, cached, path))
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let subject = super::open(ctx, &a.subject, &a.source)?;
    let params = DistanceParams { metric: a.metric.0, w: a.w, vertex_weights: None };
    let t0 = Instant::now();
    let (m, cached, cache_path) = cached_distance_matrix(ctx, &subject, &params, &a.cache)?;
    let secs = t0.elapsed().as_secs_f64();
    surfcap_mesh::atomic::write_file(&a.output, |w| write_npy(w, &m.shape, &m.data))
        .with_context(|| format!("writing {}", a.output.display()))?;
    let n = m.shape[0];
    let off: Vec<f64> = (0..n)
        .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
        .map(|(i, j)| m.data[i * n + j])
        .collect();
    let mean = off.iter().sum::<f64>() / off.len().max(1) as f64;
    let max = off.iter().cloned().fold(0.0, f64::max);
    if ctx.json {
        print_json(&json!({
            "output": a.output, "frames": n, "metric": params.metric.name(), "w": params.w,
            "cached": cached, "cache_file": cache_path, "seconds": secs, "mean": mean, "max": max,
        }));
    } else {
        println!(
            "{} x {n} {} distances -> {} ({}, {secs:.2} s; mean {mean:.4}, max {max:.4})",
            n,
            params.metric.name(),
            a.output.display(),
            if cached { "from cache" } else { "computed" }
        );
    }
    Ok(())
}
