//! Turning files on disk into a [`Subject`]: detect what a path holds, read its sequences, and
//! merge them into one subject with one topology, one frame rate, one up axis and one unit,
//! named by `--name` or after what its sources share (`subject_name.rs`).
//!
//! Or into a [`FrameSet`] (Huang et al. 2009 work on per-frame reconstructions whose vertices and
//! triangles differ from frame to frame): a folder of OBJ/PLY frames whose
//! connectivity differs between frames, or a `.frames` folder. [`open_any`] and [`import_any`]
//! return either kind ([`ImportedData`]); [`open_subject`] and [`import`], for the commands that
//! need one topology, refuse a frame set with a message saying what it is and where frame sets
//! are used ([`frame_set_refusal`]). A frame folder is first read as one topology (the fast,
//! usual case); only when that fails because a frame's vertices or triangles differ is it read
//! again frame by frame, so subjects cost what they did.

//!
//! The work is split by what it does: `sources.rs` reads what one path holds, `merge.rs` merges
//! the sequences into a subject or a frame set, `open.rs` reads the caches directly; this file
//! holds the types they share and the two entry points, [`import`] and [`import_any`].

use std::path::{Path, PathBuf};

use surfcap_mesh::cache;
use surfcap_mesh::error::{Error, Result, err};
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::frame_set_cache;
use surfcap_mesh::progress::Progress;
use surfcap_mesh::subject::{FrameLabel, JointTrack, Subject, Units, UpAxis};
use surfcap_mesh::topology::Topology;

use crate::frame_folder::FrameFormat;
use crate::manifest;

mod merge;
mod open;
mod sources;
mod subject_name;

pub use merge::assemble;
use merge::assemble_frames;
pub use open::{open_any, open_subject};
pub use sources::read_source;
use sources::{Piece, SourceFrames, frame_set_pieces, read_source_any, sequences_of};
pub use subject_name::{NameFrom, default_subject_name};

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
    /// A USD stage (`.usda`, `.usd` or `.usdc`, text or binary crate): one sequence per `Mesh` prim.
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
            SourceLayout::Usda => write!(f, "USD stage"),
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

pub(super) fn file_stem(p: &Path) -> String {
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
pub(super) fn thousands(n: usize) -> String {
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

/// Imports any mix of sources into a subject when they share one topology (as [`import`]), or
/// into a frame set when one of them is a frame set (a `.frames` folder, or a folder of frames
/// whose vertices or triangles differ between frames); the other sources' frames then join it
/// as frames of their own.
pub fn import_any(paths: &[PathBuf], opts: &ImportOptions, progress: &dyn Progress) -> Result<ImportedData> {
    let mut pieces = Vec::new();
    let mut opts = opts.clone();
    let mut notes = Vec::new();
    // What the sources share (a manifest's or a cache's own name below wins).
    let mut default_name = default_subject_name(paths).0;
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

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::ErrorKind;
    use surfcap_mesh::progress::NoProgress;

    const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

    fn mkfifo(p: &Path) {
        assert!(std::process::Command::new("mkfifo").arg(p).status().unwrap().success());
    }

    /// A lone template.obj is read as one OBJ frame and says so; a
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
        surfcap_mesh::npy::write_npy(&mut npy, &[2, 4, 3], &[0.0f32; 24]).unwrap();
        std::fs::write(&positions, npy).unwrap();
        let s = read_source(&seq, &NoProgress).unwrap();
        assert_eq!(s[0].layout, SourceLayout::TemplatePositions);
        assert_eq!(s[0].layout.to_string(), "sequence folder (template.obj + positions.npy)");
    }

    /// The optional files (`joints.npy`, a folder's `surfcap.toml`) are refused by name when
    /// something that is not a regular file has their name, instead of being silently ignored.
    /// Two sources whose sequences share a name: the error names both files (it said only
    /// "two sequences are named").
    #[test]
    fn a_repeated_sequence_name_names_both_files() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("b")).unwrap();
        let (a, b) = (d.path().join("walk.obj"), d.path().join("b/walk.obj"));
        std::fs::write(&a, TETRA).unwrap();
        std::fs::write(&b, TETRA).unwrap();
        let opts = ImportOptions { fps: Some(30.0), ..Default::default() };
        let e = import_any(&[a.clone(), b.clone()], &opts, &NoProgress).err().unwrap().to_string();
        assert_eq!(
            e,
            format!(
                "{}: a sequence of this file and one of {} are both named \"walk\": expected unique sequence names \
                 (rename one, e.g. with a `name = ...` in surfcap.toml)",
                b.display(),
                a.display()
            )
        );
    }

    #[test]
    fn optional_files_that_are_not_regular_files_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let seq = d.path().join("walk");
        std::fs::create_dir(&seq).unwrap();
        std::fs::write(seq.join("template.obj"), TETRA).unwrap();
        let mut npy = Vec::new();
        surfcap_mesh::npy::write_npy(&mut npy, &[2, 4, 3], &[0.0f32; 24]).unwrap();
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

    /// A folder of frames whose connectivity differs imports as a frame set
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
