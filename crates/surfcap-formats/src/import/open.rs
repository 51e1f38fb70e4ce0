//! Opening a subject or a frame set for a command: the caches `surfcap import` writes are read
//! directly (fast, with the user's overrides of fps, up axis and units), anything else is
//! imported.

use std::path::Path;

use surfcap_mesh::error::Result;
use surfcap_mesh::progress::Progress;
use surfcap_mesh::subject::{Units, UpAxis};
use surfcap_mesh::{cache, frame_set_cache};

use super::sources::sequences_of;
use super::{
    ImportOptions, Imported, ImportedData, ImportedFrames, ImportedSource, SourceLayout, frame_set_refusal, import_any,
    thousands,
};

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
    override_metadata(opts, &mut subject.fps, &mut subject.up_axis, &mut subject.units)?;
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
        override_metadata(opts, &mut set.fps, &mut set.up_axis, &mut set.units)?;
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

/// The user's fps, up axis and units, where given, over those a cache recorded.
/// The frame rate given is checked against the accepted range, as any frame rate a subject gets.
fn override_metadata(opts: &ImportOptions, fps: &mut f64, up_axis: &mut UpAxis, units: &mut Units) -> Result<()> {
    if let Some(f) = opts.fps {
        *fps = surfcap_mesh::subject::check_frame_rate(f)?;
    }
    if let Some(u) = opts.up_axis {
        *up_axis = u;
    }
    if let Some(u) = &opts.units {
        *units = u.clone();
    }
    Ok(())
}
