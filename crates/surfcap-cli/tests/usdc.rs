//! `.usdc` (USD's binary crate format) as surfcap writes it, read by Pixar's USD (usd-core, in
//! `tools/venv`) and by surfcap's own reader: the Vlasic crane (175 frames x 10,002 vertices)
//! exported, and a synthesised animation (samba key poses: original and synthetic frames); points,
//! velocities, topology, time codes, labels and layer metadata compared to the bit; a damaged
//! file refused naming it and what is wrong.

use surfcap_mesh::NoProgress;
use surfcap_testkit::{p, stderr, surfcap};

/// Compares what usd-core read (`read_usd`'s JSON) with surfcap's reading of the same file and
/// with `expected` (the subject written): everything to the bit. Returns usd-core's reading.
fn same_in_both_readers(file: &std::path::Path, expected: Option<&surfcap_mesh::Subject>) -> serde_json::Value {
    let u = surfcap_testkit::read_usd(file);
    let stage = surfcap_formats::usda_read::read_usda(file).unwrap();
    assert_eq!(u["time_codes_per_second"].as_f64(), stage.fps, "time codes per second");
    assert_eq!(u["start"], 0.0);
    assert_eq!(u["up_axis"] == "Z", stage.up_axis == Some(surfcap_mesh::UpAxis::PosZ), "up axis");
    let meshes = u["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), stage.meshes.len());
    let floats = |v: &serde_json::Value| -> Vec<f32> {
        v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect()
    };
    let mut longest = 0.0f64;
    for (k, (m, s)) in meshes.iter().zip(&stage.meshes).enumerate() {
        assert_eq!(m["path"].as_str().unwrap(), s.path);
        let n = s.times.len();
        let times: Vec<f64> = m["times"].as_array().unwrap().iter().map(|t| t.as_f64().unwrap()).collect();
        assert_eq!(times, s.times, "{}: time codes", s.path);
        assert_eq!(times, (0..n).map(|f| f as f64).collect::<Vec<_>>(), "{}: one sample a frame from 0", s.path);
        longest = longest.max(n as f64 - 1.0);
        let counts = m["face_vertex_counts"].as_array().unwrap();
        assert!(counts.len() == s.topology.n_triangles() && counts.iter().all(|c| c == 3));
        let ix: Vec<u32> =
            m["face_vertex_indices"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as u32).collect();
        let tris: Vec<u32> = s.topology.triangles().iter().flatten().copied().collect();
        assert_eq!(ix, tris, "{}: faces", s.path);
        let stride = s.positions.len() / n;
        for (f, frame) in m["points"].as_array().unwrap().iter().enumerate() {
            assert!(floats(frame) == s.positions[f * stride..(f + 1) * stride], "{} frame {f}: points", s.path);
        }
        // Velocities: as usd-core reads them, surfcap reads them, and the writer's finite
        // differences of the points.
        let expected_v =
            surfcap_formats::vertex_velocity::vertex_velocities(&s.positions, stride / 3, stage.fps.unwrap());
        let got_v = s.velocities.as_deref().unwrap();
        assert!(got_v == expected_v, "{}: velocities read by surfcap", s.path);
        for (f, frame) in m["velocities"].as_array().unwrap().iter().enumerate() {
            assert!(floats(frame) == got_v[f * stride..(f + 1) * stride], "{} frame {f}: velocities", s.path);
        }
        let labels: Vec<u64> = m["labels"].as_array().unwrap().iter().map(|l| l.as_u64().unwrap()).collect();
        let ours: Vec<u64> = s
            .labels
            .as_ref()
            .unwrap()
            .iter()
            .map(|l| u64::from(*l == surfcap_mesh::subject::FrameLabel::Synthetic))
            .collect();
        assert_eq!(labels, ours, "{}: frame labels", s.path);
        if let Some(e) = expected {
            let q = &e.sequences()[k];
            assert!(s.positions == q.positions(), "{}: the subject's positions", s.path);
            assert!(s.topology.first_difference(e.topology()).is_none());
            let want: Vec<u64> =
                q.labels.iter().map(|l| u64::from(*l == surfcap_mesh::subject::FrameLabel::Synthetic)).collect();
            assert_eq!(labels, want);
        }
    }
    assert_eq!(u["end"].as_f64().unwrap(), longest, "endTimeCode: the last frame");
    u
}

#[test]
fn usdc_export_of_the_crane_reads_back_exactly_in_pixars_usd_and_in_surfcap() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let crane = data.join("vlasic2008/crane");
    let out = d.path().join("crane.usdc");
    let o = surfcap!(&["--quiet", "export", p(&crane), "--format", "usdc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read(&out).unwrap().starts_with(b"PXR-USDC"));
    let s = surfcap_formats::import::import(&[crane], &Default::default(), &NoProgress).unwrap().subject;
    assert_eq!((s.n_frames(), s.topology().n_vertices()), (175, 10002));
    let u = same_in_both_readers(&out, Some(&s));
    assert_eq!(u["meshes"].as_array().unwrap().len(), 1);
    assert_eq!(u["meters_per_unit"].as_f64(), s.units.metres_per_unit);
    assert_eq!(u["frames_per_second"].as_f64(), Some(s.fps));
    // Imported back: the same subject (name, frames, topology, rate, up axis, units).
    let back = d.path().join("back.subject");
    let o = surfcap!(&["--quiet", "import", p(&out), "-o", p(&back)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let b = surfcap_mesh::cache::read_cache(&back, &NoProgress).unwrap();
    assert_eq!((b.fps, b.up_axis, &b.units), (s.fps, s.up_axis, &s.units));
    assert!(b.sequences()[0].positions() == s.sequences()[0].positions());
    // The binary encoding is smaller than the text one (the same stage: surfcap's own readings
    // of both agree).
    let text = d.path().join("crane.usda");
    let o = surfcap!(&["--quiet", "export", p(&out), "--format", "usda", "-o", p(&text)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, c) =
        (surfcap_formats::usda_read::read_usda(&text).unwrap(), surfcap_formats::usda_read::read_usda(&out).unwrap());
    assert!(a.meshes[0].positions == c.meshes[0].positions && a.meshes[0].velocities == c.meshes[0].velocities);
    assert_eq!((a.fps, a.up_axis, &a.units, &a.meshes[0].labels), (c.fps, c.up_axis, &c.units, &c.meshes[0].labels));
    let size = |f: &std::path::Path| std::fs::metadata(f).unwrap().len();
    assert!(size(&out) < size(&text) / 2, "usdc {} bytes, usda {}", size(&out), size(&text));
}

#[test]
fn a_synthesised_animation_as_usdc_reads_back_exactly_in_pixars_usd() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("samba.usdc");
    let keys = surfcap_testkit::workspace_root().join("examples/samba_keys.csv");
    let samba = data.join("vlasic2008/samba");
    let o =
        surfcap!(&["--quiet", "synth", "keyposes", p(&samba), "--keys", p(&keys), "--format", "usdc", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(same_in_both_readers(&out, None)["meshes"].as_array().unwrap().len(), 1);
    let stage = surfcap_formats::usda_read::read_usda(&out).unwrap();
    let labels = stage.meshes[0].labels.as_ref().unwrap();
    assert!(
        labels.contains(&surfcap_mesh::subject::FrameLabel::Synthetic)
            && labels.contains(&surfcap_mesh::subject::FrameLabel::Original),
        "a synthesised animation has original and synthetic (transition) frames"
    );
}

#[test]
fn a_damaged_usdc_is_refused_naming_the_file_and_what_is_wrong() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let good = d.path().join("knight.usdc");
    let walk = data.join("kaykit_adventurers/knight_Walking_A");
    let o = surfcap!(&["--quiet", "export", p(&walk), "--format", "usdc", "-o", p(&good)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&good).unwrap();
    // Cut in half: the table of contents is gone.
    let cut = d.path().join("cut.usdc");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let o = surfcap!(&["import", p(&cut), "-o", p(&d.path().join("a.subject"))]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("cut.usdc") && e.contains("table of contents") && e.contains("past the end of the file"), "{e}");
    // A crate version usd-core no longer reads either.
    let mut old = bytes.clone();
    old[9] = 3;
    let old_path = d.path().join("old.usdc");
    std::fs::write(&old_path, &old).unwrap();
    let o = surfcap!(&["import", p(&old_path), "-o", p(&d.path().join("b.subject"))]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("old.usdc") && e.contains("version 0.3.0") && e.contains("0.4.0 to 0.14.0"), "{e}");
}
