//! `surfcap view` end to end: the server on a real capture (Vlasic crane) and on synthesis
//! outputs, its routes, and the page driven by headless Chromium (tools/browser-test.mjs: loads
//! with no console error, the frame counter advances, the timeline and the arrow keys seek, the
//! legend lists what is drawn, every frame stays in view and clear of the info panel, and the
//! colours drawn are counted).

use std::path::Path;
use std::process::Command;

use surfcap_testkit::{ViewServer, http_request as request, http_request_as, p, stderr, surfcap};

/// Runs tools/browser-test.mjs on the page at `url` (failing the test when one of its checks
/// fails) and returns what it saw; the screenshot is written to `png`.
fn browser_test(url: &str, png: &Path) -> serde_json::Value {
    let tools = surfcap_testkit::workspace_root().join("tools");
    assert!(tools.join("node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let o = Command::new("node").arg(tools.join("browser-test.mjs")).args([url, p(png)]).output().expect("node runs");
    assert!(
        o.status.success(),
        "browser test failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(std::fs::metadata(png).unwrap().len() > 1000);
    serde_json::from_slice(&o.stdout).unwrap()
}

fn count(seen: &serde_json::Value, at: &str, colour: &str) -> u64 {
    seen.pointer(&format!("/{at}/{colour}")).and_then(|v| v.as_u64()).unwrap_or(0)
}

#[test]
fn the_viewer_plays_a_real_capture_in_chromium() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[crane.to_str().unwrap()]);
    let url = server.url.clone();
    // Routes: the page, its assets and the data; nothing else.
    let (status, body) = request(&url, "GET", "/");
    assert_eq!(status, 200);
    assert!(String::from_utf8_lossy(&body).contains("surfcap viewer"));
    let (status, body) = request(&url, "GET", "/api/items");
    assert_eq!(status, 200);
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let item = &v["items"][0];
    assert_eq!(item["n_frames"], 175);
    let (status, body) = request(&url, "GET", "/api/items/0/positions");
    assert_eq!(status, 200);
    assert_eq!(body.len() as u64, 175 * 3 * 4 * item["n_vertices"].as_u64().unwrap());
    for (method, target, want) in [
        ("GET", "/../../etc/passwd", 404),
        ("GET", "/assets/../../../etc/passwd", 404),
        ("GET", "/report/index.html", 404),
        ("GET", "/api/items/1/positions", 404),
        ("GET", "/etc/passwd", 404),
        ("POST", "/api/items", 405),
    ] {
        assert_eq!(request(&url, method, target).0, want, "{method} {target}");
    }
    // DNS rebinding: a request naming another host (or another port) is refused, whatever the route.
    let port = url.trim_end_matches('/').rsplit(':').next().unwrap().to_string();
    for host in [format!("evil.example:{port}"), format!("localhost.evil.example:{port}"), "127.0.0.1:1".into()] {
        for target in ["/", "/api/items", "/api/items/0/positions"] {
            let (status, body) = http_request_as(&url, "GET", target, &host);
            assert_eq!(status, 403, "Host {host} {target}");
            assert!(String::from_utf8_lossy(&body).contains("refused"), "Host {host}");
        }
    }
    assert_eq!(http_request_as(&url, "GET", "/api/items", &format!("localhost:{port}")).0, 200);
    // The same capture written as glb (sparse morph weights) serves the same positions.
    let glb_dir = tempfile::tempdir().unwrap();
    let glb = glb_dir.path().join("crane.glb");
    let o = surfcap!(&["export", crane.to_str().unwrap(), "--format", "glb", "-o", p(&glb), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let from_glb = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(&glb)]);
    let (status, glb_body) = request(&from_glb.url, "GET", "/api/items/0/positions");
    assert_eq!((status, glb_body.len()), (200, body.len()));
    let f32s = |b: &[u8]| b.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect::<Vec<_>>();
    for (x, y) in f32s(&glb_body).iter().zip(f32s(&body)) {
        assert!((x - y).abs() <= 1e-5 * (1.0 + y.abs()), "{x} vs {y}");
    }
    // The page in headless Chromium: a capture has original frames only, no overlay, a grid in
    // metres, written with the unit's symbol as everywhere else (the capture's meta says
    // "metres (approx.)").
    let shot = tempfile::tempdir().unwrap();
    let seen = browser_test(&url, &shot.path().join("viewer.png"));
    assert!(seen["painted"].as_f64().unwrap() > 0.001);
    assert_eq!(seen["legend"], serde_json::json!(["original frame", "grid: 1 square = 0.2 m"]), "{seen}");
    assert!(
        count(&seen, "colours/original", "green") > 1000 && count(&seen, "colours/original", "grey") > 100,
        "{seen}"
    );
    assert_eq!(count(&seen, "timeline", "red"), 0, "{seen}");
}

/// The viewer on synthesis outputs (the CMU-driven mannequin): `reach` reports its centre
/// track and the viewer overlays it (with no path entry); on a `path` output the page draws the
/// grid, the requested path and the achieved centre, green original and red synthetic frames on
/// the mesh and on the timeline, and keeps every frame of the walk in view.
#[test]
fn the_viewer_frames_and_explains_synthesis_outputs() {
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
    let cache = tmp.path().join("cache");
    let curve = tmp.path().join("curve.csv");
    std::fs::write(&curve, "0,0\n1,0\n2,0.3\n3,0.8\n4,1.5\n").unwrap();
    let path = tmp.path().join("path.glb");
    let o = surfcap!(&["synth", "path", p(&subject), "--curve", p(&curve), "-o", p(&path), "--cache-dir", p(&cache)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let reach = tmp.path().join("reach.glb");
    let o = surfcap!(&[
        "synth",
        "reach",
        p(&subject),
        "--from",
        "16_15:0",
        "--to",
        "16_19:60",
        "--distance",
        "3",
        "--time",
        "4",
        "-o",
        p(&reach),
        "--cache-dir",
        p(&cache),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // reach: the report holds one centre per frame, and the viewer overlays them without a path.
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("reach.report.json")).unwrap()).unwrap();
    let frames = report["frames"].as_u64().unwrap();
    assert_eq!(report["per_frame"]["centre"].as_array().unwrap().len() as u64, frames);
    let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(&reach)]);
    let (status, body) = server.get("/api/items");
    assert_eq!(status, 200);
    let item = &serde_json::from_slice::<serde_json::Value>(&body).unwrap()["items"][0];
    assert_eq!(item["overlay"]["centres"].as_array().unwrap().len() as u64, frames);
    assert!(item["overlay"]["curve"].is_null(), "reach asks for no path: {}", item["overlay"]["curve"]);
    assert_eq!((item["units"].as_str(), item["up"].as_str()), (Some("m"), Some("+y")));
    drop(server);
    // path: everything in the legend is drawn, in both frame colours.
    let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(&path)]);
    let png = tmp.path().join("path.png");
    let seen = browser_test(&server.url, &png);
    let legend = [
        "original frame",
        "synthetic frame",
        "requested path (on the ground)",
        "achieved centre of mass (on the ground)",
    ];
    assert_eq!(seen["legend"].as_array().unwrap()[..4], legend.map(serde_json::Value::from), "{seen}");
    assert!(seen["grid"]["text"].as_str().unwrap().ends_with(" m"), "{seen}");
    for (at, colour) in [
        ("colours/original", "green"),
        ("colours/synthetic", "red"),
        ("colours/original", "grey"),
        ("colours/original", "blue"),
        ("colours/original", "orange"),
        ("timeline", "green"),
        ("timeline", "red"),
    ] {
        assert!(count(&seen, at, colour) > 50, "{colour} at {at}: {seen}");
    }
    assert_eq!(count(&seen, "colours/original", "red") + count(&seen, "colours/synthetic", "green"), 0, "{seen}");
}

/// A frame set (every frame its own mesh) plays: the surface motion graph's output on the
/// re-meshed horse gallop, as a glb with a mesh per frame and as a `.frames` folder. Every frame
/// draws its own vertex and triangle counts (checked frame by frame in Chromium), the counts
/// change between frames, and the report's overlay is in the legend and its transitions on the
/// timeline (the centre track runs inside the horse's body, so no colour count checks it).
#[test]
fn the_viewer_plays_a_frame_set() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("horse.subject");
    let horse = data.join("threejs_morph_animals/horse_gallop");
    let o = surfcap!(&["--quiet", "import", p(&horse), "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let set = tmp.path().join("horse.frames");
    let o = surfcap!(&["--quiet", "remesh-frames", p(&subject), "--seed", "2", "-o", p(&set)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let glb = tmp.path().join("gallop.glb");
    let o = surfcap!(&[
        "--quiet",
        "smg",
        "query",
        p(&set),
        "--connect",
        "horse_gallop:horse_gallop",
        "--from",
        "horse_gallop:0",
        "--to",
        "horse_gallop:15",
        "--time",
        "3",
        "--distance",
        "0",
        "--distance-weight",
        "0.0001",
        "--windows",
        "3-4",
        "--tolerance",
        "1000",
        "--cache-dir",
        p(&tmp.path().join("cache")),
        "-o",
        p(&glb)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("gallop.report.json")).unwrap()).unwrap();
    let frames = report["frames"].as_u64().unwrap();
    for input in [&glb, &set] {
        let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(input)]);
        let seen = browser_test(&server.url, &tmp.path().join("frames.png"));
        let f = &seen["frame_sets"][0];
        assert!(f["distinct_vertex_counts"].as_u64().unwrap() > 1, "{seen}");
        if input == &glb {
            assert_eq!((seen["frames"].as_u64(), f["frames"].as_u64()), (Some(frames), Some(frames)), "{seen}");
            let legend = ["original frame", "achieved centre of mass (on the ground)", "transition (timeline)"];
            assert_eq!(seen["legend"].as_array().unwrap()[..3], legend.map(serde_json::Value::from), "{seen}");
            // The transitions on the timeline (counted as blue there: no other blue is drawn).
            assert!(count(&seen, "timeline", "blue") > 100, "{seen}");
        } else {
            assert_eq!(seen["frames"].as_u64(), Some(16), "{seen}");
        }
        assert!(count(&seen, "colours/original", "green") > 500, "{seen}");
    }
}

/// The head scan's colour texture at 128 x 128, each channel scaled by `tint`, as a PNG.
fn head_texture(path: &Path, tint: [f32; 3]) -> Vec<u8> {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    let mut small = image::imageops::resize(&img, 128, 128, image::imageops::FilterType::Triangle);
    for px in small.pixels_mut() {
        for (x, t) in px.0.iter_mut().zip(tint) {
            *x = (*x as f32 * t).round().min(255.0) as u8;
        }
    }
    let mut png = Vec::new();
    image::DynamicImage::ImageRgb8(small)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageOutputFormat::Png)
        .unwrap();
    png
}

/// A texture per frame plays: the head scan turning over six frames with its
/// real texture, a red tint and a blue tint (frames 0-5 show 0, 1, 2, 2, 1, 0), written as a
/// textured glb by the library and opened by `surfcap view`. Chromium checks that every frame
/// binds its own texture; the canvas turns red at the red frame and blue at the blue one.
#[test]
fn the_viewer_plays_a_texture_per_frame() {
    use surfcap_mesh::{FrameTextures, Sequence, Subject, Units, UpAxis};
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let head = data.join("leeperrysmith_head");
    let obj = surfcap_formats::obj::read_obj(&head.join("template.obj")).unwrap();
    let topology = obj.topology().unwrap();
    let nv = topology.n_vertices();
    let mut positions = Vec::with_capacity(6 * 3 * nv);
    for f in 0..6 {
        let (s, c) = (0.1 * f as f32).sin_cos();
        for q in obj.positions.chunks_exact(3) {
            positions.extend_from_slice(&[c * q[0] + s * q[2], q[1], -s * q[0] + c * q[2]]);
        }
    }
    let seq = Sequence::new("turn", nv, positions).unwrap();
    let subject = Subject::new("head", topology, vec![seq], 10.0, UpAxis::PosY, Units::arbitrary()).unwrap();
    let map = head.join("Map-COL.jpg");
    let images = [[1.0, 1.0, 1.0], [1.0, 0.15, 0.15], [0.15, 0.15, 1.0]].map(|t| head_texture(&map, t)).to_vec();
    let textures = FrameTextures::new(images, vec![vec![0, 1, 2, 2, 1, 0]]).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let glb = tmp.path().join("head.glb");
    let set = surfcap_mesh::FrameSet::from_subject(&subject);
    surfcap_formats::export::export_textured_glb(&set, &textures, &glb, &surfcap_mesh::NoProgress).unwrap();

    let server = ViewServer::start(env!("CARGO_BIN_EXE_surfcap"), &[p(&glb)]);
    let (status, items) = server.get("/api/items");
    assert_eq!(status, 200);
    let items: serde_json::Value = serde_json::from_slice(&items).unwrap();
    assert_eq!(items["items"][0]["frame_textures"], serde_json::json!([0, 1, 2, 2, 1, 0]));
    assert_eq!(items["items"][0]["n_textures"], 3);
    // The textures are served as the PNG files given; past the last one, 404.
    let (status, png) = server.get("/api/items/0/textures/1");
    assert_eq!((status, &png[..]), (200, &textures.images()[1][..]));
    assert_eq!(server.get("/api/items/0/textures/3").0, 404);
    assert_eq!(server.get("/api/items/0/textures/..%2F0").0, 404);

    let seen = browser_test(&server.url, &tmp.path().join("textured.png"));
    let t = &seen["textured"][0];
    assert_eq!(t["bound"], serde_json::json!([0, 1, 2, 2, 1, 0]), "{seen}");
    let at = |k: usize, colour: &str| t["seen"][k]["colours"][colour].as_u64().unwrap();
    assert_eq!(t["seen"][1]["texture"], 1, "{seen}");
    // The red tint draws red and hardly blue, the blue tint the other way round.
    assert!(at(1, "red") > 500 && at(1, "red") > 10 * at(1, "blue"), "{seen}");
    assert!(at(2, "blue") > 500 && at(2, "blue") > 10 * at(2, "red"), "{seen}");
    assert!(seen["legend"].as_array().unwrap().contains(&"texture per frame".into()), "{seen}");
}

#[test]
fn bad_paths_get_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let text = tmp.path().join("notes.txt");
    std::fs::write(&text, "not a mesh").unwrap();
    let empty_report = tmp.path().join("report");
    std::fs::create_dir(&empty_report).unwrap();
    std::fs::write(empty_report.join("index.html"), "<html></html>").unwrap();
    let missing = tmp.path().join("missing.glb");
    for (path, want) in [(&missing, "no such file or folder"), (&text, "notes.txt"), (&empty_report, "no .glb")] {
        let o = surfcap!(&["view", p(path)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{}: {err}", path.display());
        assert!(err.contains(want), "{}: {err}", path.display());
    }
}
