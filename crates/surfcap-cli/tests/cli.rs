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

/// Issue 15 case 11: import narrates what each source was read as; a lone template.obj is one
/// OBJ frame and says why; a positions.npy that is a FIFO is refused by name, without blocking.
/// Case 12: a binary PLY holding more faces than its header declares is an error at a byte.
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

/// Issue 15 case 5: `Frames: 0` panicked (exit 101); case 8: 100,000 nested joints overflowed
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
        let o = surfcap!(&["synth", "--bvh", p(bvh), "--vertices", "1000", "-o", p(&tmp.path().join("x.subject"))]);
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
    assert_eq!((v["l_min"].as_u64(), v["l_max"].as_u64()), (Some(8), Some(48)), "24 fps bounds");
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
        "synth",
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
    let args = ["synth", "--procedural", "walk,jump", "--shape", "slim", "--seed", "3", "--vertices", "1500", "-o"];
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
        (vec!["synth", "--procedural", "walk,moonwalk", "-o", p(&bad)], "turn_left"),
        (vec!["synth", "--procedural", "walk", "--shape", "tall", "-o", p(&bad)], "tall"),
        (vec!["synth", "--bvh", "missing.bvh", "-o", p(&bad)], "missing.bvh"),
        (vec!["synth", "--procedural", "walk", "--vertices", "50", "-o", p(&bad)], "1,000 to 20,000"),
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
    for (args, want) in [(vec!["--alpha", "0"], "--alpha"), (vec!["--kind", "kovar"], "essential or motion")] {
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
    let other = tmp.path().join("site");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("index.html"), "<html>mine</html>").unwrap();
    let o = surfcap!(&["report", p(&crane), "-o", p(&other)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("not empty"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(other.join("index.html")).unwrap(), "<html>mine</html>");
    let missing = tmp.path().join("nope");
    let o = surfcap!(&["report", p(&crane), "-o", p(&out), "--include", p(&missing)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("nope"), "{}", stderr(&o));
}
