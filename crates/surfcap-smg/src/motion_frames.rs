//! The input of the surface motion graph: named sequences of frames, each frame a mesh of its
//! own (Huang et al. 2009 work on per-frame reconstructions "with unknown temporal
//! correspondence and different mesh connectivity at each time-frame"), with what the graph
//! needs of each frame: its ground centroid (eq. 8), and the frame-to-frame shape similarity
//! (eq. 2-3), cached on disk like the other derived products.
//!
//! The ground centroid is the surface's area-weighted centroid projected on the ground plane
//! (the paper: "the projection of the centroid of the mesh ... onto the ground"); area weighting
//! makes it independent of how densely a frame is meshed, which the vertex mean is not when every
//! frame has its own connectivity.

use std::ops::Range;
use std::sync::Arc;

use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::npy::NpyArray;
use surfcap_mesh::{Progress, Subject, UpAxis};

use crate::error::{Error, Result};
use crate::shape_similarity::{FrameMesh, HistogramParams, frame_histograms, shape_similarity_matrix};

/// Frames of one or more sequences, each frame with its own triangles.
#[derive(Debug, Clone)]
pub struct MotionFrames {
    pub names: Vec<String>,
    /// Each sequence's global frames.
    pub sequences: Vec<Range<usize>>,
    /// Each frame's positions [V * 3] and triangles (shared between frames when they are).
    pub positions: Vec<Vec<f32>>,
    pub triangles: Vec<Arc<Vec<[u32; 3]>>>,
    pub up: UpAxis,
    pub fps: f64,
}

impl MotionFrames {
    /// A shared-topology subject's frames.
    pub fn from_subject(s: &Subject) -> Self {
        let t = Arc::new(s.topology().triangles().to_vec());
        let mut sequences = Vec::new();
        let mut positions = Vec::new();
        for q in s.sequences() {
            let start = positions.len();
            positions.extend((0..q.n_frames()).map(|f| q.frame(f).to_vec()));
            sequences.push(start..positions.len());
        }
        let n = positions.len();
        MotionFrames {
            names: s.sequences().iter().map(|q| q.name.clone()).collect(),
            sequences,
            positions,
            triangles: vec![t; n],
            up: s.up_axis,
            fps: s.fps,
        }
    }

    /// A frame set's frames, each with its own triangles (Huang et al.'s input).
    pub fn from_frame_set(s: &FrameSet) -> Self {
        let mut sequences = Vec::new();
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for q in s.sequences() {
            let start = positions.len();
            for f in q.frames() {
                positions.push(f.positions().to_vec());
                triangles.push(Arc::new(f.topology().triangles().to_vec()));
            }
            sequences.push(start..positions.len());
        }
        MotionFrames {
            names: s.sequences().iter().map(|q| q.name.clone()).collect(),
            sequences,
            positions,
            triangles,
            up: s.up_axis,
            fps: s.fps,
        }
    }

    pub fn n_frames(&self) -> usize {
        self.positions.len()
    }

    pub fn meshes(&self) -> Vec<FrameMesh<'_>> {
        self.positions.iter().zip(&self.triangles).map(|(p, t)| FrameMesh { positions: p, triangles: t }).collect()
    }

    /// The global frame of `sequence:frame`.
    pub fn frame(&self, sequence: &str, frame: usize) -> Result<usize> {
        let Some(k) = self.names.iter().position(|n| n == sequence) else {
            return Err(Error::Invalid(format!("no sequence {sequence:?}: expected one of {}", self.names.join(", "))));
        };
        let r = &self.sequences[k];
        if frame >= r.len() {
            return Err(Error::Invalid(format!("{sequence}:{frame}: expected a frame below {}", r.len())));
        }
        Ok(r.start + frame)
    }

    /// The global frame written `sequence:frame`.
    pub fn resolve(&self, spec: &str) -> Result<usize> {
        let (s, f) =
            spec.rsplit_once(':').ok_or_else(|| Error::Invalid(format!("{spec:?}: expected sequence:frame")))?;
        let f: usize = f
            .parse()
            .map_err(|_| Error::Invalid(format!("{spec:?}: expected a whole frame number after the colon")))?;
        self.frame(s, f)
    }

    /// `sequence:frame` of a global frame.
    pub fn name_of(&self, global: usize) -> String {
        match self.sequences.iter().position(|r| r.contains(&global)) {
            Some(k) => format!("{}:{}", self.names[k], global - self.sequences[k].start),
            None => format!("frame {global}"),
        }
    }

    /// Each frame's area-weighted surface centroid (3-D).
    pub fn centroids(&self) -> Vec<[f64; 3]> {
        self.positions
            .iter()
            .zip(&self.triangles)
            .map(|(p, t)| {
                let v = |i: u32| {
                    let i = i as usize * 3;
                    [f64::from(p[i]), f64::from(p[i + 1]), f64::from(p[i + 2])]
                };
                let (mut c, mut total) = ([0.0; 3], 0.0);
                for tr in t.iter() {
                    let (a, b, d) = (v(tr[0]), v(tr[1]), v(tr[2]));
                    let (u, w) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [d[0] - a[0], d[1] - a[1], d[2] - a[2]]);
                    let n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
                    let area = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    for k in 0..3 {
                        c[k] += area * (a[k] + b[k] + d[k]) / 3.0;
                    }
                    total += area;
                }
                if total > 0.0 { c.map(|x| x / total) } else { [0.0; 3] }
            })
            .collect()
    }

    /// Each frame's centroid on the ground plane, as (east, north) coordinates.
    pub fn ground_centroids(&self) -> Vec<[f64; 2]> {
        let (axis, _) = self.up.axis_and_sign();
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        self.centroids().into_iter().map(|c| [c[a], c[b]]).collect()
    }

    /// A hash of every frame's geometry and the up axis (the similarity's cache key).
    pub fn geometry_hash(&self) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(b"surfcap-smg-frames-v1");
        h.update(self.up.as_str().as_bytes());
        for (p, t) in self.positions.iter().zip(&self.triangles) {
            h.update(&(p.len() as u64).to_le_bytes());
            h.update(&p.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
            h.update(&(t.len() as u64).to_le_bytes());
            h.update(&t.iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
        }
        h.finalize()
    }

    /// The `F x F` shape similarity (eq. 2), from `cache` when it holds it (`.npy`, f64 [F, F]:
    /// `smg-similarity-<16 hex>.npy`), else computed and stored there; the bool says whether it
    /// came from the cache.
    pub fn shape_similarity(
        &self,
        params: HistogramParams,
        cache: Option<(&DerivedCache, bool)>,
        progress: &dyn Progress,
    ) -> Result<(Vec<f64>, bool)> {
        let n = self.n_frames();
        // No all-zero check on a stored matrix (as the distance matrix has): shape histograms
        // do not see where a frame is, so frames that only move rigidly give zero similarities
        // legitimately; a hand-made or damaged entry is caught by the cache's content hash.
        let compute = || -> Result<NpyArray<f64>> {
            progress.start("shape histograms and similarity (eq. 2)", 1);
            let set = frame_histograms(&self.meshes(), self.up, params)?;
            let m = shape_similarity_matrix(&set)?;
            progress.finish();
            Ok(NpyArray { shape: vec![n, n], data: m })
        };
        let decode = |a: NpyArray<f64>| -> Result<Vec<f64>> {
            if a.shape != [n, n] || a.data.iter().any(|x| !x.is_finite() || *x < 0.0) {
                return Err(Error::Invalid(format!(
                    "expected {n} x {n} finite similarities, found shape {:?}",
                    a.shape
                )));
            }
            Ok(a.data)
        };
        match cache {
            None => Ok((decode(compute()?)?, false)),
            Some((c, refresh)) => {
                let key = serde_json::to_string(&params).map_err(|e| Error::Invalid(e.to_string()))?;
                let path = c.path("smg-similarity", &self.geometry_hash(), &key);
                c.fetch(&path, refresh, progress, compute, decode)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{Sequence, Topology, Units};

    fn tetra_subject() -> Subject {
        let topo = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let f0 = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut p = f0.to_vec();
        p.extend(f0.iter().enumerate().map(|(i, v)| if i % 3 == 0 { v + 2.0 } else { *v }));
        let s = Sequence::new("walk", 4, p).unwrap();
        Subject::new("t", topo, vec![s], 30.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    #[test]
    fn frames_are_named_and_their_ground_centroids_move_with_them() {
        let m = MotionFrames::from_subject(&tetra_subject());
        assert_eq!(m.frame("walk", 1).unwrap(), 1);
        assert_eq!(m.name_of(1), "walk:1");
        assert!(m.frame("walk", 2).unwrap_err().to_string().contains("below 2"));
        assert!(m.frame("run", 0).unwrap_err().to_string().contains("one of walk"));
        assert_eq!(m.resolve("walk:1").unwrap(), 1);
        assert!(m.resolve("walk").unwrap_err().to_string().contains("expected sequence:frame"));
        assert!(m.resolve("walk:x").unwrap_err().to_string().contains("whole frame number"));
        let g = m.ground_centroids();
        // Up +y: ground coordinates are (z, x); frame 1 is frame 0 moved 2 along x.
        assert!((g[1][1] - g[0][1] - 2.0).abs() < 1e-12 && (g[1][0] - g[0][0]).abs() < 1e-12);
    }

    #[test]
    fn the_similarity_is_cached_by_geometry_and_parameters() {
        let d = tempfile::tempdir().unwrap();
        let cache = DerivedCache::new(d.path());
        let m = MotionFrames::from_subject(&tetra_subject());
        let p = HistogramParams { resolution: 16, ..Default::default() };
        let (a, cached) = m.shape_similarity(p, Some((&cache, false)), &surfcap_mesh::NoProgress).unwrap();
        assert!(!cached);
        let (b, cached) = m.shape_similarity(p, Some((&cache, false)), &surfcap_mesh::NoProgress).unwrap();
        assert!(cached && a == b);
        let mut files: Vec<_> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        files.sort();
        assert_eq!(files.len(), 2, "the entry and its content hash: {files:?}");
        assert!(files[0].starts_with("smg-similarity-") && files[1] == format!("{}.b3", files[0]));
    }
}
