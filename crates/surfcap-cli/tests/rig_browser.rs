//! Skinned rigs and compact streams played by `surfcap view` in headless Chromium
//! (tools/played-test.mjs): the page loads a `surfcap rig` glb with three.js's GLTFLoader and
//! plays it as a skinned mesh (the animation mixer posing the skeleton at each frame), or
//! decodes a `.scstream` frame by frame. At several frames the vertices drawn are read back
//! (a rig's skinned by three.js, `SkinnedMesh.applyBoneTransform`) and compared with the source:
//! a rig's within the error its report gives, a stream's equal to the Rust decoder's. The
//! figure must move, cover pixels, and the page must log no console error.

use std::path::Path;
use std::process::Command;

use serde_json::Value;
use surfcap_testkit::{ViewServer, p, stderr, surfcap};

/// Float32 little-endian `.npy` (C order): its shape and values.
fn read_npy(path: &Path) -> (Vec<usize>, Vec<f32>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[1..6], b"NUMPY", "{}", path.display());
    let (hlen, start) = if b[6] == 1 {
        (u16::from_le_bytes([b[8], b[9]]) as usize, 10)
    } else {
        (u32::from_le_bytes(b[8..12].try_into().unwrap()) as usize, 12)
    };
    let header = String::from_utf8_lossy(&b[start..start + hlen]).to_string();
    assert!(header.contains("'<f4'") && !header.contains("'fortran_order': True"), "{header}");
    let shape = header.split("'shape': (").nth(1).unwrap().split(')').next().unwrap();
    let shape: Vec<usize> =
        shape.split(',').filter(|s| !s.trim().is_empty()).map(|s| s.trim().parse().unwrap()).collect();
    let values = b[start + hlen..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    (shape, values)
}

/// What tools/played-test.mjs saw of item `item` of the viewer serving `args`, at `frames`.
fn play_in_chromium(args: &[&str], item: usize, frames: &[usize]) -> Value {
    let root = surfcap_testkit::workspace_root();
    assert!(root.join("tools/node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), args);
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("seen.json");
    let list: Vec<String> = frames.iter().map(|f| f.to_string()).collect();
    let o = Command::new("node")
        .arg(root.join("tools/played-test.mjs"))
        .args([server.url.as_str(), &item.to_string(), &list.join(","), p(&out)])
        .output()
        .expect("node runs");
    assert!(
        o.status.success(),
        "played test failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let seen: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(seen["errors"], serde_json::json!([]), "console errors");
    assert!(seen["figurePixels"].as_u64().unwrap() > 500, "the figure covers no pixels: {}", seen["figurePixels"]);
    seen
}

/// The vertices read back at each frame asked (`[vertices][3]` f32), checked to be that frame.
fn vertices(seen: &Value) -> Vec<(usize, Vec<f32>)> {
    seen["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            assert_eq!(f["shown"], f["frame"], "setFrame showed another frame");
            let v = f["vertices"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
            (f["frame"].as_u64().unwrap() as usize, v)
        })
        .collect()
}

/// (RMS, max) of the distances between two `[vertices][3]` arrays.
fn errors(a: &[f32], b: &[f32]) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let d: Vec<f64> = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(x, y)| (0..3).map(|k| (f64::from(x[k]) - f64::from(y[k])).powi(2)).sum::<f64>().sqrt())
        .collect();
    ((d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt(), d.iter().copied().fold(0.0, f64::max))
}

/// The skinned frames against `source` (`[frames][vertices][3]`): every frame within `bound(f)`
/// (RMS and max) plus `tol`, and the figure moving by more than `moves`.
fn check_rig(seen: &Value, source: &[f32], bound: impl Fn(usize) -> (f64, f64), tol: f64, moves: f64) {
    let got = vertices(seen);
    let n = got[0].1.len();
    for (f, v) in &got {
        let (rms, max) = errors(v, &source[f * n..(f + 1) * n]);
        let (brms, bmax) = bound(*f);
        eprintln!("frame {f}: skinned in Chromium RMS {rms:.6}, max {max:.6}; reported RMS {brms:.6}, max {bmax:.6}");
        assert!(rms <= brms + tol && max <= bmax + tol, "frame {f}: RMS {rms}, max {max}; reported {brms}, {bmax}");
    }
    let moved = got.iter().map(|(_, v)| errors(v, &got[0].1).1).fold(0.0, f64::max);
    assert!(moved > moves, "the skinned mesh moved {moved}");
}

#[test]
fn the_crane_rig_plays_in_chromium_within_its_reported_error() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let d = tempfile::tempdir().unwrap();
    let glb = d.path().join("crane.glb");
    let o = surfcap!(&["rig", p(&crane), "--bones", "16", "--iterations", "8", "-o", p(&glb), "--json", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: Value = serde_json::from_slice::<Value>(&o.stdout).unwrap()["rig"].clone();
    let seen = play_in_chromium(&[p(&glb)], 0, &[0, 40, 87, 131, 174]);
    assert_eq!(seen["played"][0]["kind"], "rig");
    assert_eq!(seen["played"][0]["bones"], 16);
    let (_, source) = read_npy(&crane.join("positions.npy"));
    let per = r["per_frame"].as_array().unwrap();
    let bound = |f: usize| (per[f]["rms"].as_f64().unwrap(), per[f]["max"].as_f64().unwrap());
    // Float rounding: the glb holds f32 weights and joint poses; 0.01% of the height.
    let tol = 1e-4 * r["height"].as_f64().unwrap();
    check_rig(&seen, &source, bound, tol, 0.1);
}

#[test]
fn a_synthesised_path_animation_rig_plays_in_chromium_within_its_error() {
    let d = tempfile::tempdir().unwrap();
    let walker = surfcap_testkit::procedural_walker!(d.path());
    let curve = surfcap_testkit::workspace_root().join("examples/s_path_15m.csv");
    let synth = |format: &str, out: &Path| {
        let o =
            surfcap!(&["synth", "path", p(&walker), "--curve", p(&curve), "--format", format, "-o", p(out), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    // The same synthesis twice (same seed, same frames): as a rig, and as positions to compare with.
    let glb = d.path().join("walk.glb");
    synth("rig-glb", &glb);
    let npy = d.path().join("walk");
    synth("npy", &npy);
    let seq = std::fs::read_dir(&npy).unwrap().map(|e| e.unwrap().path()).find(|p| p.join("positions.npy").is_file());
    let (shape, source) = read_npy(&seq.unwrap().join("positions.npy"));
    let bytes = std::fs::read(&glb).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let rig = &doc["extras"]["surfcap"]["rig"];
    let max = rig["max"].as_f64().unwrap();
    let last = shape[0] - 1;
    let seen = play_in_chromium(&[p(&glb)], 0, &[0, last / 4, last / 2, 3 * last / 4, last]);
    assert_eq!(seen["played"][0]["bones"], 32);
    // No error per frame in the file: every frame within the rig's largest error (RMS too).
    check_rig(&seen, &source, |_| (max, max), 1e-4 * 1.8, 2.0);
}

#[test]
fn a_stream_plays_progressively_and_decodes_as_the_rust_decoder_does() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let d = tempfile::tempdir().unwrap();
    let stream = d.path().join("crane.scstream");
    let o = surfcap!(&["export", p(&crane), "--format", "stream", "-o", p(&stream), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let seen = play_in_chromium(&[p(&stream)], 0, &[0, 59, 60, 61, 120, 174]);
    let s = &seen["played"][0];
    assert_eq!((s["kind"].as_str(), s["total"].as_u64()), (Some("stream"), Some(175)));
    // Progressive: the first frame was drawn before the last was decoded.
    let first = s["decodedWhenShown"].as_u64().unwrap();
    eprintln!("frames decoded when the first was drawn: {first} of 175");
    assert!((1..175).contains(&first), "{s}");
    let back = surfcap_formats::stream::read_stream(&stream).unwrap();
    let q = &back.sequences()[0];
    for (f, v) in vertices(&seen) {
        assert!(v.iter().zip(q.frame(f)).all(|(a, b)| a.to_bits() == b.to_bits()), "frame {f} differs from Rust's");
    }
}

#[test]
fn every_sequence_of_a_stream_plays_from_its_own_key_frame() {
    let d = tempfile::tempdir().unwrap();
    let walker = surfcap_testkit::procedural_walker!(d.path());
    let stream = d.path().join("walker.scstream");
    let o = surfcap!(&["export", p(&walker), "--format", "stream", "-o", p(&stream), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back = surfcap_formats::stream::read_stream(&stream).unwrap();
    assert_eq!(back.sequences().len(), 2);
    let q = &back.sequences()[1];
    let last = q.n_frames() - 1;
    let seen = play_in_chromium(&[p(&stream)], 1, &[0, 1, last / 2, last]);
    for (f, v) in vertices(&seen) {
        assert!(v.iter().zip(q.frame(f)).all(|(a, b)| a.to_bits() == b.to_bits()), "{}:{f} differs", q.name);
    }
    // --sequences picks sequences; a name that is not there is named with those that are.
    let o = surfcap!(&["view", p(&stream), "--sequences", "nope", "--port", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no sequence named \"nope\""), "{}", stderr(&o));
}

#[test]
fn files_the_page_cannot_play_are_refused_with_their_name() {
    let d = tempfile::tempdir().unwrap();
    let cut = d.path().join("cut.scstream");
    std::fs::write(&cut, b"SCSTRM\x00\x01\x10\x00").unwrap();
    let o = surfcap!(&["view", p(&cut), "--port", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cut.scstream"), "{}", stderr(&o));
    // A rig with 8 bones per vertex: three.js takes 4.
    let walker = surfcap_testkit::procedural_walker!(d.path());
    let glb = d.path().join("eight.glb");
    let o = surfcap!(&[
        "rig",
        p(&walker),
        "--bones",
        "12",
        "--iterations",
        "2",
        "--max-influences",
        "8",
        "-o",
        p(&glb),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["view", p(&glb), "--port", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--max-influences 4"), "{}", stderr(&o));
    // A colour map is not computed for what the page decodes.
    let stream = d.path().join("w.scstream");
    assert!(surfcap!(&["export", p(&walker), "--format", "stream", "-o", p(&stream), "--quiet"]).status.success());
    let o = surfcap!(&["view", p(&stream), "--strain", "--port", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("decoded by the page"), "{}", stderr(&o));
}
