//! `surfcap vary train | sample` end to end (thesis chapter 6) on a small mannequin driven by
//! two CMU clips (16_15 walk, 16_36 jog), with few GPDM iterations and short chains: the model
//! folder, a glb per variant read back, the report, seeds, blended variants and the errors a
//! user meets. The jog (47 frames) is the reference, so every learnt trajectory is short.

use std::path::{Path, PathBuf};

use surfcap_testkit::{p, stderr, surfcap};

/// The mannequin (1,000 vertices) moved by the walk and the jog, as a subject cache in `dir`.
fn subject(data: &Path, dir: &Path) -> PathBuf {
    let out = dir.join("cmu.subject");
    let bvh: Vec<PathBuf> = ["16_15", "16_36"].iter().map(|c| data.join(format!("cmu_bvh/{c}.bvh"))).collect();
    let o = surfcap!(&[
        "--quiet",
        "make",
        "mannequin",
        "--bvh",
        p(&bvh[0]),
        p(&bvh[1]),
        "--vertices",
        "1000",
        "-o",
        p(&out)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

fn json_of(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// Sequences of a glb read back through surfcap's importer: (name, frames, vertices, labels
/// synthetic).
fn glb_sequences(glb: &Path) -> (Vec<(String, usize)>, usize, Vec<Vec<f32>>) {
    let s = surfcap_formats::import::import(&[glb.to_path_buf()], &Default::default(), &surfcap_mesh::NoProgress)
        .unwrap()
        .subject;
    let seqs = s.sequences().iter().map(|q| (q.name.clone(), q.n_frames())).collect();
    let q = &s.sequences()[0];
    assert!(
        q.labels.iter().all(|l| *l == surfcap_mesh::FrameLabel::Synthetic),
        "{}: a variant's frames are synthetic",
        glb.display()
    );
    (seqs, s.topology().n_vertices(), (0..q.n_frames()).map(|f| q.frame(f).to_vec()).collect())
}

fn sample(model: &Path, out: &Path, what: &[&str], seed: &str) -> serde_json::Value {
    let mut args = vec!["--json", "vary", "sample", p(model)];
    args.extend_from_slice(what);
    args.extend(["--count", "2", "--seed", seed, "--warmup", "20", "--thin", "2", "-o", p(out)]);
    json_of(&surfcap!(&args))
}

#[test]
fn train_then_sample_variants_and_blends_read_back_and_repeat_by_seed() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let subject = subject(&data, d.path());
    let model = d.path().join("model");
    let r = json_of(&surfcap!(&[
        "--json",
        "vary",
        "train",
        p(&subject),
        "--sequences",
        "16_15,16_36",
        "--reference",
        "16_36",
        "--blend",
        "16_15:16_36",
        "--iterations",
        "50",
        "-o",
        p(&model),
    ]));
    assert_eq!(r["reference"], "16_36");
    assert_eq!(r["frames"], 47, "every trajectory on the reference's frames");
    let seqs: Vec<(&str, u64)> = r["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| (s["name"].as_str().unwrap(), s["frames"].as_u64().unwrap()))
        .collect();
    assert_eq!(seqs[..2], [("16_15", 117), ("16_36", 47)]);
    assert_eq!(seqs.len(), 3, "the two sequences and their blend at 0.5");
    assert_eq!(r["sequences"][2]["origin"]["kind"], "blend");
    let parts = r["parts"].as_array().unwrap();
    assert_eq!(parts.len(), 5, "five proposed parts");
    for part in parts {
        let iters = part["iterations"].as_u64().unwrap();
        assert!((1..=50).contains(&iters), "{part}");
        assert!(part["objective"].as_f64().unwrap() < part["objective_start"].as_f64().unwrap(), "{part}");
        let displacement = if part["part"] == "torso" { 6 } else { 0 };
        assert_eq!(part["dimensions"].as_u64().unwrap(), 3 * part["vertices"].as_u64().unwrap() + displacement);
        assert_eq!(part["alpha"].as_array().unwrap().len(), 3);
        assert_eq!(part["beta"].as_array().unwrap().len(), 4);
    }
    for f in ["model.json", "faces.npy", "reference_pose.npy", "part_0_latent.npy", "part_4_frames.npy", "report.json"]
    {
        assert!(model.join(f).is_file(), "{f}");
    }

    // Variants of the walk: a glb each, read back with the walk's frames on the model's mesh.
    let out = d.path().join("out");
    let rep = sample(&model, &out, &["--sequence", "16_15"], "3");
    let on_disk: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(on_disk["variants"], rep["variants"]);
    assert_eq!((rep["seed"].as_u64(), rep["count"].as_u64()), (Some(3), Some(2)));
    assert_eq!(rep["chains"].as_array().unwrap().len(), 5, "one chain per part");
    for c in rep["chains"].as_array().unwrap() {
        let acc = c["acceptance_rate"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&acc) && c["step_size"].as_f64().unwrap() > 0.0, "{c}");
    }
    let files: Vec<PathBuf> = (1..=2).map(|k| out.join(format!("16_15-variant-{k}.glb"))).collect();
    surfcap_testkit::validate_glb(&files);
    let mut motions = Vec::new();
    for (k, f) in files.iter().enumerate() {
        let (seqs, nv, frames) = glb_sequences(f);
        assert_eq!(seqs, [(format!("16_15~{}", k + 1), 117)], "{}", f.display());
        assert_eq!(nv * 3, frames[0].len());
        let v = &rep["variants"][k];
        assert_eq!(v["frames"], 117);
        let dist = v["body_frame_distance"].as_f64().unwrap();
        assert!(dist > 0.0 && dist < 0.2, "variant {k}: {dist} m per vertex from the learnt walk");
        assert!(v["end_distance"].as_f64().unwrap().is_finite());
        motions.push(frames);
    }
    assert_ne!(motions[0], motions[1], "two variants of one seed differ");
    let view = rep["view"].as_str().unwrap();
    assert!(view.starts_with("surfcap view ") && view.contains("--sequences 16_15,16_15~1,16_15~2"), "{view}");
    assert!(view.contains(p(&std::fs::canonicalize(&subject).unwrap())), "{view}");

    // The same seed gives the same files, on one thread too; another seed other variants.
    let again = d.path().join("again");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .env("RAYON_NUM_THREADS", "1")
        .args(["--quiet", "vary", "sample", p(&model), "--sequence", "16_15", "--count", "2", "--seed", "3"])
        .args(["--warmup", "20", "--thin", "2", "-o", p(&again)])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let other = d.path().join("other");
    sample(&model, &other, &["--sequence", "16_15"], "4");
    for k in 1..=2 {
        let name = format!("16_15-variant-{k}.glb");
        let first = std::fs::read(out.join(&name)).unwrap();
        assert_eq!(first, std::fs::read(again.join(&name)).unwrap(), "{name}: same seed, same bytes");
        assert_ne!(first, std::fs::read(other.join(&name)).unwrap(), "{name}: another seed, other variants");
    }

    // Blended variants at 0.25: between the walk (w = 0) and the learnt blend (w = 0.5).
    let blend = d.path().join("blend");
    let rep = sample(&model, &blend, &["--blend", "16_15:16_36:0.25"], "3");
    assert_eq!(rep["blend"]["lower_sequence"], "16_15");
    assert_eq!(rep["blend"]["upper_sequence"], "16_15+16_36@0.5");
    assert_eq!(rep["chains"].as_array().unwrap().len(), 10, "a chain per part on both learnt trajectories");
    for k in 1..=2 {
        let f = blend.join(format!("16_15-16_36-0.25-variant-{k}.glb"));
        let (seqs, _, _) = glb_sequences(&f);
        assert_eq!(seqs.len(), 1);
        assert_eq!(seqs[0].0, format!("16_15+16_36@0.25~{k}"));
        let frames = seqs[0].1;
        assert!((47..=117).contains(&frames), "a blend's frame count between the two: {frames}");
        assert_eq!(rep["variants"][k - 1]["frames"], frames);
    }

    // A damaged model folder names the file at fault.
    let damaged = d.path().join("damaged");
    std::fs::create_dir(&damaged).unwrap();
    for e in std::fs::read_dir(&model).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), damaged.join(e.file_name())).unwrap();
    }
    let npy = damaged.join("part_1_frames.npy");
    let bytes = std::fs::read(&npy).unwrap();
    std::fs::write(&npy, &bytes[..bytes.len() / 2]).unwrap();
    let o = surfcap!(&["vary", "sample", p(&damaged), "--sequence", "16_15", "-o", p(&d.path().join("x"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("part_1_frames.npy"), "{}", stderr(&o));
    assert!(!d.path().join("x").exists(), "nothing written from a damaged model");
    std::fs::write(damaged.join("model.json"), "{ not json").unwrap();
    let o = surfcap!(&["vary", "sample", p(&damaged), "--sequence", "16_15", "-o", p(&d.path().join("x"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("model.json"), "{}", stderr(&o));

    // Unknown learnt sequences are listed; the output may not overwrite the model.
    let o = surfcap!(&["vary", "sample", p(&model), "--sequence", "walk", "-o", p(&d.path().join("y"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("16_15, 16_36, 16_15+16_36@0.5"), "{}", stderr(&o));
    let o = surfcap!(&["vary", "sample", p(&model), "--blend", "16_15:run:0.5", "-o", p(&d.path().join("y"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("\"run\""), "{}", stderr(&o));
    let o = surfcap!(&["vary", "sample", p(&model), "--sequence", "16_15", "-o", p(&model.join("inside"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(model.join("model.json").is_file());
}

#[test]
fn bad_requests_are_refused_before_any_work() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let subject = subject(&data, d.path());
    let out = d.path().join("model");
    let train = |extra: &[&str]| {
        let mut args = vec!["vary", "train", p(&subject), "-o", p(&out)];
        args.extend_from_slice(extra);
        surfcap!(&args)
    };
    let refused = |o: std::process::Output, expected: &str| {
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(expected), "expected {expected:?} in: {}", stderr(&o));
    };
    refused(train(&["--sequences", "16_15,walk"]), "has no sequence \"walk\"; it has 16_15, 16_36");
    refused(train(&["--sequences", "16_15,16_15"]), "given twice");
    refused(train(&["--sequences", "16_15,16_36", "--reference", "16_57"]), "--reference: \"16_57\" is not one");
    refused(train(&["--sequences", "16_15,16_36", "--blend", "16_15:16_57"]), "--blend: \"16_57\" is not one");
    refused(train(&["--sequences", "16_15,16_36", "--blend", "16_15:16_36", "--blend-weights", "1"]), "strictly");
    refused(train(&["--blend", "16_15"]), "expected A:B");
    refused(train(&["--latent-dim", "0"]), "--latent-dim");
    refused(train(&["--blend-weights", "0.25"]), "--blend");
    assert!(!out.join("model.json").exists(), "no model from a refused request");
    // Sampling: a blend weight outside [0, 1], a missing model, both kinds of request.
    let model = d.path().join("missing-model");
    let sample_out = d.path().join("out");
    let sample = |extra: &[&str]| {
        let mut args = vec!["vary", "sample", p(&model), "-o", p(&sample_out)];
        args.extend_from_slice(extra);
        surfcap!(&args)
    };
    refused(sample(&["--blend", "16_15:16_36:1.5"]), "a number in [0, 1]");
    refused(sample(&["--blend", "16_15:16_36:-0.1"]), "a number in [0, 1]");
    refused(sample(&["--sequence", "16_15", "--blend", "16_15:16_36:0.5"]), "cannot be used with");
    refused(sample(&[]), "--sequence");
    refused(sample(&["--sequence", "16_15", "--start", "middle"]), "expected learnt or mean");
    refused(sample(&["--sequence", "16_15"]), "model.json");
}
