//! Outputs are written to a temporary sibling (`.NAME.tmp-PID`) and renamed into place, so an
//! interrupted run never leaves a half-written file or folder, and a failed run keeps the
//! previous output. The output path is resolved first (`crate::output_path`), so `-o .`,
//! `-o ../x` and symlinks name their real place, and what is there is checked before anything is
//! written: a file output replaces only a regular file, a folder output only an empty folder or
//! surfcap's own earlier output of the same kind. Temporaries are registered
//! (`crate::temporaries`) so a front end can remove them on SIGINT/SIGTERM, and stale ones of
//! killed runs are swept before the next write of the same output.
//!
//! A command that writes several outputs plans them in a `crate::output_set::OutputSet`: while
//! it lives, [`write_file`] and [`write_dir`] on a planned path only stage the temporary, and the
//! set renames them all at its commit (or none). A folder output written on its own is a set of
//! one, so its place is re-checked at the swap too: a folder the user made there meanwhile is
//! kept and the new output discarded.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, ErrorKind, Result};
use crate::output_path::{check_file_place, resolve, write_marker};
use crate::output_set::{OutputSet, Staging, set_staged, staging};
use crate::temporaries::{inside_live, register, sibling, sweep_stale};

fn ensure_parent(path: &Path) -> Result<()> {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => fs::create_dir_all(p).map_err(|e| Error::io(p, "create directory", e)),
        _ => Ok(()),
    }
}

/// Writes `tmp` through `write` and syncs it; removes it on failure.
fn write_temporary(tmp: &Path, path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let result = (|| {
        let f = fs::File::create(tmp)?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()
    })();
    result.map_err(|e| {
        let _ = fs::remove_file(tmp);
        Error::io(path, "write", e)
    })
}

/// Writes a file through `write`, then renames it onto `path`. `path` may be new or a regular
/// file (a symlink is written through to its target); anything else is refused. A path planned
/// by a live output set is only staged (renamed at the set's commit).
pub fn write_file(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let path = resolve(path)?;
    let path = match staging(&path)? {
        Some(Staging::File(tmp)) => {
            ensure_parent(&path)?;
            set_staged(&path, false);
            write_temporary(&tmp, &path, write)?;
            set_staged(&path, true);
            return Ok(());
        }
        Some(Staging::Dir { .. }) => {
            return Err(Error::new(ErrorKind::Refused, "planned as a folder output, written as a file").in_file(&path));
        }
        Some(Staging::Inside(real)) => real,
        None => path,
    };
    if !inside_live(&path) {
        sweep_stale(&path);
    }
    check_file_place(&path)?;
    ensure_parent(&path)?;
    let tmp = sibling(&path, "tmp");
    let _live = register(&tmp);
    write_temporary(&tmp, &path, write)?;
    fs::rename(&tmp, &path).map_err(|e| {
        let _ = fs::remove_file(&tmp);
        Error::io(&path, "write", e)
    })
}

/// Builds a folder output of `kind` through `fill` (given the temporary folder, which already
/// holds the marker of `kind`), then swaps it in for `path`; a previous folder at `path` is
/// removed only once the new one is complete. `path` may be new, an empty folder, or surfcap's
/// earlier output of the same `kind`; any other folder only with `force` (see
/// `crate::output_path`), and only when it can be removed whole. A path planned by a live output
/// set is only built (swapped in at the set's commit).
pub fn write_dir(path: &Path, kind: &str, force: bool, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let path = resolve(path)?;
    let path = match staging(&path)? {
        Some(Staging::Dir { tmp, kind: planned }) => {
            if planned != kind {
                return Err(Error::new(
                    ErrorKind::Refused,
                    format!("planned as a {planned} output, written as {kind}"),
                )
                .in_file(&path));
            }
            ensure_parent(&path)?;
            set_staged(&path, false);
            let _ = fs::remove_dir_all(&tmp);
            fs::create_dir(&tmp).map_err(|e| Error::io(&tmp, "create directory", e))?;
            if let Err(e) = write_marker(&tmp, kind).and_then(|()| fill(&tmp)) {
                let _ = fs::remove_dir_all(&tmp);
                return Err(e);
            }
            set_staged(&path, true);
            return Ok(());
        }
        Some(Staging::File(_)) => {
            return Err(Error::new(ErrorKind::Refused, "planned as a file output, written as a folder").in_file(&path));
        }
        Some(Staging::Inside(real)) => real,
        None => path,
    };
    // A folder output on its own: a set of one.
    let mut set = OutputSet::new(&[]);
    set.dir(&path, kind, force)?;
    write_dir(&path, kind, force, fill)?;
    set.commit()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ErrorKind;
    use crate::output_path::MARKER;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

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
        write_dir(&dir, "test", false, |t| write_file(&t.join("x"), |w| w.write_all(b"1"))).unwrap();
        let r = write_dir(&dir, "test", false, |_| Err(crate::error::Error::new(crate::ErrorKind::Io, "boom")));
        assert!(r.is_err());
        assert_eq!(fs::read(dir.join("x")).unwrap(), b"1");
        assert_eq!(names(d.path()), ["a.txt", "out"], "no temporaries left behind");
    }

    #[test]
    fn a_folder_output_replaces_its_own_kind_only() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path().join("keep");
        fs::create_dir_all(dir.join("sub")).unwrap();
        fs::write(dir.join("sub/mine.txt"), b"user data").unwrap();
        let e = write_dir(&dir, "test", false, |t| write_file(&t.join("x"), |w| w.write_all(b"1"))).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        assert_eq!(fs::read(dir.join("sub/mine.txt")).unwrap(), b"user data");
        assert_eq!(names(d.path()), ["keep"]);
        write_dir(&dir, "test", true, |t| write_file(&t.join("x"), |w| w.write_all(b"1"))).unwrap();
        assert_eq!(names(&dir), [MARKER, "x"], "--force replaced it");
        write_dir(&dir, "test", false, |t| write_file(&t.join("y"), |w| w.write_all(b"2"))).unwrap();
        assert_eq!(names(&dir), [MARKER, "y"], "its own earlier output is replaced whole");
        assert!(write_dir(&dir, "other", false, |_| Ok(())).is_err());
    }

    #[test]
    fn file_outputs_never_replace_a_folder() {
        let d = tempfile::tempdir().unwrap();
        fs::create_dir(d.path().join("x")).unwrap();
        assert_eq!(write_file(&d.path().join("x"), |w| w.write_all(b"1")).unwrap_err().kind, ErrorKind::Refused);
        assert!(d.path().join("x").is_dir());
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_written_through_to_its_file() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("target.txt"), b"old").unwrap();
        std::os::unix::fs::symlink("target.txt", d.path().join("link.txt")).unwrap();
        write_file(&d.path().join("link.txt"), |w| w.write_all(b"new")).unwrap();
        assert!(fs::symlink_metadata(d.path().join("link.txt")).unwrap().file_type().is_symlink());
        assert_eq!(fs::read(d.path().join("target.txt")).unwrap(), b"new");
        std::os::unix::fs::symlink("/dev/null", d.path().join("null")).unwrap();
        assert!(write_file(&d.path().join("null"), |w| w.write_all(b"x")).is_err());
    }

    #[test]
    fn relative_outputs_get_their_temporary_beside_the_real_folder() {
        let d = tempfile::tempdir().unwrap();
        let inner = d.path().join("a");
        fs::create_dir(&inner).unwrap();
        // `a/..` names the temporary folder's parent: its temporary is a sibling of it, not `.out.tmp`.
        let e = write_dir(&inner.join(".."), "test", false, |_| Ok(())).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused, "{e}");
        assert_eq!(names(d.path()), ["a"]);
        write_dir(&inner.join("../b"), "test", false, |_| Ok(())).unwrap();
        assert_eq!(names(d.path()), ["a", "b"]);
    }
}
