//! `surfcap view` end to end: the server on a real capture (Vlasic crane), its routes, and the
//! page driven by headless Chromium (tools/browser-test.mjs: loads with no console error, the
//! frame counter advances, the scrubber jumps, the canvas is not blank).

use std::process::Command;

use surfcap_testkit::{ViewServer, http_request as request, http_request_as, p, surfcap};

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
    // The page in headless Chromium.
    let tools = surfcap_testkit::workspace_root().join("tools");
    assert!(tools.join("node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let shot = tempfile::tempdir().unwrap();
    let png = shot.path().join("viewer.png");
    let o = Command::new("node")
        .arg(tools.join("browser-test.mjs"))
        .args([&url, png.to_str().unwrap()])
        .output()
        .expect("node runs");
    assert!(
        o.status.success(),
        "browser test failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let seen: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(seen["painted"].as_f64().unwrap() > 0.001);
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
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
