//! Finding files in folders given on the command line.

use std::path::{Path, PathBuf};

/// Every file under the folder `dir` (recursively) whose extension is one of `extensions`,
/// sorted. Hidden entries are skipped: surfcap's output markers (`.surfcap-output.json`) and
/// temporaries (`.NAME.tmp-PID`) are not results.
pub fn files_under(dir: &Path, extensions: &[&str]) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| anyhow::anyhow!("reading the folder {}: {e}", d.display()))?;
        for e in entries {
            let f = e?.path();
            if f.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')) {
                continue;
            }
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
