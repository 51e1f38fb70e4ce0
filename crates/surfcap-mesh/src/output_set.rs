//! All-or-nothing outputs: every file and folder one command writes (the main output, the
//! sidecar beside a `.glb`, the `.report.json`, a folder output) planned first, written to
//! temporaries, and renamed into place together at the end.
//!
//! - [`OutputSet::file`], [`OutputSet::side_file`] and [`OutputSet::dir`] plan an output before
//!   any work: the path is resolved (`crate::output_path::resolve`), refused when it overlaps an
//!   input or another planned output, and checked against the place rules
//!   (`crate::output_path`). A side file replaces only surfcap's own earlier side file of the
//!   same kind, recognised by its top-level `"written_by": "surfcap"` and `"output_kind"` keys
//!   ([`Stamped`] writes them), never an input or a file of the user's.
//! - While a set is alive, `crate::atomic::write_file`, `write_dir` and
//!   `crate::output_path::claim_dir` on a planned path write its temporary `.NAME.tmp-PID`
//!   (registered as live, `crate::temporaries`) and leave it there; writes inside a planned folder
//!   go to that folder's temporary. So libraries keep calling the ordinary writers.
//! - [`OutputSet::commit`] re-checks every place (a folder created or filled, or a file turned
//!   into a folder, while the command ran is not replaced: the whole commit is refused before any
//!   rename), checks that a folder to replace can be moved aside and removed, then renames every
//!   temporary into place, the previous versions kept aside (`.NAME.old-PID`) until all are in.
//!   If a rename fails midway, the outputs already replaced are put back. A previous folder
//!   that cannot be removed after the commit is renamed to a visible `NAME.previous` and
//!   reported, never left hidden.
//! - Dropping a set without committing removes its temporaries: every previous output stays
//!   as it was and no new file is left behind.
//! - The commit holds the process-wide commit lock (`crate::temporaries`), so a signal handler
//!   waits for a commit in progress and then knows whether the outputs were completed.
//!
//! A folder output's marker is inside its temporary, so it reaches the output's place only with
//! the commit: a failed run never leaves a marker in a folder of the user's.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use serde::{Deserialize, Serialize};

use crate::error::{Error, ErrorKind, Result};
use crate::output_path::{check_dir_place, check_file_place, check_not_input, check_removable, resolve};
use crate::temporaries::{
    Registered, commit_lock, inside_live, register, remove_any, sibling, sweep_stale, visible_name,
};

/// The value of the `written_by` key surfcap puts in every side file and marker it writes.
pub const WRITTEN_BY: &str = "surfcap";

/// A side file's JSON as surfcap writes it: `"written_by": "surfcap"` and
/// `"output_kind": KIND` first, then the fields of `body` (an object) as they are.
#[derive(Serialize)]
pub struct Stamped<'a, T: ?Sized> {
    written_by: &'static str,
    output_kind: &'a str,
    #[serde(flatten)]
    body: &'a T,
}

impl<'a, T: Serialize + ?Sized> Stamped<'a, T> {
    /// `body` stamped as surfcap's side file of `kind`.
    pub fn new(kind: &'a str, body: &'a T) -> Self {
        Stamped { written_by: WRITTEN_BY, output_kind: kind, body }
    }
}

/// Whether the regular file at `path` is surfcap's side file of `kind` (its top-level
/// `written_by` and `output_kind`). The file is parsed as a stream, so a large file costs no
/// memory; anything unreadable or not JSON is not surfcap's.
pub fn is_own_side_file(path: &Path, kind: &str) -> bool {
    #[derive(Deserialize)]
    struct Stamp {
        written_by: Option<String>,
        output_kind: Option<String>,
    }
    let Ok(f) = crate::regular_file::open_regular_file(path) else { return false };
    let Ok(s) = serde_json::from_reader::<_, Stamp>(std::io::BufReader::new(f)) else { return false };
    s.written_by.as_deref() == Some(WRITTEN_BY) && s.output_kind.as_deref() == Some(kind)
}

/// What a planned output is.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Role {
    /// A file the command writes whole (replaces a regular file).
    File,
    /// A file beside the main output: replaces only surfcap's own side file of this kind.
    Side(String),
    /// A folder output of a kind, possibly forced over a folder surfcap did not write.
    Dir { kind: String, force: bool },
}

/// What was at a planned place when it was planned: its device and inode, if anything.
type Found = Option<(u64, u64)>;

fn identity(path: &Path) -> Found {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        fs::symlink_metadata(path).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        fs::symlink_metadata(path).ok().map(|_| (0, 0))
    }
}

struct Entry {
    set: u64,
    path: PathBuf,
    role: Role,
    found: Found,
    tmp: PathBuf,
    staged: bool,
    _live: Registered,
}

static PLANNED: Mutex<Vec<Entry>> = Mutex::new(Vec::new());
static NEXT_SET: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn planned() -> MutexGuard<'static, Vec<Entry>> {
    PLANNED.lock().unwrap_or_else(|e| e.into_inner())
}

/// How a write to a (resolved) path is staged by a live set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Staging {
    /// A planned file: write its temporary.
    File(PathBuf),
    /// A planned folder of this kind: build its temporary.
    Dir { tmp: PathBuf, kind: String },
    /// A path inside a planned folder: this path inside the folder's temporary.
    Inside(PathBuf),
}

/// How a write to `path` (resolved) is staged, if a live set planned it or a folder holding it.
pub(crate) fn staging(path: &Path) -> Result<Option<Staging>> {
    let p = planned();
    for e in p.iter() {
        if e.path == path {
            return Ok(Some(match &e.role {
                Role::File | Role::Side(_) => Staging::File(e.tmp.clone()),
                Role::Dir { kind, .. } => Staging::Dir { tmp: e.tmp.clone(), kind: kind.clone() },
            }));
        }
        if let (Role::Dir { .. }, Ok(rest)) = (&e.role, path.strip_prefix(&e.path)) {
            if !e.staged {
                return Err(Error::new(
                    ErrorKind::Refused,
                    format!(
                        "cannot write inside the folder output {} before it is started (claimed or built)",
                        e.path.display()
                    ),
                )
                .in_file(path));
            }
            return Ok(Some(Staging::Inside(e.tmp.join(rest))));
        }
    }
    Ok(None)
}

/// Whether a live set planned `path` as an output (its writes are staged until the commit).
pub fn is_planned(path: &Path) -> bool {
    resolve(path).is_ok_and(|p| planned().iter().any(|e| e.path == p))
}

/// Where a write to `path` goes now: inside the temporary of a planned folder that holds it
/// (the folder reaches `path` at the commit), else `path` itself. For writers that do not go
/// through `crate::atomic` (copies).
pub fn write_place(path: &Path) -> PathBuf {
    match resolve(path).ok().and_then(|p| staging(&p).ok().flatten()) {
        Some(Staging::Inside(real)) => real,
        Some(Staging::Dir { tmp, .. }) | Some(Staging::File(tmp)) => tmp,
        None => path.to_path_buf(),
    }
}

/// Records whether the planned output at `path` has a complete temporary.
pub(crate) fn set_staged(path: &Path, staged: bool) {
    if let Some(e) = planned().iter_mut().find(|e| e.path == path) {
        e.staged = staged;
    }
}

/// One step of a commit, for [`OutputSet::commit_with`]'s hook.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommitStep {
    /// Every place was re-checked; nothing renamed yet.
    Checked,
    /// About to rename the `n`th staged output into place.
    Rename(usize),
    /// The `n`th staged output is in place.
    Renamed(usize),
    /// Every output is in place; previous versions not yet removed.
    AllInPlace,
    /// About to remove the previous version of the `n`th output (an error: it could not be).
    RemovePrevious(usize),
}

/// What a commit did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Committed {
    /// The outputs now in place (those the command wrote; a planned output never written is
    /// left as it was).
    pub written: Vec<PathBuf>,
    /// Previous folders that could not be removed after the commit: (output, where the previous
    /// folder now is, under a visible name).
    pub kept_previous: Vec<(PathBuf, PathBuf)>,
}

/// The outputs of one command, planned before work and committed together (module docs).
#[must_use = "an output set dropped without a commit discards every staged output"]
pub struct OutputSet {
    id: u64,
    inputs: Vec<PathBuf>,
    done: bool,
}

fn refused(path: &Path, message: String) -> Error {
    Error::new(ErrorKind::Refused, message).in_file(path)
}

impl OutputSet {
    /// A set for a command whose inputs are `inputs` (no output may overlap one).
    pub fn new(inputs: &[&Path]) -> Self {
        OutputSet {
            id: NEXT_SET.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
            done: false,
        }
    }

    fn plan(&mut self, path: &Path, role: Role) -> Result<PathBuf> {
        let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
        check_not_input(path, &inputs)?;
        let resolved = resolve(path)?;
        if !inside_live(&resolved) {
            sweep_stale(&resolved);
        }
        check_place(&resolved, &role, None)?;
        let mut p = planned();
        if let Some(e) = p.iter().find(|e| {
            e.path == resolved
                || (matches!(e.role, Role::Dir { .. }) && resolved.starts_with(&e.path))
                || (matches!(role, Role::Dir { .. }) && e.path.starts_with(&resolved))
        }) {
            let whose = if e.set == self.id { "another output of this command" } else { "an output being written" };
            return Err(refused(
                path,
                format!("overlaps {whose} ({}): each output needs its own place", e.path.display()),
            ));
        }
        let tmp = sibling(&resolved, "tmp");
        p.push(Entry {
            set: self.id,
            found: identity(&resolved),
            _live: register(&tmp),
            path: resolved.clone(),
            role,
            tmp,
            staged: false,
        });
        Ok(resolved)
    }

    /// Plans a file output (written whole; replaces nothing or a regular file). Returns its
    /// resolved path.
    pub fn file(&mut self, path: &Path) -> Result<PathBuf> {
        self.plan(path, Role::File)
    }

    /// Plans a side file of `kind` (a sidecar or report beside the main output): it replaces
    /// only surfcap's own earlier side file of that kind ([`is_own_side_file`]).
    pub fn side_file(&mut self, path: &Path, kind: &str) -> Result<PathBuf> {
        self.plan(path, Role::Side(kind.to_owned()))
    }

    /// Plans a folder output of `kind` (`crate::output_path`'s rules: nothing, an empty
    /// folder, surfcap's own of the same kind, or any folder with `force` when it can be
    /// removed whole).
    pub fn dir(&mut self, path: &Path, kind: &str, force: bool) -> Result<PathBuf> {
        self.plan(path, Role::Dir { kind: kind.to_owned(), force })
    }

    /// The resolved paths planned so far, in order.
    pub fn paths(&self) -> Vec<PathBuf> {
        planned().iter().filter(|e| e.set == self.id).map(|e| e.path.clone()).collect()
    }

    /// Renames every written output into place, or none (module docs).
    pub fn commit(self) -> Result<Committed> {
        self.commit_with(&mut |_| Ok(()))
    }

    /// [`commit`](Self::commit), calling `hook` at every step; an error from the hook is taken
    /// as the failure of that step (for tests: a failure midway, or a signal at the commit).
    pub fn commit_with(mut self, hook: &mut dyn FnMut(CommitStep) -> std::io::Result<()>) -> Result<Committed> {
        let mut log = commit_lock();
        self.done = true;
        let entries: Vec<Entry> = {
            let mut p = planned();
            let (mine, rest): (Vec<Entry>, Vec<Entry>) =
                std::mem::take(&mut *p).into_iter().partition(|e| e.set == self.id);
            *p = rest;
            mine
        };
        let (staged, unstaged): (Vec<Entry>, Vec<Entry>) = entries.into_iter().partition(|e| e.staged);
        for e in &unstaged {
            remove_any(&e.tmp);
        }
        let discard = |entries: &[Entry]| {
            for e in entries {
                remove_any(&e.tmp);
            }
        };
        for e in &staged {
            if let Err(err) = check_place(&e.path, &e.role, Some(e.found)) {
                discard(&staged);
                return Err(err);
            }
        }
        if let Err(e) = hook(CommitStep::Checked) {
            discard(&staged);
            return Err(Error::io(&staged.first().map_or_else(PathBuf::new, |e| e.path.clone()), "commit", e));
        }
        let mut done: Vec<Swap> = Vec::new();
        for (i, e) in staged.iter().enumerate() {
            let step = hook(CommitStep::Rename(i)).and_then(|()| swap_in(e)).and_then(|s| {
                done.push(s);
                hook(CommitStep::Renamed(i))
            });
            if let Err(err) = step {
                for s in done.iter().rev() {
                    s.undo();
                }
                discard(&staged);
                return Err(Error::io(&e.path, "rename the new output into place (every output was put back)", err));
            }
        }
        let _ = hook(CommitStep::AllInPlace);
        let mut kept_previous = Vec::new();
        for (i, s) in done.iter().enumerate() {
            let removable = hook(CommitStep::RemovePrevious(i)).is_ok();
            if let Some(kept) = s.finish(removable) {
                kept_previous.push((s.path.clone(), kept));
            }
        }
        let written: Vec<PathBuf> = staged.iter().map(|e| e.path.clone()).collect();
        log.extend(written.iter().cloned());
        drop(staged);
        Ok(Committed { written, kept_previous })
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if self.done {
            return;
        }
        let mine: Vec<Entry> = {
            let mut p = planned();
            let (mine, rest): (Vec<Entry>, Vec<Entry>) =
                std::mem::take(&mut *p).into_iter().partition(|e| e.set == self.id);
            *p = rest;
            mine
        };
        for e in &mine {
            remove_any(&e.tmp);
        }
    }
}

/// Checks that `role` may be written at `path`; at the commit (`planned` = what was there when
/// planned), a forced folder is replaced only if it is still the very folder that was there.
fn check_place(path: &Path, role: &Role, planned: Option<Found>) -> Result<()> {
    match role {
        Role::File => check_file_place(path),
        Role::Side(kind) => {
            check_file_place(path)?;
            if fs::symlink_metadata(path).is_ok() && !is_own_side_file(path, kind) {
                return Err(refused(
                    path,
                    format!(
                        "this file would be replaced by the {kind} written beside the output, but surfcap did not write it (it has no \"written_by\": \"surfcap\", \"output_kind\": \"{kind}\"); move it or choose another output name"
                    ),
                ));
            }
            Ok(())
        }
        Role::Dir { kind, force } => {
            let same = planned.is_none_or(|found| found.is_some() && identity(path) == found);
            if let Err(e) = check_dir_place(path, kind, *force && same) {
                if planned.is_some() {
                    return Err(refused(
                        path,
                        format!(
                            "changed while the command ran, so nothing was replaced and the new output was discarded: {}",
                            e.message
                        ),
                    ));
                }
                return Err(e);
            }
            check_removable(path)
        }
    }
}

/// One output renamed into place, and how to undo or finish it.
struct Swap {
    path: PathBuf,
    tmp: PathBuf,
    /// The previous version, kept aside until the end.
    aside: Option<PathBuf>,
    /// Whether the previous version was a folder (moved aside) rather than a file (linked).
    dir: bool,
}

fn swap_in(e: &Entry) -> std::io::Result<Swap> {
    let dir = matches!(e.role, Role::Dir { .. });
    let aside = sibling(&e.path, "old");
    let had = fs::symlink_metadata(&e.path).is_ok();
    let mut s = Swap { path: e.path.clone(), tmp: e.tmp.clone(), aside: None, dir };
    if had {
        remove_any(&aside);
        if dir {
            fs::rename(&e.path, &aside)?;
        } else if fs::hard_link(&e.path, &aside).is_err() {
            // A file system without hard links: move it aside (a moment without the output).
            fs::rename(&e.path, &aside)?;
        }
        s.aside = Some(aside);
    }
    if let Err(err) = fs::rename(&e.tmp, &e.path) {
        if let Some(a) = &s.aside {
            if dir || fs::symlink_metadata(&e.path).is_err() {
                let _ = fs::rename(a, &e.path);
            } else {
                let _ = fs::remove_file(a);
            }
        }
        return Err(err);
    }
    Ok(s)
}

impl Swap {
    /// Puts the previous version back (or removes the new output where there was none).
    fn undo(&self) {
        match &self.aside {
            Some(a) if self.dir => {
                if fs::rename(&self.path, &self.tmp).is_ok() {
                    let _ = fs::rename(a, &self.path);
                    remove_any(&self.tmp);
                }
            }
            Some(a) => {
                let _ = fs::rename(a, &self.path);
            }
            None if self.dir => {
                if fs::rename(&self.path, &self.tmp).is_ok() {
                    remove_any(&self.tmp);
                }
            }
            None => {
                let _ = fs::remove_file(&self.path);
            }
        }
    }

    /// Removes the previous version; a previous folder that cannot be removed is renamed to a
    /// visible name, which is returned.
    fn finish(&self, removable: bool) -> Option<PathBuf> {
        let a = self.aside.as_ref()?;
        if !self.dir {
            let _ = fs::remove_file(a);
            return None;
        }
        if removable && (fs::remove_dir_all(a).is_ok() || fs::symlink_metadata(a).is_err()) {
            return None;
        }
        let visible = visible_name(&self.path);
        Some(if fs::rename(a, &visible).is_ok() { visible } else { a.clone() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atomic::{write_dir, write_file};
    use crate::output_path::{MARKER, claim_dir};

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    fn side(path: &Path, kind: &str, body: &serde_json::Value) {
        write_file(path, |w| serde_json::to_writer(&mut *w, &Stamped::new(kind, body)).map_err(std::io::Error::other))
            .unwrap();
    }

    /// A glb and its sidecar written by an earlier run.
    fn earlier(d: &Path) -> (PathBuf, PathBuf) {
        let (glb, json) = (d.join("x.glb"), d.join("x.json"));
        fs::write(&glb, b"old glb").unwrap();
        side(&json, "sidecar", &serde_json::json!({"fps": 1}));
        (glb, json)
    }

    #[test]
    fn side_files_carry_the_stamp_and_keep_their_fields_in_order() {
        #[derive(Serialize)]
        struct Body {
            b: u32,
            a: u32,
        }
        let v = serde_json::to_string(&Stamped::new("report", &Body { b: 1, a: 2 })).unwrap();
        assert_eq!(v, r#"{"written_by":"surfcap","output_kind":"report","b":1,"a":2}"#);
    }

    #[test]
    fn nothing_is_in_place_before_the_commit_and_a_failure_keeps_every_previous_file() {
        let d = tempfile::tempdir().unwrap();
        let (glb, json) = earlier(d.path());
        let before = fs::read(&json).unwrap();
        {
            let mut set = OutputSet::new(&[]);
            set.file(&glb).unwrap();
            set.side_file(&json, "sidecar").unwrap();
            write_file(&glb, |w| w.write_all(b"new glb")).unwrap();
            assert_eq!(fs::read(&glb).unwrap(), b"old glb", "staged, not renamed");
            // The side file fails: the set is dropped without a commit.
        }
        assert_eq!(fs::read(&glb).unwrap(), b"old glb");
        assert_eq!(fs::read(&json).unwrap(), before);
        assert_eq!(names(d.path()), ["x.glb", "x.json"], "no temporary left");
        // No previous output: a failed run leaves no new file.
        let e = tempfile::tempdir().unwrap();
        {
            let mut set = OutputSet::new(&[]);
            set.file(&e.path().join("n.glb")).unwrap();
            set.side_file(&e.path().join("n.json"), "sidecar").unwrap();
            write_file(&e.path().join("n.glb"), |w| w.write_all(b"new")).unwrap();
        }
        assert!(names(e.path()).is_empty());
    }

    #[test]
    fn a_commit_puts_every_output_in_place() {
        let d = tempfile::tempdir().unwrap();
        let (glb, json) = earlier(d.path());
        let mut set = OutputSet::new(&[]);
        set.file(&glb).unwrap();
        set.side_file(&json, "sidecar").unwrap();
        write_file(&glb, |w| w.write_all(b"new glb")).unwrap();
        side(&json, "sidecar", &serde_json::json!({"fps": 2}));
        let c = set.commit().unwrap();
        assert_eq!(c.written.len(), 2);
        assert_eq!(fs::read(&glb).unwrap(), b"new glb");
        assert!(fs::read_to_string(&json).unwrap().contains("\"fps\":2"));
        assert_eq!(names(d.path()), ["x.glb", "x.json"]);
    }

    #[test]
    fn a_side_file_replaces_only_surfcaps_own_and_never_an_input() {
        let d = tempfile::tempdir().unwrap();
        let notes = d.path().join("notes.json");
        fs::write(&notes, b"{\"mine\": true}").unwrap();
        let mut set = OutputSet::new(&[]);
        set.file(&d.path().join("notes.glb")).unwrap();
        let e = set.side_file(&notes, "sidecar").unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        assert_eq!(e.path.as_deref(), Some(notes.as_path()), "names the file: {e}");
        assert!(e.to_string().contains("surfcap did not write it"), "{e}");
        // Another kind of surfcap side file is not this one's either.
        let report = d.path().join("x.report.json");
        side(&report, "sidecar", &serde_json::json!({}));
        assert!(set.side_file(&report, "report").is_err());
        // An input, even one surfcap wrote, is refused as an input.
        let keys = d.path().join("poses.json");
        side(&keys, "sidecar", &serde_json::json!({}));
        let mut set = OutputSet::new(&[&keys]);
        let e = set.side_file(&keys, "sidecar").unwrap_err();
        assert!(e.to_string().contains("is the input"), "{e}");
        assert_eq!(fs::read(&notes).unwrap(), b"{\"mine\": true}");
    }

    #[test]
    fn two_outputs_of_one_command_cannot_share_a_place() {
        let d = tempfile::tempdir().unwrap();
        let mut set = OutputSet::new(&[]);
        set.file(&d.path().join("a.json")).unwrap();
        assert!(set.side_file(&d.path().join("a.json"), "sidecar").is_err());
        set.dir(&d.path().join("f"), "test", false).unwrap();
        assert!(set.file(&d.path().join("f/inner")).is_err());
    }

    #[test]
    fn a_folder_made_at_the_output_while_the_command_ran_is_kept() {
        let d = tempfile::tempdir().unwrap();
        let (glb, _) = earlier(d.path());
        let out = d.path().join("frames");
        let mut set = OutputSet::new(&[]);
        set.file(&glb).unwrap();
        set.dir(&out, "test", false).unwrap();
        write_file(&glb, |w| w.write_all(b"new glb")).unwrap();
        write_dir(&out, "test", false, |t| write_file(&t.join("f.obj"), |w| w.write_all(b"v"))).unwrap();
        fs::create_dir(&out).unwrap();
        fs::write(out.join("thesis.tex"), b"user").unwrap();
        let e = set.commit().unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        assert!(e.to_string().contains("changed while the command ran"), "{e}");
        assert_eq!(names(&out), ["thesis.tex"]);
        assert_eq!(fs::read(&glb).unwrap(), b"old glb", "the whole commit is refused");
        assert_eq!(names(d.path()), ["frames", "x.glb", "x.json"]);
    }

    #[test]
    fn a_forced_folder_is_replaced_only_if_it_is_still_the_same_folder() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("o");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("a"), b"user").unwrap();
        let mut set = OutputSet::new(&[]);
        set.dir(&out, "test", true).unwrap();
        write_dir(&out, "test", true, |_| Ok(())).unwrap();
        fs::rename(&out, d.path().join("moved")).unwrap();
        fs::create_dir(&out).unwrap();
        fs::write(out.join("b"), b"other user folder").unwrap();
        assert!(set.commit().is_err());
        assert_eq!(names(&out), ["b"]);
    }

    #[test]
    fn a_file_turned_into_a_folder_is_not_replaced() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("x.glb");
        let mut set = OutputSet::new(&[]);
        set.file(&f).unwrap();
        write_file(&f, |w| w.write_all(b"new")).unwrap();
        fs::create_dir(&f).unwrap();
        fs::write(f.join("keep"), b"user").unwrap();
        assert!(set.commit().is_err());
        assert_eq!(names(&f), ["keep"]);
        assert_eq!(names(d.path()), ["x.glb"]);
    }

    #[test]
    fn a_rename_failing_midway_puts_back_what_was_replaced() {
        let d = tempfile::tempdir().unwrap();
        let (glb, json) = earlier(d.path());
        let sidecar = fs::read(&json).unwrap();
        let out = d.path().join("o");
        write_dir(&out, "test", false, |t| write_file(&t.join("prev"), |w| w.write_all(b"1"))).unwrap();
        let new = d.path().join("new.txt");
        for fail_at in 0..4 {
            let mut set = OutputSet::new(&[]);
            set.file(&glb).unwrap();
            set.dir(&out, "test", false).unwrap();
            set.file(&new).unwrap();
            set.side_file(&json, "sidecar").unwrap();
            write_file(&glb, |w| w.write_all(b"new glb")).unwrap();
            write_dir(&out, "test", false, |t| write_file(&t.join("next"), |w| w.write_all(b"2"))).unwrap();
            write_file(&new, |w| w.write_all(b"n")).unwrap();
            side(&json, "sidecar", &serde_json::json!({"fps": 9}));
            let e = set
                .commit_with(&mut |s| {
                    if s == CommitStep::Renamed(fail_at) { Err(std::io::Error::other("disk gone")) } else { Ok(()) }
                })
                .unwrap_err();
            assert!(e.to_string().contains("put back"), "{e}");
            assert_eq!(fs::read(&glb).unwrap(), b"old glb", "failing at {fail_at}");
            assert_eq!(names(&out), [MARKER, "prev"]);
            assert!(!new.exists(), "no new file left behind");
            assert_eq!(fs::read(&json).unwrap(), sidecar);
            assert_eq!(names(d.path()), ["o", "x.glb", "x.json"]);
        }
    }

    #[test]
    fn a_claimed_folder_and_its_marker_reach_the_place_only_with_the_commit() {
        let d = tempfile::tempdir().unwrap();
        let user = d.path().join("userdir");
        fs::create_dir(&user).unwrap();
        fs::write(user.join("data.csv"), b"1,2").unwrap();
        {
            let mut set = OutputSet::new(&[]);
            set.dir(&user, "model", true).unwrap();
            let out = claim_dir(&user, "model", true).unwrap();
            write_file(&out.join("model.json"), |w| w.write_all(b"{}")).unwrap();
            assert_eq!(names(&user), ["data.csv"], "nothing written in the user's folder during the run");
            // The run fails (unknown sequence): the set is dropped.
        }
        assert_eq!(names(&user), ["data.csv"], "no marker left: the next run without --force is refused");
        let e = claim_dir(&user, "model", false).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        let mut set = OutputSet::new(&[]);
        set.dir(&user, "model", true).unwrap();
        let out = claim_dir(&user, "model", true).unwrap();
        write_file(&out.join("model.json"), |w| w.write_all(b"{}")).unwrap();
        set.commit().unwrap();
        assert_eq!(names(&user), [MARKER, "model.json"]);
        assert_eq!(names(d.path()), ["userdir"]);
    }

    #[test]
    fn a_forced_claim_outside_a_set_never_marks_a_users_folder() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("mine.txt"), b"user").unwrap();
        assert!(claim_dir(d.path(), "model", true).is_err());
        assert_eq!(names(d.path()), ["mine.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_read_only_folder_is_refused_before_the_commit_and_never_hidden() {
        use std::os::unix::fs::PermissionsExt;
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("ro");
        fs::create_dir_all(out.join("sub")).unwrap();
        fs::write(out.join("sub/mine.txt"), b"user").unwrap();
        fs::set_permissions(out.join("sub"), fs::Permissions::from_mode(0o555)).unwrap();
        let mut set = OutputSet::new(&[]);
        let e = set.dir(&out, "test", true).unwrap_err();
        assert!(e.to_string().contains("not writable"), "{e}");
        let e = write_dir(&out, "test", true, |_| Ok(())).unwrap_err();
        assert!(e.to_string().contains("not writable"), "{e}");
        fs::set_permissions(out.join("sub"), fs::Permissions::from_mode(0o755)).unwrap();
        assert_eq!(names(d.path()), ["ro"], "nothing moved aside");
        assert_eq!(fs::read(out.join("sub/mine.txt")).unwrap(), b"user");
    }

    #[test]
    fn a_previous_folder_that_cannot_be_removed_is_kept_under_a_visible_name() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("o");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("mine.txt"), b"user").unwrap();
        let mut set = OutputSet::new(&[]);
        set.dir(&out, "test", true).unwrap();
        write_dir(&out, "test", true, |_| Ok(())).unwrap();
        let c = set
            .commit_with(&mut |s| {
                if matches!(s, CommitStep::RemovePrevious(_)) { Err(std::io::Error::other("busy")) } else { Ok(()) }
            })
            .unwrap();
        let kept = d.path().join("o.previous");
        assert_eq!(c.kept_previous, [(fs::canonicalize(&out).unwrap(), fs::canonicalize(&kept).unwrap())]);
        assert_eq!(fs::read(kept.join("mine.txt")).unwrap(), b"user");
        assert_eq!(names(d.path()), ["o", "o.previous"]);
    }
}
