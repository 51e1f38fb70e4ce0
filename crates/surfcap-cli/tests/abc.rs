//! `--format abc` read back by the reference Alembic library (PyPI `alembic3d`): for every
//! sequence its object path, sample count and times, topology (faces in Alembic's clockwise
//! order), every sample's positions to the bit, the frame box, UVs, the labels parameter, the
//! time sampling at the subject's rate, the archive's up axis and units, and the `Xform` that
//! turns a non-Y up axis onto +Y; every sample's velocities (units per second) to the bit, also
//! as surfcap's own reader gives them back.

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Checks every mesh of `a` (as the reference library reads it) against the subject.
fn check_meshes(a: &Value, s: &surfcap_mesh::Subject) {
    let meshes = a["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), s.sequences().len());
    let clockwise: Vec<u64> = s.topology().triangles().iter().flat_map(|t| [t[2], t[1], t[0]]).map(u64::from).collect();
    for (m, q) in meshes.iter().zip(s.sequences()) {
        assert_eq!(m["path"].as_str().unwrap(), format!("/{}/mesh", q.name));
        assert_eq!(m["samples"], q.n_frames());
        let times = floats(&m["times"]);
        let expected: Vec<f64> = (0..q.n_frames()).map(|f| f as f64 / s.fps).collect();
        for (t, e) in times.iter().zip(&expected) {
            assert!((t - e).abs() <= 1e-12 * e.max(1.0), "{}: time {t} instead of {e}", q.name);
        }
        // One frame: nothing moves, which Alembic calls constant.
        let variance = if q.n_frames() == 1 { "kConstantTopology" } else { "kHomogenousTopology" };
        assert_eq!(m["topology_variance"], variance);
        for f in 0..q.n_frames() {
            let counts = m["face_counts"][f].as_array().unwrap();
            assert!(counts.len() == s.topology().n_triangles() && counts.iter().all(|c| c == 3));
            let ix: Vec<u64> = m["face_indices"][f].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
            assert!(ix == clockwise, "{} frame {f}: faces differ", q.name);
            let got: Vec<f32> =
                m["positions"][f].as_array().unwrap().iter().flat_map(floats).map(|x| x as f32).collect();
            assert!(got == q.frame(f), "{} frame {f}: positions differ", q.name);
            // The frame's box (f64 of the f32 extremes).
            let b = &m["self_bounds"][f];
            for a in 0..3 {
                let (lo, hi) = q
                    .frame(f)
                    .chunks_exact(3)
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), v| (l.min(v[a]), h.max(v[a])));
                assert_eq!((b[0][a].as_f64().unwrap(), b[1][a].as_f64().unwrap()), (f64::from(lo), f64::from(hi)));
            }
        }
        // Velocities, units per second, as `.velocities` on every sample: the writer's finite
        // differences to the bit.
        let expected = surfcap_formats::vertex_velocity::vertex_velocities(q.positions(), q.n_vertices(), s.fps);
        let stride = q.n_vertices() * 3;
        for f in 0..q.n_frames() {
            let got: Vec<f32> =
                m["velocities"][f].as_array().unwrap().iter().flat_map(floats).map(|x| x as f32).collect();
            assert!(got == expected[f * stride..(f + 1) * stride], "{} frame {f}: velocities differ", q.name);
        }
        let labels: Vec<u64> = m["arb_geom_params"]["surfcap_synthetic"]["samples"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v[0].as_u64().unwrap())
            .collect();
        let expected: Vec<u64> =
            q.labels.iter().map(|l| u64::from(*l == surfcap_mesh::subject::FrameLabel::Synthetic)).collect();
        assert_eq!(labels, expected, "{}: labels", q.name);
        match s.topology().uv() {
            None => assert!(m["uvs"].is_null()),
            Some(uv) => {
                let u = &m["uvs"];
                assert_eq!((u["scope"].as_str().unwrap(), u["indexed"].as_bool().unwrap()), ("facevarying", true));
                let vals: Vec<f32> =
                    u["values"][0].as_array().unwrap().iter().flat_map(floats).map(|x| x as f32).collect();
                assert!(vals == uv.coords.iter().flatten().copied().collect::<Vec<_>>(), "{}: uv values", q.name);
                let ix: Vec<u64> = u["indices"][0].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
                let expected: Vec<u64> = uv.corners.iter().flat_map(|c| [c[2], c[1], c[0]]).map(u64::from).collect();
                assert_eq!(ix, expected, "{}: uv indices", q.name);
            }
        }
    }
    let ts = &a["time_samplings"][1];
    assert_eq!(ts["uniform"], true);
    assert_eq!(ts["time_per_cycle"].as_f64().unwrap(), 1.0 / s.fps);
    assert_eq!(ts["max_samples"], s.sequences().iter().map(|q| q.n_frames()).max().unwrap());
}

#[test]
fn abc_export_reads_back_exactly_in_the_reference_alembic_library() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let k = data.join("kaykit_adventurers");
    let (walk, run) = (k.join("knight_Walking_A"), k.join("knight_Running_A"));
    let subject = d.path().join("knight.subject");
    let o = surfcap!(&["--quiet", "import", p(&walk), p(&run), "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.path().join("knight.abc");
    let o = surfcap!(&["--quiet", "export", p(&subject), "--format", "abc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = surfcap_testkit::read_abc(&out);
    let s = surfcap_mesh::cache::read_cache(&subject, &surfcap_mesh::NoProgress).unwrap();
    check_meshes(&a, &s);
    // surfcap's own reader gives the velocities back too.
    let archive = surfcap_formats::abc_read::read_abc(&out).unwrap();
    for (m, q) in archive.meshes.iter().zip(s.sequences()) {
        let expected = surfcap_formats::vertex_velocity::vertex_velocities(q.positions(), q.n_vertices(), s.fps);
        assert!(m.velocities.as_deref() == Some(&expected[..]), "{}: velocities read back", q.name);
    }
    let md = a["archive_metadata"].as_str().unwrap();
    assert!(md.contains("surfcap_up_axis=+y") && md.contains("surfcap_units=m"), "{md}");
    // +Y up: each sequence's Xform is the identity.
    for q in s.sequences() {
        let x = &a["xforms"][format!("/{}", q.name)];
        assert_eq!(x["matrix"][1][1], 1.0, "{x}");
        assert_eq!(x["matrix"][2][2], 1.0, "{x}");
    }

    // UVs: the head scan (one frame) has a UV atlas.
    let head = data.join("leeperrysmith_head/template.obj");
    let out = d.path().join("head.abc");
    let o = surfcap!(&["--quiet", "export", p(&head), "--fps", "25", "--format", "abc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let opts = surfcap_formats::import::ImportOptions { fps: Some(25.0), ..Default::default() };
    let s = surfcap_formats::import::import(&[head], &opts, &surfcap_mesh::NoProgress).unwrap().subject;
    assert!(s.topology().uv().is_some(), "the head scan has UVs: the test checks them");
    check_meshes(&surfcap_testkit::read_abc(&out), &s);
}

#[test]
fn a_z_up_subject_gets_a_transform_onto_y_and_an_interpolation_keeps_its_labels() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let walk = data.join("kaykit_adventurers/knight_Walking_A");
    let subject = d.path().join("knight-z.subject");
    let o = surfcap!(&["--quiet", "import", p(&walk), "--up-axis", "+z", "--units", "cm", "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.path().join("knight-z.abc");
    let o = surfcap!(&["--quiet", "export", p(&subject), "--format", "abc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = surfcap_testkit::read_abc(&out);
    let md = a["archive_metadata"].as_str().unwrap();
    assert!(md.contains("surfcap_up_axis=+z") && md.contains("surfcap_units=cm"), "{md}");
    // Imath's row-vector matrix: +Z (row 2) goes to +Y.
    let m = &a["xforms"]["/knight_Walking_A"]["matrix"];
    assert_eq!(floats(&m[2])[..3], [0.0, 1.0, 0.0]);
    assert_eq!(floats(&m[1])[..3], [0.0, 0.0, -1.0]);

    let blend = d.path().join("blend.abc");
    let o = surfcap!(&[
        "--quiet",
        "interpolate",
        p(&walk),
        "--from",
        "knight_Walking_A:0",
        "--to",
        "knight_Walking_A:16",
        "--steps",
        "5",
        "--format",
        "abc",
        "-o",
        p(&blend)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = surfcap_testkit::read_abc(&blend);
    let labels: Vec<u64> = a["meshes"][0]["arb_geom_params"]["surfcap_synthetic"]["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v[0].as_u64().unwrap())
        .collect();
    assert_eq!(labels, [0, 1, 1, 1, 0]);
}

/// A frame set (every frame re-meshed on its own) as Alembic: a `PolyMesh` of heterogeneous
/// topology that the reference library reads frame by frame, and surfcap imports back as the
/// same frame set.
#[test]
fn a_frame_set_exports_as_heterogeneous_topology_and_comes_back() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let set = d.path().join("horse.frames");
    let src = data.join("threejs_morph_animals/horse_gallop");
    let o = surfcap!(&["--quiet", "remesh-frames", p(&src), "--seed", "4", "--frames", "5", "-o", p(&set)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.path().join("horse.abc");
    let o = surfcap!(&["--quiet", "export", p(&set), "--format", "abc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = surfcap_testkit::read_abc(&out);
    let m = &a["meshes"][0];
    assert_eq!(m["topology_variance"], "kHeterogenousTopology");
    // Vertices do not correspond between re-meshed frames: no velocities.
    assert!(m["velocities"].as_array().unwrap().iter().all(|v| v.is_null()), "no velocities on a frame set");
    let original = surfcap_mesh::frame_set_cache::read_frame_set(&set, &surfcap_mesh::NoProgress).unwrap();
    let frames = original.sequences()[0].frames();
    assert_eq!(m["samples"], frames.len());
    for (k, f) in frames.iter().enumerate() {
        let clockwise: Vec<u64> =
            f.topology().triangles().iter().flat_map(|t| [t[2], t[1], t[0]]).map(u64::from).collect();
        let ix: Vec<u64> = m["face_indices"][k].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
        assert!(ix == clockwise, "frame {k}: faces");
        let got: Vec<f32> = m["positions"][k].as_array().unwrap().iter().flat_map(floats).map(|x| x as f32).collect();
        assert!(got == f.positions(), "frame {k}: positions");
    }
    let back = d.path().join("back.frames");
    let o = surfcap!(&["--quiet", "import", p(&out), "-o", p(&back)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back = surfcap_mesh::frame_set_cache::read_frame_set(&back, &surfcap_mesh::NoProgress).unwrap();
    assert!(back.sequences()[0].frames() == frames, "the frame set comes back exactly");
    assert_eq!((back.fps, back.up_axis, &back.units), (original.fps, original.up_axis, &original.units));
    // A format of one topology refuses it by name.
    let o = surfcap!(&["export", p(&set), "--format", "pc2", "-o", p(&d.path().join("x.pc2"))]);
    assert!(!o.status.success() && stderr(&o).contains("expected glb, abc or obj"), "{}", stderr(&o));
}
