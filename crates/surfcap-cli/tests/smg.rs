//! `surfcap smg query` on a subject and on a frame set (every frame re-meshed): the animation,
//! its report (path as `sequence:first-last` runs, constraints), missed constraints reported and
//! `--strict` exiting 3.

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

fn report(out: &std::path::Path) -> Value {
    let stem = out.file_stem().unwrap().to_string_lossy().into_owned();
    serde_json::from_slice(&std::fs::read(out.with_file_name(format!("{stem}.report.json"))).unwrap()).unwrap()
}

#[test]
fn a_gallop_loops_to_fill_the_time_on_a_subject_and_on_a_frame_set() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let cache = d.path().join("cache");
    let horse = d.path().join("horse.subject");
    let o = surfcap!(&["--quiet", "import", p(&data.join("threejs_morph_animals/horse_gallop")), "-o", p(&horse)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // 16 frames at 10 fps with a self-transition: 4 s (40 frames) needs the loop. The gallop
    // travels (46 units a cycle): the distance weight is made negligible, so the time decides.
    let args = |input: &std::path::Path, out: &std::path::Path| {
        vec![
            "smg".to_string(),
            "query".into(),
            p(input).into(),
            "--connect".into(),
            "horse_gallop:horse_gallop".into(),
            "--from".into(),
            "horse_gallop:0".into(),
            "--to".into(),
            "horse_gallop:15".into(),
            "--time".into(),
            "4".into(),
            "--distance".into(),
            "0".into(),
            "--distance-weight".into(),
            "0.0001".into(),
            "--windows".into(),
            "3-4".into(),
            "--tolerance".into(),
            "1000".into(),
            "--cache-dir".into(),
            p(&cache).into(),
            "-o".into(),
            p(out).into(),
        ]
    };
    let out = d.path().join("gallop.glb");
    let a = args(&horse, &out);
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let r = report(&out);
    let frames = r["frames"].as_u64().unwrap();
    assert!((30..=50).contains(&frames), "{frames} frames for 40 asked");
    // 4 s at 10 fps: round(T x fps) = 40 frames shown, start included, as `synth reach` asks.
    assert_eq!(r["target_frames"], 40);
    assert!(r["path"].as_array().unwrap().len() >= 2, "the loop was taken: {}", r["path"]);
    assert!(r["path"][0].as_str().unwrap().starts_with("horse_gallop:0-"));
    // No path of a galloping horse stays within 1% of 0 units: the report says why, and the
    // paper's optimum is played instead.
    assert_eq!(r["within_tolerance"].as_bool(), Some(false), "{r}");
    assert_eq!(r["unreachable"]["kind"].as_str(), Some("too_near"), "{}", r["unreachable"]);
    surfcap_testkit::validate_glb(std::slice::from_ref(&out));
    // Outputs as the other synthesis commands write them: the centre track (its length the
    // distance covered), the asked distance and time, the transition frames; the viewer reads them.
    overlay_checks(&out, &r);
    assert_eq!(surfcap_testkit::three_load_glb(std::slice::from_ref(&out))[0]["targets"].as_u64(), Some(frames));
    // The same motion re-meshed frame by frame: a frame set in, a frame set out.
    let set = d.path().join("horse.frames");
    let o = surfcap!(&["--quiet", "remesh-frames", p(&horse), "--seed", "2", "-o", p(&set)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // By default (here by its extension) a glb with a mesh per frame, played by three.js.
    let glb = d.path().join("gallop-remeshed.glb");
    let a = args(&set, &glb);
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));
    let r = report(&glb);
    overlay_checks(&glb, &r);
    let played = &surfcap_testkit::three_load_glb(std::slice::from_ref(&glb))[0];
    assert_eq!((played["kind"].as_str(), played["frames"][0].as_u64()), (Some("frame-set"), r["frames"].as_u64()));
    assert!(played["distinct_vertex_counts"][0].as_u64().unwrap() > 1, "{played}");
    // A .frames folder: the lossless product.
    let out = d.path().join("gallop-remeshed.frames");
    let a = args(&set, &out);
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let played = surfcap_mesh::frame_set_cache::read_frame_set(&out, &surfcap_mesh::NoProgress).unwrap();
    assert_eq!(played.frame_count() as u64, report(&out)["frames"].as_u64().unwrap());
    let (lo, hi) = played.vertex_count_range();
    assert!(lo < hi, "frames keep their own meshes ({lo}..{hi} vertices)");
    // A time the loop cannot meet exactly, under --strict: written, reported, exit 3. 4.5 s at
    // 10 fps is 45 frames shown; the walk (16 frames) and its 13-frame loop give 29, 42 or 55.
    let mut a = args(&horse, &d.path().join("strict.glb"));
    let t = a.iter().position(|x| x == "--tolerance").unwrap();
    a.splice(t..t + 2, ["--frame-tolerance".to_string(), "0".into(), "--strict".into()]);
    let i = a.iter().position(|x| x == "4").unwrap();
    a[i] = "4.5".into();
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("constraint time missed"), "{}", stderr(&o));
    assert!(d.path().join("strict.glb").is_file());
}

/// The report of `out` holds the centre of every frame, whose ground path is the distance
/// covered, the asked distance and time and the transition frames; `surfcap view out` serves
/// them as the item's overlay (a frame set's item with its per-frame vertex counts).
fn overlay_checks(out: &std::path::Path, r: &Value) {
    let frames = r["frames"].as_u64().unwrap();
    assert_eq!(r["per_frame"]["centre"].as_array().unwrap().len() as u64, frames);
    let (path, distance) = (r["path_length"].as_f64().unwrap(), r["distance"].as_f64().unwrap());
    assert!((path - distance).abs() <= 1e-6 * distance.max(1.0), "centre path {path} vs distance {distance}");
    assert_eq!((r["target_distance"].as_f64(), r["target_seconds"].as_f64()), (Some(0.0), Some(4.0)));
    let switches = r["transition_frames"].as_array().unwrap();
    assert_eq!(switches.len() + 1, r["path"].as_array().unwrap().len(), "a run of frames between transitions");
    let server = surfcap_testkit::ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(out)]);
    let (status, body) = server.get("/api/items");
    assert_eq!(status, 200);
    let item = &serde_json::from_slice::<Value>(&body).unwrap()["items"][0];
    assert_eq!(item["n_frames"].as_u64(), Some(frames));
    assert_eq!(item["overlay"]["centres"].as_array().unwrap().len() as u64, frames);
    assert_eq!(&item["overlay"]["transitions"], &r["transition_frames"]);
    let lines = item["overlay"]["constraints"].as_array().unwrap();
    assert!(lines.len() == 2 && lines[0].as_str().unwrap().starts_with("distance: "), "{lines:?}");
    if out.extension().is_some_and(|e| e == "glb") && r["input"].as_str().unwrap().ends_with(".frames") {
        assert_eq!(item["frame_vertices"].as_array().unwrap().len() as u64, frames);
    }
}

#[test]
fn bad_queries_are_refused_by_name() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let src = data.join("threejs_morph_animals/horse_gallop");
    let out = d.path().join("x.glb");
    for (args, want) in [
        (
            vec!["--connect", "gallop:horse_gallop", "--from", "horse_gallop:0", "--to", "horse_gallop:15"],
            "no sequence \"gallop\"",
        ),
        (
            vec!["--connect", "horse_gallop:horse_gallop", "--from", "horse_gallop:99", "--to", "horse_gallop:15"],
            "horse_gallop:99",
        ),
        (vec!["--connect", "horse_gallop", "--from", "horse_gallop:0", "--to", "horse_gallop:15"], "expected FROM:TO"),
    ] {
        let mut a = vec!["smg", "query", p(&src)];
        a.extend(args);
        a.extend(["--distance", "1", "--time", "2", "--cache-dir", p(d.path()), "-o", p(&out)]);
        let o = surfcap!(&a);
        assert_eq!(o.status.code(), Some(1), "{a:?}");
        assert!(stderr(&o).contains(want), "{want}: {}", stderr(&o));
    }
}

/// `eval smg --input` runs Table 1 on a user's data; its options are checked by name.
#[test]
fn eval_smg_takes_any_input_with_its_graph_and_key_pairs() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let src = data.join("threejs_morph_animals/horse_gallop");
    let out = d.path().join("eval");
    let base =
        ["eval", "smg", "--input", p(&src), "--connect", "horse_gallop:horse_gallop", "--cache-dir", p(d.path())];
    let mut a = base.to_vec();
    a.extend(["--pair", "horse_gallop:0,horse_gallop:15", "-o", p(&out), "--json"]);
    let o = surfcap!(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["pairs"][0]["queries"], 800);
    assert_eq!(r["form"], "shared topology");
    assert!(r["pairs"][0]["cpu_seconds"]["mean"].as_f64().unwrap() < 0.1);
    let bad = d.path().join("bad");
    let mut a = base.to_vec();
    a.extend(["--pair", "horse_gallop:0", "-o", p(&bad)]);
    let o = surfcap!(&a);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--pair \"horse_gallop:0\": expected FROM,TO"), "{}", stderr(&o));
}

/// `eval smg` on the CMU mannequin runs the essential graph beside the surface motion graph on
/// the same key frames and targets: a comparison row per engine with finite
/// errors, transition costs and times, and the error heat maps as PNGs; re-meshed frames say
/// why there is no essential graph.
#[test]
fn eval_smg_compares_with_the_essential_graph_and_draws_heat_maps() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("eval");
    let base = [
        "eval",
        "smg",
        "--data",
        p(&data),
        "--set",
        "locomotion",
        "--vertices",
        "1000",
        "--pair",
        "16_15:0,16_15:116",
        "--distances",
        "5,10",
        "--seconds",
        "5,8,12",
        "--cache-dir",
        p(d.path()),
    ];
    let mut a = base.to_vec();
    a.extend(["-o", p(&out)]);
    let o = surfcap!(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    // Printed: both engines' rows and the heat maps' paths.
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(" SMG ") && text.contains(" EG "), "{text}");
    let shown = out.join("time-error_essential_16_15-0_to_16_15-116.png");
    assert!(text.contains(&format!("wrote {}", shown.display())), "{text}");
    let r: Value = serde_json::from_slice(&std::fs::read(out.join("smg.json")).unwrap()).unwrap();
    let rows = r["comparison"]["rows"].as_array().unwrap();
    let engines: Vec<&str> = rows.iter().map(|x| x["engine"].as_str().unwrap()).collect();
    assert_eq!(engines, ["surface motion graph", "essential graph"]);
    let finite = |v: &Value| v.as_f64().is_some_and(f64::is_finite);
    for row in rows {
        assert_eq!((row["from"].as_str(), row["to"].as_str()), (Some("16_15:0"), Some("16_15:116")));
        assert_eq!(row["queries"], 6, "{row}");
        for m in ["distance_error", "time_error_frames"] {
            for s in ["min", "rms", "max"] {
                assert!(finite(&row[m][s]), "{m}.{s}: {row}");
            }
            assert!(
                row[m]["min"].as_f64() <= row[m]["rms"].as_f64() && row[m]["rms"].as_f64() <= row[m]["max"].as_f64()
            );
        }
        for m in ["transition_cost", "smoothness"] {
            for s in ["min", "mean", "max"] {
                assert!(finite(&row[m][s]) && row[m][s].as_f64().unwrap() >= 0.0, "{m}.{s}: {row}");
            }
        }
        assert!(row["cpu_seconds"]["mean"].as_f64().unwrap() > 0.0, "{row}");
    }
    // Walking 5-10 m in 5-12 s from the walk's first frame to its last needs transitions in
    // both engines (the clip alone is 117 frames).
    for row in rows {
        assert!(row["transitions_per_query"].as_f64().unwrap() >= 1.0, "{row}");
        assert!(row["transition_cost"]["max"].as_f64().unwrap() > 0.0, "{row}");
    }
    let eg = &r["comparison"]["essential_graph"];
    assert!(eg["nodes"].as_u64().unwrap() > 300 && eg["transitions"].as_u64().unwrap() > 0, "{eg}");
    assert!(finite(&eg["precompute_seconds"]));
    // Four heat maps (distance and time errors, both engines), valid PNGs named as reported.
    let pngs: Vec<std::path::PathBuf> = r["written"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| std::path::PathBuf::from(x.as_str().unwrap()))
        .filter(|x| x.extension().is_some_and(|e| e == "png"))
        .collect();
    assert_eq!(pngs.len(), 4, "{pngs:?}");
    for (measure, engine) in
        [("distance-error", "smg"), ("distance-error", "essential"), ("time-error", "smg"), ("time-error", "essential")]
    {
        let want = out.join(format!("{measure}_{engine}_16_15-0_to_16_15-116.png"));
        assert!(pngs.contains(&want), "{want:?} in {pngs:?}");
        let bytes = std::fs::read(&want).unwrap();
        assert!(bytes.len() > 1000 && bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{want:?}: {} bytes", bytes.len());
        let (w, h) = (
            u32::from_be_bytes(bytes[16..20].try_into().unwrap()),
            u32::from_be_bytes(bytes[20..24].try_into().unwrap()),
        );
        assert!(w > 100 && h > 100, "{want:?}: {w} x {h}");
    }
    // --no-compare: the surface motion graph alone, and said so.
    let mut a = base.to_vec();
    let alone = d.path().join("alone");
    a.extend(["-o", p(&alone), "--no-compare", "--json"]);
    let o = surfcap!(&a);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["pairs"][0]["queries"], 6);
    assert!(r.get("comparison").is_none() && r["comparison_skipped"].as_str().unwrap().contains("--no-compare"));
}

/// `smg build` computes the similarity once (cached) and writes the graph; a query on the same
/// frames then reads the similarity back; a bad key frame is refused by name.
#[test]
fn build_precomputes_what_queries_reuse() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let src = data.join("threejs_morph_animals/horse_gallop");
    let cache = d.path().join("cache");
    let graph = d.path().join("graph.json");
    let build = |keys: &str| {
        surfcap!(&[
            "smg",
            "build",
            p(&src),
            "--connect",
            "horse_gallop:horse_gallop",
            "--keys",
            keys,
            "--windows",
            "3-4",
            "--cache-dir",
            p(&cache),
            "-o",
            p(&graph)
        ])
    };
    let o = build("horse_gallop:0,horse_gallop:15");
    assert!(o.status.success(), "{}", stderr(&o));
    let g: Value = serde_json::from_slice(&std::fs::read(&graph).unwrap()).unwrap();
    assert_eq!(g["similarity_cached"].as_bool(), Some(false));
    let nodes: Vec<&str> = g["nodes"].as_array().unwrap().iter().filter_map(Value::as_str).collect();
    assert!(nodes.contains(&"horse_gallop:0") && nodes.contains(&"horse_gallop:15"), "{nodes:?}");
    let transitions = g["transitions"].as_array().unwrap();
    assert_eq!(transitions.len(), 1, "one loop of the gallop: {transitions:?}");
    // Every transition is an edge of the lower level, between two of its nodes.
    let edges = g["edges"].as_array().unwrap();
    assert!(
        edges.iter().any(|e| e["kind"]["kind"] == "transition" && e["from"] == transitions[0]["from"]),
        "{edges:?}"
    );
    // A query on the same frames reads the similarity back.
    let out = d.path().join("q.glb");
    let o = surfcap!(&[
        "smg",
        "query",
        p(&src),
        "--connect",
        "horse_gallop:horse_gallop",
        "--from",
        "horse_gallop:0",
        "--to",
        "horse_gallop:15",
        "--distance",
        "50",
        "--time",
        "3",
        "--windows",
        "3-4",
        "--cache-dir",
        p(&cache),
        "-o",
        p(&out)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(report(&out)["similarity_cached"].as_bool(), Some(true));
    let o = build("horse_gallop:0,horse_gallop:16");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--keys \"horse_gallop:16\""), "{}", stderr(&o));
}

/// A window shorter than 3 frames maps a frame onto itself and the walk freezes: refused before
/// any work, naming the option and the minimum.
#[test]
fn windows_shorter_than_three_frames_are_refused() {
    let d = tempfile::tempdir().unwrap();
    for w in ["1-30", "2-4", "1-1"] {
        let o = surfcap!(&[
            "smg",
            "query",
            p(&d.path().join("absent")),
            "--connect",
            "a:a",
            "--from",
            "a:0",
            "--to",
            "a:1",
            "--distance",
            "1",
            "--time",
            "1",
            "--windows",
            w,
            "-o",
            p(&d.path().join("q.glb"))
        ]);
        assert_eq!(o.status.code(), Some(1), "{w}");
        let e = stderr(&o);
        assert!(e.contains(&format!("--windows \"{w}\"")) && e.contains("at least 3 frames"), "{e}");
    }
}

/// On the Vlasic crane, the paper's graph (`--eq5-self-transitions`) has the self-transition
/// `crane:6 -> crane:4`, a 3-frame loop of near-still standing; padding 10 s with it played 126
/// frames of the same pose. It is an excluded loop (too short, and too still once the minimum
/// is lowered), the report and the message say so, and the answer is the walk alone with the
/// reason no loop remains. The default graph chooses its self-transition among the loops a
/// query may play instead: no loop is excluded and every one played is at least the minimum.
#[test]
fn loops_too_short_or_too_still_never_pad_time_on_the_crane() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let crane = data.join("vlasic2008/crane");
    let cache = d.path().join("cache");
    // The query of every run below, writing `out`.
    let args = |out: &std::path::Path| -> Vec<String> {
        let q = ["--connect", "crane:crane", "--from", "crane:0", "--to", "crane:174", "--distance", "3.1"];
        ["smg", "query", p(&crane)]
            .into_iter()
            .chain(q)
            .chain(["--time", "10", "-o", p(out)])
            .map(String::from)
            .collect()
    };
    let query = |name: &str, extra: &[&str]| {
        let out = d.path().join(format!("{name}.glb"));
        let mut a = args(&out);
        a.extend(["--cache-dir", p(&cache)].into_iter().chain(extra.iter().copied()).map(String::from));
        let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", stderr(&o));
        (report(&out), String::from_utf8_lossy(&o.stdout).into_owned())
    };
    // The default graph: its self-transition is a loop a query may play.
    let (r, _) = query("default", &[]);
    assert_eq!(r["graph"]["self_transitions"]["choice"], "spanning", "{}", r["graph"]);
    assert!(r["excluded_loops"].as_array().unwrap().is_empty(), "{}", r["excluded_loops"]);
    let frame = |v: &Value| v.as_str().unwrap().rsplit_once(':').unwrap().1.parse::<i64>().unwrap();
    for t in r["graph"]["transitions"].as_array().unwrap() {
        assert!(frame(&t["from"]) - frame(&t["to"]) + 1 >= 10, "a loop of at least 10 frames: {t}");
    }
    // The paper's graph.
    let eq5 = ["--eq5-self-transitions"];
    let (r, text) = query("eq5", &eq5);
    assert_eq!(r["graph"]["self_transitions"]["choice"], "eq5");
    let excluded = r["excluded_loops"].as_array().unwrap();
    assert_eq!(excluded.len(), 1, "{excluded:?}");
    assert_eq!(excluded[0]["kind"], "too_short");
    assert_eq!(excluded[0]["played_frames"], 3);
    assert_eq!(excluded[0]["frames"], serde_json::json!(["crane:5-6", "crane:4-4"]));
    assert!(text.contains("excluded loop crane:5-6, crane:4-4 (not used to pad time): 3 frame(s)"), "{text}");
    // The walk alone: every captured frame once, and why 10 s cannot be met.
    assert_eq!(r["frames"], 175);
    assert_eq!(r["path"], serde_json::json!(["crane:0-174"]));
    assert!(r["loops"].as_array().unwrap().is_empty());
    assert_eq!(r["unreachable"]["kind"], "no_loop", "{}", r["unreachable"]);
    assert!(text.contains("1 excluded loop(s) not counted"), "{text}");
    // With a lower minimum the same loop is still a held pose: under the floor.
    let (r, _) = query("floor", &["--eq5-self-transitions", "--min-loop", "3"]);
    let excluded = r["excluded_loops"].as_array().unwrap();
    assert_eq!(excluded[0]["kind"], "too_still", "{excluded:?}");
    assert!(excluded[0]["pose_variation"].as_f64().unwrap() < 1.0);
    assert_eq!(r["frames"], 175);
    // Every loop allowed: the stutter the rule prevents.
    let (r, _) = query("all", &["--eq5-self-transitions", "--min-loop", "1", "--loop-variation-floor", "0"]);
    assert!(r["excluded_loops"].as_array().unwrap().is_empty());
    assert!(r["loops"][0]["repetitions"].as_u64().unwrap() > 30, "{}", r["loops"]);
    let mut bad = args(&d.path().join("bad.glb"));
    bad.push("--loop-variation-floor=-1".into());
    let bad = surfcap!(&bad.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(bad.status.code(), Some(1), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("--loop-variation-floor"), "{}", stderr(&bad));
}
