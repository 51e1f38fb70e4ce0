//! `--format usda` read back by Pixar's USD (usd-core): topology, every time sample's points to
//! the bit, sample count and times, time codes per second, up axis, metres per unit, labels
//! (an interpolation's labels as USD reads them: `tests/usd_import.rs`).

use surfcap_testkit::{p, stderr, surfcap};

#[test]
fn usda_export_reads_back_exactly_in_pixars_usd() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let k = data.join("kaykit_adventurers");
    let (walk, run) = (k.join("knight_Walking_A"), k.join("knight_Running_A"));
    let subject = d.path().join("knight.subject");
    let o = surfcap!(&["--quiet", "import", p(&walk), p(&run), "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.path().join("knight.usda");
    let o = surfcap!(&["--quiet", "export", p(&subject), "--format", "usda", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let u = surfcap_testkit::read_usd(&out);
    assert_eq!(u["time_codes_per_second"], 30.0);
    assert_eq!(u["frames_per_second"], 30.0);
    assert_eq!(u["up_axis"], "Y");
    assert_eq!(u["meters_per_unit"], 1.0);
    let s =
        surfcap_formats::import::import(&[walk, run], &Default::default(), &surfcap_mesh::NoProgress).unwrap().subject;
    let meshes = u["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 2);
    let tris: Vec<u64> = s.topology().triangles().iter().flatten().map(|&v| v as u64).collect();
    for (m, q) in meshes.iter().zip(s.sequences()) {
        assert_eq!(m["path"].as_str().unwrap(), format!("{}/{}/mesh", u["default_prim"].as_str().unwrap(), q.name));
        let counts = m["face_vertex_counts"].as_array().unwrap();
        assert!(counts.len() == s.topology().n_triangles() && counts.iter().all(|c| c == 3));
        let ix: Vec<u64> = m["face_vertex_indices"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
        assert_eq!(ix, tris);
        let times: Vec<f64> = m["times"].as_array().unwrap().iter().map(|t| t.as_f64().unwrap()).collect();
        assert_eq!(times, (0..q.n_frames()).map(|f| f as f64).collect::<Vec<_>>());
        for (f, frame) in m["points"].as_array().unwrap().iter().enumerate() {
            let got: Vec<f32> = frame.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
            assert!(got == q.frame(f), "{} frame {f} differs", q.name);
        }
        assert_eq!(m["labels"].as_array().unwrap().len(), q.n_frames());
        // Velocities: one sample per frame, units per second, the writer's finite differences to
        // the bit.
        let expected = surfcap_formats::vertex_velocity::vertex_velocities(q.positions(), q.n_vertices(), s.fps);
        let vs = m["velocities"].as_array().unwrap();
        assert_eq!(vs.len(), q.n_frames(), "{}: one velocity sample per frame", q.name);
        let stride = q.n_vertices() * 3;
        for (f, frame) in vs.iter().enumerate() {
            let got: Vec<f32> = frame.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
            assert!(got == expected[f * stride..(f + 1) * stride], "{} frame {f}: velocities differ", q.name);
        }
    }
    // surfcap's own reader gives the velocities back too.
    let stage = surfcap_formats::usda_read::read_usda(&out).unwrap();
    for (m, q) in stage.meshes.iter().zip(s.sequences()) {
        let expected = surfcap_formats::vertex_velocity::vertex_velocities(q.positions(), q.n_vertices(), s.fps);
        assert!(m.velocities.as_deref() == Some(&expected[..]), "{}: velocities read back", q.name);
    }
}

/// Velocities are the derivative of the points: on a real animation (the KayKit knight walking), as USD
/// reads them, a middle frame's velocities are the central difference of its neighbours'
/// points, in units per second.
#[test]
fn usda_velocities_are_the_points_central_difference() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let cat = data.join("kaykit_adventurers/knight_Walking_A");
    let out = d.path().join("knight.usda");
    let o = surfcap!(&["--quiet", "export", p(&cat), "--format", "usda", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let u = surfcap_testkit::read_usd(&out);
    let fps = u["time_codes_per_second"].as_f64().unwrap();
    let m = &u["meshes"][0];
    let pts =
        |f: usize| -> Vec<f64> { m["points"][f].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect() };
    let v: Vec<f64> = m["velocities"][5].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let (a, b) = (pts(4), pts(6));
    let mut moving = 0;
    for i in 0..v.len() {
        let expected = (b[i] - a[i]) * fps / 2.0;
        assert!((v[i] - expected).abs() <= 1e-4 * expected.abs().max(1.0), "coordinate {i}: {} vs {expected}", v[i]);
        moving += usize::from(expected.abs() > 1e-3);
    }
    assert!(moving > 0, "the knight moves between frames 4 and 6");
}
