//! Reading one source: what a path holds (a sequence folder, a dataset of them, a folder of OBJ
//! or PLY frames, one mesh file, a glb, a USD stage, an Alembic archive) and its sequences, as
//! a subject's sequences ([`read_source`]) or, when their topology varies, as frames of their
//! own ([`read_source_any`]: the pieces of a frame set).

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use surfcap_mesh::error::{ErrorKind, Result, err};
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::progress::Progress;
use surfcap_mesh::subject::{Subject, Units, UpAxis};
use surfcap_mesh::topology::Topology;

use super::{SourceLayout, SourceSequence, file_stem, simple, thousands};
use crate::frame_folder::{FrameFormat, list_frames, read_frame_folder};
use crate::shared_layout::{dataset_sequences, is_layout_sequence, read_layout_sequence};

/// Reads every sequence a path holds: a shared-layout sequence folder, a dataset folder of them,
/// a folder of OBJ or PLY frames, a single `.obj`/`.ply` (one frame), a `.glb`, a `.usda` or an
/// `.abc` (Alembic).
/// (Manifests and subject caches are whole subjects: see [`super::import`] and [`super::open_subject`].)
pub fn read_source(path: &Path, progress: &dyn Progress) -> Result<Vec<SourceSequence>> {
    if !path.exists() {
        return Err(err!(Io, "no such file or folder").in_file(path));
    }
    if path.is_dir() {
        if is_layout_sequence(path)? {
            let s = read_layout_sequence(path)?;
            let origin = path.join("positions.npy");
            if let Some(f) = s.meta.frames.filter(|&f| f * s.topology.n_vertices() * 3 != s.positions.len()) {
                return Err(err!(
                    Shape,
                    "{} frames, but meta.json says {f}",
                    s.positions.len() / (3 * s.topology.n_vertices())
                )
                .in_file(&origin));
            }
            return Ok(vec![SourceSequence {
                name: s.meta.name.unwrap_or(s.name),
                topology: s.topology,
                positions: s.positions,
                joints: s.joints,
                tags: s.meta.tags,
                labels: s.meta.labels,
                fps: s.meta.fps,
                up_axis: s.meta.up_axis,
                units: s.meta.units,
                origin,
                layout: SourceLayout::TemplatePositions,
            }]);
        }
        let seqs = dataset_sequences(path)?;
        if !seqs.is_empty() {
            progress.start(&format!("reading {} sequences", seqs.len()), seqs.len() as u64);
            let mut out = Vec::new();
            for s in seqs {
                out.extend(read_source(&s, &surfcap_mesh::progress::NoProgress)?);
                progress.advance(1);
            }
            progress.finish();
            return Ok(out);
        }
        for format in [FrameFormat::Obj, FrameFormat::Ply] {
            let files = list_frames(path, format)?;
            if !files.is_empty() {
                let lone_template = files.len() == 1 && files[0].file_name().is_some_and(|n| n == "template.obj");
                let (topology, positions) = read_frame_folder(path, format, progress)?;
                let layout = SourceLayout::FrameFolder { format, files: files.len(), lone_template };
                return Ok(vec![simple(file_stem(path), topology, positions, path, layout)]);
            }
        }
        return Err(err!(
            Unsupported,
            "cannot tell what this folder holds: expected template.obj + positions.npy, a dataset of such folders, \
             .obj or .ply frame files, surfcap.toml, or a subject cache (subject.json)"
        )
        .in_file(path));
    }
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "obj" => {
            let m = crate::obj::read_obj(path)?;
            let t = m.topology().map_err(|e| e.in_file(path))?;
            Ok(vec![simple(file_stem(path), t, m.positions, path, SourceLayout::MeshFile(FrameFormat::Obj))])
        }
        "ply" => {
            let m = crate::ply::read_ply(path)?;
            let t = m.topology().map_err(|e| e.in_file(path))?;
            Ok(vec![simple(file_stem(path), t, m.positions, path, SourceLayout::MeshFile(FrameFormat::Ply))])
        }
        "glb" => {
            let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
            if let Some(m) = crate::glb_frame_set::frame_set_meta(&bytes) {
                let frames: u64 = m["sequences"].as_array().into_iter().flatten().filter_map(|q| q["frames"].as_u64()).sum();
                let why = format!("{} holds a frame set (a mesh per frame, {} frames)", path.display(), thousands(frames as usize));
                return subject_only((Vec::new(), Some(why)));
            }
            let g = crate::glb::parse_glb(&bytes).map_err(|e| e.in_file(path))?;
            Ok(g.sequences
                .into_iter()
                .map(|s| SourceSequence {
                    name: s.name.clone(),
                    topology: g.topology.clone(),
                    positions: s.positions().to_vec(),
                    joints: None,
                    tags: s.tags.clone(),
                    labels: Some(s.labels.clone()),
                    fps: g.fps,
                    up_axis: g.up_axis,
                    units: g.units.clone(),
                    origin: path.to_path_buf(),
                    layout: SourceLayout::Glb,
                })
                .collect())
        }
        // `.usd` may hold text or the binary crate format; the reader refuses the latter with the
        // command that converts it.
        "usda" | "usd" | "usdc" => subject_only(usda_pieces(path, progress)?),
        "abc" => subject_only(alembic_pieces(path, progress)?),
        _ => Err(err!(
            Unsupported,
            "unknown file type {ext:?}: expected .obj, .ply, .glb, .usda, .abc, surfcap.toml or a folder (a .pc2 or .npy needs a template: list it in surfcap.toml)"
        )
        .in_file(path)),
    }
}

/// One frame's own topology and positions.
pub(super) type MeshFrame = (Topology, Vec<f32>);

/// One sequence of a frame set read from some source, before it is merged.
#[derive(Debug, Clone)]
pub(super) struct SourceFrames {
    pub(super) name: String,
    pub(super) frames: Vec<MeshFrame>,
    pub(super) tags: Vec<String>,
    pub(super) labels: Option<Vec<surfcap_mesh::subject::FrameLabel>>,
    pub(super) fps: Option<f64>,
    pub(super) up_axis: Option<UpAxis>,
    pub(super) units: Option<Units>,
    pub(super) origin: PathBuf,
    pub(super) layout: SourceLayout,
}

impl SourceFrames {
    /// A shared-topology sequence as frames of their own.
    pub(super) fn from_sequence(s: SourceSequence) -> SourceFrames {
        let n = 3 * s.topology.n_vertices();
        let frames = s.positions.chunks_exact(n).map(|p| (s.topology.clone(), p.to_vec())).collect();
        SourceFrames {
            name: s.name,
            frames,
            tags: s.tags,
            labels: s.labels,
            fps: s.fps,
            up_axis: s.up_axis,
            units: s.units,
            origin: s.origin,
            layout: s.layout,
        }
    }
}

/// What one source gave: sequences of one topology each, or a sequence of frames with their own.
pub(super) enum Piece {
    Shared(SourceSequence),
    Frames(SourceFrames),
}

/// How the first frame whose vertices or triangles differ from frame 0's (texture coordinates
/// aside) differs, for the note: vertex counts, else triangle counts, else
/// the connectivity.
fn frame_difference(frames: &[MeshFrame]) -> Option<String> {
    let t0 = &frames[0].0;
    let (k, (t, _)) = frames.iter().enumerate().skip(1).find(|(_, (t, _))| t0.first_difference(t).is_some())?;
    Some(if t.n_vertices() != t0.n_vertices() {
        format!("frame {k}: {} vertices, frame 0: {}", thousands(t.n_vertices()), thousands(t0.n_vertices()))
    } else if t.n_triangles() != t0.n_triangles() {
        format!("frame {k}: {} triangles, frame 0: {}", thousands(t.n_triangles()), thousands(t0.n_triangles()))
    } else {
        format!(
            "frame {k}: the same {} vertices and {} triangles as frame 0, connected differently",
            thousands(t.n_vertices()),
            thousands(t.n_triangles())
        )
    })
}

/// Reads a source like [`read_source`], except that a folder of OBJ/PLY frames whose vertices or
/// triangles differ between frames is read frame by frame into a frame-set piece, with the note
/// saying so.
pub(super) fn read_source_any(path: &Path, progress: &dyn Progress, notes: &mut Vec<String>) -> Result<Vec<Piece>> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let file_pieces = match ext.as_str() {
        "abc" if !path.is_dir() => Some(alembic_pieces(path, progress)?),

        "usda" | "usd" | "usdc" if !path.is_dir() => Some(usda_pieces(path, progress)?),
        _ => None,
    };
    if let Some((pieces, frame_set)) = file_pieces {
        if let Some(why) = frame_set {
            notes.push(format!("{why}: imported as a frame set; commands that need one topology cannot use it"));
        }
        return Ok(pieces);
    }
    let first_try = read_source(path, progress);
    let e = match first_try {
        Ok(seqs) => return Ok(seqs.into_iter().map(Piece::Shared).collect()),
        Err(e) if e.kind == ErrorKind::TopologyMismatch && path.is_dir() => e,
        // A frame-set glb (read again only then: a subject's glb is read once).
        Err(e) if e.kind == ErrorKind::TopologyMismatch && ext == "glb" => {
            let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
            let (pieces, why) = glb_frame_set_pieces(path, &bytes)?;
            if let Some(why) = why {
                notes.push(format!("{why}: imported as a frame set; commands that need one topology cannot use it"));
            }
            return Ok(pieces);
        }
        Err(e) => return Err(e),
    };
    // Only a frame folder reaches `read_frame_folder`, the one reader that reports a frame's
    // topology differing from the first's; anything else keeps its error.
    let Some((format, files)) = [FrameFormat::Obj, FrameFormat::Ply]
        .into_iter()
        .map(|f| list_frames(path, f).map(|files| (f, files)))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .find(|(_, files)| !files.is_empty())
    else {
        return Err(e);
    };
    if is_layout_sequence(path)? || !dataset_sequences(path)?.is_empty() {
        return Err(e);
    }
    progress.start(&format!("reading {} frames, each with its own topology", files.len()), files.len() as u64);
    // A frame with no faces at all is positions only, which only makes sense with one shared
    // topology: then the subject's error (a vertex count differing from the first frame's) is
    // what the user needs to read.
    let frames: Vec<Result<Option<MeshFrame>>> = files
        .par_iter()
        .enumerate()
        .map(|(k, file)| {
            let (t, p, faceless) = match format {
                FrameFormat::Obj => {
                    let m = crate::obj::read_obj(file).map_err(|e| e.at_frame(k))?;
                    (m.topology(), m.positions, m.triangles.is_empty())
                }
                FrameFormat::Ply => {
                    let m = crate::ply::read_ply(file).map_err(|e| e.at_frame(k))?;
                    (m.topology(), m.positions, m.triangles.is_empty())
                }
            };
            progress.advance(1);
            if faceless {
                return Ok(None);
            }
            Ok(Some((t.map_err(|e| e.in_file(file).at_frame(k))?, p)))
        })
        .collect();
    progress.finish();
    let Some(frames) = frames.into_iter().collect::<Result<Option<Vec<_>>>>()? else { return Err(e) };
    let Some(diff) = frame_difference(&frames) else { return Err(e) };
    notes.push(format!(
        "frames of {} have different vertices/triangles ({diff}): imported as a frame set; commands that need one \
         topology cannot use it",
        path.display()
    ));
    let layout = SourceLayout::FrameFolder { format, files: files.len(), lone_template: false };
    Ok(vec![Piece::Frames(SourceFrames {
        name: file_stem(path),
        frames,
        tags: Vec::new(),
        labels: None,
        fps: None,
        up_axis: None,
        units: None,
        origin: path.to_path_buf(),
        layout,
    })])
}

/// Pieces read from one file, and why they are a frame set rather than a subject's sequences
/// (the file and what varies), when they are.
type FilePieces = (Vec<Piece>, Option<String>);

/// A file's pieces as a subject's sequences (the readers of [`read_source`], which build one
/// subject): a file that holds a frame set is refused, saying why and where it can go.
fn subject_only((pieces, frame_set): FilePieces) -> Result<Vec<SourceSequence>> {
    if let Some(why) = frame_set {
        return Err(err!(TopologyMismatch, "{why}: a varying-topology source imports as a frame set (-o x.frames)"));
    }
    Ok(pieces
        .into_iter()
        .filter_map(|p| match p {
            Piece::Shared(s) => Some(s),
            Piece::Frames(_) => None,
        })
        .collect())
}

/// An Alembic archive's meshes as pieces: a mesh of constant topology is a sequence, one whose
/// topology changes between samples (per-frame reconstructions) a sequence of frames of their
/// own, which makes the import a frame set.
fn alembic_pieces(path: &Path, progress: &dyn Progress) -> Result<FilePieces> {
    use crate::abc_read::AbcFrames;
    let archive = crate::abc_read::read_abc(path)?;
    for n in &archive.notes {
        progress.note(&format!("{}: {n}", path.display()));
    }
    let mismatch = archive.topology_mismatch().map(|d| format!("{}: {d}", path.display()));
    let mut pieces = Vec::with_capacity(archive.meshes.len());
    let mut frame_set = None;
    for m in archive.meshes {
        let changes = m.topology_change();
        if let Some((frame, faces, was)) = changes {
            frame_set.get_or_insert_with(|| {
                format!(
                    "{} {}: the topology changes at frame {frame} ({faces} faces, was {was})",
                    path.display(),
                    m.path
                )
            });
        }
        if changes.is_some() || mismatch.is_some() {
            // Every frame with its own topology (a frame set's sequence).
            let frames = match m.frames {
                AbcFrames::Varying { frames } => frames.into_iter().map(|f| (f.topology, f.positions)).collect(),
                AbcFrames::Constant { topology, positions } => {
                    let per = (3 * topology.n_vertices()).max(1);
                    positions.chunks(per).map(|p| (topology.clone(), p.to_vec())).collect()
                }
            };
            pieces.push(Piece::Frames(SourceFrames {
                name: m.name,
                frames,
                tags: Vec::new(),
                labels: m.labels,
                fps: archive.fps,
                up_axis: archive.up_axis,
                units: archive.units.clone(),
                origin: path.to_path_buf(),
                layout: SourceLayout::Alembic,
            }));
            continue;
        }
        let (topology, positions) = match m.frames {
            AbcFrames::Constant { topology, positions } => (topology, positions),
            AbcFrames::Varying { frames } => {
                let Some(first) = frames.first() else { continue };
                let topology = first.topology.clone();
                (topology, frames.into_iter().flat_map(|f| f.positions).collect())
            }
        };
        pieces.push(Piece::Shared(SourceSequence {
            name: m.name,
            topology,
            positions,
            joints: None,
            tags: Vec::new(),
            labels: m.labels,
            fps: archive.fps,
            up_axis: archive.up_axis,
            units: archive.units.clone(),
            origin: path.to_path_buf(),
            layout: SourceLayout::Alembic,
        }));
    }
    Ok((pieces, frame_set.or(mismatch)))
}

/// A USD stage's meshes as pieces: one subject's sequences when they share one topology;
/// otherwise (meshes of different topology, or faces time-sampled so that they change between
/// frames) every mesh a sequence of frames with their own topology, which makes a frame set.
fn usda_pieces(path: &Path, progress: &dyn Progress) -> Result<FilePieces> {
    let stage = crate::usda_read::read_usda(path)?;
    for n in &stage.notes {
        progress.note(&format!("{}: {n}", path.display()));
    }
    let mismatch = stage.topology_mismatch().map(|e| format!("{}: {}", path.display(), e.message));
    let mut pieces = Vec::with_capacity(stage.meshes.len());
    for m in stage.meshes {
        if mismatch.is_none() {
            pieces.push(Piece::Shared(SourceSequence {
                name: m.name,
                topology: m.topology,
                positions: m.positions,
                joints: None,
                tags: Vec::new(),
                labels: m.labels,
                fps: stage.fps,
                up_axis: stage.up_axis,
                units: stage.units.clone(),
                origin: path.to_path_buf(),
                layout: SourceLayout::Usda,
            }));
            continue;
        }
        let frames = match m.varying {
            Some(frames) => frames,
            None => {
                let per = (3 * m.topology.n_vertices()).max(1);
                m.positions.chunks(per).map(|p| (m.topology.clone(), p.to_vec())).collect()
            }
        };
        pieces.push(Piece::Frames(SourceFrames {
            name: m.name,
            frames,
            tags: Vec::new(),
            labels: m.labels,
            fps: stage.fps,
            up_axis: stage.up_axis,
            units: stage.units.clone(),
            origin: path.to_path_buf(),
            layout: SourceLayout::Usda,
        }));
    }
    Ok((pieces, mismatch))
}

/// A frame-set glb (`glb_frame_set`: a mesh per frame) as pieces, with why it is a frame set.
fn glb_frame_set_pieces(path: &Path, bytes: &[u8]) -> Result<FilePieces> {
    let set = crate::glb_frame_set::parse_glb_frame_set(bytes, &file_stem(path)).map_err(|e| e.in_file(path))?;
    let why =
        format!("{} holds a frame set (a mesh per frame, {} frames)", path.display(), thousands(set.frame_count()));
    let mut pieces = frame_set_pieces(&set, path);
    for p in &mut pieces {
        if let Piece::Frames(f) = p {
            f.layout = SourceLayout::Glb;
        }
    }
    Ok((pieces, Some(why)))
}

/// A frame set's sequences as pieces (to merge a `.frames` folder with more data).
pub(super) fn frame_set_pieces(set: &FrameSet, origin: &Path) -> Vec<Piece> {
    set.sequences()
        .iter()
        .map(|q| {
            Piece::Frames(SourceFrames {
                name: q.name.clone(),
                frames: q.frames().iter().map(|f| (f.topology().clone(), f.positions().to_vec())).collect(),
                tags: q.tags.clone(),
                labels: Some(q.labels().to_vec()),
                fps: Some(set.fps),
                up_axis: Some(set.up_axis),
                units: Some(set.units.clone()),
                origin: origin.to_path_buf(),
                layout: SourceLayout::FrameSetFolder,
            })
        })
        .collect()
}

/// A subject's sequences as sources (to merge a cache with more data).
pub(super) fn sequences_of(s: &Subject, origin: &Path) -> Vec<SourceSequence> {
    s.sequences()
        .iter()
        .map(|q| SourceSequence {
            name: q.name.clone(),
            topology: s.topology().clone(),
            positions: q.positions().to_vec(),
            joints: q.joints.clone(),
            tags: q.tags.clone(),
            labels: Some(q.labels.clone()),
            fps: Some(s.fps),
            up_axis: Some(s.up_axis),
            units: Some(s.units.clone()),
            origin: origin.to_path_buf(),
            layout: SourceLayout::Cache,
        })
        .collect()
}
