//! `surfcap rig`: the crane (real capture) and a synthesised path animation as skinned rigs that
//! pass the Khronos glTF validator and play in three.js (`tools/rig-test.mjs`: the skinned mesh
//! moves and matches the source within the error the command reported), the report's numbers,
//! and bad requests refused with what was expected.

use std::path::{Path, PathBuf};

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

/// Plays `glb` in three.js against the source `npys` (one per animation) within the limits;
/// returns the script's report.
fn play_in_three(glb: &Path, npys: &[PathBuf], max_rms: f64, max_error: f64) -> Value {
    let root = surfcap_testkit::workspace_root();
    let out = std::process::Command::new("node")
        .arg(root.join("tools/rig-test.mjs"))
        .arg(glb)
        .args(npys)
        .args(["--max-rms", &max_rms.to_string(), "--max-error", &max_error.to_string()])
        .output()
        .expect("node runs (install Node.js)");
    assert!(
        out.status.success(),
        "three.js rig check failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the check prints one JSON line")
}

/// Runs `surfcap rig ... --json` and returns its report.
fn rig(args: &[&str]) -> Value {
    let mut all = vec!["rig", "--json", "--quiet"];
    all.extend_from_slice(args);
    let o = surfcap!(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    v["rig"].clone()
}

/// The report's numbers agree with one another; returns (rms, max).
fn check_report(r: &Value, frames: usize, bones: usize) -> (f64, f64) {
    let f = |k: &str| r[k].as_f64().unwrap();
    assert_eq!(r["frames"], frames);
    assert_eq!(r["bones"], bones);
    assert!(r["influences_used"].as_u64().unwrap() <= 4);
    let per = r["per_frame"].as_array().unwrap();
    assert_eq!(per.len(), frames);
    let mean_sq: f64 = per.iter().map(|x| x["rms"].as_f64().unwrap().powi(2)).sum::<f64>() / frames as f64;
    assert!((mean_sq.sqrt() - f("rms")).abs() <= 1e-9 * (1.0 + f("rms")));
    let max = per.iter().map(|x| x["max"].as_f64().unwrap()).fold(0.0, f64::max);
    assert_eq!(max, f("max"));
    assert!((f("rms_percent_of_height") - 100.0 * f("rms") / f("height")).abs() < 1e-9);
    // The error history never grows by more than rounding.
    let h: Vec<f64> = r["rms_history"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    for w in h.windows(2) {
        assert!(w[1] <= w[0] * 1.001 + 1e-9, "error grew: {h:?}");
    }
    assert!(f("bytes") < f("morph_glb_bytes") / 5.0, "{r}");
    (f("rms"), f("max"))
}

#[test]
fn the_crane_as_a_skinned_rig_validates_and_plays_in_three_js_within_its_reported_error() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let d = tempfile::tempdir().unwrap();
    let glb = d.path().join("crane.glb");
    let r = rig(&[p(&crane), "--bones", "16", "--iterations", "8", "-o", p(&glb)]);
    let (rms, max) = check_report(&r, 175, 16);
    assert_eq!(r["units"], "m");
    // A 16-bone rig of a loose-clothed capture: about a centimetre, well under 1% of its height.
    assert!(r["rms_percent_of_height"].as_f64().unwrap() < 1.0, "{r}");
    assert!(d.path().join("crane.report.json").is_file());
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));
    let three = play_in_three(&glb, &[crane.join("positions.npy")], rms * 1.02 + 1e-4, max * 1.02 + 1e-4);
    let a = &three["animations"][0];
    assert_eq!(three["bones"], 16);
    assert!(a["moved"].as_f64().unwrap() > 0.1, "{three}");
    assert!(a["rms"].as_f64().unwrap() <= rms * 1.02 + 1e-4, "{three}");
}

#[test]
fn a_synthesised_path_animation_as_a_skinned_rig_plays_in_three_js() {
    let d = tempfile::tempdir().unwrap();
    let walker = surfcap_testkit::procedural_walker!(d.path());
    let curve = surfcap_testkit::workspace_root().join("examples/s_path_15m.csv");
    let walk = d.path().join("walk");
    let o =
        surfcap!(&["synth", "path", p(&walker), "--curve", p(&curve), "--format", "npy", "-o", p(&walk), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let seqs: Vec<PathBuf> = std::fs::read_dir(&walk)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("positions.npy").is_file())
        .collect();
    assert_eq!(seqs.len(), 1, "{seqs:?}");
    let glb = d.path().join("walk.glb");
    let r = rig(&[p(&walk), "--bones", "12", "--iterations", "8", "-o", p(&glb)]);
    let frames = r["frames"].as_u64().unwrap() as usize;
    let (rms, max) = check_report(&r, frames, 12);
    assert!(r["rms_percent_of_height"].as_f64().unwrap() < 1.0, "{r}");
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));
    let three = play_in_three(&glb, &[seqs[0].join("positions.npy")], rms * 1.02 + 1e-4, max * 1.02 + 1e-4);
    // The walker travels: its skinned mesh moves metres along the path.
    assert!(three["animations"][0]["moved"].as_f64().unwrap() > 2.0, "{three}");

    // The same animation straight from synthesis as a rig: its errors are in the file's extras.
    let direct = d.path().join("walk-rig.glb");
    let o = surfcap!(&[
        "synth",
        "path",
        p(&walker),
        "--curve",
        p(&curve),
        "--format",
        "rig-glb",
        "-o",
        p(&direct),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    surfcap_testkit::validate_glb(std::slice::from_ref(&direct));
    let bytes = std::fs::read(&direct).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let rig = &doc["extras"]["surfcap"]["rig"];
    let (rms, max) = (rig["rms"].as_f64().unwrap(), rig["max"].as_f64().unwrap());
    assert_eq!(rig["bones"], 32, "{rig}");
    play_in_three(&direct, &[seqs[0].join("positions.npy")], rms * 1.02 + 1e-4, max * 1.02 + 1e-4);
    // Not an exporter's format: `surfcap export` says where rigs come from.
    let o = surfcap!(&["export", p(&walk), "--format", "rig-glb", "-o", p(&d.path().join("x.glb"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("surfcap rig SUBJECT"), "{}", stderr(&o));
}

#[test]
fn bad_requests_say_what_was_expected() {
    let d = tempfile::tempdir().unwrap();
    let walker = surfcap_testkit::procedural_walker!(d.path());
    let out = d.path().join("x.glb");
    let o = surfcap!(&["rig", p(&walker), "--bones", "0", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--bones"), "{}", stderr(&o));
    let o = surfcap!(&["rig", p(&walker), "--max-influences", "9", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--max-influences"), "{}", stderr(&o));
    let o = surfcap!(&["rig", p(&walker), "--bones", "400", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("400 bones for")
            && e.contains("vertices: each bone needs at least 4")
            && e.contains("ask for at most"),
        "{e}"
    );
    assert!(!out.exists());
}
