//! The subject cache written by `surfcap import` and read by every later command: a folder of
//! `.npy` arrays (so a researcher can open them in numpy) and a `subject.json` describing them.
//!
//! ```text
//! subject.json            name, fps, up axis, units, sequences (name, frames, tags, joints)
//! faces.npy               uint32 [triangles, 3]
//! uv.npy, uv_faces.npy    float32 [uvs, 2], uint32 [triangles, 3]      (when the mesh has UVs)
//! positions_<k>.npy       float32 [frames, vertices, 3]                 (sequence k)
//! labels_<k>.npy          uint8 [frames]: 0 original, 1 synthetic
//! joints_<k>.npy          float32 [frames, joints, 4, 4]                 (when known)
//! ```
//! Reading allocates each array once at its final size; sequences load in parallel.

use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::atomic::{write_dir, write_file};
use crate::cache_description::read_description;
use crate::error::{Result, err};
use crate::npy::{expect_shape, read_npy, write_npy};
use crate::progress::Progress;
use crate::subject::{FrameLabel, JointTrack, Sequence, Subject, Units, UpAxis};
use crate::topology::{Topology, UvAtlas};

const FORMAT: &str = "surfcap-subject";
const VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    name: String,
    fps: f64,
    up_axis: UpAxis,
    units: Units,
    vertices: usize,
    triangles: usize,
    sequences: Vec<SeqHeader>,
}

#[derive(Serialize, Deserialize)]
struct SeqHeader {
    name: String,
    frames: usize,
    tags: Vec<String>,
    joints: Option<JointsHeader>,
}

#[derive(Serialize, Deserialize)]
struct JointsHeader {
    names: Vec<String>,
    parents: Vec<Option<usize>>,
}

/// Whether `path` is a subject cache folder.
pub fn is_cache(path: &Path) -> bool {
    path.join("subject.json").is_file()
}

/// The kind of output a subject cache is, in its folder's marker.
pub const OUTPUT_KIND: &str = "subject";

/// Whether `path` is a subject cache written before surfcap marked its outputs: a folder whose
/// `subject.json` is surfcap's and whose every entry is a name the cache layout uses. Such a
/// folder holds nothing surfcap did not write (a user's file beside the arrays makes it
/// foreign), so re-importing over it is safe without `--force`.
fn is_unmarked_cache(path: &Path) -> bool {
    let ours = |name: &str| {
        let indexed = |prefix: &str| {
            name.strip_prefix(prefix)
                .and_then(|r| r.strip_suffix(".npy"))
                .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
        };
        matches!(name, "subject.json" | "faces.npy" | "uv.npy" | "uv_faces.npy")
            || ["positions_", "labels_", "joints_"].into_iter().any(indexed)
    };
    let Ok(entries) = std::fs::read_dir(path) else { return false };
    let all_ours = entries
        .into_iter()
        .all(|e| e.is_ok_and(|e| e.file_type().is_ok_and(|t| t.is_file()) && e.file_name().to_str().is_some_and(ours)));
    all_ours
        && std::fs::read(path.join("subject.json"))
            .ok()
            .and_then(|t| serde_json::from_slice::<Header>(&t).ok())
            .is_some_and(|h| h.format == FORMAT)
}

/// Writes the subject as a cache folder (atomically: all or nothing). `path` may be new, empty,
/// or a subject cache surfcap wrote (marked, or unmarked but of the exact cache layout); any
/// other folder only with `force`.
pub fn write_cache(path: &Path, subject: &Subject, force: bool, progress: &dyn Progress) -> Result<()> {
    let topo = subject.topology();
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        name: subject.name.clone(),
        fps: subject.fps,
        up_axis: subject.up_axis,
        units: subject.units.clone(),
        vertices: topo.n_vertices(),
        triangles: topo.n_triangles(),
        sequences: subject
            .sequences()
            .iter()
            .map(|s| SeqHeader {
                name: s.name.clone(),
                frames: s.n_frames(),
                tags: s.tags.clone(),
                joints: s.joints.as_ref().map(|j| JointsHeader { names: j.names.clone(), parents: j.parents.clone() }),
            })
            .collect(),
    };
    progress.start("writing subject cache", subject.sequences().len() as u64);
    let force = force || is_unmarked_cache(path);
    write_dir(path, OUTPUT_KIND, force, |dir| {
        let flat: Vec<u32> = topo.triangles().iter().flatten().copied().collect();
        write_file(&dir.join("faces.npy"), |w| write_npy(w, &[topo.n_triangles(), 3], &flat))?;
        if let Some(uv) = topo.uv() {
            let c: Vec<f32> = uv.coords.iter().flatten().copied().collect();
            write_file(&dir.join("uv.npy"), |w| write_npy(w, &[uv.coords.len(), 2], &c))?;
            let f: Vec<u32> = uv.corners.iter().flatten().copied().collect();
            write_file(&dir.join("uv_faces.npy"), |w| write_npy(w, &[uv.corners.len(), 3], &f))?;
        }
        for (k, s) in subject.sequences().iter().enumerate() {
            let nv = topo.n_vertices();
            write_file(&dir.join(format!("positions_{k}.npy")), |w| {
                write_npy(w, &[s.n_frames(), nv, 3], s.positions())
            })?;
            let labels: Vec<u8> = s.labels.iter().map(|l| (*l == FrameLabel::Synthetic) as u8).collect();
            write_file(&dir.join(format!("labels_{k}.npy")), |w| write_npy(w, &[s.n_frames()], &labels))?;
            if let Some(j) = &s.joints {
                write_file(&dir.join(format!("joints_{k}.npy")), |w| {
                    write_npy(w, &[s.n_frames(), j.n_joints(), 4, 4], &j.matrices)
                })?;
            }
            progress.advance(1);
        }
        let json = serde_json::to_vec_pretty(&header).map_err(|e| err!(Io, "cannot encode subject.json: {e}"))?;
        write_file(&dir.join("subject.json"), |w| w.write_all(&json))
    })?;
    progress.finish();
    Ok(())
}

/// Reads and checks `subject.json` and `faces.npy` of a cache folder: the description, its path
/// and the triangles.
fn read_header_and_faces(path: &Path) -> Result<(Header, std::path::PathBuf, Vec<[u32; 3]>)> {
    let hp = path.join("subject.json");
    let h: Header =
        read_description(&hp, "subject description", (FORMAT, VERSION), |h: &Header| (h.format.as_str(), h.version))?;
    // Checked here as well as by `Subject::new`: a cache opened for some frames only
    // (`CachedFrames`) builds no subject.
    crate::subject::check_frame_rate(h.fps).map_err(|e| e.in_file(&hp))?;
    crate::subject::check_sequence_names(h.sequences.iter().map(|s| s.name.as_str())).map_err(|e| e.in_file(&hp))?;
    let fp = path.join("faces.npy");
    let faces = read_npy::<u32>(&fp)?;
    expect_shape(&faces, &[Some(h.triangles), Some(3)], "triangles").map_err(|e| e.in_file(&fp))?;
    let triangles: Vec<[u32; 3]> = faces.data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok((h, hp, triangles))
}

/// Reads a cache folder, checking every array against `subject.json`.
pub fn read_cache(path: &Path, progress: &dyn Progress) -> Result<Subject> {
    let (h, hp, triangles) = read_header_and_faces(path)?;
    let fp = path.join("faces.npy");
    let uv = if path.join("uv.npy").is_file() {
        let (up, ufp) = (path.join("uv.npy"), path.join("uv_faces.npy"));
        let c = read_npy::<f32>(&up)?;
        expect_shape(&c, &[None, Some(2)], "texture coordinates").map_err(|e| e.in_file(&up))?;
        let f = read_npy::<u32>(&ufp)?;
        expect_shape(&f, &[Some(h.triangles), Some(3)], "texture corners").map_err(|e| e.in_file(&ufp))?;
        Some(UvAtlas {
            coords: c.data.chunks_exact(2).map(|x| [x[0], x[1]]).collect(),
            corners: f.data.chunks_exact(3).map(|x| [x[0], x[1], x[2]]).collect(),
        })
    } else {
        None
    };
    let topology = Topology::new(h.vertices, triangles, uv).map_err(|e| e.in_file(&fp))?;
    let nv = h.vertices;
    progress.start("reading subject", h.sequences.len() as u64);
    let sequences: Vec<Result<Sequence>> = h
        .sequences
        .par_iter()
        .enumerate()
        .map(|(k, sh)| {
            let pp = path.join(format!("positions_{k}.npy"));
            let p = read_npy::<f32>(&pp)?;
            expect_shape(&p, &[Some(sh.frames), Some(nv), Some(3)], "positions").map_err(|e| e.in_file(&pp))?;
            let mut s =
                Sequence::new(sh.name.clone(), nv, p.data).map_err(|e| e.in_file(&pp))?.with_tags(sh.tags.clone());
            let lp = path.join(format!("labels_{k}.npy"));
            let l = read_npy::<u8>(&lp)?;
            expect_shape(&l, &[Some(sh.frames)], "frame labels").map_err(|e| e.in_file(&lp))?;
            let labels = l
                .data
                .iter()
                .enumerate()
                .map(|(f, &b)| match b {
                    0 => Ok(FrameLabel::Original),
                    1 => Ok(FrameLabel::Synthetic),
                    _ => Err(err!(Shape, "label {b}: expected 0 (original) or 1 (synthetic)").in_file(&lp).at_frame(f)),
                })
                .collect::<Result<Vec<_>>>()?;
            s = s.with_labels(labels)?;
            if let Some(jh) = &sh.joints {
                let jp = path.join(format!("joints_{k}.npy"));
                let j = read_npy::<f32>(&jp)?;
                expect_shape(&j, &[Some(sh.frames), Some(jh.names.len()), Some(4), Some(4)], "joint matrices")
                    .map_err(|e| e.in_file(&jp))?;
                s = s
                    .with_joints(JointTrack { names: jh.names.clone(), parents: jh.parents.clone(), matrices: j.data })
                    .map_err(|e| e.in_file(&jp))?;
            }
            progress.advance(1);
            Ok(s)
        })
        .collect();
    let sequences = sequences.into_iter().collect::<Result<Vec<_>>>()?;
    progress.finish();
    Subject::new(h.name, topology, sequences, h.fps, h.up_axis, h.units).map_err(|e| e.in_file(&hp))
}

/// A subject cache opened to read some of its frames only: a tile job of the all-pairs work
/// (the distance matrix cut into tiles) holds the frames of its tile, not the subject. The
/// description and the topology are read and checked on opening; frames are read on demand,
/// seeking in `positions_<k>.npy`.
pub struct CachedFrames {
    path: std::path::PathBuf,
    pub name: String,
    pub topology: Topology,
    pub index: crate::FrameIndex,
    pub up_axis: UpAxis,
    pub units: Units,
    pub fps: f64,
}

impl CachedFrames {
    /// Opens the cache at `path` (its `subject.json` and `faces.npy`).
    pub fn open(path: &Path) -> Result<Self> {
        let (h, _, triangles) = read_header_and_faces(path)?;
        let fp = path.join("faces.npy");
        let topology = Topology::new(h.vertices, triangles, None).map_err(|e| e.in_file(&fp))?;
        let index = crate::FrameIndex::new(h.sequences.iter().map(|s| s.frames))
            .with_names(h.sequences.iter().map(|s| s.name.clone()).collect());
        Ok(CachedFrames {
            path: path.to_path_buf(),
            name: h.name,
            topology,
            index,
            up_axis: h.up_axis,
            units: h.units,
            fps: h.fps,
        })
    }

    /// The positions of the global frames `frames` (any order, repeats allowed), each run of
    /// consecutive frames of one sequence read with one seek; checked against the description.
    pub fn read(&self, frames: &[usize]) -> Result<Vec<(usize, Vec<f32>)>> {
        let nv = self.topology.n_vertices();
        let mut sorted = frames.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        let mut out = Vec::with_capacity(sorted.len());
        let mut k = 0;
        while k < sorted.len() {
            let g = sorted[k];
            let (s, f) = self.index.locate(g).ok_or_else(|| {
                err!(Shape, "frame {g}: the subject has {} frames", self.index.len()).in_file(&self.path)
            })?;
            let mut end = k + 1;
            while end < sorted.len()
                && sorted[end] == sorted[end - 1] + 1
                && self.index.locate(sorted[end]).map(|l| l.0) == Some(s)
            {
                end += 1;
            }
            let pp = self.path.join(format!("positions_{s}.npy"));
            let (shape, data) = crate::npy::read_npy_rows::<f32>(&pp, f..f + (end - k))?;
            if shape != [self.index.range(s).len(), nv, 3] {
                return Err(err!(
                    Shape,
                    "shape {shape:?}: expected positions of shape [{}, {nv}, 3]",
                    self.index.range(s).len()
                )
                .in_file(&pp));
            }
            for (r, chunk) in data.chunks_exact(3 * nv).enumerate() {
                out.push((sorted[k + r], chunk.to_vec()));
            }
            k = end;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    /// A cache of two one-frame sequences, "a" and "b", at 30 fps; returns its folder.
    fn cache(dir: &Path) -> std::path::PathBuf {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let seqs = vec![Sequence::new("a", 3, vec![0.0; 9]).unwrap(), Sequence::new("b", 3, vec![1.0; 9]).unwrap()];
        let s = Subject::new("s", topo, seqs, 30.0, UpAxis::PosY, Units::metres()).unwrap();
        let p = dir.join("s.subject");
        write_cache(&p, &s, false, &NoProgress).unwrap();
        p
    }

    fn edit(p: &Path, from: &str, to: &str) {
        let hp = p.join("subject.json");
        let t = std::fs::read_to_string(&hp).unwrap();
        assert!(t.contains(from), "{t}");
        std::fs::write(&hp, t.replacen(from, to, 1)).unwrap();
    }

    #[test]
    fn an_empty_or_repeated_sequence_name_is_refused_naming_the_file_and_the_sequence() {
        let d = tempfile::tempdir().unwrap();
        let p = cache(d.path());
        edit(&p, "\"name\": \"b\"", "\"name\": \"\"");
        for e in [read_cache(&p, &NoProgress).unwrap_err(), CachedFrames::open(&p).err().unwrap()] {
            let m = e.to_string();
            assert!(m.contains("subject.json") && m.contains("sequence 1 has an empty name"), "{m}");
        }
        edit(&p, "\"name\": \"\"", "\"name\": \"a\"");
        let m = read_cache(&p, &NoProgress).unwrap_err().to_string();
        assert!(m.contains("subject.json") && m.contains("sequences 0 and 1 are both named \"a\""), "{m}");
    }

    #[test]
    fn a_frame_rate_out_of_range_is_refused_naming_the_file() {
        let d = tempfile::tempdir().unwrap();
        let p = cache(d.path());
        edit(&p, "\"fps\": 30.0", "\"fps\": 1e300");
        for e in [read_cache(&p, &NoProgress).unwrap_err(), CachedFrames::open(&p).err().unwrap()] {
            let m = e.to_string();
            assert!(m.contains("subject.json") && m.contains("0.1 to 10000 frames per second"), "{m}");
        }
    }
}
