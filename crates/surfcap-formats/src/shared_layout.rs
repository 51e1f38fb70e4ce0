//! The `../shared/data` layout: `<dataset>/<sequence>/template.obj` (first frame, topology),
//! `positions.npy` (float32 `[frames, vertices, 3]`, same vertex order), optional `joints.npy`
//! (float32 `[frames, joints, 4, 4]` world matrices), and `<dataset>/meta.json` with fps, units,
//! up axis and joint names/parents (per dataset, or per sequence under `sequences.<name>`).

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::obj::read_obj;
use surfcap_mesh::error::{Error, Result, err};
use surfcap_mesh::npy::{expect_shape, read_npy};
use surfcap_mesh::regular_file::{check_regular_file, exists_at, read_regular_file};
use surfcap_mesh::subject::{FrameLabel, JointTrack, Units, UpAxis};
use surfcap_mesh::topology::Topology;

/// What a dataset's `meta.json` says about one sequence.
#[derive(Debug, Clone, Default)]
pub struct SequenceMeta {
    /// `None` when the metadata does not know it (`null`, `"unknown"`).
    pub fps: Option<f64>,
    pub up_axis: Option<UpAxis>,
    pub units: Option<Units>,
    pub frames: Option<usize>,
    pub vertices: Option<usize>,
    pub joint_names: Option<Vec<String>>,
    pub joint_parents: Option<Vec<Option<usize>>>,
    /// Sequence name, tags and frame labels, as written by `surfcap export --format npy`.
    pub name: Option<String>,
    pub tags: Vec<String>,
    pub labels: Option<Vec<FrameLabel>>,
    pub meta_path: Option<PathBuf>,
}

/// A sequence read from the shared layout.
#[derive(Debug, Clone)]
pub struct LayoutSequence {
    pub name: String,
    pub topology: Topology,
    pub positions: Vec<f32>,
    pub joints: Option<JointTrack>,
    pub meta: SequenceMeta,
}

/// Whether `dir` holds a sequence in this layout: `template.obj` and `positions.npy` both there
/// and regular files. Both there but either one a FIFO, folder, socket or device is an error
/// naming it (reading a FIFO would block; skipping it would silently read something else).
pub fn is_layout_sequence(dir: &Path) -> Result<bool> {
    let (template, positions) = (dir.join("template.obj"), dir.join("positions.npy"));
    if !(exists_at(&template) && exists_at(&positions)) {
        return Ok(false);
    }
    check_regular_file(&template)?;
    check_regular_file(&positions)?;
    Ok(true)
}

/// Sequence folders of a dataset folder (one with `meta.json` and sequence subfolders), sorted.
pub fn dataset_sequences(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, "list directory", e))? {
        let p = e.map_err(|e| Error::io(dir, "list directory", e))?.path();
        if p.is_dir() && is_layout_sequence(&p)? {
            v.push(p);
        }
    }
    v.sort_by(|a, b| surfcap_mesh::natural_order::natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    Ok(v)
}

fn number(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite() && *x > 0.0)
}

/// Reads `meta.json` next to the sequence folder (in its parent), if there is one.
pub fn read_sequence_meta(seq_dir: &Path) -> Result<SequenceMeta> {
    let name = seq_dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let Some(meta_path) = seq_dir.parent().map(|p| p.join("meta.json")).filter(|p| exists_at(p)) else {
        return Ok(SequenceMeta::default());
    };
    let text = String::from_utf8(read_regular_file(&meta_path)?)
        .map_err(|_| err!(Syntax, "not UTF-8 text: expected JSON").in_file(&meta_path))?;
    let root: Value = serde_json::from_str(&text)
        .map_err(|e| err!(Syntax, "invalid JSON: {e}").in_file(&meta_path).at_line(e.line()))?;
    let seq = &root["sequences"][&name];
    let pick = |key: &str| {
        if seq[key].is_null() { &root[key] } else { &seq[key] }
    };
    let up_axis = match pick("up_axis").as_str() {
        Some(s) => Some(UpAxis::parse(s).map_err(|e| e.in_file(&meta_path))?),
        None => None,
    };
    let joint_names = root["joint_names"]
        .as_array()
        .map(|a| a.iter().map(|n| n.as_str().unwrap_or("").to_string()).collect::<Vec<_>>());
    let joint_parents = root["joint_parents"]
        .as_array()
        .map(|a| a.iter().map(|p| p.as_i64().and_then(|p| usize::try_from(p).ok())).collect::<Vec<_>>());
    Ok(SequenceMeta {
        fps: number(&seq["fps"]).or_else(|| number(&root["fps"])),
        up_axis,
        units: pick("units").as_str().map(Units::parse),
        frames: seq["frames"].as_u64().map(|x| x as usize),
        vertices: seq["vertices"].as_u64().map(|x| x as usize),
        joint_names,
        joint_parents,
        name: seq["name"].as_str().map(str::to_string),
        tags: serde_json::from_value(seq["tags"].clone()).unwrap_or_default(),
        labels: serde_json::from_value(seq["frame_labels"].clone()).ok(),
        meta_path: Some(meta_path),
    })
}

/// Reads one sequence folder of the layout.
pub fn read_layout_sequence(dir: &Path) -> Result<LayoutSequence> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| err!(Metadata, "cannot name the sequence of this folder").in_file(dir))?;
    let template_path = dir.join("template.obj");
    let template = read_obj(&template_path)?;
    let topology = template.topology().map_err(|e| e.in_file(&template_path))?;
    let nv = topology.n_vertices();
    let positions_path = dir.join("positions.npy");
    let positions = read_npy::<f32>(&positions_path)?;
    expect_shape(&positions, &[None, Some(nv), Some(3)], &format!("positions of the template's {nv} vertices"))
        .map_err(|e| e.in_file(&positions_path))?;
    let frames = positions.shape[0];
    if frames == 0 {
        return Err(err!(Empty, "no frames: expected shape [frames >= 1, {nv}, 3]").in_file(&positions_path));
    }
    let per_frame = 3 * nv;
    if let Some(k) = positions.data.iter().position(|x| !x.is_finite()) {
        return Err(err!(
            NonFinite,
            "vertex {} has a non-finite coordinate: expected finite numbers",
            (k % per_frame) / 3
        )
        .in_file(&positions_path)
        .at_frame(k / per_frame));
    }
    let meta = read_sequence_meta(dir)?;
    let joints_path = dir.join("joints.npy");
    // Optional, but something of that name that is not a regular file is refused (by the
    // reader), not silently ignored.
    let joints = if surfcap_mesh::regular_file::exists_at(&joints_path) {
        let j = read_npy::<f32>(&joints_path)?;
        expect_shape(&j, &[Some(frames), None, Some(4), Some(4)], "joint world matrices [frames, joints, 4, 4]")
            .map_err(|e| e.in_file(&joints_path))?;
        let nj = j.shape[1];
        let names = match &meta.joint_names {
            Some(n) if n.len() == nj => n.clone(),
            Some(n) => {
                return Err(err!(Shape, "{nj} joints, but meta.json names {}", n.len()).in_file(&joints_path));
            }
            None => (0..nj).map(|i| format!("joint_{i}")).collect(),
        };
        let parents = match &meta.joint_parents {
            Some(p) if p.len() == nj => p.clone(),
            _ => vec![None; nj],
        };
        Some(JointTrack { names, parents, matrices: j.data })
    } else {
        None
    };
    Ok(LayoutSequence { name, topology, positions: positions.data, joints, meta })
}

/// Writes a sequence in the layout (`template.obj`, `positions.npy`, optional `joints.npy`)
/// into an existing folder.
pub fn write_layout_sequence(
    dir: &Path,
    topology: &Topology,
    positions: &[f32],
    joints: Option<&JointTrack>,
) -> Result<()> {
    let nv = topology.n_vertices();
    let frames = positions.len() / (3 * nv);
    surfcap_mesh::atomic::write_file(&dir.join("template.obj"), |w| {
        crate::obj::write_obj(w, topology, &positions[..3 * nv])
    })?;
    surfcap_mesh::atomic::write_file(&dir.join("positions.npy"), |w| {
        surfcap_mesh::npy::write_npy(w, &[frames, nv, 3], positions)
    })?;
    if let Some(j) = joints {
        surfcap_mesh::atomic::write_file(&dir.join("joints.npy"), |w| {
            surfcap_mesh::npy::write_npy(w, &[frames, j.n_joints(), 4, 4], &j.matrices)
        })?;
    }
    Ok(())
}
