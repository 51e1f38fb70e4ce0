//! The Alembic export loaded in real Blender: `bpy` (Blender 5.0 as a Python module, PyPI, in its
//! own environment `tools/venv-blender`, which scripts/setup installs: its numpy < 2 pin cannot
//! share tools/venv) imports the archive with Blender's own Alembic importer
//! (tools/blender-import-check.py). The mesh sequence comes in with its frames: the frame range,
//! every vertex at several frames as Blender evaluates it, and the velocities Blender reads
//! (its `velocity` attribute, for motion blur) match what surfcap wrote.

use surfcap_testkit::{p, stderr, surfcap};

#[test]
fn blender_imports_the_alembic_mesh_sequence_with_its_frames_and_velocities() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let root = surfcap_testkit::workspace_root();
    let python = root.join("tools/venv-blender/bin/python");
    assert!(python.is_file(), "{} is missing: run scripts/setup (it installs bpy there)", python.display());
    let d = tempfile::tempdir().unwrap();
    let knight = data.join("kaykit_adventurers/knight_Walking_A");
    let subject = d.path().join("knight.subject");
    let o = surfcap!(&["--quiet", "import", p(&knight), "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.path().join("knight.abc");
    let o = surfcap!(&["--quiet", "export", p(&subject), "--format", "abc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = surfcap_mesh::cache::read_cache(&subject, &surfcap_mesh::NoProgress).unwrap();
    let q = &s.sequences()[0];
    let last = q.n_frames() - 1;
    let frames = [0, 1, last / 2, last];
    let list = frames.iter().map(|f| f.to_string()).collect::<Vec<_>>().join(",");
    let o = std::process::Command::new(&python)
        .arg(root.join("tools/blender-import-check.py"))
        .args([p(&out), "--fps", &s.fps.to_string(), "--frames", &list])
        .output()
        .expect("python runs");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "Blender failed:\n{text}\n{}", String::from_utf8_lossy(&o.stderr));
    let line = text.lines().find_map(|l| l.strip_prefix("RESULT ")).unwrap_or_else(|| panic!("no RESULT in:\n{text}"));
    let r: serde_json::Value = serde_json::from_str(line).unwrap();
    assert!(r["blender"].as_str().unwrap().starts_with('5'), "{}", r["blender"]);
    // The importer sets the scene to the archive's frames.
    assert_eq!((r["frame_start"].as_u64().unwrap(), r["frame_end"].as_u64().unwrap()), (0, last as u64), "{r}");
    let meshes = r["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 1, "{r}");
    let m = &meshes[0];
    assert!(m["modifiers"].as_array().unwrap().iter().any(|x| x == "MESH_SEQUENCE_CACHE"), "{m}");
    let velocities = surfcap_formats::vertex_velocity::vertex_velocities(q.positions(), q.n_vertices(), s.fps);
    let stride = q.n_vertices() * 3;
    for f in frames {
        let e = &m["frames"][f.to_string()];
        assert_eq!(e["vertices"].as_u64().unwrap() as usize, q.n_vertices(), "frame {f}");
        assert_eq!(e["polygons"].as_u64().unwrap() as usize, s.topology().n_triangles(), "frame {f}");
        let got: Vec<f32> = e["positions"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        assert!(got == q.frame(f), "frame {f}: Blender's vertices differ from the subject's");
        let v: Vec<f32> = e["velocities"]
            .as_array()
            .unwrap_or_else(|| panic!("frame {f}: no velocity attribute in {}", e["attributes"]))
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect();
        assert!(v == velocities[f * stride..(f + 1) * stride], "frame {f}: Blender's velocities differ");
    }
    // The frames differ: the sequence plays (the walk is a loop: its last frame is its first).
    assert!(m["frames"]["0"]["positions"] != m["frames"][(last / 2).to_string()]["positions"]);
}
