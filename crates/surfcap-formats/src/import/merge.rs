//! Merging the sequences read from every source into one subject ([`assemble`]: one topology) or
//! one frame set ([`assemble_frames`]: each frame its own), with the frame rate, up axis and
//! units the sources agree on (the user's values first; a missing axis or unit assumed with a
//! note).

use std::path::Path;

use surfcap_mesh::error::{Result, err};
use surfcap_mesh::frame_set::{FrameSet, FrameSetSequence};
use surfcap_mesh::subject::{Sequence, Subject, Units, UpAxis};
use surfcap_mesh::topology::Topology;

use super::sources::SourceFrames;
use super::{ImportOptions, Imported, ImportedFrames, ImportedSource, SourceSequence};

/// Something read from a source file or folder.
trait HasOrigin {
    fn origin(&self) -> &Path;
}

impl HasOrigin for SourceSequence {
    fn origin(&self) -> &Path {
        &self.origin
    }
}

impl HasOrigin for SourceFrames {
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

/// Sequence names non-empty and unique, an error naming the file (or files) they came from: two
/// sources, or one file (a USD stage, a glb, an Alembic archive) holding two alike.
fn unique_names<'a>(named: impl Iterator<Item = (&'a str, &'a Path)>) -> Result<()> {
    let mut seen: Vec<(&str, &Path)> = Vec::new();
    for (name, origin) in named {
        if name.is_empty() {
            return Err(err!(Metadata, "a sequence has an empty name: expected a non-empty name").in_file(origin));
        }
        if let Some((_, first)) = seen.iter().find(|(n, _)| *n == name) {
            let also = if *first == origin {
                "two sequences of this file".to_string()
            } else {
                format!("a sequence of this file and one of {}", first.display())
            };
            return Err(err!(
                Metadata,
                "{also} are both named {name:?}: expected unique sequence names (rename one, e.g. with a \
                 `name = ...` in surfcap.toml)"
            )
            .in_file(origin));
        }
        seen.push((name, origin));
    }
    Ok(())
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
    unique_names(seqs.iter().map(|s| (s.name.as_str(), s.origin.as_path())))?;
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

/// Merges frame sequences into one frame set: frame rate, up axis and units agree as for
/// [`assemble`]; each frame keeps its own topology.
pub(super) fn assemble_frames(
    default_name: &str,
    seqs: Vec<SourceFrames>,
    opts: &ImportOptions,
) -> Result<ImportedFrames> {
    if seqs.is_empty() {
        return Err(err!(Empty, "nothing to import: no sequences were found"));
    }
    unique_names(seqs.iter().map(|s| (s.name.as_str(), s.origin.as_path())))?;
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
