//! The evaluation folder every `surfcap eval` command writes: claimed before any work, then the
//! report (JSON, with the files written beside it) and the `wrote ...` line.

use std::path::{Path, PathBuf};

use crate::output::write_json;

/// Refuses an output that overlaps one of the inputs, then makes it an evaluation folder of
/// `kind` (refused when surfcap did not write it, unless `--force`), filled in its temporary
/// and put in place whole when the returned set is committed (`crate::Ctx::commit`).
pub fn claim(
    ctx: &crate::Ctx,
    output: &Path,
    inputs: &[&Path],
    kind: &str,
) -> anyhow::Result<surfcap_mesh::output_set::OutputSet> {
    Ok(ctx.claim_dir(output, kind, inputs)?.0)
}

/// Writes an evaluation's report to `dir/name`: `result` as JSON with the files the command
/// wrote beside it added under `files_key`. Returns the report and its path.
pub fn save_report<T: serde::Serialize>(
    dir: &Path,
    name: &str,
    result: &T,
    files_key: &str,
    files: &[PathBuf],
) -> anyhow::Result<(serde_json::Value, PathBuf)> {
    let mut report = serde_json::to_value(result)?;
    report[files_key] = serde_json::to_value(files)?;
    let path = dir.join(name);
    write_json(&path, &report)?;
    Ok((report, path))
}

/// `wrote <report>, <plot>, <plot>...`
pub fn print_wrote(report: &Path, plots: &[PathBuf]) {
    let files: Vec<String> =
        std::iter::once(report).chain(plots.iter().map(PathBuf::as_path)).map(|p| p.display().to_string()).collect();
    println!("wrote {}", files.join(", "));
}
