//! Every claim of a `--help` text about which way an option moves the result ("larger gives a
//! denser graph", "more: less correlated variants", "raise it for longer animations") checked
//! against what the program does, one test per claim, on small real data. Each test first finds
//! the claim in the help as the user reads it, so a test and its claim change together.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The help of `args` (e.g. `["graph", "build"]`) with its lines joined, so a claim wrapped over
/// two lines reads as one.
fn help(args: &[&str]) -> String {
    let mut a = args.to_vec();
    a.push("--help");
    let o = surfcap!(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    stdout(&o).split_whitespace().collect::<Vec<_>>().join(" ")
}

fn json(o: &Output) -> Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

/// The mannequin (1,000 vertices) moved by the CMU clips `clips` (e.g. "16_15"), in `dir`.
fn mannequin(data: &Path, dir: &Path, clips: &[&str]) -> PathBuf {
    let out = dir.join("cmu.subject");
    let bvh: Vec<String> = clips.iter().map(|c| p(&data.join(format!("cmu_bvh/{c}.bvh"))).to_string()).collect();
    let mut args = vec!["--quiet", "make", "mannequin", "--bvh"];
    args.extend(bvh.iter().map(String::as_str));
    args.extend(["--vertices", "1000", "-o", p(&out)]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

/// `graph build --alpha`: "larger gives a denser graph", on the walking cat (35 real frames).
#[test]
fn a_larger_alpha_gives_a_denser_graph() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    assert!(help(&["graph", "build"]).contains("larger gives a denser graph"));
    let tmp = tempfile::tempdir().unwrap();
    let cat = data.join("walking_cat_depraz");
    let cache = tmp.path().join("cache");
    let density = |alpha: &str| {
        let g = tmp.path().join(format!("graph-{alpha}"));
        let v = json(&surfcap!(&[
            "--json",
            "graph",
            "build",
            p(&cat),
            "--alpha",
            alpha,
            "--fps",
            "30",
            "-o",
            p(&g),
            "--cache-dir",
            p(&cache)
        ]));
        v["density"].as_f64().unwrap()
    };
    let d: Vec<f64> = ["0.005", "0.05", "0.5"].iter().map(|a| density(a)).collect();
    // Never sparser for a larger alpha, and denser over the range (a 35-frame cycle keeps
    // only its chain at the two smaller values).
    assert!(d[0] <= d[1] && d[1] <= d[2] && d[0] < d[2], "density at alpha 0.005, 0.05, 0.5: {d:?}");
}

/// `smg build --transitions`: "more adds the next best windows whose switches lie at least
/// --separation frames apart (more entry points)", on the horse's gallop (48 real frames).
#[test]
fn more_transitions_per_connection_add_entry_points_apart() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let h = help(&["smg", "build"]);
    assert!(h.contains("more adds the next best windows whose switches lie at least --separation frames apart"), "{h}");
    let tmp = tempfile::tempdir().unwrap();
    let horse = data.join("sumner2004-horse");
    let cache = tmp.path().join("cache");
    let transitions = |n: &str| {
        let out = tmp.path().join(format!("graph-{n}.json"));
        let v = json(&surfcap!(&[
            "--json",
            "smg",
            "build",
            p(&horse),
            "--connect",
            "gallop:gallop",
            "--keys",
            "gallop:0",
            "--transitions",
            n,
            "--separation",
            "5",
            // A self-connection's transitions are eq. 5's only on the paper's graph; by
            // default they are the loops chosen by --loops-per-sequence.
            "--eq5-self-transitions",
            "-o",
            p(&out),
            "--cache-dir",
            p(&cache)
        ]));
        v["transitions"].as_array().unwrap().clone()
    };
    let (one, three) = (transitions("1"), transitions("3"));
    assert_eq!(one.len(), 1, "{one:?}");
    assert!(three.len() > one.len(), "{three:?}");
    assert!(three.contains(&one[0]), "the paper's single best stays: {one:?} in {three:?}");
    // Switch frames (where each transition leaves) at least --separation apart.
    let frame = |t: &Value| -> i64 {
        let f = t["from"].as_str().unwrap_or_else(|| panic!("{t}"));
        f.rsplit(':').next().unwrap().parse().unwrap()
    };
    let mut switches: Vec<i64> = three.iter().map(frame).collect();
    switches.sort();
    assert!(switches.windows(2).all(|w| w[1] - w[0] >= 5), "{switches:?}");
}

/// `vary sample --thin`: "more: less correlated variants". Consecutive variants of one chain
/// drawn 1 iteration apart differ less than variants drawn 12 iterations apart. Judged on the
/// variants as sampled (`--no-foot-skate-cleanup`): the clean-up moves each variant's body
/// along the ground by its own feet's pulls, which on this 40-iteration model made consecutive
/// variants 35-69 mm apart in the world while their poses were 4-9 mm apart, so the world frames
/// measure the clean-up rather than the chain.
#[test]
fn more_thinning_gives_less_correlated_variants() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    assert!(help(&["vary", "sample"]).contains("more: less correlated variants"));
    let tmp = tempfile::tempdir().unwrap();
    let subject = mannequin(&data, tmp.path(), &["16_15", "16_36"]);
    let model = tmp.path().join("model");
    json(&surfcap!(&[
        "--json",
        "vary",
        "train",
        p(&subject),
        "--sequences",
        "16_15,16_36",
        "--reference",
        "16_36",
        "--iterations",
        "40",
        "-o",
        p(&model)
    ]));
    // Mean distance between the poses of consecutive variants, over their frames and vertices.
    let spread = |thin: &str| {
        let out = tmp.path().join(format!("thin-{thin}"));
        let o = surfcap!(&[
            "--json",
            "vary",
            "sample",
            p(&model),
            "--sequence",
            "16_36",
            "--count",
            "4",
            "--seed",
            "1",
            "--warmup",
            "20",
            "--thin",
            thin,
            "--no-foot-skate-cleanup",
            "-o",
            p(&out)
        ]);
        json(&o);
        let mut files: Vec<PathBuf> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|f| f.extension().is_some_and(|x| x == "glb"))
            .collect();
        files.sort();
        assert_eq!(files.len(), 4, "{files:?}");
        let poses: Vec<Vec<f32>> = files
            .iter()
            .map(|f| {
                let s = surfcap_formats::import::import(
                    std::slice::from_ref(f),
                    &Default::default(),
                    &surfcap_mesh::NoProgress,
                )
                .unwrap()
                .subject;
                let q = &s.sequences()[0];
                (0..q.n_frames()).flat_map(|k| q.frame(k).to_vec()).collect()
            })
            .collect();
        let mut total = 0.0;
        for w in poses.windows(2) {
            let d: f64 = w[0]
                .chunks(3)
                .zip(w[1].chunks(3))
                .map(|(a, b)| {
                    let (x, y, z) = ((a[0] - b[0]) as f64, (a[1] - b[1]) as f64, (a[2] - b[2]) as f64);
                    (x * x + y * y + z * z).sqrt()
                })
                .sum::<f64>();
            total += d / (w[0].len() / 3) as f64;
        }
        total / (poses.len() - 1) as f64
    };
    let (near, far) = (spread("1"), spread("12"));
    assert!(far > near, "mean distance between consecutive variants: {near} at --thin 1, {far} at --thin 12");
}

/// `--max-frames`: "raise it for longer animations": a path longer than the limit allows is
/// refused before any work, naming the option; raised, the same request runs.
#[test]
fn max_frames_refuses_longer_animations_until_raised() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    assert!(help(&["synth", "path"]).contains("raise it for longer animations"));
    let tmp = tempfile::tempdir().unwrap();
    let subject = mannequin(&data, tmp.path(), &["16_15", "16_17"]);
    let curve = tmp.path().join("curve.csv");
    std::fs::write(&curve, "x,z\n0,0\n2,0.4\n4,0\n").unwrap();
    let cache = tmp.path().join("cache");
    let path = |max: &str| {
        surfcap!(&[
            "synth",
            "path",
            p(&subject),
            "--curve",
            p(&curve),
            "--max-frames",
            max,
            "-o",
            p(&tmp.path().join(format!("path-{max}.glb"))),
            "--cache-dir",
            p(&cache)
        ])
    };
    let o = path("20");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--max-frames"), "{}", stderr(&o));
    assert!(!tmp.path().join("path-20.glb").exists());
    let o = path("100000");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(tmp.path().join("path-100000.glb").is_file());
}

/// `--tolerance`: "a distance constraint missed by more than this ... is reported as missed":
/// the same reach is missed under a tolerance below its error and met under one above it.
#[test]
fn a_distance_missed_by_more_than_the_tolerance_is_reported_missed() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let h = help(&["synth", "reach"]);
    assert!(h.contains("missed by more than this, in the subject's units, is reported as missed"), "{h}");
    let tmp = tempfile::tempdir().unwrap();
    let subject = mannequin(&data, tmp.path(), &["16_15", "16_17"]);
    let cache = tmp.path().join("cache");
    let reach = |tolerance: &str| {
        json(&surfcap!(&[
            "--json",
            "synth",
            "reach",
            p(&subject),
            "--from",
            "16_15:5",
            "--to",
            "16_17:60",
            "--distance",
            "6",
            "--time",
            "5",
            "--tolerance",
            tolerance,
            "-o",
            p(&tmp.path().join(format!("reach-{tolerance}.glb"))),
            "--cache-dir",
            p(&cache)
        ]))
    };
    let distance = |v: &Value| -> Value {
        v["constraints"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == "distance")
            .unwrap_or_else(|| panic!("{v}"))
            .clone()
    };
    // The search aims within the tolerance too, so each tolerance may give its own walk: under
    // a wide one the reach is met, under none at all its error (however small) is a miss.
    let wide = distance(&reach("100"));
    assert_eq!((wide["tolerance"].as_f64(), wide["missed"].as_bool()), (Some(100.0), Some(false)), "{wide}");
    let exact = distance(&reach("0"));
    let error = exact["error"].as_f64().unwrap();
    assert!(error > 0.0, "an exact reach cannot show the tolerance: {exact}");
    assert_eq!((exact["tolerance"].as_f64(), exact["missed"].as_bool()), (Some(0.0), Some(true)), "{exact}");
    let between = distance(&reach(&format!("{}", error * 2.0)));
    let e = between["error"].as_f64().unwrap();
    assert_eq!(between["missed"].as_bool(), Some(e > error * 2.0), "{between}");
}
