//! Turning files on disk into a [`Subject`]: detect what a path holds, read its sequences, and
//! merge them into one subject with one topology, one frame rate, one up axis and one unit.
//!
//! Or into a [`FrameSet`] (issue 17 item 1: Huang et al. 2009 work on per-frame reconstructions
//! whose vertices and triangles differ from frame to frame): a folder of OBJ/PLY frames whose
//! connectivity differs between frames, or a `.frames` folder. [`open_any`] and [`import_any`]
//! return either kind ([`ImportedData`]); [`open_subject`] and [`import`], for the commands that
//! need one topology, refuse a frame set with a message saying what it is and where frame sets
//! are used ([`frame_set_refusal`]). A frame folder is first read as one topology (the fast,
//! usual case); only when that fails because a frame's vertices or triangles differ is it read
//! again frame by frame, so subjects cost what they did.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::cache;
use crate::error::{Error, ErrorKind, Result, err};
use crate::frame_set::{FrameSet, FrameSetSequence};
use crate::frame_set_cache;
use crate::io::frame_folder::{FrameFormat, list_frames, read_frame_folder};
use crate::io::shared_layout::{dataset_sequences, is_layout_sequence, read_layout_sequence};
use crate::manifest;
use crate::progress::Progress;
use crate::subject::{FrameLabel, JointTrack, Sequence, Subject, Units, UpAxis};
use crate::topology::Topology;

/// One sequence read from some source, before it is merged into a subject.
#[derive(Debug, Clone)]
pub struct SourceSequence {
    pub name: String,
    pub topology: Topology,
    pub positions: Vec<f32>,
    pub joints: Option<JointTrack>,
    pub tags: Vec<String>,
    pub labels: Option<Vec<FrameLabel>>,
    pub fps: Option<f64>,
    pub up_axis: Option<UpAxis>,
    pub units: Option<Units>,
    /// The file or folder it came from, for error messages.
    pub origin: PathBuf,
    /// How it was stored, as detected.
    pub layout: SourceLayout,
}

/// How a source stored a sequence, as detected from what is on disk. `import` narrates it, so a
/// folder read in a way the user did not mean (a lone `template.obj` as one OBJ frame) is seen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SourceLayout {
    /// `template.obj` + `positions.npy` (the shared-data layout).
    TemplatePositions,
    /// A folder of per-frame mesh files; `lone_template` when it is a `template.obj` with no
    /// `positions.npy` beside it.
    FrameFolder { format: FrameFormat, files: usize, lone_template: bool },
    /// One `.obj` or `.ply` file: one frame.
    MeshFile(FrameFormat),
    /// A `.glb` file.
    Glb,
    /// A USD text stage (`.usda`, or `.usd` holding text): one sequence per `Mesh` prim.
    Usda,
    /// An Alembic archive (`.abc`, Ogawa): one sequence per `PolyMesh` object.
    Alembic,
    /// A `.pc2` or `.npy` with the template a manifest names.
    WithTemplate,
    /// A subject cache written by `surfcap import`.
    Cache,
    /// A frame set folder (`.frames`) written by `surfcap import` or `surfcap remesh-frames`.
    FrameSetFolder,
}

impl std::fmt::Display for SourceLayout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let upper = |format: &FrameFormat| format.extension().to_ascii_uppercase();
        match self {
            SourceLayout::TemplatePositions => write!(f, "sequence folder (template.obj + positions.npy)"),
            SourceLayout::FrameFolder { format, files, lone_template } => {
                let s = if *files == 1 { "" } else { "s" };
                write!(f, "folder of {files} {} frame file{s}", upper(format))?;
                if *lone_template {
                    write!(f, " (template.obj with no positions.npy beside it: read as one frame)")?;
                }
                Ok(())
            }
            SourceLayout::MeshFile(format) => write!(f, "{} file (one frame)", upper(format)),
            SourceLayout::Glb => write!(f, "glb file"),
            SourceLayout::Usda => write!(f, "USD text stage"),
            SourceLayout::Alembic => write!(f, "Alembic archive"),
            SourceLayout::WithTemplate => write!(f, "positions file with the manifest's template"),
            SourceLayout::Cache => write!(f, "subject cache"),
            SourceLayout::FrameSetFolder => write!(f, "frame set folder"),
        }
    }
}

/// One sequence of an import, for narration: its name, where it came from and how it was stored.
#[derive(Debug, Clone)]
pub struct ImportedSource {
    pub sequence: String,
    pub origin: PathBuf,
    pub layout: SourceLayout,
    pub frames: usize,
}

/// Values given by the user that override (or fill in) what the sources say.
#[derive(Debug, Clone, Default)]
pub struct ImportOptions {
    pub name: Option<String>,
    pub fps: Option<f64>,
    pub up_axis: Option<UpAxis>,
    pub units: Option<Units>,
}

/// A subject and the assumptions made while building it (shown to the user, never silent).
#[derive(Debug)]
pub struct Imported {
    pub subject: Subject,
    pub notes: Vec<String>,
    /// Every sequence read, in subject order, with the layout detected.
    pub sources: Vec<ImportedSource>,
}

fn file_stem(p: &Path) -> String {
    let p =
        if p.file_name().is_none() { p.canonicalize().unwrap_or_else(|_| p.to_path_buf()) } else { p.to_path_buf() };
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "subject".into())
}

/// A sequence with nothing known but its geometry (no joints, tags, labels or metadata).
pub(crate) fn simple(
    name: String,
    topology: Topology,
    positions: Vec<f32>,
    origin: &Path,
    layout: SourceLayout,
) -> SourceSequence {
    SourceSequence {
        name,
        topology,
        positions,
        joints: None,
        tags: Vec::new(),
        labels: None,
        fps: None,
        up_axis: None,
        units: None,
        origin: origin.to_path_buf(),
        layout,
    }
}

/// Reads every sequence a path holds: a shared-layout sequence folder, a dataset folder of them,
/// a folder of OBJ or PLY frames, a single `.obj`/`.ply` (one frame), a `.glb`, a `.usda` or an
/// `.abc` (Alembic).
/// (Manifests and subject caches are whole subjects: see [`import`] and [`open_subject`].)
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
                out.extend(read_source(&s, &crate::progress::NoProgress)?);
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
            let m = crate::io::obj::read_obj(path)?;
            let t = m.topology().map_err(|e| e.in_file(path))?;
            Ok(vec![simple(file_stem(path), t, m.positions, path, SourceLayout::MeshFile(FrameFormat::Obj))])
        }
        "ply" => {
            let m = crate::io::ply::read_ply(path)?;
            let t = m.topology().map_err(|e| e.in_file(path))?;
            Ok(vec![simple(file_stem(path), t, m.positions, path, SourceLayout::MeshFile(FrameFormat::Ply))])
        }
        "glb" => {
            let bytes = crate::io::regular_file::read_regular_file(path)?;
            if let Some(m) = crate::io::glb_frame_set::frame_set_meta(&bytes) {
                let frames: u64 = m["sequences"].as_array().into_iter().flatten().filter_map(|q| q["frames"].as_u64()).sum();
                let why = format!("{} holds a frame set (a mesh per frame, {} frames)", path.display(), thousands(frames as usize));
                return subject_only((Vec::new(), Some(why)));
            }
            let g = crate::io::glb::parse_glb(&bytes).map_err(|e| e.in_file(path))?;
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

/// Something read from a source file or folder.
trait HasOrigin {
    fn origin(&self) -> &Path;
}

impl HasOrigin for SourceSequence {
    fn origin(&self) -> &Path {
        &self.origin
    }
}

/// The frame rate (required), up axis and units the sources agree on, the user's values first;
/// a missing axis or unit is assumed with a note.
fn agreed_metadata<S: HasOrigin>(
    opts: &ImportOptions,
    seqs: &[S],
    get: impl Fn(&S) -> (Option<f64>, Option<UpAxis>, Option<Units>),
    notes: &mut Vec<String>,
) -> Result<(f64, UpAxis, Units)> {
    let origin = seqs.first().map(|s| s.origin().to_path_buf()).unwrap_or_default();
    let fps = agree("frame rate", opts.fps, seqs, |s| get(s).0)?.ok_or_else(|| {
        err!(Metadata, "no frame rate is known for these sequences: pass --fps (or set fps in surfcap.toml)")
            .in_file(&origin)
    })?;
    let up_axis = match agree("up axis", opts.up_axis, seqs, |s| get(s).1)? {
        Some(u) => u,
        None => {
            notes.push("no up axis in the sources: assumed +y (pass --up-axis to change it)".into());
            UpAxis::PosY
        }
    };
    let units = match agree("units", opts.units.clone(), seqs, |s| get(s).2)? {
        Some(u) => u,
        None => {
            notes.push("no units in the sources: recorded as arbitrary (pass --units to set them)".into());
            Units::arbitrary()
        }
    };
    Ok((fps, up_axis, units))
}

/// Agreement of an optional per-source value: the user's value wins; otherwise all sources
/// that know it must agree.
fn agree<T: Clone + PartialEq + std::fmt::Debug, S: HasOrigin>(
    what: &str,
    user: Option<T>,
    seqs: &[S],
    get: impl Fn(&S) -> Option<T>,
) -> Result<Option<T>> {
    if user.is_some() {
        return Ok(user);
    }
    let mut found: Option<(T, &Path)> = None;
    for s in seqs {
        if let Some(v) = get(s) {
            match &found {
                None => found = Some((v, s.origin())),
                Some((w, origin)) if *w != v => {
                    return Err(err!(
                        Metadata,
                        "{what} {v:?} differs from {w:?} of {}: give it explicitly to merge them",
                        origin.display()
                    )
                    .in_file(s.origin()));
                }
                _ => {}
            }
        }
    }
    Ok(found.map(|(v, _)| v))
}

/// Merges sequences into one subject. All must share the first one's topology.
pub fn assemble(default_name: &str, seqs: Vec<SourceSequence>, opts: &ImportOptions) -> Result<Imported> {
    let Some(first) = seqs.first() else {
        return Err(err!(Empty, "nothing to import: no sequences were found"));
    };
    let topology = first.topology.clone();
    for s in &seqs[1..] {
        if let Some(diff) = topology.first_difference(&s.topology) {
            return Err(err!(
                TopologyMismatch,
                "topology differs from that of {} (a subject has one topology): {diff}",
                first.origin.display()
            )
            .in_file(&s.origin));
        }
    }
    let mut notes = Vec::new();
    let (fps, up_axis, units) = agreed_metadata(opts, &seqs, |s| (s.fps, s.up_axis, s.units.clone()), &mut notes)?;
    let nv = topology.n_vertices();
    let sources = seqs
        .iter()
        .map(|s| ImportedSource {
            sequence: s.name.clone(),
            origin: s.origin.clone(),
            layout: s.layout.clone(),
            frames: s.positions.len() / (3 * nv).max(1),
        })
        .collect();
    let mut sequences = Vec::with_capacity(seqs.len());
    for s in seqs {
        let origin = s.origin.clone();
        let mut seq = Sequence::new(s.name, nv, s.positions).map_err(|e| e.in_file(&origin))?.with_tags(s.tags);
        if let Some(l) = s.labels {
            seq = seq.with_labels(l).map_err(|e| e.in_file(&origin))?;
        }
        if let Some(j) = s.joints {
            seq = seq.with_joints(j).map_err(|e| e.in_file(&origin))?;
        }
        sequences.push(seq);
    }
    let name = opts.name.clone().unwrap_or_else(|| default_name.to_string());
    let subject = Subject::new(name, topology, sequences, fps, up_axis, units)?;
    Ok(Imported { subject, notes, sources })
}

/// Imports any mix of sources (manifests included) into one subject. Sources that hold a frame
/// set (a `.frames` folder, a folder of frames whose connectivity differs) are refused with
/// [`frame_set_refusal`]: use [`import_any`] to accept them.
pub fn import(paths: &[PathBuf], opts: &ImportOptions, progress: &dyn Progress) -> Result<Imported> {
    match import_any(paths, opts, progress)? {
        ImportedData::Subject(i) => Ok(i),
        ImportedData::FrameSet(f) => {
            let origin = f.frame_set_origin.clone().unwrap_or_else(|| paths[0].clone());
            Err(frame_set_refusal(&origin, f.frame_set.frame_count()))
        }
    }
}

/// A subject, or a frame set (every frame its own vertices and triangles), as imported.
#[derive(Debug)]
pub enum ImportedData {
    Subject(Imported),
    FrameSet(ImportedFrames),
}

/// A frame set and the assumptions made while building it (shown to the user, never silent).
#[derive(Debug)]
pub struct ImportedFrames {
    pub frame_set: FrameSet,
    /// Notes, the first of them saying why this is a frame set and not a subject.
    pub notes: Vec<String>,
    /// Every sequence read, in frame-set order, with the layout detected.
    pub sources: Vec<ImportedSource>,
    /// The first source that holds frames of different topologies (for messages).
    pub frame_set_origin: Option<PathBuf>,
}

/// The error of a command that needs one topology given a frame set at `path` (Display:
/// `<path>: is a frame set (...; 111 frames): ...`). The library does not know which command
/// called it, so it says "this command" and names the commands that read frame sets.
pub fn frame_set_refusal(path: &Path, frames: usize) -> Error {
    err!(
        TopologyMismatch,
        "is a frame set (every frame has its own vertices and triangles; {} frames): this command needs one shared \
         topology (`surfcap import`, `surfcap info` and `surfcap smg query` read frame sets; `surfcap remesh-frames` \
         makes them from a subject). Frame sets are for Huang et al.'s surface motion graph (`surfcap smg`)",
        thousands(frames)
    )
    .in_file(path)
}

/// `1187` as `1,187`.
fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// One frame's own topology and positions.
type MeshFrame = (Topology, Vec<f32>);

/// One sequence of a frame set read from some source, before it is merged.
#[derive(Debug, Clone)]
struct SourceFrames {
    name: String,
    frames: Vec<MeshFrame>,
    tags: Vec<String>,
    labels: Option<Vec<crate::subject::FrameLabel>>,
    fps: Option<f64>,
    up_axis: Option<UpAxis>,
    units: Option<Units>,
    origin: PathBuf,
    layout: SourceLayout,
}

impl HasOrigin for SourceFrames {
    fn origin(&self) -> &Path {
        &self.origin
    }
}

impl SourceFrames {
    /// A shared-topology sequence as frames of their own.
    fn from_sequence(s: SourceSequence) -> SourceFrames {
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
enum Piece {
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
fn read_source_any(path: &Path, progress: &dyn Progress, notes: &mut Vec<String>) -> Result<Vec<Piece>> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let file_pieces = match ext.as_str() {
        "abc" if !path.is_dir() => Some(alembic_pieces(path, progress)?),

        "usda" | "usd" if !path.is_dir() => Some(usda_pieces(path, progress)?),
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
            let bytes = crate::io::regular_file::read_regular_file(path)?;
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
                    let m = crate::io::obj::read_obj(file).map_err(|e| e.at_frame(k))?;
                    (m.topology(), m.positions, m.triangles.is_empty())
                }
                FrameFormat::Ply => {
                    let m = crate::io::ply::read_ply(file).map_err(|e| e.at_frame(k))?;
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
    use crate::io::abc_read::AbcFrames;
    let archive = crate::io::abc_read::read_abc(path)?;
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
    let stage = crate::io::usda_read::read_usda(path)?;
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

/// A frame-set glb (`io::glb_frame_set`: a mesh per frame) as pieces, with why it is a frame set.
fn glb_frame_set_pieces(path: &Path, bytes: &[u8]) -> Result<FilePieces> {
    let set = crate::io::glb_frame_set::parse_glb_frame_set(bytes, &file_stem(path)).map_err(|e| e.in_file(path))?;
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
fn frame_set_pieces(set: &FrameSet, origin: &Path) -> Vec<Piece> {
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

/// Imports any mix of sources into a subject when they share one topology (as [`import`]), or
/// into a frame set when one of them is a frame set (a `.frames` folder, or a folder of frames
/// whose vertices or triangles differ between frames); the other sources' frames then join it
/// as frames of their own.
pub fn import_any(paths: &[PathBuf], opts: &ImportOptions, progress: &dyn Progress) -> Result<ImportedData> {
    let mut pieces = Vec::new();
    let mut opts = opts.clone();
    let mut notes = Vec::new();
    let mut default_name = paths.first().map(|p| file_stem(p)).unwrap_or_else(|| "subject".into());
    for p in paths {
        if let Some(m) = manifest::find_manifest(p) {
            let (m_opts, m_seqs) = manifest::read_manifest(&m, progress)?;
            // Manifest values fill in what the command line left open.
            opts.fps = opts.fps.or(m_opts.fps);
            opts.up_axis = opts.up_axis.or(m_opts.up_axis);
            opts.units = opts.units.or(m_opts.units);
            if let Some(n) = m_opts.name {
                default_name = n;
            }
            pieces.extend(m_seqs.into_iter().map(Piece::Shared));
        } else if cache::is_cache(p) {
            let s = cache::read_cache(p, progress)?;
            default_name = s.name.clone();
            pieces.extend(sequences_of(&s, p).into_iter().map(Piece::Shared));
        } else if frame_set_cache::is_frame_set(p) {
            let s = frame_set_cache::read_frame_set(p, progress)?;
            default_name = s.name.clone();
            pieces.extend(frame_set_pieces(&s, p));
        } else {
            pieces.extend(read_source_any(p, progress, &mut notes)?);
        }
    }
    let frame_set_origin = pieces.iter().find_map(|p| match p {
        Piece::Frames(f) => Some(f.origin.clone()),
        Piece::Shared(_) => None,
    });
    if frame_set_origin.is_none() {
        let seqs = pieces
            .into_iter()
            .map(|p| match p {
                Piece::Shared(s) => s,
                Piece::Frames(_) => unreachable!("no frame-set piece"),
            })
            .collect();
        return Ok(ImportedData::Subject(assemble(&default_name, seqs, &opts)?));
    }
    let seqs: Vec<SourceFrames> = pieces
        .into_iter()
        .map(|p| match p {
            Piece::Shared(s) => {
                if s.joints.is_some() {
                    notes.push(format!(
                        "sequence {:?}: its ground-truth joints are not kept in a frame set (they belong to one \
                         topology)",
                        s.name
                    ));
                }
                SourceFrames::from_sequence(s)
            }
            Piece::Frames(f) => f,
        })
        .collect();
    let mut imported = assemble_frames(&default_name, seqs, &opts)?;
    notes.append(&mut imported.notes);
    imported.notes = notes;
    imported.frame_set_origin = frame_set_origin;
    Ok(ImportedData::FrameSet(imported))
}

/// Merges frame sequences into one frame set: frame rate, up axis and units agree as for
/// [`assemble`]; each frame keeps its own topology.
fn assemble_frames(default_name: &str, seqs: Vec<SourceFrames>, opts: &ImportOptions) -> Result<ImportedFrames> {
    if seqs.is_empty() {
        return Err(err!(Empty, "nothing to import: no sequences were found"));
    }
    let mut notes = Vec::new();
    let (fps, up_axis, units) = agreed_metadata(opts, &seqs, |s| (s.fps, s.up_axis, s.units.clone()), &mut notes)?;
    let sources = seqs
        .iter()
        .map(|s| ImportedSource {
            sequence: s.name.clone(),
            origin: s.origin.clone(),
            layout: s.layout.clone(),
            frames: s.frames.len(),
        })
        .collect();
    let mut sequences = Vec::with_capacity(seqs.len());
    for mut s in seqs {
        let origin = s.origin.clone();
        // A sequence's frames keep texture coordinates all or none (the `.frames` folder holds
        // them in one array per sequence): a mix loses them, with a note.
        let with_uv = s.frames.iter().filter(|(t, _)| t.uv().is_some()).count();
        if with_uv > 0 && with_uv < s.frames.len() {
            notes.push(format!(
                "sequence {:?}: only {with_uv} of its {} frames have texture coordinates: dropped from all of them",
                s.name,
                s.frames.len()
            ));
            for (t, _) in &mut s.frames {
                *t = Topology::new(t.n_vertices(), t.triangles().to_vec(), None)?;
            }
        }
        let mut seq =
            FrameSetSequence::from_frames(s.name, s.frames).map_err(|e| e.in_file(&origin))?.with_tags(s.tags);
        if let Some(l) = s.labels {
            seq = seq.with_labels(l).map_err(|e| e.in_file(&origin))?;
        }
        sequences.push(seq);
    }
    let name = opts.name.clone().unwrap_or_else(|| default_name.to_string());
    let frame_set = FrameSet::new(name, sequences, fps, up_axis, units)?;
    Ok(ImportedFrames { frame_set, notes, sources, frame_set_origin: None })
}

/// A subject's sequences as sources (to merge a cache with more data).
fn sequences_of(s: &Subject, origin: &Path) -> Vec<SourceSequence> {
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

/// Opens a subject: a cache written by `surfcap import` (fast), or any importable source. A frame
/// set (a `.frames` folder, or a source that imports as one) is refused with
/// [`frame_set_refusal`], unless every one of its frames happens to share one topology (a
/// subject written with `--as-frame-set`), which is then used as that subject, with a note.
pub fn open_subject(path: &Path, opts: &ImportOptions, progress: &dyn Progress) -> Result<Imported> {
    if cache::is_cache(path) {
        return open_cache(path, opts, progress);
    }
    match open_any(path, opts, progress)? {
        ImportedData::Subject(i) => Ok(i),
        ImportedData::FrameSet(f) => {
            let frames = f.frame_set.frame_count();
            if f.frame_set.first_topology_difference().is_none() {
                let mut notes = f.notes;
                notes.push(format!(
                    "{} is a frame set whose {} frames all share one topology: used as a subject",
                    path.display(),
                    thousands(frames)
                ));
                let subject = f.frame_set.into_subject().map_err(|e| e.in_file(path))?;
                return Ok(Imported { subject, notes, sources: f.sources });
            }
            let origin = f.frame_set_origin.unwrap_or_else(|| path.to_path_buf());
            Err(frame_set_refusal(&origin, frames))
        }
    }
}

/// A subject cache, with the user's overrides of fps, up axis and units.
fn open_cache(path: &Path, opts: &ImportOptions, progress: &dyn Progress) -> Result<Imported> {
    let mut subject = cache::read_cache(path, progress)?;
    if let Some(f) = opts.fps {
        subject.fps = f;
    }
    if let Some(u) = opts.up_axis {
        subject.up_axis = u;
    }
    if let Some(u) = &opts.units {
        subject.units = u.clone();
    }
    let sources = sequences_of(&subject, path)
        .into_iter()
        .map(|s| ImportedSource {
            frames: s.positions.len() / (3 * subject.topology().n_vertices()).max(1),
            sequence: s.name,
            origin: s.origin,
            layout: s.layout,
        })
        .collect();
    Ok(Imported { subject, notes: Vec::new(), sources })
}

/// Opens a subject or a frame set: a subject cache or a `.frames` folder written by `surfcap
/// import` (fast, with the user's overrides of fps, up axis and units), or any importable
/// source ([`import_any`]).
pub fn open_any(path: &Path, opts: &ImportOptions, progress: &dyn Progress) -> Result<ImportedData> {
    if cache::is_cache(path) {
        return Ok(ImportedData::Subject(open_cache(path, opts, progress)?));
    }
    if frame_set_cache::is_frame_set(path) {
        let mut set = frame_set_cache::read_frame_set(path, progress)?;
        if let Some(f) = opts.fps {
            set.fps = f;
        }
        if let Some(u) = opts.up_axis {
            set.up_axis = u;
        }
        if let Some(u) = &opts.units {
            set.units = u.clone();
        }
        let sources = set
            .sequences()
            .iter()
            .map(|s| ImportedSource {
                sequence: s.name.clone(),
                origin: path.to_path_buf(),
                layout: SourceLayout::FrameSetFolder,
                frames: s.n_frames(),
            })
            .collect();
        return Ok(ImportedData::FrameSet(ImportedFrames {
            frame_set: set,
            notes: Vec::new(),
            sources,
            frame_set_origin: Some(path.to_path_buf()),
        }));
    }
    import_any(&[path.to_path_buf()], opts, progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

    fn mkfifo(p: &Path) {
        assert!(std::process::Command::new("mkfifo").arg(p).status().unwrap().success());
    }

    /// Issue 15 case 11: a lone template.obj is read as one OBJ frame and says so; a
    /// positions.npy that is a FIFO, folder or socket is refused by name (and never opened, so
    /// nothing blocks).
    #[test]
    fn the_detected_layout_is_reported_and_non_regular_positions_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let seq = d.path().join("walk");
        std::fs::create_dir(&seq).unwrap();
        std::fs::write(seq.join("template.obj"), TETRA).unwrap();
        let s = read_source(&seq, &NoProgress).unwrap();
        let lone = SourceLayout::FrameFolder { format: FrameFormat::Obj, files: 1, lone_template: true };
        assert_eq!(s[0].layout, lone);
        assert_eq!(
            lone.to_string(),
            "folder of 1 OBJ frame file (template.obj with no positions.npy beside it: read as one frame)"
        );
        let imported =
            import(std::slice::from_ref(&seq), &ImportOptions { fps: Some(30.0), ..Default::default() }, &NoProgress)
                .unwrap();
        assert_eq!(imported.sources.len(), 1);
        assert_eq!((imported.sources[0].layout.clone(), imported.sources[0].frames), (lone, 1));

        let positions = seq.join("positions.npy");
        mkfifo(&positions);
        for dir in [seq.clone(), d.path().to_path_buf()] {
            let e = read_source(&dir, &NoProgress).unwrap_err();
            assert_eq!(
                e.to_string(),
                format!("{}: is a FIFO (named pipe): expected a regular file", positions.display())
            );
        }
        std::fs::remove_file(&positions).unwrap();
        std::fs::create_dir(&positions).unwrap();
        let e = read_source(&seq, &NoProgress).unwrap_err().to_string();
        assert_eq!(e, format!("{}: is a directory: expected a regular file", positions.display()));
        std::fs::remove_dir(&positions).unwrap();

        let mut npy = Vec::new();
        crate::io::npy::write_npy(&mut npy, &[2, 4, 3], &[0.0f32; 24]).unwrap();
        std::fs::write(&positions, npy).unwrap();
        let s = read_source(&seq, &NoProgress).unwrap();
        assert_eq!(s[0].layout, SourceLayout::TemplatePositions);
        assert_eq!(s[0].layout.to_string(), "sequence folder (template.obj + positions.npy)");
    }

    /// The optional files (`joints.npy`, a folder's `surfcap.toml`) are refused by name when
    /// something that is not a regular file has their name, instead of being silently ignored.
    #[test]
    fn optional_files_that_are_not_regular_files_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let seq = d.path().join("walk");
        std::fs::create_dir(&seq).unwrap();
        std::fs::write(seq.join("template.obj"), TETRA).unwrap();
        let mut npy = Vec::new();
        crate::io::npy::write_npy(&mut npy, &[2, 4, 3], &[0.0f32; 24]).unwrap();
        std::fs::write(seq.join("positions.npy"), npy).unwrap();
        let joints = seq.join("joints.npy");
        mkfifo(&joints);
        let e = read_source(&seq, &NoProgress).unwrap_err().to_string();
        assert_eq!(e, format!("{}: is a FIFO (named pipe): expected a regular file", joints.display()));
        std::fs::remove_file(&joints).unwrap();
        assert!(read_source(&seq, &NoProgress).is_ok());
        let manifest = seq.join("surfcap.toml");
        mkfifo(&manifest);
        let opts = ImportOptions { fps: Some(30.0), ..Default::default() };
        let e = import(std::slice::from_ref(&seq), &opts, &NoProgress).unwrap_err().to_string();
        assert_eq!(e, format!("{}: is a FIFO (named pipe): expected a regular file", manifest.display()));
    }

    /// Issue 17 item 1: a folder of frames whose connectivity differs imports as a frame set
    /// (with the note), and the commands that need one topology say what it is.
    #[test]
    fn a_folder_of_frames_with_different_topologies_is_a_frame_set() {
        const SPLIT: &str =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.5 0.5 0\nf 1 3 5\nf 1 5 2\nf 1 2 4\nf 2 5 4\nf 5 3 4\nf 1 4 3\n";
        let d = tempfile::tempdir().unwrap();
        let dir = d.path().join("capture");
        std::fs::create_dir(&dir).unwrap();
        for (k, text) in [TETRA, TETRA, TETRA, SPLIT].iter().enumerate() {
            std::fs::write(dir.join(format!("f_{k}.obj")), text).unwrap();
        }
        let opts = ImportOptions { fps: Some(25.0), ..Default::default() };
        let ImportedData::FrameSet(f) = import_any(std::slice::from_ref(&dir), &opts, &NoProgress).unwrap() else {
            panic!("expected a frame set");
        };
        assert_eq!(f.frame_set.frame_count(), 4);
        assert_eq!(f.frame_set.vertex_count_range(), (4, 5));
        assert_eq!(f.frame_set.frame(3).unwrap().positions()[12..], [0.5, 0.5, 0.0]);
        assert_eq!(
            f.notes[0],
            format!(
                "frames of {} have different vertices/triangles (frame 3: 5 vertices, frame 0: 4): imported as a \
                 frame set; commands that need one topology cannot use it",
                dir.display()
            )
        );
        assert_eq!(f.sources[0].frames, 4);
        let refusal = format!(
            "{}: is a frame set (every frame has its own vertices and triangles; 4 frames): this command needs one shared topology",
            dir.display()
        );
        for e in [
            open_subject(&dir, &opts, &NoProgress).unwrap_err(),
            import(std::slice::from_ref(&dir), &opts, &NoProgress).unwrap_err(),
        ] {
            assert_eq!(e.kind, ErrorKind::TopologyMismatch);
            assert!(e.to_string().starts_with(&refusal), "{e}");
            assert!(
                e.to_string().ends_with("Frame sets are for Huang et al.'s surface motion graph (`surfcap smg`)"),
                "{e}"
            );
        }
        // Its .frames folder opens as a frame set and is refused as a subject likewise.
        let out = d.path().join("x.frames");
        frame_set_cache::write_frame_set(&out, &f.frame_set, false, &NoProgress).unwrap();
        let ImportedData::FrameSet(back) = open_any(&out, &ImportOptions::default(), &NoProgress).unwrap() else {
            panic!("expected a frame set");
        };
        assert_eq!(back.frame_set, f.frame_set);
        let e = open_subject(&out, &opts, &NoProgress).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: is a frame set (", out.display())), "{e}");
        // A frame set whose frames share one topology is that subject.
        std::fs::write(dir.join("f_3.obj"), TETRA).unwrap();
        let subject = open_subject(&dir, &opts, &NoProgress).unwrap().subject;
        let shared = d.path().join("shared.frames");
        frame_set_cache::write_frame_set(&shared, &FrameSet::from_subject(&subject), false, &NoProgress).unwrap();
        let again = open_subject(&shared, &opts, &NoProgress).unwrap();
        assert_eq!(again.subject, subject);
        assert!(again.notes[0].ends_with("frames all share one topology: used as a subject"), "{:?}", again.notes);
        // Triangles that differ with the same counts are named as such.
        std::fs::write(dir.join("f_2.obj"), TETRA.replace("f 1 3 2\nf 1 2 4", "f 1 2 4\nf 1 3 2")).unwrap();
        let ImportedData::FrameSet(f) = open_any(&dir, &opts, &NoProgress).unwrap() else { panic!() };
        assert!(
            f.notes[0].contains("(frame 2: the same 4 vertices and 4 triangles as frame 0, connected differently)")
        );
        // Texture coordinates on some frames only are dropped from all, with a note.
        let textured = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 3/3 2/2\nf 1/1 2/2 4/3\nf 2/2 3/3 4/1\nf 1/1 4/3 3/2\n";
        std::fs::write(dir.join("f_0.obj"), textured).unwrap();
        let ImportedData::FrameSet(f) = open_any(&dir, &opts, &NoProgress).unwrap() else { panic!() };
        let note = "sequence \"capture\": only 1 of its 4 frames have texture coordinates: dropped from all of them";
        assert!(f.notes.iter().any(|n| n == note), "{:?}", f.notes);
        assert!(f.notes[0].contains("(frame 2: the same 4 vertices"), "{:?}", f.notes);
        assert!(!f.frame_set.sequences()[0].has_uv());
    }

    /// A FIFO named like a frame is an error when the folder is read, not a hang or a frame
    /// silently left out.
    #[test]
    fn a_fifo_among_frame_files_is_refused() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("f_0.obj"), TETRA).unwrap();
        mkfifo(&d.path().join("f_1.obj"));
        let e = read_source(d.path(), &NoProgress).unwrap_err().to_string();
        assert!(e.ends_with("f_1.obj: frame 1: is a FIFO (named pipe): expected a regular file"), "{e}");
    }
}
