//! Every sequence under `../shared/data`: imported, checked against its `meta.json`, and
//! round-tripped through OBJ, PLY, npy, glb and the subject cache.
//!
//! OBJ, PLY, npy and the cache must give back the very same f32 positions (OBJ and ascii text is
//! written with the shortest decimal that reads back to the same f32). The glb stores each frame
//! as a displacement from the first, so base + (p - base) may differ from p by an f32 rounding:
//! it must be within 2 ulps of the largest coordinate magnitude.

use std::path::{Path, PathBuf};

use surfcap_formats::export::{ExportFormat, ExportOptions, export, safe_name};
use surfcap_formats::import::{ImportOptions, import};
use surfcap_formats::shared_layout::dataset_sequences;
use surfcap_mesh::{ErrorKind, NoProgress, Subject};

fn open(paths: &[PathBuf], fps: Option<f64>) -> Subject {
    import(paths, &ImportOptions { fps, ..Default::default() }, &NoProgress)
        .unwrap_or_else(|e| panic!("import {paths:?}: {e}"))
        .subject
}

fn assert_same(a: &Subject, b: &Subject, exact: bool, what: &str) {
    assert_eq!(a.topology().triangles(), b.topology().triangles(), "{what}: triangles");
    assert_eq!(a.sequences().len(), b.sequences().len(), "{what}: sequences");
    for (x, y) in a.sequences().iter().zip(b.sequences()) {
        assert_eq!(x.n_frames(), y.n_frames(), "{what}: frames of {}", x.name);
        if exact {
            assert!(x.positions() == y.positions(), "{what}: positions of {} differ", x.name);
        } else {
            let scale = x.positions().iter().fold(0f32, |m, v| m.max(v.abs()));
            let tol = 2.0 * f32::EPSILON * scale;
            let worst = x.positions().iter().zip(y.positions()).map(|(p, q)| (p - q).abs()).fold(0f32, f32::max);
            assert!(worst <= tol, "{what}: positions of {} differ by {worst} > {tol}", x.name);
        }
    }
}

fn round_trip(subject: &Subject, fps: f64, tmp: &Path) {
    let seq_name = safe_name(&subject.sequences()[0].name);
    let fps = Some(fps);
    for format in [ExportFormat::Obj, ExportFormat::Ply] {
        let out = tmp.join(format!("{format:?}"));
        export(subject, format, &out, ExportOptions::default(), &NoProgress).unwrap();
        let back = open(&[out.join(&seq_name)], fps);
        assert_same(subject, &back, true, &format!("{format:?}"));
    }
    let out = tmp.join("ascii");
    export(subject, ExportFormat::Ply, &out, ExportOptions { ply_ascii: true, force: false }, &NoProgress).unwrap();
    assert_same(subject, &open(&[out.join(&seq_name)], fps), true, "ascii PLY");

    let out = tmp.join("npy");
    export(subject, ExportFormat::Npy, &out, ExportOptions::default(), &NoProgress).unwrap();
    let back = open(std::slice::from_ref(&out), None);
    assert_same(subject, &back, true, "npy");
    assert_eq!(back.fps, subject.fps);
    assert_eq!(back.up_axis, subject.up_axis);
    assert_eq!(back.sequences()[0].joints, subject.sequences()[0].joints, "npy joints");

    let out = tmp.join("s.glb");
    export(subject, ExportFormat::Glb, &out, ExportOptions::default(), &NoProgress).unwrap();
    let back = open(&[out], None);
    assert_same(subject, &back, false, "glb");
    assert_eq!(back.sequences()[0].labels, subject.sequences()[0].labels);
    assert_eq!(back.fps, subject.fps);

    let out = tmp.join("cache");
    surfcap_mesh::cache::write_cache(&out, subject, false, &NoProgress).unwrap();
    let back = surfcap_mesh::cache::read_cache(&out, &NoProgress).unwrap();
    assert_eq!(&back, subject, "cache round trip");
}

/// Imports each sequence of a dataset on its own, checks it against meta.json, round-trips it.
fn check_dataset(name: &str) {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    let ds = data.join(name);
    let meta = surfcap_testkit::meta(&ds);
    let seqs = dataset_sequences(&ds).unwrap();
    let listed = meta["sequences"].as_object().expect("meta lists sequences");
    assert_eq!(seqs.len(), listed.len(), "{name}: sequence folders vs meta.json");
    let known_fps = |seq: &str| meta["sequences"][seq]["fps"].as_f64().or(meta["fps"].as_f64());
    let tmp = tempfile::tempdir().unwrap();
    for dir in &seqs {
        let seq = dir.file_name().unwrap().to_string_lossy().into_owned();
        let m = &listed[&seq];
        let fps = known_fps(&seq);
        if fps.is_none() {
            // The metadata does not know the frame rate: import must say so, not guess.
            let e = import(std::slice::from_ref(dir), &ImportOptions::default(), &NoProgress).unwrap_err();
            assert_eq!(e.kind, ErrorKind::Metadata, "{e}");
            assert!(e.to_string().contains("--fps"), "{e}");
        }
        let s = open(std::slice::from_ref(dir), fps.is_none().then_some(30.0));
        let q = &s.sequences()[0];
        assert_eq!(q.n_frames() as u64, m["frames"].as_u64().unwrap(), "{name}/{seq}: frames");
        assert_eq!(s.topology().n_vertices() as u64, m["vertices"].as_u64().unwrap(), "{name}/{seq}: vertices");
        let tris = m["triangles"].as_u64().or(m["faces"].as_u64()).unwrap();
        assert_eq!(s.topology().n_triangles() as u64, tris, "{name}/{seq}: triangles");
        if let Some(names) = meta["joint_names"].as_array() {
            let j = q.joints.as_ref().unwrap_or_else(|| panic!("{name}/{seq}: joints.npy expected"));
            assert_eq!(j.n_joints(), names.len());
        }
        if let Some(f) = fps {
            assert_eq!(s.fps, f);
        }
        round_trip(&s, s.fps, &tmp.path().join(&seq));
    }
}

#[test]
fn vlasic2008() {
    check_dataset("vlasic2008");
}

#[test]
fn sumner2004_horse() {
    check_dataset("sumner2004-horse");
}

#[test]
fn sumner2004_catlion() {
    check_dataset("sumner2004-catlion");
}

#[test]
fn briceno2003() {
    check_dataset("briceno2003");
}

#[test]
fn kaykit_adventurers() {
    check_dataset("kaykit_adventurers");
}

#[test]
fn robot_expressive() {
    check_dataset("robot_expressive");
}

#[test]
fn quake2_md2_players() {
    check_dataset("quake2_md2_players");
}

#[test]
fn threejs_morph_animals() {
    check_dataset("threejs_morph_animals");
}

#[test]
fn walking_cat_depraz() {
    check_dataset("walking_cat_depraz");
}

#[test]
fn every_dataset_is_covered() {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    let covered = [
        "vlasic2008",
        "sumner2004-horse",
        "sumner2004-catlion",
        "briceno2003",
        "kaykit_adventurers",
        "robot_expressive",
        "quake2_md2_players",
        "threejs_morph_animals",
        "walking_cat_depraz",
    ];
    for e in std::fs::read_dir(&data).unwrap() {
        let p = e.unwrap().path();
        let n = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() && !dataset_sequences(&p).unwrap().is_empty() {
            assert!(covered.contains(&n.as_str()), "dataset {n} has sequences but no test");
        }
    }
}

#[test]
fn head_scan_with_uv_atlas() {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    let s = open(&[data.join("leeperrysmith_head/template.obj")], Some(1.0));
    assert_eq!(s.topology().n_vertices(), 9279);
    let uv = s.topology().uv().expect("the head has a UV atlas");
    assert_eq!(uv.corners.len(), s.topology().n_triangles());
    let tmp = tempfile::tempdir().unwrap();
    surfcap_mesh::cache::write_cache(&tmp.path().join("c"), &s, false, &NoProgress).unwrap();
    assert_eq!(surfcap_mesh::cache::read_cache(&tmp.path().join("c"), &NoProgress).unwrap(), s);
}

#[test]
fn one_subject_from_many_clips_and_a_clear_error_for_different_topologies() {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    let k = data.join("kaykit_adventurers");
    let clips: Vec<PathBuf> =
        ["knight_Idle", "knight_Running_A", "knight_Walking_A"].iter().map(|c| k.join(c)).collect();
    let s = open(&clips, None);
    assert_eq!(s.sequences().len(), 3);
    assert!(surfcap_mesh::connected_components(s.topology()).count > 1, "KayKit meshes have separate parts");
    let ix = s.frame_index();
    let last = ix.len() - 1;
    assert_eq!(ix.locate(last), Some((2, s.sequences()[2].n_frames() - 1)));
    // A knight clip and a mage clip have different meshes: one subject cannot hold both.
    let e = import(&[k.join("knight_Idle"), k.join("mage_Idle")], &ImportOptions::default(), &NoProgress).unwrap_err();
    assert_eq!(e.kind, ErrorKind::TopologyMismatch);
    assert!(e.to_string().contains("mage_Idle"), "{e}");
    // The horse's collapse sequence was re-ordered into gallop's vertex order (data notice of
    // 2026-11-23): the dataset now imports as one subject of three sequences, 111 frames.
    let horse = match import(&[data.join("sumner2004-horse")], &ImportOptions::default(), &NoProgress) {
        Ok(h) => h.subject,
        Err(e) => panic!("the horse dataset should import as one subject: {e}"),
    };
    assert_eq!(horse.n_frames(), 111);
    assert_eq!(horse.sequences().len(), 3);
    assert_eq!(horse.topology().n_vertices(), 8431);
}
