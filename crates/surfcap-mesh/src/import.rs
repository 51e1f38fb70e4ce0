//! Turning files on disk into a [`Subject`]: detect what a path holds, read its sequences, and
//! merge them into one subject with one topology, one frame rate, one up axis and one unit.

use std::path::{Path, PathBuf};

use crate::cache;
use crate::error::{Error, Result, err};
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
}

fn file_stem(p: &Path) -> String {
    let p =
        if p.file_name().is_none() { p.canonicalize().unwrap_or_else(|_| p.to_path_buf()) } else { p.to_path_buf() };
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "subject".into())
}

/// A sequence with nothing known but its geometry (no joints, tags, labels or metadata).
pub(crate) fn simple(name: String, topology: Topology, positions: Vec<f32>, origin: &Path) -> SourceSequence {
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
    }
}

/// Reads every sequence a path holds: a shared-layout sequence folder, a dataset folder of them,
/// a folder of OBJ or PLY frames, a single `.obj`/`.ply` (one frame) or a `.glb`.
/// (Manifests and subject caches are whole subjects: see [`import`] and [`open_subject`].)
pub fn read_source(path: &Path, progress: &dyn Progress) -> Result<Vec<SourceSequence>> {
    if !path.exists() {
        return Err(err!(Io, "no such file or folder").in_file(path));
    }
    if path.is_dir() {
        if is_layout_sequence(path) {
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
            if !list_frames(path, format)?.is_empty() {
                let (topology, positions) = read_frame_folder(path, format, progress)?;
                return Ok(vec![simple(file_stem(path), topology, positions, path)]);
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
            Ok(vec![simple(file_stem(path), t, m.positions, path)])
        }
        "ply" => {
            let m = crate::io::ply::read_ply(path)?;
            let t = m.topology().map_err(|e| e.in_file(path))?;
            Ok(vec![simple(file_stem(path), t, m.positions, path)])
        }
        "glb" => {
            let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
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
                })
                .collect())
        }
        _ => Err(err!(
            Unsupported,
            "unknown file type {ext:?}: expected .obj, .ply, .glb, surfcap.toml or a folder (a .pc2 or .npy needs a template: list it in surfcap.toml)"
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
    Ok(Imported { subject, notes })
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
        return Ok(Imported { subject, notes: Vec::new() });
    }
    import(&[path.to_path_buf()], opts, progress)
}
