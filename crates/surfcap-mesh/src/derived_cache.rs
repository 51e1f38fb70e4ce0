//! On-disk cache of derived matrices (distance matrices, transition tables...), keyed by the
//! hash of everything they depend on, stored as `.npy` so they open in numpy.
//!
//! The key is a BLAKE3 hash of the subject's content (topology, every sequence's positions, up
//! axis; not its name, fps or tags unless the caller adds them) plus the caller's parameter
//! text. A changed parameter gives a new key and recomputes only what depends on it; a second
//! run with the same inputs reads the file. Entries are written atomically.

use std::path::{Path, PathBuf};

use crate::atomic::write_file;
use crate::error::Result;
use crate::npy::{NpyArray, NpyElement, read_npy, write_npy};
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
    /// whether it came from the cache. An entry that cannot be read or decoded (damaged, an
    /// older layout, another subject's) is recomputed and replaced; `refresh` recomputes and
    /// replaces even a good one. A freshly computed array is decoded too, so a cached and an
    /// uncached run see the same numbers (e.g. after rounding to f32).
    ///
    /// `decode` is where an entry is checked against what it is for (shape, values): a file
    /// under the right name can still hold another subject's matrix or NaN, and a rejected
    /// entry is named with its problem through `progress.note`, so the user learns why the
    /// run recomputes.
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
        if !refresh && path.is_file() {
            let problem = match read_npy::<T>(path) {
                Ok(a) => match decode(a) {
                    Ok(v) => return Ok((v, true)),
                    Err(e) => e.to_string(),
                },
                Err(e) => e.to_string(),
            };
            progress.note(&format!("cache entry {}: {problem}; recomputing it", path.display()));
        }
        let a = compute()?;
        write_file(path, |w| write_npy(w, &a.shape, &a.data))?;
        Ok((decode(a)?, false))
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
        // A readable entry of the wrong shape is recomputed and replaced.
        write_file(&p, |w| write_npy(w, &[3], &[1.0f64, 2.0, 3.0])).unwrap();
        assert_eq!(c.fetch(&p, false, &notes, compute, decode).unwrap(), (vec![1.0, 2.0], false));
        assert_eq!(read_npy::<f64>(&p).unwrap().shape, vec![2]);
        let said = notes.0.lock().unwrap();
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(said[0].contains(&p.display().to_string()) && said[0].contains("expected [2]"), "{said:?}");
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
