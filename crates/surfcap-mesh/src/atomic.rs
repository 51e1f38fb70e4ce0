//! Outputs are written to a temporary sibling and renamed into place, so an interrupted run
//! never leaves a half-written file or directory, and a failed run keeps the previous output.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

fn sibling(path: &Path, tag: &str) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.{tag}-{}", std::process::id()))
}

fn ensure_parent(path: &Path) -> Result<()> {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => fs::create_dir_all(p).map_err(|e| Error::io(p, "create directory", e)),
        _ => Ok(()),
    }
}

/// Writes a file through `write`, then renames it onto `path`.
pub fn write_file(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    ensure_parent(path)?;
    let tmp = sibling(path, "tmp");
    let result = (|| {
        let f = fs::File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = fs::remove_file(&tmp);
        Error::io(path, "write", e)
    })
}

/// Builds a directory through `fill` (given the temporary directory), then swaps it in for
/// `path`; a previous directory at `path` is removed only once the new one is complete.
pub fn write_dir(path: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    ensure_parent(path)?;
    if path.is_file() {
        return Err(Error::io(
            path,
            "write directory",
            std::io::Error::new(std::io::ErrorKind::AlreadyExists, "a file is in the way"),
        ));
    }
    let tmp = sibling(path, "tmp");
    let _ = fs::remove_dir_all(&tmp);
    fs::create_dir(&tmp).map_err(|e| Error::io(&tmp, "create directory", e))?;
    if let Err(e) = fill(&tmp) {
        let _ = fs::remove_dir_all(&tmp);
        return Err(e);
    }
    let old = sibling(path, "old");
    let had_old = path.exists();
    if had_old {
        fs::rename(path, &old).map_err(|e| Error::io(path, "move the previous output aside", e))?;
    }
    if let Err(e) = fs::rename(&tmp, path) {
        if had_old {
            let _ = fs::rename(&old, path);
        }
        let _ = fs::remove_dir_all(&tmp);
        return Err(Error::io(path, "rename the new output into place", e));
    }
    if had_old {
        let _ = fs::remove_dir_all(&old);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_writes_keep_the_previous_output() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("a.txt");
        write_file(&f, |w| w.write_all(b"first")).unwrap();
        let r = write_file(&f, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("interrupted"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read(&f).unwrap(), b"first");
        let dir = d.path().join("out");
        write_dir(&dir, |t| write_file(&t.join("x"), |w| w.write_all(b"1"))).unwrap();
        let r = write_dir(&dir, |_| Err(crate::error::Error::new(crate::ErrorKind::Io, "boom")));
        assert!(r.is_err());
        assert_eq!(fs::read(dir.join("x")).unwrap(), b"1");
        assert_eq!(fs::read_dir(d.path()).unwrap().count(), 2, "no temporaries left behind");
    }
}
