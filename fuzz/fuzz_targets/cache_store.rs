//! The derived cache against whatever is at its names: from the input, a fresh cache folder gets
//! random things at each entry's name, its hash sidecar and its temporary (files of random
//! bytes, symlinks to a victim file and a victim folder outside the cache, FIFOs, sockets,
//! folders empty or not, valid and truncated entries), then a random run of fetches (with and
//! without refresh) and folder-entry stores and checks. Asserted: the victim file and folder
//! outside the cache are unchanged, nothing appears outside the cache, and every fetch returns
//! the computed value or an error, never another value.
#![no_main]
use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use libfuzzer_sys::fuzz_target;
use surfcap_mesh::cache_entry::{EntryRead, check_folder_entry, hash_path, store_file_entry, store_folder_entry};
use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_mesh::npy::{NpyArray, write_npy};

unsafe extern "C" {
    fn mkfifo(path: *const std::ffi::c_char, mode: u32) -> i32;
}

/// Reads the input a byte at a time (zeros once it is used up).
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn next(&mut self) -> u8 {
        let Some((&b, rest)) = self.0.split_first() else { return 0 };
        self.0 = rest;
        b
    }
    fn take(&mut self, n: usize) -> Vec<u8> {
        let n = n.min(self.0.len());
        let (a, rest) = self.0.split_at(n);
        self.0 = rest;
        a.to_vec()
    }
}

/// The value of entry `k`: a 3 x 3 matrix only it has.
fn value(k: usize) -> NpyArray<f64> {
    NpyArray { shape: vec![3, 3], data: (0..9).map(|i| (k * 10 + i) as f64).collect() }
}

fn npy_bytes(a: &NpyArray<f64>) -> Vec<u8> {
    let mut v = Vec::new();
    write_npy(&mut v, &a.shape, &a.data).unwrap();
    v
}

/// Puts something chosen by the input at `path`.
fn plant(path: &Path, b: &mut Bytes, victim_file: &Path, victim_dir: &Path, k: usize) {
    // Storing a whole entry also writes its hash file: the place may be taken already.
    if std::fs::symlink_metadata(path).is_ok() {
        return;
    }
    match b.next() % 11 {
        0 => {}
        1 => {
            let n = b.next() as usize;
            std::fs::write(path, b.take(n)).unwrap();
        }
        2 => symlink(victim_file, path).unwrap(),
        3 => symlink(victim_dir, path).unwrap(),
        4 => {
            let c = CString::new(path.as_os_str().as_bytes()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            assert_eq!(unsafe { mkfifo(c.as_ptr(), 0o600) }, 0);
        }
        5 => std::fs::create_dir(path).unwrap(),
        6 => {
            std::fs::create_dir(path).unwrap();
            std::fs::write(path.join("x"), b"inside").unwrap();
        }
        7 => store_file_entry(path, |w| w.write_all(&npy_bytes(&value(k))), &mut |_| {}).unwrap(),
        8 => {
            let full = npy_bytes(&value(k));
            let cut = b.next() as usize % full.len();
            std::fs::write(path, &full[..cut]).unwrap();
        }
        9 => {
            let _ = std::os::unix::net::UnixListener::bind(path).unwrap();
        }
        _ => symlink("missing-target", path).unwrap(),
    }
}

fn listing(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            let bytes = std::fs::read(&p).unwrap_or_default();
            (p, bytes)
        })
        .collect();
    v.sort();
    v
}

static RUN: AtomicUsize = AtomicUsize::new(0);

fuzz_target!(|data: &[u8]| {
    let root = std::env::temp_dir()
        .join(format!("surfcap-fuzz-cache-{}-{}", std::process::id(), RUN.fetch_add(1, Ordering::Relaxed)));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let victim_file = root.join("victim.txt");
    std::fs::write(&victim_file, b"the user's file").unwrap();
    let victim_dir = root.join("victim");
    std::fs::create_dir(&victim_dir).unwrap();
    std::fs::write(victim_dir.join("keep.txt"), b"the user's folder").unwrap();
    let before = (listing(&victim_dir), std::fs::read(&victim_file).unwrap());

    let cache_dir = root.join("cache");
    surfcap_mesh::cache_entry::check_folder(&cache_dir).unwrap();
    let cache = DerivedCache::new(&cache_dir);
    let mut b = Bytes(data);
    let files: Vec<PathBuf> = (0..2).map(|k| cache_dir.join(format!("distance-{k}.npy"))).collect();
    let folders: Vec<PathBuf> = (0..2).map(|k| cache_dir.join(format!("folder-{k}"))).collect();
    for (k, p) in files.iter().chain(&folders).enumerate() {
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        let tmp = p.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
        for at in [p.clone(), hash_path(p), tmp] {
            plant(&at, &mut b, &victim_file, &victim_dir, k % 2);
        }
    }
    for _ in 0..6 {
        let op = b.next();
        let k = (op as usize >> 2) % 2;
        match op % 4 {
            0 | 1 => {
                let compute = || Ok::<_, surfcap_mesh::Error>(value(k));
                match cache.fetch(&files[k], op % 4 == 1, &surfcap_mesh::NoProgress, compute, Ok) {
                    Ok((v, _)) => assert_eq!(v, value(k), "a fetch returned another value"),
                    Err(_) => {}
                }
            }
            2 => {
                let fill = |t: &Path| {
                    std::fs::write(t.join("f"), k.to_string()).map_err(|e| surfcap_mesh::Error::io(t, "write", e))
                };
                let _ = store_folder_entry(&folders[k], "fuzz", fill, &mut |_| {});
            }
            _ => {
                if let EntryRead::Read(()) = check_folder_entry(&folders[k], "fuzz") {
                    let got = std::fs::read(folders[k].join("f")).unwrap();
                    assert_eq!(got, k.to_string().as_bytes(), "a verified folder entry holds another value");
                }
            }
        }
    }
    assert_eq!((listing(&victim_dir), std::fs::read(&victim_file).unwrap()), before, "a victim outside the cache changed");
    let mut names: Vec<_> = std::fs::read_dir(&root).unwrap().map(|e| e.unwrap().file_name()).collect();
    names.sort();
    assert_eq!(names, ["cache", "victim", "victim.txt"], "something appeared outside the cache");
    std::fs::remove_dir_all(&root).unwrap();
});
