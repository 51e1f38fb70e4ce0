//! `surfcap import x.abc` on archives written by the
//! reference library (PyPI `alembic3d`, through `tools/abc-write.py`): triangles and quads with
//! Alembic's clockwise faces turned counter-clockwise, several samples to the bit (checked
//! against what the reference library reads back), indexed UVs, labels, a 24000/1001 rate,
//! several meshes under Xforms, and the refusals (varying topology, irregular times, meshes of
//! different topology, the old HDF5 container); a real KayKit clip round trip.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use surfcap_mesh::{FrameLabel, NoProgress, Subject, UpAxis};
use surfcap_testkit::{p, stderr, surfcap};

/// Writes `spec` as an Alembic archive with the reference library (`tools/abc-write.py`).
fn write_abc(spec: &Value, out: &Path) {
    let root = surfcap_testkit::workspace_root();
    let python = root.join("tools/venv/bin/python");
    assert!(python.is_file(), "{} is missing: run scripts/test (it installs alembic3d)", python.display());
    let spec_file = out.with_extension("json");
    std::fs::write(&spec_file, spec.to_string()).unwrap();
    let o = std::process::Command::new(&python)
        .arg(root.join("tools/abc-write.py"))
        .arg(&spec_file)
        .arg(out)
        .output()
        .expect("python runs");
    assert!(o.status.success(), "abc-write.py failed:\n{}", String::from_utf8_lossy(&o.stderr));
}

/// `surfcap import abc -o <dir>/x.subject`: the subject, or the error text; and the notes.
fn import(abc: &Path, dir: &Path) -> (Result<Subject, String>, String) {
    let out = dir.join(format!("{}.subject", abc.file_stem().unwrap().to_string_lossy()));
    let o = surfcap!(&["import", p(abc), "-o", p(&out)]);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    if !o.status.success() {
        return (Err(stderr(&o)), text);
    }
    (Ok(surfcap_mesh::cache::read_cache(&out, &NoProgress).unwrap()), text)
}

/// A float32 value as the double the JSON carries (exact).
fn f(x: f32) -> f64 {
    f64::from(x)
}

/// Seven points of a small sheet in the z = 0 plane (x, y), then four faces stored clockwise
/// seen from +Z, as Alembic stores them: a quad and three triangles.
const SHEET: [[f32; 2]; 7] = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0], [1.5, 1.8]];
const COUNTS: [i32; 4] = [4, 3, 3, 3];
const INDICES: [i32; 13] = [0, 3, 4, 1, 1, 4, 2, 2, 4, 5, 4, 6, 5];

/// Frame k of the sheet: moved and wobbled in float32 (values that are not short decimals).
fn sheet_frame(k: usize) -> Vec<f32> {
    SHEET
        .iter()
        .enumerate()
        .flat_map(|(i, [x, y])| {
            let t = k as f32 * 0.37 + i as f32 * 0.1;
            [x + 0.1 * t.sin(), y + k as f32 / 3.0, 0.01 * t.cos()]
        })
        .collect()
}

fn points(frame: &[f32]) -> Value {
    Value::Array(frame.chunks(3).map(|c| json!([f(c[0]), f(c[1]), f(c[2])])).collect())
}

fn sheet_mesh(path: &str, frames: usize, extra: Value) -> Value {
    let samples: Vec<Value> = (0..frames)
        .map(|k| {
            let mut s = json!({"P": points(&sheet_frame(k))});
            if k == 0 {
                s["faceIndices"] = json!(INDICES);
                s["faceCounts"] = json!(COUNTS);
            }
            s
        })
        .collect();
    let mut m = json!({"type": "mesh", "path": path, "fps": 30.0, "samples": samples});
    for (k, v) in extra.as_object().unwrap() {
        m[k] = v.clone();
    }
    m
}

/// The reference library's positions of mesh `i`, flattened.
fn reference_positions(abc: &Value, i: usize) -> Vec<f64> {
    abc["meshes"][i]["positions"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|frame| frame.as_array().unwrap().iter().flat_map(|p| p.as_array().unwrap().iter()))
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn a_reference_written_mesh_imports_with_ccw_triangles_uvs_labels_and_ntsc_rate() {
    let d = tempfile::tempdir().unwrap();
    let abc = d.path().join("sheet.abc");
    // Per-corner UVs, indexed in reverse corner order so UV and vertex indices differ.
    let uv_vals: Vec<Value> = (0..13).map(|j| json!([f(j as f32 / 16.0), f(1.0 - j as f32 / 16.0)])).collect();
    let uv_indices: Vec<u32> = (0..13).rev().collect();
    let extra = json!({
        "time_per_cycle": 1001.0 / 24000.0,
        "uv": {"vals": uv_vals, "indices": uv_indices, "scope": "facevarying"},
        "labels": [0, 1, 1, 0],
    });
    let spec = json!({
        "metadata": {"surfcap_up_axis": "+z", "surfcap_units": "cm"},
        "objects": [{"type": "xform", "path": "/sheet", "translate": [0.0, 0.0, 2.0]}, sheet_mesh("/sheet/mesh", 4, extra)],
    });
    write_abc(&spec, &abc);
    let (s, text) = import(&abc, d.path());
    let s = s.unwrap_or_else(|e| panic!("{e}"));
    assert!(!text.contains("assumed") && !text.contains("no units"), "metadata came from the file:\n{text}");
    // The sequence Xform's transform is surfcap's up-axis rotation when surfcap_up_axis is set.
    assert!(!text.contains("is ignored"), "the sequence Xform was noted:\n{text}");
    assert_eq!(s.fps, 24000.0 / 1001.0);
    assert_eq!(s.up_axis, UpAxis::PosZ);
    assert_eq!(s.units.metres_per_unit, Some(0.01));
    // Each polygon reversed (counter-clockwise) and fanned from the reversed first corner.
    let t = s.topology();
    assert_eq!(t.n_vertices(), 7);
    assert_eq!(t.triangles(), [[1, 4, 3], [1, 3, 0], [2, 4, 1], [5, 4, 2], [5, 6, 4]]);
    let first = sheet_frame(0);
    for tri in t.triangles() {
        let q = |i: u32| [first[3 * i as usize], first[3 * i as usize + 1]];
        let (a, b, c) = (q(tri[0]), q(tri[1]), q(tri[2]));
        assert!((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0, "{tri:?} faces -Z");
    }
    // UVs: the corners of each triangle, through the reversed index list.
    let uv = t.uv().expect("UVs imported");
    let fv = [[3, 2, 1], [3, 1, 0], [6, 5, 4], [9, 8, 7], [12, 11, 10]];
    let want: Vec<[u32; 3]> = fv.iter().map(|c| c.map(|x| 12 - x)).collect();
    assert_eq!(uv.corners, want);
    assert_eq!(uv.coords[5], [5.0 / 16.0, 11.0 / 16.0]);
    let seq = &s.sequences()[0];
    assert_eq!(seq.name, "sheet");
    assert_eq!(seq.labels, [FrameLabel::Original, FrameLabel::Synthetic, FrameLabel::Synthetic, FrameLabel::Original]);
    // Positions to the bit: as written, and as the reference library reads them.
    let written: Vec<f32> = (0..4).flat_map(sheet_frame).collect();
    assert!(seq.positions() == &written[..], "positions differ from the written float32 values");
    let reference = surfcap_testkit::read_abc(&abc);
    let back: Vec<f64> = seq.positions().iter().map(|&x| f(x)).collect();
    assert_eq!(back, reference_positions(&reference, 0));
    assert_eq!(reference["meshes"][0]["topology_variance"], "kHomogenousTopology");
}

/// UVs per vertex, and per corner without indices, land on the triangles' corners.
#[test]
fn vertex_and_unindexed_face_varying_uvs_are_read() {
    let d = tempfile::tempdir().unwrap();
    let vals = |n: usize| -> Vec<Value> { (0..n).map(|j| json!([f(j as f32 / 8.0), 0.5])).collect() };
    let abc = d.path().join("vertex_uv.abc");
    let uv = json!({"uv": {"vals": vals(7), "indices": null, "scope": "vertex"}});
    write_abc(&json!({"objects": [sheet_mesh("/v", 2, uv)]}), &abc);
    let s = import(&abc, d.path()).0.unwrap_or_else(|e| panic!("{e}"));
    let uv = s.topology().uv().expect("vertex UVs");
    assert_eq!(uv.corners, s.topology().triangles());
    assert_eq!(uv.coords[6], [0.75, 0.5]);
    assert_eq!(surfcap_testkit::read_abc(&abc)["meshes"][0]["uvs"]["scope"], "vertex");
    let abc = d.path().join("corner_uv.abc");
    let uv = json!({"uv": {"vals": vals(13), "indices": null, "scope": "facevarying"}});
    write_abc(&json!({"objects": [sheet_mesh("/c", 2, uv)]}), &abc);
    let s = import(&abc, d.path()).0.unwrap_or_else(|e| panic!("{e}"));
    let uv = s.topology().uv().expect("face-varying UVs");
    assert_eq!(uv.corners, [[3, 2, 1], [3, 1, 0], [6, 5, 4], [9, 8, 7], [12, 11, 10]]);
    assert_eq!(surfcap_testkit::read_abc(&abc)["meshes"][0]["uvs"]["indexed"], false);
}

#[test]
fn several_meshes_under_xforms_are_sequences_and_other_objects_are_noted() {
    let d = tempfile::tempdir().unwrap();
    let abc = d.path().join("many.abc");
    let spec = json!({"objects": [
        {"type": "xform", "path": "/a", "translate": [1.0, 0.0, 0.0]},
        sheet_mesh("/a/mesh", 3, json!({})),
        {"type": "points", "path": "/a/dust"},
        {"type": "xform", "path": "/b"},
        {"type": "xform", "path": "/b/rig"},
        sheet_mesh("/b/rig/body", 5, json!({})),
        {"type": "curves", "path": "/hair"},
        {"type": "xform", "path": "/s"},
        sheet_mesh("/s/mesh", 2, json!({"subd": true})),
    ]});
    write_abc(&spec, &abc);
    let (s, text) = import(&abc, d.path());
    let s = s.unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = s.sequences().iter().map(|q| q.name.as_str()).collect();
    assert_eq!(names, ["a", "b/rig/body", "s"]);
    let frames: Vec<usize> = s.sequences().iter().map(|q| q.n_frames()).collect();
    assert_eq!(frames, [3, 5, 2]);
    assert_eq!(s.fps, 30.0);
    assert_eq!(s.up_axis, UpAxis::PosY);
    let reference = surfcap_testkit::read_abc(&abc);
    // abc-read.py reads the PolyMeshes; the SubD's positions are checked against what was written.
    for (i, q) in s.sequences().iter().take(2).enumerate() {
        let back: Vec<f64> = q.positions().iter().map(|&x| f(x)).collect();
        assert_eq!(back, reference_positions(&reference, i), "{}", q.name);
    }
    let written: Vec<f32> = (0..2).flat_map(sheet_frame).collect();
    assert!(s.sequences()[2].positions() == &written[..], "SubD positions");
    for note in [
        "the transform of /a is ignored: points are read in the mesh's own coordinates",
        "/a/dust (AbcGeom_Points_v1) skipped",
        "/hair (AbcGeom_Curve_v2) skipped",
        "/s/mesh: a SubD surface, read as its control mesh (not subdivided)",
        "no surfcap_up_axis in the archive metadata: +y assumed",
    ] {
        assert!(text.contains(note), "no note {note:?} in:\n{text}");
    }
    assert!(!text.contains("/b is ignored") && !text.contains("/b/rig is ignored"), "identity Xforms noted:\n{text}");

    // Two meshes of different topology are not one subject.
    let other = json!({"type": "mesh", "path": "/c/mesh", "fps": 30.0, "samples": [{
        "P": points(&sheet_frame(0)[..12]), "faceIndices": [0, 3, 1], "faceCounts": [3]}]});
    let spec = json!({"objects": [sheet_mesh("/a", 2, json!({})), {"type": "xform", "path": "/c"}, other]});
    let abc = d.path().join("mixed.abc");
    write_abc(&spec, &abc);
    let e = import(&abc, d.path()).0.unwrap_err();
    assert!(e.contains("meshes /a and /c/mesh differ in topology"), "{e}");
    // ... but they are one frame set: every mesh a sequence, every frame its own mesh.
    let set_path = d.path().join("mixed.frames");
    let o = surfcap!(&["--quiet", "import", p(&abc), "-o", p(&set_path)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let set = surfcap_mesh::frame_set_cache::read_frame_set(&set_path, &surfcap_mesh::NoProgress).unwrap();
    let seqs: Vec<(&str, usize)> = set.sequences().iter().map(|q| (q.name.as_str(), q.frames().len())).collect();
    assert_eq!(seqs, [("a", 2), ("c", 1)]);
    let (lo, hi) = set.vertex_count_range();
    assert!(lo < hi, "{lo}..{hi} vertices");
}

#[test]
fn varying_topology_irregular_times_and_hdf5_are_refused_by_name() {
    let d = tempfile::tempdir().unwrap();
    // The faces change at sample 2: every frame keeps its own topology: a frame set.
    let mut spec = json!({"objects": [{"type": "xform", "path": "/walk"}, sheet_mesh("/walk/mesh", 4, json!({}))]});
    let s2 = &mut spec["objects"][1]["samples"][2];
    s2["faceIndices"] = json!([0, 3, 4, 0, 4, 1, 1, 4, 2, 2, 4, 5, 4, 6, 5]);
    s2["faceCounts"] = json!([3, 3, 3, 3, 3]);
    spec["objects"][1]["samples"][3]["faceIndices"] = json!([0, 3, 4, 0, 4, 1, 1, 4, 2, 2, 4, 5, 4, 6, 5]);
    spec["objects"][1]["samples"][3]["faceCounts"] = json!([3, 3, 3, 3, 3]);
    let abc = d.path().join("varying.abc");
    write_abc(&spec, &abc);
    // As a subject: refused, saying what it is and where it can go.
    let e = import(&abc, d.path()).0.unwrap_err();
    let want = format!(
        "{} /walk/mesh: the topology changes at frame 2 (5 faces, was 4): imported as a frame set",
        abc.display()
    );
    assert!(e.contains(&want) && e.contains(".frames"), "{e}");
    // As a frame set: every frame with its own triangles.
    let frames = d.path().join("varying.frames");
    let o = surfcap!(&["--quiet", "import", p(&abc), "--fps", "30", "-o", p(&frames)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let set = surfcap_mesh::frame_set_cache::read_frame_set(&frames, &NoProgress).unwrap();
    let tris: Vec<usize> = set.sequences()[0].frames().iter().map(|f| f.n_triangles()).collect();
    assert_eq!(tris, [5, 5, 5, 5]);
    assert_eq!(set.sequences()[0].name, "walk");
    // A command that needs one topology, given the .abc itself: it says what the file is.
    let o = surfcap!(&["export", p(&abc), "--format", "glb", "-o", p(&d.path().join("v.glb"))]);
    assert!(!o.status.success() && stderr(&o).contains("is a frame set"), "{}", stderr(&o));
    let a = surfcap_formats::abc_read::read_abc(&abc).unwrap();
    let surfcap_formats::abc_read::AbcFrames::Varying { frames } = &a.meshes[0].frames else {
        panic!("expected varying frames")
    };
    let tris: Vec<usize> = frames.iter().map(|f| f.topology.n_triangles()).collect();
    assert_eq!(tris, [5, 5, 5, 5]);
    assert_ne!(frames[1].topology, frames[2].topology);
    assert_eq!(frames[3].positions, sheet_frame(3));
    assert_eq!(surfcap_testkit::read_abc(&abc)["meshes"][0]["topology_variance"], "kHeterogenousTopology");

    // Acyclic times: evenly spaced reads at their rate, irregular ones are refused.
    let mut spec = json!({"objects": [sheet_mesh("/even", 3, json!({}))]});
    spec["objects"][0].as_object_mut().unwrap().remove("fps");
    spec["objects"][0]["times"] = json!([1.0, 1.04, 1.08]);
    let abc = d.path().join("even.abc");
    write_abc(&spec, &abc);
    assert_eq!(import(&abc, d.path()).0.unwrap().fps, 25.0);
    spec["objects"][0]["times"] = json!([0.0, 0.04, 0.1]);
    let abc = d.path().join("irregular.abc");
    write_abc(&spec, &abc);
    let e = import(&abc, d.path()).0.unwrap_err();
    assert!(e.contains("/even: irregular sample times (sample 1 at 0.04 s, evenly spaced would be 0.05 s)"), "{e}");

    // The old HDF5 container.
    let h5 = d.path().join("old.abc");
    std::fs::write(&h5, b"\x89HDF\r\n\x1a\n\0\0\0\0\0\x08\x08\0\x04\0\x10\0").unwrap();
    let e = import(&h5, d.path()).0.unwrap_err();
    assert!(e.contains("old HDF5 container") && e.contains("abcconvert -toOgawa"), "{e}");
}

/// A real KayKit clip (10 frames, with its UVs when the template has them) written as Alembic by the reference library
/// (triangles in Alembic's clockwise order) imports back to the bit: topology, UVs, positions,
/// rate, up axis and units.
#[test]
fn a_real_kaykit_clip_written_by_alembic_imports_back_exactly() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let walk: PathBuf = data.join("kaykit_adventurers/knight_Walking_A");
    let src = surfcap_formats::import::import(&[walk], &Default::default(), &NoProgress).unwrap().subject;
    let t = src.topology();
    let nv = t.n_vertices();
    let frames = 10;
    let seq = &src.sequences()[0];
    let positions = &seq.positions()[..frames * nv * 3];
    let indices: Vec<u32> = t.triangles().iter().flat_map(|&[a, b, c]| [c, b, a]).collect();
    let mut mesh = json!({
        "type": "mesh", "path": "/knight_Walking_A/mesh", "time_per_cycle": 1.0 / src.fps,
        "samples": (0..frames).map(|k| {
            let mut s = json!({"P": points(&positions[k * nv * 3..(k + 1) * nv * 3])});
            if k == 0 {
                s["faceIndices"] = json!(indices);
                s["faceCounts"] = json!(vec![3; t.n_triangles()]);
            }
            s
        }).collect::<Vec<_>>(),
    });
    if let Some(uv) = t.uv() {
        mesh["uv"] = json!({
            "vals": uv.coords.iter().map(|c| json!([f(c[0]), f(c[1])])).collect::<Vec<_>>(),
            "indices": uv.corners.iter().flat_map(|&[a, b, c]| [c, b, a]).collect::<Vec<_>>(),
            "scope": "facevarying",
        });
    }
    let spec = json!({
        "metadata": {"surfcap_up_axis": src.up_axis.as_str(), "surfcap_units": src.units.name},
        "objects": [{"type": "xform", "path": "/knight_Walking_A"}, mesh],
    });
    let abc = d.path().join("knight.abc");
    write_abc(&spec, &abc);
    let (back, _) = import(&abc, d.path());
    let back = back.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back.topology(), t, "topology with UVs");
    assert_eq!((back.fps, back.up_axis, &back.units), (src.fps, src.up_axis, &src.units));
    let b = &back.sequences()[0];
    assert_eq!(b.name, "knight_Walking_A");
    assert_eq!(b.n_frames(), frames);
    assert!(b.positions() == positions, "positions differ");
    eprintln!(
        "KayKit knight_Walking_A: {nv} vertices, {} triangles, {frames} frames, {} bytes of Alembic",
        t.n_triangles(),
        std::fs::metadata(&abc).unwrap().len()
    );
}
