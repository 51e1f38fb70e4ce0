//! `surfcap eval appearance` on a tiny sequence generated from the real head scan (12 frames of
//! 64x64, no moving light): the report's structure and sane values (naive PCA exact with every component, our
//! model far from the mean, completion better than the holed input, a row per warping and per
//! held-out fraction), the plots and images written, and the same numbers on one thread.

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

fn run(data: &std::path::Path, out: &std::path::Path, cache: &std::path::Path, threads: &str) -> Value {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .env("RAYON_NUM_THREADS", threads)
        .args([
            "--quiet",
            "eval",
            "appearance",
            "--data",
            p(data),
            "--frames",
            "12",
            "--size",
            "64",
            "--seed",
            "7",
            "--no-lighting",
            "--components",
            "3,6",
            "--held-out",
            "0,0.2,0.6",
            "--image-frames",
            "2",
            "--image-size",
            "64",
            "--cache-dir",
            p(cache),
            "-o",
            p(out),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&std::fs::read(out.join("appearance.json")).unwrap()).unwrap()
}

/// `v` without its wall-clock times.
fn without_seconds(v: &Value) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.iter().filter(|(k, _)| !k.ends_with("seconds")).map(|(k, x)| (k.clone(), without_seconds(x))).collect(),
        ),
        Value::Array(a) => Value::Array(a.iter().map(without_seconds).collect()),
        other => other.clone(),
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn the_appearance_evaluation_reports_every_part_with_sane_values() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let cache = d.path().join("cache");
    let out = d.path().join("eval");
    let r = run(&data, &out, &cache, "2");
    assert_eq!(r["frames"], 12);
    let holes = r["hole_frames"].as_array().unwrap().len();
    let n = r["complete_frames"].as_u64().unwrap() as usize;
    assert_eq!(n + holes, 12);
    assert!(holes >= 1, "the default hole fraction leaves a frame with a hole: {r}");
    // 1. Flow accuracy: one error per frame but the reference.
    let e = &r["flow"]["errors"];
    assert_eq!(e["frames"].as_u64().unwrap() as usize, n - 1);
    assert!(f(&e["mean"]).is_finite() && f(&e["mean"]) > 0.0 && f(&e["zero_flow_mean"]) > 0.0, "{e}");
    // Without the moving light the flow sees the drift only: closer to the truth than no flow
    // (measured 0.11 texels against 0.22).
    assert!(f(&e["mean"]) < 0.8 * f(&e["zero_flow_mean"]), "{e}");
    // 2. Both warpings, every component.
    let w = r["warping"].as_array().unwrap();
    let kinds: Vec<&str> = w.iter().map(|x| x["warping"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["poisson", "direct"]);
    for x in w {
        assert_eq!(x["eigen_textures"].as_u64().unwrap() as usize, n - 1);
        // Measured: SSIM 0.988 (Poisson) and 0.987 (direct) against the input frames.
        let s = f(&x["all_components"]["input"]["ssim"]);
        assert!(s > 0.95 && s <= 1.0, "{x}");
    }
    // 3. Compactness: K = 3, 6 and every component (n - 1); naive PCA is exact with all of
    // them; ours with every component is at least as good as with 3 (within noise).
    let c = r["compactness"].as_array().unwrap();
    let ks: Vec<u64> = c.iter().map(|x| x["components"].as_u64().unwrap()).collect();
    assert_eq!(ks, [3, 6, n as u64 - 1]);
    let last = &c[c.len() - 1];
    assert!(f(&last["naive"]["input"]["ssim"]) > 0.999 && f(&last["naive"]["input"]["mse"]) < 0.01, "{last}");
    assert!(f(&last["ours"]["input"]["ssim"]) >= f(&c[0]["ours"]["input"]["ssim"]) - 0.01, "{c:?}");
    for x in c {
        assert_eq!(
            x["eigen_textures"].as_u64().unwrap() + x["eigen_warps"].as_u64().unwrap(),
            x["components"].as_u64().unwrap()
        );
        let image = &x["image"];
        for m in ["ours", "naive"] {
            let s = f(&image[m]["ssim"]);
            assert!(s > 0.0 && s <= 1.0 + 1e-9, "{image}");
        }
    }
    assert_eq!(r["image_frames"].as_array().unwrap().len(), 2);
    // 4. A row per held-out fraction, holding out the share asked of the frames; the held-out
    // sets are nested (one seeded permutation): the 20% set is in the 60% one.
    let g = r["generalisation"].as_array().unwrap();
    let fr: Vec<f64> = g.iter().map(|x| f(&x["held_out_fraction"])).collect();
    assert_eq!(fr, [0.0, 0.2, 0.6]);
    assert_eq!(g[0]["test_frames"].as_array().unwrap().len(), n);
    let test = |i: usize| -> Vec<String> {
        g[i]["test_frames"].as_array().unwrap().iter().map(|v| v.as_str().unwrap().to_string()).collect()
    };
    assert_eq!(test(1).len(), (0.2 * n as f64).round() as usize);
    assert_eq!(test(2).len(), (0.6 * n as f64).round() as usize);
    assert!(test(1).iter().all(|k| test(2).contains(k)), "nested held-out sets: {:?} {:?}", test(1), test(2));
    for x in g {
        assert_eq!(
            x["training_frames"].as_u64().unwrap() as usize
                + if f(&x["held_out_fraction"]) == 0.0 { 0 } else { x["test_frames"].as_array().unwrap().len() },
            n
        );
        for m in ["ours", "naive"] {
            let s = f(&x[m]["input"]["ssim"]);
            assert!(s > 0.3 && s <= 1.0 + 1e-9, "{x}");
        }
    }
    // 5. Completion: inside the holes, the completed texture is far closer to the clean frame
    // than the holed (black) input.
    let comp = &r["completion"];
    assert_eq!(comp["frames"].as_array().unwrap().len(), holes);
    assert!(f(&comp["completed"]["mse"]) < 0.25 * f(&comp["holed_input"]["mse"]), "{comp}");
    assert!(f(&comp["completed"]["ssim"]) > f(&comp["holed_input"]["ssim"]), "{comp}");
    // Plots (SVG and PNG) and example images.
    for stem in ["compactness-texture-ssim", "compactness-texture-mse", "compactness-image-ssim", "generalisation-mse"]
    {
        for ext in ["svg", "png"] {
            assert!(out.join(format!("{stem}.{ext}")).is_file(), "{stem}.{ext}");
        }
    }
    let written: Vec<String> =
        r["written"].as_array().unwrap().iter().map(|v| v.as_str().unwrap().to_string()).collect();
    assert!(written.iter().any(|w| w.contains("interpolation-") && w.ends_with(".png")), "{written:?}");
    assert!(written.iter().any(|w| w.contains("completion-") && w.ends_with(".png")), "{written:?}");
    // The same numbers on one thread (the flows come from the cache the first run filled).
    let one = run(&data, &d.path().join("one"), &cache, "1");
    for key in ["flow", "warping", "compactness", "generalisation", "completion"] {
        assert_eq!(without_seconds(&r[key]), without_seconds(&one[key]), "{key} differs on one thread");
    }
}

#[test]
fn a_folder_that_is_not_a_generated_sequence_is_named() {
    let d = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let o = surfcap!(&["eval", "appearance", "--frames-dir", p(d.path()), "-o", p(&out.path().join("eval"))]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("frames.json") && e.contains(&d.path().display().to_string()), "{e}");
}

#[test]
fn the_capture_benchmark_reports_both_methods_and_the_warps_against_the_true_flow() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("eval");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .args([
            "--quiet",
            "eval",
            "appearance",
            "--benchmark",
            "capture",
            "--data",
            p(&data),
            "--frames",
            "10",
            "--size",
            "64",
            "--cameras",
            "8",
            "--components",
            "3",
            "--held-out",
            "0,0.3",
            "--image-frames",
            "1",
            "--image-size",
            "64",
            "--cache-dir",
            p(&d.path().join("cache")),
            "-o",
            p(&out),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let r: Value = serde_json::from_slice(&std::fs::read(out.join("appearance.json")).unwrap()).unwrap();
    assert_eq!(r["benchmark"], "capture");
    assert_eq!(r["capture"]["cameras"], 8);
    // The capture benchmark knows where each texel's content came from: the forward flows
    // have end-point errors against the true flow, which is not zero.
    let e = &r["flow"]["errors"];
    assert!(f(&e["mean"]) >= 0.0 && f(&e["zero_flow_mean"]) > 0.0, "{}", r["flow"]);
    let t = &r["warp_truth"];
    let causes: Vec<(&str, f64)> =
        t["causes"].as_array().unwrap().iter().map(|c| (c["cause"].as_str().unwrap(), f(&c["displacement"]))).collect();
    let cause = |name: &str| causes.iter().find(|c| c.0 == name).unwrap_or_else(|| panic!("{name}: {t}")).1;
    // Each capture error moves the content further than resampling alone does.
    assert!(cause("all") > cause("none") && cause("tracking") > cause("none"), "{causes:?}");
    assert!(cause("calibration") > cause("none"), "{causes:?}");
    assert!(f(&t["backward_zero_flow"]) > 0.0, "{t}");
    for b in t["backward"].as_array().unwrap() {
        assert!(f(&b["end_point_error"]) >= 0.0, "{b}");
    }
    for row in t["splits"].as_array().unwrap() {
        for m in ["ours", "true_warps"] {
            let s = f(&row[m]["input"]["ssim"]);
            assert!(s > 0.3 && s <= 1.0 + 1e-9, "{row}");
        }
    }
    let v = f(&t["true_aligned_variance_share"]);
    assert!(v > 0.0 && v.is_finite(), "{t}");
    let seen = f(&r["capture_seen_share"]);
    assert!(seen > 0.7 && seen <= 1.0, "{seen}");
    let ic = f(&r["input_vs_clean"]["ssim"]);
    assert!(ic > 0.3 && ic < 1.0, "the captured frames differ from their truth: {ic}");
    let c = r["compactness"].as_array().unwrap();
    assert!(c.len() >= 2);
    for x in c {
        for m in ["ours", "naive"] {
            let s = f(&x[m]["input"]["ssim"]);
            assert!(s > 0.3 && s <= 1.0 + 1e-9, "{x}");
        }
        assert!(x["image"]["ours"]["ssim"].is_number(), "{x}");
    }
    assert_eq!(r["generalisation"].as_array().unwrap().len(), 2);
    assert!(out.join("capture-views.png").is_file() && out.join("capture-frame-vs-clean.png").is_file());
}
