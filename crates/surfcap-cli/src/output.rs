//! How every command reports: one place decides what `--json` and `--quiet` show.
//!
//! - results (a command's summary, the files it wrote): as JSON on stdout with `--json`, else
//!   as text on stdout, `--quiet` included (`--quiet` hides progress and notes, not results);
//! - notes (assumptions, hints) and narration (the demo's steps): on stderr and stdout
//!   respectively, hidden by `--quiet` and `--json`;
//! - progress bars: `crate::progress::Bar`, hidden by `--quiet` and `--json`.

use std::path::{Path, PathBuf};

use serde::Serialize;
use surfcap_formats::export::ExportOptions;
use surfcap_mesh::output_set::OutputSet;

/// What every command gets: how to report.
pub struct Ctx {
    pub quiet: bool,
    pub json: bool,
    /// `--force`: a folder output may replace a folder surfcap did not write.
    pub force: bool,
    /// `--max-memory`, bytes: most memory a request may need (default half the memory available).
    pub max_memory: Option<u64>,
    /// `--max-disk`, bytes: most a command may write (default the free space of its output's
    /// file system).
    pub max_disk: Option<u64>,
    /// Whether results, `wrote` lines and narration are printed (false when a command runs
    /// others in-process and reports them its own way: `surfcap reproduce`).
    pub results: bool,
}

impl Ctx {
    /// The limits a request is checked against before any work: `--max-memory` and
    /// `--max-disk`, the memory available now (/proc/meminfo) and the free space where `output`
    /// goes (statvfs).
    pub fn budget(&self, output: Option<&Path>) -> surfcap_mesh::sizing::Budget {
        surfcap_mesh::sizing::Budget {
            max_memory: self.max_memory,
            available_memory: crate::limits::mem_available(),
            max_disk: self.max_disk,
            free_disk: output.and_then(crate::limits::free_disk),
        }
    }

    /// Refuses `estimate` when it exceeds [`Ctx::budget`], with the size, the limit and the
    /// option that raises it.
    pub fn check_size(&self, estimate: &surfcap_mesh::sizing::Estimate, output: Option<&Path>) -> anyhow::Result<()> {
        Ok(self.budget(output).check(estimate)?)
    }

    /// Export options honouring `--force`.
    pub fn export_options(&self) -> ExportOptions {
        ExportOptions { force: self.force, ..Default::default() }
    }

    /// Plans `dir` as the folder output of `kind` the command fills file by file (refused when
    /// it overlaps `inputs`, or is a folder surfcap did not write unless `--force`), and starts
    /// it: the files go to its temporary, which replaces `dir` whole, marker included, only at
    /// [`Ctx::commit`]. Returns the set and the folder's path to write under.
    pub fn claim_dir(&self, dir: &Path, kind: &str, inputs: &[&Path]) -> anyhow::Result<(OutputSet, PathBuf)> {
        let mut set = OutputSet::new(inputs);
        set.dir(dir, kind, self.force)?;
        let path = surfcap_mesh::output_path::claim_dir(dir, kind, self.force)?;
        Ok((set, path))
    }

    /// Commits a command's planned outputs together (`surfcap_mesh::output_set`); a previous
    /// folder that could not be removed afterwards is named.
    pub fn commit(&self, set: OutputSet) -> anyhow::Result<()> {
        let done = set.commit()?;
        for (output, kept) in done.kept_previous {
            eprintln!(
                "warning: {} replaced, but its previous folder could not be removed: it is kept as {}",
                output.display(),
                kept.display()
            );
        }
        Ok(())
    }

    /// A note for humans (assumptions, hints) on stderr; silent with --quiet or --json.
    pub fn note(&self, text: &str) {
        if !self.quiet && !self.json {
            eprintln!("note: {text}");
        }
    }

    /// Narration of a long job's steps; silent with --quiet or --json.
    pub fn say(&self, text: &str) {
        if self.results && !self.quiet && !self.json {
            println!("{text}");
        }
    }

    /// A command's result: `value` as JSON with --json, else the human text `human` prints.
    pub fn result<T: Serialize + ?Sized>(&self, value: &T, human: impl FnOnce()) {
        if !self.results {
            return;
        }
        if self.json {
            print_json(value);
        } else {
            human();
        }
    }

    /// `wrote <file>` for each file, unless --json (the JSON result lists them).
    pub fn wrote<'a>(&self, files: impl IntoIterator<Item = &'a PathBuf>) {
        if self.results && !self.json {
            for f in files {
                println!("wrote {}", f.display());
            }
        }
    }
}

/// A length in the subject's units, as "3.00 m" (or "3.00 units" when the subject's units are
/// arbitrary), `decimals` after the point: a bare "3.00-long" left the user guessing the scale.
pub fn length(x: f64, units: &surfcap_mesh::Units, decimals: usize) -> String {
    format!("{:.decimals$} {}", x + 0.0, unit_name(units))
}

/// The name lengths are given in: the unit's symbol, or "units" when it has no known size
/// ([`surfcap_mesh::Units::symbol`]).
pub fn unit_name(units: &surfcap_mesh::Units) -> &str {
    units.symbol()
}

/// The `units` line of `surfcap info`: the symbol lengths are written in, with its size in
/// metres when that is not 1, or the source's own word for arbitrary units.
pub fn units_line(units: &surfcap_mesh::Units) -> String {
    match units.metres_per_unit {
        Some(1.0) => units.symbol().to_string(),
        Some(m) => format!("{} ({m} m)", units.symbol()),
        None => format!("units (not metric: {:?})", units.name),
    }
}

/// `n` and `word`, with an "s" unless `n` is 1 ("1 sequence", "2 sequences").
pub fn count_of(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// The mean of `values`, 0 for none. (Rust's float sum of nothing is -0.0, which printed as
/// "mean -0.0000".)
pub fn mean(values: impl IntoIterator<Item = f64>) -> f64 {
    let (sum, n) = values.into_iter().fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// Prints a serialisable value as pretty JSON on stdout.
pub fn print_json<T: Serialize + ?Sized>(v: &T) {
    println!("{}", serde_json::to_string_pretty(v).expect("results always serialise"));
}

/// Writes a serialisable value as pretty JSON (a final newline) to `path`, atomically.
pub fn write_json<T: Serialize + ?Sized>(path: &std::path::Path, v: &T) -> anyhow::Result<()> {
    surfcap_mesh::atomic::write_file(path, |w| {
        serde_json::to_writer_pretty(&mut *w, v).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(())
}
