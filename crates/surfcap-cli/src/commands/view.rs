//! `surfcap view`: plays sequences in the browser (see `surfcap-view`). Accepts anything
//! `surfcap import` reads (a glb, a subject cache, a capture folder) and report folders written
//! by `surfcap report` or `surfcap demo`; several at once play side by side.

use std::io::Write;
use std::path::{Path, PathBuf};

use surfcap_mesh::Subject;
use surfcap_view::server::{ServeOptions, serve};
use surfcap_view::{Overlay, ViewItem};

use crate::options::{SourceOpts, open};
use crate::output::print_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to play: .glb files, subject caches, capture folders, or a report folder.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// Port on 127.0.0.1 (default: any free one; the URL is printed).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Only these sequences (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// Whether `p` is a report folder (an `index.html` and no subject cache).
fn is_report(p: &Path) -> bool {
    p.is_dir() && p.join("index.html").is_file() && !surfcap_mesh::cache::is_cache(p)
}

/// The achieved centres (and the requested path, when there is one) a synthesis report
/// (`x.report.json` next to `x.glb`) holds.
fn overlay_of(glb: &Path, frames: usize) -> Option<Overlay> {
    let report = crate::synthesis::report_path(glb);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(report).ok()?).ok()?;
    let points = |x: &serde_json::Value| -> Option<Vec<[f64; 3]>> {
        x.as_array()?.iter().map(|p| Some([p[0].as_f64()?, p[1].as_f64()?, p[2].as_f64()?])).collect()
    };
    let curve = points(&v["curve"]);
    let centres = points(&v["per_frame"]["centre"])?;
    (centres.len() == frames).then_some(Overlay { curve, centres })
}

fn items_of(s: &Subject, only: &[String], glb: Option<&Path>) -> Vec<ViewItem> {
    let single = s.sequences().len() == 1;
    let mut items = crate::view_items::view_items(s, only);
    for item in &mut items {
        item.overlay = glb.filter(|_| single).and_then(|g| overlay_of(g, item.n_frames));
    }
    items
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let mut items = Vec::new();
    let mut report = None;
    for p in &a.paths {
        anyhow::ensure!(p.exists(), "view {}: no such file or folder", p.display());
        if is_report(p) {
            anyhow::ensure!(report.is_none(), "view {}: only one report folder at a time", p.display());
            let glbs = crate::files::files_under(p, &["glb"])?;
            anyhow::ensure!(!glbs.is_empty(), "view {}: the report folder holds no .glb animation", p.display());
            for g in glbs {
                let s = open(ctx, &g, &a.source)?;
                items.extend(items_of(&s, &a.sequences, Some(&g)));
            }
            report = Some(p.clone());
        } else {
            let s = open(ctx, p, &a.source)?;
            let glb = p.extension().is_some_and(|x| x == "glb").then_some(p.as_path());
            items.extend(items_of(&s, &a.sequences, glb));
        }
    }
    anyhow::ensure!(!items.is_empty(), "view: no sequence named {} in what was given", a.sequences.join(", "));
    let n = items.len();
    let json = ctx.json;
    serve(items, ServeOptions { port: a.port, report }, |addr| {
        let url = format!("http://{addr}/");
        if json {
            print_json(&serde_json::json!({ "url": url, "sequences": n }));
        } else {
            println!("{url}");
            eprintln!("surfcap view: playing {} at {url} (Ctrl-C to stop)", crate::output::count_of(n, "sequence"));
        }
        let _ = std::io::stdout().flush();
    })?;
    Ok(())
}
