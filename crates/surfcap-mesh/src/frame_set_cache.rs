//! The on-disk form of a [`FrameSet`] (Huang et al. 2009's per-frame reconstructions): a folder `x.frames` of `.npy` arrays numpy opens directly, written and read
//! with the discipline of the subject cache (`cache.rs`): built under a temporary sibling and
//! renamed into place (`atomic.rs`), marked with `.surfcap-output.json` of kind `frame-set`, and
//! never replacing a folder surfcap did not write (`output_path.rs`).
//!
//! ```text
//! frameset.json            name, fps, up axis, units, sequences (name, frames, tags, labels)
//! positions_<k>.npy        float32 [sum of the frames' vertices, 3]     (sequence k)
//! vertex_offsets_<k>.npy   uint64 [frames + 1]: frame f's vertices are rows off[f]..off[f+1]
//! faces_<k>.npy            uint32 [sum of the frames' triangles, 3]: indices local to the frame
//! face_offsets_<k>.npy     uint64 [frames + 1]: frame f's triangles are rows off[f]..off[f+1]
//! correspondence_<k>.npy   float64 [sum of vertices, 4]  (optional: the known answer of
//!                          `surfcap remesh-frames`: source triangle, then 3 barycentrics)
//! uv_<k>.npy               float32 [sum of the frames' texture coordinates, 2]  (when the
//! uv_offsets_<k>.npy       uint64 [frames + 1]                 frames have texture coordinates)
//! uv_faces_<k>.npy         uint32 [sum of triangles, 3]: each corner's texture coordinate,
//!                          local to the frame, rows as in faces_<k>.npy
//! ```
//! In numpy, frame `f` of sequence `k` is `P[vo[f]:vo[f+1]]` and `F[fo[f]:fo[f+1]]`.
//!
//! Face indices are local to their frame (0 is the frame's first vertex), so a frame can be cut
//! out without renumbering. Labels live in `frameset.json` (a list of "original"/"synthetic")
//! rather than in an array: they are short and read with the header.
//!
//! Reading checks everything against everything else before using it, with errors naming the
//! file and the frame (`sequence:frame`): shapes, offsets that start at 0, increase strictly (a
//! frame has at least one vertex and one triangle), end at the array's row count; face indices
//! within their frame; finite positions. Arrays are allocated only once `read_npy` has checked
//! their declared size against the file's length.

use std::path::Path;

use npyz::TypeChar;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::atomic::{write_dir, write_file};
use crate::cache_description::read_description;
use crate::error::{Location, Result, err};
use crate::frame_set::{Correspondence, FrameSet, FrameSetSequence, frame_error};
use crate::npy::{NpyElement, expect_shape, read_npy, write_npy};
use crate::progress::Progress;
use crate::subject::{FrameLabel, Units, UpAxis};
use crate::topology::{Topology, UvAtlas};

const FORMAT: &str = "surfcap-frame-set";
const VERSION: u32 = 1;

/// The kind of output a frame set folder is, in its marker.
pub const OUTPUT_KIND: &str = "frame-set";

/// The name of the description file in a frame set folder.
pub const HEADER_FILE: &str = "frameset.json";

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    name: String,
    fps: f64,
    up_axis: UpAxis,
    units: Units,
    /// Total frames over all sequences (for a quick count without reading the arrays).
    frames: usize,
    sequences: Vec<SeqHeader>,
}

#[derive(Serialize, Deserialize)]
struct SeqHeader {
    name: String,
    frames: usize,
    tags: Vec<String>,
    labels: Vec<FrameLabel>,
    /// Whether `correspondence_<k>.npy` is there.
    correspondence: bool,
    /// Whether `uv_<k>.npy`, `uv_offsets_<k>.npy` and `uv_faces_<k>.npy` are there.
    uv: bool,
}

/// Whether `path` is a frame set folder (holds `frameset.json`).
pub fn is_frame_set(path: &Path) -> bool {
    path.join(HEADER_FILE).is_file()
}

/// Writes a frame set folder atomically (all or nothing). `path` may be new, empty, or a frame
/// set surfcap wrote; any other folder only with `force`.
pub fn write_frame_set(path: &Path, set: &FrameSet, force: bool, progress: &dyn Progress) -> Result<()> {
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        name: set.name.clone(),
        fps: set.fps,
        up_axis: set.up_axis,
        units: set.units.clone(),
        frames: set.frame_count(),
        sequences: set
            .sequences()
            .iter()
            .map(|s| SeqHeader {
                name: s.name.clone(),
                frames: s.n_frames(),
                tags: s.tags.clone(),
                labels: s.labels().to_vec(),
                correspondence: s.correspondence().is_some(),
                uv: s.has_uv(),
            })
            .collect(),
    };
    progress.start("writing frame set", set.sequences().len() as u64);
    write_dir(path, OUTPUT_KIND, force, |dir| {
        for (k, s) in set.sequences().iter().enumerate() {
            let (mut vo, mut fo) = (vec![0u64], vec![0u64]);
            let (mut positions, mut faces) = (Vec::new(), Vec::new());
            for f in s.frames() {
                positions.extend_from_slice(f.positions());
                faces.extend(f.topology().triangles().iter().flatten().copied());
                vo.push(vo.last().unwrap() + f.n_vertices() as u64);
                fo.push(fo.last().unwrap() + f.n_triangles() as u64);
            }
            let (nv, nt) = (positions.len() / 3, faces.len() / 3);
            write_file(&dir.join(format!("positions_{k}.npy")), |w| write_npy(w, &[nv, 3], &positions))?;
            write_file(&dir.join(format!("vertex_offsets_{k}.npy")), |w| write_npy(w, &[vo.len()], &vo))?;
            write_file(&dir.join(format!("faces_{k}.npy")), |w| write_npy(w, &[nt, 3], &faces))?;
            write_file(&dir.join(format!("face_offsets_{k}.npy")), |w| write_npy(w, &[fo.len()], &fo))?;
            if s.has_uv() {
                let (mut coords, mut corners, mut uo) = (Vec::new(), Vec::new(), vec![0u64]);
                for f in s.frames() {
                    let uv = f.topology().uv().expect("all frames have UVs");
                    coords.extend(uv.coords.iter().flatten().copied());
                    corners.extend(uv.corners.iter().flatten().copied());
                    uo.push(uo.last().unwrap() + uv.coords.len() as u64);
                }
                write_file(&dir.join(format!("uv_{k}.npy")), |w| write_npy(w, &[coords.len() / 2, 2], &coords))?;
                write_file(&dir.join(format!("uv_offsets_{k}.npy")), |w| write_npy(w, &[uo.len()], &uo))?;
                write_file(&dir.join(format!("uv_faces_{k}.npy")), |w| {
                    write_npy(w, &[corners.len() / 3, 3], &corners)
                })?;
            }
            if let Some(c) = s.correspondence() {
                write_file(&dir.join(format!("correspondence_{k}.npy")), |w| write_npy(w, &[nv, 4], &c.rows))?;
            }
            progress.advance(1);
        }
        let json = serde_json::to_vec_pretty(&header).map_err(|e| err!(Io, "cannot encode {HEADER_FILE}: {e}"))?;
        write_file(&dir.join(HEADER_FILE), |w| w.write_all(&json))
    })?;
    progress.finish();
    Ok(())
}

fn read_header(path: &Path) -> Result<Header> {
    let hp = path.join(HEADER_FILE);
    let h: Header =
        read_description(&hp, "frame set description", (FORMAT, VERSION), |h: &Header| (h.format.as_str(), h.version))?;
    let counted: usize = h.sequences.iter().map(|s| s.frames).sum();
    if counted != h.frames {
        return Err(err!(Metadata, "{} frames in all, but the sequences have {counted}", h.frames).in_file(&hp));
    }
    for s in &h.sequences {
        if s.labels.len() != s.frames {
            return Err(err!(
                Metadata,
                "sequence {:?}: {} labels for {} frames: expected one per frame",
                s.name,
                s.labels.len(),
                s.frames
            )
            .in_file(&hp));
        }
    }
    Ok(h)
}

/// The number of frames of a frame set folder, from its description only (no array read).
pub fn frame_count(path: &Path) -> Result<usize> {
    Ok(read_header(path)?.frames)
}

/// A frame offset (`uint64`, or any integer type holding a non-negative value).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Offset(u64);

impl NpyElement for Offset {
    const EXPECTED: &'static str = "an integer type ('<u8', '<i8', '<u4', ...) holding non-negative offsets";
    fn accepts(kind: TypeChar, size: u64) -> bool {
        matches!(kind, TypeChar::Int | TypeChar::Uint) && matches!(size, 1 | 2 | 4 | 8)
    }
    fn decode(kind: TypeChar, b: &[u8]) -> Option<Offset> {
        let mut a = [0u8; 8];
        a[..b.len()].copy_from_slice(b);
        let v = u64::from_le_bytes(a);
        match kind {
            TypeChar::Int if b.len() < 8 && b[b.len() - 1] & 0x80 != 0 => None,
            TypeChar::Int if b.len() == 8 && (v as i64) < 0 => None,
            _ => Some(Offset(v)),
        }
    }
}

/// Reads an offsets array of `frames + 1` entries that starts at 0, increases strictly (each
/// frame holds at least one row) and ends at `rows`; `what` names the rows.
fn read_offsets(path: &Path, frames: usize, rows: usize, what: &str) -> Result<Vec<usize>> {
    let a = read_npy::<Offset>(path)?;
    expect_shape(&a, &[Some(frames + 1)], &format!("{what} offsets (frames + 1)")).map_err(|e| e.in_file(path))?;
    if a.data[0].0 != 0 {
        return Err(err!(Shape, "first offset is {}: expected 0", a.data[0].0).in_file(path));
    }
    for f in 0..frames {
        let (lo, hi) = (a.data[f].0, a.data[f + 1].0);
        if hi <= lo {
            return Err(err!(
                Shape,
                "offsets {lo} then {hi}: expected them to increase (every frame has at least one of its {what})"
            )
            .in_file(path)
            .at(Location::Frame(f)));
        }
    }
    let last = a.data[frames].0;
    if last != rows as u64 {
        return Err(
            err!(Shape, "last offset is {last}: expected {rows}, the number of {what} in the array").in_file(path)
        );
    }
    Ok(a.data.iter().map(|o| o.0 as usize).collect())
}

/// Reads a frame set folder, checking every array against `frameset.json` and each other.
pub fn read_frame_set(path: &Path, progress: &dyn Progress) -> Result<FrameSet> {
    let h = read_header(path)?;
    let hp = path.join(HEADER_FILE);
    progress.start("reading frame set", h.sequences.len() as u64);
    let sequences: Vec<Result<FrameSetSequence>> = h
        .sequences
        .par_iter()
        .enumerate()
        .map(|(k, sh)| {
            let s = read_sequence(path, k, sh)?;
            progress.advance(1);
            Ok(s)
        })
        .collect();
    let sequences = sequences.into_iter().collect::<Result<Vec<_>>>()?;
    progress.finish();
    FrameSet::new(h.name, sequences, h.fps, h.up_axis, h.units).map_err(|e| e.in_file(&hp))
}

fn read_sequence(path: &Path, k: usize, sh: &SeqHeader) -> Result<FrameSetSequence> {
    let pp = path.join(format!("positions_{k}.npy"));
    let p = read_npy::<f32>(&pp)?;
    expect_shape(&p, &[None, Some(3)], "positions").map_err(|e| e.in_file(&pp))?;
    let vp = path.join(format!("vertex_offsets_{k}.npy"));
    let vo = read_offsets(&vp, sh.frames, p.shape[0], "vertices")?;
    let fp = path.join(format!("faces_{k}.npy"));
    let faces = read_npy::<u32>(&fp)?;
    expect_shape(&faces, &[None, Some(3)], "triangles").map_err(|e| e.in_file(&fp))?;
    let op = path.join(format!("face_offsets_{k}.npy"));
    let fo = read_offsets(&op, sh.frames, faces.shape[0], "triangles")?;
    let uv = if sh.uv {
        let up = path.join(format!("uv_{k}.npy"));
        let c = read_npy::<f32>(&up)?;
        expect_shape(&c, &[None, Some(2)], "texture coordinates").map_err(|e| e.in_file(&up))?;
        let uop = path.join(format!("uv_offsets_{k}.npy"));
        let uo = read_offsets(&uop, sh.frames, c.shape[0], "texture coordinates")?;
        let ufp = path.join(format!("uv_faces_{k}.npy"));
        let uf = read_npy::<u32>(&ufp)?;
        expect_shape(&uf, &[Some(faces.shape[0]), Some(3)], "texture corners (one row per triangle)")
            .map_err(|e| e.in_file(&ufp))?;
        Some((c.data, uo, uf.data, ufp))
    } else {
        None
    };
    let mut frames = Vec::with_capacity(sh.frames);
    for f in 0..sh.frames {
        let tris: Vec<[u32; 3]> =
            faces.data[3 * fo[f]..3 * fo[f + 1]].chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let nv = vo[f + 1] - vo[f];
        // Indices are 0-based and local to the frame here (Topology's own message counts from 1,
        // as OBJ does), so check them first with the file's own numbering.
        if let Some((i, &bad)) =
            faces.data[3 * fo[f]..3 * fo[f + 1]].iter().enumerate().find(|&(_, &x)| x as usize >= nv)
        {
            return Err(frame_error(
                err!(
                    IndexOutOfRange,
                    "vertex index {bad} out of range: the frame has {nv} vertices (indices 0 to {}, local to the frame)",
                    nv - 1
                ),
                &sh.name,
                f,
            )
            .in_file(&fp)
            .at(Location::Face(fo[f] + i / 3)));
        }
        let atlas = uv.as_ref().map(|(c, uo, uf, _)| UvAtlas {
            coords: c[2 * uo[f]..2 * uo[f + 1]].chunks_exact(2).map(|x| [x[0], x[1]]).collect(),
            corners: uf[3 * fo[f]..3 * fo[f + 1]].chunks_exact(3).map(|x| [x[0], x[1], x[2]]).collect(),
        });
        // The texture corners' file when they are what is wrong.
        let file = match &uv {
            Some((_, _, _, ufp)) if atlas.is_some() => ufp.clone(),
            _ => fp.clone(),
        };
        let topology = Topology::new(nv, tris, atlas).map_err(|mut e| {
            let file = if e.message.starts_with("texture") { &file } else { &fp };
            // The triangle's row in the file, so it can be found there.
            if let Some(Location::Face(i)) = e.location {
                e.location = Some(Location::Face(fo[f] + i));
            }
            frame_error(e, &sh.name, f).in_file(file)
        })?;
        frames.push((topology, p.data[3 * vo[f]..3 * vo[f + 1]].to_vec()));
    }
    drop(faces);
    let mut s = FrameSetSequence::from_frames(sh.name.clone(), frames)
        .map_err(|e| e.in_file(&pp))?
        .with_tags(sh.tags.clone())
        .with_labels(sh.labels.clone())
        .map_err(|e| e.in_file(&path.join(HEADER_FILE)))?;
    if sh.correspondence {
        let cp = path.join(format!("correspondence_{k}.npy"));
        let c = read_npy::<f64>(&cp)?;
        expect_shape(&c, &[Some(p.shape[0]), Some(4)], "correspondence (source triangle + 3 barycentrics)")
            .map_err(|e| e.in_file(&cp))?;
        s = s.with_correspondence(Correspondence { rows: c.data }).map_err(|mut e| match e.location {
            Some(Location::Frame(f)) => {
                e.location = None;
                frame_error(e, &sh.name, f).in_file(&cp)
            }
            _ => e.in_file(&cp),
        })?;
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ErrorKind;
    use crate::progress::NoProgress;

    fn set() -> FrameSet {
        let tri = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let tet = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let a = FrameSetSequence::from_frames(
            "a",
            vec![(tri.clone(), (0..9).map(|x| x as f32).collect()), (tet, (0..12).map(|x| -x as f32).collect())],
        )
        .unwrap()
        .with_tags(vec!["walk".into()])
        .with_labels(vec![FrameLabel::Original, FrameLabel::Synthetic])
        .unwrap()
        .with_correspondence(Correspondence { rows: (0..28).map(|x| (x / 4) as f64).collect() })
        .unwrap();
        let uv = UvAtlas { coords: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5]], corners: vec![[0, 1, 3]] };
        let with_uv = Topology::new(3, vec![[0, 1, 2]], Some(uv)).unwrap();
        let b = FrameSetSequence::from_frames("b", vec![(with_uv, vec![0.5; 9])]).unwrap();
        FrameSet::new("s", vec![a, b], 30.0, UpAxis::PosZ, Units::metres()).unwrap()
    }

    #[test]
    fn round_trips_and_refuses_foreign_folders() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("x.frames");
        let s = set();
        write_frame_set(&out, &s, false, &NoProgress).unwrap();
        assert!(is_frame_set(&out));
        assert_eq!(read_frame_set(&out, &NoProgress).unwrap(), s);
        assert_eq!(frame_count(&out).unwrap(), 3);
        // Its own earlier output is replaced; a foreign folder is not.
        write_frame_set(&out, &s, false, &NoProgress).unwrap();
        let foreign = d.path().join("mine");
        std::fs::create_dir(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), b"keep").unwrap();
        let e = write_frame_set(&foreign, &s, false, &NoProgress).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Refused);
        assert_eq!(std::fs::read(foreign.join("notes.txt")).unwrap(), b"keep");
        // A subject cache is another kind of output.
        let subject = d.path().join("y.subject");
        let subj = crate::Subject::new(
            "t",
            Topology::new(3, vec![[0, 1, 2]], None).unwrap(),
            vec![crate::Sequence::new("q", 3, vec![0.0; 9]).unwrap()],
            30.0,
            UpAxis::PosY,
            Units::metres(),
        )
        .unwrap();
        crate::cache::write_cache(&subject, &subj, false, &NoProgress).unwrap();
        assert_eq!(write_frame_set(&subject, &s, false, &NoProgress).unwrap_err().kind, ErrorKind::Refused);
    }

    fn overwrite<T: npyz::AutoSerialize + Copy>(p: &Path, shape: &[usize], data: &[T]) {
        let mut v = Vec::new();
        write_npy(&mut v, shape, data).unwrap();
        std::fs::write(p, v).unwrap();
    }

    #[test]
    fn damaged_arrays_are_errors_naming_file_and_frame() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("x.frames");
        write_frame_set(&out, &set(), false, &NoProgress).unwrap();
        let vo = out.join("vertex_offsets_0.npy");
        let check = |want: &str| {
            let e = read_frame_set(&out, &NoProgress).unwrap_err().to_string();
            assert!(e.contains(want), "{e}\nexpected: {want}");
        };
        overwrite(&vo, &[3], &[0u64, 3, 3]);
        check(&format!("{}: frame 1: offsets 3 then 3: expected them to increase", vo.display()));
        overwrite(&vo, &[3], &[0u64, 3, 8]);
        check(&format!("{}: last offset is 8: expected 7", vo.display()));
        overwrite(&vo, &[2], &[0u64, 7]);
        check(&format!("{}: shape [2]: expected vertices offsets (frames + 1) of shape [3]", vo.display()));
        overwrite(&vo, &[3], &[0i64, -3, 7]);
        check("does not fit");
        overwrite(&vo, &[3], &[0u64, 3, 7]);
        let fo = out.join("face_offsets_0.npy");
        overwrite(&fo, &[3], &[1u64, 2, 5]);
        check(&format!("{}: first offset is 1: expected 0", fo.display()));
        overwrite(&fo, &[3], &[0u64, 1, 5]);
        let faces = out.join("faces_0.npy");
        overwrite(&faces, &[5, 3], &[0u32, 1, 2, 0, 2, 1, 0, 1, 3, 1, 2, 4, 0, 3, 2]);
        check(&format!(
            "{}: triangle 3: frame a:1: vertex index 4 out of range: the frame has 4 vertices",
            faces.display()
        ));
        overwrite(&faces, &[5, 3], &[0u32, 1, 2, 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2]);
        let pos = out.join("positions_0.npy");
        let mut p = vec![0.0f32; 21];
        p[13] = f32::NAN;
        overwrite(&pos, &[7, 3], &p);
        check(&format!("{}: frame a:1: vertex 1 has a non-finite coordinate", pos.display()));
        overwrite(&pos, &[7, 2], &[0.0f32; 14]);
        check("expected positions of shape [*, 3]");
        overwrite(&pos, &[7, 3], &[0.0f32; 21]);
        let c = out.join("correspondence_0.npy");
        let mut rows: Vec<f64> = vec![0.0; 28];
        rows[16] = -1.0;
        overwrite(&c, &[7, 4], &rows);
        check(&format!("{}: frame a:1: vertex 1: correspondence [-1", c.display()));
        rows[16] = 0.0;
        overwrite(&c, &[7, 4], &rows);
        let uf = out.join("uv_faces_1.npy");
        overwrite(&uf, &[1, 3], &[0u32, 1, 4]);
        check(&format!(
            "{}: triangle 0: frame b:0: texture coordinate index 4 out of range (there are 4)",
            uf.display()
        ));
        overwrite(&uf, &[1, 3], &[0u32, 1, 3]);
        assert!(read_frame_set(&out, &NoProgress).is_ok());
        std::fs::write(out.join(HEADER_FILE), b"{\"format\": 1").unwrap();
        check(&format!("{}: line 1: not a surfcap frame set description", out.join(HEADER_FILE).display()));
    }
}
