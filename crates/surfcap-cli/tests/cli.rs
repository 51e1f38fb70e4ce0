//! The `surfcap` program end to end: exit codes, error messages, JSON output, and `.glb` files
//! checked by the Khronos glTF validator.

use std::path::Path;
use std::process::Command;

use surfcap_testkit::{p, stderr, surfcap};

#[test]
fn demo_runs_and_its_glb_is_valid() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("demo");
    let o = surfcap!(&["demo", "-o", p(&out), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "mannequin.subject/subject.json",
        "export/mannequin.glb",
        "export/mannequin.json",
        "export/npy/meta.json",
        "export/pc2/walk.pc2",
    ] {
        assert!(out.join(f).is_file(), "demo did not write {f}");
    }
    assert!(out.join("export/obj/walk/frame_00090.obj").is_file());
    surfcap_testkit::validate_glb(&[
        out.join("export/mannequin.glb"),
        out.join("export/interpolation.glb"),
        out.join("export/path.glb"),
    ]);
    assert!(out.join("distances.npy").is_file());
    // The path-following step: its report says how closely the S-shaped path was followed.
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("export/path.report.json")).unwrap()).unwrap();
    assert!(r["mean_error"].as_f64().unwrap() < 0.3, "demo path error {}", r["mean_error"]);
    assert!(r["transitions"].as_u64().unwrap() > 0);
    assert!(out.join("s_path.csv").is_file());
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("export/mannequin.json")).unwrap()).unwrap();
    assert_eq!(side["sequences"][0]["frame_labels"][0], "original");
    // The report, and `surfcap view` on it: both animations, the page under /report/, nothing
    // outside the report folder.
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(html.contains("Pose distances") && html.contains("anim/path.glb"), "report: {html}");
    assert!(out.join("report/plots/distances.svg").is_file() && out.join("report/anim/path.report.json").is_file());
    let view = surfcap_testkit::ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(&out.join("report"))]);
    let (status, body) = view.get("/api/items");
    assert_eq!(status, 200);
    let items: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(items["items"].as_array().unwrap().len(), 2, "interpolation and path");
    assert!(items["items"].as_array().unwrap().iter().any(|it| it["overlay"]["curve"].is_array()), "path overlay");
    assert_eq!(view.get("/report/index.html").0, 200);
    assert_eq!(view.get("/report/plots/distances.svg").0, 200);
    assert_eq!(view.get("/report/../cache").0, 404);
    assert_eq!(view.get("/report/../mannequin.subject/subject.json").0, 404);
}

#[test]
fn import_info_export_on_real_data_with_valid_glb() {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("knight.subject");
    let k = data.join("kaykit_adventurers");
    let o = surfcap!(&[
        "import",
        p(&k.join("knight_Idle")),
        p(&k.join("knight_Running_A")),
        "-o",
        p(&subject),
        "--name",
        "knight",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["sequences"], 2);

    let o = surfcap!(&["info", p(&subject), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["vertices"], 2145);
    assert_eq!(info["fps"], 30.0);
    assert!(info["connected_components"].as_u64().unwrap() > 1);
    assert_eq!(info["sequences"][1]["name"], "knight_Running_A");
    assert_eq!(info["sequences"][0]["joints"], 41);

    let o = surfcap!(&["info", p(&subject)]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("components") && text.contains("knight_Running_A"), "{text}");

    let glb = tmp.path().join("knight.glb");
    let o = surfcap!(&["export", p(&subject), "--format", "glb", "-o", p(&glb), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let crane = tmp.path().join("crane.glb");
    let o = surfcap!(&["export", p(&data.join("vlasic2008/crane")), "--format", "glb", "-o", p(&crane), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A z-up subject is stored as is and turned upright by the node's rotation.
    let zup = tmp.path().join("cat_zup.glb");
    let o = surfcap!(&[
        "export",
        p(&data.join("walking_cat_depraz/walk")),
        "--format",
        "glb",
        "-o",
        p(&zup),
        "--fps",
        "25",
        "--up-axis",
        "+z",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    surfcap_testkit::validate_glb(&[glb, crane, zup]);

    for format in ["obj", "ply", "pc2", "npy"] {
        let out = tmp.path().join(format);
        let o = surfcap!(&[
            "export",
            p(&subject),
            "--format",
            format,
            "-o",
            p(&out),
            "--sequence",
            "knight_Idle",
            "--quiet",
        ]);
        assert!(o.status.success(), "{format}: {}", stderr(&o));
        assert!(out.join("frames.json").is_file() || out.join("meta.json").is_file(), "{format}: no sidecar");
    }
}

#[test]
fn user_errors_exit_1_and_name_the_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("frames");
    std::fs::create_dir(&dir).unwrap();
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(dir.join("f_1.obj"), tri).unwrap();
    std::fs::write(dir.join("f_2.obj"), tri).unwrap();
    std::fs::write(dir.join("f_10.obj"), tri.replace("f 1 3 4", "f 1 3 9")).unwrap();
    let o = surfcap!(&["import", p(&dir), "-o", p(&tmp.path().join("s")), "--fps", "30"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("f_10.obj") && e.contains("line 6") && e.contains("frame 2"), "{e}");
    assert!(!tmp.path().join("s").exists(), "nothing written on error");

    // Natural order: f_10 is the last frame, so a vertex-count mismatch there names frame 2.
    std::fs::write(dir.join("f_10.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    let o = surfcap!(&["import", p(&dir), "-o", p(&tmp.path().join("s")), "--fps", "30"]);
    let e = stderr(&o);
    assert!(e.contains("f_10.obj") && e.contains("3 vertices, expected 4") && e.contains("frame 2"), "{e}");

    // No frame rate: a clear request for one.
    std::fs::write(dir.join("f_10.obj"), tri).unwrap();
    let o = surfcap!(&["import", p(&dir), "-o", p(&tmp.path().join("s"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--fps"), "{}", stderr(&o));
    let o = surfcap!(&["import", p(&dir), "-o", p(&tmp.path().join("s")), "--fps", "30", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));

    let o = surfcap!(&["info", p(&tmp.path().join("missing"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing"), "{}", stderr(&o));

    let o = surfcap!(&["export", p(&tmp.path().join("s")), "--format", "fbx", "-o", "x"]);
    assert_eq!(o.status.code(), Some(1), "bad arguments are user errors");

    let o = surfcap!(&["info", p(&tmp.path().join("missing")), "--json"]);
    let v: serde_json::Value = serde_json::from_str(stderr(&o).trim()).expect("--json errors are JSON");
    assert!(v["error"].as_str().unwrap().contains("missing"));
}

#[test]
fn bad_npy_and_ply_are_reported_with_what_was_expected() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = tmp.path().join("seq");
    std::fs::create_dir(&seq).unwrap();
    std::fs::write(seq.join("template.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let npy = |descr: &str, shape: &str, data: usize| {
        let header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        let h = format!("{header}{}\n", " ".repeat(128 - 10 - header.len() - 1));
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(h.len() as u16).to_le_bytes());
        b.extend_from_slice(h.as_bytes());
        b.extend_from_slice(&vec![0u8; data]);
        std::fs::write(seq.join("positions.npy"), b).unwrap();
        let o = surfcap!(&["info", p(&seq), "--fps", "30"]);
        assert_eq!(o.status.code(), Some(1));
        assert!(stderr(&o).contains("positions.npy"), "{}", stderr(&o));
        stderr(&o)
    };
    assert!(npy("<i4", "(1, 3, 3)", 36).contains("expected float32"));
    assert!(npy("<f4", "(1, 4, 3)", 48).contains("expected positions of the template's 3 vertices of shape [*, 3, 3]"));
    assert!(npy("<f4", "(2, 3, 3)", 40).contains("file holds only 40"));
    let ply = tmp.path().join("x.ply");
    std::fs::write(&ply, "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0").unwrap();
    let o = surfcap!(&["info", p(&ply), "--fps", "30"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("x.ply") && stderr(&o).contains("file ends"), "{}", stderr(&o));
}

/// Import narrates what each source was read as; a lone template.obj is one
/// OBJ frame and says why; a positions.npy that is a FIFO is refused by name, without blocking.
/// A binary PLY holding more faces than its header declares is an error at a byte.
#[test]
fn import_says_what_it_detected_and_refuses_a_fifo_or_trailing_data() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = tmp.path().join("seq");
    std::fs::create_dir(&seq).unwrap();
    std::fs::write(
        seq.join("template.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
    )
    .unwrap();
    let out = tmp.path().join("s.subject");
    let o = surfcap!(&["import", p(&seq), "-o", p(&out), "--fps", "30"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!(
            "read {}: folder of 1 OBJ frame file (template.obj with no positions.npy beside it: read as one frame) \
             -> sequence \"seq\", 1 frame",
            seq.display()
        )),
        "{text}"
    );
    let o = surfcap!(&["import", p(&seq), "-o", p(&out), "--fps", "30", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["sources"][0]["frames"], 1);
    assert!(v["sources"][0]["layout"].as_str().unwrap().starts_with("folder of 1 OBJ frame file"));

    let fifo = seq.join("positions.npy");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let o = surfcap!(&["import", p(&seq), "-o", p(&tmp.path().join("t.subject")), "--fps", "30"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains(&format!("{}: is a FIFO (named pipe): expected a regular file", fifo.display())),
        "{}",
        stderr(&o)
    );
    assert!(!tmp.path().join("t.subject").exists());

    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    let header = ply.len();
    for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        ply.extend_from_slice(&x.to_le_bytes());
    }
    // Three faces where the header declares one: a count byte, then indices 0, 1, 2 as int32.
    let face: Vec<u8> = std::iter::once(3).chain([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes())).collect();
    ply.extend(face.repeat(3));
    let path = tmp.path().join("extra.ply");
    std::fs::write(&path, &ply).unwrap();
    let o = surfcap!(&["info", p(&path), "--fps", "30"]);
    assert_eq!(o.status.code(), Some(1));
    let want = format!("extra.ply: byte {}: 26 bytes of data after the last element", header + 36 + 13);
    assert!(stderr(&o).contains(&want), "{}", stderr(&o));
}

/// A BVH with `Frames: 0` panicked (exit 101); 100,000 nested joints overflowed
/// the stack (abort). Both are now errors naming the file (and the line of `Frames:`).
#[test]
fn bvh_without_frames_or_nested_deeply_is_an_error_not_a_crash() {
    let tmp = tempfile::tempdir().unwrap();
    let empty = tmp.path().join("empty.bvh");
    std::fs::write(
        &empty,
        "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n}\nMOTION\nFrames: 0\nFrame Time: 0.04\n",
    )
    .unwrap();
    let mut deep = String::from("HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n");
    for k in 1..100_000 {
        deep.push_str(&format!("JOINT j{k}\n{{\nOFFSET 0 1 0\n"));
    }
    deep.push_str(&"}\n".repeat(100_000));
    deep.push_str("MOTION\nFrames: 1\nFrame Time: 0.04\n1 2 3\n");
    let deep_path = tmp.path().join("deep.bvh");
    std::fs::write(&deep_path, deep).unwrap();
    for (bvh, want) in [
        (&empty, format!("{}: line 8: Frames: 0: expected at least one frame of motion", empty.display())),
        (&deep_path, "no BVH joint for the mannequin's \"pelvis\"".to_string()),
    ] {
        let o = surfcap!(&[
            "make",
            "mannequin",
            "--bvh",
            p(bvh),
            "--vertices",
            "1000",
            "-o",
            p(&tmp.path().join("x.subject"))
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(&want), "{}", stderr(&o));
    }
}

#[test]
fn manifest_with_tags_and_a_point_cache() {
    let tmp = tempfile::tempdir().unwrap();
    let demo = tmp.path().join("demo");
    assert!(surfcap!(&["demo", "-o", p(&demo), "--quiet"]).status.success());
    let manifest = tmp.path().join("surfcap.toml");
    std::fs::write(
        &manifest,
        format!(
            "name = \"tube\"\nfps = 30\nup_axis = \"+y\"\nunits = \"m\"\n\n[[sequence]]\nsource = \"{}\"\ntags = [\"crawl\"]\n\n\
             [[sequence]]\nsource = \"{}\"\ntemplate = \"{}\"\nname = \"jog_from_pc2\"\n",
            p(&demo.join("export/obj/walk")),
            p(&demo.join("export/pc2/jog.pc2")),
            p(&demo.join("export/pc2/template.obj"))
        ),
    )
    .unwrap();
    let o = surfcap!(&["info", p(&manifest), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["subject"], "tube");
    assert_eq!(v["sequences"][0]["tags"], serde_json::json!(["crawl"]));
    assert_eq!(v["sequences"][1]["name"], "jog_from_pc2");
    assert_eq!(v["frames"], 182);

    std::fs::write(&manifest, "name = \"tube\"\nfps = -3\n\n[[sequence]]\nsource = \"nowhere\"\n").unwrap();
    let o = surfcap!(&["info", p(&manifest)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("surfcap.toml") && stderr(&o).contains("line 2"), "{}", stderr(&o));
    std::fs::write(&manifest, "name = \"tube\"\nfrobnicate = 1\n").unwrap();
    let o = surfcap!(&["info", p(&manifest)]);
    assert!(stderr(&o).contains("line 2") && stderr(&o).contains("frobnicate"), "{}", stderr(&o));
}

#[test]
fn pose_metric_evaluation_on_kaykit_prefers_our_distance() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let k = data.join("kaykit_adventurers");
    let subject = tmp.path().join("knight.subject");
    let clips = ["knight_Idle", "knight_Running_A", "knight_Jump_Full_Short", "knight_Cheer"];
    let mut args: Vec<String> = vec!["import".into()];
    args.extend(clips.iter().map(|c| p(&k.join(c)).to_string()));
    args.extend(["-o".into(), p(&subject).into(), "--quiet".into()]);
    let o = surfcap!(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let out = tmp.path().join("pm");
    let cache = tmp.path().join("cache");
    let evaluate = |cache: &Path| {
        let args = ["--max-frames", "60", "--permutations", "500", "--classes", "5", "--json"];
        surfcap!(
            &[&["eval", "pose-metric", p(&subject), "-o", p(&out), "--cache-dir", p(cache)][..], &args[..]].concat(),
        )
    };
    let o = evaluate(&cache);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (ours, eucl) = (v["ours"]["pearson"].as_f64().unwrap(), v["euclidean"]["pearson"].as_f64().unwrap());
    assert!(ours > eucl, "Pearson ours {ours} vs Euclidean {eucl}");
    assert!(v["ours"]["mantel_p_value"].as_f64().unwrap() < 0.01);
    for f in ["pose-metric.json", "correlogram.svg", "correlogram.png"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Same seed, same numbers; the distance matrices now come from the cache.
    let again = evaluate(&cache);
    let w: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!(v["ours"], w["ours"]);
    assert_eq!(v["correlogram"], w["correlogram"]);
    // And the same whatever the number of threads (recomputed, not read from the cache).
    let one = Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .env("RAYON_NUM_THREADS", "1")
        .args(["eval", "pose-metric", p(&subject), "--max-frames", "60", "--permutations", "500", "--classes", "5"])
        .args(["-o", p(&out), "--cache-dir", p(&tmp.path().join("cache1")), "--json"])
        .output()
        .unwrap();
    let u: serde_json::Value = serde_json::from_slice(&one.stdout).unwrap();
    assert_eq!(v["ours"], u["ours"]);
    assert_eq!(v["euclidean"], u["euclidean"]);
}

#[test]
fn transitions_table_and_evaluation_on_the_horse() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let horse = data.join("sumner2004-horse/gallop");
    let cache = tmp.path().join("cache");
    let out = tmp.path().join("tr");
    let o = surfcap!(&["transitions", p(&horse), "-o", p(&out), "--cache-dir", p(&cache), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The gallop is one loop of 48 frames: segments of at most half of it (24 fps would give 8-48).
    assert_eq!((v["l_min"].as_u64(), v["l_max"].as_u64()), (Some(8), Some(24)), "bounds of a 48-frame loop");
    for f in ["D.npy", "L.npy", "li.npy", "lj.npy"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let ev = tmp.path().join("ev");
    let o = surfcap!(&[
        "eval",
        "transitions",
        p(&horse),
        "--slopes",
        "2,3",
        "-o",
        p(&ev),
        "--cache-dir",
        p(&cache),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for r in v["rows"].as_array().unwrap() {
        let m = |k: &str| r[k]["mean"].as_f64().unwrap();
        assert!(m("dtw_vls") <= m("dtw") && m("dtw") <= m("standard"), "{r}");
        assert!(r["pairs"].as_u64().unwrap() > 0);
    }
    for f in [
        "transitions.json",
        "costs.svg",
        "costs.png",
        "durations.svg",
        "durations.png",
        "distances.svg",
        "distances.png",
    ] {
        assert!(ev.join(f).is_file(), "{f}");
    }
}

#[test]
fn one_transition_is_blended_and_valid() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let horse = data.join("sumner2004-horse/gallop");
    let out = tmp.path().join("t.glb");
    let o = surfcap!(&[
        "transition",
        p(&horse),
        "--from",
        "gallop:2",
        "--to",
        "gallop:40",
        "-o",
        p(&out),
        "--cache-dir",
        p(&tmp.path().join("cache")),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let t = &v["transition"];
    let (cost, table) = (t["normalised_cost"].as_f64().unwrap(), t["table_cost"].as_f64().unwrap());
    assert!((cost - table).abs() <= 1e-9 * table.max(1.0), "warp recovered with the table's cost: {cost} vs {table}");
    let warp = t["warp"].as_array().unwrap();
    assert_eq!(warp.len() as u64, t["duration"].as_u64().unwrap());
    assert_eq!(warp[0], serde_json::json!([2, 40 + 1 - t["destination_length"].as_u64().unwrap()]));
    surfcap_testkit::validate_glb(std::slice::from_ref(&out));
    let side: serde_json::Value = serde_json::from_slice(&std::fs::read(tmp.path().join("t.json")).unwrap()).unwrap();
    let labels = side["sequences"][0]["frame_labels"].as_array().unwrap();
    assert_eq!(labels.len(), warp.len());
    assert_eq!(labels[0], "original");
    assert_eq!(labels[1], "synthetic");
    // The distance matrix around the transition, with the warp drawn on it.
    let svg = std::fs::read_to_string(tmp.path().join("t-dtw.svg")).unwrap();
    assert!(svg.contains("DTW warp") && svg.contains("<polyline"), "heat map with the warp");
    assert!(tmp.path().join("t-dtw.png").is_file());
    // A destination too close to its sequence start has no room for a segment.
    let o = surfcap!(&["transition", p(&horse), "--from", "gallop:2", "--to", "gallop:3", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no transition"), "{}", stderr(&o));
}

#[test]
fn synth_from_cmu_bvh_and_procedural_both_shapes_export_valid_glb() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let bvh = data.join("cmu_bvh");
    let heavy = tmp.path().join("heavy.subject");
    let o = surfcap!(&[
        "make",
        "mannequin",
        "--bvh",
        p(&bvh.join("16_15.bvh")),
        p(&bvh.join("16_17.bvh")),
        "--shape",
        "heavy",
        "--vertices",
        "4000",
        "-o",
        p(&heavy),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["fps"], 30.0);
    assert_eq!(v["sequences"][0]["name"], "16_15");
    assert_eq!(v["sequences"][0]["frames"], 117);
    assert_eq!(v["sequences"][1]["tags"], serde_json::json!(["walk", "turn_left"]));
    let slim = tmp.path().join("slim.subject");
    let args = [
        "make",
        "mannequin",
        "--procedural",
        "walk,jump",
        "--shape",
        "slim",
        "--seed",
        "3",
        "--vertices",
        "1500",
        "-o",
    ];
    let o = surfcap!(&[&args[..], &[p(&slim), "--quiet"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    // Same seed, same subject.
    let again = tmp.path().join("again.subject");
    assert!(surfcap!(&[&args[..], &[p(&again), "--quiet"]].concat()).status.success());
    let positions = |s: &Path| std::fs::read(s.join("positions_0.npy")).unwrap();
    assert_eq!(positions(&slim), positions(&again));
    let mut glbs = Vec::new();
    for s in [&heavy, &slim] {
        let glb = s.with_extension("glb");
        let o = surfcap!(&["export", p(s), "--format", "glb", "-o", p(&glb), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
        glbs.push(glb);
    }
    // Two shapes, two topologies.
    let info = |s: &Path| -> serde_json::Value {
        serde_json::from_slice(&surfcap!(&["info", p(s), "--json"]).stdout).unwrap()
    };
    assert_ne!(info(&heavy)["vertices"], info(&slim)["vertices"]);
    surfcap_testkit::validate_glb(&glbs);

    // Errors name what was wrong.
    let bad = tmp.path().join("bad.subject");
    for (args, want) in [
        (vec!["synth", "-o", p(&bad)], "--procedural"),
        (vec!["make", "mannequin", "--procedural", "walk,moonwalk", "-o", p(&bad)], "turn_left"),
        (vec!["make", "mannequin", "--procedural", "walk", "--shape", "tall", "-o", p(&bad)], "tall"),
        (vec!["make", "mannequin", "--bvh", "missing.bvh", "-o", p(&bad)], "missing.bvh"),
        (vec!["make", "mannequin", "--procedural", "walk", "--vertices", "50", "-o", p(&bad)], "from 1000 to 20000"),
    ] {
        let o = surfcap!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
    }
    assert!(!bad.exists(), "nothing written on error");
}

/// Thesis 3.3.3 on real captures (Vlasic crane and samba, Briceno dance): the essential graph's
/// shortest paths are never dearer than the motion graph's and cheaper on average, for every
/// alpha; `graph build` writes its files.
#[test]
fn essential_graph_beats_the_motion_graph_on_real_captures() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let crane = data.join("vlasic2008/crane");
    for subject in [data.join("vlasic2008/samba"), data.join("briceno2003/dance"), crane.clone()] {
        let o = surfcap!(&[
            "eval",
            "graphs",
            p(&subject),
            "--alpha",
            "0.01,0.05,0.2",
            "-o",
            p(&tmp.path().join("ge")),
            "--cache-dir",
            p(&cache),
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        for r in v["rows"].as_array().unwrap() {
            let mean = |g: &str| r[g]["mean"].as_f64().unwrap();
            let (mg, eg) = (mean("motion_graph"), mean("essential_graph"));
            assert!(eg < mg, "{}: alpha {}: essential {eg} vs motion {mg}", subject.display(), r["alpha"]);
            assert_eq!(r["pairs_where_motion_graph_is_cheaper"], 0);
            assert!(r["pairs_compared"].as_u64().unwrap() > 10_000);
        }
    }
    assert!(tmp.path().join("ge/density.svg").is_file() && tmp.path().join("ge/paths_alpha_0_2.png").is_file());
    let out = tmp.path().join("g");
    let o =
        surfcap!(&["graph", "build", p(&crane), "--alpha", "0.05", "-o", p(&out), "--cache-dir", p(&cache), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let g: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(g["cached"], true, "built by the evaluation above");
    assert_eq!(g["original_edges"], 174);
    for f in ["edges.npy", "weights.npy", "graph.json"] {
        assert!(out.join(f).is_file());
    }
    for (args, want) in
        [(vec!["--alpha", "0"], "--alpha"), (vec!["--kind", "kovar"], "expected essential, sparse-essential")]
    {
        let o = surfcap!(&[&["graph", "build", p(&crane), "-o", p(&out)][..], &args[..]].concat());
        assert_eq!(o.status.code(), Some(1));
        assert!(stderr(&o).contains(want), "{}", stderr(&o));
    }
}

/// Thesis Fig. 2.8 on a real capture: the non-linear interpolation distorts edges and volume
/// less than the linear blend; `-o` adds the curves over lambda as JSON, SVG and PNG.
#[test]
fn interpolation_evaluation_writes_its_curves() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let crane = data.join("vlasic2008/crane");
    let out = tmp.path().join("ei");
    let o = surfcap!(&["eval", "interpolation", p(&crane), "--pair", "crane:0,crane:90", "-o", p(&out), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let r = &v["rows"][0];
    for m in ["edge_distortion", "volume_change"] {
        assert!(r["nonlinear"][m].as_f64().unwrap() < r["linear"][m].as_f64().unwrap(), "{m}: {r}");
    }
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("interpolation.json")).unwrap()).unwrap();
    let sweep = j["sweeps"][0]["lambda_linear_edge_nonlinear_edge_linear_volume_nonlinear_volume"].as_array().unwrap();
    assert_eq!(sweep.len(), 11);
    for end in [&sweep[0], &sweep[10]] {
        assert!(
            end[1].as_f64().unwrap().abs() < 1e-3 && end[2].as_f64().unwrap().abs() < 1e-3,
            "no distortion at the ends: {end}"
        );
    }
    for f in ["distortion.svg", "distortion.png", "volume.svg", "volume.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

/// Thesis Fig. 6.4 on a real capture (Vlasic crane): the GPDM (d = 3) reconstructs its training
/// frames better than PCA with 3 components; the learning curve never rises; the plots, the
/// latent positions and the model are written; a missing sequence is a clear error.
#[test]
fn gpdm_evaluation_on_a_real_capture() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let crane = data.join("vlasic2008/crane");
    let out = tmp.path().join("gpdm");
    let args = ["--vertices", "200", "--max-frames", "100", "--samples", "2", "-o", p(&out), "--json"];
    let o = surfcap!(&[&["eval", "gpdm", p(&crane)][..], &args[..]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let e = &v["training_mean_vertex_error"];
    assert!(e["gpdm"].as_f64().unwrap() < e["pca"].as_f64().unwrap(), "{e}");
    let history: Vec<f64> = v["fit"]["history"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert!(history.len() > 10 && history.windows(2).all(|w| w[1] <= w[0]));
    assert_eq!(v["hmc"]["samples"], 2);
    assert_eq!((v["frame_stride"].as_u64(), v["sequences"][0]["frames"].as_u64()), (Some(2), Some(88)));
    for f in [
        "gpdm.json",
        "learning_curve.svg",
        "learning_curve.png",
        "latent.svg",
        "latent.png",
        "latent.npy",
        "gpdm.model.json",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let o = surfcap!(&["eval", "gpdm", p(&crane), "--sequences", "nope", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("nope") && stderr(&o).contains("crane"), "{}", stderr(&o));
}

/// `surfcap report` replaces an earlier report in its folder but never writes into another
/// non-empty folder; a missing --include is named.
#[test]
fn report_replaces_its_own_folder_only() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let crane = data.join("vlasic2008/crane");
    let cache = tmp.path().join("cache");
    let out = tmp.path().join("rep");
    for _ in 0..2 {
        let o = surfcap!(&["report", p(&crane), "-o", p(&out), "--cache-dir", p(&cache)]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("crane") && html.contains("Not computed yet"), "no cached distances: {html}");
    // An included folder's surfcap marker is not one of its results.
    let inc = tmp.path().join("inc");
    std::fs::create_dir(&inc).unwrap();
    std::fs::write(inc.join("scores.json"), r#"{"mean_error": 0.5}"#).unwrap();
    std::fs::write(inc.join(".surfcap-output.json"), r#"{"written_by": "surfcap", "kind": "eval-graphs"}"#).unwrap();
    let o = surfcap!(&["report", p(&crane), "-o", p(&out), "--cache-dir", p(&cache), "--include", p(&inc)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("mean_error") && !html.contains("eval-graphs"), "{html}");
    let other = tmp.path().join("site");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("index.html"), "<html>mine</html>").unwrap();
    let o = surfcap!(&["report", p(&crane), "-o", p(&other)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("did not write") && stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(other.join("index.html")).unwrap(), "<html>mine</html>");
    let missing = tmp.path().join("nope");
    let o = surfcap!(&["report", p(&crane), "-o", p(&out), "--include", p(&missing)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("nope"), "{}", stderr(&o));
}

/// A small real subject for the output tests: the three.js horse gallop (16 frames, 494 vertices).
fn small_source() -> Option<std::path::PathBuf> {
    Some(surfcap_testkit::shared_data()?.join("threejs_morph_animals/horse_gallop"))
}

/// Sorted names in `dir` (hidden ones included).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// The file names of `dir` that start with `prefix` (not the entries' content hashes).
fn files_starting(dir: &Path, prefix: &str) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| {
            let name = f.file_name().unwrap().to_string_lossy();
            name.starts_with(prefix) && !name.ends_with(".b3")
        })
        .collect();
    v.sort();
    v
}

/// A folder output replaces only an empty folder or surfcap's own earlier
/// output of the same kind; a folder holding anything else is refused (its files untouched)
/// unless --force.
#[test]
fn folder_outputs_never_replace_folders_surfcap_did_not_write() {
    let Some(src) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let keep = tmp.path().join("keep");
    std::fs::create_dir_all(keep.join("sub")).unwrap();
    std::fs::write(keep.join("notes.txt"), "mine").unwrap();
    std::fs::write(keep.join("sub/data.csv"), "1,2").unwrap();
    let subject = tmp.path().join("h.subject");
    let o = surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cache = tmp.path().join("c");
    let refused: Vec<Vec<&str>> = vec![
        vec!["import", p(&src), "-o", p(&keep)],
        vec!["export", p(&subject), "--format", "npy", "-o", p(&keep)],
        vec!["export", p(&subject), "--format", "obj", "-o", p(&keep)],
        vec!["export", p(&subject), "--format", "ply", "-o", p(&keep)],
        vec!["export", p(&subject), "--format", "pc2", "-o", p(&keep)],
        vec!["transitions", p(&subject), "-o", p(&keep), "--cache-dir", p(&cache)],
    ];
    for args in refused {
        let o = surfcap!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains("keep") && e.contains("did not write") && e.contains("--force"), "{args:?}: {e}");
        assert_eq!(names(&keep), ["notes.txt", "sub"], "{args:?} touched the folder");
        assert_eq!(std::fs::read_to_string(keep.join("sub/data.csv")).unwrap(), "1,2");
    }
    assert_eq!(names(tmp.path()), ["h.subject", "keep"], "no temporaries left");
    // Its own earlier output is replaced, again and again; another kind's is not.
    for _ in 0..2 {
        let o = surfcap!(&["export", p(&subject), "--format", "obj", "-o", p(&tmp.path().join("frames")), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = surfcap!(&["export", p(&subject), "--format", "npy", "-o", p(&tmp.path().join("frames"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("another kind of surfcap output (export-obj"), "{}", stderr(&o));
    // A subject cache written before the marker existed (the exact cache layout) is still
    // replaced; with a user's file beside it, it is not.
    std::fs::remove_file(subject.join(".surfcap-output.json")).unwrap();
    let o = surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_file(subject.join(".surfcap-output.json")).unwrap();
    std::fs::write(subject.join("my-notes.txt"), "x").unwrap();
    let o = surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(subject.join("my-notes.txt").is_file());
    // --force replaces the foreign folder.
    let o = surfcap!(&["import", p(&src), "-o", p(&keep), "--quiet", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(keep.join("subject.json").is_file() && !keep.join("notes.txt").exists());
}

/// An output that is, contains or lies inside an input is refused
/// before anything is written (`import src -o src` deleted the sources; `export dataset
/// --format npy -o dataset` deleted its licence).
#[test]
fn an_output_overlapping_an_input_is_refused() {
    let Some(src) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dataset = tmp.path().join("dataset");
    let seq = dataset.join("horse_gallop");
    std::fs::create_dir_all(&seq).unwrap();
    for f in ["template.obj", "positions.npy"] {
        std::fs::copy(src.join(f), seq.join(f)).unwrap();
    }
    std::fs::write(dataset.join("LICENSE.txt"), "CC0").unwrap();
    let meta = r#"{"source": "three.js", "license": "MIT", "fps": 30}"#;
    std::fs::write(dataset.join("meta.json"), meta).unwrap();
    let before = |f: &str| std::fs::read(seq.join(f)).unwrap();
    let (template, positions) = (before("template.obj"), before("positions.npy"));
    for (args, how) in [
        (vec!["import", p(&seq), "--fps", "10", "-o", p(&seq)], "is the input"),
        (vec!["import", p(&seq), "--fps", "10", "-o", p(&seq.join("x.subject"))], "lies inside the input"),
        (vec!["import", p(&seq), "--fps", "10", "-o", p(&dataset)], "contains the input"),
        (vec!["export", p(&dataset), "--format", "npy", "-o", p(&dataset)], "is the input"),
        (vec!["export", p(&dataset), "--format", "glb", "-o", p(&seq.join("positions.npy"))], "lies inside"),
        (vec!["distance", p(&dataset), "-o", p(&dataset.join("meta.json"))], "lies inside"),
    ] {
        let o = surfcap!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(how), "{args:?}: {}", stderr(&o));
    }
    assert_eq!(before("template.obj"), template);
    assert_eq!(before("positions.npy"), positions);
    assert_eq!(std::fs::read_to_string(dataset.join("LICENSE.txt")).unwrap(), "CC0");
    assert_eq!(std::fs::read_to_string(dataset.join("meta.json")).unwrap(), meta);
    assert_eq!(names(&dataset), ["LICENSE.txt", "horse_gallop", "meta.json"]);
    assert_eq!(names(&seq), ["positions.npy", "template.obj"]);
}

/// A file output replaces only a regular file: a device, a FIFO or a folder
/// is an error (and stays what it was); a symlink is written through to its target.
#[cfg(unix)]
#[test]
fn file_outputs_never_replace_devices_fifos_or_folders() {
    use std::os::unix::fs::FileTypeExt;
    let Some(src) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("h.subject");
    assert!(surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]).status.success());
    let fifo = tmp.path().join("pipe");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let dir = tmp.path().join("a-folder");
    std::fs::create_dir(&dir).unwrap();
    let cache = tmp.path().join("cache");
    for (out, what) in [("/dev/null", "a device"), ("/dev/full", "a device"), (p(&fifo), "FIFO"), (p(&dir), "a folder")]
    {
        for args in [
            vec!["export", p(&subject), "--format", "glb", "-o", out],
            vec!["distance", p(&subject), "-o", out, "--cache-dir", p(&cache)],
        ] {
            let o = surfcap!(&args);
            assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
            assert!(stderr(&o).contains(out) && stderr(&o).contains(what), "{args:?}: {}", stderr(&o));
        }
    }
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(names(&dir), Vec::<String>::new());
    // A symlink to a regular file is written through: the link stays, the target is replaced.
    let target = tmp.path().join("target.glb");
    std::fs::write(&target, "old").unwrap();
    let link = tmp.path().join("link.glb");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let o = surfcap!(&["export", p(&subject), "--format", "glb", "-o", p(&link), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert!(std::fs::read(&target).unwrap().starts_with(b"glTF"));
    let leftovers: Vec<String> = names(tmp.path()).into_iter().filter(|n| n.contains(".tmp-")).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Runs `args` until a temporary named `.NAME.tmp-PID` of `output` appears, then sends `signal`;
/// returns the exit code, or None when the run finished before the signal reached it.
#[cfg(unix)]
fn interrupt(args: &[&str], output: &Path, signal: i32) -> Option<i32> {
    use std::os::unix::process::ExitStatusExt;
    let mut child = Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let name = output.file_name().unwrap().to_string_lossy();
    let tmp = output.with_file_name(format!(".{name}.tmp-{}", child.id()));
    while !tmp.exists() {
        if child.try_wait().unwrap().is_some() {
            return None;
        }
        std::thread::yield_now();
    }
    // SAFETY: sending a signal to our own child process.
    unsafe { libc::kill(child.id() as i32, signal) };
    let status = child.wait().unwrap();
    assert_eq!(status.signal(), None, "the program must catch {signal}, not die of it");
    status.code().filter(|&c| c != 0)
}

/// SIGINT or SIGTERM during `export` removes the temporaries, keeps the
/// previous output and exits 130 or 143; a temporary of a killed run is swept by the next run.
#[cfg(unix)]
#[test]
fn an_interrupted_export_leaves_no_temporary_and_keeps_the_previous_output() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("crane.subject");
    let o = surfcap!(&["import", p(&data.join("vlasic2008/crane")), "-o", p(&subject), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (glb, obj) = (tmp.path().join("crane.glb"), tmp.path().join("frames"));
    for (format, out) in [("glb", &glb), ("obj", &obj)] {
        let o = surfcap!(&["export", p(&subject), "--format", format, "-o", p(out), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let glb_bytes = std::fs::read(&glb).unwrap();
    let frame = obj.join("crane/frame_00174.obj");
    let frame_bytes = std::fs::read(&frame).unwrap();
    let obj_names = names(&obj.join("crane"));
    let all = names(tmp.path());
    // A glb is written in a fraction of a second: retry until a signal lands during the write.
    for (format, out, signal, code) in
        [("obj", &obj, libc::SIGINT, 130), ("glb", &glb, libc::SIGTERM, 143), ("glb", &glb, libc::SIGINT, 130)]
    {
        let args = ["export", p(&subject), "--format", format, "-o", p(out)];
        let got = (0..50).find_map(|_| interrupt(&args, out, signal));
        assert_eq!(got, Some(code), "{format}: exit code after signal {signal}");
        assert_eq!(names(tmp.path()), all, "{format}: temporaries left behind");
        assert_eq!(std::fs::read(&glb).unwrap(), glb_bytes);
        assert_eq!(std::fs::read(&frame).unwrap(), frame_bytes);
        assert_eq!(names(&obj.join("crane")), obj_names);
    }
    // A killed run's temporaries (a PID no process has) are swept by the next export of that
    // output; names that are not exactly surfcap's pattern are left alone.
    let stale = [".crane.glb.tmp-99999999", ".frames.tmp-99999999"];
    std::fs::write(tmp.path().join(stale[0]), "half a glb").unwrap();
    std::fs::create_dir_all(tmp.path().join(stale[1]).join("crane")).unwrap();
    let user = [".crane.glb.tmp-99999999.bak", "crane.glb.tmp-99999999"];
    for u in user {
        std::fs::write(tmp.path().join(u), "user").unwrap();
    }
    for (format, out) in [("glb", &glb), ("obj", &obj)] {
        let o = surfcap!(&["export", p(&subject), "--format", format, "-o", p(out), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let mut expected = all.clone();
    expected.extend(user.map(String::from));
    expected.sort();
    assert_eq!(names(tmp.path()), expected);
}

/// `cd dir; surfcap import x -o .` is a clear error (the output folder is the
/// current folder, or contains the input), with no `.out.tmp-PID` left; a relative output with
/// `..` is written where it points.
#[test]
fn import_into_the_current_folder_is_a_clear_error() {
    let Some(src) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let run = |dir: &Path, args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_surfcap")).args(args).current_dir(dir).output().unwrap()
    };
    let o = run(&work, &["import", p(&src), "-o", "."]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("is the current folder"), "{}", stderr(&o));
    let seq = work.join("horse");
    std::fs::create_dir(&seq).unwrap();
    std::fs::copy(src.join("template.obj"), seq.join("template.obj")).unwrap();
    std::fs::copy(src.join("positions.npy"), seq.join("positions.npy")).unwrap();
    let o = run(&work, &["import", "horse", "--fps", "30", "-o", "."]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("contains the input horse"), "{}", stderr(&o));
    assert_eq!(names(&work), ["horse"]);
    assert_eq!(names(tmp.path()), ["work"]);
    let o = run(&work, &["import", "horse", "--fps", "30", "-o", "../missing/../h.subject", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(names(tmp.path()), ["h.subject", "work"]);
}

#[test]
fn misfitting_or_nan_cache_entries_are_recomputed_with_a_note() {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    use surfcap_mesh::cache_entry::store_file_entry;
    use surfcap_mesh::npy::{read_npy, write_npy};
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let cat = data.join("walking_cat_depraz/walk");
    let run = |args: &[&str]| {
        let mut all = args.to_vec();
        all.extend([p(&cat), "--fps", "25", "--cache-dir", p(&cache)]);
        let o = surfcap!(&all);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        o
    };
    let d_out = tmp.path().join("d.npy");
    run(&["distance", "-o", p(&d_out)]);
    run(&["graph", "build", "-o", p(&tmp.path().join("g"))]);
    let distance_file = files_starting(&cache, "distance-").pop().unwrap();
    let table_file = files_starting(&cache, "transitions-").pop().unwrap();
    let graph_file = files_starting(&cache, "graph-").pop().unwrap();
    let originals: std::collections::HashMap<&Path, _> =
        [&distance_file, &table_file, &graph_file].map(|f| (f.as_path(), read_npy::<f64>(f).unwrap())).into();
    let good = read_npy::<f64>(&distance_file).unwrap();
    let n = 35;
    assert_eq!(good.shape, [n, n]);
    let mut nan = good.data.clone();
    nan[n + 2] = f64::NAN;
    let zeros = vec![0.0f64; 4 * n * n];
    // Each damaged entry (another subject's 16 x 16 matrix, NaN inside the right shape, a
    // table whose lengths do not fit the frames, a graph edge of NaN weight) is read by every
    // command that needs it: a new segment length or alpha makes the product above it new.
    let (t_out, g_out) = (tmp.path().join("t"), tmp.path().join("g"));
    let cases: [(&Path, Vec<usize>, &[f64], &str); 5] = [
        (&distance_file, vec![16, 16], &[0.0; 256], "shape [16, 16], expected [35, 35]"),
        (&distance_file, vec![n, n], &nan, "entry (1, 2) is NaN"),
        (&table_file, vec![4, 16, 16], &zeros[..4 * 256], "shape [4, 16, 16]"),
        (&table_file, vec![4, n, n], &zeros, "source lengths"),
        (&graph_file, vec![2, 3], &[0.0, 1.0, f64::NAN, 1.0, 2.0, 0.5], "weight NaN"),
    ];
    // Segment lengths from 7 up: the cat's walk is one loop of 35 frames, so its default
    // segments are 6-17 frames, and a table of the default lengths is cached already.
    let mut fresh = 6;
    for (file, shape, values, problem) in cases {
        fresh += 1;
        let (l_min, alpha) = (fresh.to_string(), format!("0.0{fresh}"));
        let commands: Vec<Vec<&str>> = if file == distance_file.as_path() {
            vec![
                vec!["distance", "-o", p(&d_out)],
                vec!["transitions", "-o", p(&t_out), "--l-min", &l_min],
                vec!["graph", "build", "-o", p(&g_out), "--l-min", &l_min, "--l-max", "20"],
            ]
        } else if file == table_file.as_path() {
            vec![vec!["transitions", "-o", p(&t_out)], vec!["graph", "build", "-o", p(&g_out), "--alpha", &alpha]]
        } else {
            vec![vec!["graph", "build", "-o", p(&g_out)]]
        };
        for command in commands {
            // Stored with its content hash, so the entry's decoding is what refuses it.
            store_file_entry(file, |w| write_npy(w, &shape, values), &mut |_| {}).unwrap();
            let e = stderr(&run(&command));
            assert!(e.contains(&file.display().to_string()) && e.contains(problem), "{command:?}: {e}");
            assert!(e.contains("recomputing"), "{command:?}: {e}");
            assert_eq!(read_npy::<f64>(file).unwrap(), originals[file], "{command:?} replaced {}", file.display());
        }
    }
    let d = read_npy::<f64>(&d_out).unwrap();
    assert_eq!(d.data, good.data, "the recomputed matrix is the first one");
}

#[test]
fn numeric_options_are_checked_when_parsed() {
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let (subject, output) = (tmp.path().join("missing.subject"), tmp.path().join("out"));
    let (s, out) = (p(&subject), p(&output));
    for (args, option, range) in [
        (vec!["distance", s, "-o", out, "--w", "nan"], "'nan' for '--w <W>'", "a finite number >= 0"),
        (vec!["distance", s, "-o", out, "--w=-1"], "'-1' for '--w <W>'", "a finite number >= 0"),
        (vec!["info", s, "--fps", "0"], "'0' for '--fps <FPS>'", "a finite number > 0"),
        (vec!["synth", "path", s, "--curve", "c.csv", "-o", out, "--branching", "0"], "'0' for '--branching", ">= 1"),
        (vec!["synth", "path", s, "--curve", "c.csv", "-o", out, "--window", "inf"], "'inf' for '--window", "> 0"),
        (
            vec!["synth", "reach", s, "--from", "0", "--to", "1", "--distance", "nan", "--time", "4", "-o", out],
            "--distance",
            ">= 0",
        ),
        (
            vec!["synth", "reach", s, "--from", "0", "--to", "1", "--distance", "1", "--time", "0", "-o", out],
            "--time",
            "> 0",
        ),
        (vec!["interpolate", s, "--from", "0", "--to", "1", "--steps", "1", "-o", out], "'1' for '--steps", ">= 2"),
        (vec!["eval", "interpolation", s, "--pair", "0,1", "--lambda", "1.5"], "--lambda", "in [0, 1]"),
        (vec!["eval", "transitions", s, "--slopes", "2,0"], "'0' for '--slopes", ">= 1"),
        (vec!["transitions", s, "-o", out, "--l-min", "0"], "--l-min", ">= 1"),
        (vec!["graph", "build", s, "--alpha=-0.1"], "--alpha", "> 0"),
        (
            vec!["make", "mannequin", "--procedural", "walk", "--vertices", "50", "-o", out],
            "--vertices",
            "from 1000 to 20000",
        ),
    ] {
        let o = surfcap!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(option) && e.contains(range), "{args:?}: {e}");
    }
    let o = surfcap!(&["distance", s, "-o", out, "--w", "nan", "--cache-dir", p(&cache)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!cache.exists(), "nothing computed or cached");
}

#[test]
fn every_failure_under_json_is_one_json_object() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("missing");
    for (args, says) in [
        (vec!["--json", "distance", p(&missing), "-o", "d.npy", "--w", "nan"], "'--w <W>'"),
        (vec!["info", p(&missing), "--bogus", "--json"], "'--bogus'"),
        (vec!["--json", "frobnicate"], "'frobnicate'"),
        (vec!["info", p(&missing), "--json"], "missing"),
        (vec!["export", p(&missing), "-o", "x", "--json"], "required arguments were not provided: --format"),
        (vec!["export", p(&missing), "--format", "glb", "-o", "x", "--json"], "missing"),
    ] {
        let o = surfcap!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(o.stdout.is_empty(), "{args:?}: stdout {}", String::from_utf8_lossy(&o.stdout));
        let e = stderr(&o);
        let v: serde_json::Value =
            serde_json::from_str(e.trim()).unwrap_or_else(|_| panic!("{args:?}: not one JSON object: {e}"));
        assert!(v["error"].as_str().unwrap().contains(says), "{args:?}: {v}");
        assert_eq!(v["exit_code"], 1);
    }
    // Without --json, the same argument error is text.
    let o = surfcap!(&["frobnicate"]);
    assert!(stderr(&o).starts_with("error: unrecognized subcommand"), "{}", stderr(&o));
    // An internal error (a panic, reached through the tests' variable): one JSON object, exit 2.
    let seq = tmp.path().join("one.obj");
    std::fs::write(&seq, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .args(["info", p(&seq), "--fps", "30", "--json"])
        .env("SURFCAP_TEST_INTERNAL_ERROR", "1")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    let v: serde_json::Value = serde_json::from_str(stderr(&o).trim())
        .unwrap_or_else(|_| panic!("a panic under --json is not one JSON object: {}", stderr(&o)));
    assert!(v["error"].as_str().unwrap().contains("internal error"), "{v}");
    assert_eq!(v["exit_code"], 2);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .args(["info", p(&seq), "--fps", "30"])
        .env("SURFCAP_TEST_INTERNAL_ERROR", "1")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("surfcap: internal error"), "{}", stderr(&o));
}

#[test]
fn messages_pluralise_and_never_print_negative_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let seq = tmp.path().join("one.obj");
    std::fs::write(&seq, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = surfcap!(&["info", p(&seq), "--fps", "30"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("1 in 1 sequence at"), "{text}");
    let d = tmp.path().join("d.npy");
    let o = surfcap!(&[
        "distance",
        p(&seq),
        "--fps",
        "30",
        "-o",
        p(&d),
        "--no-cache",
        "--cache-dir",
        p(&tmp.path().join("c"))
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("mean 0.0000") && !text.contains("-0.0"), "{text}");
}

/// A glb grows linearly with its frame count (its morph weights are sparse, one
/// per key; they were keys x targets floats, 40 GB for 100,000 frames), stays valid for the
/// Khronos validator, and three.js's GLTFLoader reads the sparse weights: every key shows its own
/// frame.
#[test]
fn glb_size_is_linear_in_frames_and_three_js_reads_its_sparse_weights() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let flamingo = data.join("threejs_morph_animals/flamingo_fly");
    let size = |steps: usize| {
        let out = tmp.path().join(format!("i{steps}.glb"));
        let n = steps.to_string();
        let args = ["interpolate", p(&flamingo), "--from", "0", "--to", "7", "--method", "linear", "--steps", &n];
        let o = surfcap!(&[&args[..], &["-o", p(&out), "--quiet"]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        (std::fs::metadata(&out).unwrap().len() as f64, out)
    };
    let ((s1, _), (s2, glb), (s4, _)) = (size(1000), size(2000), size(4000));
    let (per_frame_low, per_frame_high) = ((s2 - s1) / 1000.0, (s4 - s2) / 2000.0);
    // 273 vertices x 12 bytes of morph target, plus its JSON; dense weights added 4 x frames.
    assert!(per_frame_low > 273.0 * 12.0 && per_frame_low < 273.0 * 12.0 + 600.0, "{per_frame_low} bytes per frame");
    assert!((per_frame_high - per_frame_low).abs() < 0.02 * per_frame_low, "{per_frame_low} then {per_frame_high}");
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));
    let three = surfcap_testkit::three_load_glb(std::slice::from_ref(&glb));
    assert_eq!(three[0]["targets"], 2000);
}

/// `distance` says what its values mean (per-triangle radians), and a motion
/// restriction on a subject without tags says so and how to add them.
#[test]
fn distance_scale_is_explained_and_an_untagged_subject_says_how_to_tag() {
    let Some(horse) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let d = tmp.path().join("d.npy");
    let o = surfcap!(&["distance", p(&horse), "-o", p(&d), "--cache-dir", p(&cache)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("scale: a distance is the sum over the "), "{text}");
    assert!(text.contains("rad (") && text.contains("degrees) per triangle"), "{text}");
    let o =
        surfcap!(&["distance", p(&horse), "-o", p(&d), "--cache-dir", p(&cache), "--json", "--metric", "euclidean"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["scale"].as_str().unwrap().contains("squared distance"), "{v}");

    let curve = tmp.path().join("c.csv");
    std::fs::write(&curve, "x,z\n0,0\n1,0\n").unwrap();
    let out = tmp.path().join("never.glb");
    let o = surfcap!(&["synth", "path", p(&horse), "--curve", p(&curve), "--tags", "run:0-1", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("the subject has no tags; tag its sequences in a surfcap.toml manifest"), "{e}");
    assert!(!e.contains("tags are"), "{e}");
    assert!(!out.exists());
}

/// Every output of a command is planned and checked before any work: a side file (the sidecar
/// beside a glb, the report beside an animation) replaces only surfcap's own earlier side file,
/// never an input or a file of the user's, and a side file that cannot be written leaves every
/// previous output as it was (and no new one).
#[cfg(unix)]
#[test]
fn side_files_replace_only_surfcaps_own_and_a_refusal_changes_nothing() {
    let Some(src) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let subject = t.join("h.subject");
    assert!(surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]).status.success());
    let user = r#"{"mine": true}"#;
    // The user's notes.json beside -o notes.glb.
    std::fs::write(t.join("notes.json"), user).unwrap();
    let o = surfcap!(&["export", p(&subject), "--format", "glb", "-o", p(&t.join("notes.glb"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("notes.json") && stderr(&o).contains("surfcap did not write"), "{}", stderr(&o));
    // The keys file is an input (and not surfcap's).
    std::fs::write(t.join("poses.json"), user).unwrap();
    let o = surfcap!(&[
        "synth",
        "keyposes",
        p(&subject),
        "--keys",
        p(&t.join("poses.json")),
        "-o",
        p(&t.join("poses.glb"))
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
    // A curve named like the report of -o x.glb.
    std::fs::write(t.join("x.report.json"), "0,0\n1,1\n").unwrap();
    let o =
        surfcap!(&["synth", "path", p(&subject), "--curve", p(&t.join("x.report.json")), "-o", p(&t.join("x.glb"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("x.report.json") && stderr(&o).contains("is the input"), "{}", stderr(&o));
    // The user's parts file beside -o knight.parts.glb of a transfer.
    std::fs::write(t.join("knight.parts.json"), user).unwrap();
    let motion = format!("{}:gallop", p(&subject));
    let model = t.join("no-model");
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", &motion, "-o", p(&t.join("knight.parts.glb"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("knight.parts.json") && stderr(&o).contains("did not write"), "{}", stderr(&o));
    for f in ["notes.json", "poses.json", "knight.parts.json"] {
        assert_eq!(std::fs::read_to_string(t.join(f)).unwrap(), user, "{f}");
    }
    assert_eq!(std::fs::read_to_string(t.join("x.report.json")).unwrap(), "0,0\n1,1\n");
    assert_eq!(names(t), ["h.subject", "knight.parts.json", "notes.json", "poses.json", "x.report.json"]);
    // surfcap's own sidecar is replaced, run after run, and says it is surfcap's.
    let glb = t.join("y.glb");
    for _ in 0..2 {
        let o = surfcap!(&["export", p(&subject), "--format", "glb", "-o", p(&glb), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let side: serde_json::Value = serde_json::from_slice(&std::fs::read(t.join("y.json")).unwrap()).unwrap();
    assert_eq!((side["written_by"].as_str(), side["output_kind"].as_str()), (Some("surfcap"), Some("export-sidecar")));
    assert!(side["fps"].is_number() && side["sequences"].is_array(), "{side}");
    // The sidecar's place is a folder, then a FIFO: refused before anything is replaced.
    std::fs::remove_file(t.join("y.json")).unwrap();
    std::fs::create_dir(t.join("y.json")).unwrap();
    let o = surfcap!(&["export", p(&subject), "--format", "glb", "-o", p(&glb)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("y.json") && stderr(&o).contains("a folder"), "{}", stderr(&o));
    std::fs::remove_dir(t.join("y.json")).unwrap();
    assert!(Command::new("mkfifo").arg(t.join("y.json")).status().unwrap().success());
    std::fs::write(&glb, b"previous").unwrap();
    let o = surfcap!(&["export", p(&subject), "--format", "glb", "-o", p(&glb)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("FIFO"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&glb).unwrap(), b"previous", "the previous glb is kept");
    // No previous output: nothing new is left behind.
    let o = surfcap!(&["export", p(&subject), "--format", "usda", "-o", p(&t.join("y.usda"))]);
    assert_eq!(o.status.code(), Some(1), "the sidecar y.json is a FIFO: {}", stderr(&o));
    assert!(!t.join("y.usda").exists());
    let leftovers: Vec<String> = names(t).into_iter().filter(|n| n.contains(".tmp-") || n.contains(".old-")).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// A forced run that fails leaves the user's folder as it was, with no surfcap marker in it, so
/// the next run without --force still refuses it; a forced run over a folder it could not remove
/// whole (read-only) is refused before anything is moved, never leaving the folder hidden.
#[cfg(unix)]
#[test]
fn a_failed_forced_run_leaves_the_users_folder_as_it_was() {
    use std::os::unix::fs::PermissionsExt;
    let Some(src) = small_source() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let subject = t.join("h.subject");
    assert!(surfcap!(&["import", p(&src), "-o", p(&subject), "--quiet"]).status.success());
    let user = t.join("userdir");
    std::fs::create_dir(&user).unwrap();
    std::fs::write(user.join("data.csv"), "1,2").unwrap();
    let o = surfcap!(&["vary", "train", p(&subject), "--sequences", "nope", "--force", "-o", p(&user)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("nope"), "{}", stderr(&o));
    assert_eq!(names(&user), ["data.csv"], "no marker left in the user's folder");
    let o = surfcap!(&["vary", "train", p(&subject), "--sequences", "nope", "-o", p(&user)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("did not write"), "still the user's folder: {}", stderr(&o));
    assert_eq!(names(&user), ["data.csv"]);
    // A read-only folder inside the output: --force is refused up front, the folder stays visible.
    let ro = t.join("ro");
    std::fs::create_dir_all(ro.join("locked")).unwrap();
    std::fs::write(ro.join("locked/mine.txt"), "user").unwrap();
    std::fs::set_permissions(ro.join("locked"), std::fs::Permissions::from_mode(0o555)).unwrap();
    let o = surfcap!(&["export", p(&subject), "--format", "obj", "--force", "-o", p(&ro)]);
    std::fs::set_permissions(ro.join("locked"), std::fs::Permissions::from_mode(0o755)).unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("not writable"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(ro.join("locked/mine.txt")).unwrap(), "user");
    assert_eq!(names(t), ["h.subject", "ro", "userdir"], "nothing hidden beside it");
}
