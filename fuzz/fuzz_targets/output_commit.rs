//! The output commit (`surfcap_mesh::output_set`) against random pre-existing things at every
//! planned path: regular user files, surfcap's own earlier outputs, symlinks to a victim file or
//! folder outside, FIFOs, folders with user files, empty folders, the command's input. The
//! outputs (a file, two side files, a folder; sometimes the input itself) are planned, staged
//! or failed at a random step, changed behind the command's back, then committed (failing at a
//! random commit step) or dropped. Checked on the whole tree, links not followed:
//!
//! - after a failure, everything is exactly as it was (no new file, no temporary);
//! - after a commit, only the planned places changed, and each only if the rules allow it: a
//!   file output over nothing or a regular file (through a symlink too); a side file over
//!   nothing or surfcap's own side file of its kind; a folder over nothing, an empty folder,
//!   surfcap's own folder of its kind, or with force a folder still the one seen when planned;
//!   never the input, never anything touched during the run;
//! - no `.NAME.tmp-PID` or `.NAME.old-PID` is ever left.
#![no_main]
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use libfuzzer_sys::fuzz_target;
use surfcap_mesh::atomic::{write_dir, write_file};
use surfcap_mesh::output_path::{MARKER, resolve};
use surfcap_mesh::output_set::{CommitStep, OutputSet};

unsafe extern "C" {
    fn mkfifo(path: *const std::ffi::c_char, mode: u32) -> i32;
}

struct Bytes<'a>(&'a [u8], usize);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let b = self.0.get(self.1).copied().unwrap_or(0);
        self.1 += 1;
        b
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Node {
    File(Vec<u8>),
    Dir,
    Link(PathBuf),
    Other,
}

/// Every entry under `root` but surfcap's temporaries (listed apart: staged outputs exist while
/// the command runs).
fn snapshot(root: &Path) -> BTreeMap<PathBuf, Node> {
    snapshot_and_temporaries(root).0
}

fn is_temporary(p: &Path) -> bool {
    let name = p.file_name().unwrap().to_string_lossy();
    name.contains(".tmp-") || name.contains(".old-")
}

fn snapshot_and_temporaries(root: &Path) -> (BTreeMap<PathBuf, Node>, Vec<PathBuf>) {
    let mut out = BTreeMap::new();
    let mut temporaries = Vec::new();
    let mut todo = vec![root.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if is_temporary(&p) {
                temporaries.push(p);
                continue;
            }
            let m = fs::symlink_metadata(&p).unwrap();
            let node = if m.file_type().is_symlink() {
                Node::Link(fs::read_link(&p).unwrap())
            } else if m.is_dir() {
                todo.push(p.clone());
                Node::Dir
            } else if m.is_file() {
                Node::File(fs::read(&p).unwrap())
            } else {
                Node::Other
            };
            out.insert(p.strip_prefix(root).unwrap().to_path_buf(), node);
        }
    }
    (out, temporaries)
}

/// An earlier side file of `kind`, as `surfcap_mesh::output_set::Stamped` writes them.
fn stamped(kind: &str) -> Vec<u8> {
    format!("{{\"written_by\": \"surfcap\", \"output_kind\": \"{kind}\", \"earlier\": true}}").into_bytes()
}

fn marker(kind: &str) -> String {
    format!("{{\"written_by\": \"surfcap\", \"kind\": \"{kind}\"}}")
}

/// Puts thing `what` at `path`.
fn put(path: &Path, what: u8, root: &Path) {
    let _ = fs::create_dir_all(path.parent().unwrap());
    match what % 11 {
        0 => {}
        1 => fs::write(path, b"user file").unwrap(),
        2 => fs::write(path, stamped("sidecar")).unwrap(),
        3 => fs::write(path, stamped("report")).unwrap(),
        4 => std::os::unix::fs::symlink(root.join("victim/v.txt"), path).unwrap(),
        5 => std::os::unix::fs::symlink(root.join("victim/vd"), path).unwrap(),
        6 => {
            let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            unsafe { mkfifo(c.as_ptr(), 0o644) };
        }
        7 => {
            fs::create_dir(path).unwrap();
            fs::write(path.join("mine.txt"), b"user").unwrap();
        }
        8 => {
            fs::create_dir(path).unwrap();
            fs::write(path.join(MARKER), marker("k")).unwrap();
            fs::write(path.join("old-output"), b"earlier").unwrap();
        }
        9 => fs::create_dir(path).unwrap(),
        _ => std::os::unix::fs::symlink(root.join("work/in.txt"), path).unwrap(),
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Role {
    File,
    Side(&'static str),
    Dir(bool),
}

/// Whether the rules allow `role` to replace what is at `resolved` (looked at before the run).
fn allowed(role: Role, resolved: &Path, input: &Path) -> bool {
    if resolved.starts_with(input) || input.starts_with(resolved) {
        return false;
    }
    let m = match fs::symlink_metadata(resolved) {
        Err(_) => return true,
        Ok(m) => m,
    };
    match role {
        Role::File => m.is_file(),
        Role::Side(kind) => m.is_file() && fs::read(resolved).unwrap() == stamped(kind),
        Role::Dir(force) => {
            m.is_dir()
                && (force
                    || fs::read_dir(resolved).unwrap().next().is_none()
                    || fs::read_to_string(resolved.join(MARKER)).is_ok_and(|s| s == marker("k")))
        }
    }
}

static RUN: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data, 0);
    let n = RUN.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let root = std::env::temp_dir().join(format!("surfcap-fuzz-commit-{}-{n}", std::process::id()));
    let _ = fs::remove_dir_all(&root);
    fs::create_dir_all(root.join("work")).unwrap();
    fs::create_dir_all(root.join("victim/vd")).unwrap();
    fs::write(root.join("victim/v.txt"), b"victim").unwrap();
    fs::write(root.join("victim/vd/f"), b"victim folder file").unwrap();
    let root = fs::canonicalize(&root).unwrap();
    let input = root.join("work/in.txt");
    fs::write(&input, b"input").unwrap();
    let work = root.join("work");
    let force = b.u8() & 1 == 1;
    let mut planned: Vec<(PathBuf, Role)> = vec![
        (work.join("a.glb"), Role::File),
        (work.join("a.json"), Role::Side("sidecar")),
        (work.join("a.report.json"), Role::Side("report")),
        (work.join("d"), Role::Dir(force)),
    ];
    if b.u8() % 8 == 0 {
        planned.push((input.clone(), Role::File));
    }
    for (p, _) in &planned {
        if p != &input {
            put(p, b.u8(), &root);
        }
    }
    let before = snapshot(&root);
    let allowed_at: Vec<(PathBuf, bool)> = planned
        .iter()
        .map(|(p, role)| {
            let r = resolve(p).unwrap();
            let ok = allowed(*role, &r, &input);
            (r, ok)
        })
        .collect();

    let mut set = OutputSet::new(&[&input]);
    let mut plan_ok = true;
    for (p, role) in &planned {
        let r = match role {
            Role::File => set.file(p),
            Role::Side(kind) => set.side_file(p, kind),
            Role::Dir(force) => set.dir(p, "k", *force),
        };
        if r.is_err() {
            plan_ok = false;
            break;
        }
    }
    // Stage each output, fail one, or leave it unwritten.
    if plan_ok {
        for (p, role) in &planned {
            match (b.u8() % 4, role) {
                (0, _) => {}
                (1, Role::Dir(_)) => {
                    let _ = write_dir(p, "k", *role == Role::Dir(true), |_| {
                        Err(surfcap_mesh::Error::new(surfcap_mesh::ErrorKind::Io, "failed midway"))
                    });
                }
                (1, _) => {
                    let _ = write_file(p, |w| {
                        w.write_all(b"half")?;
                        Err(std::io::Error::other("failed midway"))
                    });
                }
                (_, Role::Dir(force)) => {
                    write_dir(p, "k", *force, |t| write_file(&t.join("new.obj"), |w| w.write_all(b"new"))).unwrap();
                }
                (_, Role::Side(kind)) => {
                    let body = format!("{{\"written_by\": \"surfcap\", \"output_kind\": \"{kind}\", \"new\": true}}");
                    write_file(p, |w| w.write_all(body.as_bytes())).unwrap();
                }
                (_, Role::File) => write_file(p, |w| w.write_all(b"new output")).unwrap(),
            }
        }
    }
    // Something changes at a planned place while the command runs.
    let mut touched: Option<PathBuf> = None;
    let interfere = b.u8();
    if interfere % 4 == 0 {
        let (p, _) = &planned[(interfere as usize / 4) % planned.len()];
        let r = resolve(p).unwrap();
        if fs::symlink_metadata(&r).is_err() && r.starts_with(&root) {
            // A FIFO or a folder with a file of the user's: not surfcap's to replace.
            put(&r, b.u8() % 2 + 6, &root);
            touched = Some(r);
        }
    }
    let before = if touched.is_some() { snapshot(&root) } else { before };
    let fail_at = b.u8();
    let committed = if plan_ok && b.u8() % 4 != 0 {
        let mut k = 0u8;
        set.commit_with(&mut |step| {
            k = k.wrapping_add(1);
            if fail_at % 16 == k && !matches!(step, CommitStep::AllInPlace | CommitStep::RemovePrevious(_)) {
                Err(std::io::Error::other("injected"))
            } else {
                Ok(())
            }
        })
        .is_ok()
    } else {
        drop(set);
        false
    };
    let (after, left) = snapshot_and_temporaries(&root);
    assert!(left.is_empty(), "temporaries left: {left:?}");
    if !committed {
        assert_eq!(before, after, "a failed run changed something");
    } else {
        assert!(plan_ok);
        let may_change = |rel: &Path| {
            let abs = root.join(rel);
            allowed_at.iter().any(|(r, ok)| abs.starts_with(r) && (*ok && touched.as_ref() != Some(r)))
        };
        for (p, node) in &before {
            if after.get(p) != Some(node) {
                assert!(
                    may_change(p),
                    "{p:?} changed though surfcap may not replace it: {node:?} -> {:?}",
                    after.get(p)
                );
            }
        }
        for p in after.keys() {
            if !before.contains_key(p) {
                assert!(may_change(p), "{p:?} appeared outside the planned outputs");
            }
        }
        assert_eq!(fs::read(&input).unwrap(), b"input", "the input was changed");
    }
    let _ = fs::remove_dir_all(&root);
});
