//! `surfcap-bench cache`: what verifying a derived-cache entry's content hash costs when it is
//! read. Each entry is read as the pipeline reads it (`DerivedCache::read`: open without
//! following links, parse the `.npy` into its array) with its BLAKE3 hash computed on the way
//! and compared with its sidecar, and without; the best of `--repeat` reads of each is
//! reported in ms and GB/s of file. The files were just written, so they are read from the page
//! cache: the difference is the hash's CPU cost, not the disk's.
//!
//! Entries: the pose distance matrix of `--subject` (the crane of vlasic2008 by default, when
//! the shared data is there), computed into a temporary cache first; and a transition table of
//! `--frames` frames (f64 `[4, F, F]`, 128 MB at 2,000), filled with seeded values (reading
//! does not depend on them).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use rand::{Rng, SeedableRng};
use serde_json::json;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_mesh::NoProgress;
use surfcap_mesh::cache_entry::{EntryRead, store_file_entry};
use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_mesh::npy::write_npy;
use surfcap_pipeline::{CacheStore, Pipeline};

use crate::measure::FpsOpt;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The subject whose distance matrix is read (default: vlasic2008/crane in $SURFCAP_DATA, else
    /// in the shared/data folder beside the checkout).
    #[arg(long)]
    pub subject: Option<PathBuf>,
    /// Frames of the transition table entry.
    #[arg(long, default_value_t = 2000, value_parser = |s: &str| crate::options::whole_in(s, 2, 20_000))]
    pub frames: usize,
    /// Reads of each entry, each way (the best is reported).
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::whole_in(s, 1, 1000))]
    pub repeat: usize,
    #[command(flatten)]
    pub fps: FpsOpt,
}

/// Best seconds of `repeat` reads of `path`, verified or not.
fn best_read(cache: &DerivedCache, path: &Path, verify: bool, repeat: usize) -> anyhow::Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..repeat {
        let t = Instant::now();
        match cache.read::<f64>(path, verify) {
            EntryRead::Read(a) => {
                std::hint::black_box(a.data.len());
            }
            EntryRead::Missing => anyhow::bail!("{}: no entry", path.display()),
            EntryRead::Unusable(e) => anyhow::bail!("{e}"),
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok(best)
}

/// The report of one entry.
fn measure(
    ctx: &crate::Ctx,
    what: &str,
    cache: &DerivedCache,
    path: &Path,
    repeat: usize,
) -> anyhow::Result<serde_json::Value> {
    let bytes = std::fs::metadata(path).with_context(|| format!("{}", path.display()))?.len();
    // A first read warms the page cache.
    best_read(cache, path, true, 1)?;
    let plain = best_read(cache, path, false, repeat)?;
    let verified = best_read(cache, path, true, repeat)?;
    let gbs = |s: f64| bytes as f64 / s / 1e9;
    ctx.say(&format!(
        "{what}: {:.1} MB; read {:.1} ms ({:.2} GB/s), read and verified {:.1} ms ({:.2} GB/s): the hash adds {:.1} ms ({:+.0}%)",
        bytes as f64 / 1e6,
        plain * 1e3,
        gbs(plain),
        verified * 1e3,
        gbs(verified),
        (verified - plain) * 1e3,
        100.0 * (verified / plain - 1.0)
    ));
    Ok(json!({
        "entry": what, "bytes": bytes,
        "read_ms": plain * 1e3, "read_gb_per_s": gbs(plain),
        "verified_ms": verified * 1e3, "verified_gb_per_s": gbs(verified),
        "hash_ms": (verified - plain) * 1e3,
    }))
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let tmp = tempfile::tempdir().context("creating a temporary folder")?;
    let dir = tmp.path().join("cache");
    let cache = DerivedCache::new(&dir);
    surfcap_mesh::cache_entry::check_folder(&dir)?;
    let mut reports = Vec::new();

    let subject =
        a.subject.clone().unwrap_or_else(|| crate::options::default_data_dir().join("vlasic2008").join("crane"));
    if subject.exists() {
        let s = a.fps.open_quietly(&subject)?;
        let n = s.n_frames();
        ctx.say(&format!("computing the distance matrix of {} ({n} frames) into a temporary cache", subject.display()));
        let pipe = Pipeline::new(s, CacheStore::in_folder(&dir, false), Box::new(NoProgress));
        let d = pipe.distances(&DistanceParams::default())?;
        let file = d.file.context("the distance matrix was not cached")?;
        reports.push(measure(ctx, &format!("distance matrix {n} x {n}"), &cache, &file, a.repeat)?);
    } else {
        ctx.note(&format!("{}: not found; only the transition table is measured", subject.display()));
    }

    let n = a.frames;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let data: Vec<f64> = (0..4 * n * n).map(|_| rng.random::<f64>()).collect();
    let file = dir.join(format!("transitions-bench-{n}.npy"));
    store_file_entry(&file, |w| write_npy(w, &[4, n, n], &data), &mut |_| {})?;
    drop(data);
    reports.push(measure(ctx, &format!("transition table 4 x {n} x {n}"), &cache, &file, a.repeat)?);

    // The hash alone, on bytes in memory: BLAKE3's rate on this machine.
    let bytes = std::fs::read(&file).with_context(|| format!("{}", file.display()))?;
    let t = Instant::now();
    std::hint::black_box(blake3::hash(&bytes));
    let secs = t.elapsed().as_secs_f64();
    ctx.say(&format!(
        "BLAKE3 alone on {:.1} MB in memory: {:.1} ms ({:.2} GB/s)",
        bytes.len() as f64 / 1e6,
        secs * 1e3,
        bytes.len() as f64 / secs / 1e9
    ));
    ctx.result(&json!({ "entries": reports, "blake3_gb_per_s": bytes.len() as f64 / secs / 1e9 }), || {});
    Ok(())
}
