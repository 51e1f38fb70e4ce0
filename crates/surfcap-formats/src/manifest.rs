//! `surfcap.toml`: a subject described by a list of sequences from any supported source.
//!
//! ```toml
//! name = "horse"          # optional; default: the folder's name
//! fps = 24                # optional when every source knows its frame rate
//! up_axis = "+y"          # optional
//! units = "m"             # optional
//!
//! [[sequence]]
//! source = "gallop"       # relative to this file: any source `surfcap import` reads
//! name = "gallop"         # optional rename (only for a source with one sequence)
//! tags = ["gallop", "locomotion"]
//!
//! [[sequence]]
//! source = "cache.pc2"    # a PC2 point cache or a bare positions .npy needs a template mesh
//! template = "rest.obj"
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::import::{ImportOptions, SourceSequence, read_source};
use surfcap_mesh::error::{Error, Result, err};
use surfcap_mesh::progress::Progress;
use surfcap_mesh::subject::{Units, UpAxis};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    name: Option<String>,
    fps: Option<f64>,
    up_axis: Option<String>,
    units: Option<String>,
    #[serde(default)]
    sequence: Vec<Entry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    source: PathBuf,
    name: Option<String>,
    #[serde(default)]
    tags: Vec<String>,
    template: Option<PathBuf>,
    joints: Option<PathBuf>,
}

/// The manifest file a path designates: `surfcap.toml` itself, any `.toml`, or a folder holding one.
pub fn find_manifest(path: &Path) -> Option<PathBuf> {
    if path.is_file() && path.extension().is_some_and(|e| e == "toml") {
        return Some(path.to_path_buf());
    }
    // Anything named surfcap.toml counts (a FIFO or folder there is then refused by name when
    // read, rather than silently ignored).
    let inside = path.join("surfcap.toml");
    surfcap_mesh::regular_file::exists_at(&inside).then_some(inside)
}

fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> Option<usize> {
    span.map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1)
}

/// Reads the manifest and every sequence it lists.
pub fn read_manifest(path: &Path, progress: &dyn Progress) -> Result<(ImportOptions, Vec<SourceSequence>)> {
    surfcap_mesh::regular_file::check_regular_file(path)?;
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, "read manifest", e))?;
    let m: Manifest = toml::from_str(&text).map_err(|e| {
        let mut er = err!(Syntax, "{}", e.message()).in_file(path);
        if let Some(l) = line_of(&text, e.span()) {
            er = er.at_line(l);
        }
        er
    })?;
    let line_with = |needle: &str| text.lines().position(|l| l.contains(needle)).map(|i| i + 1);
    // An error in the manifest gets its line; an error in a file it lists keeps that file's own
    // place (a binary PC2 has bytes, not lines) and says which manifest line listed it.
    let at = |mut e: Error, needle: &str| match (e.path.as_deref().is_some_and(|p| p != path), line_with(needle)) {
        (true, Some(l)) => {
            e.message = format!("{} (listed in {} at line {l})", e.message, path.display());
            e
        }
        (true, None) => e,
        (false, Some(l)) => e.in_file(path).at_line(l),
        (false, None) => e.in_file(path),
    };
    if m.sequence.is_empty() {
        return Err(err!(Empty, "no [[sequence]] entries: expected at least one").in_file(path));
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let up_axis = match &m.up_axis {
        Some(u) => Some(UpAxis::parse(u).map_err(|e| at(e, "up_axis"))?),
        None => None,
    };
    if let Some(f) = m.fps {
        surfcap_mesh::subject::check_frame_rate(f).map_err(|_| {
            at(err!(Metadata, "fps = {f}: expected {}", surfcap_mesh::subject::FRAME_RATES_TEXT), "fps")
        })?;
    }
    let opts = ImportOptions { name: m.name.clone(), fps: m.fps, up_axis, units: m.units.as_deref().map(Units::parse) };
    let mut out: Vec<SourceSequence> = Vec::new();
    // The entry (its source as written) each sequence of `out` came from.
    let mut listed_by: Vec<String> = Vec::new();
    for e in &m.sequence {
        let src = base.join(&e.source);
        let needle = e.source.to_string_lossy().into_owned();
        if let Some(inner) = find_manifest(&src) {
            return Err(at(
                err!(
                    Unsupported,
                    "manifests cannot nest: {} names the manifest {}; list its sources directly",
                    path.display(),
                    inner.display()
                ),
                &needle,
            ));
        }
        let mut seqs = match &e.template {
            Some(t) => vec![read_with_template(&src, &base.join(t)).map_err(|er| at(er, &needle))?],
            None => read_source(&src, progress)?,
        };
        if let Some(j) = &e.joints {
            let jp = base.join(j);
            if seqs.len() != 1 {
                return Err(at(err!(Metadata, "'joints' needs a source with exactly one sequence"), &needle));
            }
            let arr = surfcap_mesh::npy::read_npy::<f32>(&jp)?;
            let frames = seqs[0].positions.len() / (3 * seqs[0].topology.n_vertices());
            surfcap_mesh::npy::expect_shape(
                &arr,
                &[Some(frames), None, Some(4), Some(4)],
                "joint world matrices [frames, joints, 4, 4]",
            )
            .map_err(|er| er.in_file(&jp))?;
            let nj = arr.shape[1];
            seqs[0].joints = Some(surfcap_mesh::subject::JointTrack {
                names: (0..nj).map(|i| format!("joint_{i}")).collect(),
                parents: vec![None; nj],
                matrices: arr.data,
            });
        }
        if let Some(n) = &e.name {
            if seqs.len() != 1 {
                return Err(at(
                    err!(Metadata, "'name' renames one sequence, but {needle:?} holds {}", seqs.len()),
                    &needle,
                ));
            }
            seqs[0].name = n.clone();
        }
        for s in &mut seqs {
            s.tags.extend(e.tags.iter().cloned());
        }
        for s in &seqs {
            if let Some(k) = out.iter().position(|o| o.name == s.name) {
                let first = &listed_by[k];
                let how = if *first == needle {
                    format!("{needle:?} holds two sequences named {:?}", s.name)
                } else {
                    format!("{:?} (from {needle:?}) is also the name of a sequence from {first:?}", s.name)
                };
                return Err(at(
                    err!(Metadata, "sequence name {how}: expected unique names (give one a `name = ...`)"),
                    &needle,
                ));
            }
            listed_by.push(needle.clone());
        }
        out.extend(seqs);
    }
    Ok((opts, out))
}

/// A PC2 point cache or a bare `[frames, vertices, 3]` positions `.npy`, with a template mesh.
fn read_with_template(src: &Path, template: &Path) -> Result<SourceSequence> {
    let t = crate::obj::read_obj(template)?;
    let topology = t.topology().map_err(|e| e.in_file(template))?;
    let nv = topology.n_vertices();
    let ext = src.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let positions = match ext.as_str() {
        "pc2" => {
            let b = surfcap_mesh::regular_file::read_regular_file(src)?;
            let c = crate::pc2::parse_pc2(&b).map_err(|e| e.in_file(src))?;
            if c.n_points != nv {
                return Err(err!(
                    TopologyMismatch,
                    "point count {}: expected {nv}, the vertex count of {}",
                    c.n_points,
                    template.display()
                )
                .in_file(src)
                .at(surfcap_mesh::error::Location::Byte(16)));
            }
            c.positions
        }
        "npy" => {
            let a = surfcap_mesh::npy::read_npy::<f32>(src)?;
            surfcap_mesh::npy::expect_shape(
                &a,
                &[None, Some(nv), Some(3)],
                &format!("positions of the template's {nv} vertices"),
            )
            .map_err(|e| e.in_file(src))?;
            a.data
        }
        _ => {
            return Err(err!(Unsupported, "a template goes with a .pc2 or .npy source, not {ext:?}").in_file(src));
        }
    };
    let name = src.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(crate::import::simple(name, topology, positions, src, crate::import::SourceLayout::WithTemplate))
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::progress::NoProgress;

    /// A PC2 whose point count differs from its template was reported at "line 3" of
    /// the binary PC2 (the manifest's line). Now: the PC2 and its byte, then the manifest line.
    #[test]
    fn a_point_count_mismatch_names_the_pc2_byte_and_the_manifest_line() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(
            d.path().join("t.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
        )
        .unwrap();
        let mut pc2 = Vec::new();
        crate::pc2::write_pc2(&mut pc2, 3, &[0.0; 18]).unwrap();
        std::fs::write(d.path().join("c.pc2"), pc2).unwrap();
        let m = d.path().join("surfcap.toml");
        std::fs::write(&m, "fps = 30\n[[sequence]]\nsource = \"c.pc2\"\ntemplate = \"t.obj\"\n").unwrap();
        let e = read_manifest(&m, &NoProgress).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "{}: byte 16: point count 3: expected 4, the vertex count of {} (listed in {} at line 3)",
                d.path().join("c.pc2").display(),
                d.path().join("t.obj").display(),
                m.display()
            )
        );
    }

    const TET: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

    #[test]
    fn a_nested_manifest_is_refused_saying_manifests_cannot_nest() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("inner")).unwrap();
        std::fs::write(d.path().join("inner/surfcap.toml"), "[[sequence]]\nsource = \"a.obj\"\n").unwrap();
        std::fs::write(d.path().join("other.toml"), "[[sequence]]\nsource = \"a.obj\"\n").unwrap();
        let m = d.path().join("surfcap.toml");
        for (source, inner) in [("inner", "inner/surfcap.toml"), ("other.toml", "other.toml")] {
            std::fs::write(&m, format!("fps = 30\n[[sequence]]\nsource = \"{source}\"\n")).unwrap();
            let e = read_manifest(&m, &NoProgress).unwrap_err().to_string();
            assert_eq!(
                e,
                format!(
                    "{}: line 3: manifests cannot nest: {} names the manifest {}; list its sources directly",
                    m.display(),
                    m.display(),
                    d.path().join(inner).display()
                )
            );
        }
    }

    #[test]
    fn a_repeated_sequence_name_names_the_manifest_and_the_line() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("b")).unwrap();
        std::fs::write(d.path().join("walk.obj"), TET).unwrap();
        std::fs::write(d.path().join("b/walk.obj"), TET).unwrap();
        let m = d.path().join("surfcap.toml");
        std::fs::write(&m, "fps = 30\n[[sequence]]\nsource = \"walk.obj\"\n\n[[sequence]]\nsource = \"b/walk.obj\"\n")
            .unwrap();
        let e = read_manifest(&m, &NoProgress).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: line 6: sequence name \"walk\"", m.display())), "{e}");
        assert!(e.contains("also the name of a sequence from \"walk.obj\""), "{e}");
    }

    #[test]
    fn a_frame_rate_out_of_range_names_the_manifest_line() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("walk.obj"), TET).unwrap();
        let m = d.path().join("surfcap.toml");
        std::fs::write(&m, "name = \"x\"\nfps = 1e300\n[[sequence]]\nsource = \"walk.obj\"\n").unwrap();
        let e = read_manifest(&m, &NoProgress).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: line 2: fps = ", m.display())) && e.contains("0.1 to 10000"), "{e}");
    }
}
