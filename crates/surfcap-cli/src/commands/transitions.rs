//! `surfcap transitions <subject> -o dir/`: the all-pairs transition table (thesis 2.5.3-2.5.4).

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_mesh::npy::write_npy;

use crate::options::{CacheOpts, SubjectArgs, TableOpts};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder for D.npy (normalised costs), L.npy (durations), li.npy, lj.npy (segment lengths).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (outs, _) = ctx.claim_dir(&a.output, "transitions", &[&a.subject.path])?;
    let s = a.subject.open(ctx)?;
    let pipe = a.cache.pipeline(ctx, s)?;
    let p = a.table.params_for(&pipe)?;
    let t0 = Instant::now();
    let fetched = pipe.table(&p)?;
    let secs = t0.elapsed().as_secs_f64();
    let t = &fetched.value;
    let n = t.n;
    let w = |name: &str, f: &dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()>| {
        surfcap_mesh::atomic::write_file(&a.output.join(name), |out| f(out))
    };
    w("D.npy", &|o| write_npy(o, &[n, n], &t.cost))?;
    w("L.npy", &|o| write_npy(o, &[n, n], &t.len))?;
    w("li.npy", &|o| write_npy(o, &[n, n], &t.li))?;
    w("lj.npy", &|o| write_npy(o, &[n, n], &t.lj))?;
    let finite: Vec<f64> = t.cost.iter().copied().filter(|c| c.is_finite()).collect();
    let mean = crate::output::mean(finite.iter().copied());
    ctx.commit(outs)?;
    let result = json!({
        "frames": n, "pairs_with_transitions": finite.len(), "mean_cost": mean,
        "l_min": p.l_min, "l_max": p.l_max, "slope": p.slope, "seconds": secs, "cached": fetched.from_cache,
        "files": ["D.npy", "L.npy", "li.npy", "lj.npy"],
    });
    ctx.result(&result, || {
        println!(
            "{n} x {n} transitions (segments {}..{} frames, slope {}): {} pairs possible, mean normalised cost {mean:.3} -> {} ({}, {secs:.2} s)",
            p.l_min,
            p.l_max,
            p.slope.map_or("inf".into(), |p| p.to_string()),
            finite.len(),
            a.output.display(),
            if fetched.from_cache { "from cache" } else { "computed" }
        )
    });
    Ok(())
}
