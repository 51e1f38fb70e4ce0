//! Where an output may go, decided before anything is written, so that an output never destroys
//! what surfcap did not write:
//!
//! - [`resolve`]: the absolute path an output really names (symlinks followed, `.` and `..`
//!   resolved), so that `-o .` or `-o link.glb` are judged and replaced by what they are;
//! - [`check_not_input`]: an output that is, contains or lies inside one of the command's inputs
//!   is refused (`import src -o src` would delete the sources);
//! - a file output replaces only a regular file (never a device such as `/dev/null`, a FIFO, a
//!   socket or a folder); a symlink is written through to its target;
//! - a folder output replaces only an empty folder or surfcap's own earlier output of the same
//!   kind, recognised by the marker file [`MARKER`] surfcap writes in every folder it creates;
//!   anything else needs `force` (the CLI's `--force`), and then only a folder that can be moved
//!   aside and removed whole (it, every folder in it and its parent writable and not marked
//!   read-only), so that a forced run never leaves the old folder hidden beside the new one.
//!
//! A command writing several outputs plans them with `crate::output_set`, which applies these
//! rules to each before any work and again at the commit; [`claim_dir`] on a planned folder
//! starts its temporary, so the folder and its marker reach the place only with the commit.

use std::fs;
use std::path::{Component, Path, PathBuf};

use crate::error::{Error, ErrorKind, Result, err};

/// The marker file in every folder surfcap writes: `{"written_by": "surfcap", "version", "kind"}`.
pub const MARKER: &str = ".surfcap-output.json";

/// Symlink hops followed before giving up (as the kernel's ELOOP limit).
const MAX_HOPS: usize = 40;

fn refused(path: &Path, message: String) -> Error {
    Error::new(ErrorKind::Refused, message).in_file(path)
}

/// The absolute path `path` names: every existing component resolved (symlinks followed,
/// dangling ones too), the part that does not exist yet taken as written. Refuses a path with
/// no name of its own (`/`).
pub fn resolve(path: &Path) -> Result<PathBuf> {
    let r = resolve_hops(path, 0)?;
    if r.file_name().is_none() {
        return Err(refused(path, "cannot write an output here: expected a file or folder name".into()));
    }
    Ok(r)
}

fn resolve_hops(path: &Path, hops: usize) -> Result<PathBuf> {
    if hops > MAX_HOPS {
        return Err(refused(path, format!("more than {MAX_HOPS} symbolic links to follow")));
    }
    let abs = std::path::absolute(path).map_err(|e| Error::io(path, "resolve the path", e))?;
    let mut out = PathBuf::new();
    let mut exists = true;
    for c in abs.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => out.push(c),
            Component::CurDir => {}
            // `out` holds no symlink (they were followed), so `..` is its parent.
            Component::ParentDir => {
                out.pop();
            }
            Component::Normal(name) => {
                out.push(name);
                if !exists {
                    continue;
                }
                match fs::symlink_metadata(&out) {
                    Ok(m) if m.file_type().is_symlink() => {
                        let target = fs::read_link(&out).map_err(|e| Error::io(&out, "read the symbolic link", e))?;
                        out.pop();
                        out = resolve_hops(&out.join(target), hops + 1)?;
                        exists = fs::symlink_metadata(&out).is_ok();
                    }
                    Ok(_) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => exists = false,
                    Err(e) => return Err(Error::io(&out, "look at", e)),
                }
            }
        }
    }
    Ok(out)
}

fn what_is(m: &fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = m.file_type();
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if m.is_dir() {
        "a folder"
    } else if m.is_file() {
        "a file"
    } else {
        "not a regular file"
    }
}

/// A file output (resolved) replaces nothing or a regular file.
pub(crate) fn check_file_place(path: &Path) -> Result<()> {
    match fs::symlink_metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) => Err(refused(
            path,
            format!(
                "is {}: expected a file name (surfcap replaces only regular files it can write whole); choose another output",
                what_is(&m)
            ),
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(path, "look at", e)),
    }
}

/// The kind recorded in `dir`'s marker, if it holds a marker surfcap wrote.
fn marker_kind(dir: &Path) -> Option<String> {
    let v: serde_json::Value = serde_json::from_slice(&fs::read(dir.join(MARKER)).ok()?).ok()?;
    (v["written_by"] == "surfcap").then(|| v["kind"].as_str().map(str::to_owned)).flatten()
}

/// Whether `dir` holds a marker surfcap wrote (of any kind).
pub fn has_marker(dir: &Path) -> bool {
    marker_kind(dir).is_some()
}

/// Whether `dir` is surfcap's earlier output of `kind` (holds its marker).
pub fn is_output_of(dir: &Path, kind: &str) -> bool {
    marker_kind(dir).is_some_and(|k| k == kind)
}

/// Writes the marker of a folder output of `kind` into `dir`.
pub(crate) fn write_marker(dir: &Path, kind: &str) -> Result<()> {
    let v = serde_json::json!({ "written_by": "surfcap", "version": env!("CARGO_PKG_VERSION"), "kind": kind });
    let p = dir.join(MARKER);
    fs::write(&p, format!("{v:#}\n")).map_err(|e| Error::io(&p, "write", e))
}

/// A folder output of `kind` (resolved) may replace what is at `path`: nothing, an empty folder,
/// surfcap's earlier output of the same kind, or any folder with `force`; never a file, a device,
/// or the current working directory (or a folder holding it: the shell would be left in a
/// deleted folder).
pub(crate) fn check_dir_place(path: &Path, kind: &str, force: bool) -> Result<()> {
    let m = match fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(path, "look at", e)),
        Ok(m) => m,
    };
    if !m.is_dir() {
        return Err(refused(path, format!("is {}: expected a folder (or a new name) for this output", what_is(&m))));
    }
    if std::env::current_dir().and_then(fs::canonicalize).is_ok_and(|cwd| cwd.starts_with(path)) {
        return Err(refused(
            path,
            "is the current folder (or holds it): surfcap builds a folder output beside it and swaps it in whole, which would leave your shell in a deleted folder; run from the parent folder (cd ..) or choose another folder".into(),
        ));
    }
    let empty = fs::read_dir(path).map_err(|e| Error::io(path, "list", e))?.next().is_none();
    let found = marker_kind(path);
    if force || empty || found.as_deref() == Some(kind) {
        return Ok(());
    }
    let what = match found {
        Some(other) => {
            format!("this folder holds another kind of surfcap output ({other}; this command writes {kind})")
        }
        None => format!("this folder holds files surfcap did not write (it has no {MARKER})"),
    };
    Err(refused(
        path,
        format!(
            "{what}, and surfcap would replace it whole; choose a new or empty folder, or pass --force to replace it"
        ),
    ))
}

/// A folder that will be replaced whole (moved aside, then removed) can be: its parent and the
/// folder and every folder inside it are writable. Checked before the commit, so that a forced
/// run over a read-only folder is refused rather than leaving the folder moved aside and
/// half-removed. Nothing there, or not a folder: nothing to check.
pub(crate) fn check_removable(path: &Path) -> Result<()> {
    match fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => {}
        _ => return Ok(()),
    }
    let read_only = |p: &Path, what: &str| {
        refused(
            path,
            format!(
                "{what} {} is not writable, so the previous folder could not be moved aside and removed when the new output replaces it; make it writable or choose another output",
                p.display()
            ),
        )
    };
    if let Some(parent) = path.parent()
        && !writable(parent)
    {
        return Err(read_only(parent, "its parent folder"));
    }
    let mut todo = vec![path.to_path_buf()];
    while let Some(dir) = todo.pop() {
        if !writable(&dir) {
            return Err(read_only(&dir, "the folder"));
        }
        let entries = fs::read_dir(&dir).map_err(|e| Error::io(&dir, "list", e))?;
        for e in entries.flatten() {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                todo.push(e.path());
            }
        }
    }
    Ok(())
}

/// Whether this process may create and remove entries in the folder `dir`, and the folder is
/// not marked read-only (no write permission for anyone: its owner protected it, and even a
/// process that could override that, such as root, leaves it alone).
fn writable(dir: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        use std::os::unix::fs::PermissionsExt;
        if fs::metadata(dir).is_ok_and(|m| m.permissions().mode() & 0o222 == 0) {
            return false;
        }
        let Ok(c) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else { return false };
        // SAFETY: `c` is a valid NUL-terminated path; access only reads it.
        unsafe { libc::access(c.as_ptr(), libc::W_OK | libc::X_OK) == 0 }
    }
    #[cfg(not(unix))]
    {
        fs::metadata(dir).is_ok_and(|m| !m.permissions().readonly())
    }
}

/// Makes `path` a folder output of `kind` that the command fills file by file.
///
/// When a live [`crate::output_set::OutputSet`] planned `path`, the folder is its temporary
/// (with the marker inside): writes under `path` go there, and the folder, marker included,
/// reaches `path` only with the commit, so a failed run leaves the place as it was.
///
/// Otherwise the folder is filled in place (each file written atomically): checks the place as a
/// folder output, creates the folder and writes the marker. Earlier files of the same kind stay
/// until overwritten. A forced claim of a folder surfcap did not write is refused here (its
/// marker would be left in the user's folder by a failed run): plan it in an output set.
/// Returns the resolved folder.
pub fn claim_dir(path: &Path, kind: &str, force: bool) -> Result<PathBuf> {
    let path = resolve(path)?;
    match crate::output_set::staging(&path)? {
        Some(crate::output_set::Staging::Dir { tmp, kind: planned }) => {
            if planned != kind {
                return Err(refused(&path, format!("planned as a {planned} output, claimed as {kind}")));
            }
            remove_tmp(&tmp);
            if let Some(parent) = tmp.parent() {
                fs::create_dir_all(parent).map_err(|e| Error::io(parent, "create directory", e))?;
            }
            fs::create_dir(&tmp).map_err(|e| Error::io(&tmp, "create directory", e))?;
            write_marker(&tmp, kind)?;
            crate::output_set::set_staged(&path, true);
            return Ok(path);
        }
        Some(crate::output_set::Staging::File(_)) => {
            return Err(refused(&path, "planned as a file output, claimed as a folder".into()));
        }
        // Inside a folder output being built: claimed there, named by its final path.
        Some(crate::output_set::Staging::Inside(real)) => {
            check_dir_place(&real, kind, false)?;
            fs::create_dir_all(&real).map_err(|e| Error::io(&real, "create directory", e))?;
            write_marker(&real, kind)?;
            return Ok(path);
        }
        None => {}
    }
    check_dir_place(&path, kind, false).map_err(|e| {
        if force {
            refused(
                &path,
                format!("{}; a forced folder output is replaced only as a whole, at the end of a run", e.message),
            )
        } else {
            e
        }
    })?;
    fs::create_dir_all(&path).map_err(|e| Error::io(&path, "create directory", e))?;
    write_marker(&path, kind)?;
    Ok(path)
}

fn remove_tmp(tmp: &Path) {
    match fs::symlink_metadata(tmp) {
        Ok(m) if m.is_dir() => {
            let _ = fs::remove_dir_all(tmp);
        }
        Ok(_) => {
            let _ = fs::remove_file(tmp);
        }
        Err(_) => {}
    }
}

/// Refuses an output that is, contains or lies inside one of `inputs` (inputs that do not exist
/// are left to the readers to report).
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    let out = resolve(output)?;
    for input in inputs {
        let Ok(inp) = fs::canonicalize(input) else { continue };
        let how = if out == inp {
            "is"
        } else if out.starts_with(&inp) {
            "lies inside"
        } else if inp.starts_with(&out) {
            "contains"
        } else {
            continue;
        };
        return Err(err!(
            Refused,
            "the output {how} the input {}: writing it would destroy the input; choose an output outside the inputs",
            input.display()
        )
        .in_file(output));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_follows_symlinks_and_dots_and_keeps_missing_parts() {
        let d = tempfile::tempdir().unwrap();
        let root = fs::canonicalize(d.path()).unwrap();
        fs::create_dir(root.join("a")).unwrap();
        assert_eq!(resolve(&root.join("a/./../a/new/x.glb")).unwrap(), root.join("a/new/x.glb"));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("a", root.join("link")).unwrap();
            assert_eq!(resolve(&root.join("link/f")).unwrap(), root.join("a/f"));
            std::os::unix::fs::symlink("a/missing.glb", root.join("dangling")).unwrap();
            assert_eq!(resolve(&root.join("dangling")).unwrap(), root.join("a/missing.glb"));
            std::os::unix::fs::symlink("loop", root.join("loop")).unwrap();
            assert_eq!(resolve(&root.join("loop")).unwrap_err().kind, ErrorKind::Refused);
        }
        assert!(resolve(Path::new("/")).is_err());
    }

    #[test]
    fn folder_outputs_replace_only_empty_or_own_folders() {
        let d = tempfile::tempdir().unwrap();
        let dir = fs::canonicalize(d.path()).unwrap().join("o");
        check_dir_place(&dir, "graph", false).unwrap();
        fs::create_dir(&dir).unwrap();
        check_dir_place(&dir, "graph", false).unwrap();
        fs::write(dir.join("notes.txt"), b"mine").unwrap();
        let e = check_dir_place(&dir, "graph", false).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        assert!(e.to_string().contains("--force"), "{e}");
        check_dir_place(&dir, "graph", true).unwrap();
        write_marker(&dir, "report").unwrap();
        assert!(check_dir_place(&dir, "graph", false).is_err(), "another kind's marker");
        write_marker(&dir, "graph").unwrap();
        check_dir_place(&dir, "graph", false).unwrap();
        let f = dir.join("notes.txt");
        assert!(check_dir_place(&f, "graph", true).is_err(), "a file is not a folder, even with force");
    }

    #[test]
    fn claim_dir_creates_the_folder_with_its_marker() {
        let d = tempfile::tempdir().unwrap();
        let dir = claim_dir(&d.path().join("g"), "graph", false).unwrap();
        assert_eq!(marker_kind(&dir).as_deref(), Some("graph"));
        claim_dir(&dir, "graph", false).unwrap();
    }

    #[test]
    fn file_outputs_replace_only_regular_files() {
        let d = tempfile::tempdir().unwrap();
        check_file_place(&d.path().join("new")).unwrap();
        fs::write(d.path().join("f"), b"1").unwrap();
        check_file_place(&d.path().join("f")).unwrap();
        assert!(check_file_place(d.path()).unwrap_err().to_string().contains("a folder"));
        #[cfg(unix)]
        {
            let e = check_file_place(Path::new("/dev/null")).unwrap_err();
            assert!(e.to_string().contains("a device"), "{e}");
        }
    }

    #[test]
    fn outputs_overlapping_inputs_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let src = d.path().join("src");
        fs::create_dir(&src).unwrap();
        fs::write(src.join("template.obj"), b"").unwrap();
        for (out, how) in
            [(src.clone(), "is"), (src.join("x.subject"), "lies inside"), (d.path().to_path_buf(), "contains")]
        {
            let e = check_not_input(&out, &[&src]).unwrap_err();
            assert!(e.to_string().contains(how), "{e}");
        }
        check_not_input(&d.path().join("src2"), &[&src]).unwrap();
        check_not_input(&d.path().join("o"), &[Path::new("/no/such/input")]).unwrap();
    }
}
