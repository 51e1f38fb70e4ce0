//! The temporaries of atomic writes (`.NAME.tmp-PID` files and folders, `.NAME.old-PID` for a
//! previous folder output moved aside), known process-wide so that nothing is left behind:
//! a front end that catches SIGINT/SIGTERM calls [`remove_live`] before it exits, and every
//! write first sweeps the stale temporaries a killed run (SIGKILL, abort, power loss) left next
//! to its output (`sweep_stale`).
//!
//! Only names of surfcap's exact pattern are touched, and only when their PID is not a live
//! process: another surfcap run writing the same output at the same time keeps its temporaries.
//! A stale `.NAME.old-PID` folder is removed only when it is surfcap's own earlier output (it
//! holds surfcap's marker); a folder of the user's moved aside by a forced run that was killed is
//! renamed to a visible `NAME.previous`, never deleted.
//!
//! The commits of `crate::output_set` hold a process-wide commit lock and record what they put in
//! place, so a front end that catches a signal asks [`stop_for_signal`]: it waits for a commit in
//! progress, then either removes the live temporaries (the run was interrupted, every previous
//! output kept) or, when nothing was in progress and outputs were committed, says they are
//! complete.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// A live temporary and what undoing it means.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Live {
    /// A file or folder being written: removed.
    Temp(PathBuf),
    /// The previous folder output `aside` moved away from `output` while the new one is renamed
    /// in: put back when `output` is missing, else removed.
    Aside { aside: PathBuf, output: PathBuf },
}

static LIVE: Mutex<Vec<Live>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<Live>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// The temporary sibling `.NAME.TAG-PID` of `path` (`path` must be absolute and have a name).
pub(crate) fn sibling(path: &Path, tag: &str) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.{tag}-{}", std::process::id()))
}

/// Whether `path` lies inside a live temporary folder (a folder output being built).
pub(crate) fn inside_live(path: &Path) -> bool {
    live().iter().any(|e| matches!(e, Live::Temp(t) if path.starts_with(t) && path != t))
}

/// Registers `tmp` as live until the returned guard is dropped (the write has renamed or
/// removed it by then).
pub(crate) fn register(tmp: &Path) -> Registered {
    let entry = Live::Temp(tmp.to_path_buf());
    live().push(entry.clone());
    Registered(entry)
}

/// Unregisters its temporary when dropped.
#[must_use]
pub(crate) struct Registered(Live);

/// The outputs committed so far by this process; locked for the whole of a commit.
static COMMITTED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Registers a previous output moved aside (`aside`, from `output`) until the guard is
/// dropped: on a signal it is put back when `output` is missing, else removed.
pub(crate) fn register_aside(aside: &Path, output: &Path) -> Registered {
    let entry = Live::Aside { aside: aside.to_path_buf(), output: output.to_path_buf() };
    live().push(entry.clone());
    Registered(entry)
}

/// The commit lock: held by `crate::output_set` while it renames outputs into place, and by the
/// signal handler before it decides.
pub(crate) fn commit_lock() -> MutexGuard<'static, Vec<PathBuf>> {
    COMMITTED.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a signal stopped, as [`stop_for_signal`] and [`signal_outcome`] say.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SignalOutcome {
    /// Work was in progress: its temporaries are (or would be) removed and every previous
    /// output kept. `completed` lists outputs an earlier commit of this run had already put in
    /// place.
    Interrupted { completed: Vec<PathBuf> },
    /// Nothing was in progress and these outputs were committed whole: the run's outputs are
    /// complete.
    Completed(Vec<PathBuf>),
}

fn outcome(committed: &[PathBuf], live: &[Live]) -> SignalOutcome {
    if live.is_empty() && !committed.is_empty() {
        SignalOutcome::Completed(committed.to_vec())
    } else {
        SignalOutcome::Interrupted { completed: committed.to_vec() }
    }
}

/// What a signal would stop now: waits for a commit in progress, changes nothing.
pub fn signal_outcome() -> SignalOutcome {
    let c = commit_lock();
    let l = live();
    outcome(&c, &l)
}

/// For a front end about to exit on a signal: waits for a commit in progress to finish, then
/// removes every live temporary (putting back a previous output moved aside) when work was in
/// progress. Both registries stay locked afterwards, so no thread starts or finishes a write or
/// a commit meanwhile: call this only right before exiting the process.
pub fn stop_for_signal() -> SignalOutcome {
    let c = commit_lock();
    let l = live();
    let o = outcome(&c, &l);
    for e in l.iter().rev() {
        undo(e);
    }
    std::mem::forget(l);
    std::mem::forget(c);
    o
}

impl Drop for Registered {
    fn drop(&mut self) {
        let mut l = live();
        if let Some(i) = l.iter().rposition(|e| *e == self.0) {
            l.remove(i);
        }
    }
}

pub(crate) fn remove_any(p: &Path) {
    // A folder may still be filled by the writing thread: retry a few times.
    for _ in 0..5 {
        match fs::symlink_metadata(p) {
            Ok(m) if m.is_dir() => {
                if fs::remove_dir_all(p).is_ok() {
                    return;
                }
            }
            Ok(_) => {
                let _ = fs::remove_file(p);
                return;
            }
            Err(_) => return,
        }
    }
}

fn undo(e: &Live) {
    match e {
        Live::Temp(p) => remove_any(p),
        Live::Aside { aside, output } => {
            if fs::symlink_metadata(output).is_err() {
                let _ = fs::rename(aside, output);
            } else if is_surfcaps_own(aside) {
                remove_any(aside);
            } else {
                // A folder of the user's replaced with --force by a run killed before it removed
                // it: made visible again, never deleted.
                let _ = fs::rename(aside, visible_name(output));
            }
        }
    }
}

/// Removes every live temporary (and puts back a previous output moved aside), for a front end
/// about to exit on a signal: [`stop_for_signal`] without its answer. The registries stay locked
/// afterwards: call this only right before exiting the process.
pub fn remove_live() {
    let _ = stop_for_signal();
}

/// A free visible name for a previous folder kept beside `output`: `NAME.previous`, else
/// `NAME.previous-2`, `-3`...
pub(crate) fn visible_name(output: &Path) -> PathBuf {
    let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut visible = output.with_file_name(format!("{name}.previous"));
    let mut k = 1;
    while fs::symlink_metadata(&visible).is_ok() {
        k += 1;
        visible = output.with_file_name(format!("{name}.previous-{k}"));
    }
    visible
}

/// Whether a previous output moved aside may be removed: a file (an output surfcap replaced
/// with the user's leave), or a folder holding surfcap's marker. A folder without it is the
/// user's and stays.
fn is_surfcaps_own(aside: &Path) -> bool {
    match fs::symlink_metadata(aside) {
        Ok(m) if m.is_dir() => crate::output_path::has_marker(aside),
        Ok(_) => true,
        Err(_) => false,
    }
}

fn pid_is_live(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else { return false };
        // SAFETY: signal 0 only checks that the process exists and may be signalled.
        let r = unsafe { libc::kill(pid, 0) };
        r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// The PID in `.NAME.TAG-PID` when `entry` is exactly that pattern for `name` and `tag`.
fn temp_pid(entry: &str, name: &str, tag: &str) -> Option<u32> {
    let digits =
        entry.strip_prefix('.')?.strip_prefix(name)?.strip_prefix('.')?.strip_prefix(tag)?.strip_prefix('-')?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// Removes the stale `.NAME.tmp-PID` and `.NAME.old-PID` siblings of `output` (absolute) whose
/// process is gone. A stale `.old` is a previous output moved aside by a run killed before it
/// renamed the new one in: it is put back when `output` is missing, else removed when it is
/// surfcap's own (a file, or a folder with surfcap's marker), else renamed to a visible
/// `NAME.previous`.
pub(crate) fn sweep_stale(output: &Path) {
    let (Some(dir), Some(name)) = (output.parent(), output.file_name().and_then(|n| n.to_str())) else {
        return;
    };
    let Ok(entries) = fs::read_dir(dir) else { return };
    let me = std::process::id();
    let mut olds = Vec::new();
    for e in entries.flatten() {
        let entry = e.file_name();
        let Some(entry) = entry.to_str() else { continue };
        if temp_pid(entry, name, "tmp").is_some_and(|p| p != me && !pid_is_live(p)) {
            remove_any(&dir.join(entry));
        } else if temp_pid(entry, name, "old").is_some_and(|p| p != me && !pid_is_live(p)) {
            olds.push(dir.join(entry));
        }
    }
    for aside in olds {
        undo(&Live::Aside { aside, output: output.to_path_buf() });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_exact_pattern_is_a_temporary() {
        assert_eq!(temp_pid(".out.glb.tmp-123", "out.glb", "tmp"), Some(123));
        assert_eq!(temp_pid(".out.glb.old-7", "out.glb", "old"), Some(7));
        for other in [".out.glb.tmp-", ".out.glb.tmp-12x", "out.glb.tmp-12", ".out.glb.tmp-12.bak", ".x.glb.tmp-12"] {
            assert_eq!(temp_pid(other, "out.glb", "tmp"), None, "{other}");
        }
    }

    /// A PID no process has: above the kernel's maximum (2^22 on Linux).
    const DEAD: u32 = 99_999_999;

    #[test]
    fn stale_temporaries_of_dead_processes_are_swept_and_nothing_else() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("a.glb");
        fs::write(&out, b"old output").unwrap();
        let stale_file = d.path().join(format!(".a.glb.tmp-{DEAD}"));
        fs::write(&stale_file, b"half").unwrap();
        let stale_dir = d.path().join(format!(".a.glb.old-{DEAD}"));
        fs::create_dir(&stale_dir).unwrap();
        fs::write(stale_dir.join("x"), b"1").unwrap();
        crate::output_path::write_marker(&stale_dir, "test").unwrap();
        let live_one = d.path().join(format!(".a.glb.tmp-{}", std::process::id()));
        fs::write(&live_one, b"mine").unwrap();
        let keep = [".a.glb.tmp-12x", ".b.glb.tmp-99999999", "a.glb.tmp-99999999"];
        for k in keep {
            fs::write(d.path().join(k), b"user").unwrap();
        }
        sweep_stale(&out);
        assert!(!stale_file.exists() && !stale_dir.exists());
        assert!(live_one.exists(), "this process's temporary is live");
        for k in keep {
            assert!(d.path().join(k).exists(), "{k} is not surfcap's");
        }
        assert_eq!(fs::read(&out).unwrap(), b"old output");
    }

    #[test]
    fn a_stale_previous_folder_of_the_users_is_never_swept() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("o");
        fs::create_dir(&out).unwrap();
        let aside = d.path().join(format!(".o.old-{DEAD}"));
        fs::create_dir(&aside).unwrap();
        fs::write(aside.join("thesis.tex"), b"user").unwrap();
        sweep_stale(&out);
        let visible = d.path().join("o.previous");
        assert_eq!(fs::read(visible.join("thesis.tex")).unwrap(), b"user", "no marker: not surfcap's to delete");
        assert!(!aside.exists(), "made visible again");
    }

    #[test]
    fn a_stale_previous_output_is_put_back_when_the_output_is_missing() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("o");
        let aside = d.path().join(format!(".o.old-{DEAD}"));
        fs::create_dir(&aside).unwrap();
        fs::write(aside.join("f"), b"prev").unwrap();
        sweep_stale(&out);
        assert_eq!(fs::read(out.join("f")).unwrap(), b"prev");
    }
}
