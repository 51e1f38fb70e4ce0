//! The viewer's views and overlays end to end in headless Chromium (tools/viewer-views-test.mjs):
//! the centre track drawn on the ground plane (its pixels cast back onto the grid's plane land on
//! the track; the hip-height track's do not), the view presets and the follow camera, labels over
//! side-by-side figures, per-vertex colour maps with their colour bar (`--strain`,
//! `--distance-from`, `--error-against`), looks, onion skin, frame entry, loop range, the bare
//! scene (`?ui=0`) and `reload()`.

use std::path::Path;
use std::process::Command;

use surfcap_testkit::{ViewServer, p, stderr, surfcap};

/// Runs tools/viewer-views-test.mjs on the page at `url` (failing the test when one of its
/// checks fails), screenshots in `out`; returns what it saw.
fn views_test(url: &str, out: &Path) -> serde_json::Value {
    let tools = surfcap_testkit::workspace_root().join("tools");
    assert!(tools.join("node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let o =
        Command::new("node").arg(tools.join("viewer-views-test.mjs")).args([url, p(out)]).output().expect("node runs");
    assert!(
        o.status.success(),
        "viewer views test failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

fn f32s(b: &[u8]) -> Vec<f32> {
    b.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect()
}

/// A path output of the CMU-driven mannequin: the centre track lies on the grid's plane (and
/// the test tells it from the hip-height track), the presets look as named, the follow camera
/// moves with the walk, and the panel says the centre's distance from the path in metres.
#[test]
fn the_centre_track_lies_on_the_ground_and_the_presets_look_as_named() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("cmu.subject");
    let bvh: Vec<String> =
        ["16_15", "16_17", "16_19"].iter().map(|c| p(&data.join(format!("cmu_bvh/{c}.bvh"))).to_string()).collect();
    let mut args = vec!["make", "mannequin", "--bvh"];
    args.extend(bvh.iter().map(String::as_str));
    args.extend(["--vertices", "1500", "-o", p(&subject), "--quiet"]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let curve = tmp.path().join("curve.csv");
    std::fs::write(&curve, "0,0\n1,0\n2,0.3\n3,0.8\n4,1.5\n").unwrap();
    let path = tmp.path().join("path.glb");
    let cache = tmp.path().join("cache");
    let o = surfcap!(&[
        "synth",
        "path",
        p(&subject),
        "--curve",
        p(&curve),
        "-o",
        p(&path),
        "--cache-dir",
        p(&cache),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(&path)]);
    let (_, items) = server.get("/api/items");
    let items: serde_json::Value = serde_json::from_slice(&items).unwrap();
    let errors = items["items"][0]["overlay"]["centre_errors"].as_array().expect("a path's per-frame centre errors");
    assert_eq!(errors.len() as u64, items["items"][0]["n_frames"].as_u64().unwrap());
    let seen = views_test(&server.url, &tmp.path().join("shots"));
    let ground = &seen["ground"];
    assert!(ground["on_ground"].as_f64().unwrap() >= 0.97 && ground["pixels"].as_u64().unwrap() > 50, "{seen}");
    assert!(seen["hip"]["on_ground"].as_f64().unwrap() < 0.5, "{seen}");
    for preset in ["top", "front", "side", "three-quarter"] {
        assert!(seen["presets"][preset]["cos"].as_f64().unwrap() > 0.999, "{preset}: {seen}");
    }
    // The walk travels about 4.5 m: the follow camera's target moves with it.
    assert!(seen["follow"]["target_moved"].as_f64().unwrap() > 2.0, "{seen}");
    let text = seen["centre_error_text"].as_str().unwrap();
    assert!(text.contains(" m at this frame; largest ") && text.contains(" m (frame "), "{text}");
    assert!(seen["onion"]["ghosts"].as_u64().unwrap() >= 2, "{seen}");
}

/// Two real captures side by side with labels given on the command line and coloured by their
/// edge-length strain against their first frame: the labels stand over their figures, the
/// colour bar names the strain in percent over both captures' range, and the values are the
/// strain (zero at the first frame, where every edge has its own length).
#[test]
fn labels_and_a_strain_colour_map_on_two_captures() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let samba = data.join("vlasic2008/samba");
    let server = ViewServer::start(
        env!("CARGO_BIN_EXE_surfcap"),
        &[p(&crane), p(&samba), "--labels", "actor I (crane),actress T (samba)", "--strain"],
    );
    let (_, items) = server.get("/api/items");
    let items: serde_json::Value = serde_json::from_slice(&items).unwrap();
    let it = &items["items"][0];
    assert_eq!(it["label"], "actor I (crane)");
    assert_eq!(
        (it["field"]["name"].as_str(), it["field"]["unit"].as_str()),
        (Some("edge-length strain against the first frame"), Some("%"))
    );
    let (status, body) = server.get("/api/items/0/field");
    assert_eq!(status, 200);
    let values = f32s(&body);
    let nv = it["n_vertices"].as_u64().unwrap() as usize;
    assert_eq!(values.len(), 175 * nv);
    assert!(values[..nv].iter().all(|&v| v == 0.0), "the first frame has no strain against itself");
    let last = &values[174 * nv..];
    let mean = last.iter().map(|&v| v as f64).sum::<f64>() / nv as f64;
    // A real capture's surface stretches a little (cloth, tracking): a few percent on average.
    assert!(mean > 0.1 && mean < 50.0, "mean strain at the last frame {mean}%");
    // The bar's range ends at the 99th percentile of the values; `max` is the largest.
    let (hi, max) = (it["field"]["range"][1].as_f64().unwrap(), it["field"]["max"].as_f64().unwrap());
    assert_eq!(max, values.iter().cloned().fold(0.0f32, f32::max) as f64);
    let below = values.iter().filter(|&&v| v as f64 <= hi).count() as f64 / values.len() as f64;
    assert!(hi <= max && (0.985..=0.999).contains(&below), "range ends at {hi}, {below} of the values below it");
    let tmp = tempfile::tempdir().unwrap();
    let seen = views_test(&server.url, tmp.path());
    let texts: Vec<&str> = seen["labels"].as_array().unwrap().iter().map(|l| l["text"].as_str().unwrap()).collect();
    assert_eq!(texts, ["actor I (crane)", "actress T (samba)"], "{seen}");
    assert_eq!(seen["colour_map"]["bar"]["unit"], "%", "{seen}");
    assert!(seen["colour_map"]["hues_used"].as_u64().unwrap() >= 3, "{seen}");
}

/// `--distance-from` compares with a named sequence of another source, frame by frame at the
/// same fraction of each sequence: the horse's gallop against its collapse (one mesh), each
/// value the distance after the best rigid alignment (recomputed here with the library).
#[test]
fn distance_from_a_reference_sequence_is_per_vertex_after_rigid_alignment() {
    use surfcap_geometry::vertex_rigid_distance::vertex_rigid_distance;
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let horse = data.join("sumner2004-horse");
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("horse.subject");
    let o = surfcap!(&["--quiet", "import", p(&horse), "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = surfcap_mesh::cache::read_cache(&subject, &surfcap_mesh::NoProgress).unwrap();
    let names: Vec<String> = s.sequences().iter().map(|q| q.name.clone()).collect();
    let gallop = names.iter().find(|n| n.contains("gallop")).unwrap().clone();
    let collapse = names.iter().find(|n| n.contains("collapse")).unwrap().clone();
    let server = ViewServer::start(
        env!("CARGO_BIN_EXE_surfcap"),
        &[p(&subject), "--sequences", &gallop, "--distance-from", p(&subject), "--reference-sequence", &collapse],
    );
    let (_, items) = server.get("/api/items");
    let items: serde_json::Value = serde_json::from_slice(&items).unwrap();
    let it = &items["items"][0];
    assert_eq!(it["field"]["name"].as_str().unwrap(), format!("distance from {collapse}"));
    assert_eq!(it["field"]["unit"], it["units"]);
    let values = f32s(&server.get("/api/items/0/field").1);
    let (g, c) = (s.sequence(&gallop).unwrap().1, s.sequence(&collapse).unwrap().1);
    let (n, m, nv) = (g.n_frames(), c.n_frames(), g.n_vertices());
    assert_eq!(values.len(), n * nv);
    for f in [0, n / 2, n - 1] {
        let at = ((f * (m - 1)) as f64 / (n - 1) as f64).round() as usize;
        let want = vertex_rigid_distance(g.frame(f), c.frame(at));
        assert_eq!(&values[f * nv..(f + 1) * nv], &want[..], "frame {f}");
        assert!(want.iter().any(|&d| d > 0.0));
    }
}

/// Mistakes in the colour-map and label options get a message naming what is wrong.
#[test]
fn colour_map_and_label_mistakes_are_explained() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let crane = p(&crane);
    for (args, want) in [
        (vec!["view", crane, "--labels", "a,b"], "--labels: 2 given for 1 sequence"),
        (
            vec!["view", crane, "--reference-sequence", "x"],
            "--reference-sequence: give --error-against or --distance-from",
        ),
        (vec!["view", crane, "--error-against", crane, "--reference-sequence", "nope"], "no sequence \"nope\""),
        (vec!["view", crane, "--error-against", crane, "--strain"], "cannot be used with"),
    ] {
        let o = surfcap!(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
