//! Turning files on disk into a [`Subject`]: detect what a path holds, read its sequences, and
//! merge them into one subject with one topology, one frame rate, one up axis and one unit.

use std::path::{Path, PathBuf};

use crate::cache;
use crate::error::{Result, err};
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
        "usda" | "usd" | "usdc" => {
            // `.usd` may hold text or the binary crate format; the reader refuses the latter with
            // the command that converts it.
            let stage = crate::io::usda_read::read_usda(path)?;
            for n in &stage.notes {
                progress.note(&format!("{}: {n}", path.display()));
            }
            Ok(stage
                .meshes
                .into_iter()
                .map(|m| SourceSequence {
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
                })
                .collect())
        }
        "abc" => {
            let archive = crate::io::abc_read::read_abc(path)?;
            for n in &archive.notes {
                progress.note(&format!("{}: {n}", path.display()));
            }
            let mut out = Vec::with_capacity(archive.meshes.len());
            for m in archive.meshes {
                // A mesh whose topology changes between samples is a frame set, not a sequence.
                if let Some((frame, faces, was)) = m.topology_change() {
                    return Err(err!(
                        Unsupported,
                        "{}: the topology changes at frame {frame} ({faces} faces, was {was}): a varying-topology mesh imports as a frame set",
                        m.path
                    )
                    .in_file(path));
                }
                let (topology, positions) = match m.frames {
                    crate::io::abc_read::AbcFrames::Constant { topology, positions } => (topology, positions),
                    // Stored as varying but every frame has the same topology: one after all.
                    crate::io::abc_read::AbcFrames::Varying { frames } => {
                        let Some(first) = frames.first() else { continue };
                        let positions = frames.iter().flat_map(|f| f.positions.iter().copied()).collect();
                        (first.topology.clone(), positions)
                    }
                };
                out.push(SourceSequence {
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
                });
            }
            Ok(out)
        }
        _ => Err(err!(
            Unsupported,
            "unknown file type {ext:?}: expected .obj, .ply, .glb, .usda, .abc, surfcap.toml or a folder (a .pc2 or .npy needs a template: list it in surfcap.toml)"
        )
        .in_file(path)),
    }
}

/// Agreement of an optional per-source value: the user's value wins; otherwise all sources
/// that know it must agree.
fn agree<T: Clone + PartialEq + std::fmt::Debug>(
    what: &str,
    user: Option<T>,
    seqs: &[SourceSequence],
    get: impl Fn(&SourceSequence) -> Option<T>,
) -> Result<Option<T>> {
    if user.is_some() {
        return Ok(user);
    }
    let mut found: Option<(T, &Path)> = None;
    for s in seqs {
        if let Some(v) = get(s) {
            match &found {
                None => found = Some((v, &s.origin)),
                Some((w, origin)) if *w != v => {
                    return Err(err!(
                        Metadata,
                        "{what} {v:?} differs from {w:?} of {}: give it explicitly to merge them",
                        origin.display()
                    )
                    .in_file(&s.origin));
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
    let fps = agree("frame rate", opts.fps, &seqs, |s| s.fps)?.ok_or_else(|| {
        err!(Metadata, "no frame rate is known for these sequences: pass --fps (or set fps in surfcap.toml)")
            .in_file(&first.origin)
    })?;
    let up_axis = match agree("up axis", opts.up_axis, &seqs, |s| s.up_axis)? {
        Some(u) => u,
        None => {
            notes.push("no up axis in the sources: assumed +y (pass --up-axis to change it)".into());
            UpAxis::PosY
        }
    };
    let units = match agree("units", opts.units.clone(), &seqs, |s| s.units.clone())? {
        Some(u) => u,
        None => {
            notes.push("no units in the sources: recorded as arbitrary (pass --units to set them)".into());
            Units::arbitrary()
        }
    };
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

/// Imports any mix of sources (manifests included) into one subject.
pub fn import(paths: &[PathBuf], opts: &ImportOptions, progress: &dyn Progress) -> Result<Imported> {
    let mut seqs = Vec::new();
    let mut opts = opts.clone();
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
            seqs.extend(m_seqs);
        } else if cache::is_cache(p) {
            let s = cache::read_cache(p, progress)?;
            default_name = s.name.clone();
            seqs.extend(sequences_of(&s, p));
        } else {
            seqs.extend(read_source(p, progress)?);
        }
    }
    assemble(&default_name, seqs, &opts)
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

/// Opens a subject: a cache written by `surfcap import` (fast), or any importable source.
pub fn open_subject(path: &Path, opts: &ImportOptions, progress: &dyn Progress) -> Result<Imported> {
    if cache::is_cache(path) {
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
        return Ok(Imported { subject, notes: Vec::new(), sources });
    }
    import(&[path.to_path_buf()], opts, progress)
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
