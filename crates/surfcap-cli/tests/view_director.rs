//! `surfcap view SUBJECT --direct` end to end on the CMU-driven mannequin: the direction routes
//! (only this server's own page may direct: same Origin, JSON bodies; a viewer started without
//! `--direct` refuses), and the page driven by headless Chromium (tools/director-test.mjs): a
//! path drawn with the mouse is synthesised and played with its curve where it was drawn, a
//! click on a transition of the graph's timeline plays that transition, a distance in a time and
//! key poses dragged on the timeline are synthesised, and the result downloads as a valid glb
//! (Khronos validator), abc and usda.

use std::io::{Read, Write};
use std::path::Path;
use std::process::Command;

use surfcap_testkit::{ViewServer, p, stderr, surfcap};

/// A raw HTTP/1.1 request with extra headers and a body: status and body.
fn send(url: &str, method: &str, target: &str, headers: &[(&str, &str)], body: &str) -> (u16, String) {
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).expect("the server accepts connections");
    let mut req = format!("{method} {target} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n");
    for (k, v) in headers {
        req.push_str(&format!("{k}: {v}\r\n"));
    }
    req.push_str(&format!("Content-Length: {}\r\n\r\n{body}", body.len()));
    s.write_all(req.as_bytes()).unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).unwrap();
    let text = String::from_utf8_lossy(&buf).into_owned();
    let status = text.split_whitespace().nth(1).and_then(|x| x.parse().ok()).expect("an HTTP status line");
    let body = text.split_once("\r\n\r\n").map(|(_, b)| b.to_string()).unwrap_or_default();
    (status, body)
}

/// The CMU-driven mannequin of three subject-16 clips (walk, turns) at 1,500 vertices.
fn mannequin(dir: &Path, data: &Path) -> std::path::PathBuf {
    let subject = dir.join("cmu.subject");
    let bvh: Vec<String> =
        ["16_15", "16_17", "16_19"].iter().map(|c| p(&data.join(format!("cmu_bvh/{c}.bvh"))).to_string()).collect();
    let mut args = vec!["make", "mannequin", "--bvh"];
    args.extend(bvh.iter().map(String::as_str));
    args.extend(["--vertices", "1500", "-o", p(&subject), "--quiet"]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    subject
}

#[test]
fn the_page_directs_a_subject_drawn_clicked_and_exported() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = mannequin(tmp.path(), &data);
    let cache = tmp.path().join("cache");
    let exe = env!("CARGO_BIN_EXE_surfcap");

    // Without --direct the viewer only plays: the direction routes say how to direct.
    let plain = ViewServer::start(exe, &[p(&subject)]);
    let (status, body) = plain.get("/api/direct/graph");
    assert_eq!(status, 404);
    assert!(body.windows(8).any(|w| w == b"--direct"), "{}", String::from_utf8_lossy(&body));
    let json = [("Content-Type", "application/json")];
    assert_eq!(send(&plain.url, "POST", "/api/direct", &json, r#"{"kind":"reach"}"#).0, 404);
    drop(plain);
    // --direct directs one subject.
    let o = surfcap!(&["view", p(&subject), p(&subject), "--direct", "--cache-dir", p(&cache)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--direct: give exactly one subject to direct (2 given)"), "{}", stderr(&o));

    let server = ViewServer::start(exe, &[p(&subject), "--direct", "--cache-dir", p(&cache)]);
    let url = server.url.clone();
    let port = url.trim_end_matches('/').rsplit(':').next().unwrap().to_string();
    let (status, body) = server.get("/api/direct/graph");
    assert_eq!(status, 200);
    let graph: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let names: Vec<&str> = graph["sequences"].as_array().unwrap().iter().map(|q| q["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["16_15", "16_17", "16_19"]);
    assert_eq!(graph["units"], "m");
    let arcs = graph["transitions"].as_array().unwrap();
    assert!(!arcs.is_empty(), "{graph}");
    // Every arc is a transition (never the step to the next frame of the same sequence) and names
    // its frames as users write them.
    for a in arcs {
        let (from, to) = (a["from"].as_u64().unwrap(), a["to"].as_u64().unwrap());
        let (ff, tf) = (a["from_frame"].as_str().unwrap(), a["to_frame"].as_str().unwrap());
        assert!(ff.contains(':') && tf.contains(':'), "{a}");
        assert!(!(to == from + 1 && ff.split(':').next() == tf.split(':').next()), "{a}");
    }
    // Nothing to export yet.
    let (status, body) = server.get("/api/direct/export/glb");
    assert_eq!(status, 404);
    assert!(String::from_utf8_lossy(&body).contains("nothing to export yet"));
    // Only this server's own page may direct: another Origin, a form's content type, or no
    // content type at all are refused before any work; a bad direction says what is taken.
    let reach = r#"{"kind":"reach","from":"16_15:0","to":"16_19:60","distance":2,"seconds":3}"#;
    let evil = [("Content-Type", "application/json"), ("Origin", "http://evil.example")];
    let (status, body) = send(&url, "POST", "/api/direct", &evil, reach);
    assert_eq!(status, 403, "{body}");
    assert!(body.contains("refused"), "{body}");
    let other_port = [("Content-Type", "application/json"), ("Origin", "http://127.0.0.1:1")];
    assert_eq!(send(&url, "POST", "/api/direct", &other_port, reach).0, 403);
    let form = [("Content-Type", "application/x-www-form-urlencoded")];
    assert_eq!(send(&url, "POST", "/api/direct", &form, reach).0, 415);
    assert_eq!(send(&url, "POST", "/api/direct", &[], reach).0, 415);
    let (status, body) = send(&url, "POST", "/api/direct", &json, r#"{"kind":"teleport"}"#);
    assert_eq!(status, 400);
    assert!(body.contains("path, keyposes, reach or transition"), "{body}");
    let rebound = [("Content-Type", "application/json")];
    let (status, _) = {
        // DNS rebinding: the Host check holds for the POST routes too.
        let host = url.trim_start_matches("http://").trim_end_matches('/');
        let mut s = std::net::TcpStream::connect(host).unwrap();
        write!(
            s,
            "POST /api/direct HTTP/1.1\r\nHost: evil.example:{port}\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{reach}",
            rebound[0].1,
            reach.len()
        )
        .unwrap();
        let mut b = String::new();
        s.read_to_string(&mut b).unwrap();
        (b.split_whitespace().nth(1).and_then(|x| x.parse::<u16>().ok()).unwrap(), b)
    };
    assert_eq!(status, 403);
    // A frame that does not exist is the user's error, in their words.
    let bad = r#"{"kind":"reach","from":"16_15:0","to":"16_99:0","distance":2,"seconds":3}"#;
    let (status, body) = send(&url, "POST", "/api/direct", &json, bad);
    assert_eq!(status, 422, "{body}");
    assert!(body.contains("reach not made") && body.contains("16_99"), "{body}");
    // The same origin directs: the result replaces the items played.
    let same = [("Content-Type", "application/json"), ("Origin", url.trim_end_matches('/'))];
    let (status, body) = send(&url, "POST", "/api/direct", &same, reach);
    assert_eq!(status, 200, "{body}");
    let answer: serde_json::Value = serde_json::from_str(&body).unwrap();
    let (_, items) = server.get("/api/items");
    let items: serde_json::Value = serde_json::from_slice(&items).unwrap();
    assert_eq!(items["items"].as_array().unwrap().len(), 1);
    assert_eq!(items["items"][0]["n_frames"], answer["frames"]);
    assert!(items["items"][0]["overlay"]["constraints"][0].as_str().unwrap().starts_with("distance"), "{items}");
    assert_eq!(send(&url, "POST", "/api/direct/reset", &same, "{}").0, 200);
    let (_, items) = server.get("/api/items");
    let items: serde_json::Value = serde_json::from_slice(&items).unwrap();
    assert_eq!(items["items"].as_array().unwrap().len(), 3);

    // The page, as a user drives it.
    let tools = surfcap_testkit::workspace_root().join("tools");
    assert!(tools.join("node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let shots = tmp.path().join("shots");
    std::fs::create_dir_all(&shots).unwrap();
    let o = Command::new("node").arg(tools.join("director-test.mjs")).args([url.as_str(), p(&shots)]).output().unwrap();
    assert!(
        o.status.success(),
        "director test failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let seen: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    eprintln!("director test saw: {seen}");
    assert_eq!(seen["path"]["kind"], "path");
    assert!(seen["path"]["n_frames"].as_u64().unwrap() > 30, "{seen}");
    assert_eq!(seen["transition"]["kind"], "transition");
    assert!(seen["transition"]["hover_title"].as_str().unwrap().starts_with("transition "), "{seen}");
    assert_eq!(seen["reach"]["kind"], "reach");
    assert_eq!(seen["keyposes"]["kind"], "keyposes");
    for shot in ["start", "path", "transition", "reach", "keyposes"] {
        assert!(std::fs::metadata(shots.join(format!("{shot}.png"))).unwrap().len() > 1000, "{shot}");
    }
    // The downloaded glb passes the Khronos validator; the abc and usda read back.
    let glb = shots.join("keyposes.glb");
    for report in surfcap_testkit::validate_glb(std::slice::from_ref(&glb)) {
        assert_eq!(report["numErrors"], 0, "{report}");
    }
    // The last result was the key poses' walk: its frames in every format.
    let frames = seen["keyposes"]["frames"].as_f64().unwrap();
    let usd = surfcap_testkit::read_usd(&shots.join("keyposes.usda"));
    assert_eq!(usd["end"].as_f64(), Some(frames - 1.0), "usda from frame {} to {}", usd["start"], usd["end"]);
    let abc = surfcap_testkit::read_abc(&shots.join("keyposes.abc"));
    let samples = abc["meshes"][0]["self_bounds"].as_array().map(Vec::len);
    assert_eq!(samples, Some(frames as usize), "abc samples");
}
