//! Animation synthesis under user constraints (thesis 3.5) on real data, end to end:
//! `surfcap synth path | keyposes | reach`, their reports and their files.

use std::path::{Path, PathBuf};
use std::process::Output;

use surfcap_testkit::{p, procedural_walker, stderr, surfcap};

fn example(name: &str) -> PathBuf {
    surfcap_testkit::workspace_root().join("examples").join(name)
}

fn report(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("--json prints the report")
}

/// Frame labels of a glb's sidecar, and checks that they agree with the report's counts.
fn check_labels(glb: &Path, r: &serde_json::Value) {
    let side: serde_json::Value = serde_json::from_slice(&std::fs::read(glb.with_extension("json")).unwrap()).unwrap();
    let labels = side["sequences"][0]["frame_labels"].as_array().unwrap();
    assert_eq!(labels.len() as u64, r["frames"].as_u64().unwrap());
    let synthetic = labels.iter().filter(|l| *l == "synthetic").count() as u64;
    assert_eq!(synthetic, r["synthetic_frames"].as_u64().unwrap());
    assert_eq!(r["original_frames"].as_u64().unwrap() + synthetic, r["frames"].as_u64().unwrap());
    assert!(r["transitions"].as_u64().unwrap() > 0 && synthetic > 0, "a synthesis that never transitions");
}

/// Acceptance: on the mannequin driven by the real CMU locomotion clips, a 15 m S-shaped
/// ground path is followed with a mean centre-of-mass error under 0.25 m (measured on the
/// written frames); `reach` meets a distance and a time; restrictions and bad input.
#[test]
fn path_and_reach_on_cmu_locomotion() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let subject = tmp.path().join("cmu.subject");
    let bvh: Vec<PathBuf> = ["16_15", "16_17", "16_19", "16_31", "16_36", "16_57", "16_07"]
        .iter()
        .map(|c| data.join("cmu_bvh").join(format!("{c}.bvh")))
        .collect();
    let mut args = vec!["make", "mannequin", "--bvh"];
    args.extend(bvh.iter().map(|b| p(b)));
    args.extend(["--vertices", "1500", "-o", p(&subject), "--quiet"]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));

    let glb = tmp.path().join("path.glb");
    let curve = example("s_path_15m.csv");
    let o = surfcap!(&[
        "synth",
        "path",
        p(&subject),
        "--curve",
        p(&curve),
        "-o",
        p(&glb),
        "--cache-dir",
        p(&cache),
        "--json",
    ]);
    let r = report(&o);
    let (mean, max) = (r["mean_error"].as_f64().unwrap(), r["max_error"].as_f64().unwrap());
    eprintln!(
        "S-path 15 m: mean error {mean:.3} m, max {max:.3} m, {} frames ({} synthetic), {} transitions, search {:.2} s",
        r["frames"], r["synthetic_frames"], r["transitions"], r["search"]["seconds"]
    );
    assert!(mean < 0.25, "mean centre-of-mass error {mean} m");
    assert!(r["curve_length"].as_f64().unwrap() > 14.9 && r["travelled"].as_f64().unwrap() >= 14.9);
    // The search's prediction is the played animation's centre track.
    let predicted = r["predicted"]["mean_error"].as_f64().unwrap();
    assert!((predicted - mean).abs() < 0.01, "predicted {predicted} vs measured {mean}");
    check_labels(&glb, &r);
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));
    // The error in the subject's unit and relative to the curve's length.
    let path = &r["constraints"][0];
    assert_eq!(path["unit"], "m", "{path}");
    assert_eq!(path["error"].as_f64(), Some(max));
    assert_eq!(path["relative_error"].as_f64(), Some(max / r["curve_length"].as_f64().unwrap()), "{path}");

    // Only running between 4 and 8 m: every original frame shown there is from the run clip.
    let o = surfcap!(&[
        "synth",
        "path",
        p(&subject),
        "--curve",
        p(&curve),
        "--tags",
        "run:4-8",
        "--start",
        "16_15:10",
        "-o",
        p(&tmp.path().join("run.glb")),
        "--cache-dir",
        p(&cache),
        "--json",
    ]);
    let r = report(&o);
    // The asked start pose is shown first (f32 rounding only).
    assert!(r["pose_distance_start"].as_f64().unwrap() < 1.0, "{}", r["pose_distance_start"]);
    let centres = r["per_frame"]["centre"].as_array().unwrap();
    let (mut s, mut prev) = (0.0, None::<(f64, f64)>);
    let mut arc = Vec::new();
    for c in centres {
        let q = (c[0].as_f64().unwrap(), c[2].as_f64().unwrap());
        if let Some(a) = prev {
            s += ((q.0 - a.0).powi(2) + (q.1 - a.1).powi(2)).sqrt();
        }
        arc.push(s);
        prev = Some(q);
    }
    let side: serde_json::Value = serde_json::from_slice(&std::fs::read(tmp.path().join("run.json")).unwrap()).unwrap();
    let labels = side["sequences"][0]["frame_labels"].as_array().unwrap();
    let walk: Vec<u64> = r["walk"].as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect();
    // Original frames are the walk's nodes, in order.
    let run_frames = 117 + 129 + 102 + 106..117 + 129 + 102 + 106 + 47;
    let mut node = 0;
    let mut checked = 0;
    for (k, l) in labels.iter().enumerate() {
        if l == "original" {
            if (4.05..=7.95).contains(&arc[k]) {
                assert!(run_frames.contains(&walk[node]), "frame {k} at {:.2} m shows node {}", arc[k], walk[node]);
                checked += 1;
            }
            node += 1;
        }
    }
    assert!(checked > 10, "{checked} frames checked in the run section");

    let o = surfcap!(&[
        "synth",
        "reach",
        p(&subject),
        "--from",
        "16_15:10",
        "--to",
        "16_31:80",
        "--distance",
        "10",
        "--time",
        "9",
        "-o",
        p(&tmp.path().join("reach.glb")),
        "--cache-dir",
        p(&cache),
        "--json",
    ]);
    let r = report(&o);
    eprintln!(
        "reach 10 m in 9 s: {:.2} m in {} frames, search {:.2} s",
        r["distance"], r["obtained_frames"], r["search_seconds"]
    );
    assert!(r["distance_error"].as_f64().unwrap() < 0.3, "{}", r["distance_error"]);
    assert!(r["time_error_frames"].as_u64().unwrap() <= 10, "{}", r["time_error_frames"]);
    let met = r["constraints"].as_array().unwrap();
    assert_eq!(met.len(), 2, "distance and time: {met:?}");
    assert!(met.iter().all(|c| c["missed"] == false), "{met:?}");
    // One count of frames, the surface motion graph's (frames shown, start included: 9 s at
    // 30 fps is 270 frames), errors in metres and relative to the request, and the poses at both
    // ends.
    assert_eq!(r["target_frames"], 270, "{r}");
    assert_eq!(r["obtained_frames"], r["frames"], "{r}");
    assert_eq!((met[1]["asked"].as_f64(), met[1]["achieved"].as_f64()), (Some(270.0), r["frames"].as_f64()), "{met:?}");
    assert_eq!(r["seconds"].as_f64(), Some(r["frames"].as_f64().unwrap() / 30.0));
    assert_eq!(r["target_seconds"].as_f64(), Some(9.0));
    assert_eq!(met[0]["unit"], "m");
    let distance_error = r["distance_error"].as_f64().unwrap();
    assert_eq!(met[0]["relative_error"].as_f64(), Some(distance_error / 10.0), "{met:?}");
    // The walk starts and ends on the asked frames: the distance is f32 rounding (neighbouring
    // frames of these clips are hundreds apart).
    for end in ["pose_distance_from", "pose_distance_to"] {
        assert!(r[end].as_f64().unwrap() < 1.0, "{end}: {r}");
    }

    // A distance the clips cannot cover in 4 s: written, but reported as missed (a warning even
    // with --quiet, the report's constraints), and exit code 3 with --strict.
    let far = tmp.path().join("far.glb");
    let reach_far = |extra: &[&str]| {
        let args = [
            "synth",
            "reach",
            p(&subject),
            "--from",
            "16_15:10",
            "--to",
            "16_31:80",
            "--distance",
            "1e9",
            "--time",
            "4",
            "-o",
            p(&far),
            "--cache-dir",
            p(&cache),
        ];
        surfcap!(&[&args[..], extra].concat())
    };
    let o = reach_far(&["--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("warning: constraint distance missed: asked 1000000000"), "{e}");
    assert!(e.contains(" m, 100% of the asked, tolerance"), "{e}");
    assert!(!e.contains("constraint time missed"), "{e}");
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("far.report.json")).unwrap()).unwrap();
    let distance = &r["constraints"][0];
    assert_eq!((distance["name"].as_str(), distance["missed"].as_bool()), (Some("distance"), Some(true)), "{r}");
    assert_eq!(distance["asked"], 1e9);
    assert_eq!(r["constraints"][1]["missed"], false);
    // The printed line counts frames as the report does (4 s at 30 fps: 120 frames shown,
    // start included, asked).
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(printed.contains(&format!("in {} frames", r["frames"])), "{printed} vs {r}");
    assert!(printed.contains("(asked 4s: 120 frames)"), "{printed}");
    std::fs::remove_file(&far).unwrap();
    let o = reach_far(&["--strict", "--quiet"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("1 constraint missed (--strict"), "{}", stderr(&o));
    assert!(far.is_file(), "the animation is written before --strict fails");
    let o = reach_far(&["--strict", "--json"]);
    assert_eq!(o.status.code(), Some(3));
    let v: serde_json::Value = serde_json::from_str(stderr(&o).trim()).expect("one JSON object");
    assert_eq!(v["exit_code"], 3);
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the report on stdout");
    assert_eq!(r["constraints"][0]["missed"], true);
    // A tolerance the user sets: 1e9 units of slack meets it.
    let o = reach_far(&["--strict", "--quiet", "--tolerance", "1e9"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));

    // Bad input names the file and line, or what is known.
    let bad_curve = tmp.path().join("bad.csv");
    std::fs::write(&bad_curve, "x,z\n0,0\n1,zero\n").unwrap();
    let out = tmp.path().join("never.glb");
    for (extra, want) in [
        (vec!["--curve", p(&bad_curve)], "bad.csv:3"),
        (vec!["--curve", p(&curve), "--tags", "moonwalk:1-2"], "jump, run, turn_left"),
        (vec!["--curve", p(&curve), "--tags", "run:9-5"], "FROM < TO"),
        (vec!["--curve", p(&curve), "--start", "16_15:500"], "16_15"),
        // The last frame of a clip leads nowhere; named, not walked into.
        (vec!["--curve", p(&curve), "--start", "16_15:116"], "the start frame 16_15:116 is a dead end"),
    ] {
        let o = surfcap!(
            &[&["synth", "path", p(&subject), "-o", p(&out), "--cache-dir", p(&cache)][..], &extra[..]].concat(),
        );
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{extra:?}: {}", stderr(&o));
    }
    assert!(!out.exists());

    // Lengths in the subject's units, frames as sequence:frame, --time in
    // seconds (bare, or 9s) or frames (270f at 30 fps), and an impossible request says why.
    let line = tmp.path().join("line.csv");
    std::fs::write(&line, "x,z\n0,0\n3,0\n").unwrap();
    let o = surfcap!(&[
        "synth",
        "path",
        p(&subject),
        "--curve",
        p(&line),
        "-o",
        p(&tmp.path().join("line.glb")),
        "--cache-dir",
        p(&cache),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("followed a 3.00 m curve") && text.contains(" m, max "), "{text}");
    let r_glb = tmp.path().join("r.glb");
    let reach = |from: &str, to: &str, time: &str, extra: &[&str]| {
        let args = [
            "synth",
            "reach",
            p(&subject),
            "--from",
            from,
            "--to",
            to,
            "--distance",
            "3",
            "--time",
            time,
            "-o",
            p(&r_glb),
            "--cache-dir",
            p(&cache),
        ];
        surfcap!(&[&args[..], extra].concat())
    };
    let info: serde_json::Value = serde_json::from_slice(&surfcap!(&["info", p(&subject), "--json"]).stdout).unwrap();
    let fps = info["fps"].as_f64().unwrap();
    let frames = (3.0 * fps).round() as u64;
    // Frames shown for 3 s, start included: round(3 x fps), as the surface motion graph counts.
    let written = frames;
    let o = reach("16_15:10", "16_31:80", "3s", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.starts_with("16_15:10 -> 16_31:80: ") && text.contains(" m travelled (asked 3.00 m)"), "{text}");
    assert!(text.contains(&format!("(asked 3s: {written} frames)")), "{text}");
    for time in ["3".to_string(), format!("{frames}f")] {
        let r = report(&reach("16_15:10", "16_31:80", &time, &["--json"]));
        assert_eq!(r["target_frames"].as_u64(), Some(written), "--time {time}");
    }
    let o = reach("16_15:10", "16_17:0", "3s", &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains(
            "no walk leads from 16_15:10 to 16_17:0 in the graph, whatever its duration: nothing enters 16_17:0"
        ),
        "{e}"
    );
}

/// Acceptance: ten key poses moved to new times on the Vlasic samba and the Briceno dance,
/// mean absolute timing error at most 3 frames (thesis Fig. 3.18).
#[test]
fn key_pose_timing_on_samba_and_dance() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    for (subject, keys) in
        [(data.join("vlasic2008/samba"), "samba_keys.csv"), (data.join("briceno2003/dance"), "dance_keys.csv")]
    {
        let glb = tmp.path().join(keys.replace(".csv", ".glb"));
        let o = surfcap!(&[
            "synth",
            "keyposes",
            p(&subject),
            "--keys",
            p(&example(keys)),
            "-o",
            p(&glb),
            "--cache-dir",
            p(&cache),
            "--json",
        ]);
        let r = report(&o);
        let err = r["mean_abs_error_frames"].as_f64().unwrap();
        let rows = r["keys"].as_array().unwrap();
        eprintln!(
            "{keys}: requested {:?}, obtained {:?}, mean error {err:.2} frames",
            rows.iter().map(|k| k["requested_time"].as_i64().unwrap()).collect::<Vec<_>>(),
            rows.iter().map(|k| k["obtained_time"].as_i64().unwrap()).collect::<Vec<_>>()
        );
        assert_eq!(rows.len(), 10);
        assert!(err <= 3.0, "{keys}: {err}");
        // The output's length is the last key's obtained time plus one frame.
        assert_eq!(r["frames"].as_i64().unwrap(), rows[9]["obtained_time"].as_i64().unwrap() + 1);
        // The pose shown at each key's time is the key's own pose (the
        // distance is f32 rounding; neighbouring frames are hundreds apart); times are in
        // frames, which are positions, so no relative error.
        for k in rows {
            let d = k["pose_distance"].as_f64().unwrap();
            assert!((0.0..1.0).contains(&d), "{keys}: {k}");
        }
        let timing = r["constraints"].as_array().unwrap();
        assert!(timing.iter().all(|c| c["unit"] == "frames" && c["relative_error"].is_null()), "{timing:?}");
        check_labels(&glb, &r);
        // The viewer's centre overlay: one centre per frame written.
        assert_eq!(r["per_frame"]["centre"].as_array().map(Vec::len), r["frames"].as_u64().map(|n| n as usize));
    }
    let bad = tmp.path().join("bad_keys.csv");
    std::fs::write(&bad, "frame,time\nsamba:10,0\nsamba:20,40\nsamba:30,20\n").unwrap();
    let o = surfcap!(&[
        "synth",
        "keyposes",
        p(&data.join("vlasic2008/samba")),
        "--keys",
        p(&bad),
        "-o",
        p(&tmp.path().join("x.glb")),
        "--cache-dir",
        p(&cache),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("bad_keys.csv:4"), "{}", stderr(&o));
}

/// A few characters of arguments that asked for tens of gigabytes to terabytes
/// (`interpolate --steps 100000`, a key at output frame 100000, `reach --time 1e9`, a 2 km
/// curve) are refused with the size, the limit and the option that raises it, before any work:
/// no graph is built (the cache folder stays absent) and nothing is written.
#[test]
fn requests_beyond_the_limits_are_refused_before_any_work() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let out = tmp.path().join("never.glb");
    let samba = data.join("vlasic2008/samba");
    let keys = tmp.path().join("far_keys.csv");
    std::fs::write(&keys, "frame,time\nsamba:10,0\nsamba:20,100000\n").unwrap();
    let walker = tmp.path().join("walker.subject");
    let o = surfcap!(&[
        "make",
        "mannequin",
        "--procedural",
        "walk,jog",
        "--seed",
        "1",
        "--vertices",
        "1000",
        "-o",
        p(&walker),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let km2 = tmp.path().join("line_2km.csv");
    std::fs::write(&km2, "0,0\n2000,0\n").unwrap();
    let limits = |extra: &[&'static str], want: &[&str], args: &[&str]| {
        let cached: &[&str] = if args[0] == "synth" { &["--cache-dir", p(&cache)] } else { &[] };
        let o = surfcap!(&[args, &["-o", p(&out)], cached, extra].concat());
        assert_eq!(o.status.code(), Some(1), "{args:?} {extra:?}: {}", stderr(&o));
        for w in want {
            assert!(stderr(&o).contains(w), "{args:?} {extra:?}: expected {w:?} in: {}", stderr(&o));
        }
        assert!(!cache.exists() && !out.exists(), "{args:?}: work was done before the refusal");
    };
    let interp = ["interpolate", p(&samba), "--from", "samba:0", "--to", "samba:100"];
    let steps = [&interp[..], &["--steps", "100000"]].concat();
    limits(&[], &["--steps 100000 asks for about 100000 frames, above the limit of 18000 (--max-frames"], &steps);
    limits(
        &["--max-frames", "1000000", "--max-memory", "2G"],
        &[
            "--steps 100000 needs about 11.1 GiB of memory (100000 frames x 9971 vertices)",
            "limit of 2.0 GiB (--max-memory)",
        ],
        &steps,
    );
    limits(
        &["--max-frames", "1000000", "--max-memory", "1T"],
        &["would write a glb of about 4.5 GiB", "above the format's limit of 4294967295 bytes", "--format npy"],
        &[&interp[..], &["--steps", "40000"]].concat(),
    );
    let keyposes = ["synth", "keyposes", p(&samba), "--keys", p(&keys)];
    limits(
        &[],
        &["far_keys.csv: keys from output frame 0 to 100000 asks for about 100001 frames", "--max-frames"],
        &keyposes,
    );
    let reach =
        ["synth", "reach", p(&samba), "--from", "samba:0", "--to", "samba:50", "--distance", "0", "--time", "1e9"];
    limits(&[], &["--time 1000000000s at 30 fps asks for about 30000000000 frames, above the limit of 18000"], &reach);
    limits(
        &["--max-frames", "100000000000", "--max-memory", "64G"],
        &[
            "PiB of memory (30000000000 frames x 9971 vertices and 382.0 TiB of search tables)",
            "above the limit of 64.0 GiB (--max-memory)",
        ],
        &reach,
    );
    let path = ["synth", "path", p(&walker), "--curve", p(&km2)];
    limits(
        &[],
        &["line_2km.csv (2000.0 m long, the subject's fastest motion covers", "above the limit of 18000"],
        &path,
    );
}

/// A reach target no walk of the graph can meet (1 km in 6 s from a procedural walker's clips)
/// says why, in the same words in the message and the report (the surface motion graph's
/// reason `too_fast`), and `--strict` exits with the missed-constraint code 3.
#[test]
fn an_unreachable_reach_target_says_why_and_strict_exits_with_the_missed_code() {
    let tmp = tempfile::tempdir().unwrap();
    let walker = procedural_walker!(tmp.path());
    let cache = tmp.path().join("cache");
    let out = tmp.path().join("far.glb");
    let reach = |extra: &[&str]| {
        let args = [
            "synth",
            "reach",
            p(&walker),
            "--from",
            "walk:0",
            "--to",
            "jog:30",
            "--distance",
            "1000",
            "--time",
            "6",
            "--strict",
            "-o",
            p(&out),
            "--cache-dir",
            p(&cache),
        ];
        surfcap!(&[&args[..], extra].concat())
    };
    let o = reach(&[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("no walk of the graph can meet this target: too fast: needs "), "{text}");
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("far.report.json")).unwrap()).unwrap();
    assert_eq!(r["met"], false, "{r}");
    let u = &r["unreachable"];
    assert_eq!(u["reason"], "too_fast", "{r}");
    assert!(u["needed"].as_f64().unwrap() > u["fastest"].as_f64().unwrap(), "{u}");
    let why = r["unreachable_why"].as_str().unwrap();
    assert!(why.starts_with("too fast: needs "), "{why}");
    assert!(text.contains(&format!("no walk of the graph can meet this target: {why}\n")), "{text} vs {why}");
    assert!(!text.contains("missed: the target lies within"), "{text}");
    // With --json the report on stdout carries the same reason.
    let o = reach(&["--json"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the report on stdout");
    assert_eq!((&j["unreachable"], &j["unreachable_why"]), (u, &r["unreachable_why"]), "{j}");
}

/// Learned variants' plumbing (thesis 6.6): a walk that loops reports its repeated frames; `--vary` needs
/// `--variation-model` and a model folder that is there, refused before any search (the cache
/// folder stays absent) and before anything is written.
#[test]
fn a_looping_walk_reports_its_repeats_and_vary_options_are_checked_first() {
    let tmp = tempfile::tempdir().unwrap();
    let walker = procedural_walker!(tmp.path());
    let line = tmp.path().join("line_20m.csv");
    std::fs::write(&line, "0,0\n20,0\n").unwrap();
    let cache = tmp.path().join("cache");
    let out = tmp.path().join("line.glb");
    let path = ["synth", "path", p(&walker), "--curve", p(&line), "-o", p(&out), "--cache-dir", p(&cache)];
    for (extra, want) in [
        (&["--vary", "3"][..], "--variation-model"),
        (&["--variation-model", p(tmp.path())][..], "--vary"),
        (
            &["--vary", "3", "--variation-model", "no-such-model"][..],
            "--variation-model no-such-model: expected the folder",
        ),
    ] {
        let o = surfcap!(&[&path[..], extra].concat());
        assert!(!o.status.success() && stderr(&o).contains(want), "{extra:?}: {}", stderr(&o));
        assert!(!cache.exists() && !out.exists(), "{extra:?}: work was done before the refusal");
    }
    // 20 m from 2 s clips: the walk loops over the same frames.
    let r = report(&surfcap!(&[&path[..], &["--json"]].concat()));
    // Every node of the walk shown before is a repeat.
    let walk: Vec<u64> = r["walk"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    let mut seen = std::collections::HashSet::new();
    let expected = walk.iter().filter(|n| !seen.insert(**n)).count() as u64;
    let repeats = r["repeated_frames"].as_u64().unwrap();
    assert!(expected > 0 && repeats == expected, "{repeats} repeats reported, {expected} in the walk");
    assert!(r.get("variation").is_none(), "no variation without --vary");
}

/// Learned variants on a walk's repeats (thesis 6.1, 6.6) end to end: a path that loops over a procedural walker's frames, played with
/// variants from a variation model of that walker: the repeated runs show variants (the output
/// differs from the plain walk there, not in the first pass), the same seed gives the same
/// bytes, and a model of another mesh is refused.
#[test]
fn vary_plays_learned_variants_on_the_repeats_of_a_looping_walk() {
    let tmp = tempfile::tempdir().unwrap();
    let walker = procedural_walker!(tmp.path());
    let model = tmp.path().join("model");
    let o = surfcap!(&["vary", "train", p(&walker), "--iterations", "40", "-o", p(&model), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let line = tmp.path().join("line_20m.csv");
    std::fs::write(&line, "0,0\n20,0\n").unwrap();
    let cache = tmp.path().join("cache");
    let run = |name: &str, vary: &[&str]| {
        let out = tmp.path().join(format!("{name}.glb"));
        let mut args = vec!["synth", "path", p(&walker), "--curve", p(&line), "-o", p(&out), "--cache-dir", p(&cache)];
        args.push("--json");
        args.extend_from_slice(vary);
        let r = report(&surfcap!(&args));
        let bytes = std::fs::read(&out).unwrap();
        (r, bytes)
    };
    let (plain, plain_bytes) = run("plain", &[]);
    let (r, bytes) = run("varied", &["--vary", "3", "--variation-model", p(&model)]);
    let v = &r["variation"];
    assert!(v["played_as_variants"].as_u64().unwrap() > 0, "{v}");
    // The variants shown are the foot-skate cleaned ones, as `vary sample` gives them: every
    // variant shown has its report, and the clean-up pinned planted feet.
    let cleaned = v["foot_skate_cleanup"].as_array().expect("the clean-up's reports");
    assert!(!cleaned.is_empty(), "{v}");
    let total = |k: &str| cleaned.iter().map(|c| c[k].as_f64().unwrap()).sum::<f64>();
    assert!(total("plants") > 0.0, "{v}");
    assert!(total("pinned_drift_after") < total("pinned_drift_before"), "{v}");
    assert_eq!(r["walk"], plain["walk"], "--vary changed the walk the search found");
    assert_ne!(bytes, plain_bytes, "the varied walk shows the same poses");
    let (_, again) = run("again", &["--vary", "3", "--variation-model", p(&model)]);
    assert_eq!(bytes, again, "same seed, different animation");
    let (_, other) = run("other", &["--vary", "4", "--variation-model", p(&model)]);
    assert_ne!(bytes, other, "another seed gave the same animation");
    // A model of another mesh is refused, naming the folder.
    let small = tmp.path().join("small.subject");
    let o = surfcap!(&[
        "make",
        "mannequin",
        "--procedural",
        "walk",
        "--duration",
        "2",
        "--vertices",
        "1500",
        "-o",
        p(&small),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m2 = tmp.path().join("model2");
    let o = surfcap!(&["vary", "train", p(&small), "--iterations", "10", "-o", p(&m2), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = tmp.path().join("bad.glb");
    let o = surfcap!(&[
        "synth",
        "path",
        p(&walker),
        "--curve",
        p(&line),
        "-o",
        p(&out),
        "--cache-dir",
        p(&cache),
        "--vary",
        "3",
        "--variation-model",
        p(&m2)
    ]);
    assert!(!o.status.success() && stderr(&o).contains("trained on a mesh of"), "{}", stderr(&o));
    assert!(!out.exists());
}
