//! Round trips through the interchange formats: every sequence
//! of a data folder laid out as `../shared/data` is imported as its own subject, exported as
//! `.abc` and `.usda`, and imported back; the evaluation says for each whether everything came
//! back exactly (positions to the bit in f32, topology with its UVs, sequence names, frame labels,
//! frame rate, up axis, units) and otherwise names the first difference, with the file size and
//! the write and read times.
//!
//! A dataset folder's sequences are its `<sequence>/template.obj + positions.npy` folders (the
//! dataset's `meta.json` gives their rate, axis and units, as `surfcap import` reads them); a
//! dataset with a lone `template.obj` and no sequences (the head scan) is one frame, so its UV
//! atlas goes through the formats too. Sources without a frame rate (pose sets, the lone mesh)
//! get [`InterchangeOptions::default_fps`], said in the round trip's `assumed_fps`. Folders
//! without either (skeleton-only BVH data) are listed as skipped, with the reason.
//!
//! Unlike the other evaluations this one writes and reads files: that is what it measures. It
//! writes only inside [`InterchangeOptions::scratch`], one file at a time, removed once read.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use surfcap_formats::export::{ExportFormat, ExportOptions, export};
use surfcap_formats::import::{ImportOptions, import};
use surfcap_formats::shared_layout::dataset_sequences;
use surfcap_mesh::{Progress, Subject};

use crate::error::{Error, Result};

/// Options of [`interchange_eval`] (`surfcap eval interchange`).
#[derive(Debug, Clone)]
pub struct InterchangeOptions {
    /// The data folder (datasets as sub-folders).
    pub data: PathBuf,
    /// Only these datasets (folder names); empty: all.
    pub datasets: Vec<String>,
    /// The formats to go through (`Abc`, `Usda`, or any other single-file format).
    pub formats: Vec<ExportFormat>,
    /// Where the exported files go while they are checked.
    pub scratch: PathBuf,
    /// The rate given to sources that have none (pose sets, a lone mesh).
    pub default_fps: f64,
}

/// One sequence through one format.
#[derive(Debug, Clone, Serialize)]
pub struct RoundTrip {
    pub dataset: String,
    pub sequence: String,
    pub format: String,
    pub frames: usize,
    pub vertices: usize,
    pub triangles: usize,
    pub uv: bool,
    /// The rate given to a source that had none.
    pub assumed_fps: Option<f64>,
    pub bytes: u64,
    pub write_seconds: f64,
    pub read_seconds: f64,
    /// Everything came back as it was.
    pub exact: bool,
    /// The first difference found, when not exact.
    pub difference: Option<String>,
}

/// A dataset folder that holds nothing to round-trip, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Skipped {
    pub dataset: String,
    pub reason: String,
}

/// The result of [`interchange_eval`].
#[derive(Debug, Clone, Serialize)]
pub struct InterchangeEval {
    pub formats: Vec<String>,
    pub sequences: usize,
    pub frames: usize,
    pub round_trips: Vec<RoundTrip>,
    /// Round trips that were not exact.
    pub not_exact: usize,
    pub skipped: Vec<Skipped>,
}

fn format_name(f: ExportFormat) -> Result<&'static str> {
    Ok(match f {
        ExportFormat::Abc => "abc",
        ExportFormat::Usda => "usda",
        ExportFormat::Usdc => "usdc",
        ExportFormat::Glb => "glb",
        other => {
            return Err(Error::parameter(
                "--formats",
                Some(format!("{other:?}").to_lowercase()),
                "expected single-file formats: abc, usda, usdc or glb",
            ));
        }
    })
}

/// The first way `b` differs from `a`, or `None` when it is the same subject.
pub fn first_difference(a: &Subject, b: &Subject) -> Option<String> {
    if let Some(d) = a.topology().first_difference(b.topology()) {
        return Some(format!("topology: {d}"));
    }
    if a.topology().uv() != b.topology().uv() {
        return Some("the UV atlas differs".into());
    }
    if a.fps.to_bits() != b.fps.to_bits() {
        return Some(format!("frame rate {} came back as {}", a.fps, b.fps));
    }
    if a.up_axis != b.up_axis {
        return Some(format!("up axis {} came back as {}", a.up_axis.as_str(), b.up_axis.as_str()));
    }
    if a.units != b.units {
        return Some(format!("units {:?} came back as {:?}", a.units, b.units));
    }
    if a.sequences().len() != b.sequences().len() {
        return Some(format!("{} sequences came back as {}", a.sequences().len(), b.sequences().len()));
    }
    for (s, t) in a.sequences().iter().zip(b.sequences()) {
        if s.name != t.name {
            return Some(format!("sequence {:?} came back named {:?}", s.name, t.name));
        }
        if s.n_frames() != t.n_frames() {
            return Some(format!("{}: {} frames came back as {}", s.name, s.n_frames(), t.n_frames()));
        }
        for f in 0..s.n_frames() {
            let (p, q) = (s.frame(f), t.frame(f));
            if let Some(i) = p.iter().zip(q).position(|(x, y)| x.to_bits() != y.to_bits()) {
                return Some(format!(
                    "{}:{f}: vertex {} coordinate {} is {} instead of {}",
                    s.name,
                    i / 3,
                    i % 3,
                    q[i],
                    p[i]
                ));
            }
        }
        if s.labels != t.labels {
            return Some(format!("{}: the frame labels differ", s.name));
        }
    }
    None
}

/// Exports `subject` as `format` into `scratch`, imports it back and compares.
fn round_trip(
    subject: &Subject,
    dataset: &str,
    assumed_fps: Option<f64>,
    format: ExportFormat,
    scratch: &Path,
) -> Result<RoundTrip> {
    let ext = format_name(format)?;
    let file = scratch.join(format!("roundtrip.{ext}"));
    let t0 = Instant::now();
    let written = export(subject, format, &file, ExportOptions::default(), &surfcap_mesh::NoProgress)?;
    let write_seconds = t0.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0);
    let t0 = Instant::now();
    let back = import(std::slice::from_ref(&file), &ImportOptions::default(), &surfcap_mesh::NoProgress);
    let read_seconds = t0.elapsed().as_secs_f64();
    for w in &written {
        // Only what the export just wrote, inside the scratch folder.
        let _ = std::fs::remove_file(w);
    }
    let difference = match back {
        Ok(b) => first_difference(subject, &b.subject),
        Err(e) => Some(format!("reading it back failed: {e}")),
    };
    Ok(RoundTrip {
        dataset: dataset.into(),
        sequence: subject.sequences().first().map(|s| s.name.clone()).unwrap_or_default(),
        format: ext.into(),
        frames: subject.n_frames(),
        vertices: subject.topology().n_vertices(),
        triangles: subject.topology().n_triangles(),
        uv: subject.topology().uv().is_some(),
        assumed_fps,
        bytes,
        write_seconds,
        read_seconds,
        exact: difference.is_none(),
        difference,
    })
}

/// Runs the round trips (see the module documentation).
pub fn interchange_eval(opts: &InterchangeOptions, progress: &dyn Progress) -> Result<InterchangeEval> {
    if opts.formats.is_empty() {
        return Err(Error::parameter("--formats", None, "expected at least one format"));
    }
    let formats = opts.formats.iter().map(|&f| format_name(f).map(String::from)).collect::<Result<Vec<_>>>()?;
    let mut datasets = Vec::new();
    let entries =
        std::fs::read_dir(&opts.data).map_err(|e| surfcap_mesh::Error::io(&opts.data, "list the data folder", e))?;
    for e in entries {
        let p = e.map_err(|e| surfcap_mesh::Error::io(&opts.data, "list the data folder", e))?.path();
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if p.is_dir() && (opts.datasets.is_empty() || opts.datasets.contains(&name)) {
            datasets.push((name, p));
        }
    }
    for want in &opts.datasets {
        if !datasets.iter().any(|(n, _)| n == want) {
            return Err(Error::parameter(
                "--datasets",
                Some(want.clone()),
                format!("no such folder in {}", opts.data.display()),
            ));
        }
    }
    datasets.sort();
    // The sources: each sequence folder, or a dataset's lone template.obj.
    let mut sources: Vec<(String, PathBuf)> = Vec::new();
    let mut skipped = Vec::new();
    for (name, dir) in &datasets {
        let seqs = dataset_sequences(dir)?;
        if !seqs.is_empty() {
            sources.extend(seqs.into_iter().map(|s| (name.clone(), s)));
        } else if dir.join("template.obj").is_file() {
            sources.push((name.clone(), dir.join("template.obj")));
        } else {
            skipped.push(Skipped {
                dataset: name.clone(),
                reason: "no mesh sequences (template.obj + positions.npy) and no lone template.obj".into(),
            });
        }
    }
    progress.start("round trips", (sources.len() * formats.len()) as u64);
    let mut round_trips = Vec::new();
    let mut frames = 0;
    for (dataset, path) in &sources {
        let source = std::slice::from_ref(path);
        let (subject, assumed_fps) = match import(source, &ImportOptions::default(), &surfcap_mesh::NoProgress) {
            Ok(i) => (i.subject, None),
            // Only a missing frame rate is supplied; any other error is the data's.
            Err(e) if e.kind == surfcap_mesh::ErrorKind::Metadata && e.to_string().contains("no frame rate") => {
                let with = ImportOptions { fps: Some(opts.default_fps), ..Default::default() };
                (import(source, &with, &surfcap_mesh::NoProgress)?.subject, Some(opts.default_fps))
            }
            Err(e) => return Err(e.into()),
        };
        frames += subject.n_frames();
        for &f in &opts.formats {
            round_trips.push(round_trip(&subject, dataset, assumed_fps, f, &opts.scratch)?);
            progress.advance(1);
        }
    }
    progress.finish();
    let not_exact = round_trips.iter().filter(|r| !r.exact).count();
    Ok(InterchangeEval { formats, sequences: sources.len(), frames, round_trips, not_exact, skipped })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{Sequence, Topology, Units, UpAxis};

    fn subject(z: f32) -> Subject {
        let topo = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let p = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, z];
        Subject::new("t", topo, vec![Sequence::new("s", 4, p).unwrap()], 30.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    #[test]
    fn the_first_difference_names_the_frame_and_vertex() {
        assert_eq!(first_difference(&subject(1.0), &subject(1.0)), None);
        let d = first_difference(&subject(1.0), &subject(1.5)).unwrap();
        assert_eq!(d, "s:0: vertex 3 coordinate 2 is 1.5 instead of 1");
    }

    #[test]
    fn a_tiny_subject_round_trips_through_usda() {
        let d = tempfile::tempdir().unwrap();
        let r = round_trip(&subject(1.0), "tiny", None, ExportFormat::Usda, d.path()).unwrap();
        assert!(r.exact, "{:?}", r.difference);
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0, "the scratch files are removed");
        let e = format_name(ExportFormat::Obj).unwrap_err().to_string();
        assert!(e.starts_with("--formats obj: expected single-file formats"), "{e}");
    }
}
