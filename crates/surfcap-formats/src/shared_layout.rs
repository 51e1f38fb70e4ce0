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
use surfcap_mesh::subject::{FRAME_RATES_TEXT, FrameLabel, JointTrack, Units, UpAxis, check_frame_rate};
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

/// A field of `meta.json`, `key` where the sequence's own entry (`sequences.<name>.<key>`) wins
/// over the dataset's (`<key>`); absent or `null` is unknown.
struct MetaFields<'a> {
    path: &'a Path,
    root: &'a Value,
    seq: &'a Value,
    name: &'a str,
}

impl MetaFields<'_> {
    /// The value of `key` and the field's name as the user wrote it: the sequence's own, else
    /// the dataset's.
    fn pick(&self, key: &str) -> (&Value, String) {
        if self.seq[key].is_null() {
            (&self.root[key], key.to_string())
        } else {
            (&self.seq[key], format!("sequences.{}.{key}", self.name))
        }
    }

    /// `key` of the sequence's own entry only.
    fn own(&self, key: &str) -> (&Value, String) {
        (&self.seq[key], format!("sequences.{}.{key}", self.name))
    }

    /// The value as a `T`, `None` when absent or `null`; any other type is an error naming the
    /// file, the field and what was expected.
    fn typed<T: serde::de::DeserializeOwned>(&self, (v, field): (&Value, String), expected: &str) -> Result<Option<T>> {
        if v.is_null() {
            return Ok(None);
        }
        serde_json::from_value(v.clone()).map(Some).map_err(|_| self.bad(v, &field, expected))
    }

    fn bad(&self, v: &Value, field: &str, expected: &str) -> Error {
        let mut shown = v.to_string();
        if shown.len() > 60 {
            shown = format!("{}...", &shown[..shown.floor_char_boundary(57)]);
        }
        err!(Metadata, "{field} = {shown}: expected {expected}").in_file(self.path)
    }

    /// The frame rate: a number of frames per second in the accepted range, or unknown
    /// (absent, `null`, or a text starting with "unknown", such as `"unknown (35-frame cycle)"`).
    fn fps(&self) -> Result<Option<f64>> {
        let (v, field) = self.pick("fps");
        let unknown =
            |v: &Value| v.is_null() || v.as_str().is_some_and(|t| t.trim().to_lowercase().starts_with("unknown"));
        if unknown(v) {
            // A sequence's own "unknown" leaves the dataset's rate to decide.
            return if v.is_null() || self.root["fps"].is_null() || unknown(&self.root["fps"]) {
                Ok(None)
            } else {
                MetaFields { seq: &Value::Null, ..*self }.fps()
            };
        }
        let expected = format!("{FRAME_RATES_TEXT}, null or \"unknown\"");
        let f = v.as_f64().ok_or_else(|| self.bad(v, &field, &expected))?;
        check_frame_rate(f).map(Some).map_err(|_| self.bad(v, &field, &expected))
    }
}

/// Reads `meta.json` next to the sequence folder (in its parent), if there is one. A field of
/// the wrong type or out of range is an error naming the file and the field (a silently ignored
/// `"fps": -10` would surface later as "no frame rate is known").
pub fn read_sequence_meta(seq_dir: &Path) -> Result<SequenceMeta> {
    let name = seq_dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let Some(meta_path) = seq_dir.parent().map(|p| p.join("meta.json")).filter(|p| exists_at(p)) else {
        return Ok(SequenceMeta::default());
    };
    let text = String::from_utf8(read_regular_file(&meta_path)?)
        .map_err(|_| err!(Syntax, "not UTF-8 text: expected JSON").in_file(&meta_path))?;
    let root: Value = serde_json::from_str(&text)
        .map_err(|e| err!(Syntax, "invalid JSON: {e}").in_file(&meta_path).at_line(e.line()))?;
    if !root.is_object() {
        return Err(
            err!(Metadata, "expected a JSON object of fields (fps, units, up_axis, sequences)").in_file(&meta_path)
        );
    }
    if !(root["sequences"].is_null() || root["sequences"].is_object()) {
        return Err(
            err!(Metadata, "sequences: expected an object with one entry per sequence folder").in_file(&meta_path)
        );
    }
    let seq = &root["sequences"][&name];
    if !(seq.is_null() || seq.is_object()) {
        return Err(err!(Metadata, "sequences.{name}: expected an object of fields (fps, frames, name, tags)")
            .in_file(&meta_path));
    }
    let m = MetaFields { path: &meta_path, root: &root, seq, name: &name };
    let up_axis = match m.typed::<String>(m.pick("up_axis"), "an axis such as \"+y\"")? {
        Some(s) => Some(UpAxis::parse(&s).map_err(|e| e.in_file(&meta_path))?),
        None => None,
    };
    let joint_names = m.typed::<Vec<String>>((&root["joint_names"], "joint_names".into()), "a list of texts")?;
    let joint_parents = m
        .typed::<Vec<Option<i64>>>(
            (&root["joint_parents"], "joint_parents".into()),
            "a list of joint indices (-1 or null for a root)",
        )?
        .map(|a| a.into_iter().map(|p| p.and_then(|p| usize::try_from(p).ok())).collect::<Vec<_>>());
    let count = "a whole number";
    Ok(SequenceMeta {
        fps: m.fps()?,
        up_axis,
        units: m.typed::<String>(m.pick("units"), "a unit such as \"m\"")?.map(|u| Units::parse(&u)),
        frames: m.typed::<usize>(m.own("frames"), count)?,
        vertices: m.typed::<usize>(m.own("vertices"), count)?,
        joint_names,
        joint_parents,
        name: m.typed::<String>(m.own("name"), "a text")?,
        tags: m.typed::<Vec<String>>(m.own("tags"), "a list of texts")?.unwrap_or_default(),
        labels: m.typed::<Vec<FrameLabel>>(m.own("frame_labels"), "a list of \"original\" or \"synthetic\"")?,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `read_sequence_meta` of the sequence folder `walk` under a dataset whose `meta.json` is `json`.
    fn meta(json: &str) -> (Result<SequenceMeta>, PathBuf) {
        let d = tempfile::tempdir().unwrap();
        let m = d.path().join("meta.json");
        std::fs::write(&m, json).unwrap();
        (read_sequence_meta(&d.path().join("walk")), m)
    }

    #[test]
    fn a_bad_frame_rate_in_meta_json_names_the_file_and_the_field() {
        let cases = [
            (r#"{"fps": -10}"#, "fps = -10"),
            (r#"{"fps": "fast"}"#, "fps = \"fast\""),
            (r#"{"fps": [30]}"#, "fps = [30]"),
            (r#"{"fps": 1e300}"#, "fps = 1e+300"),
            (r#"{"fps": 30, "sequences": {"walk": {"fps": {"a": 1}}}}"#, "sequences.walk.fps = {\"a\":1}"),
        ];
        for (json, field) in cases {
            let (r, path) = meta(json);
            let e = r.unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("{}: {field}: expected 0.1 to 10000 frames per second", path.display())),
                "{e}"
            );
            assert!(e.ends_with("null or \"unknown\""), "{e}");
        }
    }

    #[test]
    fn unknown_frame_rates_stay_unknown_and_good_ones_are_read() {
        for (json, fps) in [
            (r#"{"fps": null}"#, None),
            (r#"{"fps": "unknown (35-frame walk cycle)", "sequences": {"walk": {"fps": null}}}"#, None),
            (r#"{"fps": 24}"#, Some(24.0)),
            (r#"{"fps": 24, "sequences": {"walk": {"fps": 30}}}"#, Some(30.0)),
            (r#"{"fps": 24, "sequences": {"walk": {"fps": "unknown"}}}"#, Some(24.0)),
        ] {
            assert_eq!(meta(json).0.unwrap().fps, fps, "{json}");
        }
    }

    #[test]
    fn other_fields_of_the_wrong_type_name_the_file_and_the_field() {
        let cases = [
            (r#"[1, 2]"#, "expected a JSON object"),
            (r#"{"units": 3}"#, "units = 3: expected a unit"),
            (r#"{"up_axis": true}"#, "up_axis = true: expected an axis"),
            (r#"{"sequences": {"walk": {"frames": -1}}}"#, "sequences.walk.frames = -1: expected a whole number"),
            (r#"{"sequences": {"walk": {"tags": "a"}}}"#, "sequences.walk.tags = \"a\": expected a list of texts"),
            (r#"{"sequences": {"walk": {"frame_labels": ["x"]}}}"#, "sequences.walk.frame_labels = [\"x\"]"),
            (r#"{"joint_names": [1]}"#, "joint_names = [1]: expected a list of texts"),
            (r#"{"sequences": [1]}"#, "sequences: expected an object"),
        ];
        for (json, want) in cases {
            let (r, path) = meta(json);
            let e = r.unwrap_err().to_string();
            assert!(e.starts_with(&format!("{}: ", path.display())) && e.contains(want), "{json}: {e}");
        }
    }
}
