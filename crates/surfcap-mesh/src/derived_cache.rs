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
use crate::io::npy::{NpyArray, NpyElement, read_npy, write_npy};
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

    /// Reads the cached matrix, or computes, stores and returns it. The bool says whether it
    /// came from the cache. `compute` may fail with any error a data-layer error converts into.
    pub fn get_or_compute<T: NpyElement + npyz::AutoSerialize, E: From<crate::Error>>(
        &self,
        path: &Path,
        compute: impl FnOnce() -> Result<NpyArray<T>, E>,
    ) -> Result<(NpyArray<T>, bool), E> {
        // An unreadable entry (older format, damaged disk) is recomputed and replaced.
        if path.is_file()
            && let Ok(a) = read_npy::<T>(path)
        {
            return Ok((a, true));
        }
        let a = compute()?;
        write_file(path, |w| write_npy(w, &a.shape, &a.data))?;
        Ok((a, false))
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
        let mut calls = 0;
        for expect_cached in [false, true] {
            let (a, cached) = c
                .get_or_compute(&p, || {
                    calls += 1;
                    Ok::<_, crate::Error>(NpyArray { shape: vec![2, 2], data: vec![0.0, 1.5, 1.5, 0.0] })
                })
                .unwrap();
            assert_eq!(cached, expect_cached);
            assert_eq!(a.data[1], 1.5);
        }
        assert_eq!(calls, 1);
    }
}
