//! Opening input files only when they are regular files (symlinks to one included). Opening a
//! FIFO for reading blocks until a writer appears, and a device or socket is never a mesh: every
//! reader goes through here, so a bad path is an error naming what it is, never a hang.

use std::fs::File;
use std::path::Path;

use crate::error::{Error, Result, err};

/// What a non-regular file is, in words ("a FIFO", "a directory", ...).
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else {
        "not a regular file"
    }
}

/// Fails unless `path` exists and is a regular file (after following symlinks).
pub fn check_regular_file(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, "read", e))?;
    if meta.is_file() {
        return Ok(());
    }
    Err(err!(Unsupported, "is {}: expected a regular file", kind_of(&meta)).in_file(path))
}

/// Whether something (anything: file, folder, FIFO, dangling symlink) is at `path`.
pub fn exists_at(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok()
}

/// Opens a regular file for reading.
pub fn open_regular_file(path: &Path) -> Result<File> {
    check_regular_file(path)?;
    File::open(path).map_err(|e| Error::io(path, "read", e))
}

/// Reads a regular file whole.
pub fn read_regular_file(path: &Path) -> Result<Vec<u8>> {
    check_regular_file(path)?;
    std::fs::read(path).map_err(|e| Error::io(path, "read", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifos_and_folders_are_refused_without_blocking() {
        let d = tempfile::tempdir().unwrap();
        let fifo = d.path().join("p.obj");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let e = read_regular_file(&fifo).unwrap_err();
        assert_eq!(e.to_string(), format!("{}: is a FIFO (named pipe): expected a regular file", fifo.display()));
        let e = open_regular_file(d.path()).unwrap_err().to_string();
        assert!(e.ends_with("is a directory: expected a regular file"), "{e}");
        let f = d.path().join("f");
        std::fs::write(&f, b"x").unwrap();
        assert_eq!(read_regular_file(&f).unwrap(), b"x");
        assert!(exists_at(&fifo) && !exists_at(&d.path().join("none")));
    }
}
