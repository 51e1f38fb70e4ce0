//! Entries of surfcap's derived caches, treated as a trust boundary: an entry is one of
//! surfcap's own names inside a cache folder that only the user can write, its bytes are checked
//! against a content hash before they are used, and nothing outside the folder is ever read,
//! written or removed through it.
//!
//! - The cache folder is created private (0700). A folder owned by another user, or writable by
//!   group or others and not sticky, is refused, as ssh refuses such a folder for its keys
//!   (StrictModes): anyone who can write it could plant entries. In a sticky shared folder (like
//!   `/tmp`) only entries owned by this user are read or replaced.
//! - Symbolic links are never followed at an entry's name: entries are opened with `O_NOFOLLOW`
//!   (and `O_NONBLOCK`, so a FIFO there cannot block the run), and a symlink, FIFO, device or
//!   empty folder at an entry's name is removed as a name and replaced; its target is never
//!   touched. A non-empty folder or another user's file there is left alone, and the entry is
//!   not stored. Every such case is said through a note.
//! - An entry is written as a temporary inside the cache folder (`.NAME.tmp-PID`, created new,
//!   mode 0600, never through a link) and renamed onto its name; the rename replaces the name
//!   itself. Unlike [`crate::atomic::write_file`], which resolves a user's output through its
//!   links on purpose, the cache never resolves an entry's path.
//! - Every entry has a content hash beside it, `NAME.b3`: the BLAKE3 hash of its bytes (of each
//!   file's name and bytes for a folder entry), written in the format of `b3sum`, so
//!   `b3sum -c NAME.b3` checks it by hand. A sidecar rather than a header key: `np.load` refuses
//!   unknown keys in a `.npy` header, and the entries must stay loadable by numpy. An entry whose
//!   hash is missing or does not match is not used (the caller recomputes and replaces it). The
//!   hash is computed while the entry is read, so verifying costs no second pass over the file.
//! - Folder entries (a trained model) are built in a temporary folder inside the cache and
//!   swapped in; an existing real folder is replaced only when it holds surfcap's marker of the
//!   same kind, never by force.

use std::fs;
use std::io::{BufReader, BufWriter, Read, Write};
use std::os::unix::fs::{DirBuilderExt, FileTypeExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

use crate::error::{Error, ErrorKind, Result};
use crate::output_path::MARKER;
use crate::temporaries::{register, register_aside, sibling, sweep_stale};

/// The suffix of an entry's content-hash sidecar.
pub const HASH_SUFFIX: &str = ".b3";

/// What reading an entry found.
#[derive(Debug)]
pub enum EntryRead<T> {
    /// Nothing usable is stored under the name and there is nothing to say (a new entry).
    Missing,
    /// The entry, verified against its content hash.
    Read(T),
    /// Something is at the name but cannot be used; the error says what and names the entry.
    Unusable(Error),
}

fn refused(path: &Path, message: String) -> Error {
    Error::new(ErrorKind::Refused, message).in_file(path)
}

fn euid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// What a non-regular thing at a name is, in words.
fn what_is(t: &fs::FileType) -> &'static str {
    if t.is_symlink() {
        "a symbolic link"
    } else if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else {
        "a regular file"
    }
}

/// Says what a symlink at `path` points to, for notes ("a symbolic link to X").
fn describe(path: &Path, t: &fs::FileType) -> String {
    match (t.is_symlink(), fs::read_link(path)) {
        (true, Ok(target)) => format!("a symbolic link to {}", target.display()),
        _ => what_is(t).to_string(),
    }
}

/// Makes sure `dir` can hold a cache: creates it private (0700) when missing, and refuses a
/// folder owned by another user, or writable by group or others without the sticky bit.
pub fn check_folder(dir: &Path) -> Result<()> {
    fs::DirBuilder::new()
        .recursive(true)
        .mode(0o700)
        .create(dir)
        .map_err(|e| Error::io(dir, "create the cache folder", e))?;
    // The folder itself may be reached through a link (`~/.cache` on another disk): only the
    // entries inside are never followed.
    let m = fs::metadata(dir).map_err(|e| Error::io(dir, "look at the cache folder", e))?;
    if !m.is_dir() {
        return Err(refused(dir, "is not a folder: expected a cache folder; choose another --cache-dir".into()));
    }
    if m.uid() != euid() {
        return Err(refused(
            dir,
            format!(
                "the cache folder belongs to another user (uid {}): surfcap keeps its cache only in a folder of yours; choose another --cache-dir",
                m.uid()
            ),
        ));
    }
    let mode = m.mode() & 0o7777;
    if mode & 0o022 != 0 && mode & 0o1000 == 0 {
        return Err(refused(
            dir,
            format!(
                "the cache folder is writable by other users (mode {mode:04o}): they could plant or replace its entries; make it private (chmod 700 {}) or choose another --cache-dir",
                dir.display()
            ),
        ));
    }
    Ok(())
}

/// The content-hash sidecar of an entry.
pub fn hash_path(entry: &Path) -> PathBuf {
    let mut s = entry.as_os_str().to_owned();
    s.push(HASH_SUFFIX);
    PathBuf::from(s)
}

/// Opens the regular file at `path` for reading without following a link or blocking on a
/// FIFO, and checks that it is this user's regular file.
fn open_own_file(path: &Path) -> std::result::Result<fs::File, Error> {
    let f = fs::OpenOptions::new().read(true).custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK).open(path).map_err(
        |e| {
            if e.raw_os_error() == Some(libc::ELOOP) {
                refused(path, "is a symbolic link: the cache never follows one".into())
            } else {
                Error::io(path, "read", e)
            }
        },
    )?;
    let m = f.metadata().map_err(|e| Error::io(path, "look at", e))?;
    if !m.is_file() {
        return Err(refused(path, format!("is {}: expected a cache entry file", what_is(&m.file_type()))));
    }
    if m.uid() != euid() {
        return Err(refused(path, format!("belongs to another user (uid {}): not trusted", m.uid())));
    }
    Ok(f)
}

/// The hash recorded in the sidecar of `entry`.
fn recorded_hash(entry: &Path) -> Result<blake3::Hash> {
    let side = hash_path(entry);
    let f = open_own_file(&side).map_err(|e| match e.kind {
        ErrorKind::Io => refused(entry, "has no content hash beside it (NAME.b3): it cannot be verified".into()),
        _ => e,
    })?;
    let mut text = String::new();
    f.take(4096).read_to_string(&mut text).map_err(|e| Error::io(&side, "read", e))?;
    let hex = text.split_whitespace().next().unwrap_or("");
    blake3::Hash::from_hex(hex).map_err(|_| refused(&side, "expected a BLAKE3 hash in b3sum's format".into()))
}

/// A reader that hashes what passes through it.
struct Hashing<R> {
    inner: R,
    hasher: blake3::Hasher,
}

impl<R: Read> Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
}

/// A writer that hashes what passes through it.
struct HashingWriter<W> {
    inner: W,
    hasher: blake3::Hasher,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Looks at what is at an entry's name before reading it: `Ok(true)` for a regular file,
/// `Ok(false)` for nothing, else what it is (to be replaced when the entry is stored).
fn look_before_reading(path: &Path) -> std::result::Result<bool, Error> {
    match fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(Error::io(path, "look at", e)),
        Ok(m) if m.is_file() => Ok(true),
        Ok(m) => Err(refused(
            path,
            format!("is {}, not a cache entry: it is not followed or read", describe(path, &m.file_type())),
        )),
    }
}

/// Reads the file entry at `path` through `read` (given the bytes and their count), checking
/// them against the entry's content hash when `verify` (always, except to measure its cost).
/// `read` runs before the hash is known: its value is returned only once the hash matches.
pub fn read_file_entry<T>(
    path: &Path,
    verify: bool,
    read: impl FnOnce(&mut dyn Read, u64) -> Result<T>,
) -> EntryRead<T> {
    match look_before_reading(path) {
        Ok(false) => return EntryRead::Missing,
        Ok(true) => {}
        Err(e) => return EntryRead::Unusable(e),
    }
    let run = || -> Result<T> {
        let expected = if verify { Some(recorded_hash(path)?) } else { None };
        let f = open_own_file(path)?;
        let len = f.metadata().map_err(|e| Error::io(path, "look at", e))?.len();
        let mut r = Hashing { inner: BufReader::with_capacity(1 << 20, f), hasher: blake3::Hasher::new() };
        let value = read(&mut r, len);
        let Some(expected) = expected else { return value.map_err(|e| e.in_file(path)) };
        // Whatever `read` left (it may stop early on an error) is hashed too.
        std::io::copy(&mut r, &mut std::io::sink()).map_err(|e| Error::io(path, "read", e))?;
        if r.hasher.finalize() != expected {
            return Err(refused(
                path,
                "its content does not match its hash (NAME.b3): damaged or changed since surfcap wrote it".into(),
            ));
        }
        value.map_err(|e| e.in_file(path))
    };
    match run() {
        Ok(v) => EntryRead::Read(v),
        Err(e) => EntryRead::Unusable(e),
    }
}

/// Frees an entry's name for a rename onto it: nothing there, a regular file of this user's
/// (replaced by the rename), or a symlink, FIFO, socket, device or empty folder, which is
/// removed as a name (a link's target is never touched) with a note. A non-empty folder, or
/// another user's file, is refused.
fn make_room(path: &Path, for_folder: bool, note: &mut dyn FnMut(String)) -> Result<()> {
    let m = match fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(path, "look at", e)),
        Ok(m) => m,
    };
    let t = m.file_type();
    if m.uid() != euid() {
        return Err(refused(
            path,
            format!("is {} of another user (uid {}): surfcap replaces only its own entries", what_is(&t), m.uid()),
        ));
    }
    if t.is_file() && !for_folder {
        return Ok(());
    }
    if t.is_file() {
        return Err(refused(
            path,
            "is a file where a cache folder goes: surfcap did not write it, so it is left alone".into(),
        ));
    }
    let what = describe(path, &t);
    if t.is_dir() {
        fs::remove_dir(path).map_err(|_| {
            refused(
                path,
                "is a folder holding files where a cache entry goes: surfcap did not write it, so it is left alone"
                    .into(),
            )
        })?;
    } else {
        fs::remove_file(path).map_err(|e| Error::io(path, "remove", e))?;
    }
    note(format!(
        "cache entry {}: was {what}; removed as a name (nothing it points to was touched) and replaced",
        path.display()
    ));
    Ok(())
}

/// Creates `tmp` as a new file of this user's (0600), never through a link; whatever a dead
/// run of the same PID left at that name is removed first.
fn create_temp(tmp: &Path) -> Result<fs::File> {
    let open =
        || fs::OpenOptions::new().write(true).create_new(true).mode(0o600).custom_flags(libc::O_NOFOLLOW).open(tmp);
    match open() {
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            match fs::symlink_metadata(tmp) {
                Ok(m) if !m.is_dir() => fs::remove_file(tmp).map_err(|e| Error::io(tmp, "remove", e))?,
                _ => return Err(refused(tmp, "is in the way of a cache entry's temporary".into())),
            }
            open().map_err(|e| Error::io(tmp, "create", e))
        }
        r => r.map_err(|e| Error::io(tmp, "create", e)),
    }
}

/// Writes a small file of the cache (a hash sidecar) as a temporary renamed onto `path`.
fn put_small(path: &Path, bytes: &[u8], note: &mut dyn FnMut(String)) -> Result<()> {
    let tmp = sibling(path, "tmp");
    let _live = register(&tmp);
    let result = (|| {
        let mut f = create_temp(&tmp)?;
        f.write_all(bytes).and_then(|()| f.sync_all()).map_err(|e| Error::io(&tmp, "write", e))?;
        make_room(path, false, note)?;
        fs::rename(&tmp, path).map_err(|e| Error::io(path, "rename into place", e))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// The sidecar text of `hash` for the entry `path`, in `b3sum`'s format.
fn sidecar_text(hash: &blake3::Hash, path: &Path) -> String {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    format!("{}  {name}\n", hash.to_hex())
}

/// Stores a file entry at `path` (inside a folder checked by [`check_folder`]) through `write`,
/// with its content hash; see the module documentation for what may be replaced. Notes say
/// what was at the name when it was not an entry.
pub fn store_file_entry(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    note: &mut dyn FnMut(String),
) -> Result<()> {
    sweep_stale(path);
    let tmp = sibling(path, "tmp");
    let _live = register(&tmp);
    let result = (|| {
        let f = create_temp(&tmp)?;
        let mut w = HashingWriter { inner: BufWriter::with_capacity(1 << 20, f), hasher: blake3::Hasher::new() };
        write(&mut w).and_then(|()| w.flush()).map_err(|e| Error::io(&tmp, "write", e))?;
        let hash = w.hasher.finalize();
        let f = w.inner.into_inner().map_err(|e| Error::io(&tmp, "write", e.into_error()))?;
        f.sync_all().map_err(|e| Error::io(&tmp, "write", e))?;
        make_room(path, false, note)?;
        fs::rename(&tmp, path).map_err(|e| Error::io(path, "rename into place", e))?;
        // Until the sidecar is renamed in, the entry does not match the old hash (if any), so
        // an interruption here leaves an entry that is recomputed, never one that is trusted.
        put_small(&hash_path(path), sidecar_text(&hash, path).as_bytes(), note)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// The content hash of a folder entry: every file's name, length and bytes, in name order.
/// Anything in it that is not a regular file of this user's makes it unusable.
fn folder_hash(dir: &Path) -> Result<blake3::Hash> {
    let mut names = Vec::new();
    for e in fs::read_dir(dir).map_err(|e| Error::io(dir, "list", e))? {
        names.push(e.map_err(|e| Error::io(dir, "list", e))?.file_name());
    }
    names.sort();
    let mut h = blake3::Hasher::new();
    h.update(b"surfcap-cache-folder-v1");
    for name in names {
        let p = dir.join(&name);
        let m = fs::symlink_metadata(&p).map_err(|e| Error::io(&p, "look at", e))?;
        if !m.is_file() {
            return Err(refused(
                &p,
                format!("is {} inside a cache entry: expected only files", what_is(&m.file_type())),
            ));
        }
        let bytes = name.as_encoded_bytes();
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
        h.update(&m.len().to_le_bytes());
        let mut r = open_own_file(&p)?;
        std::io::copy(&mut r, &mut h).map_err(|e| Error::io(&p, "read", e))?;
    }
    Ok(h.finalize())
}

/// Checks the folder entry at `path` of `kind`: a real folder of this user's, holding
/// surfcap's marker of `kind`, whose files match its content hash. The caller reads it only
/// after [`EntryRead::Read`].
pub fn check_folder_entry(path: &Path, kind: &str) -> EntryRead<()> {
    let m = match fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return EntryRead::Missing,
        Err(e) => return EntryRead::Unusable(Error::io(path, "look at", e)),
        Ok(m) => m,
    };
    if !m.is_dir() {
        let what = describe(path, &m.file_type());
        return EntryRead::Unusable(refused(
            path,
            format!("is {what}, not a cache folder: it is not followed or read"),
        ));
    }
    if m.uid() != euid() {
        return EntryRead::Unusable(refused(path, format!("belongs to another user (uid {}): not trusted", m.uid())));
    }
    let run = || -> Result<()> {
        let expected = recorded_hash(path)?;
        if folder_hash(path)? != expected {
            return Err(refused(
                path,
                "its files do not match their hash (NAME.b3): damaged or changed since surfcap wrote them".into(),
            ));
        }
        if !is_own_folder(path, kind) {
            return Err(refused(path, format!("holds no surfcap marker of kind {kind}")));
        }
        Ok(())
    };
    match run() {
        Ok(()) => EntryRead::Read(()),
        Err(e) => EntryRead::Unusable(e),
    }
}

/// Whether the real folder `dir` holds surfcap's marker of `kind` (read without following a
/// link).
fn is_own_folder(dir: &Path, kind: &str) -> bool {
    let Ok(f) = open_own_file(&dir.join(MARKER)) else { return false };
    let mut text = Vec::new();
    if f.take(1 << 16).read_to_end(&mut text).is_err() {
        return false;
    }
    let Ok(v) = serde_json::from_slice::<serde_json::Value>(&text) else { return false };
    v["written_by"] == "surfcap" && v["kind"] == kind
}

/// Stores a folder entry of `kind` at `path` (inside a folder checked by [`check_folder`]):
/// `fill` writes its files into a temporary folder inside the cache (which already holds the
/// marker of `kind`), then it is swapped in with its content hash. What is at `path` is
/// replaced only when it is a symlink or other non-folder name (removed as a name), an empty
/// folder, or surfcap's own folder of `kind`; never by force.
pub fn store_folder_entry(
    path: &Path,
    kind: &str,
    fill: impl FnOnce(&Path) -> Result<()>,
    note: &mut dyn FnMut(String),
) -> Result<()> {
    sweep_stale(path);
    let tmp = sibling(path, "tmp");
    let _live = register(&tmp);
    match fs::symlink_metadata(&tmp) {
        Ok(m) if m.is_dir() => fs::remove_dir_all(&tmp).map_err(|e| Error::io(&tmp, "remove", e))?,
        Ok(_) => fs::remove_file(&tmp).map_err(|e| Error::io(&tmp, "remove", e))?,
        Err(_) => {}
    }
    fs::DirBuilder::new().mode(0o700).create(&tmp).map_err(|e| Error::io(&tmp, "create directory", e))?;
    let built = crate::output_path::write_marker(&tmp, kind).and_then(|()| fill(&tmp)).and_then(|()| folder_hash(&tmp));
    let hash = match built {
        Ok(h) => h,
        Err(e) => {
            let _ = fs::remove_dir_all(&tmp);
            return Err(e);
        }
    };
    let swapped = (|| {
        let m = fs::symlink_metadata(path);
        let own = matches!(&m, Ok(m) if m.is_dir() && m.uid() == euid()) && is_own_folder(path, kind);
        if !own {
            make_room(path, true, note)?;
            return fs::rename(&tmp, path).map_err(|e| Error::io(path, "rename into place", e));
        }
        let old = sibling(path, "old");
        let _aside = register_aside(&old, path);
        fs::rename(path, &old).map_err(|e| Error::io(path, "move the previous entry aside", e))?;
        if let Err(e) = fs::rename(&tmp, path) {
            let _ = fs::rename(&old, path);
            return Err(Error::io(path, "rename into place", e));
        }
        let _ = fs::remove_dir_all(&old);
        Ok(())
    })();
    if let Err(e) = swapped {
        let _ = fs::remove_dir_all(&tmp);
        return Err(e);
    }
    put_small(&hash_path(path), sidecar_text(&hash, path).as_bytes(), note)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::{PermissionsExt, symlink};

    fn read_all(path: &Path) -> EntryRead<Vec<u8>> {
        read_file_entry(path, true, |r, _| {
            let mut v = Vec::new();
            r.read_to_end(&mut v).map_err(|e| Error::io(path, "read", e))?;
            Ok(v)
        })
    }

    #[test]
    fn a_stored_entry_reads_back_and_a_changed_one_does_not() {
        let d = tempfile::tempdir().unwrap();
        check_folder(d.path()).unwrap();
        let p = d.path().join("x.npy");
        assert!(matches!(read_all(&p), EntryRead::Missing));
        store_file_entry(&p, |w| w.write_all(b"hello"), &mut |_| {}).unwrap();
        assert!(matches!(read_all(&p), EntryRead::Read(v) if v == b"hello"));
        let side = fs::read_to_string(hash_path(&p)).unwrap();
        assert_eq!(side, format!("{}  x.npy\n", blake3::hash(b"hello").to_hex()));
        fs::write(&p, b"hellO").unwrap();
        let EntryRead::Unusable(e) = read_all(&p) else { panic!("a changed entry was trusted") };
        assert!(e.to_string().contains("does not match its hash"), "{e}");
        fs::remove_file(hash_path(&p)).unwrap();
        let EntryRead::Unusable(e) = read_all(&p) else { panic!("an entry without hash was trusted") };
        assert!(e.to_string().contains("no content hash"), "{e}");
    }

    #[test]
    fn a_symlink_at_an_entry_is_replaced_as_a_name_and_its_target_kept() {
        let d = tempfile::tempdir().unwrap();
        let cache = d.path().join("cache");
        check_folder(&cache).unwrap();
        let victim = d.path().join("victim.txt");
        fs::write(&victim, b"precious").unwrap();
        let p = cache.join("x.npy");
        symlink(&victim, &p).unwrap();
        symlink(&victim, hash_path(&p)).unwrap();
        let EntryRead::Unusable(e) = read_all(&p) else { panic!("a symlink was read") };
        assert!(e.to_string().contains("symbolic link"), "{e}");
        let mut said = Vec::new();
        store_file_entry(&p, |w| w.write_all(b"new"), &mut |n| said.push(n)).unwrap();
        assert_eq!(fs::read(&victim).unwrap(), b"precious");
        assert!(fs::symlink_metadata(&p).unwrap().is_file());
        assert!(matches!(read_all(&p), EntryRead::Read(v) if v == b"new"));
        assert!(said.iter().any(|n| n.contains("symbolic link") && n.contains("replaced")), "{said:?}");
    }

    #[test]
    fn fifos_and_folders_at_entry_names_never_block_or_lose_files() {
        let d = tempfile::tempdir().unwrap();
        check_folder(d.path()).unwrap();
        let p = d.path().join("x.npy");
        assert!(std::process::Command::new("mkfifo").arg(&p).status().unwrap().success());
        assert!(matches!(read_all(&p), EntryRead::Unusable(_)));
        let mut note = |_: String| {};
        store_file_entry(&p, |w| w.write_all(b"1"), &mut note).unwrap();
        assert!(fs::symlink_metadata(&p).unwrap().is_file());
        let q = d.path().join("y.npy");
        fs::create_dir(&q).unwrap();
        fs::write(q.join("mine"), b"user").unwrap();
        assert_eq!(store_file_entry(&q, |w| w.write_all(b"1"), &mut note).unwrap_err().kind, ErrorKind::Refused);
        assert_eq!(fs::read(q.join("mine")).unwrap(), b"user");
    }

    #[test]
    fn a_folder_others_can_write_is_refused_unless_sticky() {
        let d = tempfile::tempdir().unwrap();
        let c = d.path().join("new/cache");
        check_folder(&c).unwrap();
        assert_eq!(fs::metadata(&c).unwrap().permissions().mode() & 0o777, 0o700, "created private");
        fs::set_permissions(&c, fs::Permissions::from_mode(0o777)).unwrap();
        let e = check_folder(&c).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        assert!(e.to_string().contains("0777") && e.to_string().contains("chmod 700"), "{e}");
        fs::set_permissions(&c, fs::Permissions::from_mode(0o1777)).unwrap();
        check_folder(&c).unwrap();
    }

    #[test]
    fn folder_entries_replace_only_their_own_kind_and_never_follow_a_link() {
        let d = tempfile::tempdir().unwrap();
        let cache = d.path().join("cache");
        check_folder(&cache).unwrap();
        let victim = d.path().join("victim");
        fs::create_dir(&victim).unwrap();
        fs::write(victim.join("keep.txt"), b"mine").unwrap();
        let p = cache.join("model");
        symlink(&victim, &p).unwrap();
        assert!(matches!(check_folder_entry(&p, "m"), EntryRead::Unusable(_)));
        let mut said = Vec::new();
        let fill = |t: &Path| fs::write(t.join("a"), b"1").map_err(|e| Error::io(t, "write", e));
        store_folder_entry(&p, "m", fill, &mut |n| said.push(n)).unwrap();
        assert_eq!(fs::read(victim.join("keep.txt")).unwrap(), b"mine");
        assert_eq!(fs::read_dir(&victim).unwrap().count(), 1);
        assert!(matches!(check_folder_entry(&p, "m"), EntryRead::Read(())));
        fs::write(p.join("a"), b"2").unwrap();
        assert!(matches!(check_folder_entry(&p, "m"), EntryRead::Unusable(_)), "a changed file is seen");
        store_folder_entry(&p, "m", fill, &mut |n| said.push(n)).unwrap();
        assert!(matches!(check_folder_entry(&p, "m"), EntryRead::Read(())), "its own earlier entry is replaced");
        let q = cache.join("other");
        fs::create_dir(&q).unwrap();
        fs::write(q.join("x"), b"user").unwrap();
        assert!(store_folder_entry(&q, "m", fill, &mut |n| said.push(n)).is_err());
        assert_eq!(fs::read(q.join("x")).unwrap(), b"user");
        let names: Vec<_> = fs::read_dir(&cache).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 3, "no temporaries left: {names:?}");
    }
}
