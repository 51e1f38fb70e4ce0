//! On-disk cache of derived matrices (distance matrices, transition tables...), keyed by the
//! hash of everything they depend on, stored as `.npy` so they open in numpy.
//!
//! The key is a BLAKE3 hash of the subject's content (topology, every sequence's positions, up
//! axis; not its name, fps or tags unless the caller adds them) plus the caller's parameter
//! text. A changed parameter gives a new key and recomputes only what depends on it; a second
//! run with the same inputs reads the file.
//!
//! The cache is a trust boundary ([`crate::cache_entry`]): the folder is created private and
//! refused when other users can write it; an entry is surfcap's own name inside it, never
//! followed when it is a symbolic link (such a name is replaced, its target never touched);
//! every entry has a BLAKE3 content hash beside it (`NAME.npy.b3`, in `b3sum`'s format, so the
//! `.npy` still opens in numpy) that is verified while the entry is read; and a decoded entry
//! is checked for sense by its caller, so a damaged, planted or all-zero entry is recomputed
//! with a note instead of being used. Entries are written as a temporary renamed into place.

use std::path::{Path, PathBuf};

use crate::cache_entry::{EntryRead, check_folder, read_file_entry, store_file_entry};
use crate::error::Result;
use crate::npy::{NpyArray, NpyElement, parse_npy, write_npy};
use crate::progress::Progress;
use crate::subject::Subject;

/// Hash of the subject's geometry: topology, positions of every sequence (in order), up axis.
pub fn subject_hash(subject: &Subject) -> blake3::Hash {
    let mut h = blake3::Hasher::new();
    h.update(b"surfcap-subject-geometry-v1");
    h.update(&(subject.topology().n_vertices() as u64).to_le_bytes());
    for t in subject.topology().triangles() {
        for i in t {
            h.update(&i.to_le_bytes());
        }
    }
    h.update(subject.up_axis.as_str().as_bytes());
    for s in subject.sequences() {
        h.update(&(s.n_frames() as u64).to_le_bytes());
        let bytes: Vec<u8> = s.positions().iter().flat_map(|x| x.to_le_bytes()).collect();
        h.update(&bytes);
    }
    h.finalize()
}

/// A cache folder of derived matrices.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DerivedCache {
    dir: PathBuf,
}

impl DerivedCache {
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        DerivedCache { dir: dir.into() }
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file for `kind` (a readable prefix such as `distance-deformation`) of this subject
    /// and these parameters.
    pub fn path(&self, kind: &str, subject_hash: &blake3::Hash, params: &str) -> PathBuf {
        let mut h = blake3::Hasher::new();
        h.update(subject_hash.as_bytes());
        h.update(kind.as_bytes());
        h.update(params.as_bytes());
        let key = h.finalize().to_hex();
        self.dir.join(format!("{kind}-{}.npy", &key[..16]))
    }

    /// Reads and decodes the entry at `path`, or computes, stores and decodes it; the bool says
    /// whether it came from the cache. An entry that cannot be used (not a regular file of this
    /// user's, no or a wrong content hash, unreadable, an older layout, another subject's, values
    /// that make no sense) is recomputed and replaced, with a note naming it and its problem;
    /// `refresh` recomputes and replaces even a good one. A freshly computed array is decoded
    /// too, so a cached and an uncached run see the same numbers (e.g. after rounding to f32).
    ///
    /// The cache folder is checked first ([`check_folder`]: created private, refused when other
    /// users can write it); an error there stops the run. An entry that cannot be stored (a
    /// folder or another user's file at its name) is only noted: the value is still returned.
    ///
    /// `decode` is where an entry is checked against what it is for (shape, values): a file
    /// under the right name can still hold another subject's matrix or NaN.
    pub fn fetch<T, V, E>(
        &self,
        path: &Path,
        refresh: bool,
        progress: &dyn Progress,
        compute: impl Fn() -> Result<NpyArray<T>, E>,
        decode: impl Fn(NpyArray<T>) -> Result<V, E>,
    ) -> Result<(V, bool), E>
    where
        T: NpyElement + npyz::AutoSerialize,
        E: From<crate::Error> + std::fmt::Display,
    {
        check_folder(&self.dir)?;
        let problem = if refresh {
            None
        } else {
            match self.read::<T>(path, true) {
                EntryRead::Missing => None,
                EntryRead::Unusable(e) => Some(e.to_string()),
                EntryRead::Read(a) => match decode(a) {
                    Ok(v) => return Ok((v, true)),
                    Err(e) => Some(format!("{}: {e}", path.display())),
                },
            }
        };
        if let Some(problem) = problem {
            progress.note(&format!("cache entry {problem}; recomputing it"));
        }
        let a = compute()?;
        let mut note = |n: String| progress.note(&n);
        if let Err(e) = store_file_entry(path, |w| write_npy(w, &a.shape, &a.data), &mut note) {
            progress.note(&format!("cache entry not stored: {e}"));
        }
        Ok((decode(a)?, false))
    }

    /// Reads the entry at `path` as an array, checked against its content hash when `verify`
    /// (always in [`DerivedCache::fetch`]; `false` only measures what verifying costs).
    pub fn read<T: NpyElement>(&self, path: &Path, verify: bool) -> EntryRead<NpyArray<T>> {
        read_file_entry(path, verify, |r, len| parse_npy::<T>(r, len))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn computes_once_then_reads() {
        let d = tempfile::tempdir().unwrap();
        let c = DerivedCache::new(d.path());
        let h = blake3::hash(b"x");
        let p = c.path("distance-test", &h, "w=0.01");
        assert_ne!(p, c.path("distance-test", &h, "w=0.02"));
        let calls = std::cell::Cell::new(0);
        for expect_cached in [false, true] {
            let compute = || {
                calls.set(calls.get() + 1);
                Ok::<_, crate::Error>(NpyArray { shape: vec![2, 2], data: vec![0.0, 1.5, 1.5, 0.0] })
            };
            let (a, cached) = c.fetch(&p, false, &crate::NoProgress, compute, Ok).unwrap();
            assert_eq!(cached, expect_cached);
            assert_eq!(a.data[1], 1.5);
        }
        assert_eq!(calls.get(), 1);
    }

    #[test]
    fn fetch_recomputes_entries_it_cannot_decode_and_on_refresh() {
        let d = tempfile::tempdir().unwrap();
        let c = DerivedCache::new(d.path());
        let p = c.path("test", &blake3::hash(b"x"), "");
        let notes = Notes::default();
        let calls = std::cell::Cell::new(0);
        let compute = || {
            calls.set(calls.get() + 1);
            Ok::<_, crate::Error>(NpyArray { shape: vec![2], data: vec![1.0f64, 2.0] })
        };
        let decode = |a: NpyArray<f64>| {
            if a.shape == [2] { Ok(a.data) } else { Err(crate::Error::new(crate::ErrorKind::Shape, "expected [2]")) }
        };
        assert_eq!(c.fetch(&p, false, &notes, compute, decode).unwrap(), (vec![1.0, 2.0], false));
        assert_eq!(c.fetch(&p, false, &notes, compute, decode).unwrap(), (vec![1.0, 2.0], true));
        assert_eq!(calls.get(), 1);
        assert!(!c.fetch(&p, true, &notes, compute, decode).unwrap().1);
        assert_eq!(calls.get(), 2);
        // A readable entry of the wrong shape (with a good hash) is recomputed and replaced.
        store_file_entry(&p, |w| write_npy(w, &[3], &[1.0f64, 2.0, 3.0]), &mut |_| {}).unwrap();
        assert_eq!(c.fetch(&p, false, &notes, compute, decode).unwrap(), (vec![1.0, 2.0], false));
        assert_eq!(crate::npy::read_npy::<f64>(&p).unwrap().shape, vec![2]);
        let said = notes.0.lock().unwrap();
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(said[0].contains(&p.display().to_string()) && said[0].contains("expected [2]"), "{said:?}");
    }

    fn two_by_two() -> Result<NpyArray<f64>> {
        Ok(NpyArray { shape: vec![2, 2], data: vec![0.0, 1.5, 1.5, 0.0] })
    }

    #[test]
    fn an_entry_whose_bytes_do_not_match_its_hash_is_recomputed_with_a_note() {
        let d = tempfile::tempdir().unwrap();
        let c = DerivedCache::new(d.path());
        let p = c.path("distance-test", &blake3::hash(b"x"), "");
        c.fetch(&p, false, &crate::NoProgress, two_by_two, Ok).unwrap();
        // Decodable, of the right shape, but not what surfcap wrote: all zeros.
        std::fs::write(&p, {
            let mut v = Vec::new();
            write_npy(&mut v, &[2, 2], &[0.0f64; 4]).unwrap();
            v
        })
        .unwrap();
        let notes = Notes::default();
        let (a, cached) = c.fetch(&p, false, &notes, two_by_two, Ok).unwrap();
        assert!(!cached);
        assert_eq!(a.data[1], 1.5);
        let said = notes.0.lock().unwrap();
        assert!(said.len() == 1 && said[0].contains(&p.display().to_string()) && said[0].contains("hash"), "{said:?}");
        assert_eq!(crate::npy::read_npy::<f64>(&p).unwrap().data[1], 1.5, "replaced");
        assert!(c.fetch(&p, false, &notes, two_by_two, Ok).unwrap().1, "and then read");
    }

    #[cfg(unix)]
    #[test]
    fn a_damaged_entry_linked_to_a_user_file_is_replaced_and_the_file_kept() {
        let d = tempfile::tempdir().unwrap();
        let cache = d.path().join("cache");
        let c = DerivedCache::new(&cache);
        let p = c.path("distance-test", &blake3::hash(b"x"), "");
        std::fs::create_dir(&cache).unwrap();
        let victim = d.path().join("thesis.tex");
        std::fs::write(&victim, b"years of work").unwrap();
        std::os::unix::fs::symlink(&victim, &p).unwrap();
        let notes = Notes::default();
        let (a, cached) = c.fetch(&p, false, &notes, two_by_two, Ok).unwrap();
        assert!(!cached && a.data[1] == 1.5);
        assert_eq!(std::fs::read(&victim).unwrap(), b"years of work");
        assert!(std::fs::symlink_metadata(&p).unwrap().is_file());
        let said = notes.0.lock().unwrap();
        assert!(said.iter().any(|n| n.contains("symbolic link") && !n.contains("choose another output")), "{said:?}");
    }

    #[cfg(unix)]
    #[test]
    fn a_cache_folder_others_can_write_is_refused_with_how_to_fix_it() {
        use std::os::unix::fs::PermissionsExt;
        let d = tempfile::tempdir().unwrap();
        std::fs::set_permissions(d.path(), std::fs::Permissions::from_mode(0o777)).unwrap();
        let c = DerivedCache::new(d.path());
        let p = c.path("distance-test", &blake3::hash(b"x"), "");
        let e = c.fetch(&p, false, &crate::NoProgress, two_by_two, Ok).unwrap_err();
        assert_eq!(e.kind, crate::ErrorKind::Refused);
        assert!(e.to_string().contains("chmod 700"), "{e}");
        assert!(!p.exists());
    }

    /// Collects notes.
    #[derive(Default)]
    struct Notes(std::sync::Mutex<Vec<String>>);

    impl Progress for Notes {
        fn note(&self, text: &str) {
            self.0.lock().unwrap().push(text.to_string());
        }
    }
}
