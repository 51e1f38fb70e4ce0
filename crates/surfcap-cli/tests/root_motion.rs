//! In-place clips: path and distance constraints refused on clips that cannot travel
//! (with the clips named and the way out), root motion recovered from ground contacts at import
//! (the KayKit knight's in-place walks and runs then follow a path), and `eval root-motion`.

use std::path::Path;

use surfcap_testkit::{p, stderr, surfcap};

fn write_line(path: &Path, length: f64) {
    let rows: String = (0..=20).map(|k| format!("{:.4},0\n", length * k as f64 / 20.0)).collect();
    std::fs::write(path, rows).unwrap();
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn path_and_distance_are_refused_on_in_place_clips_naming_them_and_the_way_out() {
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("idle.subject");
    let o = surfcap!(&[
        "make",
        "mannequin",
        "--procedural",
        "idle",
        "--duration",
        "2",
        "--vertices",
        "1000",
        "-o",
        p(&subject),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let curve = tmp.path().join("line.csv");
    write_line(&curve, 3.0);
    let out = tmp.path().join("out.glb");
    let o =
        surfcap!(&["synth", "path", p(&subject), "--curve", p(&curve), "-o", p(&out), "--cache-dir", p(tmp.path())]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("every clip of the subject is in place: idle (") && e.contains("--root-motion contacts"), "{e}");
    assert!(!out.exists(), "nothing written for an impossible request");
    let o = surfcap!(&[
        "synth",
        "reach",
        p(&subject),
        "--from",
        "idle:0",
        "--to",
        "idle:30",
        "--distance",
        "2",
        "--time",
        "2",
        "-o",
        p(&out),
        "--cache-dir",
        p(tmp.path())
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--distance 2 needs clips that travel"), "{}", stderr(&o));
}

/// The knight's in-place walks and runs, with an idle and a jump, imported with root motion
/// from contacts, follow a straight 6 m line with a mean centre error under 0.1 m and a 6 m
/// arc of radius 12 m (a 29 degree turn, with clips that only walk straight) under 0.2 m (a
/// tenth of the knight's height; 0.012 m and 0.069 m measured).
#[test]
fn kaykit_knight_in_place_clips_travel_after_import_with_root_motion_from_contacts() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let clips = ["Walking_A", "Walking_B", "Walking_C", "Running_A", "Running_B", "Idle", "Jump_Full_Short"];
    let sources: Vec<String> =
        clips.iter().map(|c| p(&data.join(format!("kaykit_adventurers/knight_{c}"))).to_string()).collect();
    let curve = tmp.path().join("line.csv");
    write_line(&curve, 6.0);
    let cache = tmp.path().join("cache");
    // As authored: refused, the walks named.
    let plain = tmp.path().join("plain.subject");
    let mut args = vec!["import"];
    args.extend(sources.iter().map(String::as_str));
    args.extend(["--name", "knight", "-o", p(&plain)]);
    assert!(surfcap!(&args).status.success());
    let o = surfcap!(&[
        "synth",
        "path",
        p(&plain),
        "--curve",
        p(&curve),
        "-o",
        p(&tmp.path().join("x.glb")),
        "--cache-dir",
        p(&cache)
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("knight_Walking_A (0.00 m in"), "{}", stderr(&o));
    // With root motion from contacts: the walks and runs travel, the idle does not.
    let moved = tmp.path().join("knight.subject");
    args.truncate(args.len() - 1);
    args.extend([p(&moved), "--root-motion", "contacts", "--json"]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let recovered = r["root_motion_from_contacts"].as_array().unwrap();
    assert_eq!(recovered.len(), clips.len(), "every clip is in place: {recovered:?}");
    let after = |name: &str| {
        recovered.iter().find(|x| x["sequence"] == name).unwrap()["net_displacement_after"].as_f64().unwrap()
    };
    for walk in ["knight_Walking_A", "knight_Walking_B", "knight_Running_A"] {
        assert!(after(walk) > 0.6, "{walk}: {}", after(walk));
    }
    assert!(after("knight_Idle") < 0.05, "idle: {}", after("knight_Idle"));
    let manifest = std::fs::read_to_string(moved.join("subject.json")).unwrap();
    assert!(manifest.contains("root_motion_from_contacts"), "the changed clips are tagged");
    let arc = tmp.path().join("arc.csv");
    let rows: String = (0..=40)
        .map(|k| {
            let a = 6.0 * k as f64 / 40.0 / 12.0;
            format!("{:.4},{:.4}\n", 12.0 * a.sin(), 12.0 - 12.0 * a.cos())
        })
        .collect();
    std::fs::write(&arc, rows).unwrap();
    for (curve, tolerance) in [(&curve, 0.1), (&arc, 0.2)] {
        let out = tmp.path().join("path.glb");
        let o = surfcap!(&[
            "synth",
            "path",
            p(&moved),
            "--curve",
            p(curve),
            "-o",
            p(&out),
            "--cache-dir",
            p(&cache),
            "--quiet"
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let r = json(&tmp.path().join("path.report.json"));
        let mean = r["mean_error"].as_f64().unwrap();
        assert!(mean < tolerance, "{}: mean centre error {mean} m", curve.display());
        assert!(r["net_displacement"].as_f64().unwrap() > 4.5, "net displacement {}", r["net_displacement"]);
    }
}

#[test]
fn eval_root_motion_recovers_a_cmu_walk_within_5_percent() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let o = surfcap!(&[
        "eval",
        "root-motion",
        "--bvh",
        p(&data.join("cmu_bvh/16_15.bvh")),
        "--vertices",
        "1000",
        "-o",
        p(tmp.path()),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("16_15") && table.contains("final%"), "{table}");
    let r = json(&tmp.path().join("root-motion.json"));
    let clip = &r["clips"][0];
    assert_eq!(clip["clip"], "16_15");
    assert!(clip["final_error_percent"].as_f64().unwrap() < 5.0, "{clip}");
    assert!(clip["heading_error_degrees"].as_f64().unwrap() < 5.0, "{clip}");
    assert!(r["written"].is_array());
}
