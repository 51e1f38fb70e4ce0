//! One file per subcommand.

pub mod bench;
pub mod bench_learn;
pub mod demo;
pub mod distance;
pub mod eval;
pub mod eval_gpdm;
pub mod eval_pose_metric;
pub mod eval_transitions;
pub mod export;
pub mod graph;
pub mod import;
pub mod info;
pub mod interpolate;
pub mod report;
pub mod synth;
pub mod synth_walk;
pub mod transition;
pub mod transitions;
pub mod view;

use std::path::Path;

use surfcap_mesh::import::ImportOptions;
use surfcap_mesh::{Units, UpAxis};

/// Options that say what the sources do not (shared by import, info and export).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SourceOpts {
    /// Frame rate, when the sources do not give it (or to override them).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Up axis: +x, +y, +z, -x, -y or -z.
    #[arg(long, value_parser = parse_up)]
    pub up_axis: Option<UpAxis>,
    /// Length unit: m, cm, mm, in, or any other word for arbitrary units.
    #[arg(long)]
    pub units: Option<String>,
}

fn parse_up(s: &str) -> Result<UpAxis, String> {
    UpAxis::parse(s).map_err(|e| e.message)
}

impl SourceOpts {
    pub fn to_import(&self, name: Option<String>) -> anyhow::Result<ImportOptions> {
        if let Some(f) = self.fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
            anyhow::bail!("--fps {f}: expected a positive number of frames per second");
        }
        Ok(ImportOptions { name, fps: self.fps, up_axis: self.up_axis, units: self.units.as_deref().map(Units::parse) })
    }
}

/// Opens a subject (cache or any importable source) with a progress bar and shows the notes.
pub fn open(ctx: &crate::Ctx, path: &Path, opts: &SourceOpts) -> anyhow::Result<surfcap_mesh::Subject> {
    let bar = crate::progress::Bar::new(ctx);
    let imported = surfcap_mesh::import::open_subject(path, &opts.to_import(None)?, &bar)?;
    for n in &imported.notes {
        ctx.note(n);
    }
    Ok(imported.subject)
}

/// Prints a JSON value on stdout.
pub fn print_json(v: &serde_json::Value) {
    println!("{}", serde_json::to_string_pretty(v).expect("JSON values always serialise"));
}

/// Every file under the folder `dir` (recursively) whose extension is one of `extensions`,
/// sorted.
pub fn files_under(dir: &Path, extensions: &[&str]) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| anyhow::anyhow!("reading the folder {}: {e}", d.display()))?;
        for e in entries {
            let f = e?.path();
            if f.is_dir() {
                stack.push(f);
            } else if f.extension().is_some_and(|x| extensions.iter().any(|k| x == *k)) {
                out.push(f);
            }
        }
    }
    out.sort();
    Ok(out)
}
