//! `surfcap transfer train | apply` end to end on the KayKit knight and barbarian (the same clips
//! on two bodies and topologies, so the barbarian's own clip is the ground truth of a transfer),
//! and the errors a user meets.

use std::path::{Path, PathBuf};

use surfcap_testkit::{p, stderr, surfcap};

/// Imports `<character>_<clip>` for each clip as one subject cache in `dir`.
fn import(data: &Path, dir: &Path, character: &str, clips: &[&str]) -> PathBuf {
    let out = dir.join(format!("{character}.subject"));
    let sources: Vec<String> =
        clips.iter().map(|c| data.join(format!("kaykit_adventurers/{character}_{c}")).display().to_string()).collect();
    let mut args = vec!["--quiet", "import"];
    args.extend(sources.iter().map(String::as_str));
    args.extend(["--name", character, "-o", p(&out)]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

/// The barbarian's own Walking_C clip: the truth the knight's transferred walk is judged on.
fn barbarian_walking_c(data: &Path) -> surfcap_mesh::Subject {
    surfcap_formats::import::import(
        &[data.join("kaykit_adventurers/barbarian_Walking_C")],
        &Default::default(),
        &surfcap_mesh::NoProgress,
    )
    .unwrap()
    .subject
}

/// Reads a glb's positions back through surfcap's importer (all frames of its one sequence).
fn glb_frames(glb: &Path) -> Vec<Vec<f32>> {
    let s = surfcap_formats::import::import(&[glb.to_path_buf()], &Default::default(), &surfcap_mesh::NoProgress)
        .unwrap()
        .subject;
    let q = &s.sequences()[0];
    (0..q.n_frames()).map(|f| q.frame(f).to_vec()).collect()
}

/// RMS per-vertex distance after a rigid alignment of `b` onto `a`.
fn aligned_rms(a: &[f32], b: &[f32]) -> f64 {
    let (aligned, _) = surfcap_transfer::pose_representation::align_to_reference(a, b);
    let s: f64 = a.iter().zip(&aligned).map(|(x, y)| ((x - y) as f64).powi(2)).sum();
    (s / (a.len() / 3) as f64).sqrt()
}

#[test]
fn knight_to_barbarian_train_apply_matches_the_barbarians_own_clip() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let clips = ["Walking_A", "Running_A", "Walking_B", "Walking_C"];
    let knight = import(&data, d.path(), "knight", &clips);
    let barbarian = import(&data, d.path(), "barbarian", &clips);
    // Five key pairs per training clip; densification fills in the rest.
    let mut csv = String::from("source,target\n# the same clip on two bodies\n");
    for (clip, n) in [("Walking_A", 33), ("Running_A", 25), ("Walking_B", 33)] {
        for k in 0..5 {
            let f = k * (n - 1) / 4;
            csv.push_str(&format!("knight_{clip}:{f}, barbarian_{clip}:{f}\n"));
        }
    }
    let pairs = d.path().join("pairs.csv");
    std::fs::write(&pairs, csv).unwrap();
    let model = d.path().join("model");
    let cache = d.path().join("cache");
    let train = |out: &Path, extra: &[&str]| {
        let mut args = vec!["--json", "transfer", "train", "--source", p(&knight), "--target", p(&barbarian)];
        args.extend(["--pairs", p(&pairs), "-o", p(out), "--cache-dir", p(&cache)]);
        args.extend_from_slice(extra);
        surfcap!(&args)
    };
    let o = train(&model, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["key_pairs"], 15);
    assert_eq!(r["pairs"], 33 + 25 + 33, "one pair per frame after densification");
    let names: Vec<&str> = r["parts"].as_array().unwrap().iter().map(|x| x["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["torso", "arm_left", "arm_right", "leg_left", "leg_right"], "5 proposed parts");
    for f in ["model.json", "target_training.npy", "report.json", ".surfcap-output.json"] {
        assert!(model.join(f).is_file(), "{f}");
    }
    assert_eq!(r["cached"], false);
    // The same training again comes from the cache, the same model.
    let again_model = d.path().join("again_model");
    let o = train(&again_model, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r2: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r2["cached"], true);
    assert_eq!(r2["parts"], r["parts"]);
    for f in ["model.json", "target_training.npy"] {
        assert_eq!(std::fs::read(model.join(f)).unwrap(), std::fs::read(again_model.join(f)).unwrap(), "{f}");
    }

    // Transfer the unseen Walking_C; the barbarian's own Walking_C is the truth.
    let out = d.path().join("walk.glb");
    let motion = format!("{}:knight_Walking_C", p(&knight));
    let o = surfcap!(&["--json", "transfer", "apply", p(&model), "--motion", &motion, "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path().join("walk.report.json")).unwrap()).unwrap();
    assert_eq!(rep["reconstruction"], "stitch");
    assert_eq!(rep["correction"], false, "the correction is opt-in");
    assert_eq!(rep["frames"], 49);
    surfcap_testkit::validate_glb(std::slice::from_ref(&out));
    let got = glb_frames(&out);
    let truth = barbarian_walking_c(&data);
    let t = &truth.sequences()[0];
    assert_eq!(got.len(), t.n_frames());
    let (lo, hi) = surfcap_mesh::bounding_box(t.frame(0));
    let height = (hi[1] - lo[1]) as f64;
    let mean = (0..got.len()).map(|f| aligned_rms(&got[f], t.frame(f))).sum::<f64>() / got.len() as f64 / height;
    eprintln!("knight -> barbarian Walking_C through the CLI: {:.2}% of height", 100.0 * mean);
    assert!(mean < 0.02, "mean RMS {:.2}% of height", 100.0 * mean);
    // No truth given: the edge-length measure is dropped rather than taken against the rest pose.
    assert!(rep["edge_length_distortion"]["against"].as_str().unwrap().starts_with("dropped"), "{rep}");
    // With the truth: the error beside the nearest training pose's, edges against the truth's.
    let truth_arg = format!("{}:barbarian_Walking_C", p(&barbarian));
    let with_truth = d.path().join("walk_truth.glb");
    let o = surfcap!(&[
        "--json",
        "transfer",
        "apply",
        p(&model),
        "--motion",
        &motion,
        "--truth",
        &truth_arg,
        "-o",
        p(&with_truth)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rt: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let acc = &rt["accuracy"];
    let err = acc["rms_percent"].as_f64().unwrap();
    eprintln!("GP with --truth: {acc}, edges {}", rt["edge_length_distortion"]);
    assert!((err - 100.0 * mean).abs() < 0.25 * 100.0 * mean, "{err} vs {}", 100.0 * mean);
    assert!(acc["nearest_training_pose_percent"].as_f64().unwrap() > 0.0, "{acc}");
    let e = &rt["edge_length_distortion"];
    assert!(e["against"].as_str().unwrap().starts_with("the true motion"), "{e}");
    // The knight's and barbarian's limbs are separate meshes: no overlaps, no boundary edges.
    assert!(e["boundary_max"].is_null() || e["boundary_max"].as_f64().is_some_and(f64::is_finite), "{e}");
    assert!(e["inside_max"].as_f64().is_some_and(|x| x.is_finite() && x < 0.5), "{e}");

    // The same model and motion give the same file (the model reloads deterministically).
    let again = d.path().join("again.glb");
    let o = surfcap!(&["--quiet", "transfer", "apply", p(&model), "--motion", &motion, "-o", p(&again)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());

    // Training on one thread gives the same model as on the default pool.
    let model1 = d.path().join("model1");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .env("RAYON_NUM_THREADS", "1")
        .args(["--quiet", "transfer", "train", "--source", p(&knight), "--target", p(&barbarian)])
        .args(["--pairs", p(&pairs), "-o", p(&model1), "--cache-dir", p(&cache), "--no-cache"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::read(model.join("model.json")).unwrap() == std::fs::read(model1.join("model.json")).unwrap(),
        "model.json differs between 1 thread and the default"
    );
}

#[test]
fn transfer_errors_name_the_file_line_and_what_was_expected() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let knight = import(&data, d.path(), "knight", &["Walking_A"]);
    let barbarian = import(&data, d.path(), "barbarian", &["Walking_A"]);
    let pairs = d.path().join("pairs.csv");
    let model = d.path().join("model");
    let cache = d.path().join("cache");
    let train = |extra: &[&str]| {
        let mut args = vec![
            "transfer",
            "train",
            "--source",
            p(&knight),
            "--target",
            p(&barbarian),
            "--pairs",
            p(&pairs),
            "--cache-dir",
            p(&cache),
        ];
        args.extend_from_slice(extra);
        surfcap!(&args)
    };
    std::fs::write(&pairs, "knight_Walking_A:0,barbarian_Walking_A:0\nknight_Walking_A:40,barbarian_Walking_A:5\n")
        .unwrap();
    let o = train(&["-o", p(&model)]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains(&format!("{} line 2: source frame \"knight_Walking_A:40\"", pairs.display()))
            && e.contains("frames 0 to 32"),
        "{e}"
    );
    assert!(
        !model.exists() || std::fs::read_dir(&model).unwrap().all(|f| f.unwrap().file_name() == ".surfcap-output.json")
    );

    // The model may not be written over an input.
    std::fs::write(&pairs, "knight_Walking_A:0-32,barbarian_Walking_A:0-32\n").unwrap();
    let o = train(&["-o", p(&knight)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(knight.join("subject.json").is_file(), "the subject cache is untouched");

    // Parts whose names differ between the subjects.
    let sp = d.path().join("s.json");
    let tp = d.path().join("t.json");
    let o = surfcap!(&["--quiet", "parts", "propose", p(&knight), "--method", "components", "-o", p(&sp)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let nv = 2095;
    std::fs::write(&tp, format!("{{\"names\": [\"body\"], \"labels\": [{}]}}", vec!["0"; nv].join(","))).unwrap();
    let o = train(&["--source-parts", p(&sp), "--target-parts", p(&tp), "-o", p(&model)]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("both subjects need the same part names") || e.contains("both subjects need the same parts"),
        "{e}"
    );

    // A trained model applied to a motion of another subject.
    let o = train(&["--whole-body", "-o", p(&model)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let motion = format!("{}:barbarian_Walking_A", p(&barbarian));
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", &motion, "-o", p(&d.path().join("x.glb"))]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("2095 vertices, but the model") && e.contains("source of 2145 vertices (knight)"), "{e}");
    // Sized before any work: a motion longer than --max-frames is refused, nothing written.
    let motion = format!("{}:knight_Walking_A", p(&knight));
    let x = d.path().join("x.glb");
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", &motion, "--max-frames", "10", "-o", p(&x)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--max-frames"), "{}", stderr(&o));
    assert!(!x.exists());
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", p(&knight), "-o", p(&d.path().join("x.glb"))]);
    let e = stderr(&o);
    assert!(e.contains("expected SUBJECT:SEQUENCE"), "{e}");
    let motion = format!("{}:jog", p(&knight));
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", &motion, "-o", p(&d.path().join("x.glb"))]);
    let e = stderr(&o);
    assert!(e.contains("has no sequence \"jog\"; it has knight_Walking_A"), "{e}");
    // A motion on another mesh with the same vertex count: one triangle turned over.
    let other = d.path().join("other_knight");
    std::fs::create_dir(&other).unwrap();
    let src = data.join("kaykit_adventurers/knight_Walking_A");
    std::fs::copy(src.join("positions.npy"), other.join("positions.npy")).unwrap();
    let obj = std::fs::read_to_string(src.join("template.obj")).unwrap();
    let mut flipped = false;
    let obj: String = obj
        .lines()
        .map(|l| {
            if !flipped && l.starts_with("f ") {
                flipped = true;
                let f: Vec<&str> = l.split_whitespace().collect();
                format!("f {} {} {}\n", f[1], f[3], f[2])
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(other.join("template.obj"), obj).unwrap();
    let motion = format!("{}:other_knight", p(&other));
    let o = surfcap!(&[
        "transfer",
        "apply",
        p(&model),
        "--motion",
        &motion,
        "--fps",
        "30",
        "-o",
        p(&d.path().join("x.glb"))
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("other triangles than the source knight was trained on"), "{e}");

    // A damaged model names its file.
    std::fs::write(model.join("model.json"), "{\"format\": \"surfcap-transfer-model\"").unwrap();
    let motion = format!("{}:knight_Walking_A", p(&knight));
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", &motion, "-o", p(&d.path().join("x.glb"))]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains(&format!("{}:", model.join("model.json").display())), "{e}");
}

#[test]
fn baran_trains_and_applies_from_the_command_line_and_truth_gives_the_nearest_pose_beside_it() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let clips = ["Walking_A", "Walking_C"];
    let knight = import(&data, d.path(), "knight", &clips);
    let barbarian = import(&data, d.path(), "barbarian", &clips);
    let mut csv = String::from("source,target\n");
    for k in 0..8 {
        let f = k * 32 / 7;
        csv.push_str(&format!("knight_Walking_A:{f}, barbarian_Walking_A:{f}\n"));
    }
    let pairs = d.path().join("pairs.csv");
    std::fs::write(&pairs, csv).unwrap();
    let model = d.path().join("baran");
    let o = surfcap!(&[
        "--json",
        "transfer",
        "train",
        "--method",
        "baran",
        "--source",
        p(&knight),
        "--target",
        p(&barbarian),
        "--pairs",
        p(&pairs),
        "-o",
        p(&model),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["method"], "baran");
    assert_eq!(r["key_pairs"], 8);
    for f in ["model.json", "source_keys.npy", "target_keys.npy", "report.json", ".surfcap-output.json"] {
        assert!(model.join(f).is_file(), "{f}");
    }
    // Applied to the unseen Walking_C with the barbarian's own Walking_C as the truth.
    let out = d.path().join("walk.glb");
    let motion = format!("{}:knight_Walking_C", p(&knight));
    let truth = format!("{}:barbarian_Walking_C", p(&barbarian));
    let o =
        surfcap!(&["--json", "transfer", "apply", p(&model), "--motion", &motion, "--truth", &truth, "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rep: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(rep["method"], "baran");
    assert_eq!(rep["frames"], 49);
    let acc = &rep["accuracy"];
    let (err, nearest) = (acc["rms_percent"].as_f64().unwrap(), acc["nearest_training_pose_percent"].as_f64().unwrap());
    eprintln!("Baran knight -> barbarian Walking_C: {err:.2}% of height, nearest key pose {nearest:.2}%");
    assert!(err > 0.0 && err < 5.0, "{acc}");
    assert!(nearest > 0.0, "{acc}");
    assert_eq!(acc["nearest_training_poses"], 8);
    let e = &rep["edge_length_distortion"];
    assert!(e["against"].as_str().unwrap().starts_with("the true motion"), "{e}");
    assert!(e["boundary_max"].is_null(), "one part, no boundaries: {e}");
    assert!(e["inside_max"].as_f64().unwrap() >= 0.0, "{e}");
    surfcap_testkit::validate_glb(std::slice::from_ref(&out));
    // The same output as file frames: the one the report measured (aligned onto the truth).
    let got = glb_frames(&out);
    let t = barbarian_walking_c(&data);
    assert_eq!(got.len(), t.sequences()[0].n_frames());

    // Without the truth the edge-length measure is dropped, and says so.
    let out2 = d.path().join("walk2.glb");
    let o = surfcap!(&["--json", "transfer", "apply", p(&model), "--motion", &motion, "-o", p(&out2)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rep: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(rep["accuracy"].is_null());
    let e = &rep["edge_length_distortion"];
    assert!(e["boundary_max"].is_null() && e["inside_max"].is_null(), "{e}");
    assert!(e["against"].as_str().unwrap().starts_with("dropped: no --truth"), "{e}");

    // A truth of another length is refused before any work, naming both.
    let short = format!("{}:barbarian_Walking_A", p(&barbarian));
    let o = surfcap!(&["transfer", "apply", p(&model), "--motion", &motion, "--truth", &short, "-o", p(&out2)]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("barbarian_Walking_A: 33 frames, but the motion") && e.contains("has 49"), "{e}");
}
