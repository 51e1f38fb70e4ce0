//! `surfcap eval interchange`: every sequence of the data folder through Alembic and USD and back
//! (`surfcap_eval::interchange_eval` does it; this command writes
//! `interchange.json`, prints one line per dataset and format and every round trip that was not
//! exact, and fails when any was not).

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Context;
use surfcap_eval::interchange_eval::{InterchangeOptions, interchange_eval};
use surfcap_formats::export::ExportFormat;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("datasets as sub-folders"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Only these datasets (folder names, comma-separated; default: all).
    #[arg(long, value_delimiter = ',')]
    pub datasets: Vec<String>,
    /// Formats to go through.
    #[arg(long, value_delimiter = ',', default_value = "abc,usda")]
    pub formats: Vec<ExportFormat>,
    /// Folder for the report (interchange.json); the exported files go to a temporary
    /// folder and are removed once read back.
    #[arg(short, long, default_value = "interchange-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.data], "eval-interchange")?;
    let Args { data, datasets, formats, output } = a;
    let output = output.as_path();
    let scratch = tempfile::tempdir().context("creating a temporary folder")?;
    let opts = InterchangeOptions { data, datasets, formats, scratch: scratch.path().to_path_buf(), default_fps: 30.0 };
    let bar = crate::progress::Bar::new(ctx);
    let r = interchange_eval(&opts, &bar)?;
    let (report, path) = super::folder::save_report(output, "interchange.json", &r, "written", &[])?;
    ctx.result(&report, || {
        // Per dataset and format: sequences, frames, exact ones, bytes, write and read time.
        // (sequences, frames, exact, bytes, write seconds, read seconds)
        type Totals = (usize, usize, usize, u64, f64, f64);
        let mut rows: BTreeMap<(String, String), Totals> = BTreeMap::new();
        for t in &r.round_trips {
            let e = rows.entry((t.dataset.clone(), t.format.clone())).or_default();
            *e = (
                e.0 + 1,
                e.1 + t.frames,
                e.2 + usize::from(t.exact),
                e.3 + t.bytes,
                e.4 + t.write_seconds,
                e.5 + t.read_seconds,
            );
        }
        println!(
            "{:<24} {:<6} {:>9} {:>7} {:>7} {:>10} {:>8} {:>8}",
            "dataset", "format", "sequences", "frames", "exact", "MB", "write s", "read s"
        );
        for ((d, f), (n, frames, exact, bytes, w, rd)) in &rows {
            println!("{d:<24} {f:<6} {n:>9} {frames:>7} {exact:>7} {:>10.1} {w:>8.2} {rd:>8.2}", *bytes as f64 / 1e6);
        }
        for s in &r.skipped {
            println!("skipped {}: {}", s.dataset, s.reason);
        }
        for t in r.round_trips.iter().filter(|t| !t.exact) {
            println!(
                "NOT EXACT {} {} as {}: {}",
                t.dataset,
                t.sequence,
                t.format,
                t.difference.as_deref().unwrap_or("")
            );
        }
        println!(
            "{} sequences ({} frames) through {}: {} round trips, {} not exact; wrote {}",
            r.sequences,
            r.frames,
            r.formats.join(", "),
            r.round_trips.len(),
            r.not_exact,
            path.display()
        );
    });
    // The report is the result even when a round trip is not exact: it is committed first.
    ctx.commit(outs)?;
    if r.not_exact > 0 {
        anyhow::bail!("{} of {} round trips were not exact (see {})", r.not_exact, r.round_trips.len(), path.display());
    }
    Ok(())
}
