//! `surfcap transitions <subject> -o dir/`: the all-pairs transition table (thesis 2.5.3-2.5.4).

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_mesh::Subject;
use surfcap_mesh::derived_cache::subject_hash;
use surfcap_mesh::io::npy::{NpyArray, write_npy};
use surfcap_motion::dtw::Slope;
use surfcap_motion::segment_bounds;
use surfcap_motion::transition_table::{TableParams, TransitionTable, transition_table};

use super::distance::{CacheOpts, cached_distance_matrix};
use super::{SourceOpts, print_json};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// Folder for D.npy (normalised costs), L.npy (durations), li.npy, lj.npy (segment lengths).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// Options of a transition table.
#[derive(clap::Args, Debug, Clone)]
pub struct TableOpts {
    /// Slope constraint p of the warping path (thesis eq. 2.53; "inf" for none).
    #[arg(long, default_value = "3", value_parser = parse_slope)]
    pub slope: SlopeArg,
    /// Shortest segment, frames (default: a third of a second at the subject's fps).
    #[arg(long)]
    pub l_min: Option<usize>,
    /// Longest segment, frames (default: two seconds).
    #[arg(long)]
    pub l_max: Option<usize>,
}

#[derive(Debug, Clone, Copy)]
pub struct SlopeArg(pub Slope);

pub fn parse_slope(s: &str) -> Result<SlopeArg, String> {
    match s {
        "inf" | "infinity" => Ok(SlopeArg(None)),
        _ => match s.parse::<usize>() {
            Ok(p) if p >= 1 => Ok(SlopeArg(Some(p))),
            _ => Err(format!("{s:?}: expected a whole number >= 1 or inf")),
        },
    }
}

impl TableOpts {
    pub fn params(&self, fps: f64) -> anyhow::Result<TableParams> {
        let (lo, hi) = segment_bounds(fps);
        let (l_min, l_max) = (self.l_min.unwrap_or(lo), self.l_max.unwrap_or(hi));
        anyhow::ensure!(1 <= l_min && l_min <= l_max, "segment lengths {l_min}..{l_max}: expected 1 <= l-min <= l-max");
        Ok(TableParams { l_min, l_max, slope: self.slope.0 })
    }
}

/// The deformation distance matrix and the transition table of a subject, both cached.
pub fn cached_table(
    ctx: &crate::Ctx,
    s: &Subject,
    p: &TableParams,
    cache: &CacheOpts,
) -> anyhow::Result<(TransitionTable, bool)> {
    let (d, _, _) = cached_distance_matrix(ctx, s, &DistanceParams::default(), cache)?;
    let store = cache.cache();
    let key = format!("distance=deformation w=0.01 l={}..{} slope={:?} algo=1", p.l_min, p.l_max, p.slope);
    let path = store.path("transitions", &subject_hash(s), &key);
    if cache.no_cache {
        let _ = std::fs::remove_file(&path);
    }
    let n = s.n_frames();
    let bar = crate::progress::Bar::new(ctx);
    let (a, cached) = store.get_or_compute(&path, || {
        let t = transition_table(&d.data, s.frame_index(), p, &bar);
        let mut data = t.cost.clone();
        data.extend(t.len.iter().map(|&x| x as f64));
        data.extend(t.li.iter().map(|&x| x as f64));
        data.extend(t.lj.iter().map(|&x| x as f64));
        Ok::<_, surfcap_mesh::Error>(NpyArray { shape: vec![4, n, n], data })
    })?;
    anyhow::ensure!(a.shape == [4, n, n], "cached transition table has shape {:?}, expected [4, {n}, {n}]", a.shape);
    let part = |k: usize| &a.data[k * n * n..(k + 1) * n * n];
    let table = TransitionTable {
        n,
        cost: part(0).to_vec(),
        len: part(1).iter().map(|&x| x as u32).collect(),
        li: part(2).iter().map(|&x| x as u32).collect(),
        lj: part(3).iter().map(|&x| x as u32).collect(),
    };
    Ok((table, cached))
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let s = super::open(ctx, &a.subject, &a.source)?;
    let p = a.table.params(s.fps)?;
    let t0 = Instant::now();
    let (t, cached) = cached_table(ctx, &s, &p, &a.cache)?;
    let secs = t0.elapsed().as_secs_f64();
    let n = t.n;
    std::fs::create_dir_all(&a.output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", a.output.display()))?;
    let w = |name: &str, f: &dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()>| {
        surfcap_mesh::atomic::write_file(&a.output.join(name), |out| f(out))
    };
    w("D.npy", &|o| write_npy(o, &[n, n], &t.cost))?;
    w("L.npy", &|o| write_npy(o, &[n, n], &t.len))?;
    w("li.npy", &|o| write_npy(o, &[n, n], &t.li))?;
    w("lj.npy", &|o| write_npy(o, &[n, n], &t.lj))?;
    let finite: Vec<f64> = t.cost.iter().copied().filter(|c| c.is_finite()).collect();
    let mean = finite.iter().sum::<f64>() / finite.len().max(1) as f64;
    let report = json!({
        "frames": n, "pairs_with_transitions": finite.len(), "mean_cost": mean,
        "l_min": p.l_min, "l_max": p.l_max, "slope": p.slope, "seconds": secs, "cached": cached,
        "files": ["D.npy", "L.npy", "li.npy", "lj.npy"],
    });
    if ctx.json {
        print_json(&report);
    } else {
        println!(
            "{n} x {n} transitions (segments {}..{} frames, slope {}): {} pairs possible, mean normalised cost {mean:.3} -> {} ({}, {secs:.2} s)",
            p.l_min,
            p.l_max,
            p.slope.map_or("inf".into(), |p| p.to_string()),
            finite.len(),
            a.output.display(),
            if cached { "from cache" } else { "computed" }
        );
    }
    Ok(())
}
